//! Snapshots of a sky: its file and every file it references, copied into a hidden folder next to
//! the sky (`.skytune-snapshots/NAME/`), so "before my edit" stays one click away. Snapshots are
//! written by copying to a temporary folder and renaming it; the artist's files are only read.

use std::path::{Component, Path, PathBuf};

use thiserror::Error;

use crate::sky::Sky;

/// Name of the folder holding a sky's snapshots, next to the sky file.
pub const SNAPSHOT_DIR: &str = ".skytune-snapshots";

/// A snapshot that could not be written or read.
#[derive(Debug, Error)]
pub enum SnapshotError {
    /// The built-in sky has no files to snapshot.
    #[error("the built-in sky has no file to snapshot; open a sky file (or `skytune new-sky`) first")]
    NoFile,
    /// A referenced file lies outside the sky's folder, where a snapshot cannot mirror it.
    #[error("snapshot of {sky}: {file} lies outside the sky's folder")]
    Outside {
        /// The sky file.
        sky: String,
        /// The referenced file.
        file: String,
    },
    /// The name cannot be a folder name.
    #[error("snapshot name \"{0}\": use letters, digits, '-', '_' or '.' (not only dots)")]
    BadName(String),
    /// A snapshot of that name exists.
    #[error("a snapshot named \"{0}\" exists already")]
    Exists(String),
    /// Reading or writing failed.
    #[error("{what} {path}: {source}")]
    Io {
        /// What was being done.
        what: &'static str,
        /// The path.
        path: String,
        /// The error.
        source: std::io::Error,
    },
}

fn io<'a>(what: &'static str, path: &'a Path) -> impl FnOnce(std::io::Error) -> SnapshotError + 'a {
    move |source| SnapshotError::Io { what, path: path.display().to_string(), source }
}

/// A saved snapshot.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Snapshot {
    /// Its name (the folder's).
    pub name: String,
    /// The sky file inside it.
    pub sky_file: PathBuf,
}

/// The snapshots folder of a sky file.
pub fn snapshot_root(sky_file: &Path) -> PathBuf {
    sky_file.parent().unwrap_or(Path::new(".")).join(SNAPSHOT_DIR)
}

/// A default snapshot name from the time: `2026-11-24_01-30-05`.
pub fn timestamp_name() -> String {
    let secs = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_secs());
    let (days, rest) = (secs / 86400, secs % 86400);
    // Civil date from days since 1970-01-01 (Howard Hinnant's algorithm).
    let z = days as i64 + 719468;
    let era = z.div_euclid(146097);
    let doe = z - era * 146097;
    let yoe = (doe - doe / 1460 + doe / 36524 - doe / 146096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!("{y:04}-{m:02}-{d:02}_{:02}-{:02}-{:02}", rest / 3600, rest % 3600 / 60, rest % 60)
}

/// Copies `sky_file` and every file `sky` references into `.skytune-snapshots/NAME/` next to it,
/// at the same paths relative to the sky's folder.
pub fn save(sky_file: &Path, sky: &Sky, name: &str) -> Result<Snapshot, SnapshotError> {
    if name.is_empty() || name.chars().all(|c| c == '.') || !name.chars().all(|c| c.is_ascii_alphanumeric() || "-_.".contains(c)) {
        return Err(SnapshotError::BadName(name.to_string()));
    }
    let base = sky_file.parent().unwrap_or(Path::new("."));
    let mut files = vec![sky_file.to_path_buf()];
    files.extend(sky.watched_files.iter().filter(|f| f.is_file()).cloned());
    let mut relative = Vec::new();
    for f in &files {
        let rel = f.strip_prefix(base).ok().filter(|r| r.components().all(|c| matches!(c, Component::Normal(_))));
        match rel {
            Some(r) => relative.push((f.clone(), r.to_path_buf())),
            None => {
                // Paths may be spelled differently (./x, absolute): compare canonical forms.
                let (cf, cb) = (f.canonicalize().map_err(io("reading", f))?, base.canonicalize().map_err(io("reading", base))?);
                let r = cf.strip_prefix(&cb).map_err(|_| SnapshotError::Outside { sky: sky_file.display().to_string(), file: f.display().to_string() })?;
                relative.push((f.clone(), r.to_path_buf()));
            }
        }
    }
    let root = snapshot_root(sky_file);
    let target = root.join(name);
    if target.exists() {
        return Err(SnapshotError::Exists(name.to_string()));
    }
    let staging = root.join(format!(".{name}.partial"));
    let _ = std::fs::remove_dir_all(&staging);
    for (from, rel) in &relative {
        let to = staging.join(rel);
        if let Some(parent) = to.parent() {
            std::fs::create_dir_all(parent).map_err(io("creating", parent))?;
        }
        std::fs::copy(from, &to).map_err(io("copying", from))?;
    }
    std::fs::rename(&staging, &target).map_err(io("renaming", &staging))?;
    let sky_name = sky_file.file_name().map(PathBuf::from).unwrap_or_else(|| PathBuf::from("sky.toml"));
    Ok(Snapshot { name: name.to_string(), sky_file: target.join(sky_name) })
}

/// The snapshots of a sky file, oldest name first.
pub fn list(sky_file: &Path) -> Vec<Snapshot> {
    let Some(sky_name) = sky_file.file_name() else { return Vec::new() };
    let Ok(entries) = std::fs::read_dir(snapshot_root(sky_file)) else { return Vec::new() };
    let mut out: Vec<Snapshot> = entries
        .filter_map(Result::ok)
        .filter_map(|e| {
            let name = e.file_name().to_str()?.to_string();
            let sky = e.path().join(sky_name);
            (!name.starts_with('.') && sky.is_file()).then_some(Snapshot { name, sky_file: sky })
        })
        .collect();
    out.sort_by(|a, b| a.name.cmp(&b.name));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_snapshot_copies_the_sky_and_its_bitmaps_and_loads() {
        let dir = tempfile::tempdir().unwrap();
        let palette = crate::sky::procedural::preset("default").unwrap();
        let sky_file = crate::sky::builtin::write_sky_folder(dir.path(), palette, 7).unwrap();
        let sky = crate::sky::load_sky_file(&sky_file).unwrap();
        let before: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
        let snap = save(&sky_file, &sky, "before").unwrap();
        assert_eq!(snap.sky_file, dir.path().join(SNAPSHOT_DIR).join("before").join("sky.toml"));
        let copy = crate::sky::load_sky_file(&snap.sky_file).unwrap();
        assert_eq!(copy.objects.len(), sky.objects.len());
        // The artist's folder only gained the hidden folder.
        let after: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(after.len(), before.len() + 1);
        assert!(matches!(save(&sky_file, &sky, "before"), Err(SnapshotError::Exists(_))));
        assert!(matches!(save(&sky_file, &sky, "../x"), Err(SnapshotError::BadName(_))));
        save(&sky_file, &sky, &timestamp_name()).unwrap();
        let names: Vec<_> = list(&sky_file).into_iter().map(|s| s.name).collect();
        assert_eq!(names.len(), 2);
        assert!(names.contains(&"before".to_string()));
    }
}
