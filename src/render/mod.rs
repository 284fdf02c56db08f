//! wgpu renderer of sky scenes, organised as an ordered list of phases (see [`frame::pass`]).
//! One pass = one module in [`passes`] (or the [`sky_objects`] and [`atmosphere`] folders) + one `.wgsl` file in
//! `shaders/` of the same name. [`plan`] decides how a frame is drawn without GPU types,
//! [`frame`] carries it out, [`gpu`] holds what every pass builds on.

pub mod atmosphere;
pub mod frame;
pub mod gpu;
pub mod passes;
pub mod plan;
pub mod sky_objects;

pub use frame::camera::Camera;
pub use frame::headless::{self, Headless, Offscreen};
pub use frame::options::{Occluder, RenderOptions, Skips, TestWall};
pub use frame::pass::{Pass, Phase};
pub use frame::renderer::{release_freed_memory, RenderTarget, SkyRenderer, SCENE_DEPTH, SKY_DEPTH};
pub use frame::stats::{FrameStats, UploadStats};
pub use gpu::context::{AdapterChoice, GpuContext};
pub use gpu::error::{RenderError, RenderResult};
pub use gpu::shaders::ShaderLibrary;
pub use passes::PASSES;
pub use plan::resolution::{Divisor, DomeResolution};
pub use plan::strategy::FillStrategy;

pub use gpu::parts::{DEPTH_FORMAT, HDR_FORMAT, OFFSCREEN_FORMAT};
