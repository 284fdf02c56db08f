//! Hot reload: watch a sky file and everything it references, reload off the render path, and
//! swap the new sky in only if it is valid. A broken edit leaves the last good sky in place.

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::sync::mpsc::{channel, Receiver, RecvTimeoutError, Sender};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use crate::files::watch::{normalize, FileWatcher};
use crate::sky::builtin;
use crate::sky::load::{is_continent_file, load_continent, SEASONS};
use crate::sky::{load_sky_file, Sky, SkyError, SkyErrors};

/// Which sky to show.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum SkySpec {
    /// The built-in default sky.
    Builtin,
    /// A sky file.
    File(PathBuf),
    /// A continent file and the season picking its sky (0 spring .. 3 winter).
    Continent {
        /// The continent file.
        path: PathBuf,
        /// Season index into [`SEASONS`].
        season: usize,
    },
}

impl SkySpec {
    /// A spec for a path given by the user: continent files are recognised by their `[seasons]`.
    pub fn from_path(path: &Path, season: Option<&str>) -> Result<SkySpec, SkyErrors> {
        if is_continent_file(path) {
            let season = season.unwrap_or("summer");
            let index = SEASONS.iter().position(|s| *s == season).ok_or_else(|| {
                SkyErrors(vec![SkyError {
                    file: path.display().to_string(),
                    line: 1,
                    column: 1,
                    field: "--season".into(),
                    message: format!("unknown season \"{season}\"; expected one of {}", SEASONS.join(", ")),
                }])
            })?;
            Ok(SkySpec::Continent { path: path.to_path_buf(), season: index })
        } else {
            Ok(SkySpec::File(path.to_path_buf()))
        }
    }

    /// Loads and validates the sky (blocking; call off the render path for reloads); its
    /// warnings go to the log.
    pub fn load(&self) -> Result<Sky, SkyErrors> {
        let sky = match self {
            SkySpec::Builtin => Ok(builtin::default_sky()),
            SkySpec::File(p) => load_sky_file(p),
            SkySpec::Continent { path, season } => {
                let c = load_continent(path)?;
                load_sky_file(&c.skies[*season])
            }
        }?;
        for w in &sky.warnings {
            log::warn!("{w}");
        }
        Ok(sky)
    }

    /// The sky file shown (for a continent, its season's), if any.
    pub fn sky_file(&self) -> Option<PathBuf> {
        match self {
            SkySpec::Builtin => None,
            SkySpec::File(p) => Some(p.clone()),
            SkySpec::Continent { path, season } => load_continent(path).ok().map(|c| c.skies[*season].clone()),
        }
    }

    /// Short name for titles and screenshot file names.
    pub fn display(&self) -> String {
        match self {
            SkySpec::Builtin => "default".into(),
            SkySpec::File(p) => p.display().to_string(),
            SkySpec::Continent { path, season } => format!("{} ({})", path.display(), SEASONS[*season]),
        }
    }

    /// Files whose change must trigger a reload besides the sky's own references.
    fn own_files(&self) -> Vec<PathBuf> {
        match self {
            SkySpec::Builtin => vec![],
            SkySpec::File(p) => vec![p.clone()],
            SkySpec::Continent { path, season } => {
                let mut v = vec![path.clone()];
                if let Ok(c) = load_continent(path) {
                    v.push(c.skies[*season].clone());
                }
                v
            }
        }
    }
}

/// What a call to [`LiveSky::poll`] found.
#[derive(Debug, Clone, PartialEq)]
pub enum ReloadEvent {
    /// A new sky is in place.
    Reloaded,
    /// The edit was invalid; the previous sky stays.
    Failed(SkyErrors),
    /// A load failed on files that changed while it ran or since (a save in progress): its error
    /// is not shown, and a new load was requested.
    Superseded,
}

/// Length and modification time of each file a load depends on, taken before it read them.
type Fingerprint = Vec<(PathBuf, Option<(u64, std::time::SystemTime)>)>;

