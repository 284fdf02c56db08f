//! The window's panels. `draw` is a pure function of the controls and what the frame produced,
//! returning actions for the app to carry out, so it can run in a headless egui context in tests.

use std::path::PathBuf;

use egui::{Color32, RichText};

use crate::atmosphere::OpticalDepth;
use crate::render::frame::camera::PRESETS;
use crate::sky::bitmap::ColorBitmap;
use crate::sky::eval::Tier;
use crate::sky::load::SEASONS;
use crate::sky::resolved::{ColorMode, SkyModelKind, ToneMapper};
use crate::sky::{Rgba, Sky};

use super::controls::{section, CompareInfo, Controls, InspectTarget, UiInfo};
use super::layout::{around, SkyViewport, ERRORS_MAX_FRACTION};

/// What the app must do after the panels ran.
#[derive(Debug, Clone, PartialEq)]
pub enum UiAction {
    /// Open a sky or continent file.
    Open(PathBuf),
    /// Show the built-in sky.
    OpenBuiltin,
    /// Switch season.
    Season(usize),
    /// Reload the sky now.
    Reload,
    /// Rebuild the shaders now.
    ReloadShaders,
    /// Save a screenshot.
    Screenshot,
    /// Start a contact sheet.
    ContactSheet,
    /// Save the sky file and its bitmaps as a snapshot.
    Snapshot,
    /// Read the list of snapshots again.
    RefreshSnapshots,
    /// Build a new GPU device (after the old one was lost).
    RecreateDevice,
    /// The curve editor changed its bitmap: show it from the next frame.
    CurvesEdited,
    /// Bake the sky's model into columns `from ..= to` of the curve editor's bitmap.
    CurvesBake {
        /// First column.
        from: u32,
        /// Last column.
        to: u32,
    },
}

/// The most of the window's height the curve editor takes: the sky keeps the rest.
const CURVES_MAX_FRACTION: f32 = 0.4;

/// Opens the file the sky names `key` (next to the sky file) in the curve editor.
pub fn open_curves(c: &mut Controls, sky: &Sky, key: &str, label: String, gradient: bool) {
    let dir = std::path::Path::new(&sky.source_name).parent().map(std::path::Path::to_path_buf).unwrap_or_default();
    let path = dir.join(key);
    c.curves_closed.extend(c.curves.take());
    // The same file edited before in this window: its editor, history and all.
    if let Some(i) = c.curves_closed.iter().position(|ed| ed.editor.path() == path) {
        let mut ed = c.curves_closed.remove(i);
        if ed.editor.is_dirty() && ed.editor.changed_on_disk() {
            ed.conflict = true;
        }
        c.curves = Some(ed);
        c.curves_error = None;
        return;
    }
    match crate::files::bitmap_edit::BitmapEditor::open(&path, key) {
        Ok(editor) => {
            c.curves = Some(Box::new(super::curve_editor::CurveEditor::new(editor, label, gradient, c.weather)));
            c.curves_error = None;
        }
        Err(e) => c.curves_error = Some(format!("cannot edit {label}: {e}")),
    }
}

/// An "edit" button (captioned `caption`) for a bitmap slot the sky loaded from a file.
fn edit_button_as(ui: &mut egui::Ui, c: &mut Controls, sky: &Sky, bitmap: &ColorBitmap, label: String, gradient: bool, caption: &str) {
    if let Some(key) = bitmap.source.clone() {
        if ui.small_button(caption).on_hover_text(format!("edit {label} ({key}) as curves over the day")).clicked() {
            open_curves(c, sky, &key, label, gradient);
        }
    }
}

/// An "edit" button for a bitmap slot the sky loaded from a file.
fn edit_button(ui: &mut egui::Ui, c: &mut Controls, sky: &Sky, bitmap: &ColorBitmap, label: String, gradient: bool) {
    edit_button_as(ui, c, sky, bitmap, label, gradient, "edit");
}

/// Keyboard shortcuts, shown in the help overlay.
pub const SHORTCUTS: [(&str, &str); 16] = [
    ("Tab", "hide / show the panels"),
    ("Space", "play / pause time"),
    ("[ / ]", "hour -0.25 / +0.25"),
    ("- / =", "weather -0.05 / +0.05"),
    ("A / D", "turn left / right"),
    ("W / S", "look up / down"),
    ("drag (left mouse)", "free look"),
    ("1 / 2 / 4", "GPU tier: 1, 2 or 4 texture stages"),
    ("Z", "look at the zenith"),
    ("F5", "reload the sky now"),
    ("F6", "reload the shaders now"),
    ("F7", "compare view (A: the sky now, B: another version, model, tier or hour)"),
    ("F8", "save a snapshot of the sky file and its bitmaps"),
    ("F12", "screenshot"),
    ("F1", "this help"),
    ("Esc", "quit"),
];

fn swatch(ui: &mut egui::Ui, c: Rgba) {
    let (rect, _) = ui.allocate_exact_size(egui::vec2(14.0, 14.0), egui::Sense::hover());
    let to8 = |x: f32| (x.clamp(0.0, 1.0) * 255.0).round() as u8;
    ui.painter().rect_filled(rect, 2.0, Color32::from_rgb(to8(c[0]), to8(c[1]), to8(c[2])));
    ui.painter().rect_stroke(rect, 2.0, egui::Stroke::new(1.0, Color32::GRAY), egui::StrokeKind::Inside);
}

