//! Evaluates a GPU sky model for a list of radiance cases and reads the answers back: the
//! interface `skytune radiance`, the model tests and the benchmarks use. A compute pipeline of
//! its own (`shaders/radiance_probe.wgsl`), outside the frame's phases.

use wgpu::util::DeviceExt;

use crate::atmosphere::analytic::{self, AnalyticModel};
use crate::atmosphere::reference::Case;
use crate::atmosphere::{Atmosphere, LutSettings, PrecomputedSettings, SingleSettings};
use crate::render::atmosphere::precomputed_tables::PrecomputedBuilder;
use crate::render::atmosphere::sky_luts::LutBuilder;
use crate::render::atmosphere::tables::{table_bytes, LutTables, PrecomputedHeader, PrecomputedTables};
use crate::render::atmosphere::uniforms::{AtmosphereUniform, LutUniform, SingleUniform};
use crate::render::gpu::context::GpuContext;
use crate::render::gpu::error::RenderResult;
use crate::render::gpu::parts::storage_entry;
use crate::render::gpu::shaders;
use crate::render::gpu::shaders::ShaderLibrary;

/// The probe's pipelines, and the `lut` and `precomputed` models' table builders.
pub struct RadianceProbe {
    layout: wgpu::BindGroupLayout,
    empty_layout: wgpu::BindGroupLayout,
    single: wgpu::ComputePipeline,
    lut: wgpu::ComputePipeline,
    analytic: wgpu::ComputePipeline,
    precomputed: wgpu::ComputePipeline,
    tables: LutTables,
    builder: LutBuilder,
    precomputed_builder: PrecomputedBuilder,
    /// Stands in for the `precomputed` tables when another model runs.
    no_tables: PrecomputedTables,
    /// The `precomputed` tables built so far and what each was built for, least recently used
    /// first, at most [`PRECOMPUTED_CACHE_BYTES`] together: evaluations that share an atmosphere,
    /// settings and ground albedo build them once, even with other tables built in between (`auto`
    /// measures every candidate for one weather step after another, and skies share atmospheres).
    precomputed_cache: std::cell::RefCell<Vec<(PrecomputedKey, PrecomputedTables)>>,
    /// `precomputed` table builds so far (tests).
    pub precomputed_builds: std::cell::Cell<u64>,
}

/// What `precomputed` tables depend on.
type PrecomputedKey = (AtmosphereUniform, PrecomputedHeader, u32);

/// How much memory the kept `precomputed` tables may hold together, bytes: a few default-size
/// sets (about 100 MB each), so that `auto`'s candidates and weather steps do not evict each
/// other. The most recent set is kept whatever its size.
pub const PRECOMPUTED_CACHE_BYTES: u64 = 512 << 20;

/// Which entry point evaluates the cases.
#[derive(Clone, Copy)]
enum Model {
    Single,
    Lut,
    Analytic,
    Precomputed,
}

