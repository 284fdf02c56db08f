//! Evaluates a GPU sky model for a list of radiance cases and reads the answers back: the
//! interface `skytune radiance`, the model tests and the benchmarks use. A compute pipeline of
//! its own (`shaders/radiance_probe.wgsl`), outside the frame's phases.

use wgpu::util::DeviceExt;

use crate::atmosphere::analytic::{self, AnalyticModel};
use crate::atmosphere::reference::Case;
use crate::atmosphere::{Atmosphere, LutSettings, SingleSettings};
use crate::render::gpu::error::RenderResult;
use crate::render::gpu::shaders;
use crate::render::passes::sky_model::{storage_entry, AtmosphereUniform, LutBuilder, LutTables, LutUniform, SingleUniform};
use crate::render::{GpuContext, ShaderLibrary};

/// The probe's pipelines, and the `lut` model's tables and builders.
pub struct RadianceProbe {
    layout: wgpu::BindGroupLayout,
    empty_layout: wgpu::BindGroupLayout,
    single: wgpu::ComputePipeline,
    lut: wgpu::ComputePipeline,
    analytic: wgpu::ComputePipeline,
    tables: LutTables,
    builder: LutBuilder,
}

/// Which entry point evaluates the cases.
#[derive(Clone, Copy)]
enum Model {
    Single,
    Lut,
    Analytic,
}

fn buffer_entry(binding: u32, ty: wgpu::BufferBindingType) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer { ty, has_dynamic_offset: false, min_binding_size: None },
        count: None,
    }
}

