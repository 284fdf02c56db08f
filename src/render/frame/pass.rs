//! The frame as an ordered list of phases, and the interface every GPU pass implements.
//!
//! Words: a **phase** is one slot of the frame and one wgpu compute or render pass (one pair of
//! GPU timestamps); a **pass** is one module here plus one `shaders/NAME.wgsl` (or a folder
//! `shaders/NAME/`) that records its work into a phase. The sky file's NeL "fallback passes" are
//! object versions (`crate::sky::VersionFrame`), not GPU passes.
//!
//! Adding a pass: write the module and its `.wgsl`, implement [`Pass`], add one line to
//! [`crate::render::passes::PASSES`].

use std::any::Any;

use crate::render::atmosphere::AtmosphereGpu;
use crate::render::frame::camera::Camera;
use crate::render::frame::history::{Histories, HistoryRequest};
use crate::render::frame::light::LightSource;
use crate::render::frame::options::RenderOptions;
use crate::render::frame::stats::FrameStats;
use crate::render::gpu::error::RenderResult;
use crate::render::gpu::shaders::ShaderLibrary;
use crate::render::gpu::textures::TextureCache;
pub use crate::render::plan::items::{Caps, DrawItem, OwnBuffer, Phase, Placement, Target};
use crate::sky::{FrameSky, Sky};

/// What a pass builds its layouts and pipelines with.
#[derive(Clone, Copy)]
pub struct PassBuild<'a> {
    /// The device.
    pub device: &'a wgpu::Device,
    /// Layout of bind group 0 (per-frame globals), shared by every pipeline.
    pub globals_layout: &'a wgpu::BindGroupLayout,
    /// The scene's light, bind group 0's binding 1 ([`crate::render::frame::light::SceneLight`]): a pass that computes a
    /// model's light copies it into its `model` on the GPU.
    pub scene_light: &'a wgpu::Buffer,
    /// Shader sources.
    pub library: &'a ShaderLibrary,
    /// Colour format of the display target (render pipelines are also built for
    /// [`crate::render::gpu::parts::HDR_FORMAT`]: see [`Pipelines::new_render`]).
    pub color_format: wgpu::TextureFormat,
    /// The frame's atmosphere on the GPU: its uniform, tables and sky-view map, which one pass
    /// writes and others read.
    pub atmosphere: &'a AtmosphereGpu,
    /// The target the render pipelines being built draw into ([`Pipelines::new_render`] builds
    /// a set for each).
    pub target: Target,
}

impl PassBuild<'_> {
    /// Override constants of shaders that include `sky_model/tone.wgsl`: the target these
    /// pipelines draw into, so `to_target` compiles to one side.
    pub fn target_constants(&self) -> [(&'static str, f64); 1] {
        [("TARGET_KIND", if self.target == Target::Hdr { 2.0 } else { 1.0 })]
    }
}

/// What a pass uploads a sky with.
pub struct SkyUpload<'a> {
    /// The device.
    pub device: &'a wgpu::Device,
    /// Its queue.
    pub queue: &'a wgpu::Queue,
    /// The sky being uploaded.
    pub sky: &'a Sky,
    /// Textures shared between passes; files whose content did not change are not uploaded again.
    pub textures: &'a mut TextureCache,
}

/// What a pass sees of a frame in its per-frame step.
pub struct FrameContext<'a> {
    /// The device (non-blocking polls of readbacks).
    pub device: &'a wgpu::Device,
    /// Its queue (uniform writes).
    pub queue: &'a wgpu::Queue,
    /// The evaluated sky and the frame's clock (`dt_s`, frame number).
    pub frame: &'a FrameSky,
    /// The viewer.
    pub camera: &'a Camera,
    /// What to draw besides the sky.
    pub options: &'a RenderOptions,
    /// Target size, pixels.
    pub size: (u32, u32),
    /// The colour target this frame's drawing phases write.
    pub target: Target,
    /// Whether blended layers are drawn as the HDR path's blend over the model's sky would leave
    /// them ([`crate::render::plan::matches_hdr_picture`]).
    pub matched: bool,
    /// The frame's HDR target and a number that changes whenever it is recreated (`None` when
    /// the frame draws display values directly).
    pub hdr: Option<(&'a wgpu::TextureView, u64)>,
    /// The scene's depth ([`crate::render::frame::depth::SceneDepth`]) and its generation: the
    /// compute phase sees the last frame's; a phase after the scene's may sample it where it does
    /// not also draw into it.
    pub depth: (&'a wgpu::TextureView, u64),
    /// The passes' histories, made for this frame's size: a pass finds its own by its name.
    pub histories: &'a Histories,
}

impl FrameContext<'_> {
    /// Width / height of the target.
    pub fn aspect(&self) -> f32 {
        self.size.0 as f32 / self.size.1.max(1) as f32
    }
}

