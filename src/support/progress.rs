//! Progress of long work, and how it is shown.
//!
//! - [`Job`]: what a long computation shares with whoever waits for it (a fraction done, what it
//!   is doing, a cancel flag). The window reads it for its progress bars; a worker sets it.
//! - [`Reporter`]: progress on stderr. On a terminal it is a bar redrawn in place; anywhere else
//!   (CI logs, pipes, files) it writes at most one line every [`LINE_EVERY`] and a summary line at
//!   the end, each ending in a newline, so a log never gets a 15 KB line of carriage returns.

use std::io::{IsTerminal, Write as _};
use std::sync::atomic::{AtomicBool, AtomicU32, AtomicU64, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// The work was cancelled through its [`Job`] (a newer request superseded it).
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("cancelled")]
pub struct Cancelled;

/// Progress and cancellation shared between a long computation and whoever waits for it.
#[derive(Debug, Default)]
pub struct Job {
    /// Fraction done, 0..1, as `f32` bits.
    fraction: AtomicU32,
    cancelled: AtomicBool,
    stage: Mutex<String>,
}

impl Job {
    /// A job at 0%, not cancelled.
    pub fn new() -> Self {
        Self::default()
    }

    /// Sets the fraction done (clamped to 0..1).
    pub fn set_fraction(&self, fraction: f64) {
        let f = if fraction.is_finite() { fraction.clamp(0.0, 1.0) as f32 } else { 0.0 };
        self.fraction.store(f.to_bits(), Ordering::Relaxed);
    }

    /// Fraction done, 0..1.
    pub fn fraction(&self) -> f32 {
        f32::from_bits(self.fraction.load(Ordering::Relaxed))
    }

    /// Says what the job is doing now (shown beside the bar).
    pub fn set_stage(&self, stage: impl Into<String>) {
        *self.stage.lock().unwrap_or_else(|p| p.into_inner()) = stage.into();
    }

    /// What the job is doing now.
    pub fn stage(&self) -> String {
        self.stage.lock().unwrap_or_else(|p| p.into_inner()).clone()
    }

    /// Asks the job to stop at its next check.
    pub fn cancel(&self) {
        self.cancelled.store(true, Ordering::Release);
    }

    /// Whether the job was asked to stop.
    pub fn is_cancelled(&self) -> bool {
        self.cancelled.load(Ordering::Acquire)
    }

    /// `Err(Cancelled)` once the job was asked to stop: for `?` at the job's check points.
    pub fn check(&self) -> Result<(), Cancelled> {
        if self.is_cancelled() {
            Err(Cancelled)
        } else {
            Ok(())
        }
    }

    /// A view of this job covering `[start, start + span)` of its fraction: a phase of the work
    /// reports 0..1 of itself and the job moves through its share.
    pub fn phase(&self, start: f64, span: f64) -> Phase<'_> {
        Phase { job: self, start, span }
    }
}

/// A share of a [`Job`]'s progress (see [`Job::phase`]).
#[derive(Debug, Clone, Copy)]
pub struct Phase<'a> {
    /// The job.
    pub job: &'a Job,
    start: f64,
    span: f64,
}

impl Phase<'_> {
    /// Reports `done` of `total` of this phase.
    pub fn report(&self, done: usize, total: usize) {
        self.job.set_fraction(self.start + self.span * done as f64 / total.max(1) as f64);
    }
}

/// Longest gap between two progress lines when stderr is not a terminal.
pub const LINE_EVERY: Duration = Duration::from_secs(5);

/// Progress of one long command on stderr: a bar on a terminal, occasional lines elsewhere.
pub struct Reporter {
    what: String,
    started: Instant,
    length: AtomicU64,
    position: AtomicU64,
    /// The bar, on a terminal.
    bar: Option<ProgressBar>,
    /// When the last line was written, elsewhere.
    last_line: Mutex<Instant>,
    /// What is being done now.
    message: Mutex<String>,
    /// Steps are thousandths of the whole: show a percentage.
    percent: bool,
}

impl Reporter {
    /// A reporter of `len` steps (0: not known yet, see [`Self::set_length`]) named `what`,
    /// drawing a bar when stderr is a terminal.
    pub fn new(len: u64, what: &str) -> Self {
        Self::with_terminal(len, what, std::io::stderr().is_terminal())
    }

    /// As [`Self::new`], saying whether stderr is a terminal (tests use `false`).
    pub fn with_terminal(len: u64, what: &str, terminal: bool) -> Self {
        Self::build(len, what, terminal, false)
    }

    /// A reporter of a fraction done (positions are thousandths), shown as a percentage.
    fn percentage(what: &str) -> Self {
        Self::build(1000, what, std::io::stderr().is_terminal(), true)
    }

    fn build(len: u64, what: &str, terminal: bool, percent: bool) -> Self {
        let bar = terminal.then(|| {
            let bar = ProgressBar::with_draw_target(Some(len), ProgressDrawTarget::stderr());
            let counts = if percent { "{percent:>3}%" } else { "{pos}/{len}" };
            let template = format!("{{prefix}} [{{bar:40}}] {counts} {{elapsed_precise}} eta {{eta}} {{msg}}");
            bar.set_style(ProgressStyle::with_template(&template).expect("valid template").progress_chars("=> "));
            bar.set_prefix(what.to_string());
            bar
        });
        let now = Instant::now();
        Self {
            what: what.to_string(),
            started: now,
            length: AtomicU64::new(len),
            position: AtomicU64::new(0),
            bar,
            last_line: Mutex::new(now),
            message: Mutex::new(String::new()),
            percent,
        }
    }

