//! `kind = "auto"` in the window: the pick for a new atmosphere measures the candidates that decide
//! it against a reference computed for it (up to a minute on two cores), so it runs on a worker
//! thread.
//! The window keeps rendering with the last good model meanwhile, shows the worker's progress,
//! and swaps the pick in when it arrives. A reload that changes what is measured (an atmosphere,
//! the sun's range) cancels a running pick and drops whatever it would have returned; one that
//! changes anything else (a bitmap, the budget) lets it run on, and the pick is chosen from its
//! scores for the sky shown when they arrive.

use std::sync::mpsc::{self, Receiver, TryRecvError};
use std::sync::Arc;
use std::time::{Duration, Instant};

use crate::measure::auto_model::{self, Pick, Scores};
use crate::render::GpuContext;
use crate::sky::resolved::{Budget, SkyModel};
use crate::sky::Sky;
use crate::support::progress::Job;

/// A pick being measured on the worker.
struct Pending {
    job: Arc<Job>,
    result: Receiver<Result<Scores, String>>,
    /// What it measures ([`auto_model::scores_key`]).
    key: u64,
    /// The latest version of the sky it measures for, and its generation.
    sky: Arc<Sky>,
    generation: u64,
    started: Instant,
    /// Longest frame of the window while it ran.
    longest_frame: Duration,
    frames: u64,
    /// The adapter it measures on, kept to measure on when a reload's budget needs more.
    ctx: GpuContext,
}

/// Frames left out of the longest frame time a pick reports: a window's first frames build
/// pipelines and upload the panels' fonts, with or without a pick running.
const WARM_UP_FRAMES: u64 = 10;

/// The auto pick of the sky shown: the latest result and the measurement under way, if any.
#[derive(Default)]
pub struct AutoPicker {
    pending: Option<Pending>,
    /// The pick for the sky shown, or why there is none; while a new one is measured, the last
    /// good pick (of an earlier version of the sky), which the window keeps rendering with.
    result: Option<Result<Pick, String>>,
}

impl AutoPicker {
    /// Asks for the pick of `sky` (generation `generation`): known picks (cached in this process
    /// or on disk) apply at once; otherwise a worker measures it on `ctx`. A pick still running
    /// for an earlier version goes on when it measures the same atmospheres and suns, else it is
    /// cancelled. Skies that name their model need no pick.
    pub fn request(&mut self, sky: &Arc<Sky>, generation: u64, ctx: &GpuContext) {
        let key = sky.auto_model.map(|_| auto_model::scores_key(sky));
        if let Some(p) = self.pending.as_mut() {
            if Some(p.key) == key {
                // Same atmospheres and suns: the measurement under way serves this version too.
                (p.sky, p.generation) = (sky.clone(), generation);
                return;
            }
            p.job.cancel();
            self.pending = None;
            log::info!("auto model: the sky's atmosphere changed; the pick under way for the previous version is cancelled");
        }
        let (Some(budget), Some(key)) = (sky.auto_model, key) else {
            self.result = None;
            return;
        };
        if let Some(pick) = auto_model::known_pick(sky, budget) {
            log::info!("{}", pick.describe());
            self.result = Some(Ok(pick));
            return;
        }
        self.spawn(sky, generation, key, budget, ctx);
    }

    /// Starts a worker measuring the candidates of `sky` until they decide its pick for `budget`
    /// (resuming from what the caches hold).
    fn spawn(&mut self, sky: &Arc<Sky>, generation: u64, key: u64, budget: Budget, ctx: &GpuContext) {
        let job = Arc::new(Job::new());
        let (send, result) = mpsc::channel();
        let (worker_sky, worker_ctx, worker_job) = (sky.clone(), ctx.clone(), job.clone());
        let spawned = std::thread::Builder::new().name("auto-pick".into()).spawn(move || {
            lower_priority();
            let started = Instant::now();
            let out = auto_model::score_cached(&worker_sky, Some(budget), &worker_ctx, &worker_job);
            if worker_job.is_cancelled() {
                // Nobody waits for a cancelled pick: its receiver is gone.
                log::info!("auto model: stopped measuring for a superseded version of the sky after {:.1} s", started.elapsed().as_secs_f64());
                return;
            }
            let _ = send.send(out.map_err(|e| format!("auto model: {e:#}")));
        });
        match spawned {
            Ok(_) => {
                log::info!("auto model: measuring the candidates for this sky's atmosphere on a worker (once; cached)");
                self.pending =
                    Some(Pending { job, result, key, sky: sky.clone(), generation, started: Instant::now(), longest_frame: Duration::ZERO, frames: 0, ctx: ctx.clone() });
            }
            Err(e) => self.result = Some(Err(format!("auto model: cannot start its worker: {e}"))),
        }
    }

