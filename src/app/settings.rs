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
}

impl Default for Settings {
    fn default() -> Self {
        Self { window_size: [1280, 720], last_sky: None, recent: Vec::new() }
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

    /// Loads the settings; a missing or unreadable file gives the defaults (with a warning).
    pub fn load() -> Self {
        let Some(path) = Self::path() else { return Self::default() };
        match std::fs::read_to_string(&path) {
            Ok(text) => toml::from_str(&text).unwrap_or_else(|e| {
                log::warn!("ignoring {}: {e}", path.display());
                Self::default()
            }),
            Err(_) => Self::default(),
        }
    }

    /// Saves the settings; failures are logged, never fatal.
    pub fn save(&self) {
        let Some(path) = Self::path() else { return };
        let result = path.parent().map_or(Ok(()), std::fs::create_dir_all).and_then(|_| {
            let text = toml::to_string(self).map_err(std::io::Error::other)?;
            std::fs::write(&path, text)
        });
        if let Err(e) = result {
            log::warn!("cannot save {}: {e}", path.display());
        }
    }

    /// Records an opened sky file.
    pub fn opened(&mut self, path: PathBuf) {
        self.recent.retain(|p| p != &path);
        self.recent.insert(0, path.clone());
        self.recent.truncate(MAX_RECENT);
        self.last_sky = Some(path);
    }
}
