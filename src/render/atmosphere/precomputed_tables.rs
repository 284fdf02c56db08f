//! Precomputed-tables pass (compute phase): builds the `precomputed` model's tables (after
//! Bruneton 2017: transmittance, direct and indirect irradiance, single Rayleigh and Mie and
//! multiple scattering in (r, mu, mu_s, nu)) into one shared storage buffer, only when the
//! atmosphere, the settings or the ground albedo change. Idle for every other model. The layout
//! and the lookup are in shaders/sky_model/precomputed_sampling.wgsl.

use crate::atmosphere::{PrecomputedSettings, TablePrecision};
use crate::render::atmosphere::tables::{PrecomputedHeader, PrecomputedState, PrecomputedTables};
use crate::render::atmosphere::uniforms::AtmosphereUniform;
use crate::render::frame::pass::{DrawItem, FrameContext, Pass, PassBuild, Phase, Staged};
use crate::render::gpu::error::RenderResult;
use crate::render::gpu::parts::storage_entry;
use crate::render::plan::strategy::TableBuilds;
use crate::sky::resolved::SkyModelKind;

/// A stage of the build: one entry point of shaders/precomputed_tables.wgsl.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    /// The transmittance table.
    Transmittance,
    /// The direct irradiance (order 1's ground light); the indirect total starts at zero.
    DirectIrradiance,
    /// Single Rayleigh and Mie scattering.
    Single,
    /// Scattering density of order 2 (from single scattering with its phase functions).
    DensitySecond,
    /// Scattering density of a higher order.
    DensityHigher,
    /// Irradiance from single scattering.
    IndirectFirst,
    /// Irradiance from a higher order.
    IndirectHigher,
    /// An order's scattering, added to the total.
    Multiple,
    /// The last order's scattering (from order 3), added to the total with the orders above it
    /// extrapolated as a geometric series.
    MultipleLast,
    /// Half-precision storage: both looked-up tables packed into one, after the last order.
    PackHalf,
}

impl Stage {
    const ALL: [Stage; 10] = [
        Stage::Transmittance,
        Stage::DirectIrradiance,
        Stage::Single,
        Stage::DensitySecond,
        Stage::DensityHigher,
        Stage::IndirectFirst,
        Stage::IndirectHigher,
        Stage::Multiple,
        Stage::MultipleLast,
        Stage::PackHalf,
    ];

    fn entry(self) -> &'static str {
        match self {
            Stage::Transmittance => "cs_transmittance",
            Stage::DirectIrradiance => "cs_direct_irradiance",
            Stage::Single => "cs_single",
            Stage::DensitySecond => "cs_density_second",
            Stage::DensityHigher => "cs_density_higher",
            Stage::IndirectFirst => "cs_indirect_first",
            Stage::IndirectHigher => "cs_indirect_higher",
            Stage::Multiple => "cs_multiple",
            Stage::MultipleLast => "cs_multiple_last",
            Stage::PackHalf => "cs_pack_half",
        }
    }

    /// Whether the stage writes a 4D scattering table (the stages a software rasteriser slices).
    fn writes_4d(self) -> bool {
        matches!(self, Stage::Single | Stage::DensitySecond | Stage::DensityHigher | Stage::Multiple | Stage::MultipleLast | Stage::PackHalf)
    }

    /// Texels the stage writes with `settings`.
    fn texels(self, settings: &PrecomputedSettings) -> u32 {
        let [tw, th] = settings.transmittance_size;
        let [iw, ih] = settings.irradiance_size;
        match self {
            s if s.writes_4d() => settings.scattering_texels(),
            Stage::Transmittance => tw * th,
            _ => iw * ih,
        }
    }
}

/// One dispatch of the build: a stage over `count` texels from `first`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BuildStep {
    /// What it computes.
    pub stage: Stage,
    /// First texel of its table.
    pub first: u32,
    /// Texels.
    pub count: u32,
}