/// What the panels produced: the user's actions and where the sky shows.
#[derive(Debug, Clone, PartialEq)]
pub struct UiOutput {
    /// Actions for the app to carry out.
    pub actions: Vec<UiAction>,
    /// The part of the window the panels leave to the sky, points, on whole pixels.
    pub sky_rect: egui::Rect,
}

/// Sliders as wide as leaves room for their value and label in the panel's width: a wider one
/// would widen what the text below wraps at, past the panel's edge.
fn fit_sliders(ui: &mut egui::Ui) {
    ui.spacing_mut().slider_width = (ui.available_width() - 150.0).clamp(40.0, 200.0);
}

/// A panel's header: the title and a button that hides the panel.
fn panel_header(ui: &mut egui::Ui, title: &str, open: &mut bool) {
    ui.horizontal(|ui| {
        ui.heading(title);
        ui.with_layout(egui::Layout::right_to_left(egui::Align::Center), |ui| {
            if ui.small_button("hide").on_hover_text("hide this panel (Tab hides and shows every panel)").clicked() {
                *open = false;
            }
        });
    });
}

/// Which side panel.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Side {
    /// The controls.
    Left,
    /// The objects.
    Right,
}

/// A side panel: resizable within `range` (points), hidden by its button or a drag past its edge
/// (and shown again by a drag or Tab), its width and state kept in the layout; `contents` scroll
/// inside it. Returns its width this frame (0 when hidden).
fn side_panel(ui: &mut egui::Ui, c: &mut Controls, side: Side, range: (f32, f32), title: &str, contents: impl FnOnce(&mut egui::Ui, &mut Controls)) -> f32 {
    let (panel, width, shown) = match side {
        Side::Left => (egui::Panel::left("controls"), c.layout.left_width, c.layout.shows_left()),
        Side::Right => (egui::Panel::right("objects"), c.layout.right_width, c.layout.shows_right()),
    };
    let mut open = shown;
    let response = panel.default_size(width.clamp(range.0, range.1)).size_range(range.0..=range.1).show_collapsible(ui, &mut open, |ui| {
        let mut keep = true;
        panel_header(ui, title, &mut keep);
        egui::ScrollArea::vertical().auto_shrink([false, false]).show(ui, |ui| {
            fit_sliders(ui);
            contents(ui, c)
        });
        keep
    });
    let drawn = response.as_ref().map_or(0.0, |r| r.response.rect.width());
    let hidden_by_button = response.as_ref().is_some_and(|r| !r.inner);
    let (stored_width, stored_open) = match side {
        Side::Left => (&mut c.layout.left_width, &mut c.layout.left_open),
        Side::Right => (&mut c.layout.right_width, &mut c.layout.right_open),
    };
    if response.as_ref().is_some_and(|r| r.inner) {
        *stored_width = drawn;
    }
    if open != shown || hidden_by_button {
        // Its own button, or a drag on its edge, opened or closed it.
        *stored_open = open && !hidden_by_button;
        let opened = *stored_open;
        c.layout.hidden &= !opened;
    }
    drawn
}

