//! The physical atmosphere on the GPU, with one owner: [`AtmosphereGpu`] holds the frame's
//! atmosphere uniform (written once a frame, bound by every pass that marches it), the tables of
//! the physical models, the sky-view map and the light the map's model gives the scene. The
//! passes here build and fill them in the compute phase: [`sky_luts`] (transmittance and
//! multiple scattering), [`precomputed_tables`] (the `precomputed` model's tables),
//! [`sky_view`] (the map and its exposure) and [`aerial_perspective`] (the volume of the
//! atmosphere between the viewer and the scene). [`radiance_probe`] evaluates the same models outside
//! the frame. The atmosphere itself (`crate::atmosphere`) knows nothing of wgpu.

pub mod aerial_perspective;
pub mod aerial_probe;
mod cpu_maps;
pub mod precomputed_tables;
pub mod radiance_probe;
pub mod sky_luts;
pub mod sky_view;
pub mod tables;
pub mod uniforms;

use crate::atmosphere::Atmosphere;
use crate::render::plan::resolution::SKY_VIEW_SIZE;
use tables::{AerialVolume, LutTables, PrecomputedState, PrecomputedTables};
use uniforms::AtmosphereUniform;

/// Format of the sky-view map: linear radiance above 1 near the sun must survive.
pub const SKY_VIEW_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// The GPU side of the frame's atmosphere: made once by the renderer, shared by the passes.
pub struct AtmosphereGpu {
    /// [`AtmosphereUniform`] of the frame's atmosphere ([`Self::prepare`] writes it).
    pub uniform: wgpu::Buffer,
    /// What [`Self::uniform`] holds.
    written: Option<AtmosphereUniform>,
    /// The `lut` model's tables: `sky_luts` builds them, `sky_view` reads them.
    pub luts: LutTables,
    /// The `precomputed` model's tables: `precomputed_tables` builds them, `sky_view` reads them.
    pub precomputed: PrecomputedTables,
    /// Whether they are complete (a software rasteriser builds them over several frames).
    pub precomputed_state: std::sync::Arc<PrecomputedState>,
    /// The sky-view map: a physical model's exposed linear radiance by direction (`sky_view`
    /// writes it in the compute phase, `sky_objects` samples it in the gradient stage).
    pub sky_view: wgpu::Texture,
    /// Its view.
    pub sky_view_view: wgpu::TextureView,
    /// Its sampler: both clamp (the azimuth's ends, towards the sun and away from it, are the
    /// sky's planes of symmetry).
    pub sky_view_sampler: wgpu::Sampler,
    /// The map's light, four vec4 (units: display values but [0]): [0].x the exposure scale of
    /// the last map (2^EV, or the automatic one); [1], [2], [3] the scene's fog colour, ambient
    /// and diffuse light from the model (`cs_exposure` in shaders/sky_view.wgsl writes them).
    pub sky_light: wgpu::Buffer,
    /// The aerial-perspective volume: `aerial_perspective` builds it from the LUT tables, the
    /// scene reads it.
    pub aerial: AerialVolume,
}

impl AtmosphereGpu {
    /// Allocates the uniform, the tables (sized for the largest settings) and the map.
    pub fn new(device: &wgpu::Device) -> Self {
        let (width, height) = SKY_VIEW_SIZE;
        let sky_view = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("SkyView::map"),
            size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: SKY_VIEW_FORMAT,
            usage: wgpu::TextureUsages::COPY_DST | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        let sky_view_view = sky_view.create_view(&Default::default());
        let sky_view_sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("SkyView::sampler"),
            address_mode_u: wgpu::AddressMode::ClampToEdge,
            address_mode_v: wgpu::AddressMode::ClampToEdge,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        let uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("AtmosphereGpu::uniform"),
            size: std::mem::size_of::<AtmosphereUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let sky_light = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("AtmosphereGpu::sky_light"),
            size: 64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        Self {
            uniform,
            written: None,
            luts: LutTables::new(device),
            precomputed: PrecomputedTables::largest(device),
            precomputed_state: Default::default(),
            sky_view,
            sky_view_view,
            sky_view_sampler,
            sky_light,
            aerial: AerialVolume::new(device),
        }
    }

    /// Writes the frame's atmosphere into [`Self::uniform`] when it changed, before any pass
    /// records: every pass of the frame reads the same one.
    pub fn prepare(&mut self, queue: &wgpu::Queue, atmosphere: &Atmosphere) {
        let next = AtmosphereUniform::from(atmosphere);
        if self.written != Some(next) {
            queue.write_buffer(&self.uniform, 0, bytemuck::bytes_of(&next));
            self.written = Some(next);
        }
    }
}
