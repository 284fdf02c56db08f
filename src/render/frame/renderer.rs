//! The sky renderer: runs the passes of [`PASSES`] phase by phase. It owns bind group 0 and the
//! frame's atmosphere on the GPU ([`AtmosphereGpu`]); each pass owns its pipelines, its per-sky resources and its state. It knows
//! nothing of egui or winit; the app and the CLI drive it.

use crate::render::atmosphere::AtmosphereGpu;
use crate::render::frame::camera::Camera;
use crate::render::frame::depth::SceneDepth;
use crate::render::frame::globals::{Globals, GlobalsBinding};
use crate::render::frame::history::Histories;
use crate::render::frame::light::SceneLight;
use crate::render::frame::options::RenderOptions;
use crate::render::frame::pass::{DrawItem, FrameContext, Pass, PassBuild, Phase, Placement, SkyUpload, Target};
use crate::render::frame::stats::{FrameStats, UploadStats};
use crate::render::gpu::context::GpuContext;
use crate::render::gpu::error::RenderResult;
use crate::render::gpu::shaders::{self, ShaderLibrary};
use crate::render::gpu::textures::TextureCache;
use crate::render::gpu::timing::GpuTimer;
use crate::render::passes::reduced_layers::{Joining, ReducedLayersPass};
use crate::render::passes::PASSES;
use crate::render::plan::{self, FrameFacts, RunInput, Seeding, SkyPlan, SkyStep, Step};
use crate::sky::{FrameSky, Sky};

/// Depth range of the main scene: it always wins against the sky.
pub const SCENE_DEPTH: (f32, f32) = (0.0, 0.95);
/// Depth range of the sky.
pub const SKY_DEPTH: (f32, f32) = (0.99, 1.0);

/// Extra frames a still renders at most while its passes settle, unless one asks for more
/// ([`Pass::settle_frames`]).
pub const SETTLE_FRAMES: usize = 6;

/// Plans of one frame at most after the first, each after a pipeline the previous one chose
/// failed to build (each failure is remembered, so the plans converge; a draw whose pipeline
/// still fails after them is not drawn, and was logged).
const MAX_REPLANS: usize = 4;

/// Where a frame is drawn.
pub struct RenderTarget<'a> {
    /// Colour view, in the renderer's colour format.
    pub color: &'a wgpu::TextureView,
    /// Size, pixels.
    pub size: (u32, u32),
}

/// The HDR colour target of physical-model frames, sized like the display target.
struct HdrTarget {
    texture: wgpu::Texture,
    view: wgpu::TextureView,
    size: (u32, u32),
    /// Changes whenever the target is recreated (passes that bind it rebuild their bind groups).
    generation: u64,
}

/// One draw item of a phase and the index of its pass.
type PhaseItem = (usize, DrawItem);

/// Records frames of a sky.
pub struct SkyRenderer {
    globals: GlobalsBinding,
    library: ShaderLibrary,
    color_format: wgpu::TextureFormat,
    textures: TextureCache,
    atmosphere: AtmosphereGpu,
    passes: Vec<Box<dyn Pass>>,
    has_sky: bool,
    hdr: Option<HdrTarget>,
    timer: Option<GpuTimer>,
    /// The scene's depth, sized like the last frame's target.
    depth: Option<SceneDepth>,
    /// The passes' histories.
    histories: Histories,
    /// The last frame's main-scene camera, world -> clip (the globals carry it as the previous one).
    previous_clip_from_world: Option<glam::Mat4>,
    /// Counters of the last recorded frame.
    pub stats: FrameStats,
    /// The last frame's plan of its sky phase (diagnostics and tests read it).
    pub plan: SkyPlan,
    /// What the last sky upload reused.
    pub upload_stats: UploadStats,
}

impl SkyRenderer {
    /// Builds every pass of [`PASSES`] for a colour format.
    pub fn new(ctx: &GpuContext, color_format: wgpu::TextureFormat, library: ShaderLibrary) -> RenderResult<Self> {
        Self::with_passes(ctx, color_format, library, &[])
    }

