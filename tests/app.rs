//! The desktop app: its panels run in a headless egui context, and the binary starts under
//! Xvfb on lavapipe, renders frames, saves a screenshot through its own code path and exits.

mod common;

use std::collections::VecDeque;
use std::process::Command;

use skytune::app::controls::{CompareInfo, Controls, UiInfo};
use skytune::app::ui::{self, UiAction};
use skytune::render::FrameStats;
use skytune::sky::builtin::default_sky;
use skytune::sky::FrameInput;

fn run_panels(controls: &mut Controls, events: Vec<egui::Event>) -> Vec<UiAction> {
    run_panels_at(controls, events, (1280.0, 800.0)).actions
}

/// The panels laid out in a window of `size` points; their actions and the sky's rectangle.
fn run_panels_at(controls: &mut Controls, events: Vec<egui::Event>, size: (f32, f32)) -> ui::UiOutput {
    let sky = default_sky();
    let mut input = FrameInput::new(controls.hour, controls.weather);
    input.tier = controls.tier;
    let frame = sky.evaluate(&input);
    let stats = FrameStats::default();
    let times: VecDeque<f32> = [16.0, 17.0, 15.5].into_iter().collect();
    let info = UiInfo {
        sky: &sky,
        frame: &frame,
        stats: &stats,
        glare: None,
        errors: &["sky reload failed: sky.toml:3:1: name: expected a string".to_string()],
        adapter: "test",
        adapter_strategy: skytune::render::FillStrategy::software(),
        source: "default",
        continent: false,
        recent: &[],
        frame_times_ms: &times,
        cpu_ms: &[("record", 1.0)],
        gpu_ms: &[],
        sheet_progress: Some((3, 32)),
        last_capture: "",
        model_progress: Some(0.4),
        compare: controls.compare.open.then(|| CompareInfo {
            texture: None,
            summary: Some(("model lut".into(), "FLIP mean 0.1".into(), skytune::measure::image_diff::FlipSummary { mean: 0.1, p95: 0.2, max: 0.5 })),
            progress: Some(0.5),
            error: Some("no earlier version yet".into()),
            snapshots: Vec::new(),
            has_file: true,
        }),
        device_lost: true,
        floor_ms: Some(6.0),
        auto_model: Some("auto model: lut-default (test)".into()),
        auto_progress: Some((0.4, "computing the reference for weather step 1 of 2".into())),
        auto_point: Some("lut-default".into()),
    };
    let ctx = egui::Context::default();
    let mut output = None;
    // Two passes: egui lays out on the first and answers clicks on the second.
    for events in [Vec::new(), events] {
        let raw = egui::RawInput { screen_rect: Some(egui::Rect::from_min_size(egui::Pos2::ZERO, egui::vec2(size.0, size.1))), events, ..Default::default() };
        let mut out = ctx.run_ui(raw, |ui| output = Some(ui::draw(ui, controls, &info, None)));
        // Nothing is painted in this test: the font atlas upload is dropped on purpose.
        out.textures_delta.clear();
        assert!(!out.shapes.is_empty(), "the panels drew nothing");
    }
    output.expect("the panels ran")
}

#[test]
fn the_panels_leave_the_sky_most_of_the_window_with_every_section_open() {
    for size in [(800.0, 600.0), (1280.0, 720.0), (1920.0, 1080.0)] {
        let mut c = Controls::default();
        // Every section open, the long statistics among them: none may widen its panel.
        c.layout.open_sections = ["sky_file", "model_chart", "view", "glare", "times", "skipped", "switches"].map(String::from).to_vec();
        let out = run_panels_at(&mut c, Vec::new(), size);
        let share = out.sky_rect.area() / (size.0 * size.1);
        // The errors panel (this test shows one) takes height too; the side panels no more than their share.
        assert!(out.sky_rect.width() >= size.0 * (1.0 - skytune::app::layout::PANELS_MAX_FRACTION) - 1.0, "{size:?}: {:?}", out.sky_rect);
        assert!(share >= 0.6 * (1.0 - skytune::app::layout::ERRORS_MAX_FRACTION), "{size:?}: the sky has {share:.2} of the window");
        // Tab hides every panel: the sky takes the whole width.
        c.layout.toggle_hidden();
        let hidden = run_panels_at(&mut c, Vec::new(), size);
        assert_eq!(hidden.sky_rect.width(), size.0, "{size:?}");
    }
}

#[test]
fn panels_lay_out_with_every_section_and_no_action_by_default() {
    let mut c = Controls { show_help: true, ..Default::default() };
    let actions = run_panels(&mut c, Vec::new());
    assert!(actions.is_empty(), "{actions:?}");
    assert!(c.show_help, "help stays open until closed");
}