    /// Takes the worker's result when it is there, if it is for the sky `generation` shown (once
    /// per frame; `frame` is the window's last frame time, kept to say how the window fared
    /// meanwhile). Returns whether the pick changed.
    pub fn poll(&mut self, frame: Duration, generation: u64) -> bool {
        let Some(p) = self.pending.as_mut() else { return false };
        p.frames += 1;
        if p.frames > WARM_UP_FRAMES {
            p.longest_frame = p.longest_frame.max(frame);
        }
        let result = match p.result.try_recv() {
            Ok(r) => r,
            Err(TryRecvError::Empty) => return false,
            Err(TryRecvError::Disconnected) => Err("auto model: its worker stopped without a result".to_string()),
        };
        let p = self.pending.take().expect("pending above");
        if p.generation != generation {
            // Measured for a version of the sky no longer shown (a request updates or cancels
            // these; belt and braces).
            return false;
        }
        let result = match (result, p.sky.auto_model) {
            (Ok(scores), Some(budget)) => match scores.pick(budget, auto_model::sky_suns(&p.sky)) {
                Some(pick) => Ok(pick),
                None => {
                    // A reload changed the budget meanwhile, to one these candidates do not
                    // decide: measure on from where this worker stopped.
                    self.spawn(&p.sky, p.generation, p.key, budget, &p.ctx);
                    return false;
                }
            },
            (Ok(_), None) => Err("auto model: the sky no longer asks for one".to_string()),
            (Err(e), _) => Err(e),
        };
        match &result {
            Ok(pick) => log::info!(
                "auto model: picked after {:.1} s on a worker, while the window drew {} frames (longest {:.0} ms after the first {WARM_UP_FRAMES}): {}",
                p.started.elapsed().as_secs_f64(),
                p.frames,
                p.longest_frame.as_secs_f64() * 1000.0,
                pick.describe()
            ),
            Err(e) => log::warn!("{e}"),
        }
        self.result = Some(result);
        true
    }

    /// The model the window renders the auto sky with: the pick, or while none has arrived the
    /// last good one; None before any (the sky's own stand-in, `lut`).
    pub fn model(&self, base: &SkyModel) -> Option<SkyModel> {
        self.result.as_ref().and_then(|r| r.as_ref().ok()).map(|p| p.model(base))
    }

    /// The picked point's id on the benchmark chart.
    pub fn point(&self) -> Option<String> {
        self.result.as_ref().and_then(|r| r.as_ref().ok()).map(|p| p.chosen.id.clone())
    }

    /// Progress (0..1) and stage of the pick under way.
    pub fn progress(&self) -> Option<(f32, String)> {
        self.pending.as_ref().map(|p| (p.job.fraction(), p.job.stage()))
    }

    /// Whether a pick is being measured.
    pub fn is_measuring(&self) -> bool {
        self.pending.is_some()
    }

    /// The panel's line: the pick, or what is shown while one is measured, or why there is none.
    pub fn describe(&self, sky: &Sky) -> Option<String> {
        sky.auto_model?;
        let shown = match (&self.result, self.pending.is_some()) {
            (Some(Ok(p)), true) => format!("showing {} (the last pick) meanwhile", p.chosen.id),
            (_, true) => format!("showing the stand-in {} meanwhile", sky.model.kind.name()),
            (Some(Ok(p)), false) => return Some(p.describe()),
            (Some(Err(e)), false) => return Some(e.clone()),
            (None, false) => return None,
        };
        Some(format!("auto model: measuring the candidates for this atmosphere on a worker; {shown}"))
    }
}

impl Drop for AutoPicker {
    fn drop(&mut self) {
        if let Some(p) = &self.pending {
            p.job.cancel();
        }
    }
}

/// The worker's nice value: a little below the window's threads, so frames keep their pace, yet
/// not so low that a window drawing flat out on a software rasteriser starves it (at 10 a pick of
/// two minutes took over twenty on two cores).
#[cfg(target_os = "linux")]
const WORKER_NICE: libc::c_int = 3;

/// Lowers this thread's scheduling priority (and so of the threads it starts): the window's own
/// threads, the rasteriser's among them on a software adapter, go first on a machine with few cores.
fn lower_priority() {
    #[cfg(target_os = "linux")]
    // SAFETY: setpriority on the calling thread's id changes only this thread's nice value.
    unsafe {
        let tid = libc::syscall(libc::SYS_gettid) as libc::id_t;
        libc::setpriority(libc::PRIO_PROCESS, tid, WORKER_NICE);
    }
}
