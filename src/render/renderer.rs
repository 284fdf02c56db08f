//! The sky renderer: owns the passes and the current sky's GPU resources, and records a frame.
//! It knows nothing of egui or winit; the app and the CLI drive it.

use super::camera::Camera;
use super::glare::{GlareFrame, GlarePass, GlareResources, GlareState};
use super::globals::{Globals, GlobalsBinding};
use super::scene::{Occluder, ScenePass};
use super::shaders::ShaderLibrary;
use super::sky_objects::{SkyObjectDraws, SkyObjectsPass};
use super::stars::{StarField, StarsPass};
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
    pub occluder: Option<Occluder>,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self { scene: true, depth_split: true, glare: true, occluder: None }
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
}

struct SkyGpu {
    draws: SkyObjectDraws,
    stars: Option<(StarField, u8)>,
    glare: Option<GlareResources>,
}

/// Records frames of a sky.
pub struct SkyRenderer {
    globals: GlobalsBinding,
    library: ShaderLibrary,
    textures: TextureCache,
    sky_objects: SkyObjectsPass,
    stars: StarsPass,
    scene: ScenePass,
    glare: GlarePass,
    current: Option<SkyGpu>,
    frame_number: u64,
    timer: Option<GpuTimer>,
    /// Counters of the last recorded frame.
    pub stats: FrameStats,
}

impl SkyRenderer {
    /// Builds every pass for a colour format. Errors are shader or pipeline errors.
    pub fn new(ctx: &GpuContext, color_format: wgpu::TextureFormat, library: ShaderLibrary) -> Result<Self, String> {
        let device = &ctx.device;
        let globals = GlobalsBinding::new(device);
        Ok(Self {
            sky_objects: SkyObjectsPass::new(device, &globals.layout, &library, color_format)?,
            stars: StarsPass::new(device, &globals.layout, &library, color_format)?,
            scene: ScenePass::new(device, &globals.layout, &library, color_format)?,
            glare: GlarePass::new(device, &globals.layout, &library, color_format)?,
            textures: TextureCache::new(device, &ctx.queue),
            globals,
            library,
            current: None,
            frame_number: 0,
            timer: ctx.timestamps.then(|| GpuTimer::new(device, &ctx.queue)),
            stats: FrameStats::default(),
        })
    }

    /// Uploads a sky, replacing the previous one only if the upload succeeds.
    pub fn set_sky(&mut self, ctx: &GpuContext, sky: &Sky) -> Result<(), String> {
        let (device, queue) = (&ctx.device, &ctx.queue);
        let mut textures = TextureCache::new(device, queue);
        let gpu = super::shaders::validated(device, "uploading the sky", || SkyGpu {
            draws: SkyObjectDraws::new(device, queue, &self.sky_objects, &mut textures, sky),
            stars: sky.stars.as_ref().map(|s| (StarField::new(device, &self.stars, s), s.priority)),
            glare: sky.glare.as_ref().map(|g| GlareResources::new(device, queue, &self.glare, &mut textures, g)),
        })?;
        self.textures = textures;
        self.current = Some(gpu);
        Ok(())
    }

    /// Rebuilds every pipeline from the shader library (hot reload). All or nothing: on any error
    /// every pass keeps its previous pipelines and the error is returned.
    pub fn reload_shaders(&mut self, ctx: &GpuContext) -> Result<(), String> {
        let (d, lib) = (&ctx.device, &self.library);
        let sky_objects = self.sky_objects.rebuilt(d, lib)?;
        let stars = self.stars.rebuilt(d, lib)?;
        let scene = self.scene.rebuilt(d, lib)?;
        let glare = self.glare.rebuilt(d, lib)?;
        self.sky_objects.install(sky_objects);
        self.stars.install(stars);
        self.scene.install(scene);
        self.glare.install(glare);
        Ok(())
    }

    /// Replaces the shader library (e.g. switch between embedded and on-disk sources).
    pub fn set_library(&mut self, library: ShaderLibrary) {
        self.library = library;
    }

    /// The shader library in use.
    pub fn library(&self) -> &ShaderLibrary {
        &self.library
    }

    /// Glare visibility and intensity, if the sky has glare.
    pub fn glare_state(&self) -> Option<&GlareState> {
        self.current.as_ref()?.glare.as_ref().map(|g| &g.state)
    }

    /// Phase of the glare's occlusion queries, if the sky has glare.
    pub fn glare_query_phase(&self) -> Option<super::glare::QueryPhase> {
        self.current.as_ref()?.glare.as_ref().map(|g| g.query_phase().clone())
    }

    /// Mutable glare state (freeze toggle).
    pub fn glare_state_mut(&mut self) -> Option<&mut GlareState> {
        self.current.as_mut()?.glare.as_mut().map(|g| &mut g.state)
    }