#[test]
fn the_compare_window_lays_out_and_saves_snapshots() {
    let mut c = Controls::default();
    c.compare.open = true;
    let actions = run_panels(&mut c, Vec::new());
    assert!(actions.is_empty(), "{actions:?}");
    assert!(c.compare.open);
}

#[test]
fn window_compares_the_sky_with_a_snapshot_under_xvfb() {
    let (dir, sky_file) = common::default_sky_folder();
    let sky = skytune::sky::load_sky_file(&sky_file).unwrap();
    skytune::files::snapshot::save(&sky_file, &sky, "before").unwrap();
    // The edit after the snapshot: darker gradients.
    let gradient = sky_file.parent().unwrap().join("gradient_clear.png");
    let mut img = image::open(&gradient).unwrap().to_rgba8();
    for p in img.pixels_mut() {
        for c in 0..3 {
            p[c] /= 2;
        }
    }
    img.save(&gradient).unwrap();
    let (out, stderr) = in_window(&dir.path().join("state.toml"), |c| {
        c.arg(&sky_file).args(["--cpu", "--frames", "8", "--compare", "snapshot=before"]);
    });
    assert!(out.status.success(), "{stderr}");
    let line = stderr.lines().find(|l| l.contains("compare: B = snapshot before:")).unwrap_or_else(|| panic!("no comparison logged: {stderr}"));
    let mean: f64 = line.split("FLIP mean ").nth(1).and_then(|r| r.split_whitespace().next()).and_then(|v| v.parse().ok()).unwrap();
    assert!(mean > 0.01, "the darker gradient shows against the snapshot: {line}");
    // The snapshot was only read; the artist's folder holds it in the hidden folder alone.
    assert!(sky_file.parent().unwrap().join(".skytune-snapshots/before/sky.toml").is_file());
}

#[test]
fn hidden_objects_keep_their_reason_in_the_model_the_panel_shows() {
    let sky = default_sky();
    let frame = sky.evaluate(&FrameInput::new(12.0, 0.0));
    let galaxy = &frame.objects[sky.object_index("galaxy").unwrap()];
    assert_eq!(galaxy.versions.as_ref().unwrap_err().to_string(), "ref_color constant0 has alpha 0");
}

#[test]
fn screenshot_names_carry_sky_time_and_weather() {
    assert_eq!(skytune::app::capture::screenshot_name("Lakes (winter)", 6.5, 0.25), "lakes__winter__06.50h_w0.25.png");
    let dir = tempfile::tempdir().unwrap();
    let a = skytune::app::capture::free_path(dir.path(), "x.png").unwrap();
    std::fs::write(&a, b"").unwrap();
    assert_eq!(skytune::app::capture::free_path(dir.path(), "x.png").unwrap(), dir.path().join("x-2.png"));
}

#[test]
fn contact_sheet_covers_the_grid() {
    let mut sheet = skytune::app::capture::ContactSheet::new(24.0, 4, 3, (10, 5), "s.png".into());
    let mut cells = Vec::new();
    while let Some((h, w, c, r)) = sheet.next_cell() {
        cells.push((h, w));
        sheet.put(c, r, &image::RgbaImage::from_pixel(10, 5, image::Rgba([c as u8, r as u8, 0, 255])));
    }
    assert_eq!(cells.len(), 12);
    assert_eq!(cells[0], (0.0, 0.0));
    assert_eq!(cells[5], (6.0, 0.5));
    assert_eq!(cells[11], (18.0, 1.0));
    assert_eq!(sheet.image.dimensions(), (40, 15));
    assert_eq!(sheet.image.get_pixel(35, 12).0, [3, 2, 0, 255]);
}

/// Runs the window under its own Xvfb with `config` as its settings file and `RUST_LOG=info`;
/// `customise` adds the arguments and environment. Returns the output and its stderr.
fn in_window(config: &std::path::Path, customise: impl FnOnce(&mut Command)) -> (std::process::Output, String) {
    let (mut server, display) = common::xvfb((1024, 768)).expect("Xvfb is required: run scripts/setup.sh");
    let mut command = Command::new(env!("CARGO_BIN_EXE_skytune"));
    command.env("DISPLAY", &display).env("SKYTUNE_CONFIG", config).env("RUST_LOG", "info");
    customise(&mut command);
    let out = command.output().expect("running skytune");
    let _ = server.kill();
    let _ = server.wait();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    (out, stderr)
}