    /// Builds the passes of [`PASSES`] and then `extra` ones (tools and tests that add a pass
    /// without touching the product's list).
    pub fn with_passes(
        ctx: &GpuContext,
        color_format: wgpu::TextureFormat,
        library: ShaderLibrary,
        extra: &[(&str, crate::render::frame::pass::PassConstructor)],
    ) -> RenderResult<Self> {
        let device = &ctx.device;
        let globals = GlobalsBinding::new(device);
        let atmosphere = AtmosphereGpu::new(device);
        let build = PassBuild {
            device,
            globals_layout: &globals.layout,
            scene_light: &globals.scene_light,
            library: &library,
            color_format,
            atmosphere: &atmosphere,
            target: Target::Display,
        };
        let passes = PASSES.iter().chain(extra).map(|(_, new)| new(&build)).collect::<RenderResult<Vec<_>>>()?;
        Ok(Self {
            textures: TextureCache::new(device, &ctx.queue),
            atmosphere,
            globals,
            library,
            color_format,
            passes,
            has_sky: false,
            hdr: None,
            timer: ctx.timestamps.then(|| GpuTimer::new(device, &ctx.queue)),
            depth: None,
            histories: Histories::default(),
            previous_clip_from_world: None,
            stats: FrameStats::default(),
            plan: SkyPlan::default(),
            upload_stats: UploadStats::default(),
        })
    }

    /// Uploads a sky into every pass, replacing the previous one only if every upload succeeds.
    /// Textures whose file did not change, meshes and the state of simulations carry over.
    pub fn set_sky(&mut self, ctx: &GpuContext, sky: &Sky) -> RenderResult<()> {
        let mut textures = self.textures.successor();
        let result = shaders::validated(&ctx.device, "uploading the sky", || {
            let mut upload = SkyUpload { device: &ctx.device, queue: &ctx.queue, sky, textures: &mut textures };
            for pass in &mut self.passes {
                pass.stage_sky(&mut upload);
            }
        });
        for pass in &mut self.passes {
            pass.commit_sky(result.is_ok());
        }
        result?;
        textures.forget_previous();
        self.upload_stats = UploadStats { textures_uploaded: textures.uploaded, textures_reused: textures.reused };
        self.textures = textures;
        self.has_sky = true;
        Ok(())
    }

    /// Rebuilds every pipeline from the shader library (hot reload). All or nothing: on any error
    /// every pass keeps its previous pipelines and the error is returned.
    pub fn reload_shaders(&mut self, ctx: &GpuContext) -> RenderResult<()> {
        let build = PassBuild {
            device: &ctx.device,
            globals_layout: &self.globals.layout,
            scene_light: &self.globals.scene_light,
            library: &self.library,
            color_format: self.color_format,
            atmosphere: &self.atmosphere,
            target: Target::Display,
        };
        let result = self.passes.iter_mut().try_for_each(|p| p.stage_pipelines(&build));
        for pass in &mut self.passes {
            pass.commit_pipelines(result.is_ok());
        }
        release_freed_memory();
        result
    }

    /// Replaces the shader library (e.g. switch between embedded and on-disk sources).
    pub fn set_library(&mut self, library: ShaderLibrary) {
        self.library = library;
    }

    /// The shader library in use.
    pub fn library(&self) -> &ShaderLibrary {
        &self.library
    }

    /// Colour format of the pipelines.
    pub fn color_format(&self) -> wgpu::TextureFormat {
        self.color_format
    }

    /// Names and phases of the passes, in list order.
    pub fn pass_names(&self) -> Vec<(&'static str, Phase)> {
        self.passes.iter().map(|p| (p.name(), p.phase())).collect()
    }

    /// The frame's atmosphere on the GPU (its tables, the sky-view map and its light).
    pub fn atmosphere(&self) -> &AtmosphereGpu {
        &self.atmosphere
    }

    /// The pass of type `P`, if the renderer has one.
    pub fn pass<P: Pass>(&self) -> Option<&P> {
        self.passes.iter().find_map(|p| (p.as_ref() as &dyn std::any::Any).downcast_ref::<P>())
    }

