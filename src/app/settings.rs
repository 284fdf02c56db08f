//! What the window remembers between runs: size, last sky, recent files.

use std::path::PathBuf;

use serde::{Deserialize, Serialize};

/// Persisted window state (`$XDG_CONFIG_HOME/skytune/state.toml`).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(default)]
pub struct Settings {
    /// Inner window size, logical pixels.
    pub window_size: [u32; 2],
    /// Last sky file opened (None: the built-in sky).
    pub last_sky: Option<PathBuf>,
    /// Recently opened sky files, most recent first.
    pub recent: Vec<PathBuf>,
    /// Panel widths, which panels and sections are open.
    pub panels: super::layout::PanelLayout,
}

impl Default for Settings {
    fn default() -> Self {
        Self { window_size: [1280, 720], last_sky: None, recent: Vec::new(), panels: Default::default() }
    }
}

/// Most recent files kept.
const MAX_RECENT: usize = 8;

impl Settings {
    /// Where the settings live (None when no config folder can be found).
    pub fn path() -> Option<PathBuf> {
        if let Some(p) = std::env::var_os("SKYTUNE_CONFIG") {
            return Some(PathBuf::from(p));
        }
        let base = std::env::var_os("XDG_CONFIG_HOME").map(PathBuf::from).or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".config")))?;
        Some(base.join("skytune").join("state.toml"))
    }

    /// Loads the settings; never a reason not to start. A missing file gives the defaults; a
    /// corrupt one (not TOML, not UTF-8, wrong types, absurd sizes) is reported, kept beside as
    /// `state.toml.corrupt` for inspection, and replaced by the defaults. Returns the settings and
    /// the report, if any.
    pub fn load() -> (Self, Option<String>) {
        let Some(path) = Self::path() else { return (Self::default(), None) };
        let problem = match std::fs::read(&path) {
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return (Self::default(), None),
            Err(e) => format!("cannot read it: {e}"),
            Ok(bytes) => match std::str::from_utf8(&bytes).map_err(|e| e.to_string()).and_then(|t| toml::from_str::<Settings>(t).map_err(|e| e.to_string())) {
                Ok(s) if s.window_size.iter().all(|v| (1..=16384).contains(v)) && s.panels_are_sane() => return (s, None),
                Ok(s) if !s.panels_are_sane() => format!("panels {:?} has widths outside 0..=16384", s.panels),
                Ok(s) => format!("window_size {:?} is out of range 1..=16384", s.window_size),
                Err(e) => e.trim().to_string(),
            },
        };
        let kept = path.with_extension("toml.corrupt");
        let _ = std::fs::rename(&path, &kept);
        let defaults = Self::default();
        defaults.save();
        let report = format!("the settings file {} was unusable ({problem}); it was moved to {} and replaced by defaults", path.display(), kept.display());
        log::warn!("{report}");
        (defaults, Some(report))
    }

    /// Saves the settings; failures are logged, never fatal.
    pub fn save(&self) {
        let Some(path) = Self::path() else { return };
        let result = toml::to_string(self).map_err(std::io::Error::other).and_then(|text| crate::support::safe_write::write_atomic(&path, text.as_bytes()).map_err(|e| e.source));
        if let Err(e) = result {
            log::warn!("cannot save {}: {e}", path.display());
        }
    }

    fn panels_are_sane(&self) -> bool {
        [self.panels.left_width, self.panels.right_width].iter().all(|w| w.is_finite() && (0.0..=16384.0).contains(w))
    }

    /// Records an opened sky file.
    pub fn opened(&mut self, path: PathBuf) {
        self.recent.retain(|p| p != &path);
        self.recent.insert(0, path.clone());
        self.recent.truncate(MAX_RECENT);
        self.last_sky = Some(path);
    }
}
