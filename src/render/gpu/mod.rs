//! What every pass builds on and nothing frame-specific: the device, readback, the formats and pipeline parts passes share, shader sources and hot reload, textures and samplers, meshes, GPU timing, errors.

pub mod context;
pub mod error;
pub mod mesh;
pub mod parts;
pub mod readback;
pub mod shaders;
pub mod textures;
pub mod timing;