impl RadianceProbe {
    /// Builds the pipeline from `library`.
    pub fn new(ctx: &GpuContext, library: &ShaderLibrary) -> RenderResult<Self> {
        let device = &ctx.device;
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("RadianceProbe::layout"),
            entries: &[
                buffer_entry(0, wgpu::BufferBindingType::Uniform),
                buffer_entry(1, wgpu::BufferBindingType::Uniform),
                buffer_entry(2, wgpu::BufferBindingType::Storage { read_only: true }),
                buffer_entry(3, wgpu::BufferBindingType::Storage { read_only: false }),
                storage_entry(4, true),
                storage_entry(5, true),
                storage_entry(6, true),
                storage_entry(7, true),
            ],
        });
        // Group 0 (the frame's globals) is declared by every module but unused here.
        let empty = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some("RadianceProbe::empty_layout"), entries: &[] });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("RadianceProbe::pipeline_layout"),
            bind_group_layouts: &[Some(&empty), Some(&layout)],
            immediate_size: 0,
        });
        let module = shaders::module(device, library, "radiance_probe")?;
        let single = shaders::compute_pipeline(device, &pipeline_layout, &module, "cs_single", "RadianceProbe::single")?;
        let lut = shaders::compute_pipeline(device, &pipeline_layout, &module, "cs_lut", "RadianceProbe::lut")?;
        let analytic = shaders::compute_pipeline(device, &pipeline_layout, &module, "cs_analytic", "RadianceProbe::analytic")?;
        let builder = LutBuilder::new(device, library, &empty)?;
        Ok(Self { layout, empty_layout: empty, single, lut, analytic, tables: LutTables::new(device), builder })
    }

    /// Radiance of the `lut` model for every case (tables built per distinct ground albedo).
    pub fn lut(&self, ctx: &GpuContext, atmosphere: &Atmosphere, settings: &LutSettings, cases: &[Case]) -> RenderResult<Vec<[f32; 3]>> {
        let mut out = vec![[0.0; 3]; cases.len()];
        let mut albedos: Vec<f64> = cases.iter().map(|c| c.albedo).collect();
        albedos.sort_by(f64::total_cmp);
        albedos.dedup();
        for albedo in albedos {
            let index: Vec<usize> = (0..cases.len()).filter(|i| cases[*i].albedo == albedo).collect();
            let subset: Vec<Case> = index.iter().map(|i| cases[*i]).collect();
            let params = LutUniform::new(settings, albedo as f32);
            ctx.queue.write_buffer(&self.tables.params, 0, bytemuck::bytes_of(&params));
            let result = self.run(ctx, atmosphere, &SingleSettings::default(), &subset, Model::Lut, Some(settings), &[])?;
            for (i, r) in index.into_iter().zip(result) {
                out[i] = r;
            }
        }
        Ok(out)
    }

    /// Radiance of the `single` model for every case, sr^-1 per unit of solar irradiance
    /// (blocks until the GPU is done).
    pub fn single(&self, ctx: &GpuContext, atmosphere: &Atmosphere, settings: &SingleSettings, cases: &[Case]) -> RenderResult<Vec<[f32; 3]>> {
        self.run(ctx, atmosphere, settings, cases, Model::Single, None, &[])
    }

    /// Radiance of an analytic model for every case (the model's units, [`AnalyticModel::units`]):
    /// the sun at the case's elevation, azimuth 0; `linear` at [`equinox_morning_hour`].
    /// `model_for` gives each case's model (Hosek's albedo comes from the case).
    pub fn analytic(&self, ctx: &GpuContext, cases: &[Case], model_for: impl Fn(&Case) -> AnalyticModel) -> RenderResult<Vec<[f32; 3]>> {
        let models: Vec<AnalyticModel> = cases.iter().map(model_for).collect();
        self.analytic_each(ctx, cases, &models)
    }

    /// Radiance of `models[i]` for `cases[i]` (each case its own model and settings).
    pub fn analytic_each(&self, ctx: &GpuContext, cases: &[Case], models: &[AnalyticModel]) -> RenderResult<Vec<[f32; 3]>> {
        let coefficients: Vec<[f32; 4]> = cases
            .iter()
            .zip(models)
            .flat_map(|(c, model)| {
                let sun = analytic::direction(c.sun_elev_deg.to_radians(), 0.0);
                model.coefficients(sun, analytic::equinox_morning_hour(c.sun_elev_deg)).vectors
            })
            .collect();
        self.run(ctx, &Atmosphere::default(), &SingleSettings::default(), cases, Model::Analytic, None, &coefficients)
    }

    /// Evaluates `model` for `cases`; with `luts`, builds the tables first; `analytic`: the analytic
    /// models' coefficients (12 per case, or none).
    #[allow(clippy::too_many_arguments)]
    fn run(
        &self,
        ctx: &GpuContext,
        atmosphere: &Atmosphere,
        settings: &SingleSettings,
        cases: &[Case],
        model: Model,
        luts: Option<&LutSettings>,
        analytic: &[[f32; 4]],
    ) -> RenderResult<Vec<[f32; 3]>> {
        if cases.is_empty() {
            return Ok(Vec::new());
        }
        let device = &ctx.device;
        let init = |label: &str, contents: &[u8], usage| device.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some(label), contents, usage });
        let atm = init("RadianceProbe::atmosphere", bytemuck::bytes_of(&AtmosphereUniform::from(atmosphere)), wgpu::BufferUsages::UNIFORM);
        let set = init("RadianceProbe::settings", bytemuck::bytes_of(&SingleUniform::from(settings)), wgpu::BufferUsages::UNIFORM);
        let data: Vec<[f32; 4]> = cases.iter().map(|c| [c.camera_km as f32, c.sun_elev_deg as f32, c.view_elev_deg as f32, c.rel_azimuth_deg as f32]).collect();
        let input = init("RadianceProbe::cases", bytemuck::cast_slice(&data), wgpu::BufferUsages::STORAGE);
        // A binding may not be empty: one zero vector stands in when no model reads it.
        let coefficients = init("RadianceProbe::analytic", if analytic.is_empty() { &[0u8; 16] } else { bytemuck::cast_slice(analytic) }, wgpu::BufferUsages::STORAGE);
        let size = (cases.len() * 16) as u64;
        let output = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("RadianceProbe::radiance"),
            size,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("RadianceProbe::bind_group"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: atm.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: set.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 2, resource: input.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 3, resource: output.as_entire_binding() },
                self.tables.entries(4)[0].clone(),
                self.tables.entries(4)[1].clone(),
                self.tables.entries(4)[2].clone(),
                wgpu::BindGroupEntry { binding: 7, resource: coefficients.as_entire_binding() },
            ],
        });
        let empty = device.create_bind_group(&wgpu::BindGroupDescriptor { label: Some("RadianceProbe::empty"), layout: &self.empty_layout, entries: &[] });
        let builder_group = luts.map(|_| self.builder.bind_group(device, &atm, &self.tables));
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("RadianceProbe::encoder") });
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("RadianceProbe::pass"), timestamp_writes: None });
            pass.set_bind_group(0, &empty, &[]);
            if let (Some(settings), Some(group)) = (luts, &builder_group) {
                self.builder.dispatch(&mut pass, group, settings);
            }
            pass.set_pipeline(match model {
                Model::Single => &self.single,
                Model::Lut => &self.lut,
                Model::Analytic => &self.analytic,
            });
            pass.set_bind_group(1, &bind_group, &[]);
            pass.dispatch_workgroups((cases.len() as u32).div_ceil(64), 1, 1);
        }
        ctx.queue.submit([encoder.finish()]);
        let bytes = crate::render::gpu::headless::read_buffer(ctx, &output, size)?;
        let out = bytemuck::pod_collect_to_vec::<u8, [f32; 4]>(&bytes).iter().map(|v| [v[0], v[1], v[2]]).collect();
        Ok(out)
    }
}
