//! skytune: author and debug real-time skies in the style of the NeL engine's sky system.
//!
//! - [`sky`]: the sky description file, validation, bitmap sampling and per-frame evaluation
//!   (no GPU types).
//! - [`render`]: the wgpu renderer (no UI types).
//! - [`atmosphere`]: physical atmospheres and the double-precision reference (no GPU types).
//! - [`compare`]: differences between two renders (FLIP and channel figures, heat maps, layouts).
//! - [`fsx`]: writes through a temporary file and a rename.
//! - [`live`]: hot reload of sky files.
//! - [`progress`]: progress and cancellation of long work, and how it is shown on stderr.
//! - [`soak`]: long runs with random changes and reloads, measuring memory growth.
//! - [`snapshot`]: snapshots of a sky's files for before/after comparisons.
//! - [`watch`]: file watching, shared by sky and shader hot reload.

pub mod app;
pub mod atmosphere;
pub mod auto_model;
pub mod bake;
pub mod compare;
pub mod export;
pub mod fsx;
pub mod live;
pub mod modelbench;
pub mod progress;
pub mod render;
pub mod sky;
pub mod snapshot;
pub mod soak;
pub mod sweep;
pub mod watch;
