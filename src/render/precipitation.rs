//! Precipitation pass (scene-after-sky phase): the particles of emitters attached to the camera
//! (rain, snow, sleet), in metres around the viewer, depth-tested in the main scene's depth
//! range so the scene stand-in hides the drops behind it. Same sprites and resources as
//! `particles.rs`.

use super::error::RenderResult;
use super::particles::{bind_layout, build_pipelines, draw_emitter, sampler, EmitterSet};
use super::pass::{DrawItem, FrameContext, Pass, PassBuild, Phase, Pipelines, SkyUpload, Staged, Target};

/// The precipitation pass.
pub struct PrecipitationPass {
    bind_layout: wgpu::BindGroupLayout,
    sampler: wgpu::Sampler,
    pipeline: Pipelines<[wgpu::RenderPipeline; 2]>,
    set: Staged<Option<EmitterSet>>,
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
        Ok(Self { sampler: sampler(b.device, "Precipitation::sampler"), bind_layout, pipeline, set: Staged::new(None) })
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
        self.pipeline.stage(b)
    }

    fn commit_pipelines(&mut self, accept: bool) {
        self.pipeline.commit(accept);
    }

    fn stage_sky(&mut self, up: &mut SkyUpload<'_>) {
        let set = up
            .sky
            .emitters
            .iter()
            .any(|e| e.attach == crate::sky::resolved::EmitterAttach::Camera)
            .then(|| EmitterSet::new(up.device, up.queue, &self.bind_layout, &self.sampler, up.textures, up.sky));
        self.set.stage(set);
    }

    fn commit_sky(&mut self, accept: bool) {
        self.set.commit(accept);
    }

    fn prepare(&mut self, cx: &FrameContext<'_>) {
        if let Some(set) = self.set.current.as_mut() {
            set.upload(cx, true);
        }
    }

    fn items(&self, _cx: &FrameContext<'_>, out: &mut Vec<DrawItem>) {
        if let Some(set) = &self.set.current {
            for (key, _) in set.emitters.iter().enumerate().filter(|(_, g)| g.camera && g.count > 0) {
                out.push(DrawItem { priority: 0, key });
            }
        }
    }

    fn draw(&self, rpass: &mut wgpu::RenderPass<'_>, key: usize, target: Target) -> u32 {
        self.set.current.as_ref().and_then(|s| s.emitters.get(key)).map_or(0, |g| draw_emitter(rpass, self.pipeline.for_target(target), g))
    }
}
