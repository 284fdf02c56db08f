//! GPU forms of the physical sky models' parameters and the storage of their tables (the `lut`
//! and `precomputed` ones, which the renderer shares between passes), for every pass that
//! evaluates a model (`shaders/sky_model/`). The atmosphere types themselves know nothing of wgpu.

use bytemuck::{Pod, Zeroable};

use crate::atmosphere::{Atmosphere, LutSettings, OpticalDepth, PrecomputedSettings, SingleSettings};

/// Keep in sync with `Atmosphere` in shaders/sky_model/atmosphere.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable, PartialEq)]
pub struct AtmosphereUniform {
    /// Rayleigh scattering rgb, km^-1; scale height, km.
    pub rayleigh: [f32; 4],
    /// Mie scattering rgb (km^-1), scale height (km).
    pub mie_scattering: [f32; 4],
    /// Mie extinction rgb (km^-1), Cornette-Shanks g.
    pub mie_extinction: [f32; 4],
    /// Ozone absorption rgb (km^-1), tent centre (km).
    pub ozone: [f32; 4],
    /// Ground radius, top radius (km), ozone half width (km), sun angular radius (rad).
    pub shape: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<AtmosphereUniform>() == 80);

impl From<&Atmosphere> for AtmosphereUniform {
    fn from(a: &Atmosphere) -> Self {
        let [r, g, b] = a.rayleigh_scattering_per_km.map(|x| x as f32);
        let [or, og, ob] = a.ozone_absorption_per_km.map(|x| x as f32);
        let [sr, sg, sb] = a.mie_scattering_per_km.map(|x| x as f32);
        let [er, eg, eb] = a.mie_extinction_per_km.map(|x| x as f32);
        Self {
            rayleigh: [r, g, b, a.rayleigh_scale_height_km as f32],
            mie_scattering: [sr, sg, sb, a.mie_scale_height_km as f32],
            mie_extinction: [er, eg, eb, a.mie_g as f32],
            ozone: [or, og, ob, a.ozone_center_km as f32],
            shape: [a.ground_radius_km as f32, a.top_radius_km as f32, a.ozone_half_width_km as f32, a.sun_angular_radius_rad as f32],
        }
    }
}

/// Keep in sync with `SingleSettings` in shaders/sky_model/single.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable, PartialEq, Eq)]
pub struct SingleUniform {
    /// Samples along the view ray.
    pub view_steps: u32,
    /// Samples towards the sun (numerical mode).
    pub sun_steps: u32,
    /// 0: erf, 1: numerical.
    pub numeric: u32,
    /// Padding.
    pub pad: u32,
}
const _: () = assert!(std::mem::size_of::<SingleUniform>() == 16);

impl From<&SingleSettings> for SingleUniform {
    fn from(s: &SingleSettings) -> Self {
        Self { view_steps: s.view_steps.max(1), sun_steps: s.sun_steps.max(1), numeric: matches!(s.optical_depth, OpticalDepth::Numerical) as u32, pad: 0 }
    }
}

/// Keep in sync with `LutParams` in shaders/sky_model/lut_sampling.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable, PartialEq)]
pub struct LutUniform {
    /// Transmittance width, height; multiple-scattering side; direction grid.
    pub sizes: [u32; 4],
    /// Transmittance, multiple-scattering and view-ray samples; unused.
    pub steps: [u32; 4],
    /// Ground albedo; the Mie phase function's Legendre moments g_1, g_2; unused.
    pub albedo_phase: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<LutUniform>() == 48);

