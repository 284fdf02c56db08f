//! Sky descriptions: file format, loading and validation, bitmap sampling and per-frame evaluation.
//! Nothing here knows about wgpu, egui or winit.

pub mod bitmap;
pub mod builtin;
pub mod error;
pub mod eval;
mod evaluate;
pub mod load;
pub mod model;
pub mod particle_sim;
pub mod particles;
pub mod procedural;
pub mod resolved;
pub mod sky_model;
pub mod starfield;

pub use bitmap::{ColorBitmap, Rgba};
pub use error::{SkyError, SkyErrors};
pub use eval::{Clock, FrameInput, FrameSky, Hidden, ObjectFrame, StarsFrame, Stepping, Tier, VersionFrame};
pub use load::{load_sky, load_sky_file, AssetSource, FsSource};
pub use resolved::Sky;
