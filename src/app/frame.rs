//! One redraw of the window, as a sequence of small steps, and what the user asked for through
//! the keyboard and the panels.

use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{anyhow, Context as _};
use winit::event_loop::ActiveEventLoop;
use winit::keyboard::{Key, NamedKey};

use super::capture::{free_path, screenshot_name, ContactSheet};
use super::controls::{CompareInfo, UiInfo};
use super::ui::{self, UiAction};
use super::window::UiPaint;
use super::App;
use crate::files::hot_reload::{ReloadEvent, SkySpec};
use crate::sky::{FrameInput, FrameSky, Sky, Tier};

/// Frame times kept for the stats graph.
const FRAME_TIMES_KEPT: usize = 240;

/// The window's soak: a temporary copy of the sky, the random driver, memory samples.
pub struct WindowSoak {
    /// The temporary sky file being rewritten.
    pub sky_file: PathBuf,
    good: String,
    driver: crate::measure::soak::Driver,
    dir: PathBuf,
    /// Resident memory samples (frame, bytes).
    samples: Vec<(u64, u64)>,
}

impl WindowSoak {
    /// Copies the sky of `spec` (its folder's files, or the built-in sky) to a temporary folder.
    pub fn new(spec: &SkySpec) -> anyhow::Result<Self> {
        let (dir, sky_file) = crate::measure::soak::sky_copy("window-soak", spec.sky_file().as_deref())?;
        let good = std::fs::read_to_string(&sky_file).with_context(|| format!("reading {}", sky_file.display()))?;
        log::info!("soak: working on a copy of the sky in {}", dir.display());
        Ok(Self { sky_file, good, driver: crate::measure::soak::Driver::new(1), dir, samples: Vec::new() })
    }
}

impl Drop for WindowSoak {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

impl App {
    /// Soak mode: random controls every frame, sky rewrites every 100 frames, shader rebuilds every
    /// 500, memory logged every 100.
    fn step_soak(&mut self) {
        let Some(soak) = self.soak.as_mut() else { return };
        let frame = self.clock.frames() + 1;
        let (input, camera) = soak.driver.frame(self.live.sky());
        let c = &mut self.controls;
        (c.hour, c.game_hours, c.weather, c.tier, c.sky_model, c.camera) = (input.hour, input.game_hours, input.weather, input.tier, input.sky_model, camera);
        if frame.is_multiple_of(crate::measure::soak::RELOAD_EVERY) {
            let n = frame / crate::measure::soak::RELOAD_EVERY;
            let text = if n.is_multiple_of(2) { crate::measure::soak::broken_version(&soak.good) } else { crate::measure::soak::good_version(&soak.good, frame) };
            if let Err(e) = crate::support::safe_write::write_atomic(&soak.sky_file, text.as_bytes()) {
                self.gpu_error = Some(format!("soak: {e}"));
            }
        }
        if frame.is_multiple_of(crate::measure::soak::SAMPLE_EVERY) {
            let rss = crate::measure::soak::resident_bytes();
            soak.samples.push((frame, rss));
            log::info!("soak: frame {frame} resident {:.1} MiB", rss as f64 / 1048576.0);
        }
        if frame.is_multiple_of(crate::measure::soak::SHADERS_EVERY) {
            self.reload_shaders();
        }
    }

