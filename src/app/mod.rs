//! The desktop app: a winit window showing the live sky with egui panels. It wires the renderer
//! (which knows nothing of egui or winit), the hot-reloading sky and the UI.

pub mod capture;
pub mod settings;
pub mod ui;

use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{anyhow, Context as _};
use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::{Key, NamedKey};
use winit::window::{Window, WindowId};

use crate::live::{LiveSky, ReloadEvent, SkySpec};
use crate::render::headless::depth_view;
use crate::render::{AdapterChoice, GpuContext, Headless, RenderOptions, ShaderLibrary, SkyRenderer};
use crate::sky::{FrameInput, Tier};
use capture::{free_path, screenshot_name, Capture, ContactSheet};
use settings::Settings;
use ui::{Controls, UiAction, UiInfo};

/// How the window was asked to start.
#[derive(Debug, Clone, Default)]
pub struct AppConfig {
    /// Sky or continent file (None: the last one, else the built-in sky).
    pub sky: Option<PathBuf>,
    /// Season for continent files.
    pub season: Option<String>,
    /// Starting GPU tier.
    pub tier: Option<u8>,
    /// Exit after this many frames.
    pub frames: Option<u64>,
    /// Save a screenshot after a few frames, then exit.
    pub screenshot_and_exit: bool,
    /// Screenshot folder.
    pub shots: Option<PathBuf>,
    /// Software adapter.
    pub cpu: bool,
    /// Shader folder to hot-reload from.
    pub shader_dir: Option<PathBuf>,
}

/// Whether a display server is reachable (X11 or Wayland).
pub fn display_available() -> bool {
    std::env::var_os("DISPLAY").is_some_and(|d| !d.is_empty()) || std::env::var_os("WAYLAND_DISPLAY").is_some_and(|d| !d.is_empty())
}