/// The controls panel's contents: the sky file, time and weather, tier and model, view, glare,
/// captures, compare, and the statistics.
fn controls_panel(ui: &mut egui::Ui, c: &mut Controls, info: &UiInfo<'_>, actions: &mut Vec<UiAction>) {
    let sky = info.sky;
    ui.label(RichText::new(info.source).small());
    ui.label(RichText::new(format!("{} · fill strategy: {}", info.adapter, c.options.strategy.name())).small().weak());
    ui.separator();

    section(ui, c, "sky_file", "Sky file", |ui, c| {
        ui.horizontal(|ui| {
            let width = (ui.available_width() - 60.0).max(60.0);
            ui.add(egui::TextEdit::singleline(&mut c.path_input).desired_width(width)).on_hover_text("path of a sky or continent file");
            if ui.button("Open").clicked() && !c.path_input.trim().is_empty() {
                actions.push(UiAction::Open(PathBuf::from(c.path_input.trim())));
            }
        });
        ui.horizontal_wrapped(|ui| {
            if ui.button("Built-in sky").clicked() {
                actions.push(UiAction::OpenBuiltin);
            }
            if ui.button("Reload (F5)").clicked() {
                actions.push(UiAction::Reload);
            }
            if ui.button("Shaders (F6)").clicked() {
                actions.push(UiAction::ReloadShaders);
            }
        });
        for p in info.recent {
            if ui.link(p.display().to_string()).clicked() {
                actions.push(UiAction::Open(p.clone()));
            }
        }
        ui.label(RichText::new("Tip: drop a sky file onto the window.").small().weak());
        if info.continent {
            let mut season = c.season;
            egui::ComboBox::from_label("season").selected_text(SEASONS[season]).show_ui(ui, |ui| {
                for (i, s) in SEASONS.iter().enumerate() {
                    ui.selectable_value(&mut season, i, *s);
                }
            });
            if season != c.season {
                c.season = season;
                actions.push(UiAction::Season(season));
            }
        }
    });

    ui.separator();
    ui.add(egui::Slider::new(&mut c.hour, 0.0..=sky.hours_per_day - 0.001).text("hour").fixed_decimals(2));
    if ui.button(if c.playing { "Pause" } else { "Play" }).clicked() {
        c.playing = !c.playing;
    }
    ui.add(egui::Slider::new(&mut c.speed, 0.0..=4.0).text("game h/s"));
    ui.add(egui::Slider::new(&mut c.weather, 0.0..=1.0).text("weather").fixed_decimals(2));
    if !sky.weather_names.is_empty() {
        let n = sky.weather_names.len();
        let i = ((c.weather * (n - 1) as f32).round() as usize).min(n - 1);
        ui.label(format!("weather step: {} ({})", sky.weather_names[i], sky.weather_names.join(" / ")));
    }

    ui.separator();
    ui.horizontal_wrapped(|ui| {
        ui.label("GPU tier:");
        for t in Tier::ALL {
            ui.radio_value(&mut c.tier, t, if t.stages() == 1 { "1 stage".to_string() } else { format!("{} stages", t.stages()) });
        }
    });
    if let Some(line) = &info.auto_model {
        ui.label(line);
    }
    if let Some((p, stage)) = &info.auto_progress {
        ui.add(egui::ProgressBar::new(*p).show_percentage());
        ui.label(RichText::new(stage).small());
    }
    sky_model_controls(ui, c, info.sky);
    let current = info.auto_point.clone().filter(|_| c.sky_model.is_none()).or_else(|| crate::measure::model_points::point_for(&c.sky_model.unwrap_or(info.sky.model)));
    section(ui, c, "model_chart", "Speed against accuracy", |ui, _| model_chart(ui, current.as_deref()));
    if let Some(p) = info.model_progress {
        ui.add(egui::ProgressBar::new(p).show_percentage().text("computing the sky in the background"));
    }

    section(ui, c, "view", "View", |ui, c| {
        ui.add(egui::Slider::new(&mut c.camera.fov_y_deg, 10.0..=120.0).text("fov"));
        ui.add(egui::Slider::new(&mut c.camera.yaw_deg, 0.0..=360.0).text("yaw"));
        ui.add(egui::Slider::new(&mut c.camera.pitch_deg, -89.0..=89.0).text("pitch"));
        ui.horizontal_wrapped(|ui| {
            for (name, yaw, pitch) in PRESETS {
                if ui.button(name).clicked() {
                    c.camera.yaw_deg = yaw;
                    c.camera.pitch_deg = pitch;
                }
            }
        });
        ui.checkbox(&mut c.options.scene, "main-scene stand-in");
        ui.checkbox(&mut c.options.depth_split, "depth-range split (scene [0, 0.95], sky [0.99, 1])");
        ui.checkbox(&mut c.options.glare, "sun glare");
    });

    section(ui, c, "glare", "Sun glare", |ui, c| match info.glare {
        Some(g) => {
            ui.label(format!("V = {}  T = {}", g.visible_samples, g.total_samples));
            ui.label(format!("visibility V/T = {:.3}", g.ratio));
            ui.label(format!("intensity = {:.3}", g.intensity));
            ui.label(format!("last result waited {} frame(s); {} frames without result", g.frames_waited, g.frames_without_result));
            ui.checkbox(&mut c.freeze_glare, "freeze the visibility ratio");
        }
        None => {
            ui.label("this sky has no [glare]");
        }
    });

    captures(ui, c, info, actions);
    ui.separator();
    super::diagnostics::stats(ui, c, info);
}

/// Screenshots, contact sheets and the compare view's switch.
fn captures(ui: &mut egui::Ui, c: &mut Controls, info: &UiInfo<'_>, actions: &mut Vec<UiAction>) {
    ui.separator();
    ui.horizontal_wrapped(|ui| {
        if ui.button("Screenshot (F12)").clicked() {
            actions.push(UiAction::Screenshot);
        }
        if ui.button("Contact sheet").clicked() && info.sheet_progress.is_none() {
            actions.push(UiAction::ContactSheet);
        }
    });
    ui.horizontal_wrapped(|ui| {
        ui.add(egui::DragValue::new(&mut c.sheet_grid.0).range(1..=24).prefix("hours "));
        ui.add(egui::DragValue::new(&mut c.sheet_grid.1).range(1..=8).prefix("weathers "));
    });
    if let Some((done, total)) = info.sheet_progress {
        ui.add(egui::ProgressBar::new(done as f32 / total.max(1) as f32).text(format!("contact sheet {done}/{total}")));
    }
    if !info.last_capture.is_empty() {
        ui.label(RichText::new(info.last_capture).small());
    }

    ui.separator();
    if ui.button(if c.compare.open { "Close compare (F7)" } else { "Compare (F7)" }).clicked() {
        c.compare.open = !c.compare.open;
        actions.push(UiAction::RefreshSnapshots);
    }
}