#[test]
fn window_starts_renders_screenshots_and_exits_under_xvfb() {
    let shots = tempfile::tempdir().unwrap();
    let config = shots.path().join("state.toml");
    let (_d, sky) = common::default_sky_folder();
    let (out, stderr) = in_window(&config, |c| {
        c.arg(&sky).args(["--cpu", "--screenshot-and-exit", "--shots"]).arg(shots.path());
    });
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "exit {:?}\nstdout:\n{stdout}\nstderr:\n{stderr}", out.status);
    let shot = std::fs::read_dir(shots.path()).unwrap().filter_map(|e| e.ok()).map(|e| e.path()).find(|p| p.extension().is_some_and(|x| x == "png")).expect("a screenshot");
    assert!(shot.file_name().unwrap().to_string_lossy().starts_with("default_17.50h_w0.10"), "{}", shot.display());
    let img = image::open(&shot).unwrap().to_rgba8();
    // The screenshot is the sky view, at its size: the part of the 1280x720 window the panels leave.
    let view = stderr.lines().rfind(|l| l.contains("sky view: ")).unwrap_or_else(|| panic!("no sky view logged: {stderr}"));
    assert!(view.contains(&format!("width {} height {} of a 1280x720 window", img.width(), img.height())), "{view}: the screenshot is {:?}", img.dimensions());
    assert!(img.width() >= 1280 * 6 / 10 && img.height() == 720, "{:?}", img.dimensions());
    // A real sky: the top is not black, and the image is not one flat colour.
    let (cx, bottom) = (img.width() / 2, img.height() - 20);
    let top = img.get_pixel(cx, 40).0;
    assert!(top[0] as u32 + top[1] as u32 + top[2] as u32 > 60, "{top:?}");
    assert_ne!(img.get_pixel(cx, 40), img.get_pixel(cx, bottom));
    // The window remembered its size and the sky it showed.
    let state = std::fs::read_to_string(&config).unwrap();
    assert!(state.contains("window_size") && state.contains("sky.toml"), "{state}");
}

#[test]
fn window_runs_a_fixed_number_of_frames() {
    let dir = tempfile::tempdir().unwrap();
    let (out, stderr) = in_window(&dir.path().join("state.toml"), |c| {
        c.args(["--cpu", "--frames", "5"]);
    });
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("rendered 5 frames, exiting"), "{stderr}");
    // Reading the shaders must not look like an edit of them (that would reload in a loop).
    assert!(!stderr.contains("shaders reloaded"), "{stderr}");
}

#[test]
fn a_lost_device_is_reported_and_recreated_in_the_window() {
    let dir = tempfile::tempdir().unwrap();
    let (out, stderr) = in_window(&dir.path().join("state.toml"), |c| {
        c.args(["--cpu", "--frames", "12"]).env("SKYTUNE_TEST_LOSE_DEVICE_AT", "4");
    });
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("the GPU device was lost"), "{stderr}");
    assert!(stderr.contains("GPU device recreated"), "{stderr}");
    assert!(stderr.contains("rendered 12 frames, exiting"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
}

#[test]
fn window_soak_changes_everything_and_keeps_running() {
    let dir = tempfile::tempdir().unwrap();
    let state = dir.path().join("state.toml");
    std::fs::write(&state, "window_size = [320, 180]\n").unwrap();
    let (out, stderr) = in_window(&state, |c| {
        c.args(["--cpu", "--soak", "--frames", "520"]);
    });
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("soak: working on a copy"), "{stderr}");
    assert!(stderr.contains("reloaded sky \"soak 100"), "the good edit at frame 100 loaded: {stderr}");
    assert!(stderr.contains("object[10].name"), "the broken edit at frame 200 was rejected with its location: {stderr}");
    assert!(stderr.contains("shaders reloaded"), "{stderr}");
    assert!(stderr.contains("soak: frame 500 resident"), "{stderr}");
    assert!(stderr.contains("rendered 520 frames, exiting") && !stderr.contains("panicked"), "{stderr}");
}

#[test]
fn a_corrupt_settings_file_is_reported_and_replaced() {
    let dir = tempfile::tempdir().unwrap();
    let state = dir.path().join("state.toml");
    std::fs::write(&state, b"window_size = [\xff\xfe not toml").unwrap();
    let (out, stderr) = in_window(&state, |c| {
        c.args(["--cpu", "--frames", "3"]);
    });
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("was unusable") && stderr.contains("replaced by defaults"), "{stderr}");
    assert!(dir.path().join("state.toml.corrupt").is_file());
    let text = std::fs::read_to_string(&state).unwrap();
    assert!(text.contains("window_size"), "replaced by a readable file: {text}");
}

#[test]
fn without_a_display_it_says_so_and_renders_headless() {
    let dir = tempfile::tempdir().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_skytune"))
        .arg("--cpu")
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .env("SKYTUNE_CONFIG", dir.path().join("state.toml"))
        .current_dir(dir.path())
        .output()
        .expect("running skytune");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("no display available") && stderr.contains("skytune render"), "{stderr}");
    assert!(dir.path().join("skytune-default.png").is_file());
}
