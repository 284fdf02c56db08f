//! The sky renderer: runs the passes of [`PASSES`] phase by phase. It owns bind group 0 and the
//! shared textures; each pass owns its pipelines, its per-sky resources and its state. It knows
//! nothing of egui or winit; the app and the CLI drive it.

use super::camera::Camera;
use super::error::RenderResult;
use super::globals::{Globals, GlobalsBinding};
use super::pass::{DrawItem, FrameContext, Pass, PassBuild, Phase, SharedResources, SkyUpload, Target, PASSES};
use super::reduced_layers::Divisor;
use super::reduced_layers::{Joining, ReducedLayersPass};
use super::shaders::{self, ShaderLibrary};
use super::strategy::FillStrategy;
use super::textures::TextureCache;
use super::timing::GpuTimer;
use super::GpuContext;
use crate::sky::{FrameSky, Sky};

/// Depth range of the main scene: it always wins against the sky.
pub const SCENE_DEPTH: (f32, f32) = (0.0, 0.95);
/// Depth range of the sky.
pub const SKY_DEPTH: (f32, f32) = (0.99, 1.0);

/// What to draw besides the sky.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RenderOptions {
    /// Draw the main-scene stand-in (terrain, buildings).
    pub scene: bool,
    /// Draw the scene first in [0, 0.95] and the sky in [0.99, 1] (early depth rejection of hidden
    /// sky). Off: the sky is painted first over the whole screen, then the scene, as without the split.
    pub depth_split: bool,
    /// Draw the sun glare (and run its occlusion queries).
    pub glare: bool,
    /// Draw a test occluder into the scene's depth.
    pub occluder: Option<super::scene::Occluder>,
    /// Work skipped because it would contribute nothing (all on by default; off to measure
    /// what each saves).
    pub skips: Skips,
    /// How the sky's pixels are filled: reduced buffers and the tricks that go with them, a
    /// preset per kind of adapter ([`FillStrategy::for_device`]).
    pub strategy: FillStrategy,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self { scene: true, depth_split: true, glare: true, occluder: None, skips: Skips::default(), strategy: FillStrategy::default() }
    }
}

impl RenderOptions {
    /// These options filling the sky's pixels with `strategy`.
    pub fn with_strategy(self, strategy: FillStrategy) -> Self {
        Self { strategy, ..self }
    }
}

/// The renderer's skips of work that contributes nothing to the frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Skips {
    /// Texture stages whose term is black this frame are not sampled, and alpha-blended or
    /// additive draws whose every term is (black and transparent) are not drawn.
    pub dark_stages: bool,
    /// The star field is not drawn while its colour is transparent (daylight), nor its stars
    /// too faint this frame to add half a level of 255 (dusk).
    pub invisible_stars: bool,
    /// The `lut` tables and the sky-view map are not recomputed while nothing they depend on moved.
    pub unchanged_tables: bool,
    /// With the main scene drawn, billboards and quads entirely below the horizon (by more than
    /// [`SCENE_COVERS_BELOW_DEG`]) are not drawn, nor the rows of dome triangles there (domes
    /// are drawn by rows with `unneeded_mips`): the scene covers that part of the sky.
    pub below_horizon: bool,
    /// Dome layers whose band of elevations the frame does not show (a fog band under a view
    /// of the zenith) are not drawn, nor composited; nor are billboards and quads wholly
    /// outside the frame, nor the parts of the main-scene stand-in wholly outside the view, nor
    /// the glare's occlusion queries while the sun's disc lies wholly outside the frame (both
    /// would count no sample: that result stands for them).
    pub off_screen: bool,
    /// Texture stages that no pixel of a draw minifies are sampled from level 0 alone (the same
    /// texels; lavapipe then skips computing the level of detail).
    pub unneeded_mips: bool,
    /// The frame's colour is not cleared when the background (the first run of reduced dome
    /// layers, composited or fused with the skydome's stars) writes every pixel before anything
    /// reads it, nor the depth while it still holds the clear value: no main scene drawn into
    /// that depth view since the renderer last cleared it. Each clear is a pass over the frame.
    pub covered_clears: bool,
}

/// The main-scene stand-in covers every direction more than this far below the horizon, degrees
/// (its terrain reaches 2.5 km at a viewer height of 2 m; its lowest dip is 40 m down).
pub const SCENE_COVERS_BELOW_DEG: f32 = 2.0;

impl Default for Skips {
    fn default() -> Self {
        Self { dark_stages: true, invisible_stars: true, unchanged_tables: true, below_horizon: true, off_screen: true, unneeded_mips: true, covered_clears: true }
    }
}

