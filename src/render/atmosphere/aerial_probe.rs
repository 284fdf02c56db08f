//! Answers finite-ray radiance cases from the aerial-perspective volume the renderer builds: per
//! case, a camera looking along the case's view, the volume built by the frame's own builder
//! ([`AerialBuilder`]) from LUT tables built as the frame builds them, then read at the screen's
//! centre and the case's distance as the scene reads it (`aerial_lookup`,
//! shaders/aerial_probe.wgsl). For `skytune radiance`, the tests and the chart.

use wgpu::util::DeviceExt;

use crate::atmosphere::aerial::AerialSettings;
use crate::atmosphere::reference::Case;
use crate::atmosphere::{Atmosphere, LutSettings};
use crate::render::atmosphere::aerial_perspective::AerialBuilder;
use crate::render::atmosphere::radiance_probe::ProbeAnswers;
use crate::render::atmosphere::sky_luts::LutBuilder;
use crate::render::atmosphere::tables::{AerialVolume, LutTables};
use crate::render::atmosphere::uniforms::{AerialUniform, AerialUse, AtmosphereUniform, LutUniform};
use crate::render::frame::camera::Camera;
use crate::render::gpu::context::GpuContext;
use crate::render::gpu::error::RenderResult;
use crate::render::gpu::parts::storage_entry;
use crate::render::gpu::shaders::{self, ShaderLibrary};

/// The probe camera's vertical field of view, degrees, and aspect: the window's default view.
const FOV_Y_DEG: f32 = 70.0;
const ASPECT: f32 = 16.0 / 9.0;

/// Clip from world of the probe's camera at the origin looking along `view` (unit).
fn camera_along(view: glam::Vec3) -> glam::Mat4 {
    let up = if view.y.abs() > 0.99 { glam::Vec3::X } else { glam::Vec3::Y };
    glam::Mat4::perspective_rh(FOV_Y_DEG.to_radians(), ASPECT, Camera::NEAR_M, Camera::FAR_M) * glam::Mat4::look_to_rh(glam::Vec3::ZERO, view, up)
}

/// A uniform buffer holding `atmosphere`.
fn atmosphere_buffer(device: &wgpu::Device, atmosphere: &Atmosphere) -> wgpu::Buffer {
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("AerialProbe::atmosphere"),
        contents: bytemuck::bytes_of(&AtmosphereUniform::from(atmosphere)),
        usage: wgpu::BufferUsages::UNIFORM,
    })
}

/// The volume's builder, its tables and the reader.
pub struct AerialProbe {
    empty_layout: wgpu::BindGroupLayout,
    tables: LutTables,
    lut_builder: LutBuilder,
    builder: AerialBuilder,
    volume: AerialVolume,
    layout: wgpu::BindGroupLayout,
    read: wgpu::ComputePipeline,
}

