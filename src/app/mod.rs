//! The desktop app: a winit window showing the live sky with egui panels. It wires the renderer
//! (which knows nothing of egui or winit), the hot-reloading sky and the UI.
//!
//! - this file: start-up and the event loop;
//! - [`frame`]: one redraw, step by step (reloads, clock, evaluation, panels, present, actions);
//! - [`window`]: the GPU side of the window;
//! - [`capture`]: screenshots and contact sheets (through [`crate::render::Headless`]);
//! - [`compare`]: the compare view (two renders, their difference) and snapshots;
//! - [`auto_pick`]: `kind = "auto"` measured on a worker, the window rendering meanwhile;
//! - [`layout`]: panel widths and sections, the sky view's rectangle;
//! - [`controls`]: what the panels read and write; [`ui`]: the panels; [`diagnostics`]: their
//!   statistics section.

pub mod auto_pick;
pub mod capture;
pub mod compare;
pub mod controls;
pub mod curve_bake;
pub mod curve_editor;
pub mod diagnostics;
mod frame;
pub mod layout;
pub mod settings;
pub mod ui;
pub mod window;

use std::collections::VecDeque;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use anyhow::{anyhow, Context as _};
use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::window::WindowId;

use crate::files::hot_reload::{LiveSky, SkySpec};
use crate::files::watch::FileWatcher;
use crate::render::{AdapterChoice, FillStrategy, GpuContext, Headless, RenderOptions, ShaderLibrary};
use crate::sky::{Clock, FrameInput, Stepping, Tier};
use capture::{screenshot_name, ContactSheet};
use controls::Controls;
use settings::Settings;
use window::WindowGpu;

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
    /// Open the compare view with this B (see [`compare::CompareB::parse`]).
    pub compare: Option<String>,
    /// Soak mode (see `skytune --help`).
    pub soak: bool,
    /// Time of day to start at, game hours (None: the panel's default).
    pub hour: Option<f32>,
    /// Weather to start at, 0..1.
    pub weather: Option<f32>,
    /// Preset view to start with (`south`, `zenith`, ...).
    pub view: Option<String>,
    /// Fill strategy (None: the adapter's, [`FillStrategy::for_device`]).
    pub strategy: Option<FillStrategy>,
    /// Open the curve editor on this bitmap of the sky (a path, or a name next to the sky file).
    pub edit: Option<PathBuf>,
}

/// Whether a display server is reachable (X11 or Wayland).
pub fn display_available() -> bool {
    std::env::var_os("DISPLAY").is_some_and(|d| !d.is_empty()) || std::env::var_os("WAYLAND_DISPLAY").is_some_and(|d| !d.is_empty())
}