/// Counters of the last frame, for the stats panel and logs.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FrameStats {
    /// Draw calls recorded.
    pub draw_calls: u32,
    /// Sky objects drawn.
    pub objects_drawn: u32,
    /// Sky objects hidden (ref alpha, tier, toggle, view).
    pub objects_hidden: u32,
    /// Stars in the field after the magnitude cutoff.
    pub stars: u32,
    /// Of those, the stars drawn this frame: bright enough to add half a level of 255 somewhere
    /// ([`Skips::invisible_stars`]).
    pub stars_drawn: u32,
    /// Texture stages of sky objects not sampled because their term is black this frame.
    pub stages_skipped: u32,
    /// Alpha-blended and additive draws of sky objects left out because every term of theirs is
    /// black and transparent this frame (they would leave the frame as it is).
    pub draws_dark: u32,
    /// Sky objects not drawn because their ref colour's alpha is 0 this frame.
    pub objects_ref_hidden: u32,
    /// Sky objects not drawn because they are below the horizon, behind the main scene.
    pub objects_below_horizon: u32,
    /// Dome layers not drawn because the frame does not show their elevations, and billboards
    /// and quads not drawn because they lie wholly outside the frame.
    pub objects_off_screen: u32,
    /// Texture stages sampled from level 0 alone (no pixel minifies them), over every draw.
    pub stages_level0: u32,
    /// Sky objects drawn into a reduced-resolution buffer ([`dome_resolution`](super::strategy::FillStrategy::dome_resolution)).
    pub objects_reduced: u32,
    /// Each run of reduced layers this frame, in draw order: its buffer's divisor (2: half the
    /// frame's width and height, 2.5: two fifths, 4: a quarter). One composite each.
    pub reduced_runs: Vec<Divisor>,
    /// Full-screen composites of those runs (the background included): one for all the runs
    /// joined ([`Combined`](super::strategy::RunJoining::Combined)).
    pub composites: u32,
    /// Additive draws put under the background ([`Additive`](super::strategy::UnderBackground::Additive)).
    pub drawn_first: u32,
    /// One of them (the skydome's fine stars) covered the frame and was drawn as the background
    /// itself, its run's colour plus its term: no separate composite of the background.
    pub background_fused: bool,
    /// The first two runs were joined by seeding the second's buffer with the first
    /// ([`Seeded`](super::strategy::RunJoining::Seeded)): no combining pass.
    pub seeded: bool,
    /// The seeded buffer's first layer was drawn over the lower run itself ([`SeededFolded`](super::strategy::RunJoining::SeededFolded)).
    pub seed_folded: bool,
    /// Pairs of reduced layers drawn at once ([`AtOnce`](super::strategy::LayerPairs::AtOnce)).
    pub layers_paired: u32,
    /// Triangles of texel polygons drawn in place of a sparse stage's sample
    /// ([`TexelPolygons`](super::strategy::SparseStages::TexelPolygons)).
    pub texel_triangles: u32,
    /// Scissor rectangles in which the background without its sparse stage went as one triangle
    /// over the frame ([`TexelPolygonsOnBands`](super::strategy::SparseStages::TexelPolygonsOnBands)).
    pub background_rects: u32,
    /// Draws added to a run of reduced layers only because the run was there
    /// ([`DrawItem::joins_only`]: the lightning flash, [`InRun`](super::strategy::FlashPlacement::InRun)).
    pub joined_runs_only: u32,
    /// Clears of the frame left out ([`Skips::covered_clears`]): the colour's, the depth's.
    pub clears_skipped: u32,
    /// The star field was not drawn: transparent this frame.
    pub stars_skipped: bool,
    /// The `lut` tables were not rebuilt: nothing they depend on moved.
    pub tables_skipped: bool,
    /// The sky-view map was not recomputed: nothing it depends on moved.
    pub map_skipped: bool,
    /// Particles alive (every emitter).
    pub particles: u32,
}

/// What the last sky upload did with the textures of the sky before it.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct UploadStats {
    /// Textures uploaded (new files, or files whose content changed).
    pub textures_uploaded: u32,
    /// Textures taken over from the previous sky unchanged.
    pub textures_reused: u32,
}

/// Where a frame is drawn.
pub struct RenderTarget<'a> {
    /// Colour view, in the renderer's colour format.
    pub color: &'a wgpu::TextureView,
    /// Depth view ([`super::DEPTH_FORMAT`]), written by the renderer alone: it does not clear a
    /// depth view again while it has drawn no main scene into it ([`Skips::covered_clears`]).
    pub depth: &'a wgpu::TextureView,
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

