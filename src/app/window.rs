//! The window's GPU side: surface, renderer and egui's renderer. It presents a
//! frame of the sky with the panels on top, and keeps going through resizes and lost surfaces.

use std::sync::Arc;

use anyhow::Context as _;
use winit::event_loop::ActiveEventLoop;
use winit::window::Window;

use super::layout::SkyViewport;
use crate::render::{AdapterChoice, Camera, GpuContext, Headless, Offscreen, RenderOptions, RenderTarget, ShaderLibrary, SkyRenderer};
use crate::sky::{FrameSky, Sky};

/// What egui produced for one frame, ready to paint.
pub struct UiPaint {
    /// Tessellated shapes.
    pub jobs: Vec<egui::ClippedPrimitive>,
    /// Textures to free after painting.
    pub frees: Vec<egui::TextureId>,
    /// egui's pixels per point.
    pub pixels_per_point: f32,
    /// The part of the window the panels leave to the sky, points.
    pub sky_rect: egui::Rect,
}

/// The window and everything drawn into it.
pub struct WindowGpu {
    /// The window.
    pub window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    /// Surface size and format.
    pub surface_config: wgpu::SurfaceConfiguration,
    /// Device shared by the window and the capture renderer.
    pub ctx: GpuContext,
    /// The sky renderer of the window.
    pub renderer: SkyRenderer,
    /// egui's window state.
    pub egui_state: egui_winit::State,
    egui_renderer: egui_wgpu::Renderer,
    /// Offscreen renderer of screenshots and contact sheets, made on first use, and the sky
    /// generation it holds.
    capture: Option<(Headless, u64)>,
    /// Bitmap inspector texture and the bitmap it shows.
    pub inspector: Option<(usize, egui::TextureHandle)>,
    /// The fill-rate floor pass, its target, and its last measurement (ms, frame).
    floor: Option<FloorProbe>,
    /// Where the sky shows this frame, pixels (the part the panels leave).
    pub sky_view: SkyViewport,
    /// The sky's target while it covers part of the window: rendered there at the view's size,
    /// then copied into the surface.
    sky_target: Option<Offscreen>,
    /// The surface can be copied into; without it the sky is drawn over the whole window, under
    /// the panels.
    copies_to_surface: bool,
}

/// The fill-rate floor pass, its target at the window's size, and its last measurement (ms, frame).
type FloorProbe = (crate::render::passes::baseline::Baseline, crate::render::Offscreen, Option<(f32, u64)>);

impl WindowGpu {
    /// Opens the window and its device, builds the renderer (falling back to the embedded shaders
    /// if the ones on disk are broken: returned as the second value) and uploads `sky`.
    pub fn new(event_loop: &ActiveEventLoop, title: &str, size: [u32; 2], adapter: AdapterChoice, library: ShaderLibrary, sky: &Sky) -> anyhow::Result<(Self, Option<String>)> {
        let attrs = Window::default_attributes().with_title(title).with_inner_size(winit::dpi::LogicalSize::new(size[0].max(320), size[1].max(240)));
        let window = Arc::new(event_loop.create_window(attrs).context("creating the window")?);
        Self::with_window(window, adapter, library, sky)
    }