/// Builds every panel for one frame; returns the actions the user asked for and the sky's part
/// of the window. The side panels share at most `layout::PANELS_MAX_FRACTION` of the width.
pub fn draw(ui: &mut egui::Ui, c: &mut Controls, info: &UiInfo<'_>, inspector_texture: Option<egui::TextureId>) -> UiOutput {
    let mut actions = Vec::new();
    let sky = info.sky;
    // Painted first, so under the panels: the window outside the sky (set once the panels are laid out).
    let background = ui.painter().add(egui::Shape::Noop);
    let screen = ui.max_rect();
    let (left_min, left_max) = c.layout.left_range(screen.width());
    let left_width = side_panel(ui, c, Side::Left, (left_min, left_max), &sky.name, |ui, c| controls_panel(ui, c, info, &mut actions));
    if let Some(info) = &info.compare {
        compare_window(ui, c, info, &mut actions);
    }
    let (right_min, right_max) = c.layout.right_range(screen.width(), left_width);
    let right_width = side_panel(ui, c, Side::Right, (right_min, right_max), "Objects", |ui, c| objects(ui, c, info));

    if !info.errors.is_empty() {
        egui::Panel::bottom("errors").max_size(screen.height() * ERRORS_MAX_FRACTION).show(ui, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| {
                for e in info.errors {
                    ui.colored_label(Color32::from_rgb(255, 110, 110), e);
                }
                if info.device_lost && ui.button("Recreate the GPU device").clicked() {
                    actions.push(UiAction::RecreateDevice);
                }
            });
        });
    }

    if c.curves.is_some() {
        let hour = c.hour;
        let mut close = false;
        egui::Panel::bottom("curves").max_size(screen.height() * CURVES_MAX_FRACTION).show(ui, |ui| {
            if let Some(ed) = c.curves.as_mut() {
                for a in super::curve_editor::show(ui, ed, hour, sky.hours_per_day).actions {
                    match a {
                        super::curve_editor::CurveAction::Edited => actions.push(UiAction::CurvesEdited),
                        super::curve_editor::CurveAction::Close => close = true,
                        super::curve_editor::CurveAction::Bake { from, to } => actions.push(UiAction::CurvesBake { from, to }),
                    }
                }
            }
        });
        if close {
            c.curves_closed.extend(c.curves.take());
        }
    }

    // What the panels leave is the sky's, on whole pixels so the sky's copy and the paint around
    // it meet without a gap.
    let ppp = ui.ctx().pixels_per_point();
    let surface = ((screen.width() * ppp).round() as u32, (screen.height() * ppp).round() as u32);
    // A panel whose content is wider than its range grows past it this frame, over what egui
    // leaves for the centre: the sky ends where the panels drawn end.
    let available = ui.available_rect_before_wrap();
    let available = egui::Rect::from_min_max(
        egui::pos2(available.min.x.max(screen.min.x + left_width), available.min.y),
        egui::pos2(available.max.x.min(screen.max.x - right_width), available.max.y),
    );
    let sky_rect = SkyViewport::from_points(available, ppp, surface).to_points(ppp);
    let fill = ui.visuals().panel_fill;
    ui.painter().set(background, egui::Shape::Vec(around(screen, sky_rect).into_iter().map(|r| egui::Shape::rect_filled(r, 0.0, fill)).collect()));

    if let (Some(target), Some(tex)) = (c.inspect.clone(), inspector_texture) {
        let mut open = true;
        egui::Window::new("Bitmap inspector").open(&mut open).show(ui.ctx(), |ui| {
            ui.horizontal(|ui| {
                ui.label(&target.label);
                edit_button(ui, c, sky, &target.bitmap, target.label.clone(), false);
            });
            let b = &target.bitmap;
            let scale = (360.0 / b.width as f32).min(120.0 / b.height as f32).max(1.0);
            let size = egui::vec2(b.width as f32 * scale, b.height as f32 * scale);
            let response = ui.add(egui::Image::new((tex, size)).fit_to_exact_size(size));
            let (x, y) = b.sample_position(c.hour, sky.hours_per_day, c.weather);
            // Texel centres: the sample at x sits x texels from the left edge of column 0's centre.
            let p = response.rect.min + egui::vec2((x + 0.5) * scale, (y + 0.5) * scale);
            ui.painter().circle_stroke(p, 5.0, egui::Stroke::new(2.0, Color32::RED));
            let v = b.sample(c.hour, sky.hours_per_day, c.weather);
            ui.horizontal(|ui| {
                swatch(ui, v);
                ui.label(format!("({x:.2}, {y:.2}) -> rgba {:.3} {:.3} {:.3} {:.3}", v[0], v[1], v[2], v[3]));
            });
        });
        if !open {
            c.inspect = None;
        }
    }

    if c.show_help {
        egui::Window::new("Keyboard shortcuts").open(&mut c.show_help).show(ui.ctx(), |ui| {
            egui::Grid::new("shortcuts").striped(true).show(ui, |ui| {
                for (k, what) in SHORTCUTS {
                    ui.monospace(k);
                    ui.label(what);
                    ui.end_row();
                }
            });
        });
    }
    UiOutput { actions, sky_rect }
}

