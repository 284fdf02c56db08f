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
    /// Main-scene camera, clip -> world (view rays and scene positions from pixels).
    pub world_from_clip: [[f32; 4]; 4],
    /// The previous frame's main-scene camera, world -> clip (this frame's on the first frame):
    /// what reprojects a history into this frame.
    pub previous_clip_from_world: [[f32; 4]; 4],
    /// Unit vector towards the sun (w unused).
    pub towards_sun: [f32; 4],
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
    /// The scene's depth: the viewport's depth range it is stored in (x, y: [`crate::render::SCENE_DEPTH`]
    /// with the depth split), the camera's near and far planes (z, w; m), for
    /// `scene_distance_m` in shaders/globals.wgsl.
    pub depth: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<Globals>() == 5 * 64 + 6 * 16);

impl Globals {
    /// Globals for a frame seen by `camera` on a `width` x `height` target.
    /// `matched`: a display-referred physical frame whose layers are matched to the HDR picture
    /// ([`crate::render::plan::strategy::PhysicalTarget::DisplayMatched`]).
    pub fn new(frame: &FrameSky, camera: &Camera, width: u32, height: u32, (target, matched): (crate::render::frame::pass::Target, bool)) -> Self {
        let aspect = width as f32 / height.max(1) as f32;
        let (clip_from_world, clip_from_sky) = camera.matrices(aspect);
        let s: Vec3 = frame.towards_sun;
        Globals {
            clip_from_world: clip_from_world.to_cols_array_2d(),
            clip_from_sky: clip_from_sky.to_cols_array_2d(),
            celestial_from_world: Mat4::from_quat(frame.celestial_from_world).to_cols_array_2d(),
            world_from_clip: clip_from_world.inverse().to_cols_array_2d(),
            previous_clip_from_world: clip_from_world.to_cols_array_2d(),
            towards_sun: [s.x, s.y, s.z, 0.0],
            time: [frame.hour, frame.hours_per_day, frame.weather, frame.game_hours as f32],
            viewport: [width as f32, height as f32, 1.0 / width.max(1) as f32, 1.0 / height.max(1) as f32],
            camera_position: camera.position().extend(1.0).to_array(),
            depth: [0.0, 1.0, Camera::NEAR_M, Camera::FAR_M],
            output: [
                if target == crate::render::frame::pass::Target::Hdr { 1.0 } else { 0.0 },
                crate::render::passes::tone_map::ToneMapUniform::from(frame.sky_model.camera.tone_mapper).settings[0] as f32,
                if matched { 1.0 } else { 0.0 },
                0.0,
            ],
        }
    }
}

/// Bind group 0: the globals buffer and the scene's light, their layout and bind group.
pub struct GlobalsBinding {
    /// Uniform buffer holding [`Globals`].
    pub buffer: wgpu::Buffer,
    /// Uniform buffer holding [`crate::render::frame::light::SceneLight`] (binding 1).
    pub scene_light: wgpu::Buffer,
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
        let scene_light = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("Globals::scene_light"),
            size: std::mem::size_of::<crate::render::frame::light::SceneLight>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let stages = wgpu::ShaderStages::VERTEX_FRAGMENT | wgpu::ShaderStages::COMPUTE;
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("Globals::layout"),
            entries: &[crate::render::gpu::parts::uniform_entry(0, stages), crate::render::gpu::parts::uniform_entry(1, stages)],
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("Globals::bind_group"),
            layout: &layout,
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: buffer.as_entire_binding() }, wgpu::BindGroupEntry { binding: 1, resource: scene_light.as_entire_binding() }],
        });
        Self { buffer, scene_light, layout, bind_group }
    }
}
