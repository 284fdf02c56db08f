//! wgpu renderer of sky scenes. One pass = one module here + one `.wgsl` file in `shaders/`.

pub mod camera;
pub mod context;
pub mod glare;
pub mod globals;
pub mod headless;
pub mod mesh;
pub mod renderer;
pub mod scene;
pub mod shaders;
pub mod sky_objects;
pub mod stars;
pub mod textures;
pub mod timing;

pub use camera::Camera;
pub use context::{AdapterChoice, GpuContext};
pub use headless::{Headless, Offscreen};
pub use renderer::{FrameStats, RenderOptions, SkyRenderer};
pub use shaders::ShaderLibrary;

/// Depth buffer format of every pass.
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// Colour format of offscreen renders and screenshots (display-encoded, like the 2005 pipeline).
pub const OFFSCREEN_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