/// The build of tables with `settings`, in dependency order, each 4D stage cut into `slices`
/// dispatches (a software rasteriser spreads them over frames: [`TableBuilds`]).
pub fn build_steps(settings: &PrecomputedSettings, slices: u32) -> Vec<BuildStep> {
    let mut stages = vec![Stage::Transmittance, Stage::DirectIrradiance, Stage::Single];
    for order in 2..=settings.orders {
        let second = order == 2;
        // The tail needs two orders of multiple scattering to take their ratio.
        let multiple = if order == settings.orders && order >= 3 { Stage::MultipleLast } else { Stage::Multiple };
        stages.extend([if second { Stage::DensitySecond } else { Stage::DensityHigher }, if second { Stage::IndirectFirst } else { Stage::IndirectHigher }, multiple]);
    }
    if settings.precision == TablePrecision::Half {
        stages.push(Stage::PackHalf);
    }
    let mut steps = Vec::new();
    for stage in stages {
        let texels = stage.texels(settings);
        let cut = if stage.writes_4d() { slices.max(1) } else { 1 };
        let per = texels.div_ceil(cut);
        let mut first = 0;
        while first < texels {
            steps.push(BuildStep { stage, first, count: per.min(texels - first) });
            first += per;
        }
    }
    steps
}

/// Most steps a build may have (cursor entries).
const MAX_STEPS: usize = 4096;
/// Stride of the cursor entries (the minimum uniform offset alignment wgpu allows everywhere).
const CURSOR_STRIDE: u64 = 256;

/// The table builders (shaders/precomputed_tables.wgsl), for the pass and the radiance probe.
pub struct PrecomputedBuilder {
    layout: wgpu::BindGroupLayout,
    pipelines: Vec<wgpu::ComputePipeline>,
    /// Per step: first texel, texel count (a uniform read at a dynamic offset).
    cursor: wgpu::Buffer,
}

impl PrecomputedBuilder {
    /// Builds the pipelines with `group0` as bind group 0 (the frame's globals, or an empty layout).
    pub fn new(device: &wgpu::Device, library: &crate::render::gpu::shaders::ShaderLibrary, group0: &wgpu::BindGroupLayout) -> RenderResult<Self> {
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("PrecomputedTables::layout"),
            entries: &[
                crate::render::gpu::parts::uniform_entry(0, wgpu::ShaderStages::COMPUTE),
                storage_entry(1, false),
                wgpu::BindGroupLayoutEntry {
                    binding: 2,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Buffer { ty: wgpu::BufferBindingType::Uniform, has_dynamic_offset: true, min_binding_size: wgpu::BufferSize::new(16) },
                    count: None,
                },
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("PrecomputedTables::pipeline_layout"),
            bind_group_layouts: &[Some(group0), Some(&layout)],
            immediate_size: 0,
        });
        let module = crate::render::gpu::shaders::module(device, library, "precomputed_tables")?;
        let pipelines = Stage::ALL
            .iter()
            .map(|stage| crate::render::gpu::shaders::compute_pipeline(device, &pipeline_layout, &module, stage.entry(), &format!("PrecomputedTables::{}", stage.entry())))
            .collect::<RenderResult<Vec<_>>>()?;
        let cursor = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("PrecomputedTables::cursor"),
            size: MAX_STEPS as u64 * CURSOR_STRIDE,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Ok(Self { layout, pipelines, cursor })
    }

    /// A bind group of the builders over `tables` with the atmosphere uniform `atmosphere`.
    pub fn bind_group(&self, device: &wgpu::Device, atmosphere: &wgpu::Buffer, tables: &PrecomputedTables) -> wgpu::BindGroup {
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("PrecomputedTables::bind_group"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: atmosphere.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: tables.buffer.as_entire_binding() },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding { buffer: &self.cursor, offset: 0, size: wgpu::BufferSize::new(16) }),
                },
            ],
        })
    }

    /// Writes the cursors of a build's steps (before the frame that records the first of them).
    pub fn write_steps(&self, queue: &wgpu::Queue, steps: &[BuildStep]) {
        let mut bytes = vec![0u8; steps.len().min(MAX_STEPS) * CURSOR_STRIDE as usize];
        for (k, step) in steps.iter().take(MAX_STEPS).enumerate() {
            let at = k * CURSOR_STRIDE as usize;
            bytes[at..at + 8].copy_from_slice(bytemuck::cast_slice(&[step.first, step.count]));
        }
        queue.write_buffer(&self.cursor, 0, &bytes);
    }

    /// Records steps `range` of `steps` (whose cursors are written) into `cpass`, whose bind
    /// group 0 is set; the tables' header must hold the build's settings ([`PrecomputedHeader`]).
    pub fn dispatch(&self, cpass: &mut wgpu::ComputePass<'_>, bind_group: &wgpu::BindGroup, steps: &[BuildStep], range: std::ops::Range<usize>) {
        let end = range.end.min(steps.len()).min(MAX_STEPS);
        for (k, step) in steps.iter().enumerate().take(end).skip(range.start) {
            cpass.set_bind_group(1, bind_group, &[(k as u64 * CURSOR_STRIDE) as u32]);
            cpass.set_pipeline(&self.pipelines[Stage::ALL.iter().position(|s| *s == step.stage).unwrap_or(0)]);
            cpass.dispatch_workgroups(step.count.div_ceil(64), 1, 1);
        }
    }
}