/// Tables a run builds before it evaluates the cases.
#[derive(Clone, Copy)]
enum Build<'a> {
    Nothing,
    Lut(&'a LutSettings),
    Precomputed(&'a PrecomputedSettings, &'a PrecomputedTables),
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
                storage_entry(8, true),
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
        let precomputed = shaders::compute_pipeline(device, &pipeline_layout, &module, "cs_precomputed", "RadianceProbe::precomputed")?;
        let builder = LutBuilder::new(device, library, &empty)?;
        let precomputed_builder = PrecomputedBuilder::new(device, library, &empty)?;
        let no_tables =
            PrecomputedTables::new(device, &PrecomputedSettings { transmittance_size: [2, 2], irradiance_size: [2, 2], scattering_size: [2, 2, 4, 2], ..Default::default() });
        Ok(Self {
            layout,
            empty_layout: empty,
            single,
            lut,
            analytic,
            precomputed,
            tables: LutTables::new(device),
            builder,
            precomputed_builder,
            no_tables,
            precomputed_cache: Default::default(),
            precomputed_builds: Default::default(),
        })
    }

    /// Drops the kept `precomputed` tables: the next evaluation builds them (timing a build).
    pub fn forget_precomputed(&self) {
        self.precomputed_cache.borrow_mut().clear();
    }

    /// Radiance of the `precomputed` model for every case (tables built per distinct ground
    /// albedo, and kept for the next call while nothing they depend on changes).
    pub fn precomputed(&self, ctx: &GpuContext, atmosphere: &Atmosphere, settings: &PrecomputedSettings, cases: &[Case]) -> RenderResult<Vec<[f32; 3]>> {
        let mut out = vec![[0.0; 3]; cases.len()];
        for (index, subset) in by_albedo(cases) {
            let header = PrecomputedHeader::new(settings, subset[0].albedo as f32);
            let key = (AtmosphereUniform::from(atmosphere), header, settings.orders);
            let mut cache = self.precomputed_cache.borrow_mut();
            let fresh = match cache.iter().position(|(k, _)| *k == key) {
                Some(at) => {
                    let hit = cache.remove(at);
                    cache.push(hit);
                    false
                }
                None => {
                    let needed = table_bytes(settings);
                    let mut reusable = None;
                    while !cache.is_empty() && cache.iter().map(|(_, t)| t.bytes).sum::<u64>() + needed > PRECOMPUTED_CACHE_BYTES {
                        reusable = Some(cache.remove(0).1).filter(|t| t.holds(settings));
                    }
                    let tables = reusable.unwrap_or_else(|| PrecomputedTables::new(&ctx.device, settings));
                    ctx.queue.write_buffer(&tables.buffer, 0, bytemuck::bytes_of(&header));
                    cache.push((key, tables));
                    self.precomputed_builds.set(self.precomputed_builds.get() + 1);
                    true
                }
            };
            let tables = &cache.last().expect("just filled").1;
            let build = if fresh { Build::Precomputed(settings, tables) } else { Build::Nothing };
            let result = self.run(ctx, atmosphere, &SingleSettings::default(), &subset, Model::Precomputed, build, &[], Some(tables)).map(|r| r.radiance);
            // Tables whose build did not finish must not be looked up as built next time.
            if result.is_err() && fresh {
                cache.pop();
            }
            let result = result?;
            for (i, r) in index.into_iter().zip(result) {
                out[i] = r;
            }
        }
        Ok(out)
    }

    /// Radiance of the `lut` model for every case (tables built per distinct ground albedo).
    pub fn lut(&self, ctx: &GpuContext, atmosphere: &Atmosphere, settings: &LutSettings, cases: &[Case]) -> RenderResult<Vec<[f32; 3]>> {
        Ok(self.lut_rays(ctx, atmosphere, settings, cases)?.radiance)
    }

    /// The `lut` model along each case's ray, stopped at its `distance_km` if it has one: the
    /// exact per-pixel integration of aerial perspective (`lut_aerial`), in-scatter and
    /// transmittance.
    pub fn lut_rays(&self, ctx: &GpuContext, atmosphere: &Atmosphere, settings: &LutSettings, cases: &[Case]) -> RenderResult<ProbeAnswers> {
        let mut out = ProbeAnswers { radiance: vec![[0.0; 3]; cases.len()], transmittance: vec![[1.0; 3]; cases.len()] };
        for (index, subset) in by_albedo(cases) {
            let params = LutUniform::new(settings, subset[0].albedo as f32, atmosphere.mie_g);
            ctx.queue.write_buffer(&self.tables.params, 0, bytemuck::bytes_of(&params));
            let result = self.run(ctx, atmosphere, &SingleSettings::default(), &subset, Model::Lut, Build::Lut(settings), &[], None)?;
            for (k, i) in index.into_iter().enumerate() {
                (out.radiance[i], out.transmittance[i]) = (result.radiance[k], result.transmittance[k]);
            }
        }
        Ok(out)
    }

    /// Radiance of the `single` model for every case, sr^-1 per unit of solar irradiance
    /// (blocks until the GPU is done).
    pub fn single(&self, ctx: &GpuContext, atmosphere: &Atmosphere, settings: &SingleSettings, cases: &[Case]) -> RenderResult<Vec<[f32; 3]>> {
        Ok(self.run(ctx, atmosphere, settings, cases, Model::Single, Build::Nothing, &[], None)?.radiance)
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
        Ok(self.run(ctx, &Atmosphere::default(), &SingleSettings::default(), cases, Model::Analytic, Build::Nothing, &coefficients, None)?.radiance)
    }

    /// Evaluates `model` for `cases` after building the tables of `build`; `analytic`: the analytic
    /// models' coefficients (12 per case, or none); `precomputed`: that model's tables.
    #[allow(clippy::too_many_arguments)]
    fn run(
        &self,
        ctx: &GpuContext,
        atmosphere: &Atmosphere,
        settings: &SingleSettings,
        cases: &[Case],
        model: Model,
        build: Build<'_>,
        analytic: &[[f32; 4]],
        precomputed: Option<&PrecomputedTables>,
    ) -> RenderResult<ProbeAnswers> {
        if cases.is_empty() {
            return Ok(ProbeAnswers::default());
        }
        let device = &ctx.device;
        let init = |label: &str, contents: &[u8], usage| device.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some(label), contents, usage });
        let atm = init("RadianceProbe::atmosphere", bytemuck::bytes_of(&AtmosphereUniform::from(atmosphere)), wgpu::BufferUsages::UNIFORM);
        let set = init("RadianceProbe::settings", bytemuck::bytes_of(&SingleUniform::from(settings)), wgpu::BufferUsages::UNIFORM);
        // Keep in sync with `cases` and `radiance` in shaders/radiance_probe.wgsl: two vectors per case.
        let data: Vec<[f32; 4]> = cases
            .iter()
            .flat_map(|c| [[c.camera_km as f32, c.sun_elev_deg as f32, c.view_elev_deg as f32, c.rel_azimuth_deg as f32], [c.distance_km.map_or(0.0, |d| d as f32), 0.0, 0.0, 0.0]])
            .collect();
        let input = init("RadianceProbe::cases", bytemuck::cast_slice(&data), wgpu::BufferUsages::STORAGE);
        // The transmittance of models that write none: ones.
        let answers = vec![[1.0f32; 4]; 2 * cases.len()];
        // A binding may not be empty: one zero vector stands in when no model reads it.
        let coefficients = init("RadianceProbe::analytic", if analytic.is_empty() { &[0u8; 16] } else { bytemuck::cast_slice(analytic) }, wgpu::BufferUsages::STORAGE);
        let size = (answers.len() * 16) as u64;
        let output = init("RadianceProbe::radiance", bytemuck::cast_slice(&answers), wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC);
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
                wgpu::BindGroupEntry { binding: 8, resource: precomputed.unwrap_or(&self.no_tables).buffer.as_entire_binding() },
            ],
        });
        let empty = device.create_bind_group(&wgpu::BindGroupDescriptor { label: Some("RadianceProbe::empty"), layout: &self.empty_layout, entries: &[] });
        let builder_group = match build {
            Build::Nothing => None,
            Build::Lut(_) => Some(self.builder.bind_group(device, &atm, &self.tables)),
            Build::Precomputed(_, tables) => Some(self.precomputed_builder.bind_group(device, &atm, tables)),
        };
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("RadianceProbe::encoder") });
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("RadianceProbe::pass"), timestamp_writes: None });
            pass.set_bind_group(0, &empty, &[]);
            match (build, &builder_group) {
                (Build::Lut(settings), Some(group)) => self.builder.dispatch(&mut pass, group, settings),
                (Build::Precomputed(settings, _), Some(group)) => {
                    let steps = crate::render::atmosphere::precomputed_tables::build_steps(settings, 1);
                    self.precomputed_builder.write_steps(&ctx.queue, &steps);
                    self.precomputed_builder.dispatch(&mut pass, group, &steps, 0..steps.len());
                }
                _ => {}
            }
            pass.set_pipeline(match model {
                Model::Single => &self.single,
                Model::Lut => &self.lut,
                Model::Analytic => &self.analytic,
                Model::Precomputed => &self.precomputed,
            });
            pass.set_bind_group(1, &bind_group, &[]);
            pass.dispatch_workgroups((cases.len() as u32).div_ceil(64), 1, 1);
        }
        ctx.queue.submit([encoder.finish()]);
        let bytes = crate::render::gpu::readback::read_buffer(ctx, &output, size)?;
        Ok(ProbeAnswers::read(&bytes, cases.len()))
    }
}

