//! Sky LUTs pass (compute phase): builds the atmosphere's transmittance and multiple-scattering
//! tables (Hillaire 2020) into the shared buffers of [`crate::render::atmosphere::AtmosphereGpu`],
//! only when the atmosphere, the LUT settings or the ground albedo change. Every physical model's
//! frame has them (the `lut` model draws from them; what marches the atmosphere between the
//! viewer and the scene reads them whatever the dome's model); idle under the NeL bitmaps.

use crate::atmosphere::LutSettings;
use crate::render::atmosphere::tables::LutTables;
use crate::render::atmosphere::uniforms::{AtmosphereUniform, LutUniform};
use crate::render::frame::pass::{DrawItem, FrameContext, Pass, PassBuild, Phase, Staged};
use crate::render::gpu::error::RenderResult;
use crate::render::gpu::parts::storage_entry;

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

/// The sky LUTs pass.
pub struct SkyLutsPass {
    builder: Staged<LutBuilder>,
    params: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    /// What the tables hold now.
    built: Option<(AtmosphereUniform, LutUniform)>,
    settings: LutSettings,
    dirty: bool,
    /// The tables were current this frame: the build was skipped.
    skipped: bool,
    /// Table builds so far (stats and tests).
    pub builds: u64,
}

impl SkyLutsPass {
    /// Builds the pipelines and binds the shared tables.
    pub fn new(b: &PassBuild<'_>) -> RenderResult<Self> {
        let builder = LutBuilder::new(b.device, b.library, b.globals_layout)?;
        let bind_group = builder.bind_group(b.device, &b.atmosphere.uniform, &b.atmosphere.luts);
        let params = b.atmosphere.luts.params.clone();
        Ok(Self { builder: Staged::new(builder), params, bind_group, built: None, settings: LutSettings::default(), dirty: false, skipped: false, builds: 0 })
    }
}

impl Pass for SkyLutsPass {
    fn name(&self) -> &'static str {
        "sky_luts"
    }

    fn phase(&self) -> Phase {
        Phase::Compute
    }

    fn stage_pipelines(&mut self, b: &PassBuild<'_>) -> RenderResult<()> {
        let next = LutBuilder::new(b.device, b.library, b.globals_layout)?;
        self.builder.stage(next);
        Ok(())
    }

    fn commit_pipelines(&mut self, accept: bool) {
        if self.builder.pending().is_some() && accept {
            // New shaders may build different tables; the layout is the same, so the bind group stays valid.
            self.built = None;
        }
        self.builder.commit(accept);
    }

    fn prepare(&mut self, cx: &FrameContext<'_>) {
        self.dirty = false;
        self.skipped = false;
        let model = &cx.frame.sky_model;
        if !model.kind.is_physical() {
            return;
        }
        let key = (AtmosphereUniform::from(&cx.frame.atmosphere), LutUniform::new(&model.settings.lut, model.world.ground_albedo, cx.frame.atmosphere.mie_g));
        if self.built == Some(key) && cx.options.skips.unchanged_tables {
            self.skipped = true;
            return;
        }
        cx.queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&key.1));
        self.built = Some(key);
        self.settings = model.settings.lut;
        self.dirty = true;
        self.builds += 1;
    }

    fn items(&self, _cx: &FrameContext<'_>, out: &mut Vec<DrawItem>) {
        if self.dirty {
            out.push(DrawItem::new(0, 0));
        }
    }

    fn stats(&self, stats: &mut crate::render::frame::stats::FrameStats) {
        stats.tables_skipped = self.skipped;
    }

    fn dispatch(&self, cpass: &mut wgpu::ComputePass<'_>, _key: usize) {
        self.builder.current.dispatch(cpass, &self.bind_group, &self.settings);
    }
}
