//! Sky LUTs pass (compute phase): builds the `lut` model's transmittance and multiple-scattering
//! tables (Hillaire 2020) into the shared buffers, only when the atmosphere, the LUT settings or
//! the ground albedo change. Idle for every other model.

use crate::atmosphere::LutSettings;
use crate::render::frame::pass::{DrawItem, FrameContext, Pass, PassBuild, Phase, Staged};
use crate::render::gpu::error::RenderResult;
use crate::render::passes::sky_model::{AtmosphereUniform, LutBuilder, LutUniform};
use crate::sky::resolved::SkyModelKind;

/// The sky LUTs pass.
pub struct SkyLutsPass {
    builder: Staged<LutBuilder>,
    atmosphere: wgpu::Buffer,
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
        let atmosphere = b.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("SkyLuts::atmosphere"),
            size: std::mem::size_of::<AtmosphereUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind_group = builder.bind_group(b.device, &atmosphere, &b.shared.luts);
        let params = b.shared.luts.params.clone();
        Ok(Self { builder: Staged::new(builder), atmosphere, params, bind_group, built: None, settings: LutSettings::default(), dirty: false, skipped: false, builds: 0 })
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
        if model.kind != SkyModelKind::Lut {
            return;
        }
        let key = (AtmosphereUniform::from(&cx.frame.atmosphere), LutUniform::new(&model.lut, model.ground_albedo, cx.frame.atmosphere.mie_g));
        if self.built == Some(key) && cx.options.skips.unchanged_tables {
            self.skipped = true;
            return;
        }
        cx.queue.write_buffer(&self.atmosphere, 0, bytemuck::bytes_of(&key.0));
        cx.queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&key.1));
        self.built = Some(key);
        self.settings = model.lut;
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