/// What the tables depend on.
type Key = (AtmosphereUniform, PrecomputedHeader, u32);

/// A build in progress.
struct Building {
    key: Key,
    /// Steps recorded so far.
    next: usize,
}

/// The precomputed-tables pass.
pub struct PrecomputedTablesPass {
    builder: Staged<PrecomputedBuilder>,
    tables: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    /// What the tables hold when complete.
    built: Option<Key>,
    building: Option<Building>,
    /// The steps of the last build started.
    steps: Vec<BuildStep>,
    /// Steps this frame records.
    this_frame: std::ops::Range<usize>,
    skipped: bool,
    state: std::sync::Arc<PrecomputedState>,
    /// Table builds started so far (stats and tests).
    pub builds: u64,
}

impl PrecomputedTablesPass {
    /// Builds the pipelines and binds the shared tables.
    pub fn new(b: &PassBuild<'_>) -> RenderResult<Self> {
        let builder = PrecomputedBuilder::new(b.device, b.library, b.globals_layout)?;
        let bind_group = builder.bind_group(b.device, &b.atmosphere.uniform, &b.atmosphere.precomputed);
        Ok(Self {
            builder: Staged::new(builder),
            tables: b.atmosphere.precomputed.buffer.clone(),
            bind_group,
            built: None,
            building: None,
            steps: Vec::new(),
            this_frame: 0..0,
            skipped: false,
            state: b.atmosphere.precomputed_state.clone(),
            builds: 0,
        })
    }

    /// Progress (0..1) of a build under way, if one is.
    pub fn progress(&self) -> Option<f32> {
        self.building.as_ref().map(|b| b.next as f32 / self.steps.len().max(1) as f32)
    }

    fn set_complete(&self, complete: bool) {
        use std::sync::atomic::Ordering;
        if complete && !self.state.complete.load(Ordering::Relaxed) {
            self.state.generation.fetch_add(1, Ordering::Relaxed);
        }
        self.state.complete.store(complete, Ordering::Relaxed);
    }
}