/// Label of a sky model in the selector.
fn model_label(kind: SkyModelKind) -> &'static str {
    match kind {
        SkyModelKind::Bitmap => "NeL bitmaps",
        SkyModelKind::Single => "single scattering",
        SkyModelKind::Lut => "LUT multiple scattering",
        SkyModelKind::Precomputed => "precomputed scattering (Bruneton)",
        SkyModelKind::Cells => "cells (CPU, background)",
        SkyModelKind::Reference => "reference (CPU still, background)",
        SkyModelKind::Preetham => "Preetham 1999 (analytic)",
        SkyModelKind::Hosek => "Hosek-Wilkie 2012 (analytic)",
        SkyModelKind::Linear => "Braun-Cohen linear (one colour)",
    }
}

/// The committed model benchmark (docs/models.csv) as in docs/models-cost.svg: mean dE2000
/// against frame cost, both log10, the Pareto front, and the current model's point ringed.
fn model_chart(ui: &mut egui::Ui, current: Option<&str>) {
    let rows = match crate::measure::model_points::rows_from_csv(crate::measure::model_points::COMMITTED_CSV) {
        Ok(r) if !r.is_empty() => r,
        _ => {
            ui.label("no benchmark in this build (run skytune bench models)");
            return;
        }
    };
    let at = |r: &crate::measure::model_points::ChartRow| [r.frame_ms().max(1e-3).log10(), r.error().max(1e-3).log10()];
    let mut front: Vec<[f64; 2]> = rows.iter().filter(|r| r.pareto).map(at).collect();
    front.sort_by(|a, b| a[0].total_cmp(&b[0]));
    ui.label("x: log10 frame ms in which the sun moved; y: log10 mean CIE dE2000 over the dome");
    egui_plot::Plot::new("model_chart").height(220.0).allow_drag(false).allow_scroll(false).show(ui, |p| {
        p.line(egui_plot::Line::new("Pareto front", front));
        for r in &rows {
            let [x, y] = at(r);
            let mine = current == Some(r.id.as_str());
            let colour = if mine {
                egui::Color32::YELLOW
            } else if r.pareto {
                egui::Color32::LIGHT_GREEN
            } else {
                egui::Color32::GRAY
            };
            p.points(egui_plot::Points::new(r.id.clone(), vec![[x, y]]).radius(if mine { 6.0 } else { 3.0 }).color(colour).filled(true));
            p.text(egui_plot::Text::new(r.id.clone(), egui_plot::PlotPoint::new(x, y + 0.04), r.id.clone()).color(colour));
        }
    });
    match current.and_then(|id| rows.iter().find(|r| r.id == id)) {
        Some(r) => ui.label(format!("current: {} - dE2000 {:.2} (p95 {:.2}), PSNR {:.1} dB, {:.1} ms", r.id, r.de_mean, r.de_p95, r.psnr_db, r.frame_ms())),
        None => ui.label("current model: not a benchmark point"),
    };
}

/// The skydome colour source: every model, switchable live, and the physical models' settings.
fn sky_model_controls(ui: &mut egui::Ui, c: &mut Controls, sky: &Sky) {
    let mut model = c.sky_model.unwrap_or(sky.model);
    let before = model;
    ui.label("sky model:");
    egui::ComboBox::from_id_salt("sky_model").selected_text(model_label(model.kind)).show_ui(ui, |ui| {
        for kind in SkyModelKind::ALL {
            ui.selectable_value(&mut model.kind, kind, model_label(kind));
        }
    });
    if model.kind == SkyModelKind::Linear {
        linear_controls(ui, &mut model.settings.linear);
    } else if model.kind.is_physical() {
        ui.checkbox(&mut model.camera.auto_exposure, "automatic exposure (EV below compensates)");
        ui.checkbox(&mut model.drive_scene, "light the scene from the model (fog, ambient, sun)");
        ui.add(egui::Slider::new(&mut model.camera.exposure_ev, -4.0..=12.0).text("exposure (EV)"));
        ui.horizontal_wrapped(|ui| {
            ui.label("tone mapper:");
            for t in ToneMapper::ALL {
                ui.radio_value(&mut model.camera.tone_mapper, t, t.name());
            }
        });
        if model.kind == SkyModelKind::Single {
            ui.horizontal_wrapped(|ui| {
                ui.label("optical depth:");
                ui.radio_value(&mut model.settings.single.optical_depth, OpticalDepth::Erf, "erf");
                ui.radio_value(&mut model.settings.single.optical_depth, OpticalDepth::Numerical, "numerical");
            });
        }
        if matches!(model.kind, SkyModelKind::Preetham | SkyModelKind::Hosek) {
            if ui.add(egui::Slider::new(&mut model.settings.analytic.turbidity, 1.0..=10.0).text("turbidity")).changed() {
                model.settings.analytic.turbidity_from_atmosphere = false;
            }
            if model.kind == SkyModelKind::Hosek {
                ui.add(egui::Slider::new(&mut model.world.ground_albedo, 0.0..=1.0).text("ground albedo"));
            } else if (model.settings.analytic.turbidity as f64) < crate::atmosphere::analytic::PREETHAM_MIN_TURBIDITY {
                ui.label(format!("below {} Preetham's fit goes negative: clamped", crate::atmosphere::analytic::PREETHAM_MIN_TURBIDITY));
            }
        } else if model.kind == SkyModelKind::Reference {
            ui.add(egui::Slider::new(&mut model.settings.reference.paths, 1..=1024).text("paths per direction"));
            ui.add(egui::Slider::new(&mut model.world.ground_albedo, 0.0..=1.0).text("ground albedo"));
        } else if model.kind == SkyModelKind::Cells {
            ui.add(egui::Slider::new(&mut model.settings.cell_iterations, 1..=12).text("iterations"));
            ui.add(egui::Slider::new(&mut model.world.ground_albedo, 0.0..=1.0).text("ground albedo"));
        } else if model.kind == SkyModelKind::Lut {
            ui.add(egui::Slider::new(&mut model.settings.lut.view_steps, 1..=256).text("view steps"));
            ui.add(egui::Slider::new(&mut model.settings.lut.multiscattering_grid, 1..=16).text("multiple-scattering directions (grid)"));
            ui.add(egui::Slider::new(&mut model.world.ground_albedo, 0.0..=1.0).text("ground albedo"));
        } else if model.kind == SkyModelKind::Precomputed {
            // Each change rebuilds the tables (seconds on a software rasteriser).
            ui.add(egui::Slider::new(&mut model.settings.precomputed.orders, 1..=crate::atmosphere::PrecomputedSettings::MAX_ORDERS).text("scattering orders"));
            ui.add(egui::Slider::new(&mut model.world.ground_albedo, 0.0..=1.0).text("ground albedo"));
        } else {
            ui.add(egui::Slider::new(&mut model.settings.single.view_steps, 1..=256).text("view steps"));
            if model.settings.single.optical_depth == OpticalDepth::Numerical {
                ui.add(egui::Slider::new(&mut model.settings.single.sun_steps, 1..=256).text("sun steps"));
            }
        }
    }
    if model != before {
        c.sky_model = Some(model);
    }
    if c.sky_model.is_some() && ui.small_button("use the sky file's model").clicked() {
        c.sky_model = None;
    }
}