    /// Records one frame into `encoder`. Call [`Self::after_submit`] once it is submitted.
    #[allow(clippy::too_many_arguments)]
    pub fn render(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        color: &wgpu::TextureView,
        depth: &wgpu::TextureView,
        size: (u32, u32),
        sky: &Sky,
        frame: &FrameSky,
        camera: &Camera,
        options: &RenderOptions,
        dt_s: f32,
        game_hours: f64,
    ) {
        self.frame_number += 1;
        let (w, h) = size;
        let aspect = w as f32 / h.max(1) as f32;
        let globals = Globals::new(frame, camera, w, h, sky.hours_per_day, game_hours);
        ctx.queue.write_buffer(&self.globals.buffer, 0, bytemuck::bytes_of(&globals));
        let Some(gpu) = self.current.as_mut() else { return };
        gpu.draws.prepare(&ctx.queue, frame, camera);
        let stars_visible = match (&gpu.stars, frame.stars) {
            (Some((field, _)), Some(c)) => field.prepare(&ctx.queue, c),
            _ => false,
        };
        if let Some(o) = &options.occluder {
            self.scene.prepare_occluder(&ctx.queue, o);
        }

        let mut stats = FrameStats {
            objects_drawn: frame.objects.iter().filter(|o| o.passes.is_ok()).count() as u32,
            objects_hidden: frame.objects.iter().filter(|o| o.passes.is_err()).count() as u32,
            stars: gpu.stars.as_ref().map_or(0, |(f, _)| f.count()),
            ..Default::default()
        };
        if let Some(t) = self.timer.as_mut() {
            t.begin_frame();
        }
        let (wf, hf) = (w as f32, h as f32);
        {
            // Scene pass: clears, and draws the main-scene stand-in first when the depth split is on.
            let mut rpass = begin_pass(encoder, "SkyRenderer::scene_pass", color, depth, (wgpu::LoadOp::Clear(wgpu::Color::BLACK), wgpu::LoadOp::Clear(1.0)), self.timer.as_mut().and_then(|t| t.writes(0)), None);
            rpass.set_bind_group(0, &self.globals.bind_group, &[]);
            if options.depth_split {
                rpass.set_viewport(0.0, 0.0, wf, hf, SCENE_DEPTH.0, SCENE_DEPTH.1);
                stats.draw_calls += self.scene.draw(&mut rpass, options.scene, options.occluder.is_some());
            }
        }
        {
            // Sky pass: objects by priority with the stars in between. With the split, sky fragments
            // behind the scene fail the depth test; without it the sky covers the screen first.
            let mut rpass = begin_pass(encoder, "SkyRenderer::sky_pass", color, depth, (wgpu::LoadOp::Load, wgpu::LoadOp::Load), self.timer.as_mut().and_then(|t| t.writes(1)), None);
            rpass.set_bind_group(0, &self.globals.bind_group, &[]);
            let range = if options.depth_split { SKY_DEPTH } else { (0.0, 1.0) };
            rpass.set_viewport(0.0, 0.0, wf, hf, range.0, range.1);
            let stars_priority = gpu.stars.as_ref().map_or(u8::MAX, |(_, p)| *p);
            let below = |o: &crate::sky::ObjectFrame| sky.objects[o.index].priority <= stars_priority;
            stats.draw_calls += gpu.draws.draw(&mut rpass, &self.sky_objects, frame, below);
            if stars_visible {
                if let Some((field, _)) = &gpu.stars {
                    field.draw(&mut rpass, &self.stars);
                    stats.draw_calls += 1;
                }
            }
            stats.draw_calls += gpu.draws.draw(&mut rpass, &self.sky_objects, frame, |o| !below(o));
            if !options.depth_split {
                // Without the split the scene is painted over an already fully shaded sky.
                rpass.set_viewport(0.0, 0.0, wf, hf, 0.0, 1.0);
                stats.draw_calls += self.scene.draw(&mut rpass, options.scene, options.occluder.is_some());
            }
        }

        if let (Some(glare), Some(color_now), true) = (gpu.glare.as_mut(), frame.glare, options.glare) {
            glare.prepare(&ctx.device, &ctx.queue, &GlareFrame { towards_sun: frame.towards_sun, color: color_now, dt_s, frame: self.frame_number }, camera, aspect);
            let mut rpass = begin_pass(encoder, "SkyRenderer::glare_pass", color, depth, (wgpu::LoadOp::Load, wgpu::LoadOp::Load), self.timer.as_mut().and_then(|t| t.writes(2)), Some(glare.query_set()));
            rpass.set_bind_group(0, &self.globals.bind_group, &[]);
            rpass.set_viewport(0.0, 0.0, wf, hf, SKY_DEPTH.0, SKY_DEPTH.1);
            stats.draw_calls += glare.draw(&mut rpass, &self.glare);
            drop(rpass);
            glare.resolve(encoder);
        } else if let Some(glare) = gpu.glare.as_mut() {
            glare.state.drawn_last_frame = false;
        }
        if let Some(t) = &self.timer {
            t.resolve(encoder);
        }
        self.stats = stats;
    }

    /// GPU time of each pass of a recent frame, ms (empty without timestamp queries).
    pub fn gpu_pass_ms(&self) -> &[(&'static str, f32)] {
        self.timer.as_ref().map_or(&[], |t| &t.last_ms)
    }

    /// Call after the encoder of [`Self::render`] was submitted: starts asynchronous readbacks.
    pub fn after_submit(&mut self) {
        if let Some(t) = self.timer.as_mut() {
            t.after_submit();
        }
        if let Some(g) = self.current.as_mut().and_then(|c| c.glare.as_mut()) {
            g.after_submit();
        }
    }
}

/// Begins one of the renderer's passes on the shared colour and depth targets.
fn begin_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    label: &str,
    color: &wgpu::TextureView,
    depth: &wgpu::TextureView,
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