    /// Sets the number of steps.
    pub fn set_length(&self, len: u64) {
        self.length.store(len, Ordering::Relaxed);
        if let Some(b) = &self.bar {
            b.set_length(len);
        }
    }

    /// Sets the steps done.
    pub fn set_position(&self, pos: u64) {
        self.position.store(pos, Ordering::Relaxed);
        if let Some(b) = &self.bar {
            b.set_position(pos);
        }
        self.maybe_line();
    }

    /// Adds `n` steps done.
    pub fn inc(&self, n: u64) {
        self.position.fetch_add(n, Ordering::Relaxed);
        if let Some(b) = &self.bar {
            b.inc(n);
        }
        self.maybe_line();
    }

    /// Says what is being done now (beside the bar; in the next line elsewhere).
    pub fn set_message(&self, message: impl Into<String>) {
        let m = message.into();
        if let Some(b) = &self.bar {
            b.set_message(m.clone());
        }
        *self.message.lock().unwrap_or_else(|p| p.into_inner()) = m;
    }

    /// Ends the bar, or writes the summary line.
    pub fn finish(&self) {
        match &self.bar {
            Some(b) => b.finish(),
            None => self.line(true),
        }
    }

    fn maybe_line(&self) {
        if self.bar.is_some() {
            return;
        }
        let mut last = self.last_line.lock().unwrap_or_else(|p| p.into_inner());
        if last.elapsed() >= LINE_EVERY {
            *last = Instant::now();
            drop(last);
            self.line(false);
        }
    }

    /// One line of progress (or, with `done`, the summary).
    fn line(&self, done: bool) {
        let (pos, len) = (self.position.load(Ordering::Relaxed), self.length.load(Ordering::Relaxed));
        let secs = self.started.elapsed().as_secs_f64();
        let message = self.message.lock().unwrap_or_else(|p| p.into_inner()).clone();
        let now = if message.is_empty() { String::new() } else { format!(" ({message})") };
        let text = match (done, self.percent) {
            (true, true) => format!("{}: done in {secs:.1} s\n", self.what),
            (true, false) => format!("{}: done, {pos} in {secs:.1} s\n", self.what),
            (false, true) => format!("{}: {:.0}% after {secs:.0} s{now}\n", self.what, pos as f64 / 10.0),
            (false, false) if len > 0 => format!("{}: {pos}/{len} ({:.0}%) after {secs:.0} s{now}\n", self.what, 100.0 * pos as f64 / len as f64),
            (false, false) => format!("{}: {pos} after {secs:.0} s{now}\n", self.what),
        };
        // One write per line, so lines of threads reporting at once never interleave.
        let _ = std::io::stderr().lock().write_all(text.as_bytes());
    }
}

/// How long work runs before [`run_reported`] starts showing its progress: quick work (a cached
/// result) stays silent.
const QUIET_START: Duration = Duration::from_millis(500);

/// Runs `work` with a [`Job`] while a helper thread shows its progress with a [`Reporter`] named
/// `what` once it has run longer than [`QUIET_START`]; for commands that wait on work the window
/// runs on a worker.
pub fn run_reported<T>(what: &str, work: impl FnOnce(&Job) -> T + Send) -> T
where
    T: Send,
{
    let job = Job::new();
    let finished = AtomicBool::new(false);
    /// Sets `finished` however the work ends: a work that panics must not leave the reporter
    /// polling for ever (the scope waits for it before the panic goes on).
    struct Finish<'a>(&'a AtomicBool);
    impl Drop for Finish<'_> {
        fn drop(&mut self) {
            self.0.store(true, Ordering::Release);
        }
    }
    std::thread::scope(|scope| {
        let shown = scope.spawn(|| {
            let started = Instant::now();
            let mut reporter: Option<Reporter> = None;
            let mut stage = String::new();
            while !finished.load(Ordering::Acquire) {
                std::thread::sleep(Duration::from_millis(50));
                if started.elapsed() < QUIET_START {
                    continue;
                }
                let r = reporter.get_or_insert_with(|| Reporter::percentage(what));
                let now = job.stage();
                if now != stage {
                    r.set_message(now.clone());
                    stage = now;
                }
                r.set_position((job.fraction() as f64 * 1000.0).round() as u64);
            }
            reporter
        });
        let out = {
            let _finish = Finish(&finished);
            work(&job)
        };
        if let Ok(Some(r)) = shown.join() {
            r.set_position(1000);
            r.finish();
        }
        out
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn phases_share_the_fraction() {
        let job = Job::new();
        job.phase(0.5, 0.25).report(2, 4);
        assert!((job.fraction() - 0.625).abs() < 1e-6);
        job.set_fraction(7.0);
        assert_eq!(job.fraction(), 1.0);
        assert_eq!(job.check(), Ok(()));
        job.cancel();
        assert_eq!(job.check(), Err(Cancelled));
    }

    /// A work that panics ends the reported run with its panic (it hung, the reporter polling
    /// for a finish that never came, when `skytune check` panicked in an auto pick).
    #[test]
    fn a_panicking_work_ends_the_run() {
        let (send, done) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let out = std::panic::catch_unwind(|| run_reported("test", |_| -> u32 { panic!("on purpose") }));
            let _ = send.send(out.is_err());
        });
        assert_eq!(done.recv_timeout(Duration::from_secs(30)), Ok(true), "the run ended with the work's panic");
    }
}
