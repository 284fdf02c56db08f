//! Bind group 0: per-frame globals shared by every pass.

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3};

use crate::render::frame::camera::Camera;
use crate::sky::FrameSky;

/// Per-frame globals. Keep in sync with `Globals` in shaders/globals.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct Globals {
    /// Main-scene camera, world -> clip.
    pub clip_from_world: [[f32; 4]; 4],
    /// Rotation-only camera for sky objects (camera at the dome centre).
    pub clip_from_sky: [[f32; 4]; 4],
    /// World -> rotating celestial frame.
    pub celestial_from_world: [[f32; 4]; 4],
    /// Unit vector towards the sun (w unused).
    pub towards_sun: [f32; 4],
    /// Main-scene fog colour.
    pub fog_color: [f32; 4],
    /// Sun ambient light.
    pub sun_ambient: [f32; 4],
    /// Sun diffuse light.
    pub sun_diffuse: [f32; 4],
    /// hour, hours_per_day, weather, game_hours.
    pub time: [f32; 4],
    /// width, height, 1/width, 1/height, pixels.
    pub viewport: [f32; 4],
    /// Main-scene camera position, m.
    pub camera_position: [f32; 4],
    /// x: 1 when the drawing phases write exposed linear radiance into the HDR target, 0 when
    /// they write display values (see [`crate::render::frame::pass::Target`]); y: the tone mapper
    /// ([`crate::render::passes::tone_map::ToneMapUniform`]), which display-referred colours are inverted through;
    /// z: 1 on a display-referred physical frame matched to the HDR picture.
    pub output: [f32; 4],
    /// Sun light on lit clouds (display values): the sky model's transmitted sun (E T / pi, as
    /// `sun_diffuse`) when a physical or analytic model shows, else the sky's `sun_diffuse`.
    pub cloud_sun: [f32; 4],
    /// Ambient light on lit clouds (display values): the model's mean sky radiance, else `sun_ambient`.
    pub cloud_ambient: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<Globals>() == 3 * 64 + 10 * 16);

/// Byte offset of `cloud_sun` in [`Globals`], followed by `cloud_ambient` (a physical or analytic
/// sky model overwrites both on the GPU: see `render/atmosphere/sky_view.rs`).
pub const CLOUD_LIGHT_OFFSET: u64 = std::mem::offset_of!(Globals, cloud_sun) as u64;
const _: () = assert!(std::mem::offset_of!(Globals, cloud_ambient) - std::mem::offset_of!(Globals, cloud_sun) == 16);

/// Byte offset of `fog_color` in [`Globals`], followed by `sun_ambient` and `sun_diffuse` (a
/// physical sky model overwrites the three on the GPU: see `render/atmosphere/sky_view.rs`).
pub const SCENE_LIGHT_OFFSET: u64 = std::mem::offset_of!(Globals, fog_color) as u64;
const _: () = assert!(std::mem::offset_of!(Globals, sun_diffuse) - std::mem::offset_of!(Globals, fog_color) == 32);
const _: () = assert!(std::mem::offset_of!(Globals, sun_ambient) - std::mem::offset_of!(Globals, fog_color) == 16);

impl Globals {
    /// Globals for a frame seen by `camera` on a `width` x `height` target.
    /// `matched`: a display-referred physical frame whose layers are matched to the HDR picture
    /// ([`crate::render::plan::strategy::PhysicalTarget::DisplayMatched`]).
    pub fn new(frame: &FrameSky, camera: &Camera, width: u32, height: u32, (target, matched): (crate::render::frame::pass::Target, bool)) -> Self {
        let aspect = width as f32 / height.max(1) as f32;
        let (clip_from_world, clip_from_sky) = camera.matrices(aspect);
        let v = |c: [f32; 4]| c;
        let s: Vec3 = frame.towards_sun;
        Globals {
            clip_from_world: clip_from_world.to_cols_array_2d(),
            clip_from_sky: clip_from_sky.to_cols_array_2d(),
            celestial_from_world: Mat4::from_quat(frame.celestial_from_world).to_cols_array_2d(),
            towards_sun: [s.x, s.y, s.z, 0.0],
            fog_color: v(frame.fog_color),
            sun_ambient: v(frame.sun_ambient),
            sun_diffuse: v(frame.sun_diffuse),
            time: [frame.hour, frame.hours_per_day, frame.weather, frame.game_hours as f32],
            viewport: [width as f32, height as f32, 1.0 / width.max(1) as f32, 1.0 / height.max(1) as f32],
            camera_position: camera.position().extend(1.0).to_array(),
            cloud_sun: v(frame.sun_diffuse),
            cloud_ambient: v(frame.sun_ambient),
            output: [
                if target == crate::render::frame::pass::Target::Hdr { 1.0 } else { 0.0 },
                crate::render::passes::tone_map::ToneMapUniform::from(frame.sky_model.tone_mapper).settings[0] as f32,
                if matched { 1.0 } else { 0.0 },
                0.0,
            ],
        }
    }
}

/// The globals buffer, its layout and bind group.
pub struct GlobalsBinding {
    /// Uniform buffer holding [`Globals`].
    pub buffer: wgpu::Buffer,
    /// Layout of bind group 0, used by every pipeline.
    pub layout: wgpu::BindGroupLayout,
    /// Bind group 0.
    pub bind_group: wgpu::BindGroup,
}

impl GlobalsBinding {
    /// Creates the buffer and bind group.
    pub fn new(device: &wgpu::Device) -> Self {
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("Globals::buffer"),
            size: std::mem::size_of::<Globals>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("Globals::layout"),
            entries: &[crate::render::gpu::parts::uniform_entry(0, wgpu::ShaderStages::VERTEX_FRAGMENT | wgpu::ShaderStages::COMPUTE)],
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("Globals::bind_group"),
            layout: &layout,
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: buffer.as_entire_binding() }],
        });
        Self { buffer, layout, bind_group }
    }
}