    /// The pass of type `P`, mutable.
    pub fn pass_mut<P: Pass>(&mut self) -> Option<&mut P> {
        self.passes.iter_mut().find_map(|p| (p.as_mut() as &mut dyn std::any::Any).downcast_mut::<P>())
    }

    /// Glare visibility and intensity, if the sky has glare.
    pub fn glare_state(&self) -> Option<&crate::render::passes::glare::GlareState> {
        self.pass::<crate::render::passes::glare::GlarePass>()?.resources().map(|g| &g.state)
    }

    /// Phase of the glare's occlusion queries, if the sky has glare.
    pub fn glare_query_phase(&self) -> Option<crate::render::passes::glare::QueryPhase> {
        self.pass::<crate::render::passes::glare::GlarePass>()?.resources().map(|g| g.query_phase().clone())
    }

    /// Mutable glare state (freeze toggle).
    pub fn glare_state_mut(&mut self) -> Option<&mut crate::render::passes::glare::GlareState> {
        self.pass_mut::<crate::render::passes::glare::GlarePass>()?.resources_mut().map(|g| &mut g.state)
    }

    /// Time step for the frames of a still until it settles, if a pass needs history to show
    /// its steady state.
    pub fn settle_dt_s(&self, options: &RenderOptions) -> Option<f32> {
        self.passes.iter().filter_map(|p| p.settle_dt_s(options)).reduce(f32::max)
    }

    /// Extra frames a still renders at most while its passes settle.
    pub fn settle_frames(&self, options: &RenderOptions) -> usize {
        self.passes.iter().map(|p| p.settle_frames(options)).fold(SETTLE_FRAMES, usize::max)
    }

    /// Whether the last frame showed every pass's steady state.
    pub fn settled(&self) -> bool {
        self.passes.iter().all(|p| p.settled())
    }

    /// Whether any pass has background work in flight.
    pub fn busy(&self) -> bool {
        self.passes.iter().any(|p| p.busy())
    }