/// What the probe answers for each case, in the cases' order.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ProbeAnswers {
    /// Radiance, sr^-1 per unit of solar irradiance: the sky's, or the light scattered into a
    /// ray that stops at its case's distance.
    pub radiance: Vec<[f32; 3]>,
    /// Transmittance of each case's ray, per channel (ones from models that give none).
    pub transmittance: Vec<[f32; 3]>,
}

impl ProbeAnswers {
    /// The answers to `cases` cases in a probe's read-back buffer: two vec4 per case, the
    /// radiance then the transmittance.
    pub(crate) fn read(bytes: &[u8], cases: usize) -> Self {
        let vectors = bytemuck::pod_collect_to_vec::<u8, [f32; 4]>(bytes);
        let rgb = |v: &[f32; 4]| [v[0], v[1], v[2]];
        Self { radiance: vectors.iter().step_by(2).take(cases).map(rgb).collect(), transmittance: vectors.iter().skip(1).step_by(2).take(cases).map(rgb).collect() }
    }

    /// Both, in double precision (the CSV writers' type).
    pub fn to_f64(&self) -> (Vec<[f64; 3]>, Vec<[f64; 3]>) {
        let wide = |v: &[[f32; 3]]| v.iter().map(|c| c.map(f64::from)).collect();
        (wide(&self.radiance), wide(&self.transmittance))
    }
}

/// The cases grouped by ground albedo (tables are built per albedo): each group's indices into
/// `cases` and its cases.
fn by_albedo(cases: &[Case]) -> Vec<(Vec<usize>, Vec<Case>)> {
    let mut albedos: Vec<f64> = cases.iter().map(|c| c.albedo).collect();
    albedos.sort_by(f64::total_cmp);
    albedos.dedup();
    albedos
        .into_iter()
        .map(|albedo| {
            let index: Vec<usize> = (0..cases.len()).filter(|i| cases[*i].albedo == albedo).collect();
            let subset = index.iter().map(|i| cases[*i]).collect();
            (index, subset)
        })
        .collect()
}