impl Pass for PrecomputedTablesPass {
    fn name(&self) -> &'static str {
        "precomputed_tables"
    }

    fn phase(&self) -> Phase {
        Phase::Compute
    }

    fn stage_pipelines(&mut self, b: &PassBuild<'_>) -> RenderResult<()> {
        let next = PrecomputedBuilder::new(b.device, b.library, b.globals_layout)?;
        self.builder.stage(next);
        Ok(())
    }

    fn commit_pipelines(&mut self, accept: bool) {
        if self.builder.pending().is_some() && accept {
            // New shaders may build different tables: build again (the new builder's cursors are
            // written when the build starts).
            self.built = None;
            self.building = None;
        }
        self.builder.commit(accept);
    }

    fn prepare(&mut self, cx: &FrameContext<'_>) {
        self.this_frame = 0..0;
        self.skipped = false;
        let model = &cx.frame.sky_model;
        if model.kind != SkyModelKind::Precomputed {
            // A build for a model no longer shown is dropped; the next one starts over.
            self.building = None;
            return;
        }
        let header = PrecomputedHeader::new(&model.settings.precomputed, model.world.ground_albedo);
        let key = (AtmosphereUniform::from(&cx.frame.atmosphere), header, model.settings.precomputed.orders);
        let current = self.building.as_ref().map(|b| b.key).or(self.built);
        if current == Some(key) && (cx.options.skips.unchanged_tables || self.building.is_some()) {
            self.skipped = self.building.is_none();
        } else {
            let slices = match cx.options.strategy.table_builds {
                TableBuilds::AtOnce => 1,
                TableBuilds::Spread { slices } => slices,
            };
            self.steps = build_steps(&model.settings.precomputed, slices);
            cx.queue.write_buffer(&self.tables, 0, bytemuck::bytes_of(&header));
            self.builder.current.write_steps(cx.queue, &self.steps);
            self.building = Some(Building { key, next: 0 });
            self.built = None;
            self.set_complete(false);
            self.builds += 1;
        }
        let Some(b) = self.building.as_mut() else { return };
        let end = match cx.options.strategy.table_builds {
            TableBuilds::AtOnce => self.steps.len(),
            TableBuilds::Spread { .. } => b.next + 1,
        };
        self.this_frame = b.next..end.min(self.steps.len());
        b.next = self.this_frame.end;
        if b.next >= self.steps.len() {
            self.built = Some(b.key);
            self.building = None;
            // The last steps are recorded before the passes that read the tables, in this phase.
            self.set_complete(true);
        }
    }

    fn items(&self, _cx: &FrameContext<'_>, out: &mut Vec<DrawItem>) {
        if !self.this_frame.is_empty() {
            out.push(DrawItem::new(0, 0));
        }
    }

    fn stats(&self, stats: &mut crate::render::frame::stats::FrameStats) {
        stats.tables_skipped |= self.skipped;
    }

    fn busy(&self) -> bool {
        self.building.is_some()
    }

    fn settled(&self) -> bool {
        self.building.is_none()
    }

    fn dispatch(&self, cpass: &mut wgpu::ComputePass<'_>, _key: usize) {
        self.builder.current.dispatch(cpass, &self.bind_group, &self.steps, self.this_frame.clone());
    }
}
#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::atmosphere::tables::table_bytes;

    #[test]
    fn a_build_covers_every_texel_of_every_stage_in_order() {
        let settings = PrecomputedSettings { scattering_size: [8, 16, 64, 16], orders: 3, ..Default::default() };
        for slices in [1, 7, 32] {
            let steps = build_steps(&settings, slices);
            let stages: Vec<Stage> = steps.iter().map(|s| s.stage).fold(Vec::new(), |mut v, s| {
                if v.last() != Some(&s) {
                    v.push(s);
                }
                v
            });
            use Stage::*;
            assert_eq!(stages, [Transmittance, DirectIrradiance, Single, DensitySecond, IndirectFirst, Multiple, DensityHigher, IndirectHigher, MultipleLast]);
            // Each run of one stage covers its table from the first texel to the last, in order.
            let mut next = 0;
            for (k, step) in steps.iter().enumerate() {
                assert_eq!(step.first, next, "{step:?} with {slices} slices");
                next = step.first + step.count;
                let run_ends = steps.get(k + 1).is_none_or(|n| n.stage != step.stage || n.first == 0);
                if run_ends {
                    assert_eq!(next, step.stage.texels(&settings), "{step:?} ends its table");
                    next = 0;
                }
            }
            let single: Vec<&BuildStep> = steps.iter().filter(|s| s.stage == Single).collect();
            assert_eq!(single.len() as u32, slices, "4D stages come in slices");
            assert_eq!(single.iter().map(|s| s.count).sum::<u32>(), settings.scattering_texels());
        }
        assert!(build_steps(&PrecomputedSettings { orders: PrecomputedSettings::MAX_ORDERS, ..Default::default() }, 64).len() <= MAX_STEPS);
    }

    #[test]
    fn only_the_last_of_at_least_two_multiple_orders_adds_the_tail() {
        let multiple = |orders: u32| -> Vec<Stage> {
            build_steps(&PrecomputedSettings { orders, ..Default::default() }, 1).iter().map(|s| s.stage).filter(|s| matches!(s, Stage::Multiple | Stage::MultipleLast)).collect()
        };
        assert!(multiple(1).is_empty());
        let last = |precision| build_steps(&PrecomputedSettings { precision, ..Default::default() }, 1).last().map(|s| s.stage);
        assert_eq!(last(TablePrecision::Single), Some(Stage::MultipleLast));
        assert_eq!(last(TablePrecision::Half), Some(Stage::PackHalf), "packing comes after every order");
        // Order 2 alone has no order below it to take a ratio with.
        assert_eq!(multiple(2), [Stage::Multiple]);
        assert_eq!(multiple(4), [Stage::Multiple, Stage::Multiple, Stage::MultipleLast]);
    }

    #[test]
    fn the_largest_tables_fit_one_storage_binding() {
        // wgpu's downlevel limit on a storage binding: 128 MiB.
        let largest = PrecomputedSettings {
            transmittance_size: PrecomputedSettings::MAX_TRANSMITTANCE,
            irradiance_size: PrecomputedSettings::MAX_IRRADIANCE,
            scattering_size: [PrecomputedSettings::MAX_SCATTERING_TEXELS, 1, 1, 1],
            ..Default::default()
        };
        assert!(table_bytes(&largest) <= 128 << 20);
        assert!(table_bytes(&PrecomputedSettings::default()) < table_bytes(&largest));
    }
}