    /// Builds the device and everything on it for an existing window (start-up, and after the
    /// device was lost).
    pub fn with_window(window: Arc<Window>, adapter: AdapterChoice, library: ShaderLibrary, sky: &Sky) -> anyhow::Result<(Self, Option<String>)> {
        let instance = crate::render::gpu::context::new_instance();
        let surface = instance.create_surface(window.clone()).context("creating the window surface")?;
        let ctx = GpuContext::new(instance, adapter, Some(&surface))?;
        log::info!("adapter: {}", ctx.adapter_line());
        let inner = window.inner_size();
        let caps = surface.get_capabilities(&ctx.adapter);
        // Colours are display-encoded (as in the 2005 pipeline): prefer a non-sRGB surface.
        let format = caps.formats.iter().copied().find(|f| !f.is_srgb()).unwrap_or(caps.formats[0]);
        let copies_to_surface = caps.usages.contains(wgpu::TextureUsages::COPY_DST);
        if !copies_to_surface {
            log::warn!("the window's surface cannot be copied into: the sky is drawn over the whole window, under the panels");
        }
        let surface_config = wgpu::SurfaceConfiguration {
            usage: if copies_to_surface { wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_DST } else { wgpu::TextureUsages::RENDER_ATTACHMENT },
            format,
            width: inner.width.max(1),
            height: inner.height.max(1),
            present_mode: wgpu::PresentMode::AutoVsync,
            desired_maximum_frame_latency: 2,
            alpha_mode: caps.alpha_modes[0],
            view_formats: vec![],
            color_space: Default::default(),
        };
        surface.configure(&ctx.device, &surface_config);
        let (mut renderer, shader_error) = match SkyRenderer::new(&ctx, format, library) {
            Ok(r) => (r, None),
            // A broken shader on disk must not stop the tool: fall back to the embedded ones.
            Err(e) => (SkyRenderer::new(&ctx, format, ShaderLibrary::embedded())?, Some(format!("shaders on disk failed, using the embedded ones: {e}"))),
        };
        renderer.set_sky(&ctx, sky)?;
        let egui_ctx = egui::Context::default();
        let egui_state = egui_winit::State::new(
            egui_ctx,
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            Some(ctx.device.limits().max_texture_dimension_2d as usize),
        );
        let egui_renderer = egui_wgpu::Renderer::new(&ctx.device, format, egui_wgpu::RendererOptions::default());
        let sky_view = SkyViewport::full((surface_config.width, surface_config.height));
        let gpu = Self {
            window,
            surface,
            surface_config,
            ctx,
            renderer,
            egui_state,
            egui_renderer,
            capture: None,
            inspector: None,
            floor: None,
            sky_view,
            sky_target: None,
            copies_to_surface,
        };
        Ok((gpu, shader_error))
    }

    /// Follows a new window size (a zero size, minimised, keeps the old surface; sizes beyond
    /// the device's largest texture are clamped, the window's edge then stretches).
    pub fn resize(&mut self, width: u32, height: u32) {
        if width == 0 || height == 0 {
            return;
        }
        let max = self.ctx.device.limits().max_texture_dimension_2d;
        let (width, height) = (width.min(max), height.min(max));
        self.surface_config.width = width;
        self.surface_config.height = height;
        self.surface.configure(&self.ctx.device, &self.surface_config);
    }

    /// Surface size, pixels.
    pub fn size(&self) -> (u32, u32) {
        (self.surface_config.width, self.surface_config.height)
    }

    /// The sky view's size, pixels: what screenshots and the fill-rate floor are taken at.
    pub fn sky_size(&self) -> (u32, u32) {
        (self.sky_view.width, self.sky_view.height)
    }

    /// Rebuilds the window's pipelines; the capture renderer rebuilds from the same sources on
    /// next use.
    pub fn reload_shaders(&mut self) -> crate::render::RenderResult<()> {
        self.renderer.reload_shaders(&self.ctx)?;
        self.capture = None;
        Ok(())
    }

    /// Renders a still of `sky` offscreen at `size` through the headless path, sharing the device.
    pub fn capture(
        &mut self,
        sky: &Sky,
        generation: u64,
        input: &crate::sky::FrameInput,
        camera: &Camera,
        options: &RenderOptions,
        size: (u32, u32),
    ) -> anyhow::Result<image::RgbaImage> {
        if self.capture.is_none() {
            let h = Headless::with_library(self.ctx.clone(), self.renderer.library().clone(), size.0, size.1)?;
            self.capture = Some((h, u64::MAX));
        }
        let (h, held) = self.capture.as_mut().expect("just created");
        if *held != generation {
            h.set_sky(sky)?;
            *held = generation;
        }
        h.resize(size.0, size.1);
        Ok(h.render(sky, input, camera, options)?)
    }