    /// Records one frame into `encoder`: every pass's per-frame step, then each phase in order.
    /// Call [`Self::after_submit`] once the encoder is submitted.
    pub fn render(&mut self, ctx: &GpuContext, encoder: &mut wgpu::CommandEncoder, target: &RenderTarget<'_>, frame: &FrameSky, camera: &Camera, options: &RenderOptions) {
        let (w, h) = target.size;
        let physical = self.has_sky && frame.sky_model.kind.is_physical();
        let (kind, matched) = (plan::frame_target(physical, &options.strategy), plan::matches_hdr_picture(physical, &options.strategy));
        let mut globals = Globals::new(frame, camera, w, h, (kind, matched));
        let current = glam::Mat4::from_cols_array_2d(&globals.clip_from_world);
        globals.previous_clip_from_world = self.previous_clip_from_world.replace(current).unwrap_or(current).to_cols_array_2d();
        let range = if options.depth_split { SCENE_DEPTH } else { (0.0, 1.0) };
        (globals.depth[0], globals.depth[1]) = range;
        ctx.queue.write_buffer(&self.globals.buffer, 0, bytemuck::bytes_of(&globals));
        if !self.has_sky {
            return;
        }
        if kind == Target::Hdr {
            self.ensure_hdr(&ctx.device, target.size);
        }
        self.ensure_depth(&ctx.device, target.size);
        let hdr = self.hdr.as_ref().filter(|_| kind == Target::Hdr).map(|t| (&t.view, t.generation));
        let depth = self.depth.as_ref().expect("made above");
        let mut requests = Vec::new();
        for pass in &self.passes {
            requests.clear();
            pass.histories(options, &mut requests);
            self.histories.ensure(&ctx.device, pass.name(), &requests, target.size);
        }
        self.atmosphere.prepare(&ctx.queue, &frame.atmosphere);
        let cx = FrameContext {
            device: &ctx.device,
            queue: &ctx.queue,
            frame,
            camera,
            options,
            size: target.size,
            target: kind,
            matched,
            hdr,
            depth: (&depth.view, depth.generation),
            histories: &self.histories,
        };
        for pass in &mut self.passes {
            pass.prepare(&cx);
        }
        let source = self.passes.iter().find_map(|p| p.light_source()).unwrap_or_default();
        ctx.queue.write_buffer(&self.globals.scene_light, 0, bytemuck::bytes_of(&SceneLight::new(frame, source)));
        let mut stats = FrameStats::default();
        for pass in &self.passes {
            pass.stats(&mut stats);
        }
        let mut items = self.collect_items(&cx);
        let (wf, hf) = (w as f32, h as f32);
        let facts = FrameFacts {
            scene_in_view: options.scene && camera.elevation_range_deg(wf / hf.max(1.0)).0 < -crate::render::plan::visibility::SCENE_COVERS_BELOW_DEG,
            reduced_layers: self.pass::<ReducedLayersPass>().is_some(),
            covered_clears: options.skips.covered_clears,
            depth_clean: depth.untouched,
        };
        let mut plan = plan::plan(std::mem::take(&mut items[Phase::Sky.index()]), &options.strategy, facts);
        // Pipelines for what the plan uses and nothing else. A failed one withdraws the
        // capability that offered it (the pass remembers it): plan again without it.
        for attempt in 0..=MAX_REPLANS {
            if !Self::build_planned(&mut self.passes, &ctx.device, kind, &plan) || attempt == MAX_REPLANS {
                break;
            }
            items = self.collect_items(&cx);
            plan = plan::plan(std::mem::take(&mut items[Phase::Sky.index()]), &options.strategy, facts);
        }
        stats.reduced_runs = plan.divisors();
        stats.joined_runs_only = plan.items.iter().filter(|(_, it)| it.reduced && it.joins_only).count() as u32;
        stats.composites = plan.composites;
        stats.seeded = plan.seeded;
        stats.drawn_first = plan.drawn_first;
        stats.background_fused = matches!(plan.background, Some(plan::Background::Fused { .. }));
        stats.seed_folded = plan.seed_folded;
        stats.layers_paired = plan.layers_paired;
        stats.own_buffers = plan.own_buffers.len() as u32;
        stats.clears_skipped = u32::from(!plan.clear_color) + u32::from(!plan.clear_depth);
        if let (false, Some(layers)) = (plan.runs.is_empty(), self.pass_mut::<ReducedLayersPass>()) {
            let joining = if plan.seeded { Joining::Seeded(&plan.combined) } else { Joining::Combined(&plan.combined) };
            // Layers over the seed blend in radiance on a matched frame (`OVER_MODEL_SKY`).
            let seed_radiance = plan.seed_folded && matched;
            layers.ensure(&ctx.device, &ctx.queue, ((w, h), kind), &plan.divisors(), (joining, seed_radiance), &plan.own_buffers.iter().map(|o| o.divisor).collect::<Vec<_>>());
        }
        if let Some(t) = self.timer.as_mut() {
            t.begin_frame();
        }
        for phase in Phase::ALL {
            let list = if phase == Phase::Sky { &plan.items } else { &items[phase.index()] };
            match phase {
                Phase::Compute if !list.is_empty() => {
                    let mut cpass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                        label: Some("SkyRenderer::compute"),
                        timestamp_writes: self.timer.as_mut().and_then(|t| t.compute_writes(phase)),
                    });
                    cpass.set_bind_group(0, &self.globals.bind_group, &[]);
                    for (i, it) in list {
                        self.passes[*i].dispatch(&mut cpass, it.key);
                    }
                }
                Phase::Compute => {}
                // The scene and sky phases always run (the scene phase clears the target); the
                // others only when a pass has something to draw.
                _ if list.is_empty() && phase != Phase::Scene && phase != Phase::Sky => {}
                Phase::Display => stats.draw_calls += self.record_display(encoder, target, list),
                _ => stats.draw_calls += self.record_phase(encoder, target, (phase, kind), options, (&plan, &items[Phase::Scene.index()], list)),
            }
            for pass in self.passes.iter().filter(|p| p.phase() == phase) {
                pass.after_phase(encoder, &self.globals.bind_group);
            }
        }
        for pass in &self.passes {
            pass.resolve(encoder);
        }
        if let Some(t) = &self.timer {
            t.resolve(encoder);
        }
        // Only the main scene writes depth: without it the view still holds the clear value.
        if let Some(depth) = self.depth.as_mut() {
            depth.untouched = items[Phase::Scene.index()].is_empty();
        }
        self.histories.swap();
        for pass in &self.passes {
            pass.stats_recorded(&mut stats);
        }
        self.stats = stats;
        self.plan = plan;
    }

    /// Has every pass build the pipelines of its draws in `plan`; returns whether one failed at
    /// a placement its item's capabilities offered.
    fn build_planned(passes: &mut [Box<dyn Pass>], device: &wgpu::Device, kind: Target, plan: &SkyPlan) -> bool {
        let uses = plan.uses();
        let mut failed = false;
        let mut mine = Vec::new();
        for (i, pass) in passes.iter_mut().enumerate() {
            mine.clear();
            mine.extend(uses.iter().filter(|u| u.0 == i).map(|&(_, key, placement)| (key, placement)));
            if !mine.is_empty() {
                failed |= pass.build_planned(device, kind, &mine);
            }
        }
        failed
    }

    /// Every pass's items this frame, per phase: (pass index, item), in list order.
    fn collect_items(&self, cx: &FrameContext<'_>) -> [Vec<PhaseItem>; Phase::ALL.len()] {
        let mut items: [Vec<PhaseItem>; Phase::ALL.len()] = Default::default();
        let mut scratch = Vec::new();
        for (i, pass) in self.passes.iter().enumerate() {
            scratch.clear();
            pass.items(cx, &mut scratch);
            items[pass.phase().index()].extend(scratch.iter().map(|it| (i, *it)));
            scratch.clear();
            pass.compute_items(cx, &mut scratch);
            items[Phase::Compute.index()].extend(scratch.iter().map(|it| (i, *it)));
        }
        items
    }

    /// The display phase: the HDR target tone-mapped into the display target.
    fn record_display(&mut self, encoder: &mut wgpu::CommandEncoder, target: &RenderTarget<'_>, list: &[(usize, DrawItem)]) -> u32 {
        let writes = self.timer.as_mut().and_then(|t| t.render_writes(Phase::Display));
        let mut rpass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("SkyRenderer::display"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: target.color,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: writes,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        rpass.set_bind_group(0, &self.globals.bind_group, &[]);
        list.iter().map(|(i, it)| self.passes[*i].draw(&mut rpass, it.key, Target::Display, Placement::Plain, None)).sum()
    }

    /// One drawing phase into the frame's target: for the scene phase the reduced runs first and
    /// the background; for the sky phase the plan's steps. Returns draw calls.
    fn record_phase(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        target: &RenderTarget<'_>,
        (phase, kind): (Phase, Target),
        options: &RenderOptions,
        (plan, scene, list): (&SkyPlan, &[PhaseItem], &[PhaseItem]),
    ) -> u32 {
        let (wf, hf) = (target.size.0 as f32, target.size.1 as f32);
        let split = options.depth_split;
        let mut calls = 0;
        let load = if phase == Phase::Scene {
            let color = if plan.clear_color {
                wgpu::LoadOp::Clear(wgpu::Color::BLACK)
            } else {
                // SAFETY: the background, the pass's first draw, writes every pixel of the frame
                // (the plan's `clear_color` is false only then), unblended, before any read or store.
                wgpu::LoadOp::DontCare(unsafe { wgpu::LoadOpDontCare::enabled() })
            };
            (color, if plan.clear_depth { wgpu::LoadOp::Clear(1.0) } else { wgpu::LoadOp::Load })
        } else {
            (wgpu::LoadOp::Load, wgpu::LoadOp::Load)
        };
        if phase == Phase::Scene && !plan.runs.is_empty() {
            // The reduced buffers first: the first may be the background.
            calls += self.record_runs(encoder, kind, plan);
        }
        let queries = list.iter().find_map(|(i, _)| self.passes[*i].occlusion_query_set());
        let label = format!("SkyRenderer::{}", phase.name());
        let writes = self.timer.as_mut().and_then(|t| t.render_writes(phase));
        let color = match &self.hdr {
            Some(t) if kind == Target::Hdr => &t.view,
            _ => target.color,
        };
        let depth = &self.depth.as_ref().expect("made before the phases").view;
        let mut rpass = begin_pass(encoder, &label, (color, depth), load, writes, queries);
        rpass.set_bind_group(0, &self.globals.bind_group, &[]);
        let range = match phase {
            Phase::Sky | Phase::Overlay if split || phase == Phase::Overlay => SKY_DEPTH,
            Phase::Scene | Phase::SceneAfterSky if split => SCENE_DEPTH,
            _ => (0.0, 1.0),
        };
        rpass.set_viewport(0.0, 0.0, wf, hf, range.0, range.1);
        if let (Phase::Scene, Some(background)) = (phase, &plan.background) {
            calls += self.record_background(&mut rpass, target.size, kind, plan, background);
        }
        // Without the depth split the scene phase's draws move to the end of the sky phase,
        // painted over an already shaded sky.
        match phase {
            Phase::Sky => {
                calls += self.record_sky(&mut rpass, kind, plan);
                if !split {
                    rpass.set_viewport(0.0, 0.0, wf, hf, 0.0, 1.0);
                    calls += scene.iter().map(|(i, it)| self.passes[*i].draw(&mut rpass, it.key, kind, Placement::Plain, None)).sum::<u32>();
                }
            }
            Phase::Scene if !split => {}
            _ => calls += list.iter().map(|(i, it)| self.passes[*i].draw(&mut rpass, it.key, kind, Placement::Plain, None)).sum::<u32>(),
        }
        calls
    }

    /// The run buffer a step reads.
    fn run_input(&self, input: RunInput) -> Option<&wgpu::BindGroup> {
        let layers = reduced_layers(&self.passes)?;
        match input {
            RunInput::None => None,
            RunInput::Upper(j) => layers.upper_bind_group(j),
            RunInput::Seed => layers.seed_source(),
            // Composited by the run's pass itself (`record_runs`), never read by a draw.
            RunInput::Own(_) => None,
        }
    }

    /// Records one step of the plan; a step whose run buffer is missing is drawn in its place.
    fn record_step(&self, rpass: &mut wgpu::RenderPass<'_>, kind: Target, plan: &SkyPlan, step: &Step) -> u32 {
        let (i, it) = &plan.items[step.item];
        match (step.input, self.run_input(step.input)) {
            (RunInput::None, _) => self.passes[*i].draw(rpass, it.key, kind, step.placement, None),
            (_, Some(run)) => self.passes[*i].draw(rpass, it.key, kind, step.placement, Some(run)),
            // Never while the plan and the buffers agree (`ReducedLayersPass::ensure` makes every
            // buffer the plan reads): drawn without the run, at its resolution, both of a pair.
            (_, None) => {
                debug_assert!(step.input == RunInput::None, "the plan reads a run buffer that was not made: {step:?}");
                match step.placement {
                    Placement::Pair { upper, .. } => {
                        self.passes[*i].draw(rpass, it.key, kind, Placement::Reduced, None) + self.passes[*i].draw(rpass, upper, kind, Placement::Reduced, None)
                    }
                    Placement::OverSeed => self.passes[*i].draw(rpass, it.key, kind, Placement::Reduced, None),
                    _ => self.passes[*i].draw(rpass, it.key, kind, Placement::Plain, None),
                }
            }
        }
    }

    /// Each run of reduced layers into its buffer, and the joined runs' combinations.
    fn record_runs(&mut self, encoder: &mut wgpu::CommandEncoder, kind: Target, plan: &SkyPlan) -> u32 {
        let mut calls = 0;
        let n = plan.runs.len();
        for (r, run) in plan.runs.iter().enumerate() {
            // The layers the run composites from buffers of their own, drawn into those first.
            let mut first_pass = r == 0;
            for step in &run.draws {
                let RunInput::Own(p) = step.input else { continue };
                let writes = self.timer.as_mut().and_then(|t| t.reduced_writes(first_pass, false));
                first_pass = false;
                let Some(layers) = reduced_layers(&self.passes) else { return calls };
                let Some(mut rpass) = layers.begin_own(encoder, p, writes) else { continue };
                rpass.set_bind_group(0, &self.globals.bind_group, &[]);
                let (i, it) = &plan.items[step.item];
                calls += self.passes[*i].draw(&mut rpass, it.key, kind, Placement::Reduced, None);
            }
            let run_writes = self.timer.as_mut().and_then(|t| t.reduced_writes(first_pass, r + 1 == n && plan.combined.is_empty()));
            let Some(layers) = reduced_layers(&self.passes) else { return calls };
            if run.draws.iter().any(|s| s.input == RunInput::Seed) {
                calls += layers.convert_seed(encoder, &self.globals.bind_group);
            }
            let Some(mut rpass) = layers.begin(encoder, r, run_writes) else { continue };
            match run.seeding {
                Seeding::None => {}
                Seeding::Whole => calls += layers.seed(&mut rpass, &self.globals.bind_group, kind),
                Seeding::Within(gap) => calls += layers.seed_within(&mut rpass, &self.globals.bind_group, kind, gap),
            }
            rpass.set_bind_group(0, &self.globals.bind_group, &[]);
            for step in &run.draws {
                calls += match step.input {
                    RunInput::Own(p) => layers.composite_own(&mut rpass, &self.globals.bind_group, kind, (p, plan.own_buffers[p].covers), run.divisor),
                    _ => self.record_step(&mut rpass, kind, plan, step),
                };
            }
        }
        if !plan.combined.is_empty() {
            let writes = self.timer.as_mut().and_then(|t| t.reduced_writes(false, true));
            if let Some(layers) = reduced_layers(&self.passes) {
                calls += layers.record_combined(encoder, &self.globals.bind_group, kind, writes);
            }
        }
        calls
    }

    /// The background, first in the scene's pass.
    fn record_background(&self, rpass: &mut wgpu::RenderPass<'_>, (w, h): (u32, u32), kind: Target, plan: &SkyPlan, background: &plan::Background) -> u32 {
        let Some(layers) = self.pass::<ReducedLayersPass>() else { return 0 };
        let joined = plan.joined();
        let mut calls = 0;
        match background {
            plan::Background::Fused { gap, fused, others } => {
                // Where the fused draw does not reach (below a dome), the background's
                // composite, onto the cleared frame and confined to those pixels.
                if let Some([x, y, gw, gh]) = *gap {
                    rpass.set_scissor_rect(x, y, gw, gh);
                    calls += layers.draw_background(rpass, kind, joined, false);
                    rpass.set_scissor_rect(0, 0, w, h);
                }
                calls += self.record_step(rpass, kind, plan, fused);
                for step in others {
                    calls += self.record_step(rpass, kind, plan, step);
                }
            }
            plan::Background::Composite { first } => {
                for &k in first {
                    calls += self.record_step(rpass, kind, plan, &Step { item: k, placement: Placement::First, input: RunInput::None });
                }
                calls += layers.draw_background(rpass, kind, joined, !first.is_empty());
            }
        }
        calls
    }

    /// The sky phase's steps.
    fn record_sky(&self, rpass: &mut wgpu::RenderPass<'_>, kind: Target, plan: &SkyPlan) -> u32 {
        let layers = reduced_layers(&self.passes);
        plan.steps
            .iter()
            .map(|step| match (step, layers) {
                (SkyStep::Draw(step), _) => self.record_step(rpass, kind, plan, step),
                (SkyStep::Composite(r), Some(layers)) => layers.draw(rpass, *r, kind, Placement::Plain, None),
                (SkyStep::Composite(_), None) => 0,
            })
            .sum()
    }

    /// Creates the depth target, or recreates it at a new size.
    fn ensure_depth(&mut self, device: &wgpu::Device, size: (u32, u32)) {
        if self.depth.as_ref().is_none_or(|d| d.size != size) {
            let generation = self.depth.as_ref().map_or(0, |d| d.generation + 1);
            self.depth = Some(SceneDepth::new(device, size, generation));
        }
    }

    /// The scene's depth of the last frame ([`crate::render::gpu::parts::DEPTH_FORMAT`]; the
    /// main scene's in [`SCENE_DEPTH`] with the depth split), once a frame was drawn.
    pub fn depth(&self) -> Option<&SceneDepth> {
        self.depth.as_ref()
    }

    /// The passes' histories (made for the last frame's size).
    pub fn histories(&self) -> &Histories {
        &self.histories
    }

    /// Creates the HDR target, or recreates it at a new size.
    fn ensure_hdr(&mut self, device: &wgpu::Device, (width, height): (u32, u32)) {
        if self.hdr.as_ref().is_some_and(|t| t.size == (width, height)) {
            return;
        }
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("SkyRenderer::hdr_target"),
            size: wgpu::Extent3d { width: width.max(1), height: height.max(1), depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: crate::render::gpu::parts::HDR_FORMAT,
            // COPY_SRC: linear exports (`render --format exr`) read it back.
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let view = texture.create_view(&Default::default());
        let generation = self.hdr.as_ref().map_or(0, |t| t.generation + 1);
        self.hdr = Some(HdrTarget { texture, view, size: (width, height), generation });
    }

    /// The HDR target (exposed linear radiance, rgba16float) of the last frame that used one.
    pub fn hdr_texture(&self) -> Option<&wgpu::Texture> {
        self.hdr.as_ref().map(|t| &t.texture)
    }

    /// GPU time of each phase of a recent frame, ms (empty without timestamp queries).
    pub fn gpu_pass_ms(&self) -> &[(&'static str, f32)] {
        self.timer.as_ref().map_or(&[], |t| &t.last_ms)
    }

    /// Makes [`Self::gpu_pass_ms`] the last submitted frame's, when its readback has finished
    /// (after [`Self::after_submit`] and a wait on the device); otherwise the next frame picks it
    /// up. For measurements that alternate different frames and need each one's own phases.
    pub fn collect_gpu_timings(&mut self) {
        if let Some(t) = self.timer.as_mut() {
            t.collect();
        }
    }

    /// Call after the encoder of [`Self::render`] was submitted: starts asynchronous readbacks.
    pub fn after_submit(&mut self) {
        if let Some(t) = self.timer.as_mut() {
            t.after_submit();
        }
        for pass in &mut self.passes {
            pass.after_submit();
        }
    }
}

/// Hands heap memory freed so far back to the system. A shader compiler (lavapipe's LLVM, a
/// driver's) makes large short-lived allocations for every pipeline; glibc keeps freed heap in its
/// arenas, so without this the resident size ratchets up with every shader rebuild of a long
/// session (measured by `skytune soak`: docs/reliability.md).
pub fn release_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        extern "C" {
            fn malloc_trim(pad: usize) -> std::ffi::c_int;
        }
        // SAFETY: malloc_trim only releases free heap pages; it has no preconditions.
        unsafe {
            malloc_trim(0);
        }
    }
}

/// The pass drawing reduced buffers, found through the pass list alone (so that the timer may be
/// borrowed beside it).
fn reduced_layers(passes: &[Box<dyn Pass>]) -> Option<&ReducedLayersPass> {
    passes.iter().find_map(|p| (p.as_ref() as &dyn std::any::Any).downcast_ref::<ReducedLayersPass>())
}

/// Begins one phase's render pass on the shared colour and depth targets.
fn begin_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    label: &str,
    (color, depth): (&wgpu::TextureView, &wgpu::TextureView),
    (load_color, load_depth): (wgpu::LoadOp<wgpu::Color>, wgpu::LoadOp<f32>),
    timestamp_writes: Option<wgpu::RenderPassTimestampWrites<'_>>,
    occlusion_query_set: Option<&wgpu::QuerySet>,
) -> wgpu::RenderPass<'e> {
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: color,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations { load: load_color, store: wgpu::StoreOp::Store },
        })],
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: depth,
            depth_ops: Some(wgpu::Operations { load: load_depth, store: wgpu::StoreOp::Store }),
            stencil_ops: None,
        }),
        timestamp_writes,
        occlusion_query_set,
        multiview_mask: None,
    })
}
