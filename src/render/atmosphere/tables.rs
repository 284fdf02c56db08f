//! Storage of the physical models' tables (the `lut` model's transmittance and multiple
//! scattering, the `precomputed` model's tables), shared by the passes that build and read them.

use bytemuck::{Pod, Zeroable};

use crate::atmosphere::{LutSettings, PrecomputedSettings};
use crate::render::atmosphere::uniforms::LutUniform;

/// Values per multiple-scattering texel: the incoming radiance of the orders from the second on
/// in six real spherical harmonics (bands 0 to 2, those even about the plane of the sun and the
/// vertical). Keep in sync with `MS_LAYERS` in shaders/sky_model/lut_sampling.wgsl.
pub const MULTISCATTERING_LAYERS: u32 = 6;

/// Regions of the multiple-scattering buffer: the sum of the orders the model reads, and the
/// second order alone while the table is built.
pub const MULTISCATTERING_REGIONS: u32 = 2;

/// The `lut` model's tables: storage buffers of vec4 sized for the largest settings.
pub struct LutTables {
    /// `LutUniform` (read-only storage: Mesa 22's lavapipe miscompiles some uniform-driven loops).
    pub params: wgpu::Buffer,
    /// Transmittance, rgb per texel.
    pub transmittance: wgpu::Buffer,
    /// Multiple scattering: [`MULTISCATTERING_LAYERS`] rgb values per texel.
    pub multiscattering: wgpu::Buffer,
}

impl LutTables {
    /// Allocates the tables.
    pub fn new(device: &wgpu::Device) -> Self {
        let storage = |label: &str, size: u64, extra: wgpu::BufferUsages| {
            device.create_buffer(&wgpu::BufferDescriptor { label: Some(label), size, usage: wgpu::BufferUsages::STORAGE | extra, mapped_at_creation: false })
        };
        let [tw, th] = LutSettings::MAX_TRANSMITTANCE;
        let m = LutSettings::MAX_MULTISCATTERING;
        Self {
            params: storage("LutTables::params", std::mem::size_of::<LutUniform>() as u64, wgpu::BufferUsages::COPY_DST),
            transmittance: storage("LutTables::transmittance", (tw * th * 16) as u64, wgpu::BufferUsages::COPY_SRC),
            multiscattering: storage("LutTables::multiscattering", (m * m * MULTISCATTERING_LAYERS * MULTISCATTERING_REGIONS * 16) as u64, wgpu::BufferUsages::COPY_SRC),
        }
    }

    /// Bind group entries of the three buffers at `first`, `first + 1`, `first + 2`.
    pub fn entries(&self, first: u32) -> [wgpu::BindGroupEntry<'_>; 3] {
        [
            wgpu::BindGroupEntry { binding: first, resource: self.params.as_entire_binding() },
            wgpu::BindGroupEntry { binding: first + 1, resource: self.transmittance.as_entire_binding() },
            wgpu::BindGroupEntry { binding: first + 2, resource: self.multiscattering.as_entire_binding() },
        ]
    }
}

/// The tables' header, their first four texels. Keep in sync with `PrecomputedHeader` in
/// shaders/sky_model/precomputed_sampling.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable, PartialEq)]
pub struct PrecomputedHeader {
    /// Transmittance width, height; irradiance width, height (texels).
    pub sizes_2d: [u32; 4],
    /// Scattering texels along nu, mu_s, mu (both halves), r.
    pub sizes_4d: [u32; 4],
    /// Transmittance samples, samples along rays, density directions per half turn; storage of
    /// the looked-up tables (0 single, 1 half).
    pub steps: [u32; 4],
    /// Ground albedo, smallest sun cosine tabulated; unused.
    pub ground: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<PrecomputedHeader>() == 64);

impl PrecomputedHeader {
    /// The header of tables built with `settings` over a ground of `albedo`.
    pub fn new(settings: &PrecomputedSettings, albedo: f32) -> Self {
        let [tw, th] = settings.transmittance_size;
        let [iw, ih] = settings.irradiance_size;
        Self {
            sizes_2d: [tw, th, iw, ih],
            sizes_4d: settings.scattering_size,
            steps: [settings.transmittance_steps, settings.ray_steps, settings.density_directions, settings.precision as u32],
            ground: [albedo, PrecomputedSettings::MU_S_MIN, 0.0, 0.0],
        }
    }
}

/// Bytes the tables of `settings` take: the header, three 2D tables and five 4D tables of rgba32f.
pub fn table_bytes(settings: &PrecomputedSettings) -> u64 {
    let [tw, th] = settings.transmittance_size;
    let [iw, ih] = settings.irradiance_size;
    let texels = 4 + (tw * th) as u64 + 2 * (iw * ih) as u64 + 5 * settings.scattering_texels() as u64;
    texels * 16
}

/// The `precomputed` model's tables: one storage buffer (the header, then every table).
pub struct PrecomputedTables {
    /// The buffer.
    pub buffer: wgpu::Buffer,
    /// Its size, bytes.
    pub bytes: u64,
}