/// Runs the window until it is closed. Without a display, says so, renders the sky headless to
/// `skytune-default.png` (or the sky's name) instead and points to `skytune render`.
pub fn run(config: AppConfig) -> anyhow::Result<()> {
    let (mut settings, settings_report) = Settings::load();
    let spec = match &config.sky {
        Some(p) => SkySpec::from_path(p, config.season.as_deref()).map_err(|e| anyhow!("{e}"))?,
        None => match &settings.last_sky {
            Some(p) if p.is_file() && !config.soak => SkySpec::from_path(p, config.season.as_deref()).unwrap_or(SkySpec::Builtin),
            _ => SkySpec::Builtin,
        },
    };
    // A soak rewrites the sky file: it works on a temporary copy, never on the artist's.
    let soak = if config.soak { Some(frame::WindowSoak::new(&spec)?) } else { None };
    let spec = soak.as_ref().map_or(spec, |s| SkySpec::File(s.sky_file.clone()));
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
    let mut controls = Controls { layout: settings.panels.clone(), ..Controls::default() };
    if let Some(h) = config.hour {
        anyhow::ensure!(h.is_finite() && (0.0..live.sky().hours_per_day).contains(&h), "--hour: expected 0 to {}, found {h}", live.sky().hours_per_day);
        (controls.hour, controls.game_hours) = (h, h as f64);
    }
    if let Some(w) = config.weather {
        anyhow::ensure!((0.0..=1.0).contains(&w), "--weather: expected 0 to 1, found {w}");
        controls.weather = w;
    }
    if let Some(v) = &config.view {
        controls.camera = crate::render::Camera::preset_arg(v).map_err(|e| anyhow!(e))?;
    }
    let strategy = config.strategy;
    if let Some(t) = config.tier {
        controls.tier = Tier::new(t).ok_or_else(|| anyhow!("--tier: expected 4, 2 or 1, found {t}"))?;
    }
    if let SkySpec::Continent { season, .. } = spec {
        controls.season = season;
    }
    if let Some(edit) = &config.edit {
        let sky = live.sky();
        let dir = std::path::Path::new(&sky.source_name).parent().map(std::path::Path::to_path_buf).unwrap_or_default();
        let key = edit.strip_prefix(&dir).unwrap_or(edit).to_string_lossy().replace('\\', "/");
        let gradient = sky.objects.iter().any(|o| o.standard.gradients.as_ref().is_some_and(|g| g.bitmaps.iter().any(|b| b.source.as_deref() == Some(key.as_str()))));
        anyhow::ensure!(
            crate::sky::Sky::clone(sky).color_bitmaps_mut().iter().any(|b| b.source.as_deref() == Some(key.as_str())),
            "--edit: {} is not a colour bitmap of {}",
            edit.display(),
            sky.source_name
        );
        ui::open_curves(&mut controls, sky, &key, key.clone(), gradient);
        if let Some(e) = controls.curves_error.take() {
            anyhow::bail!("--edit: {e}");
        }
    }
    if let Some(b) = &config.compare {
        let file = live.sky_file();
        controls.compare.b = compare::CompareB::parse(b, file.as_deref()).map_err(|e| anyhow!("--compare: {e}"))?;
        controls.compare.open = true;
    }
    let mut app = App {
        config,
        settings,
        live,
        controls,
        gpu: None,
        error: None,
        clock: Clock::new(Stepping::RealTime),
        frame_times: VecDeque::new(),
        cpu_ms: Vec::new(),
        shader_error: None,
        gpu_error: settings_report,
        sheet: None,
        last_capture: String::new(),
        drag: None,
        shader_watch: None,
        shaders_changed: Arc::new(AtomicBool::new(false)),
        compare: compare::CompareView::default(),
        recreate_device: false,
        soak,
        test_lose_device_at: std::env::var("SKYTUNE_TEST_LOSE_DEVICE_AT").ok().and_then(|v| v.parse().ok()),
        snapshots: Vec::new(),
        auto: auto_pick::AutoPicker::default(),
        title: String::new(),
        strategy: Some(strategy),
        adapter_strategy: FillStrategy::default(),
        edited_sky: None,
        curve_bake: None,
    };
    event_loop.run_app(&mut app).context("running the window")?;
    app.settings.panels = app.controls.layout.clone();
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
    crate::support::safe_write::save_png(&img, &out)?;
    println!("wrote {} (sky \"{}\", hour {}, weather {})", out.display(), sky.name, c.hour, c.weather);
    Ok(())
}

/// The app's state between frames.
pub struct App {
    config: AppConfig,
    settings: Settings,
    live: LiveSky,
    controls: Controls,
    gpu: Option<WindowGpu>,
    error: Option<anyhow::Error>,
    clock: Clock,
    frame_times: VecDeque<f32>,
    cpu_ms: Vec<(&'static str, f32)>,
    shader_error: Option<String>,
    gpu_error: Option<String>,
    sheet: Option<ContactSheet>,
    last_capture: String,
    drag: Option<(f64, f64)>,
    shader_watch: Option<FileWatcher>,
    shaders_changed: Arc<AtomicBool>,
    compare: compare::CompareView,
    /// The user asked for a new GPU device (done at the start of the next frame).
    recreate_device: bool,
    /// Soak mode's state.
    soak: Option<frame::WindowSoak>,
    /// Test hook: frame at which to destroy the device (`SKYTUNE_TEST_LOSE_DEVICE_AT`).
    test_lose_device_at: Option<u64>,
    /// Snapshots of the sky file shown (refreshed when the compare view opens and after saving one).
    snapshots: Vec<crate::files::snapshot::Snapshot>,
    /// `kind = "auto"`: the pick for the sky shown, measured on a worker.
    auto: auto_pick::AutoPicker,
    /// The window's title as last set.
    title: String,
    /// The fill strategy to start with, until the first device is made (None afterwards: a new
    /// device keeps the panel's choice). `Some(None)`: the adapter's.
    strategy: Option<Option<FillStrategy>>,
    /// The strategy the current device's adapter defaults to.
    adapter_strategy: FillStrategy,
    /// The sky shown while the curve editor holds a bitmap: the loaded sky with the editor's
    /// version of it, for (the loaded sky's generation, the editor's revision).
    edited_sky: Option<(u64, u64, Arc<crate::sky::Sky>)>,
    /// A bake into the curve editor's bitmap running on a worker.
    curve_bake: Option<curve_bake::CurveBake>,
}

impl App {
    /// The sky to show: the loaded one, with the curve editor's bitmap in place of its file's.
    fn shown_sky(&mut self) -> Arc<crate::sky::Sky> {
        let Some(ed) = self.controls.curves.as_ref() else {
            self.edited_sky = None;
            return self.live.sky().clone();
        };
        let key = (self.live.generation, ed.editor.revision());
        match &self.edited_sky {
            Some((g, r, sky)) if (*g, *r) == key => sky.clone(),
            _ => {
                let mut sky = (**self.live.sky()).clone();
                sky.replace_bitmap(ed.editor.key(), ed.editor.color_bitmap());
                let sky = Arc::new(sky);
                self.edited_sky = Some((key.0, key.1, sky.clone()));
                sky
            }
        }
    }

