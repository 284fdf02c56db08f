//! Precipitation pass (scene-after-sky phase): the particles of emitters attached to the camera
//! (rain, snow, sleet), in metres around the viewer, depth-tested in the main scene's depth
//! range so the scene stand-in hides the drops behind it. Same sprites and resources as
//! `particles.rs`. Their births are evaluated on the GPU in the compute phase
//! (`particle_sim.rs`, faster than the CPU from a few thousand particles: docs/performance.md);
//! bursts come from the CPU.

use crate::render::frame::pass::{DrawItem, FrameContext, Pass, PassBuild, Phase, Pipelines, Placement, SkyUpload, Staged, Target};
use crate::render::gpu::error::RenderResult;
use crate::render::passes::particle_sim::GpuParticleSim;
use crate::render::passes::particles::{bind_layout, build_pipelines, draw_emitter, sampler, EmitterSet};

/// The precipitation pass.
pub struct PrecipitationPass {
    bind_layout: wgpu::BindGroupLayout,
    sampler: wgpu::Sampler,
    pipeline: Pipelines<[wgpu::RenderPipeline; 2]>,
    set: Staged<Option<EmitterSet>>,
    sim_layout: wgpu::BindGroupLayout,
    sim_pipeline: Pipelines<wgpu::ComputePipeline>,
    /// Per emitter of the sky: its GPU evaluation and settings (camera emitters only).
    sims: Staged<Vec<Option<(GpuParticleSim, crate::sky::resolved::Emitter)>>>,
}

impl PrecipitationPass {
    /// Builds the pipelines.
    pub fn new(b: &PassBuild<'_>) -> RenderResult<Self> {
        let bind_layout = bind_layout(b.device, "Precipitation::layout");
        let pipeline_layout = b.device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("Precipitation::pipeline_layout"),
            bind_group_layouts: &[Some(b.globals_layout), Some(&bind_layout)],
            immediate_size: 0,
        });
        let pipeline = Pipelines::new_render(b, pipeline_layout, |b, l| build_pipelines(b, l, "precipitation", "Precipitation::pipeline"))?;
        let sim_layout = crate::render::passes::particle_sim::layout(b.device);
        let sim_pipeline = Pipelines::new(b, crate::render::passes::particle_sim::pipeline_layout(b.device, b.globals_layout, &sim_layout), |b, l| {
            crate::render::passes::particle_sim::pipeline(b.device, b.library, l)
        })?;
        Ok(Self { sampler: sampler(b.device, "Precipitation::sampler"), bind_layout, pipeline, set: Staged::new(None), sim_layout, sim_pipeline, sims: Staged::new(Vec::new()) })
    }
}

impl Pass for PrecipitationPass {
    fn name(&self) -> &'static str {
        "precipitation"
    }

    fn phase(&self) -> Phase {
        Phase::SceneAfterSky
    }

    fn stage_pipelines(&mut self, b: &PassBuild<'_>) -> RenderResult<()> {
        self.pipeline.stage(b)?;
        self.sim_pipeline.stage(b)
    }

    fn commit_pipelines(&mut self, accept: bool) {
        self.pipeline.commit(accept);
        self.sim_pipeline.commit(accept);
    }

    fn stage_sky(&mut self, up: &mut SkyUpload<'_>) {
        let set = up
            .sky
            .emitters
            .iter()
            .any(|e| e.attach == crate::sky::resolved::EmitterAttach::Camera)
            .then(|| EmitterSet::new(up.device, up.queue, &self.bind_layout, &self.sampler, up.textures, up.sky));
        self.set.stage(set);
        let sims = up
            .sky
            .emitters
            .iter()
            .map(|e| (e.attach == crate::sky::resolved::EmitterAttach::Camera).then(|| (GpuParticleSim::new(up.device, &self.sim_layout, e.max_particles), e.clone())))
            .collect();
        self.sims.stage(sims);
    }

    fn commit_sky(&mut self, accept: bool) {
        self.set.commit(accept);
        self.sims.commit(accept);
    }

    fn prepare(&mut self, cx: &FrameContext<'_>) {
        if let Some(set) = self.set.current.as_mut() {
            set.upload(cx, true);
        }
        for (sim, _) in self.sims.current.iter_mut().flatten() {
            sim.slots = 0;
        }
        for f in &cx.frame.particles.emitters {
            if let (Some(births), Some(Some((sim, e)))) = (&f.gpu, self.sims.current.get_mut(f.emitter)) {
                sim.prepare(cx.queue, e, births);
            }
        }
    }

    fn compute_items(&self, _cx: &FrameContext<'_>, out: &mut Vec<DrawItem>) {
        for (key, sim) in self.sims.current.iter().enumerate() {
            if sim.as_ref().is_some_and(|(s, _)| s.slots > 0) {
                out.push(DrawItem::new(0, key));
            }
        }
    }

    fn dispatch(&self, cpass: &mut wgpu::ComputePass<'_>, key: usize) {
        if let Some(Some((sim, _))) = self.sims.current.get(key) {
            sim.dispatch(cpass, self.sim_pipeline.get());
        }
    }

    fn items(&self, _cx: &FrameContext<'_>, out: &mut Vec<DrawItem>) {
        if let Some(set) = &self.set.current {
            for (key, g) in set.emitters.iter().enumerate().filter(|(_, g)| g.camera) {
                let gpu = self.sims.current.get(key).and_then(|s| s.as_ref()).is_some_and(|(s, _)| s.slots > 0);
                if g.count > 0 || gpu {
                    out.push(DrawItem::new(0, key));
                }
            }
        }
    }

    fn draw(&self, rpass: &mut wgpu::RenderPass<'_>, key: usize, target: Target, _placement: Placement, _run: Option<&wgpu::BindGroup>) -> u32 {
        let Some(g) = self.set.current.as_ref().and_then(|s| s.emitters.get(key)) else { return 0 };
        let pipelines = self.pipeline.for_target(target);
        let mut calls = draw_emitter(rpass, [&pipelines[0], &pipelines[1]], g);
        if let Some(Some((sim, _))) = self.sims.current.get(key).filter(|s| s.as_ref().is_some_and(|(s, _)| s.slots > 0)) {
            rpass.set_pipeline(&pipelines[g.additive as usize]);
            rpass.set_bind_group(1, &g.bind_group, &[]);
            rpass.set_vertex_buffer(0, sim.particles.slice(..));
            rpass.draw(0..4, 0..sim.slots);
            calls += 1;
        }
        calls
    }
}