/// Records frames of a sky.
pub struct SkyRenderer {
    globals: GlobalsBinding,
    library: ShaderLibrary,
    color_format: wgpu::TextureFormat,
    textures: TextureCache,
    shared: SharedResources,
    passes: Vec<Box<dyn Pass>>,
    has_sky: bool,
    hdr: Option<HdrTarget>,
    timer: Option<GpuTimer>,
    /// A depth view that still holds the clear value (1) everywhere: cleared by this renderer,
    /// and no scene drawn into it since ([`Skips::covered_clears`]).
    depth_untouched: Option<wgpu::TextureView>,
    /// Counters of the last recorded frame.
    pub stats: FrameStats,
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
    pub fn with_passes(ctx: &GpuContext, color_format: wgpu::TextureFormat, library: ShaderLibrary, extra: &[(&str, super::pass::PassConstructor)]) -> RenderResult<Self> {
        let device = &ctx.device;
        let globals = GlobalsBinding::new(device);
        let shared = SharedResources::new(device);
        let build =
            PassBuild { device, globals_layout: &globals.layout, globals_buffer: &globals.buffer, library: &library, color_format, shared: &shared, target: Target::Display };
        let passes = PASSES.iter().chain(extra).map(|(_, new)| new(&build)).collect::<RenderResult<Vec<_>>>()?;
        Ok(Self {
            textures: TextureCache::new(device, &ctx.queue),
            shared,
            globals,
            library,
            color_format,
            passes,
            has_sky: false,
            hdr: None,
            timer: ctx.timestamps.then(|| GpuTimer::new(device, &ctx.queue)),
            depth_untouched: None,
            stats: FrameStats::default(),
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
            globals_buffer: &self.globals.buffer,
            library: &self.library,
            color_format: self.color_format,
            shared: &self.shared,
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

    /// The pass of type `P`, if the renderer has one.
    pub fn pass<P: Pass>(&self) -> Option<&P> {
        self.passes.iter().find_map(|p| (p.as_ref() as &dyn std::any::Any).downcast_ref::<P>())
    }

    /// The pass of type `P`, mutable.
    pub fn pass_mut<P: Pass>(&mut self) -> Option<&mut P> {
        self.passes.iter_mut().find_map(|p| (p.as_mut() as &mut dyn std::any::Any).downcast_mut::<P>())
    }

    /// Glare visibility and intensity, if the sky has glare.
    pub fn glare_state(&self) -> Option<&super::glare::GlareState> {
        self.pass::<super::glare::GlarePass>()?.resources().map(|g| &g.state)
    }

    /// Phase of the glare's occlusion queries, if the sky has glare.
    pub fn glare_query_phase(&self) -> Option<super::glare::QueryPhase> {
        self.pass::<super::glare::GlarePass>()?.resources().map(|g| g.query_phase().clone())
    }

    /// Mutable glare state (freeze toggle).
    pub fn glare_state_mut(&mut self) -> Option<&mut super::glare::GlareState> {
        self.pass_mut::<super::glare::GlarePass>()?.resources_mut().map(|g| &mut g.state)
    }

    /// Time step for the frames of a still until it settles, if a pass needs history to show
    /// its steady state.
    pub fn settle_dt_s(&self, options: &RenderOptions) -> Option<f32> {
        self.passes.iter().filter_map(|p| p.settle_dt_s(options)).reduce(f32::max)
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
        let (wf, hf) = (w as f32, h as f32);
        let kind = if self.has_sky && frame.sky_model.kind.is_physical() { Target::Hdr } else { Target::Display };
        let globals = Globals::new(frame, camera, w, h, kind);
        ctx.queue.write_buffer(&self.globals.buffer, 0, bytemuck::bytes_of(&globals));
        if !self.has_sky {
            return;
        }
        if kind == Target::Hdr {
            self.ensure_hdr(&ctx.device, target.size);
        }
        let hdr = self.hdr.as_ref().filter(|_| kind == Target::Hdr).map(|t| (&t.view, t.generation));
        let cx = FrameContext { device: &ctx.device, queue: &ctx.queue, frame, camera, options, size: target.size, target: kind, hdr };
        for pass in &mut self.passes {
            pass.prepare(&cx);
        }
        let mut stats = FrameStats::default();
        for pass in &self.passes {
            pass.stats(&mut stats);
        }
        // Items per phase: (pass index, item), ordered.
        let mut items: [Vec<(usize, DrawItem)>; Phase::ALL.len()] = Default::default();
        let mut scratch = Vec::new();
        for (i, pass) in self.passes.iter().enumerate() {
            scratch.clear();
            pass.items(&cx, &mut scratch);
            items[pass.phase().index()].extend(scratch.iter().map(|it| (i, *it)));
            scratch.clear();
            pass.compute_items(&cx, &mut scratch);
            items[Phase::Compute.index()].extend(scratch.iter().map(|it| (i, *it)));
        }
        // Sky objects and stars interleave by priority; list order among equals.
        let sky_items = &mut items[Phase::Sky.index()];
        sky_items.sort_by_key(|(_, it)| it.priority);
        // Runs of consecutive dome layers drawn at reduced resolution, each into its own buffer
        // before the scene; the sky pass composites each in its run's place.
        let reduce = options.strategy.dome_resolution.divisors().0 > Divisor::FULL;
        if reduce {
            join_additive_runs(sky_items);
            leave_lone_joiners(sky_items);
        }
        let runs = if reduce { reduced_runs(sky_items, options.strategy.seeds_joined()) } else { Vec::new() };
        // A run's buffer is as fine as its finest layer needs.
        let divisors: Vec<Divisor> = runs.iter().map(|&(start, end)| sky_items[start..end].iter().map(|(_, it)| it.divisor).min().unwrap_or(Divisor::FULL)).collect();
        stats.reduced_runs.clone_from(&divisors);
        stats.joined_runs_only = sky_items.iter().filter(|(_, it)| it.reduced && it.joins_only).count() as u32;
        let reduced_pass = self.passes.iter().position(|p| (p.as_ref() as &dyn std::any::Any).is::<ReducedLayersPass>()).filter(|_| !runs.is_empty());
        // The first run, when the sky phase draws nothing before it, is the frame's background:
        // drawn first in the scene's pass, over the clear colour.
        let background = reduced_pass.is_some() && runs.first().is_some_and(|&(start, _)| start == 0);
        // And the second joins it when every draw between them (billboards) can be drawn after
        // it, corrected by it: one full-screen pass for both.
        // So do the runs after it, for as long as every draw between two can (a lightning bolt
        // between the clouds and the fog): `chain` runs, each combined with those above it.
        let mut chain = usize::from(background);
        while background
            && options.strategy.joins_runs()
            && chain < runs.len()
            && sky_items[runs[chain - 1].1..runs[chain].0].iter().all(|(i, it)| self.passes[*i].can_draw_under_run(it.key, kind))
        {
            chain += 1;
        }
        let joined = chain >= 2;
        stats.composites = (runs.len() + 1).saturating_sub(chain.max(1)) as u32;
        // Two joined runs, the second at least as fine: the second's buffer is seeded with the
        // first and ends as their combination. Otherwise joined runs are combined from the top
        // down, each combination at the finer resolution of its run and the combination above it.
        let seeded = options.strategy.seeds_joined() && chain == 2 && divisors[1] <= divisors[0];
        stats.seeded = seeded;
        let combined = if seeded { Vec::new() } else { combined_divisors(&divisors[..chain]) };
        // The additive draws right after the background go under it, first onto the cleared
        // frame: items `first` of the sky phase. Not where the scene covers part of the frame:
        // they would pay for its pixels, which the depth test spares them in the sky phase.
        let scene_in_view = options.scene && camera.elevation_range_deg(wf / hf.max(1.0)).0 < -SCENE_COVERS_BELOW_DEG;
        let first = match runs.first() {
            Some(&(_, start)) if background && options.strategy.additive_first() && !scene_in_view => {
                let limit = runs.get(1).map_or(sky_items.len(), |r| r.0);
                let end = (start..limit).find(|&k| !(sky_items[k].1.additive && self.passes[sky_items[k].0].can_draw_first(sky_items[k].1.key, kind))).unwrap_or(limit);
                // Blending the background costs a full-screen pass about a millisecond: worth it
                // only when a draw spanning the frame (the skydome's fine stars) is among them.
                if sky_items[start..end].iter().any(|(i, it)| self.passes[*i].spans_frame(it.key)) {
                    start..end
                } else {
                    0..0
                }
            }
            _ => 0..0,
        };
        stats.drawn_first = first.len() as u32;
        // One of them that covers the frame can be the background itself (its run's colour plus
        // its term, written): the others are then added under the runs above the first (joined)
        // or onto it. Saves the background's full-screen composite and the first draw's blend.
        let fused =
            first.clone().filter(|_| options.strategy.fuses_background()).find(|&k| self.passes[sky_items[k].0].can_draw_as_background(sky_items[k].1.key, kind, joined)).filter(
                |&f| {
                    first.clone().filter(|&k| k != f).all(|k| {
                        let (i, it) = &sky_items[k];
                        if joined {
                            self.passes[*i].can_draw_under_run(it.key, kind)
                        } else {
                            self.passes[*i].can_draw_first(it.key, kind)
                        }
                    })
                },
            );
        stats.background_fused = fused.is_some();
        if let (false, Some(layers)) = (runs.is_empty(), self.pass_mut::<ReducedLayersPass>()) {
            let joining = if seeded { Joining::Seeded } else { Joining::Combined(&combined) };
            layers.ensure(&ctx.device, &ctx.queue, (w, h), kind, &divisors, joining);
        }
        // The background writes every pixel of the frame before anything reads it: the fused draw
        // (and the composite below its dome) where it has its run to read (as drawn below), or the
        // composite's full-screen triangle, unless additive draws went onto the cleared frame
        // before it.
        let fused_drawn = fused.is_some() && self.pass::<ReducedLayersPass>().and_then(|l| l.upper_bind_group(0)).is_some();
        let color_covered = options.skips.covered_clears && background && (fused_drawn || first.is_empty());
        let depth_clean = options.skips.covered_clears && self.depth_untouched.as_ref() == Some(target.depth);
        stats.clears_skipped = u32::from(color_covered) + u32::from(depth_clean);

        if let Some(t) = self.timer.as_mut() {
            t.begin_frame();
        }
        let split = options.depth_split;
        for phase in Phase::ALL {
            let list = &items[phase.index()];
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
                Phase::Display => {
                    let writes = self.timer.as_mut().and_then(|t| t.render_writes(phase));
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
                    for (i, it) in list {
                        stats.draw_calls += self.passes[*i].draw(&mut rpass, it.key, Target::Display);
                    }
                }
                _ => {
                    // Without the depth split the scene phase's draws move to the end of the sky
                    // phase, painted over an already shaded sky.
                    let draws_here = phase != Phase::Scene || split;
                    let load = if phase == Phase::Scene {
                        let color = if color_covered {
                            // SAFETY: the background, the pass's first draw, writes every pixel
                            // of the frame (`color_covered`), unblended, before any read or store.
                            wgpu::LoadOp::DontCare(unsafe { wgpu::LoadOpDontCare::enabled() })
                        } else {
                            wgpu::LoadOp::Clear(wgpu::Color::BLACK)
                        };
                        (color, if depth_clean { wgpu::LoadOp::Load } else { wgpu::LoadOp::Clear(1.0) })
                    } else {
                        (wgpu::LoadOp::Load, wgpu::LoadOp::Load)
                    };
                    if let (Phase::Scene, Some(rp)) = (phase, reduced_pass) {
                        // The reduced buffers first: the first may be the background.
                        let sky_list = &items[Phase::Sky.index()];
                        let layers = (self.passes[rp].as_ref() as &dyn std::any::Any).downcast_ref::<ReducedLayersPass>();
                        for (r, &(start, end)) in runs.iter().enumerate() {
                            let run_writes = self.timer.as_mut().and_then(|t| t.reduced_writes(r == 0, r + 1 == runs.len() && (!joined || seeded)));
                            let Some(mut rpass) = layers.and_then(|l| l.begin(encoder, r, run_writes)) else { continue };
                            let mut first = start;
                            if let (1, true, Some(l)) = (r, seeded, layers) {
                                let (i, it) = &sky_list[start];
                                match l.seed_source().filter(|_| options.strategy.folds_seed() && self.passes[*i].can_draw_over_seed(it.key, kind)) {
                                    // The first layer goes over the seed itself; the seeding pass
                                    // fills what it does not reach (below its dome), first.
                                    Some(seed) => {
                                        if let Some(gap) = self.passes[*i].background_gap(it.key) {
                                            stats.draw_calls += l.seed_within(&mut rpass, &self.globals.bind_group, kind, gap);
                                        }
                                        rpass.set_bind_group(0, &self.globals.bind_group, &[]);
                                        // With the layer after it, at once, where the two pair.
                                        match pair_at(&self.passes, sky_list, start, end, kind, true).filter(|_| options.strategy.pairs_layers()) {
                                            Some(upper) => {
                                                stats.draw_calls += self.passes[*i].draw_pair(&mut rpass, it.key, upper, kind, Some(seed));
                                                stats.layers_paired += 1;
                                                first += 2;
                                            }
                                            None => {
                                                stats.draw_calls += self.passes[*i].draw_over_seed(&mut rpass, it.key, kind, seed);
                                                first += 1;
                                            }
                                        }
                                        stats.seed_folded = true;
                                    }
                                    None => stats.draw_calls += l.seed(&mut rpass, &self.globals.bind_group, kind),
                                }
                            }
                            rpass.set_bind_group(0, &self.globals.bind_group, &[]);
                            let mut k = first;
                            while k < end {
                                let (i, it) = &sky_list[k];
                                if let Some(upper) = pair_at(&self.passes, sky_list, k, end, kind, false).filter(|_| options.strategy.pairs_layers()) {
                                    stats.draw_calls += self.passes[*i].draw_pair(&mut rpass, it.key, upper, kind, None);
                                    stats.layers_paired += 1;
                                    k += 2;
                                } else {
                                    stats.draw_calls += self.passes[*i].draw_reduced(&mut rpass, it.key, kind);
                                    k += 1;
                                }
                            }
                        }
                        if let (true, false, Some(l)) = (joined, seeded, layers) {
                            let writes = self.timer.as_mut().and_then(|t| t.reduced_writes(false, true));
                            stats.draw_calls += l.record_combined(encoder, &self.globals.bind_group, kind, writes);
                        }
                    }
                    let queries = list.iter().find_map(|(i, _)| self.passes[*i].occlusion_query_set());
                    let label = format!("SkyRenderer::{}", phase.name());
                    let writes = self.timer.as_mut().and_then(|t| t.render_writes(phase));
                    let color = match &self.hdr {
                        Some(t) if kind == Target::Hdr => &t.view,
                        _ => target.color,
                    };
                    let mut rpass = begin_pass(encoder, &label, (color, target.depth), load, writes, queries);
                    rpass.set_bind_group(0, &self.globals.bind_group, &[]);
                    let range = match phase {
                        Phase::Sky | Phase::Overlay if split || phase == Phase::Overlay => SKY_DEPTH,
                        Phase::Scene | Phase::SceneAfterSky if split => SCENE_DEPTH,
                        _ => (0.0, 1.0),
                    };
                    rpass.set_viewport(0.0, 0.0, wf, hf, range.0, range.1);
                    if let (Phase::Scene, true, Some(layers)) = (phase, background, self.pass::<ReducedLayersPass>()) {
                        let sky_list = &items[Phase::Sky.index()];
                        match (fused, layers.upper_bind_group(0)) {
                            // The background's buffer: the joined runs' combination, or the first run's.
                            (Some(f), Some(run)) => {
                                let (i, it) = &sky_list[f];
                                // Where it does not reach (below a dome), the background's
                                // composite, onto the cleared frame and confined to those pixels.
                                if let Some([x, y, gw, gh]) = self.passes[*i].background_gap(it.key) {
                                    rpass.set_scissor_rect(x, y, gw, gh);
                                    stats.draw_calls += layers.draw_background(&mut rpass, kind, joined, false);
                                    rpass.set_scissor_rect(0, 0, w, h);
                                }
                                stats.draw_calls += self.passes[*i].draw_as_background(&mut rpass, it.key, kind, joined, run);
                                for (i, it) in first.clone().filter(|&k| k != f).map(|k| &sky_list[k]) {
                                    stats.draw_calls +=
                                        if joined { self.passes[*i].draw_under_run(&mut rpass, it.key, kind, run) } else { self.passes[*i].draw_first(&mut rpass, it.key, kind) };
                                }
                            }
                            _ => {
                                for (i, it) in &sky_list[first.clone()] {
                                    stats.draw_calls += self.passes[*i].draw_first(&mut rpass, it.key, kind);
                                }
                                let over = !first.is_empty();
                                stats.draw_calls += layers.draw_background(&mut rpass, kind, joined, over);
                            }
                        }
                    }
                    let layers = self.pass::<ReducedLayersPass>();
                    if draws_here {
                        let mut k = 0;
                        while k < list.len() {
                            // Already under the background.
                            if phase == Phase::Sky && k == first.start && !first.is_empty() {
                                k = first.end;
                                continue;
                            }
                            if let (Phase::Sky, Some(r), Some(rp)) = (phase, runs.iter().position(|&(start, _)| start == k), reduced_pass) {
                                // The background's runs are already in the frame.
                                if r >= chain {
                                    stats.draw_calls += self.passes[rp].draw(&mut rpass, r, kind);
                                }
                                k = runs[r].1;
                                continue;
                            }
                            // Between two joined runs: under the combination of those above.
                            let under = (1..chain).find(|&j| k >= runs[j - 1].1 && k < runs[j].0);
                            if let (Phase::Sky, Some(run)) = (phase, under.and_then(|j| layers.and_then(|l| l.upper_bind_group(j)))) {
                                let (i, it) = &list[k];
                                stats.draw_calls += self.passes[*i].draw_under_run(&mut rpass, it.key, kind, run);
                                k += 1;
                                continue;
                            }
                            let (i, it) = &list[k];
                            stats.draw_calls += self.passes[*i].draw(&mut rpass, it.key, kind);
                            k += 1;
                        }
                    }
                    if phase == Phase::Sky && !split {
                        rpass.set_viewport(0.0, 0.0, wf, hf, 0.0, 1.0);
                        for (i, it) in &items[Phase::Scene.index()] {
                            stats.draw_calls += self.passes[*i].draw(&mut rpass, it.key, kind);
                        }
                    }
                }
            }
            for pass in self.passes.iter().filter(|p| p.phase() == phase) {
                pass.after_phase(encoder);
            }
        }
        for pass in &self.passes {
            pass.resolve(encoder);
        }
        if let Some(t) = &self.timer {
            t.resolve(encoder);
        }
        // Only the main scene writes depth: without it the view still holds the clear value.
        self.depth_untouched = items[Phase::Scene.index()].is_empty().then(|| target.depth.clone());
        for pass in &self.passes {
            pass.stats_recorded(&mut stats);
        }
        self.stats = stats;
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
            format: super::HDR_FORMAT,
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

/// The key of the item after item `k` of a run ending at `end` when the two can be drawn at once
/// by their pass ([`Pass::draw_pair`]; `over_seed`: item `k` as a seeded buffer's first layer).
fn pair_at(passes: &[Box<dyn Pass>], items: &[(usize, DrawItem)], k: usize, end: usize, target: Target, over_seed: bool) -> Option<usize> {
    let ((i, lower), (j, upper)) = (items.get(k)?, items.get(k + 1).filter(|_| k + 1 < end)?);
    (i == j && passes[*i].can_draw_pair(lower.key, upper.key, target, over_seed)).then_some(upper.key)
}

/// Moves every full-resolution additive draw of the sky phase past the reduced additive layers
/// that follow it. Additive draws commute (target + a + b, clamped, in either
/// order), so the picture is the same; reduced layers that only such draws kept apart (the
/// skydome's fine stars between it and the galaxy) then share a run and one composite.
fn join_additive_runs(list: &mut [(usize, DrawItem)]) {
    let mut moved = true;
    while moved {
        moved = false;
        for k in 0..list.len().saturating_sub(1) {
            let (a, b) = (list[k].1, list[k + 1].1);
            if !a.reduced && a.additive && b.reduced && b.additive {
                list.swap(k, k + 1);
                moved = true;
            }
        }
    }
}

/// Items that go to a reduced buffer only in company ([`DrawItem::joins_only`]) and found none
/// (a run of nothing else) are drawn at full resolution.
fn leave_lone_joiners(list: &mut [(usize, DrawItem)]) {
    for (start, end) in reduced_runs(list, false) {
        if list[start..end].iter().all(|(_, it)| it.joins_only) {
            for (_, it) in &mut list[start..end] {
                it.reduced = false;
                it.divisor = Divisor::FULL;
            }
        }
    }
}

/// Divisors of the combinations of a chain of joined runs (their buffers' `divisors`, lowest
/// first): combination j holds runs j.. and is as fine as the finest of them. The last run
/// needs none (its own buffer); fewer than two runs, none at all.
fn combined_divisors(divisors: &[Divisor]) -> Vec<Divisor> {
    let n = divisors.len();
    (0..n.saturating_sub(1)).map(|j| divisors[j..].iter().copied().min().unwrap_or(Divisor::FULL)).collect()
}

/// The runs of consecutive items marked `reduced` in a sorted phase list: (start, end) indices.
/// `split_first`: a lone run at the start of the list whose layers get finer part-way (the
/// skydome's at a quarter of the resolution, the clouds' at half, when the billboards between
/// them lie out of the frame) is two runs, the coarse layers in their own buffer seeding the
/// finer one ([`Seeded`](super::strategy::RunJoining::Seeded)), rather than every layer at the finer resolution.
fn reduced_runs(list: &[(usize, DrawItem)], split_first: bool) -> Vec<(usize, usize)> {
    let mut runs = Vec::new();
    let mut k = 0;
    while k < list.len() {
        if list[k].1.reduced {
            let start = k;
            while k < list.len() && list[k].1.reduced {
                k += 1;
            }
            runs.push((start, k));
        } else {
            k += 1;
        }
    }
    if let (true, [(0, end)]) = (split_first, runs.as_slice()) {
        let divisor = |k: usize| list[k].1.divisor;
        if let Some(k) = (1..*end).find(|&k| (0..k).all(|j| divisor(k) < divisor(j))) {
            return vec![(0, k), (k, *end)];
        }
    }
    runs
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

#[cfg(test)]
mod tests {
    use super::*;

    fn item(key: usize, reduced: bool, additive: bool) -> (usize, DrawItem) {
        (0, DrawItem { reduced, additive, divisor: if reduced { Divisor::HALF } else { Divisor::FULL }, ..DrawItem::new(0, key) })
    }

    #[test]
    fn additive_draws_move_past_reduced_additive_layers_only() {
        // Skydome (reduced, opaque), its fine stars (full, additive), galaxy (reduced, additive),
        // sun (full, additive), clouds (reduced, alpha), fog (reduced, alpha).
        let list = [item(0, true, false), item(1, false, true), item(2, true, true), item(3, false, true), item(4, true, false), item(5, true, false)];
        let mut joined = list;
        join_additive_runs(&mut joined);
        let keys: Vec<usize> = joined.iter().map(|(_, it)| it.key).collect();
        // The stars go past the galaxy; the sun stays before the alpha-blended clouds.
        assert_eq!(keys, [0, 2, 1, 3, 4, 5]);
        assert_eq!(reduced_runs(&list, true), [(0, 1), (2, 3), (4, 6)]);
        assert_eq!(reduced_runs(&joined, true), [(0, 2), (4, 6)]);
        // Nothing to join: unchanged.
        let plain = [item(0, true, false), item(1, false, false), item(2, true, true)];
        let mut unchanged = plain;
        join_additive_runs(&mut unchanged);
        assert_eq!(unchanged, plain);
    }

    #[test]
    fn items_that_only_join_runs_stay_at_full_resolution_alone() {
        let joiner = |key: usize| (0, DrawItem { reduced: true, additive: true, divisor: Divisor::QUARTER, joins_only: true, ..DrawItem::new(0, key) });
        // The flash after the fog's run joins it, the bolts before it moving past it; after an
        // alpha-blended billboard, or first, it is alone.
        let mut after_bolts = [item(0, true, false), item(1, false, true), joiner(2)];
        join_additive_runs(&mut after_bolts);
        leave_lone_joiners(&mut after_bolts);
        assert_eq!(reduced_runs(&after_bolts, true), [(0, 2)]);
        assert_eq!(after_bolts[1].1.divisor, Divisor::QUARTER);
        let mut after_moon = [item(0, true, false), item(1, false, false), joiner(2)];
        join_additive_runs(&mut after_moon);
        leave_lone_joiners(&mut after_moon);
        assert_eq!(reduced_runs(&after_moon, true), [(0, 1)]);
        let mut alone = [joiner(0), item(1, false, false), joiner(2), joiner(3)];
        leave_lone_joiners(&mut alone);
        assert!(alone.iter().all(|(_, it)| !it.reduced && it.divisor == Divisor::FULL), "{alone:?}");
    }

    #[test]
    fn a_lone_first_run_that_gets_finer_is_split_where_it_does() {
        let at = |key: usize, divisor: u8| (0, DrawItem { reduced: true, divisor: Divisor::whole(divisor), ..DrawItem::new(0, key) });
        // Skydome and galaxy at a quarter, clouds at half, fog at a quarter: the billboards
        // between the skydome and the clouds out of the frame.
        let lone = [at(0, 4), at(1, 4), at(2, 2), at(3, 4)];
        assert_eq!(reduced_runs(&lone, true), [(0, 2), (2, 4)]);
        assert_eq!(reduced_runs(&lone, false), [(0, 4)]);
        // Finer first, or all alike: one run.
        assert_eq!(reduced_runs(&[at(0, 2), at(1, 4)], true), [(0, 2)]);
        assert_eq!(reduced_runs(&[at(0, 4), at(1, 4)], true), [(0, 2)]);
        // Not at the start of the list, or not alone: as they are.
        let after = [item(0, false, false), at(1, 4), at(2, 2)];
        assert_eq!(reduced_runs(&after, true), [(1, 3)]);
        let two = [at(0, 4), at(1, 2), item(2, false, false), at(3, 2)];
        assert_eq!(reduced_runs(&two, true), [(0, 2), (3, 4)]);
    }

    #[test]
    fn each_combination_is_as_fine_as_its_finest_run() {
        // Skydome at a quarter, clouds at half, fog at a quarter: combination 0 holds all three,
        // combination 1 the clouds and the fog; the fog's own buffer stands for itself.
        let [half, quarter] = [Divisor::HALF, Divisor::QUARTER];
        assert_eq!(combined_divisors(&[quarter, half, quarter]), [half, half]);
        assert_eq!(combined_divisors(&[quarter, quarter, half]), [half, half]);
        assert_eq!(combined_divisors(&[half, quarter]), [half]);
        assert_eq!(combined_divisors(&[Divisor::whole(3), Divisor::whole(3), Divisor::at_most(2.6, half, quarter)]), [Divisor::at_most(2.5, half, quarter); 2]);
        assert_eq!(combined_divisors(&[quarter]), Vec::<Divisor>::new());
        assert_eq!(combined_divisors(&[]), Vec::<Divisor>::new());
    }
}