/// A GPU pass: its pipelines (built once, rebuilt on shader reload), its per-sky resources and
/// its per-frame work. Staging and committing make pipeline rebuilds and sky uploads all or
/// nothing across every pass.
pub trait Pass: Any {
    /// Name: GPU labels, and the shader `shaders/NAME.wgsl` (or folder `shaders/NAME/`).
    fn name(&self) -> &'static str;

    /// The phase the pass records into.
    fn phase(&self) -> Phase;

    /// Builds new pipelines from the library into a pending slot.
    fn stage_pipelines(&mut self, build: &PassBuild<'_>) -> RenderResult<()>;

    /// Swaps the pending pipelines in (`accept`) or drops them.
    fn commit_pipelines(&mut self, accept: bool);

    /// Uploads a sky's resources into a pending slot, reusing what did not change. wgpu
    /// validation errors are caught by the caller's error scope.
    fn stage_sky(&mut self, _upload: &mut SkyUpload<'_>) {}

    /// Swaps the pending sky resources in (`accept`) or drops them. Simulation state of things
    /// that still exist carries over.
    fn commit_sky(&mut self, _accept: bool) {}

    /// The per-frame step: simulation (with `frame.dt_s`), uniform writes, readbacks that arrived.
    fn prepare(&mut self, _cx: &FrameContext<'_>) {}

    /// Draws wanted this frame (none: the pass is idle).
    fn items(&self, cx: &FrameContext<'_>, out: &mut Vec<DrawItem>);

    /// Records one item into the phase's render pass (or a run's buffer), with the pipelines
    /// built for `target`, at `placement` (one the item's [`Caps`] allow); `run`: the run buffer
    /// the placement reads, as group 2. Returns draw calls.
    fn draw(&self, _rpass: &mut wgpu::RenderPass<'_>, _key: usize, _target: Target, _placement: Placement, _run: Option<&wgpu::BindGroup>) -> u32 {
        0
    }

    /// Builds the pipelines for this pass's draws that the frame's plan records, `uses` being
    /// (item key, placement) of each ([`crate::render::plan::SkyPlan::uses`]): no pipeline is
    /// built for a placement the plan did not choose. Returns true when one failed at a
    /// placement the item's [`Caps`] offered; the renderer then plans again, and the failure,
    /// remembered, is no longer offered.
    fn build_planned(&mut self, _device: &wgpu::Device, _target: Target, _uses: &[(usize, Placement)]) -> bool {
        false
    }

    /// Records one item into the compute phase.
    fn dispatch(&self, _cpass: &mut wgpu::ComputePass<'_>, _key: usize) {}

    /// Compute work this frame of a pass that draws in another phase (recorded with
    /// [`Pass::dispatch`] in the compute phase, before any drawing).
    fn compute_items(&self, _cx: &FrameContext<'_>, _out: &mut Vec<DrawItem>) {}

    /// An occlusion query set the phase's render pass must carry (at most one pass per phase).
    fn occlusion_query_set(&self) -> Option<&wgpu::QuerySet> {
        None
    }

    /// Right after the pass's phase ended, every frame (whether or not the pass had items in it):
    /// copies that later phases of the same frame need; `globals` is the renderer's bind group 0.
    fn after_phase(&self, _encoder: &mut wgpu::CommandEncoder, _globals: &wgpu::BindGroup) {}

    /// After every phase was recorded: resolve queries, copy results.
    fn resolve(&self, _encoder: &mut wgpu::CommandEncoder) {}

    /// After the frame was submitted: start asynchronous readbacks.
    fn after_submit(&mut self) {}

    /// Adds this pass's counters to the frame's.
    fn stats(&self, _stats: &mut FrameStats) {}

    /// Where this frame's scene light comes from, if this pass computes a model's light (at most
    /// one pass does); asked after every pass's [`Pass::prepare`].
    fn light_source(&self) -> Option<LightSource> {
        None
    }

    /// Adds the counters of what this pass recorded to the frame's, once every phase is recorded.
    fn stats_recorded(&self, _stats: &mut FrameStats) {}

    /// The time step a still should use while it settles, if this pass needs history to show
    /// its steady state (glare: one persistence period per frame).
    fn settle_dt_s(&self, _options: &RenderOptions) -> Option<f32> {
        None
    }

    /// The histories this pass keeps from frame to frame ([`crate::render::frame::history`]),
    /// asked before every frame's [`Pass::prepare`], which finds them in [`FrameContext::histories`].
    fn histories(&self, _options: &RenderOptions, _out: &mut Vec<HistoryRequest>) {}

    /// Extra frames a still may need for this pass's history to reach its steady state (a
    /// temporal accumulation's length); the renderer allows the most any pass asks, and at
    /// least [`crate::render::frame::renderer::SETTLE_FRAMES`].
    fn settle_frames(&self, _options: &RenderOptions) -> usize {
        0
    }

    /// Whether the last frame showed the steady state (a still stops settling when all agree).
    fn settled(&self) -> bool {
        true
    }

    /// Whether background work for this pass is in flight (a still waits for it).
    fn busy(&self) -> bool {
        false
    }
}

/// Creates a pass; its pipelines are built, its sky resources empty.
pub type PassConstructor = fn(&PassBuild<'_>) -> RenderResult<Box<dyn Pass>>;

/// Boxes a pass's constructor for [`crate::render::passes::PASSES`].
pub fn boxed<P: Pass, F: Fn(&PassBuild<'_>) -> RenderResult<P>>(f: F, build: &PassBuild<'_>) -> RenderResult<Box<dyn Pass>> {
    Ok(Box::new(f(build)?))
}

/// A value in use and a replacement waiting for every other pass to succeed too.
#[derive(Debug)]
pub struct Staged<T> {
    /// In use.
    pub current: T,
    pending: Option<T>,
}

impl<T> Staged<T> {
    /// A value in use, nothing pending.
    pub fn new(current: T) -> Self {
        Self { current, pending: None }
    }

    /// Sets the replacement.
    pub fn stage(&mut self, next: T) {
        self.pending = Some(next);
    }

    /// The replacement, if one is staged.
    pub fn pending(&self) -> Option<&T> {
        self.pending.as_ref()
    }

    /// Swaps the replacement in (`accept`) or drops it; returns the value replaced, if any.
    pub fn commit(&mut self, accept: bool) -> Option<T> {
        match (self.pending.take(), accept) {
            (Some(next), true) => Some(std::mem::replace(&mut self.current, next)),
            _ => None,
        }
    }
}

/// Builds a pass's pipelines with its layout.
pub type PipelineBuilder<T> = fn(&PassBuild<'_>, &wgpu::PipelineLayout) -> RenderResult<T>;

/// A pass's pipelines: its layout (built once), the pipelines in use, and a rebuilt set waiting
/// for every other pass's rebuild to succeed. Render pipelines come in two sets, one per
/// [`Target`] format; compute pipelines in one.
pub struct Pipelines<T> {
    layout: wgpu::PipelineLayout,
    build: PipelineBuilder<T>,
    per_target: bool,
    staged: Staged<(T, Option<T>)>,
}

impl<T> Pipelines<T> {
    /// Builds one set of pipelines with `layout`: compute pipelines, or render pipelines that
    /// only ever draw into the display target.
    pub fn new(b: &PassBuild<'_>, layout: wgpu::PipelineLayout, build: PipelineBuilder<T>) -> RenderResult<Self> {
        Self::with_targets(b, layout, build, false)
    }

    /// Builds render pipelines with `layout` for the display format and for [`crate::render::gpu::parts::HDR_FORMAT`].
    pub fn new_render(b: &PassBuild<'_>, layout: wgpu::PipelineLayout, build: PipelineBuilder<T>) -> RenderResult<Self> {
        Self::with_targets(b, layout, build, true)
    }

    fn with_targets(b: &PassBuild<'_>, layout: wgpu::PipelineLayout, build: PipelineBuilder<T>, per_target: bool) -> RenderResult<Self> {
        let current = Self::build_all(b, &layout, build, per_target)?;
        Ok(Self { layout, build, per_target, staged: Staged::new(current) })
    }

    fn build_all(b: &PassBuild<'_>, layout: &wgpu::PipelineLayout, build: PipelineBuilder<T>, per_target: bool) -> RenderResult<(T, Option<T>)> {
        let display = build(b, layout)?;
        let hdr = if per_target { Some(build(&PassBuild { color_format: crate::render::gpu::parts::HDR_FORMAT, target: Target::Hdr, ..*b }, layout)?) } else { None };
        Ok((display, hdr))
    }

    /// Rebuilds from `b.library` into the pending slot ([`Pass::stage_pipelines`]).
    pub fn stage(&mut self, b: &PassBuild<'_>) -> RenderResult<()> {
        let next = Self::build_all(b, &self.layout, self.build, self.per_target)?;
        self.staged.stage(next);
        Ok(())
    }

    /// Swaps the rebuilt pipelines in, or drops them ([`Pass::commit_pipelines`]).
    pub fn commit(&mut self, accept: bool) {
        self.staged.commit(accept);
    }

    /// The pipelines in use (for the display format).
    pub fn get(&self) -> &T {
        &self.staged.current.0
    }

    /// The pipelines in use for `target`.
    pub fn for_target(&self, target: Target) -> &T {
        match (&self.staged.current, target) {
            ((_, Some(hdr)), Target::Hdr) => hdr,
            ((display, _), _) => display,
        }
    }
}