impl LutUniform {
    /// The GPU form of `settings` with a ground albedo and the Mie asymmetry `mie_g`.
    pub fn new(settings: &LutSettings, albedo: f32, mie_g: f64) -> Self {
        let [w, h] = settings.transmittance_size;
        let [g1, g2] = crate::atmosphere::cornette_shanks_moments(mie_g);
        Self {
            sizes: [w, h, settings.multiscattering_size, settings.multiscattering_grid],
            steps: [settings.transmittance_steps, settings.multiscattering_steps, settings.view_steps, 0],
            albedo_phase: [albedo, g1 as f32, g2 as f32, 0.0],
        }
    }
}

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
            transmittance: storage("LutTables::transmittance", (tw * th * 16) as u64, wgpu::BufferUsages::empty()),
            multiscattering: storage("LutTables::multiscattering", (m * m * MULTISCATTERING_LAYERS * MULTISCATTERING_REGIONS * 16) as u64, wgpu::BufferUsages::empty()),
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

/// Layout entry of a compute-stage storage buffer.
pub fn storage_entry(binding: u32, read_only: bool) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer { ty: wgpu::BufferBindingType::Storage { read_only }, has_dynamic_offset: false, min_binding_size: None },
        count: None,
    }
}

/// The `lut` model's table builders (shaders/sky_luts.wgsl), for the sky LUTs pass and the probe.
pub struct LutBuilder {
    layout: wgpu::BindGroupLayout,
    transmittance: wgpu::ComputePipeline,
    multiscattering: wgpu::ComputePipeline,
    /// The third order and the extrapolated ones above it.
    later_orders: wgpu::ComputePipeline,
}

impl LutBuilder {
    /// Builds the pipelines with `group0` as bind group 0 (the frame's globals, or an empty layout).
    pub fn new(device: &wgpu::Device, library: &crate::render::gpu::shaders::ShaderLibrary, group0: &wgpu::BindGroupLayout) -> crate::render::gpu::error::RenderResult<Self> {
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("SkyLuts::layout"),
            entries: &[crate::render::gpu::parts::uniform_entry(0, wgpu::ShaderStages::COMPUTE), storage_entry(1, true), storage_entry(2, false), storage_entry(3, false)],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("SkyLuts::pipeline_layout"),
            bind_group_layouts: &[Some(group0), Some(&layout)],
            immediate_size: 0,
        });
        let module = crate::render::gpu::shaders::module(device, library, "sky_luts")?;
        let pipeline = |entry: &str, label: &str| crate::render::gpu::shaders::compute_pipeline(device, &pipeline_layout, &module, entry, label);
        Ok(Self {
            transmittance: pipeline("cs_transmittance", "SkyLuts::transmittance")?,
            multiscattering: pipeline("cs_multiscattering", "SkyLuts::multiscattering")?,
            later_orders: pipeline("cs_multiscattering_later", "SkyLuts::multiscattering_later")?,
            layout,
        })
    }

    /// A bind group of the builders over `tables` with the atmosphere uniform `atmosphere`.
    pub fn bind_group(&self, device: &wgpu::Device, atmosphere: &wgpu::Buffer, tables: &LutTables) -> wgpu::BindGroup {
        let [p, t, m] = tables.entries(1);
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("SkyLuts::bind_group"),
            layout: &self.layout,
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: atmosphere.as_entire_binding() }, p, t, m],
        })
    }

    /// Records both tables' builds (transmittance first: the other reads it) into `cpass`, whose
    /// bind group 0 is set; `bind_group` comes from [`Self::bind_group`].
    pub fn dispatch(&self, cpass: &mut wgpu::ComputePass<'_>, bind_group: &wgpu::BindGroup, settings: &LutSettings) {
        let [w, h] = settings.transmittance_size;
        let m = settings.multiscattering_size;
        cpass.set_bind_group(1, bind_group, &[]);
        cpass.set_pipeline(&self.transmittance);
        cpass.dispatch_workgroups((w * h).div_ceil(64), 1, 1);
        cpass.set_pipeline(&self.multiscattering);
        cpass.dispatch_workgroups((m * m).div_ceil(64), 1, 1);
        cpass.set_pipeline(&self.later_orders);
        cpass.dispatch_workgroups((m * m).div_ceil(64), 1, 1);
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
