//! The curve editor in the window: driven headless through egui's input (a drag on the curves,
//! Ctrl+Z), the saved PNG changes exactly the edited pixels and undo restores the original bytes;
//! the window opens with `--edit` under Xvfb and the sky keeps at least half of it.

mod common;

use std::process::Command;

use skytune::app::curve_editor::{self, CurveAction, CurveEditor};
use skytune::files::bitmap_edit::{BitmapEditor, Edit};

/// Runs the editor for one frame per event list in a 1000 x 400 window: every frame's actions
/// and the curves' place.
fn frames(ed: &mut CurveEditor, hour: f32, events: Vec<Vec<egui::Event>>) -> curve_editor::CurveOutput {
    let ctx = egui::Context::default();
    let mut all = curve_editor::CurveOutput { actions: Vec::new(), curves_rect: egui::Rect::NOTHING };
    for events in events {
        let raw = egui::RawInput { screen_rect: Some(egui::Rect::from_min_size(egui::Pos2::ZERO, egui::vec2(1000.0, 400.0))), events, ..Default::default() };
        let mut out = ctx.run_ui(raw, |ui| {
            let o = curve_editor::show(ui, ed, hour, 24.0);
            all.actions.extend(o.actions);
            all.curves_rect = o.curves_rect;
        });
        out.textures_delta.clear();
    }
    all
}

fn press(pos: egui::Pos2, pressed: bool) -> egui::Event {
    egui::Event::PointerButton { pos, button: egui::PointerButton::Primary, pressed, modifiers: Default::default() }
}

#[test]
fn a_drag_sets_one_column_and_undo_restores_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("sun_diffuse.png");
    let original = image::RgbaImage::from_fn(24, 3, |x, y| image::Rgba([(x * 10) as u8, (y * 80) as u8, 200, 255]));
    original.save(&path).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let mut ed = CurveEditor::new(BitmapEditor::open(&path, "sun_diffuse.png").unwrap(), "sun_diffuse".into(), false, 0.5);
    assert_eq!(ed.row, 1, "weather 0.5 is the middle row");
    ed.channel = 2;
    // Where the curves are, then a drag at 6:00 from blue 0.3 to 0.1 (one undo step).
    let rect = frames(&mut ed, 12.0, vec![Vec::new()]).curves_rect;
    let at = |hour: f32, v: f32| egui::pos2(rect.left() + hour / 24.0 * rect.width(), rect.bottom() - v * rect.height());
    let out = frames(
        &mut ed,
        12.0,
        vec![
            vec![egui::Event::PointerMoved(at(6.0, 0.3))],
            vec![press(at(6.0, 0.3), true)],
            vec![egui::Event::PointerMoved(at(6.1, 0.2))],
            vec![egui::Event::PointerMoved(at(6.1, 0.1))],
            vec![press(at(6.1, 0.1), false)],
        ],
    );
    assert!(out.actions.contains(&CurveAction::Edited), "{:?}", out.actions);
    assert!((ed.editor.texel(6, 1)[2] - 0.1).abs() < 0.01, "{:?}", ed.editor.texel(6, 1));
    // A colour at 18:00 and a smoothed span, as the picker and the smooth button apply them.
    ed.editor.apply(&Edit::SetColor { x: 18, y: 1, rgba: [1.0, 0.0, 0.0, 1.0] }, false);
    ed.editor.apply(&Edit::Smooth { y: 1, from: 17, to: 21, passes: 1 }, false);
    ed.save(false);
    assert!(!ed.conflict, "{:?}", ed.message);
    let saved = image::open(&path).unwrap().to_rgba8();
    let changed: Vec<(u32, u32)> = saved.enumerate_pixels().filter(|(x, y, p)| *p != original.get_pixel(*x, *y)).map(|(x, y, _)| (x, y)).collect();
    // The drag's column, the colour's (smoothed too), and 19 next to it; the span's ends (17, 21)
    // stay, and 20's neighbours were linear in x, so it stays as well.
    assert_eq!(changed, [(6, 1), (18, 1), (19, 1)]);
    // Ctrl+Z three times through the window's keys: the file's bytes come back on save.
    let z = egui::Event::Key { key: egui::Key::Z, physical_key: None, pressed: true, repeat: false, modifiers: egui::Modifiers::COMMAND };
    frames(&mut ed, 12.0, vec![vec![z.clone()], vec![z.clone()], vec![z]]);
    assert_eq!(ed.editor.can_undo_redo(), (false, true), "three edits undone");
    ed.save(false);
    assert_eq!(std::fs::read(&path).unwrap(), bytes);
}