/// Braun and Cohen's parameters: the paper's presets, light factors and ramps.
fn linear_controls(ui: &mut egui::Ui, p: &mut crate::atmosphere::analytic::LinearParams) {
    use crate::atmosphere::analytic::{LinearParams, Ramp, LINEAR_PRESETS};
    ui.horizontal_wrapped(|ui| {
        ui.label("preset:");
        for (name, _, _) in LINEAR_PRESETS {
            if ui.small_button(name).clicked() {
                if let Some(preset) = LinearParams::preset(name) {
                    *p =
                        LinearParams { hours_per_day: p.hours_per_day, sunrise_hour: p.sunrise_hour, sunset_hour: p.sunset_hour, ramp_hours: p.ramp_hours, ramp: p.ramp, ..preset };
                }
            }
        }
    });
    for (label, values) in [("min", &mut p.min), ("max", &mut p.max)] {
        ui.horizontal_wrapped(|ui| {
            ui.label(label);
            for v in values.iter_mut() {
                ui.add(egui::DragValue::new(v).range(0.0..=255.0));
            }
        });
    }
    let day = p.hours_per_day;
    ui.add(egui::Slider::new(&mut p.sunrise_hour, 0.0..=day).text("sunrise starts (h)"));
    ui.add(egui::Slider::new(&mut p.sunset_hour, 0.0..=day).text("sunset starts (h)"));
    ui.add(egui::Slider::new(&mut p.ramp_hours, 0.1..=day / 4.0).text("ramp (h)"));
    ui.horizontal_wrapped(|ui| {
        ui.radio_value(&mut p.ramp, Ramp::Linear, "linear ramp");
        ui.radio_value(&mut p.ramp, Ramp::Exponential, "exponential ramp");
    });
}

/// Emitters: toggles, particles alive against their caps, births now, a burst button; the clock.
fn particles(ui: &mut egui::Ui, c: &mut Controls, info: &UiInfo<'_>) {
    let sky = info.sky;
    if sky.emitters.is_empty() {
        return;
    }
    ui.heading("Particles");
    ui.checkbox(&mut c.particles_real_time, "real time (else the time slider drives them, deterministically)");
    let now = c.particle_clock(sky).time_s;
    for (index, e) in sky.emitters.iter().enumerate() {
        let f = info.frame.particles.emitters.iter().find(|f| f.emitter == index);
        let mut on = !c.disabled.contains(&e.name);
        ui.horizontal_wrapped(|ui| {
            if ui.checkbox(&mut on, "").changed() {
                if on {
                    c.disabled.retain(|n| n != &e.name);
                } else {
                    c.disabled.push(e.name.clone());
                }
            }
            let alive = f.map_or(0, |f| f.instances.len());
            let births = if f.is_some_and(|f| f.emitting) { "emitting" } else { "off" };
            ui.label(RichText::new(&e.name).strong());
            match f.and_then(|f| f.gpu.as_ref()) {
                // Evaluated on the GPU: the CPU knows the slots of the last lifetime, not which live.
                Some(g) => ui.label(RichText::new(format!("at most {} / {} alive (GPU), {births}", g.slots as usize + alive, e.max_particles)).small()),
                None => ui.label(RichText::new(format!("{alive} / {} alive, {births}", e.max_particles)).small()),
            };
            if ui.small_button("burst").on_hover_text("births a quarter of the cap now, whatever the emission bitmap says").clicked() {
                c.bursts.push(crate::sky::particles::Burst { emitter: e.name.clone(), time_s: now, count: (e.max_particles / 4).clamp(1, 500) });
            }
        });
    }
    // Bursts older than any particle's life are done.
    let oldest = sky.emitters.iter().map(|e| e.lifetime_s * (1.0 + e.lifetime_spread)).fold(0.0, f32::max) as f64;
    c.bursts.retain(|b| (now - b.time_s) <= oldest && b.time_s <= now);
    ui.separator();
}