    pub(crate) fn shader_library(&self) -> ShaderLibrary {
        match &self.config.shader_dir {
            Some(d) => ShaderLibrary { dir: Some(d.clone()) },
            // Development builds hot-reload the checkout's shaders; release builds use the embedded copies.
            None if cfg!(debug_assertions) => ShaderLibrary { dir: ShaderLibrary::source_dir() },
            None => ShaderLibrary::embedded(),
        }
    }

    fn init(&mut self, event_loop: &ActiveEventLoop) -> anyhow::Result<()> {
        let library = self.shader_library();
        if let Some(dir) = &library.dir {
            self.watch_shaders(dir.clone());
        }
        let adapter = if self.config.cpu { AdapterChoice::Cpu } else { AdapterChoice::from_env() };
        self.title = self.window_title();
        let (gpu, shader_error) = WindowGpu::new(event_loop, &self.title, self.settings.window_size, adapter, library, self.live.sky())?;
        self.shader_error = shader_error;
        // The adapter's strategy unless one was asked for.
        let device_type = gpu.ctx.adapter.get_info().device_type;
        self.adapter_strategy = FillStrategy::resolve(None, device_type);
        if let Some(asked) = self.strategy.take() {
            self.controls.options.strategy = FillStrategy::resolve(asked, device_type);
        }
        self.gpu = Some(gpu);
        self.refresh_snapshots();
        self.request_auto_model();
        Ok(())
    }

    /// Asks for the model of a `kind = "auto"` sky: at once when cached, else measured on a worker
    /// (the first pick for a new atmosphere measures every candidate, a minute or more).
    fn request_auto_model(&mut self) {
        if let Some(gpu) = self.gpu.as_ref() {
            self.auto.request(self.live.sky(), self.live.generation, &gpu.ctx);
        }
    }

    /// The window's title: the sky's name, and a marker while its file fails to load or an auto
    /// pick is measured.
    fn window_title(&self) -> String {
        let mut title = format!("skytune - {}", self.live.sky().name);
        if self.live.error.is_some() {
            title.push_str(" [reload failed: showing the last good sky]");
        }
        if self.auto.is_measuring() {
            title.push_str(" [measuring the auto model]");
        }
        title
    }

    /// Watches the shader folder with the same facility as the sky files.
    fn watch_shaders(&mut self, dir: PathBuf) {
        let flag = self.shaders_changed.clone();
        match FileWatcher::new(move |changed| {
            if changed.iter().any(|p| p.extension().is_some_and(|x| x == "wgsl")) {
                flag.store(true, Ordering::Release);
            }
        }) {
            Ok(mut w) => {
                w.set_dirs([dir.clone()].into_iter().collect());
                log::info!("hot-reloading shaders from {}", dir.display());
                self.shader_watch = Some(w);
            }
            Err(e) => log::warn!("shader hot reload unavailable: {e}"),
        }
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
            WindowEvent::Resized(size) => {
                gpu.resize(size.width, size.height);
                if size.width > 0 && size.height > 0 {
                    let logical = size.to_logical::<u32>(gpu.window.scale_factor());
                    self.settings.window_size = [logical.width, logical.height];
                }
            }
            WindowEvent::DroppedFile(path) => self.open_path(&path),
            WindowEvent::MouseInput { state, button: MouseButton::Left, .. } => {
                self.drag = (state == ElementState::Pressed && !egui_ctx.egui_wants_pointer_input()).then_some((f64::NAN, f64::NAN));
            }
            WindowEvent::CursorMoved { position, .. } => {
                if let Some((x, y)) = self.drag {
                    if x.is_finite() {
                        let c = &mut self.controls.camera;
                        let per_px = c.fov_y_deg / gpu.sky_view.height.max(1) as f32;
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