#[test]
fn a_change_on_disk_shows_both_choices() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("fog.png");
    image::RgbImage::from_pixel(8, 2, image::Rgb([10, 20, 30])).save(&path).unwrap();
    let mut ed = CurveEditor::new(BitmapEditor::open(&path, "fog.png").unwrap(), "fog_color".into(), false, 0.0);
    ed.editor.apply(&Edit::SetColor { x: 1, y: 0, rgba: [1.0, 1.0, 1.0, 1.0] }, false);
    image::RgbImage::from_pixel(8, 2, image::Rgb([90, 90, 90])).save(&path).unwrap();
    ed.save(false);
    assert!(ed.conflict && ed.message.as_deref().is_some_and(|m| m.contains("changed on disk")), "{:?}", ed.message);
    // Theirs on disk, ours in the editor: both still there.
    assert_eq!(image::open(&path).unwrap().to_rgb8().get_pixel(1, 0).0, [90, 90, 90]);
    assert_eq!(ed.editor.texel(1, 0), [1.0, 1.0, 1.0, 1.0]);
    // The panel draws the choice.
    let out = frames(&mut ed, 3.0, vec![Vec::new()]);
    assert!(out.actions.is_empty());
}

#[test]
fn the_window_opens_with_the_editor_and_keeps_half_for_the_sky() {
    let shots = tempfile::tempdir().unwrap();
    let config = shots.path().join("state.toml");
    let (_d, sky) = common::default_sky_folder();
    let (mut server, display) = common::xvfb((1280, 720)).expect("Xvfb is required: run scripts/setup.sh");
    let out = Command::new(env!("CARGO_BIN_EXE_skytune"))
        .env("DISPLAY", &display)
        .env("SKYTUNE_CONFIG", &config)
        .env("RUST_LOG", "info")
        .arg(&sky)
        .args(["--edit", "sun_diffuse.png", "--cpu", "--screenshot-and-exit", "--shots"])
        .arg(shots.path())
        .output()
        .unwrap();
    let _ = server.kill();
    let _ = server.wait();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let view = stderr.lines().rfind(|l| l.contains("sky view: ")).unwrap_or_else(|| panic!("no sky view logged: {stderr}"));
    let number = |after: &str| -> f32 { view[view.find(after).unwrap() + after.len()..].split_whitespace().next().unwrap().parse().unwrap() };
    let (w, h) = (number("width "), number("height "));
    assert!(h < 720.0, "the editor takes some of the height: {view}");
    assert!(w * h >= 0.5 * 1280.0 * 720.0, "the sky keeps {:.2} of the window: {view}", w * h / (1280.0 * 720.0));
}

#[test]
fn reopening_a_bitmap_brings_its_history_back() {
    let (_dir, sky_path) = common::default_sky_folder();
    let sky = skytune::sky::load_sky_file(&sky_path).unwrap();
    let mut c = skytune::app::controls::Controls::default();
    skytune::app::ui::open_curves(&mut c, &sky, "fog.png", "fog_color".into(), false);
    c.curves.as_mut().unwrap().editor.apply(&Edit::SetColor { x: 3, y: 0, rgba: [1.0, 0.0, 0.0, 1.0] }, false);
    // Another bitmap, then back: the edit and its undo are still there.
    skytune::app::ui::open_curves(&mut c, &sky, "sun_diffuse.png", "sun_diffuse".into(), false);
    assert_eq!(c.curves.as_ref().unwrap().editor.key(), "sun_diffuse.png");
    skytune::app::ui::open_curves(&mut c, &sky, "fog.png", "fog_color".into(), false);
    let ed = &mut c.curves.as_mut().unwrap().editor;
    assert_eq!(ed.texel(3, 0), [1.0, 0.0, 0.0, 1.0]);
    assert!(ed.is_dirty() && ed.undo() && !ed.is_dirty());
}