/// Runs the window until it is closed. Without a display, says so, renders the sky headless to
/// `skytune-default.png` (or the sky's name) instead and points to `skytune render`.
pub fn run(config: AppConfig) -> anyhow::Result<()> {
    let mut settings = Settings::load();
    let spec = match &config.sky {
        Some(p) => SkySpec::from_path(p, config.season.as_deref()).map_err(|e| anyhow!("{e}"))?,
        None => match &settings.last_sky {
            Some(p) if p.is_file() => SkySpec::from_path(p, config.season.as_deref()).unwrap_or(SkySpec::Builtin),
            _ => SkySpec::Builtin,
        },
    };
    if !display_available() {
        return headless_fallback(&spec, &config);
    }
    let event_loop = match EventLoop::new() {
        Ok(l) => l,
        Err(e) => {
            eprintln!("skytune: cannot open a window ({e})");
            return headless_fallback(&spec, &config);
        }
    };
    let live = LiveSky::new(spec.clone()).map_err(|e| anyhow!("{e}"))?;
    if let SkySpec::File(p) | SkySpec::Continent { path: p, .. } = &spec {
        settings.opened(p.clone());
    }
    let mut controls = Controls::default();
    if let Some(t) = config.tier {
        controls.tier = Tier::new(t).ok_or_else(|| anyhow!("--tier: expected 4, 2 or 1, found {t}"))?;
    }
    if let SkySpec::Continent { season, .. } = spec {
        controls.season = season;
    }
    let mut app = App {
        config,
        settings,
        live,
        controls,
        gpu: None,
        error: None,
        frame_count: 0,
        last_frame: Instant::now(),
        frame_times: VecDeque::new(),
        cpu_ms: Vec::new(),
        shader_error: None,
        gpu_error: None,
        sheet: None,
        last_capture: String::new(),
        drag: None,
        shader_watch: None,
        shaders_changed: Arc::new(AtomicBool::new(false)),
    };
    event_loop.run_app(&mut app).context("running the window")?;
    app.settings.save();
    match app.error {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

fn headless_fallback(spec: &SkySpec, config: &AppConfig) -> anyhow::Result<()> {
    eprintln!("skytune: no display available (DISPLAY and WAYLAND_DISPLAY are unset), so no window can open.");
    eprintln!("skytune: rendering the sky headless instead; use `skytune render SKY --hour H --weather W --out shot.png` for other frames.");
    let sky = spec.load().map_err(|e| anyhow!("{e}"))?;
    let ctx = GpuContext::headless(if config.cpu { AdapterChoice::Cpu } else { AdapterChoice::from_env() })?;
    println!("adapter: {}", ctx.adapter_line());
    let mut h = Headless::new(ctx, 1280, 720)?;
    h.set_sky(&sky)?;
    let c = Controls::default();
    let input = FrameInput::new(c.hour, c.weather);
    let img = h.render(&sky, &input, &c.camera, &RenderOptions::default())?;
    let out = PathBuf::from(if matches!(spec, SkySpec::Builtin) { "skytune-default.png".to_string() } else { screenshot_name(&sky.name, c.hour, c.weather) });
    img.save(&out).with_context(|| format!("writing {}", out.display()))?;
    println!("wrote {} (sky \"{}\", hour {}, weather {})", out.display(), sky.name, c.hour, c.weather);
    Ok(())
}

struct Gpu {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    surface_config: wgpu::SurfaceConfiguration,
    ctx: GpuContext,
    renderer: SkyRenderer,
    depth: wgpu::TextureView,
    egui_state: egui_winit::State,
    egui_renderer: egui_wgpu::Renderer,
    capture: Option<Capture>,
    inspector: Option<(usize, egui::TextureHandle)>,
    sky_generation: u64,
}

struct App {
    config: AppConfig,
    settings: Settings,
    live: LiveSky,
    controls: Controls,
    gpu: Option<Gpu>,
    error: Option<anyhow::Error>,
    frame_count: u64,
    last_frame: Instant,
    frame_times: VecDeque<f32>,
    cpu_ms: Vec<(&'static str, f32)>,
    shader_error: Option<String>,
    gpu_error: Option<String>,
    sheet: Option<ContactSheet>,
    last_capture: String,
    drag: Option<(f64, f64)>,
    shader_watch: Option<notify_debouncer_full::Debouncer<notify_debouncer_full::notify::RecommendedWatcher, notify_debouncer_full::RecommendedCache>>,
    shaders_changed: Arc<AtomicBool>,
}

impl App {
    fn shader_library(&self) -> ShaderLibrary {
        match &self.config.shader_dir {
            Some(d) => ShaderLibrary { dir: Some(d.clone()) },
            // Development builds hot-reload the checkout's shaders; release builds use the embedded copies.
            None if cfg!(debug_assertions) => ShaderLibrary { dir: ShaderLibrary::source_dir() },
            None => ShaderLibrary::embedded(),
        }
    }

    fn init(&mut self, event_loop: &ActiveEventLoop) -> anyhow::Result<()> {
        let [w, h] = self.settings.window_size;
        let attrs = Window::default_attributes()
            .with_title(format!("skytune - {}", self.live.sky().name))
            .with_inner_size(winit::dpi::LogicalSize::new(w.max(320), h.max(240)));
        let window = Arc::new(event_loop.create_window(attrs).context("creating the window")?);
        let instance = crate::render::context::new_instance();
        let surface = instance.create_surface(window.clone()).context("creating the window surface")?;
        let choice = if self.config.cpu { AdapterChoice::Cpu } else { AdapterChoice::from_env() };
        let ctx = GpuContext::new(instance, choice, Some(&surface))?;
        log::info!("adapter: {}", ctx.adapter_line());
        let size = window.inner_size();
        let caps = surface.get_capabilities(&ctx.adapter);
        // Colours are display-encoded (as in the 2005 pipeline): prefer a non-sRGB surface.
        let format = caps.formats.iter().copied().find(|f| !f.is_srgb()).unwrap_or(caps.formats[0]);
        let surface_config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            format,
            width: size.width.max(1),
            height: size.height.max(1),
            present_mode: wgpu::PresentMode::AutoVsync,
            desired_maximum_frame_latency: 2,
            alpha_mode: caps.alpha_modes[0],
            view_formats: vec![],
            color_space: Default::default(),
        };
        surface.configure(&ctx.device, &surface_config);
        let library = self.shader_library();
        if let Some(dir) = &library.dir {
            let flag = self.shaders_changed.clone();
            match notify_debouncer_full::new_debouncer(Duration::from_millis(150), None, move |r: notify_debouncer_full::DebounceEventResult| {
                let changed = |e: &notify_debouncer_full::DebouncedEvent| crate::live::is_content_change(&e.kind) && e.paths.iter().any(|p| p.extension().is_some_and(|x| x == "wgsl"));
                if r.is_ok_and(|ev| ev.iter().any(changed)) {
                    flag.store(true, Ordering::Release);
                }
            }) {
                Ok(mut d) => {
                    if let Err(e) = d.watch(dir, notify_debouncer_full::notify::RecursiveMode::NonRecursive) {
                        log::warn!("cannot watch {}: {e}", dir.display());
                    }
                    log::info!("hot-reloading shaders from {}", dir.display());
                    self.shader_watch = Some(d);
                }
                Err(e) => log::warn!("shader hot reload unavailable: {e}"),
            }
        }
        let mut renderer = match SkyRenderer::new(&ctx, format, library) {
            Ok(r) => r,
            Err(e) => {
                // A broken shader on disk must not stop the tool: fall back to the embedded ones.
                self.shader_error = Some(format!("shaders on disk failed, using the embedded ones: {e}"));
                SkyRenderer::new(&ctx, format, ShaderLibrary::embedded()).map_err(|e| anyhow!(e))?
            }
        };
        renderer.set_sky(&ctx, self.live.sky()).map_err(|e| anyhow!(e))?;
        let egui_ctx = egui::Context::default();
        let egui_state = egui_winit::State::new(egui_ctx, egui::ViewportId::ROOT, &window, Some(window.scale_factor() as f32), None, Some(ctx.device.limits().max_texture_dimension_2d as usize));
        let egui_renderer = egui_wgpu::Renderer::new(&ctx.device, format, egui_wgpu::RendererOptions::default());
        let depth = depth_view(&ctx.device, surface_config.width, surface_config.height);
        self.gpu = Some(Gpu { window, surface, surface_config, ctx, renderer, depth, egui_state, egui_renderer, capture: None, inspector: None, sky_generation: self.live.generation });
        Ok(())
    }

    fn frame_input(&self) -> FrameInput {
        let c = &self.controls;
        FrameInput { hour: c.hour, game_hours: c.game_hours, weather: c.weather, tier: c.tier, env_map: false, disabled: c.disabled.clone() }
    }

    /// Renders `input` offscreen at `size` through the capture renderer (created on first use).
    fn capture_image(&mut self, input: &FrameInput, size: (u32, u32)) -> anyhow::Result<image::RgbaImage> {
        let (generation, camera, options) = (self.live.generation, self.controls.camera, self.controls.options);
        let gpu = self.gpu.as_mut().ok_or_else(|| anyhow!("no GPU yet"))?;
        if gpu.capture.is_none() {
            gpu.capture = Some(Capture::new(&gpu.ctx, gpu.renderer.library().clone(), size.0, size.1)?);
        }
        let capture = gpu.capture.as_mut().expect("just created");
        capture.render(&gpu.ctx, self.live.sky(), generation, input, &camera, &options, size.0, size.1)
    }

    fn screenshot(&mut self) -> anyhow::Result<PathBuf> {
        let input = self.frame_input();
        let dir = self.config.shots.clone().unwrap_or_else(|| PathBuf::from("shots"));
        let path = free_path(&dir, &screenshot_name(&self.live.sky().name, input.hour, input.weather))?;
        let gpu = self.gpu.as_ref().ok_or_else(|| anyhow!("no GPU yet"))?;
        let size = (gpu.surface_config.width, gpu.surface_config.height);
        let img = self.capture_image(&input, size)?;
        img.save(&path).with_context(|| format!("writing {}", path.display()))?;
        Ok(path)
    }

    fn step_contact_sheet(&mut self) -> anyhow::Result<()> {
        let Some(sheet) = self.sheet.as_mut() else { return Ok(()) };
        let Some((hour, weather, col, row)) = sheet.next_cell() else {
            let sheet = self.sheet.take().expect("present");
            sheet.image.save(&sheet.path).with_context(|| format!("writing {}", sheet.path.display()))?;
            self.last_capture = format!("contact sheet saved to {}", sheet.path.display());
            println!("{}", self.last_capture);
            return Ok(());
        };
        let cell = sheet.cell;
        let mut input = self.frame_input();
        input.hour = hour;
        input.weather = weather;
        input.game_hours = hour as f64;
        let img = self.capture_image(&input, cell)?;
        if let Some(sheet) = self.sheet.as_mut() {
            sheet.put(col, row, &img);
        }
        Ok(())
    }

    fn open(&mut self, spec: SkySpec) {
        if let SkySpec::File(p) | SkySpec::Continent { path: p, .. } = &spec {
            self.settings.opened(p.clone());
        }
        self.live.switch(spec);
    }

    fn open_path(&mut self, path: &Path) {
        match SkySpec::from_path(path, None) {
            Ok(spec) => {
                if let SkySpec::Continent { season, .. } = spec {
                    self.controls.season = season;
                }
                self.open(spec);
            }
            Err(e) => self.gpu_error = Some(e.to_string()),
        }
    }

    fn handle_key(&mut self, key: &Key, event_loop: &ActiveEventLoop) {
        let c = &mut self.controls;
        let hpd = self.live.sky().hours_per_day;
        match key {
            Key::Named(NamedKey::Space) => c.playing = !c.playing,
            Key::Named(NamedKey::F1) => c.show_help = !c.show_help,
            Key::Named(NamedKey::F5) => self.live.request_reload(),
            Key::Named(NamedKey::F6) => self.reload_shaders(),
            Key::Named(NamedKey::F12) => self.take_screenshot(),
            Key::Named(NamedKey::Escape) => event_loop.exit(),
            Key::Character(s) => match s.as_str() {
                "[" => c.hour = (c.hour - 0.25).rem_euclid(hpd),
                "]" => c.hour = (c.hour + 0.25).rem_euclid(hpd),
                "-" => c.weather = (c.weather - 0.05).max(0.0),
                "=" | "+" => c.weather = (c.weather + 0.05).min(1.0),
                "a" | "A" => c.camera.yaw_deg = (c.camera.yaw_deg - 5.0).rem_euclid(360.0),
                "d" | "D" => c.camera.yaw_deg = (c.camera.yaw_deg + 5.0).rem_euclid(360.0),
                "w" | "W" => c.camera.pitch_deg = (c.camera.pitch_deg + 5.0).min(89.0),
                "s" | "S" => c.camera.pitch_deg = (c.camera.pitch_deg - 5.0).max(-89.0),
                "z" | "Z" => c.camera.pitch_deg = 89.0,
                "1" | "2" | "4" => c.tier = Tier::new(s.parse().unwrap_or(4)).unwrap_or_default(),
                _ => {}
            },
            _ => {}
        }
    }

    fn take_screenshot(&mut self) {
        match self.screenshot() {
            Ok(p) => {
                self.last_capture = format!("screenshot saved to {}", p.display());
                println!("{}", self.last_capture);
            }
            Err(e) => self.gpu_error = Some(format!("screenshot failed: {e:#}")),
        }
    }

    fn reload_shaders(&mut self) {
        let Some(gpu) = self.gpu.as_mut() else { return };
        match gpu.renderer.reload_shaders(&gpu.ctx) {
            Ok(()) => {
                self.shader_error = None;
                // The screenshot renderer rebuilds from the same sources on next use.
                gpu.capture = None;
                log::info!("shaders reloaded");
            }
            Err(e) => {
                // Shown once in the panel and the log; the previous pipelines keep rendering.
                if self.shader_error.as_deref() != Some(e.as_str()) {
                    log::error!("shader reload failed, keeping the previous pipelines:\n{e}");
                }
                self.shader_error = Some(e);
            }
        }
    }

    fn redraw(&mut self, event_loop: &ActiveEventLoop) -> anyhow::Result<()> {
        let now = Instant::now();
        let dt = now.duration_since(self.last_frame).as_secs_f32().min(0.25);
        self.last_frame = now;
        let t0 = Instant::now();

        match self.live.poll() {
            Some(ReloadEvent::Reloaded) => {
                if let Some(gpu) = self.gpu.as_mut() {
                    match gpu.renderer.set_sky(&gpu.ctx, self.live.sky()) {
                        Ok(()) => {
                            gpu.sky_generation = self.live.generation;
                            self.gpu_error = None;
                            gpu.window.set_title(&format!("skytune - {}", self.live.sky().name));
                        }
                        Err(e) => self.gpu_error = Some(format!("GPU upload failed, keeping the previous sky: {e}")),
                    }
                }
            }
            Some(ReloadEvent::Failed(_)) | None => {}
        }
        if self.shaders_changed.swap(false, Ordering::AcqRel) {
            self.reload_shaders();
        }
        if let Err(e) = self.step_contact_sheet() {
            self.sheet = None;
            self.gpu_error = Some(format!("contact sheet failed: {e:#}"));
        }

        let sky = self.live.sky().clone();
        if self.controls.playing {
            self.controls.hour = (self.controls.hour + dt * self.controls.speed).rem_euclid(sky.hours_per_day);
            self.controls.game_hours += (dt * self.controls.speed) as f64;
        }
        let input = self.frame_input();
        let frame = sky.evaluate(&input);
        let t_eval = t0.elapsed();

        let mut errors: Vec<String> = Vec::new();
        if let Some(e) = &self.live.error {
            errors.push(format!("sky reload failed; showing the last good sky:\n{e}"));
        }
        errors.extend(self.shader_error.iter().map(|e| format!("shader reload failed; previous pipelines kept:\n{e}")));
        errors.extend(self.gpu_error.iter().cloned());

        let Some(gpu) = self.gpu.as_mut() else { return Ok(()) };
        // Bitmap inspector texture, rebuilt when the target changes.
        let inspector_id = self.controls.inspect.as_ref().map(|t| {
            let key = Arc::as_ptr(&t.bitmap) as usize;
            if gpu.inspector.as_ref().is_none_or(|(k, _)| *k != key) {
                let b = &t.bitmap;
                let img = egui::ColorImage::from_rgba_unmultiplied([b.width as usize, b.height as usize], &b.to_rgba8());
                let handle = gpu.egui_state.egui_ctx().load_texture("inspector", img, egui::TextureOptions::NEAREST);
                gpu.inspector = Some((key, handle));
            }
            gpu.inspector.as_ref().expect("just set").1.id()
        });

        let raw = gpu.egui_state.take_egui_input(&gpu.window);
        let spec = self.live.spec();
        if let Some(g) = gpu.renderer.glare_state_mut() {
            g.frozen = self.controls.freeze_glare;
        }
        let glare = gpu.renderer.glare_state().cloned();
        let gpu_ms = gpu.renderer.gpu_pass_ms().to_vec();
        let stats = gpu.renderer.stats.clone();
        let mut actions = Vec::new();
        let info = UiInfo {
            sky: &sky,
            frame: &frame,
            stats: &stats,
            glare: glare.as_ref(),
            errors: &errors,
            adapter: &gpu.ctx.adapter_line(),
            source: &spec.display(),
            continent: matches!(spec, SkySpec::Continent { .. }),
            recent: &self.settings.recent,
            frame_times_ms: &self.frame_times,
            cpu_ms: &self.cpu_ms,
            gpu_ms: &gpu_ms,
            sheet_progress: self.sheet.as_ref().map(|s| (s.done, s.total())),
            last_capture: &self.last_capture,
        };
        let controls = &mut self.controls;
        let full = gpu.egui_state.egui_ctx().clone().run_ui(raw, |ui| actions = ui::draw(ui, controls, &info, inspector_id));
        gpu.egui_state.handle_platform_output(&gpu.window, full.platform_output);
        let ppp = full.pixels_per_point;
        let jobs = gpu.egui_state.egui_ctx().tessellate(full.shapes, ppp);
        let t_ui = t0.elapsed();
        // Texture uploads do not need the surface: apply them now so no delta is ever lost.
        let mut deltas = full.textures_delta;
        for (id, list) in &deltas.set {
            for delta in list {
                gpu.egui_renderer.update_texture(&gpu.ctx.device, &gpu.ctx.queue, *id, delta);
            }
        }
        let frees = std::mem::take(&mut deltas.free);
        deltas.clear();

        let surface_texture = match gpu.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t) | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
            other => {
                log::debug!("no surface texture this frame: {other:?}");
                if matches!(other, wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost) {
                    gpu.surface.configure(&gpu.ctx.device, &gpu.surface_config);
                }
                for id in &frees {
                    gpu.egui_renderer.free_texture(id);
                }
                return Ok(());
            }
        };
        let view = surface_texture.texture.create_view(&Default::default());
        let size = (gpu.surface_config.width, gpu.surface_config.height);
        let mut encoder = gpu.ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("App::frame") });
        gpu.renderer.render(&gpu.ctx, &mut encoder, &view, &gpu.depth, size, &sky, &frame, &self.controls.camera, &self.controls.options, dt, input.game_hours);

        let screen = egui_wgpu::ScreenDescriptor { size_in_pixels: [size.0, size.1], pixels_per_point: ppp };
        let extra = gpu.egui_renderer.update_buffers(&gpu.ctx.device, &gpu.ctx.queue, &mut encoder, &jobs, &screen);
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
            gpu.egui_renderer.render(&mut rpass.forget_lifetime(), &jobs, &screen);
        }
        for id in &frees {
            gpu.egui_renderer.free_texture(id);
        }
        let t_record = t0.elapsed();
        gpu.ctx.queue.submit(extra.into_iter().chain([encoder.finish()]));
        gpu.renderer.after_submit();
        gpu.window.pre_present_notify();
        gpu.ctx.queue.present(surface_texture);
        let t_submit = t0.elapsed();

        let ms = |d: Duration| d.as_secs_f32() * 1000.0;
        self.cpu_ms = vec![
            ("reload + evaluate", ms(t_eval)),
            ("ui", ms(t_ui - t_eval)),
            ("record", ms(t_record - t_ui)),
            ("submit + present", ms(t_submit - t_record)),
        ];
        self.frame_times.push_back(dt * 1000.0);
        if self.frame_times.len() > 240 {
            self.frame_times.pop_front();
        }
        self.frame_count += 1;

        for action in actions {
            match action {
                UiAction::Open(p) => self.open_path(&p),
                UiAction::OpenBuiltin => self.open(SkySpec::Builtin),
                UiAction::Season(s) => {
                    if let SkySpec::Continent { path, .. } = self.live.spec() {
                        self.open(SkySpec::Continent { path, season: s });
                    }
                }
                UiAction::Reload => self.live.request_reload(),
                UiAction::ReloadShaders => self.reload_shaders(),
                UiAction::Screenshot => self.take_screenshot(),
                UiAction::ContactSheet => {
                    let (cols, rows) = self.controls.sheet_grid;
                    let dir = self.config.shots.clone().unwrap_or_else(|| PathBuf::from("shots"));
                    let name = screenshot_name(&sky.name, 0.0, 0.0).replace("_00.00h_w0.00", "_contact_sheet");
                    match free_path(&dir, &name) {
                        Ok(path) => self.sheet = Some(ContactSheet::new(sky.hours_per_day, cols, rows, (240, 135), path)),
                        Err(e) => self.gpu_error = Some(format!("{e:#}")),
                    }
                }
            }
        }

        if self.config.screenshot_and_exit && self.frame_count == 3 {
            self.take_screenshot();
            event_loop.exit();
        }
        if self.config.frames.is_some_and(|n| self.frame_count >= n) {
            log::info!("rendered {} frames, exiting", self.frame_count);
            event_loop.exit();
        }
        Ok(())
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.gpu.is_none() {
            if let Err(e) = self.init(event_loop) {
                self.error = Some(e);
                event_loop.exit();
            }
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let Some(gpu) = self.gpu.as_mut() else { return };
        let response = gpu.egui_state.on_window_event(&gpu.window, &event);
        let egui_ctx = gpu.egui_state.egui_ctx().clone();
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) if size.width > 0 && size.height > 0 => {
                gpu.surface_config.width = size.width;
                gpu.surface_config.height = size.height;
                gpu.surface.configure(&gpu.ctx.device, &gpu.surface_config);
                gpu.depth = depth_view(&gpu.ctx.device, size.width, size.height);
                let logical = size.to_logical::<u32>(gpu.window.scale_factor());
                self.settings.window_size = [logical.width, logical.height];
            }
            WindowEvent::DroppedFile(path) => self.open_path(&path),
            WindowEvent::MouseInput { state, button: MouseButton::Left, .. } => {
                if state == ElementState::Released || egui_ctx.egui_wants_pointer_input() {
                    self.drag = None;
                } else {
                    self.drag = Some((f64::NAN, f64::NAN));
                }
            }
            WindowEvent::CursorMoved { position, .. } => {
                if let Some((x, y)) = self.drag {
                    if x.is_finite() {
                        let c = &mut self.controls.camera;
                        let per_px = c.fov_y_deg / gpu.surface_config.height.max(1) as f32;
                        c.yaw_deg = (c.yaw_deg - (position.x - x) as f32 * per_px).rem_euclid(360.0);
                        c.pitch_deg = (c.pitch_deg + (position.y - y) as f32 * per_px).clamp(-89.0, 89.0);
                    }
                    self.drag = Some((position.x, position.y));
                }
            }
            WindowEvent::KeyboardInput { event, .. } if event.state == ElementState::Pressed && !response.consumed && !egui_ctx.egui_wants_keyboard_input() => {
                self.handle_key(&event.logical_key, event_loop);
            }
            WindowEvent::RedrawRequested => {
                if let Err(e) = self.redraw(event_loop) {
                    // Never crash the artist's session: show it and go on with the next frame.
                    self.gpu_error = Some(format!("{e:#}"));
                }
            }
            _ => {}
        }
    }

    fn about_to_wait(&mut self, _event_loop: &ActiveEventLoop) {
        if let Some(gpu) = &self.gpu {
            gpu.window.request_redraw();
        }
    }
}
