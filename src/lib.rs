//! skytune: author and debug real-time skies in the style of the NeL engine's sky system.
//!
//! Layers, lowest first; a layer uses only those before it (docs/architecture.md):
//! - [`support`]: safe file writes, progress and cancellation of long work.
//! - [`atmosphere`]: physical atmospheres and the double-precision reference (no GPU types).
//! - [`sky`]: the sky description file, validation, bitmap sampling and per-frame evaluation
//!   (no GPU types).
//! - [`render`]: the wgpu renderer (no UI types).
//! - [`files`]: watching and hot reload of sky files, snapshots, exports for engines.
//! - [`measure`]: the sky models' points of speed against accuracy, `kind = "auto"`, the
//!   stability sweep, soak runs, bakes and image differences.
//! - [`app`]: the window (egui and winit).

pub mod app;
pub mod atmosphere;
pub mod files;
pub mod measure;
pub mod render;
pub mod sky;
pub mod support;

/// Which build this is, for measurements: "release build of skytune at 1a2b3c4" (the commit the
/// build was made from; uncommitted changes are not named).
pub fn build_line() -> String {
    format!("{} build of skytune at {}", if cfg!(debug_assertions) { "debug" } else { "release" }, option_env!("SKYTUNE_COMMIT").unwrap_or("an unknown commit"))
}