    /// One frame: reloads, the clock, evaluation, the panels, the surface, then the UI's actions.
    pub(super) fn redraw(&mut self, event_loop: &ActiveEventLoop) -> anyhow::Result<()> {
        let t0 = Instant::now();
        if std::mem::take(&mut self.recreate_device) {
            self.rebuild_gpu()?;
        }
        if let Some(gpu) = self.gpu.as_ref() {
            // Non-blocking: runs finished callbacks, among them the device-lost one.
            let _ = gpu.ctx.device.poll(wgpu::PollType::Poll);
        }
        self.apply_reloads();
        self.poll_curve_bake();
        let last_frame = Duration::from_secs_f32(self.frame_times.back().copied().unwrap_or(0.0) / 1000.0);
        self.auto.poll(last_frame, self.live.generation);
        self.update_title();
        self.step_soak();
        if let Err(e) = self.step_contact_sheet() {
            self.sheet = None;
            self.gpu_error = Some(format!("contact sheet failed: {e:#}"));
        }
        let sky = self.shown_sky();
        let input = self.advance_clock(&sky);
        if self.controls.compare.open {
            self.step_compare();
        }
        let frame = sky.evaluate(&input);
        let t_eval = t0.elapsed();
        let Some((actions, paint)) = self.run_panels(&sky, &frame) else { return Ok(()) };
        let t_ui = t0.elapsed();
        let gpu = self.gpu.as_mut().ok_or_else(|| anyhow!("no GPU yet"))?;
        gpu.present(&frame, &self.controls.camera, &self.controls.options, &paint);
        let t_present = t0.elapsed();

        let ms = |d: Duration| d.as_secs_f32() * 1000.0;
        self.cpu_ms = vec![("reload + evaluate", ms(t_eval)), ("ui", ms(t_ui - t_eval)), ("record + submit + present", ms(t_present - t_ui))];
        self.frame_times.push_back(input.dt_s * 1000.0);
        if self.frame_times.len() > FRAME_TIMES_KEPT {
            self.frame_times.pop_front();
        }
        for action in actions {
            self.apply_action(action, &sky);
        }
        let frames = self.clock.frames();
        // Test hook (SKYTUNE_TEST_LOSE_DEVICE_AT=N): lose the device at frame N, then press
        // "Recreate the GPU device" three frames later, as a user would.
        if let Some(n) = self.test_lose_device_at {
            if frames == n {
                if let Some(gpu) = self.gpu.as_ref() {
                    log::warn!("test hook: destroying the GPU device");
                    gpu.ctx.device.destroy();
                }
            } else if frames == n + 3 {
                self.apply_action(UiAction::RecreateDevice, &sky);
            }
        }
        if self.config.screenshot_and_exit && frames == 3 {
            self.take_screenshot();
            event_loop.exit();
        }
        if self.config.frames.is_some_and(|n| frames >= n) {
            if let Some(soak) = &self.soak {
                // Growth after the first tenth of the run (warm-up), as `skytune soak` measures it.
                let steady = &soak.samples[(soak.samples.len() / 10).min(soak.samples.len().saturating_sub(1))..];
                if let (Some(first), Some(last)) = (steady.first(), steady.last()) {
                    log::info!("soak: resident memory {:+.1}% after warm-up ({} samples)", (last.1 as f64 / first.1.max(1) as f64 - 1.0) * 100.0, steady.len());
                }
            }
            log::info!("rendered {frames} frames, exiting");
            event_loop.exit();
        }
        Ok(())
    }

    /// Sets the window's title when what it says changed.
    fn update_title(&mut self) {
        let title = self.window_title();
        if title != self.title {
            if let Some(gpu) = &self.gpu {
                gpu.window.set_title(&title);
            }
            self.title = title;
        }
    }

    /// Starts baking the model shown into the curve editor's bitmap (columns `from ..= to`).
    fn start_curve_bake(&mut self, from: u32, to: u32) {
        let (Some(ed), Some(gpu)) = (self.controls.curves.as_mut(), self.gpu.as_ref()) else { return };
        let model = self.controls.sky_model.or(self.auto.model(&self.live.sky().model)).unwrap_or(self.live.sky().model);
        match super::curve_bake::CurveBake::start(self.live.sky(), &model, ed.editor.key(), ed.editor.size(), (from, to), &gpu.ctx) {
            Ok(bake) => {
                ed.message = Some("baking the model on a worker...".into());
                self.curve_bake = Some(bake);
            }
            Err(e) => ed.message = Some(e),
        }
    }

    /// Applies a finished bake to the curve editor, if it still holds that bitmap.
    fn poll_curve_bake(&mut self) {
        let Some(result) = self.curve_bake.as_ref().and_then(|b| b.poll()) else { return };
        let key = self.curve_bake.take().map(|b| b.key).unwrap_or_default();
        let Some(ed) = self.controls.curves.as_mut().filter(|ed| ed.editor.key() == key) else { return };
        match result {
            Ok(edit) => {
                ed.editor.apply(&edit, false);
                ed.message = Some("baked the model into the span (Undo takes it back)".into());
            }
            Err(e) => ed.message = Some(e),
        }
    }