impl PrecomputedTables {
    /// Allocates tables large enough for `settings`.
    pub fn new(device: &wgpu::Device, settings: &PrecomputedSettings) -> Self {
        Self::with_bytes(device, table_bytes(settings))
    }

    /// Allocates tables large enough for any valid settings (the renderer's shared tables).
    pub fn largest(device: &wgpu::Device) -> Self {
        let largest = PrecomputedSettings {
            transmittance_size: PrecomputedSettings::MAX_TRANSMITTANCE,
            irradiance_size: PrecomputedSettings::MAX_IRRADIANCE,
            scattering_size: [PrecomputedSettings::MAX_SCATTERING_TEXELS, 1, 1, 1],
            ..Default::default()
        };
        Self::with_bytes(device, table_bytes(&largest))
    }

    fn with_bytes(device: &wgpu::Device, bytes: u64) -> Self {
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("PrecomputedTables::buffer"),
            size: bytes,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Self { buffer, bytes }
    }

    /// Whether tables of `settings` fit.
    pub fn holds(&self, settings: &PrecomputedSettings) -> bool {
        table_bytes(settings) <= self.bytes
    }
}

/// Whether the shared tables are complete, for the passes that read them.
#[derive(Debug, Default)]
pub struct PrecomputedState {
    /// The tables hold a finished build (none is under way).
    pub complete: std::sync::atomic::AtomicBool,
    /// Finished builds so far: a reader's results depend on it.
    pub generation: std::sync::atomic::AtomicU64,
}

/// Format of the aerial-perspective volume's textures.
pub const AERIAL_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// The aerial-perspective volume: `aerial_perspective` builds it in the compute phase, the scene
/// reads it. Sized for the largest settings; a smaller volume fills a corner (the readers scale
/// their coordinates by the size in [`Self::params`]).
pub struct AerialVolume {
    /// [`crate::render::atmosphere::uniforms::AerialUniform`] of the volume the textures hold.
    pub params: wgpu::Buffer,
    /// Light scattered in up to each slice (rgb, sr^-1 per unit of solar irradiance).
    pub in_scatter: wgpu::Texture,
    /// Transmittance up to each slice (rgb).
    pub transmittance: wgpu::Texture,
    /// Their views.
    pub in_scatter_view: wgpu::TextureView,
    /// Its view.
    pub transmittance_view: wgpu::TextureView,
    /// Trilinear, clamped.
    pub sampler: wgpu::Sampler,
}

impl AerialVolume {
    /// Allocates the volume at [`crate::atmosphere::aerial::AerialSettings::MAX_SIZE`].
    pub fn new(device: &wgpu::Device) -> Self {
        let [w, h, d] = crate::atmosphere::aerial::AerialSettings::MAX_SIZE;
        let texture = |label: &str| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d { width: w, height: h, depth_or_array_layers: d },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D3,
                format: AERIAL_FORMAT,
                usage: wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            })
        };
        let in_scatter = texture("AerialVolume::in_scatter");
        let transmittance = texture("AerialVolume::transmittance");
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("AerialVolume::params"),
            size: std::mem::size_of::<crate::render::atmosphere::uniforms::AerialUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("AerialVolume::sampler"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        Self {
            params,
            in_scatter_view: in_scatter.create_view(&Default::default()),
            transmittance_view: transmittance.create_view(&Default::default()),
            in_scatter,
            transmittance,
            sampler,
        }
    }

    /// Layout entries of the readers' bindings from `first`: params, the two textures, the
    /// sampler, visible to `stages`.
    pub fn layout_entries(first: u32, stages: wgpu::ShaderStages) -> [wgpu::BindGroupLayoutEntry; 4] {
        let texture = |binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: stages,
            ty: wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: true },
                view_dimension: wgpu::TextureViewDimension::D3,
                multisampled: false,
            },
            count: None,
        };
        [
            crate::render::gpu::parts::uniform_entry(first, stages),
            texture(first + 1),
            texture(first + 2),
            wgpu::BindGroupLayoutEntry { binding: first + 3, visibility: stages, ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering), count: None },
        ]
    }

    /// The readers' bind group entries from `first` (as [`Self::layout_entries`]).
    pub fn entries(&self, first: u32) -> [wgpu::BindGroupEntry<'_>; 4] {
        [
            wgpu::BindGroupEntry { binding: first, resource: self.params.as_entire_binding() },
            wgpu::BindGroupEntry { binding: first + 1, resource: wgpu::BindingResource::TextureView(&self.in_scatter_view) },
            wgpu::BindGroupEntry { binding: first + 2, resource: wgpu::BindingResource::TextureView(&self.transmittance_view) },
            wgpu::BindGroupEntry { binding: first + 3, resource: wgpu::BindingResource::Sampler(&self.sampler) },
        ]
    }
}