fn objects(ui: &mut egui::Ui, c: &mut Controls, info: &UiInfo<'_>) {
    let sky = info.sky;
    for of in &info.frame.objects {
        let o = &sky.objects[of.index];
        let mut on = !c.disabled.contains(&o.name);
        let status = match &of.versions {
            Ok(p) if of.fallback => format!("fallback ({} pass{})", p.len(), if p.len() == 1 { "" } else { "es" }),
            Ok(_) => "standard".to_string(),
            Err(why) => format!("hidden: {why}"),
        };
        // NeL: an object hidden by its ref colour keeps drawing the particles it already emitted.
        let living: usize = info
            .frame
            .particles
            .emitters
            .iter()
            .filter(|f| sky.emitters.get(f.emitter).is_some_and(|e| e.attach == crate::sky::resolved::EmitterAttach::Object(of.index)))
            .map(|f| f.instances.len())
            .sum();
        let status = if of.versions.is_err() && living > 0 { format!("{status}; its {living} particles live on until they die") } else { status };
        let color = if of.versions.is_ok() { Color32::LIGHT_GREEN } else { Color32::from_rgb(230, 170, 90) };
        ui.horizontal_wrapped(|ui| {
            if ui.checkbox(&mut on, "").changed() {
                if on {
                    c.disabled.retain(|n| n != &o.name);
                } else {
                    c.disabled.push(o.name.clone());
                }
            }
            ui.label(RichText::new(format!("[{}] {}", o.priority, o.name)).strong());
        });
        ui.label(RichText::new(status).color(color).small());
        for (pass, dropped) in &of.dropped {
            ui.label(RichText::new(format!("fallback version {pass} dropped: needs {dropped} stages")).small().weak());
        }
        if let Ok(versions) = &of.versions {
            for p in versions {
                let version = if p.version == 0 { &o.standard } else { &o.fallback[p.version - 1] };
                ui.horizontal_wrapped(|ui| {
                    swatch(ui, p.diffuse);
                    let label = format!("{}.{}diffuse", o.name, version_label(p.version));
                    inspect_button(ui, c, &version.diffuse, label.clone());
                    if let Some(b) = &version.diffuse.bitmap {
                        edit_button(ui, c, sky, b, label, false);
                    }
                    for (k, col) in version.constants.iter().enumerate() {
                        swatch(ui, p.constants[k]);
                        let label = format!("{}.{}constants[{k}]", o.name, version_label(p.version));
                        inspect_button(ui, c, col, label.clone());
                        if let Some(b) = &col.bitmap {
                            edit_button(ui, c, sky, b, label, false);
                        }
                    }
                    if let Some(g) = &version.gradients {
                        for (k, b) in g.bitmaps.iter().enumerate() {
                            edit_button_as(ui, c, sky, b, format!("{}.{}gradient[{k}]", o.name, version_label(p.version)), true, &format!("gradient {k}"));
                        }
                    }
                });
            }
        }
        ui.separator();
    }
    particles(ui, c, info);
    ui.label("Sky bitmaps:");
    ui.horizontal_wrapped(|ui| {
        for (name, b) in [("fog_color", &sky.fog_color), ("sun_ambient", &sky.sun_ambient), ("sun_diffuse", &sky.sun_diffuse)] {
            if ui.small_button(name).on_hover_text(format!("inspect {name}")).clicked() {
                c.inspect = Some(InspectTarget { label: name.to_string(), bitmap: b.clone() });
            }
            edit_button(ui, c, sky, b, name.to_string(), false);
        }
    });
    if let Some(e) = &c.curves_error {
        ui.colored_label(Color32::from_rgb(255, 170, 90), e);
    }
    // Every colour bitmap the sky reads from a file (glare, stars, emitters, UV offsets too).
    section(ui, c, "all_bitmaps", "All colour bitmaps", |ui, c| {
        let mut keys: Vec<String> = Sky::clone(sky).color_bitmaps_mut().iter().filter_map(|b| b.source.clone()).collect();
        keys.sort();
        keys.dedup();
        ui.horizontal_wrapped(|ui| {
            for key in keys {
                // Truncated: a long path must not widen the panel over the sky view.
                if ui.add(egui::Button::new(key.as_str()).small().truncate()).on_hover_text(format!("edit {key} as curves over the day")).clicked() {
                    let gradient = matches!(crate::measure::bake::bake_target(sky, &key), Some(crate::measure::bake::BakeTarget::Gradient { .. }));
                    open_curves(c, sky, &key, key.clone(), gradient);
                }
            }
        });
    });
}

