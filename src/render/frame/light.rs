//! The light the main scene and lit clouds use, as data: bind group 0's second binding. The
//! renderer writes the NeL bitmaps' colours and which source the frame uses; when a sky model
//! lights the frame, its atmosphere stage puts the model's light in [`SceneLight::model`] on the
//! GPU (`render/atmosphere/sky_view.rs`), and the shaders choose (`scene_fog_color` and the
//! others in shaders/globals.wgsl).

use bytemuck::{Pod, Zeroable};

use crate::sky::FrameSky;

/// Keep in sync with `SceneLight` in shaders/globals.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable, PartialEq)]
pub struct SceneLight {
    /// The bitmaps' main-scene fog colour (display values).
    pub fog_color: [f32; 4],
    /// The bitmaps' ambient light (display values).
    pub sun_ambient: [f32; 4],
    /// The bitmaps' diffuse sun light (display values).
    pub sun_diffuse: [f32; 4],
    /// The sky model's light, laid out as [`crate::render::atmosphere::AtmosphereGpu::sky_light`]
    /// (the GPU copies it here): [0].x the exposure scale; [1] fog colour, [2] ambient (the sky's
    /// mean radiance), [3] diffuse (the transmitted sun, E T / pi), display values. Zero until
    /// then.
    pub model: [[f32; 4]; 4],
    /// Which light this frame uses: x 1 when the model lights the main scene, y 1 when it lights
    /// the clouds (it has a map, and so a light); 0 for the bitmaps' colours.
    pub source: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<SceneLight>() == 8 * 16);

/// Byte offset of [`SceneLight::model`], where the model's light is copied on the GPU.
pub const MODEL_LIGHT_OFFSET: u64 = std::mem::offset_of!(SceneLight, model) as u64;

/// Where the frame's light comes from (a pass that computes a model's light says so:
/// [`crate::render::frame::pass::Pass::light_source`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum LightSource {
    /// The NeL bitmaps' colours light the scene and the clouds.
    #[default]
    Bitmaps,
    /// The sky model lights the clouds; the bitmaps the main scene.
    ModelClouds,
    /// The sky model lights the clouds and the main scene.
    Model,
}

impl SceneLight {
    /// The frame's bitmap colours, lit from `source`.
    pub fn new(frame: &FrameSky, source: LightSource) -> Self {
        let flag = |on: bool| if on { 1.0 } else { 0.0 };
        Self {
            fog_color: frame.fog_color,
            sun_ambient: frame.sun_ambient,
            sun_diffuse: frame.sun_diffuse,
            model: [[0.0; 4]; 4],
            source: [flag(source == LightSource::Model), flag(source != LightSource::Bitmaps), 0.0, 0.0],
        }
    }
}
