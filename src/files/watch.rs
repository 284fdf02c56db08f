//! Watching files for edits: the one facility behind sky hot reload and shader hot reload.
//!
//! Folders are watched, not files, because editors that save by rename replace the file's inode.
//! Events are debounced; reads (our own reloads included) and editors' swap files are ignored.

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::time::Duration;

use notify_debouncer_full::notify::event::{AccessKind, AccessMode, EventKind, ModifyKind};
use notify_debouncer_full::notify::{RecommendedWatcher, RecursiveMode};
use notify_debouncer_full::{new_debouncer, DebounceEventResult, Debouncer, RecommendedCache};

/// Quiet time after the last event before a burst of events is reported.
pub const DEBOUNCE: Duration = Duration::from_millis(150);

/// Watches a set of folders and reports the files in them whose content may have changed.
pub struct FileWatcher {
    debouncer: Debouncer<RecommendedWatcher, RecommendedCache>,
    dirs: HashSet<PathBuf>,
}

impl FileWatcher {
    /// Starts a watcher; `on_change` receives the normalised paths of each debounced burst of
    /// content changes (on the watcher's thread).
    pub fn new(on_change: impl Fn(&[PathBuf]) + Send + 'static) -> Result<Self, notify_debouncer_full::notify::Error> {
        let debouncer = new_debouncer(DEBOUNCE, None, move |res: DebounceEventResult| {
            let Ok(events) = res else { return };
            let changed: Vec<PathBuf> =
                events.iter().filter(|e| is_content_change(&e.kind)).flat_map(|e| e.paths.iter()).map(|p| normalize(p)).filter(|p| !is_editor_noise(p)).collect();
            if !changed.is_empty() {
                on_change(&changed);
            }
        })?;
        Ok(Self { debouncer, dirs: HashSet::new() })
    }

    /// Watches exactly `dirs` from now on (non-recursively), adding and removing watches as needed.
    pub fn set_dirs(&mut self, dirs: HashSet<PathBuf>) {
        for dir in dirs.difference(&self.dirs) {
            if let Err(e) = self.debouncer.watch(dir, RecursiveMode::NonRecursive) {
                log::warn!("cannot watch {}: {e}", dir.display());
            }
        }
        for dir in self.dirs.difference(&dirs) {
            let _ = self.debouncer.unwatch(dir);
        }
        self.dirs = dirs;
    }
}

/// Absolute, symlink-free form of a path that may not exist yet (editors delete and recreate).
pub fn normalize(p: &Path) -> PathBuf {
    if let Ok(c) = p.canonicalize() {
        return c;
    }
    match (p.parent().and_then(|d| d.canonicalize().ok()), p.file_name()) {
        (Some(dir), Some(name)) => dir.join(name),
        _ => std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf()),
    }
}

/// Whether a file event can mean new content. Reading a file (our own reloads included) raises
/// open/close events, which must not trigger another reload.
pub fn is_content_change(kind: &EventKind) -> bool {
    match kind {
        EventKind::Create(_) | EventKind::Remove(_) | EventKind::Any => true,
        EventKind::Modify(m) => !matches!(m, ModifyKind::Metadata(_)),
        EventKind::Access(a) => matches!(a, AccessKind::Close(AccessMode::Write)),
        EventKind::Other => false,
    }
}

/// Swap and backup files that editors write next to the real one.
fn is_editor_noise(p: &Path) -> bool {
    let name = p.file_name().and_then(|n| n.to_str()).unwrap_or("");
    name.ends_with('~') || name.ends_with(".swp") || name.ends_with(".swx") || name.starts_with(".#") || name == "4913"
}