fn version_label(v: usize) -> String {
    if v == 0 {
        "standard.".into()
    } else {
        format!("fallback[{}].", v - 1)
    }
}

fn inspect_button(ui: &mut egui::Ui, c: &mut Controls, color: &crate::sky::resolved::Color, label: String) {
    if let (Some(b), ColorMode::Bitmap | ColorMode::BitmapTimesFog) = (&color.bitmap, color.mode) {
        if ui.small_button("inspect").on_hover_text(format!("inspect {label}")).clicked() {
            c.inspect = Some(InspectTarget { label, bitmap: b.clone() });
        }
    }
}

/// The compare window: what B is, the layout, the picture and its figures.
fn compare_window(ui: &mut egui::Ui, c: &mut Controls, info: &CompareInfo, actions: &mut Vec<UiAction>) {
    use super::compare::CompareB;
    use crate::measure::image_diff::Layout;
    let mut open = c.compare.open;
    egui::Window::new("Compare").open(&mut open).default_width(520.0).show(ui.ctx(), |ui| {
        let cc = &mut c.compare;
        ui.horizontal(|ui| {
            ui.label("A: the sky now.  B:");
            egui::ComboBox::from_id_salt("compare_b").selected_text(cc.b.label()).show_ui(ui, |ui| {
                ui.selectable_value(&mut cc.b, CompareB::LastGood, "last good version");
                for s in &info.snapshots {
                    ui.selectable_value(&mut cc.b, CompareB::Snapshot(s.sky_file.clone()), format!("snapshot {}", s.name));
                }
                for k in SkyModelKind::ALL {
                    ui.selectable_value(&mut cc.b, CompareB::Model(k), format!("model {}", k.name()));
                }
                for t in Tier::ALL {
                    ui.selectable_value(&mut cc.b, CompareB::Tier(t), format!("tier {}", t.stages()));
                }
                if ui.selectable_label(matches!(cc.b, CompareB::Hour(_)), "another hour").clicked() && !matches!(cc.b, CompareB::Hour(_)) {
                    cc.b = CompareB::Hour((c.hour + 6.0).rem_euclid(24.0));
                }
                if ui.selectable_label(matches!(cc.b, CompareB::Weather(_)), "another weather").clicked() && !matches!(cc.b, CompareB::Weather(_)) {
                    cc.b = CompareB::Weather(if c.weather < 0.5 { 1.0 } else { 0.0 });
                }
            });
        });
        match &mut cc.b {
            CompareB::Hour(h) => {
                ui.add(egui::Slider::new(h, 0.0..=23.99).text("B's hour"));
            }
            CompareB::Weather(w) => {
                ui.add(egui::Slider::new(w, 0.0..=1.0).text("B's weather"));
            }
            _ => {}
        }
        ui.horizontal(|ui| {
            for (l, name) in [(Layout::Split, "split"), (Layout::SideBySide, "side by side"), (Layout::Difference, "difference (FLIP)")] {
                ui.radio_value(&mut cc.layout, l, name);
            }
        });
        if cc.layout == Layout::Split {
            ui.add(egui::Slider::new(&mut cc.split, 0.0..=1.0).text("split (A left, B right)"));
        }
        ui.horizontal(|ui| {
            if ui.add_enabled(info.has_file, egui::Button::new("Save snapshot (F8)")).on_disabled_hover_text("the built-in sky has no file").clicked() {
                actions.push(UiAction::Snapshot);
            }
            ui.label(RichText::new(format!("{} snapshot(s) in .skytune-snapshots/", info.snapshots.len())).small().weak());
        });
        if let Some(p) = info.progress {
            ui.add(egui::ProgressBar::new(p).show_percentage().text("B is computing in the background"));
        }
        if let Some(e) = &info.error {
            ui.colored_label(Color32::from_rgb(255, 120, 100), e);
        }
        if let Some((texture, size)) = info.texture {
            let width = ui.available_width().min(size[0] as f32 * 2.0);
            let height = width * size[1] as f32 / size[0].max(1) as f32;
            let response = ui.add(egui::Image::new((texture, egui::vec2(width, height))).sense(egui::Sense::drag()));
            // Dragging on the picture moves the split.
            if cc.layout == Layout::Split {
                if let Some(pos) = response.interact_pointer_pos() {
                    cc.split = ((pos.x - response.rect.left()) / response.rect.width()).clamp(0.0, 1.0);
                }
            }
            if cc.layout != Layout::Split {
                ui.horizontal(|ui| {
                    ui.label(RichText::new("FLIP heat map: 0 (black) .. 1 (yellow), ticks every 0.25").small());
                });
            }
        }
        if let Some((b, summary, flip)) = &info.summary {
            ui.label(format!("B = {b}"));
            ui.label(RichText::new(summary).small());
            ui.label(format!("FLIP mean {:.4}, 95th percentile {:.4}, max {:.4}", flip.mean, flip.p95, flip.max));
        }
    });
    c.compare.open = open;
}