    /// Swaps in a sky the loader finished, and rebuilds pipelines after a shader edit.
    fn apply_reloads(&mut self) {
        if let Some(ReloadEvent::Reloaded) = self.live.poll() {
            // A reload while the curve editor holds unsaved edits of a file that changed: say so,
            // keep showing the edits, and let the artist choose.
            if let Some(ed) = self.controls.curves.as_mut() {
                if ed.editor.is_dirty() && ed.editor.changed_on_disk() {
                    ed.conflict = true;
                }
            }
            if let Some(gpu) = self.gpu.as_mut() {
                match gpu.renderer.set_sky(&gpu.ctx, self.live.sky()) {
                    Ok(()) => self.gpu_error = None,
                    Err(e) => self.gpu_error = Some(format!("GPU upload failed, keeping the previous sky: {e}")),
                }
            }
            self.request_auto_model();
        }
        if self.shaders_changed.swap(false, Ordering::AcqRel) {
            self.reload_shaders();
        }
    }

    /// Advances the clock (and time of day while playing); the frame's input.
    fn advance_clock(&mut self, sky: &Sky) -> FrameInput {
        let mut input = self.frame_input();
        self.clock.advance(&mut input);
        let c = &mut self.controls;
        if c.playing {
            c.hour = (c.hour + input.dt_s * c.speed).rem_euclid(sky.hours_per_day);
            c.game_hours += (input.dt_s * c.speed) as f64;
        }
        c.particle_time_s += input.dt_s as f64;
        (input.hour, input.game_hours) = (c.hour, c.game_hours);
        input.particle_clock = Some(c.particle_clock(sky));
        input.bursts = c.bursts.clone();
        input
    }

    /// The frame the controls describe (no clock yet).
    fn frame_input(&self) -> FrameInput {
        let c = &self.controls;
        // The panel's choice wins; else an auto sky's pick (the last good one while a new one is
        // measured); else the sky file's model.
        let auto = self.auto.model(&self.live.sky().model);
        FrameInput { game_hours: c.game_hours, tier: c.tier, disabled: c.disabled.clone(), sky_model: c.sky_model.or(auto), ..FrameInput::new(c.hour, c.weather) }
    }

    /// Every error to show, newest state of each source.
    fn errors(&self) -> Vec<String> {
        let mut errors = Vec::new();
        if let Some(reason) = self.gpu.as_ref().and_then(|g| g.ctx.lost_reason()) {
            errors.push(format!("the GPU device was lost ({reason}); the sky and your files are safe: recreate the device to go on"));
        }
        if let Some(e) = &self.live.error {
            errors.push(format!("sky reload failed; showing the last good sky:\n{e}"));
        }
        errors.extend(self.shader_error.iter().map(|e| format!("shader reload failed; previous pipelines kept:\n{e}")));
        errors.extend(self.gpu_error.iter().cloned());
        errors
    }

    /// Runs the panels; their actions and what to paint (None before the window exists).
    fn run_panels(&mut self, sky: &Sky, frame: &FrameSky) -> Option<(Vec<UiAction>, UiPaint)> {
        let errors = self.errors();
        let spec = self.live.spec();
        let gpu = self.gpu.as_mut()?;
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
        if let Some(g) = gpu.renderer.glare_state_mut() {
            g.frozen = self.controls.freeze_glare;
        }
        let raw = gpu.egui_state.take_egui_input(&gpu.window);
        let glare = gpu.renderer.glare_state().cloned();
        let gpu_ms = gpu.renderer.gpu_pass_ms().to_vec();
        let stats = gpu.renderer.stats.clone();
        let adapter = gpu.ctx.adapter_line();
        let info = UiInfo {
            sky,
            frame,
            stats: &stats,
            glare: glare.as_ref(),
            errors: &errors,
            adapter: &adapter,
            adapter_strategy: self.adapter_strategy,
            source: &spec.display(),
            continent: matches!(spec, SkySpec::Continent { .. }),
            recent: &self.settings.recent,
            frame_times_ms: &self.frame_times,
            cpu_ms: &self.cpu_ms,
            gpu_ms: &gpu_ms,
            sheet_progress: self.sheet.as_ref().map(|s| (s.done, s.total())),
            last_capture: &self.last_capture,
            model_progress: gpu
                .renderer
                .pass::<crate::render::atmosphere::sky_view::SkyViewPass>()
                .and_then(|p| p.progress())
                .or_else(|| gpu.renderer.pass::<crate::render::atmosphere::precomputed_tables::PrecomputedTablesPass>().and_then(|p| p.progress())),
            compare: None,
            device_lost: gpu.ctx.lost_reason().is_some(),
            floor_ms: gpu.floor_ms(self.clock.frames()),
            auto_model: self.auto.describe(sky),
            auto_progress: self.auto.progress(),
            auto_point: self.auto.point(),
        };
        let compare = self.controls.compare.open.then(|| {
            let c = &self.controls.compare;
            let texture = self.compare.picture(gpu.egui_state.egui_ctx(), c.layout, c.split);
            CompareInfo {
                texture,
                summary: self.compare.result.as_ref().map(|r| (r.b_label.clone(), r.diff.summary(), r.diff.flip)),
                progress: self.compare.pending.then_some(self.compare.progress.unwrap_or(0.0)),
                error: self.compare.error.clone(),
                snapshots: self.snapshots.clone(),
                has_file: self.live.sky_file().is_some(),
            }
        });
        let info = UiInfo { compare, ..info };
        let mut out = None;
        let controls = &mut self.controls;
        let full = gpu.egui_state.egui_ctx().clone().run_ui(raw, |ui| out = Some(ui::draw(ui, controls, &info, inspector_id)));
        gpu.egui_state.handle_platform_output(&gpu.window, full.platform_output);
        let pixels_per_point = full.pixels_per_point;
        let jobs = gpu.egui_state.egui_ctx().tessellate(full.shapes, pixels_per_point);
        let frees = gpu.update_ui_textures(full.textures_delta);
        let out = out?;
        Some((out.actions, UiPaint { jobs, frees, pixels_per_point, sky_rect: out.sky_rect }))
    }