    /// The fill-rate floor at the window's size (ms), measured again every 300 frames (a few ms
    /// of blocking on a software rasteriser, rarely).
    pub fn floor_ms(&mut self, frame: u64) -> Option<f32> {
        let (w, h) = self.sky_size();
        let stale = match &self.floor {
            Some((_, target, last)) => (target.width, target.height) != (w, h) || last.is_none_or(|(_, at)| frame >= at + 300),
            None => frame > 10,
        };
        if stale {
            if self.floor.as_ref().is_none_or(|(_, t, _)| (t.width, t.height) != (w, h)) {
                let baseline = crate::render::passes::baseline::Baseline::new(&self.ctx.device, &self.ctx.queue, self.renderer.library(), crate::render::OFFSCREEN_FORMAT).ok()?;
                self.floor = Some((baseline, crate::render::Offscreen::new(&self.ctx.device, w, h), None));
            }
            let (baseline, target, last) = self.floor.as_mut()?;
            let _ = self.ctx.wait_idle();
            let t = std::time::Instant::now();
            let mut encoder = self.ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("App::floor") });
            baseline.record(&mut encoder, &target.color_view);
            self.ctx.queue.submit([encoder.finish()]);
            let _ = self.ctx.wait_idle();
            *last = Some((t.elapsed().as_secs_f32() * 1000.0, frame));
        }
        self.floor.as_ref().and_then(|(_, _, last)| last.map(|(ms, _)| ms))
    }

    /// Uploads egui's texture changes; they do not need the surface, so none is ever lost.
    pub fn update_ui_textures(&mut self, mut deltas: egui::TexturesDelta) -> Vec<egui::TextureId> {
        for (id, list) in &deltas.set {
            for delta in list {
                self.egui_renderer.update_texture(&self.ctx.device, &self.ctx.queue, *id, delta);
            }
        }
        let frees = std::mem::take(&mut deltas.free);
        deltas.clear();
        frees.into_iter().collect()
    }

    /// Draws the sky and the panels into the surface and presents. Returns false when the
    /// surface had no texture this frame (minimised, outdated: reconfigured for the next one).
    pub fn present(&mut self, frame: &FrameSky, camera: &Camera, options: &RenderOptions, ui: &UiPaint) -> bool {
        let surface_texture = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t) | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
            other => {
                log::debug!("no surface texture this frame: {other:?}");
                if matches!(other, wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost) {
                    self.surface.configure(&self.ctx.device, &self.surface_config);
                }
                self.free_ui_textures(&ui.frees);
                return false;
            }
        };
        let view = surface_texture.texture.create_view(&Default::default());
        let size = self.size();
        let sky_view = if self.copies_to_surface { SkyViewport::from_points(ui.sky_rect, ui.pixels_per_point, size) } else { SkyViewport::full(size) };
        if sky_view != self.sky_view {
            log::info!("sky view: x {} y {} width {} height {} of a {}x{} window", sky_view.x, sky_view.y, sky_view.width, sky_view.height, size.0, size.1);
            self.sky_view = sky_view;
        }
        let mut encoder = self.ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("App::frame") });
        if sky_view.is_full(size) {
            self.sky_target = None;
            self.renderer.render(&self.ctx, &mut encoder, &RenderTarget { color: &view, size }, frame, camera, options);
        } else {
            // The sky at the view's own size (its aspect, its pixels), then into its place.
            let (w, h) = (sky_view.width, sky_view.height);
            if self.sky_target.as_ref().is_none_or(|t| (t.width, t.height) != (w, h)) {
                self.sky_target = Some(Offscreen::with_format(&self.ctx.device, w, h, self.surface_config.format, "App::sky_view"));
            }
            let target = self.sky_target.as_ref().expect("made above");
            self.renderer.render(&self.ctx, &mut encoder, &target.target(), frame, camera, options);
            encoder.copy_texture_to_texture(
                target.color.as_image_copy(),
                wgpu::TexelCopyTextureInfo {
                    texture: &surface_texture.texture,
                    mip_level: 0,
                    origin: wgpu::Origin3d { x: sky_view.x, y: sky_view.y, z: 0 },
                    aspect: wgpu::TextureAspect::All,
                },
                wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
            );
        }
        let screen = egui_wgpu::ScreenDescriptor { size_in_pixels: [size.0, size.1], pixels_per_point: ui.pixels_per_point };
        let extra = self.egui_renderer.update_buffers(&self.ctx.device, &self.ctx.queue, &mut encoder, &ui.jobs, &screen);
        {
            let rpass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("App::egui_pass"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            self.egui_renderer.render(&mut rpass.forget_lifetime(), &ui.jobs, &screen);
        }
        self.free_ui_textures(&ui.frees);
        self.ctx.queue.submit(extra.into_iter().chain([encoder.finish()]));
        self.renderer.after_submit();
        self.window.pre_present_notify();
        self.ctx.queue.present(surface_texture);
        true
    }

    fn free_ui_textures(&mut self, frees: &[egui::TextureId]) {
        for id in frees {
            self.egui_renderer.free_texture(id);
        }
    }
}