type LoadResult = (u64, Result<Sky, SkyErrors>, Fingerprint);

/// The fingerprint of `files` now.
fn fingerprint(files: impl IntoIterator<Item = PathBuf>) -> Fingerprint {
    let mut out: Fingerprint = files
        .into_iter()
        .map(|p| {
            let meta = std::fs::metadata(&p).ok().and_then(|m| Some((m.len(), m.modified().ok()?)));
            (p, meta)
        })
        .collect();
    out.sort_by(|a, b| a.0.cmp(&b.0));
    out.dedup_by(|a, b| a.0 == b.0);
    out
}

struct Shared {
    spec: SkySpec,
    /// Normalised files that trigger a reload.
    files: HashSet<PathBuf>,
    /// Folders of the sky and continent files: any file appearing there may be a new reference.
    sky_dirs: HashSet<PathBuf>,
}

/// The current sky, kept up to date with its files.
pub struct LiveSky {
    current: Arc<Sky>,
    /// Errors of the last reload, if it failed (cleared by the next good one).
    pub error: Option<SkyErrors>,
    /// Incremented on every successful swap.
    pub generation: u64,
    /// The sky before the last successful swap of the same spec, and its generation (what "last
    /// good version" compares against).
    pub previous: Option<(Arc<Sky>, u64)>,
    shared: Arc<Mutex<Shared>>,
    trigger: Sender<u64>,
    results: Receiver<LoadResult>,
    requested: u64,
    watcher: Option<FileWatcher>,
}

impl LiveSky {
    /// Loads a sky (blocking) and starts watching its files. Fails only if the first load fails.
    pub fn new(spec: SkySpec) -> Result<Self, SkyErrors> {
        let sky = spec.load()?;
        let shared = Arc::new(Mutex::new(Shared { spec: spec.clone(), files: HashSet::new(), sky_dirs: HashSet::new() }));
        let (trigger, trigger_rx) = channel::<u64>();
        let (result_tx, results) = channel::<LoadResult>();
        let loader_shared = shared.clone();
        std::thread::Builder::new()
            .name("skytune-loader".into())
            .spawn(move || {
                while let Ok(mut id) = trigger_rx.recv() {
                    // Coalesce a burst of triggers into one load.
                    while let Ok(next) = trigger_rx.try_recv() {
                        id = next;
                    }
                    let state = loader_shared.lock().map(|s| (s.spec.clone(), s.files.clone()));
                    let Ok((spec, files)) = state else { break };
                    let before = fingerprint(files.into_iter().chain(spec.own_files().iter().map(|p| normalize(p))));
                    let result = spec.load();
                    if result_tx.send((id, result, before)).is_err() {
                        break;
                    }
                }
            })
            .expect("spawning the loader thread");

        let handler_shared = shared.clone();
        let handler_trigger = trigger.clone();
        let watcher = FileWatcher::new(move |changed| {
            // Snapshots (`.skytune-snapshots/`) are copies, never the sky's own files.
            let snapshot = |p: &PathBuf| p.components().any(|c| c.as_os_str() == crate::files::snapshot::SNAPSHOT_DIR);
            let relevant =
                handler_shared.lock().is_ok_and(|s| changed.iter().filter(|p| !snapshot(p)).any(|p| s.files.contains(p) || p.parent().is_some_and(|d| s.sky_dirs.contains(d))));
            if relevant {
                let _ = handler_trigger.send(0);
            }
        });
        let watcher = match watcher {
            Ok(w) => Some(w),
            Err(e) => {
                log::warn!("file watching unavailable ({e}); edits will not reload");
                None
            }
        };
        let mut live = Self { current: Arc::new(sky), error: None, generation: 0, previous: None, shared, trigger, results, requested: 0, watcher };
        live.refresh_watches();
        Ok(live)
    }