impl AerialProbe {
    /// Builds the pipelines from `library`.
    pub fn new(ctx: &GpuContext, library: &ShaderLibrary) -> RenderResult<Self> {
        let device = &ctx.device;
        let compute = wgpu::ShaderStages::COMPUTE;
        let [a0, a1, a2, a3] = AerialVolume::layout_entries(0, compute);
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("AerialProbe::layout"),
            entries: &[
                a0,
                a1,
                a2,
                a3,
                crate::render::gpu::parts::uniform_entry(4, compute),
                storage_entry(5, false),
                storage_entry(6, true),
                storage_entry(7, true),
                storage_entry(8, true),
            ],
        });
        // Group 0 (the frame's globals) is declared by every module but unused here.
        let empty_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some("AerialProbe::empty_layout"), entries: &[] });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("AerialProbe::pipeline_layout"),
            bind_group_layouts: &[Some(&empty_layout), Some(&layout)],
            immediate_size: 0,
        });
        let module = shaders::module(device, library, "aerial_probe")?;
        let read = shaders::compute_pipeline(device, &pipeline_layout, &module, "cs_main", "AerialProbe::read")?;
        Ok(Self {
            tables: LutTables::new(device),
            lut_builder: LutBuilder::new(device, library, &empty_layout)?,
            builder: AerialBuilder::new(device, library, &empty_layout)?,
            volume: AerialVolume::new(device),
            empty_layout,
            layout,
            read,
        })
    }

    /// Each case's in-scatter and transmittance read from a volume of `aerial` built over tables
    /// of `lut` (with the multiple-scattering orders when `multiple`); a case with no distance is
    /// read at the volume's far end.
    pub fn volume_rays(&self, ctx: &GpuContext, atmosphere: &Atmosphere, lut: &LutSettings, aerial: &AerialSettings, multiple: bool, cases: &[Case]) -> RenderResult<ProbeAnswers> {
        let device = &ctx.device;
        let atm = atmosphere_buffer(device, atmosphere);
        let query = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("AerialProbe::query"),
            size: 16,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let size = (cases.len().max(1) * 32) as u64;
        let answers = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("AerialProbe::answers"),
            size,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let [v0, v1, v2, v3] = self.volume.entries(0);
        let [l0, l1, l2] = self.tables.entries(6);
        let read_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("AerialProbe::read_group"),
            layout: &self.layout,
            entries: &[
                v0,
                v1,
                v2,
                v3,
                wgpu::BindGroupEntry { binding: 4, resource: query.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 5, resource: answers.as_entire_binding() },
                l0,
                l1,
                l2,
            ],
        });
        let empty = device.create_bind_group(&wgpu::BindGroupDescriptor { label: Some("AerialProbe::empty"), layout: &self.empty_layout, entries: &[] });
        let lut_group = self.lut_builder.bind_group(device, &atm, &self.tables);
        let build_group = self.builder.bind_group(device, &atm, &self.tables, &self.volume);
        let using = AerialUse::Model { multiple };
        let mut albedo = None;
        for (k, c) in cases.iter().enumerate() {
            let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("AerialProbe::encoder") });
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("AerialProbe::pass"), timestamp_writes: None });
            pass.set_bind_group(0, &empty, &[]);
            if albedo != Some(c.albedo) {
                albedo = Some(c.albedo);
                ctx.queue.write_buffer(&self.tables.params, 0, bytemuck::bytes_of(&LutUniform::new(lut, c.albedo as f32, atmosphere.mie_g)));
                self.lut_builder.dispatch(&mut pass, &lut_group, lut);
            }
            let view = glam::DVec3::from(crate::atmosphere::analytic::direction(c.view_elev_deg.to_radians(), c.rel_azimuth_deg.to_radians())).as_vec3();
            let sun = glam::DVec3::from(crate::atmosphere::analytic::direction(c.sun_elev_deg.to_radians(), 0.0)).as_vec3();
            let params = AerialUniform::new(aerial, using, camera_along(view).inverse(), glam::Vec3::ZERO, c.camera_km as f32, sun);
            ctx.queue.write_buffer(&self.volume.params, 0, bytemuck::bytes_of(&params));
            let distance_km = c.distance_km.unwrap_or(aerial.distance_km);
            ctx.queue.write_buffer(&query, 0, bytemuck::bytes_of(&[0.5f32, 0.5, distance_km as f32, k as f32]));
            self.builder.dispatch(&mut pass, &build_group, aerial.volume_size);
            pass.set_bind_group(1, &read_group, &[]);
            pass.set_pipeline(&self.read);
            pass.dispatch_workgroups(1, 1, 1);
            drop(pass);
            ctx.queue.submit([encoder.finish()]);
        }
        let bytes = crate::render::gpu::readback::read_buffer(ctx, &answers, size)?;
        Ok(ProbeAnswers::read(&bytes, cases.len()))
    }

    /// Wall times of `runs` builds of a volume of `aerial` for a camera looking along +x, level
    /// (the LUT tables built first, untimed), each submitted and waited for, ms: the build's cost
    /// as the frame pays it whenever the camera, the sun or the atmosphere moves.
    pub fn time_builds(&self, ctx: &GpuContext, atmosphere: &Atmosphere, lut: &LutSettings, aerial: &AerialSettings, runs: u32) -> RenderResult<Vec<f64>> {
        let device = &ctx.device;
        let atm = atmosphere_buffer(device, atmosphere);
        let empty = device.create_bind_group(&wgpu::BindGroupDescriptor { label: Some("AerialProbe::empty"), layout: &self.empty_layout, entries: &[] });
        let lut_group = self.lut_builder.bind_group(device, &atm, &self.tables);
        let build_group = self.builder.bind_group(device, &atm, &self.tables, &self.volume);
        ctx.queue.write_buffer(&self.tables.params, 0, bytemuck::bytes_of(&LutUniform::new(lut, 0.3, atmosphere.mie_g)));
        let params = AerialUniform::new(
            aerial,
            AerialUse::Model { multiple: true },
            camera_along(glam::Vec3::X).inverse(),
            glam::Vec3::ZERO,
            0.0,
            glam::Vec3::new(0.5, 0.5, 0.0).normalize(),
        );
        ctx.queue.write_buffer(&self.volume.params, 0, bytemuck::bytes_of(&params));
        let record = |tables: bool| {
            let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("AerialProbe::timing") });
            {
                let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("AerialProbe::timing_pass"), timestamp_writes: None });
                pass.set_bind_group(0, &empty, &[]);
                if tables {
                    self.lut_builder.dispatch(&mut pass, &lut_group, lut);
                }
                self.builder.dispatch(&mut pass, &build_group, aerial.volume_size);
            }
            encoder.finish()
        };
        ctx.queue.submit([record(true)]);
        ctx.wait_idle()?;
        let mut out = Vec::new();
        for _ in 0..runs {
            let t = std::time::Instant::now();
            ctx.queue.submit([record(false)]);
            ctx.wait_idle()?;
            out.push(t.elapsed().as_secs_f64() * 1000.0);
        }
        Ok(out)
    }
}