    /// Carries out one action of the panels.
    fn apply_action(&mut self, action: UiAction, sky: &Sky) {
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
            UiAction::Snapshot => self.save_snapshot(),
            UiAction::RecreateDevice => self.recreate_device = true,
            // The next frame's sky carries the edit (`shown_sky`).
            UiAction::CurvesEdited => {}
            UiAction::CurvesBake { from, to } => self.start_curve_bake(from, to),
            UiAction::RefreshSnapshots => self.refresh_snapshots(),
            UiAction::ContactSheet => {
                let (cols, rows) = self.controls.sheet_grid;
                let dir = self.shots_dir();
                let name = screenshot_name(&sky.name, 0.0, 0.0).replace("_00.00h_w0.00", "_contact_sheet");
                match free_path(&dir, &name) {
                    Ok(path) => self.sheet = Some(ContactSheet::new(sky.hours_per_day, cols, rows, (240, 135), path)),
                    Err(e) => self.gpu_error = Some(format!("{e:#}")),
                }
            }
        }
    }

    /// Carries out a key press outside the panels.
    pub(super) fn handle_key(&mut self, key: &Key, event_loop: &ActiveEventLoop) {
        let c = &mut self.controls;
        let hpd = self.live.sky().hours_per_day;
        match key {
            Key::Named(NamedKey::Space) => c.playing = !c.playing,
            Key::Named(NamedKey::Tab) => c.layout.toggle_hidden(),
            Key::Named(NamedKey::F1) => c.show_help = !c.show_help,
            Key::Named(NamedKey::F5) => self.live.request_reload(),
            Key::Named(NamedKey::F6) => self.reload_shaders(),
            Key::Named(NamedKey::F12) => self.take_screenshot(),
            Key::Named(NamedKey::F7) => {
                c.compare.open = !c.compare.open;
                self.refresh_snapshots();
            }
            Key::Named(NamedKey::F8) => self.save_snapshot(),
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

    fn open(&mut self, spec: SkySpec) {
        if let SkySpec::File(p) | SkySpec::Continent { path: p, .. } = &spec {
            self.settings.opened(p.clone());
        }
        self.live.switch(spec);
    }

    pub(super) fn open_path(&mut self, path: &Path) {
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

    fn reload_shaders(&mut self) {
        // The compare renderers rebuild from the new sources on their next comparison.
        self.compare.reset();
        let Some(gpu) = self.gpu.as_mut() else { return };
        match gpu.reload_shaders() {
            Ok(()) => {
                self.shader_error = None;
                log::info!("shaders reloaded");
            }
            Err(e) => {
                // Shown once in the panel and the log; the previous pipelines keep rendering.
                let e = e.to_string();
                if self.shader_error.as_deref() != Some(e.as_str()) {
                    log::error!("shader reload failed, keeping the previous pipelines:\n{e}");
                }
                self.shader_error = Some(e);
            }
        }
    }

    /// A new device, renderer and surface for the same window (after the device was lost).
    fn rebuild_gpu(&mut self) -> anyhow::Result<()> {
        let Some(old) = self.gpu.take() else { return Ok(()) };
        let window = old.window.clone();
        drop(old);
        self.compare.reset();
        let adapter = if self.config.cpu { crate::render::AdapterChoice::Cpu } else { crate::render::AdapterChoice::from_env() };
        let (gpu, shader_error) = super::window::WindowGpu::with_window(window, adapter, self.shader_library(), self.live.sky())?;
        log::info!("GPU device recreated");
        self.shader_error = shader_error;
        self.gpu_error = None;
        self.gpu = Some(gpu);
        Ok(())
    }

    /// Renders and measures the compare view again if its inputs changed.
    fn step_compare(&mut self) {
        let Some(gpu) = self.gpu.as_ref() else { return };
        let previous = self.live.previous.as_ref().map(|(s, g)| (s.as_ref(), *g));
        let inputs = super::compare::CompareInputs {
            sky: (self.live.sky().as_ref(), self.live.generation),
            previous,
            input: self.frame_input(),
            camera: self.controls.camera,
            options: self.controls.options,
        };
        self.compare.step(&gpu.ctx, gpu.renderer.library(), &self.controls.compare, &inputs);
    }

    /// Saves the sky file shown and its bitmaps as a snapshot named by the time.
    fn save_snapshot(&mut self) {
        let result = match self.live.sky_file() {
            Some(file) => crate::files::snapshot::save(&file, self.live.sky(), &crate::files::snapshot::timestamp_name()).map_err(|e| e.to_string()),
            None => Err(crate::files::snapshot::SnapshotError::NoFile.to_string()),
        };
        match result {
            Ok(snap) => {
                self.last_capture = format!("snapshot \"{}\" saved to {}", snap.name, snap.sky_file.display());
                println!("{}", self.last_capture);
                self.refresh_snapshots();
            }
            Err(e) => self.gpu_error = Some(format!("snapshot failed: {e}")),
        }
    }

    pub(super) fn refresh_snapshots(&mut self) {
        self.snapshots = self.live.sky_file().map(|f| crate::files::snapshot::list(&f)).unwrap_or_default();
    }

    fn shots_dir(&self) -> PathBuf {
        self.config.shots.clone().unwrap_or_else(|| PathBuf::from("shots"))
    }

    /// Renders `input` offscreen at `size` through the headless still path.
    fn capture_image(&mut self, input: &FrameInput, size: (u32, u32)) -> anyhow::Result<image::RgbaImage> {
        let (generation, camera, options) = (self.live.generation, self.controls.camera, self.controls.options);
        let gpu = self.gpu.as_mut().ok_or_else(|| anyhow!("no GPU yet"))?;
        gpu.capture(self.live.sky(), generation, input, &camera, &options, size)
    }

    fn screenshot(&mut self) -> anyhow::Result<PathBuf> {
        let input = self.frame_input();
        let path = free_path(&self.shots_dir(), &screenshot_name(&self.live.sky().name, input.hour, input.weather))?;
        let size = self.gpu.as_ref().ok_or_else(|| anyhow!("no GPU yet"))?.sky_size();
        let img = self.capture_image(&input, size)?;
        crate::support::safe_write::save_png(&img, &path)?;
        Ok(path)
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

    /// Renders the next cell of a contact sheet in progress (one per frame keeps the window responsive).
    fn step_contact_sheet(&mut self) -> anyhow::Result<()> {
        let Some(sheet) = self.sheet.as_mut() else { return Ok(()) };
        let Some((hour, weather, col, row)) = sheet.next_cell() else {
            let sheet = self.sheet.take().expect("present");
            crate::support::safe_write::save_png(&sheet.image, &sheet.path)?;
            self.last_capture = format!("contact sheet saved to {}", sheet.path.display());
            println!("{}", self.last_capture);
            return Ok(());
        };
        let cell = sheet.cell;
        let input = FrameInput { hour, weather, game_hours: hour as f64, ..self.frame_input() };
        let img = self.capture_image(&input, cell)?;
        if let Some(sheet) = self.sheet.as_mut() {
            sheet.put(col, row, &img);
        }
        Ok(())
    }
}