    /// The last good sky.
    pub fn sky(&self) -> &Arc<Sky> {
        &self.current
    }

    /// The sky file shown (for a continent, its current season's), if any.
    pub fn sky_file(&self) -> Option<PathBuf> {
        self.spec().sky_file()
    }

    /// What is being shown.
    pub fn spec(&self) -> SkySpec {
        self.shared.lock().map(|s| s.spec.clone()).unwrap_or(SkySpec::Builtin)
    }

    /// Switches to another sky; the current one stays until the new one loads successfully.
    pub fn switch(&mut self, spec: SkySpec) {
        if let Ok(mut s) = self.shared.lock() {
            s.spec = spec;
        }
        self.request_reload();
    }

    /// Asks for a reload now (e.g. from a UI button).
    pub fn request_reload(&mut self) {
        self.requested += 1;
        let _ = self.trigger.send(self.requested);
    }

    /// Applies finished reloads without blocking. Returns the last event, if any.
    pub fn poll(&mut self) -> Option<ReloadEvent> {
        let mut last = None;
        while let Ok((_, result, before)) = self.results.try_recv() {
            last = Some(self.apply(result, before));
        }
        last
    }

    /// Waits up to `timeout` for the next reload result (watch mode and tests).
    /// Superseded failures are skipped: the load they asked for is waited for instead.
    pub fn wait(&mut self, timeout: Duration) -> Option<ReloadEvent> {
        let deadline = std::time::Instant::now() + timeout;
        loop {
            let left = deadline.saturating_duration_since(std::time::Instant::now());
            match self.results.recv_timeout(left) {
                Ok((_, result, before)) => {
                    let event = self.apply(result, before);
                    match self.poll().unwrap_or(event) {
                        ReloadEvent::Superseded => continue,
                        event => return Some(event),
                    }
                }
                Err(RecvTimeoutError::Timeout | RecvTimeoutError::Disconnected) => return None,
            }
        }
    }

    fn apply(&mut self, result: Result<Sky, SkyErrors>, before: Fingerprint) -> ReloadEvent {
        if result.is_err() && fingerprint(before.iter().map(|(p, _)| p.clone())) != before {
            // A save in progress (truncated file, bitmap half written): the error may be of a
            // state the artist never meant; load what is there now instead.
            log::debug!("a reload failed on files that changed since it read them; loading again");
            self.request_reload();
            return ReloadEvent::Superseded;
        }
        match result {
            Ok(sky) => {
                let same_source = sky.source_name == self.current.source_name;
                let old = std::mem::replace(&mut self.current, Arc::new(sky));
                self.previous = same_source.then_some((old, self.generation));
                self.error = None;
                self.generation += 1;
                self.refresh_watches();
                log::info!("reloaded sky \"{}\"", self.current.name);
                ReloadEvent::Reloaded
            }
            Err(e) => {
                log::error!("sky reload failed, keeping the last good sky:\n{e}");
                // Watch the files a fixed version may reference, not only the old ones.
                self.refresh_watches();
                self.error = Some(e.clone());
                ReloadEvent::Failed(e)
            }
        }
    }

    /// Watches the folders of the sky file, the continent file and every referenced file.
    fn refresh_watches(&mut self) {
        let Ok(mut s) = self.shared.lock() else { return };
        let own: Vec<PathBuf> = s.spec.own_files().iter().map(|p| normalize(p)).collect();
        s.sky_dirs = own.iter().filter_map(|f| f.parent().map(Path::to_path_buf)).collect();
        let mut files: HashSet<PathBuf> = own.into_iter().collect();
        files.extend(self.current.watched_files.iter().map(|p| normalize(p)));
        let dirs: HashSet<PathBuf> = files.iter().filter_map(|f| f.parent().map(Path::to_path_buf)).collect();
        if let Some(w) = self.watcher.as_mut() {
            w.set_dirs(dirs);
        }
        s.files = files;
    }
}
