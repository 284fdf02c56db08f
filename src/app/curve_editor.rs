//! The curve editor: one colour bitmap of the sky as R, G, B and alpha curves over the hours of
//! the current weather row (or, for a gradient bitmap, of a chosen position on the dome), a strip
//! of its colours, a marker at the current hour, and the edits of [`BitmapEditor`] behind drags,
//! a colour picker and span tools. The app shows every edit in the next frame
//! ([`crate::sky::Sky::replace_bitmap`]) and writes the file only on Save.

use egui::{Color32, RichText};

use crate::files::bitmap_edit::{BitmapEditor, Edit, EditError};
use crate::sky::bitmap::Rgba;

/// The editor's state in the window.
#[derive(Debug, Clone)]
pub struct CurveEditor {
    /// The bitmap being edited.
    pub editor: BitmapEditor,
    /// What it is in the sky (`sun_diffuse`, `skydome.standard.constants[0]`, ...).
    pub label: String,
    /// A gradient bitmap: rows are positions from the zenith down, not weather steps.
    pub gradient: bool,
    /// The row whose curves show.
    pub row: u32,
    /// The channel a drag on the curves sets (0 r, 1 g, 2 b, 3 a).
    pub channel: usize,
    /// The span of hours the span tools work on, from and to (wrapping past midnight).
    pub span: (f32, f32),
    /// Columns a shift moves the span by.
    pub shift: i32,
    /// Hour the span's end is stretched to.
    pub stretch_to: f32,
    /// Rows to blend (a, b, t) into the shown row.
    pub blend: (u32, u32, f32),
    /// The file changed on disk while there were unsaved edits.
    pub conflict: bool,
    /// The last save's or open's outcome.
    pub message: Option<String>,
}

/// What the editor asks of the app.
#[derive(Debug, Clone, PartialEq)]
pub enum CurveAction {
    /// The bitmap changed: show it.
    Edited,
    /// The editor was closed.
    Close,
    /// Bake the sky's model into columns `from ..= to` (wrapping).
    Bake {
        /// First column.
        from: u32,
        /// Last column.
        to: u32,
    },
}

/// What one frame of the editor produced.
#[derive(Debug, Clone, PartialEq)]
pub struct CurveOutput {
    /// Requests for the app.
    pub actions: Vec<CurveAction>,
    /// Where the curves are, points (drags inside set the chosen channel).
    pub curves_rect: egui::Rect,
}

const CHANNELS: [(&str, Color32); 4] =
    [("R", Color32::from_rgb(235, 80, 80)), ("G", Color32::from_rgb(90, 200, 90)), ("B", Color32::from_rgb(90, 140, 245)), ("A", Color32::from_gray(200))];

impl CurveEditor {
    /// An editor on `editor`'s bitmap, at the weather row of `weather`.
    pub fn new(editor: BitmapEditor, label: String, gradient: bool, weather: f32) -> Self {
        let (w, h) = editor.size();
        let row = if gradient { 0 } else { (weather.clamp(0.0, 1.0) * (h - 1) as f32).round() as u32 };
        Self { editor, label, gradient, row, channel: 0, span: (0.0, 0.0), shift: 1, stretch_to: 0.0, blend: (0, h.saturating_sub(1), 0.5), conflict: false, message: None }
            .with_width(w)
    }

    fn with_width(mut self, _w: u32) -> Self {
        self.span = (6.0, 9.0);
        self.stretch_to = 10.0;
        self
    }

    /// Saves, refusing over a change on disk unless `overwrite`.
    pub fn save(&mut self, overwrite: bool) {
        match self.editor.save(overwrite) {
            Ok(()) => {
                self.conflict = false;
                self.message = Some(format!("saved {}", self.editor.path().display()));
            }
            Err(e @ EditError::Conflict { .. }) => {
                self.conflict = true;
                self.message = Some(e.to_string());
            }
            Err(e) => self.message = Some(format!("not saved: {e}")),
        }
    }
}

fn to32(c: Rgba) -> Color32 {
    let q = |v: f32| (v.clamp(0.0, 1.0) * 255.0).round() as u8;
    Color32::from_rgb(q(c[0]), q(c[1]), q(c[2]))
}

/// Draws the editor into `ui`; `hour` is the time slider's, `hours_per_day` the sky's.
pub fn show(ui: &mut egui::Ui, ed: &mut CurveEditor, hour: f32, hours_per_day: f32) -> CurveOutput {
    let mut actions = Vec::new();
    let (w, h) = ed.editor.size();
    let edited = |ed: &mut CurveEditor, edit: Edit, merge: bool, actions: &mut Vec<CurveAction>| {
        let before = ed.editor.revision();
        ed.editor.apply(&edit, merge);
        if ed.editor.revision() != before {
            actions.push(CurveAction::Edited);
        }
    };
    ui.horizontal_wrapped(|ui| {
        let file = ed.editor.path().file_name().map_or_else(String::new, |n| n.to_string_lossy().into_owned());
        ui.label(RichText::new(format!("{}  ({file}{})", ed.label, if ed.editor.is_dirty() { ", unsaved" } else { "" })).strong());
        let (can_undo, can_redo) = ed.editor.can_undo_redo();
        // Redo's keys first: Ctrl+Z alone would also match Ctrl+Shift+Z.
        let redo_key = ui.input_mut(|i| i.consume_key(egui::Modifiers::COMMAND | egui::Modifiers::SHIFT, egui::Key::Z));
        let undo_key = ui.input_mut(|i| i.consume_key(egui::Modifiers::COMMAND, egui::Key::Z));
        if (ui.add_enabled(can_undo, egui::Button::new("Undo")).on_hover_text("Ctrl+Z").clicked() || undo_key) && ed.editor.undo() {
            actions.push(CurveAction::Edited);
        }
        if (ui.add_enabled(can_redo, egui::Button::new("Redo")).on_hover_text("Ctrl+Shift+Z").clicked() || redo_key) && ed.editor.redo() {
            actions.push(CurveAction::Edited);
        }
        if ui.button("Save").clicked() {
            ed.save(false);
        }
        if ui.button("Close").clicked() {
            actions.push(CurveAction::Close);
        }
        let what = if ed.gradient { "position (0 = zenith)" } else { "weather row" };
        ui.add(egui::DragValue::new(&mut ed.row).range(0..=h - 1).prefix(format!("{what} ")));
        ui.label("drag sets:");
        for (k, (name, colour)) in CHANNELS.iter().enumerate() {
            ui.radio_value(&mut ed.channel, k, RichText::new(*name).color(*colour));
        }
        if let Some(m) = &ed.message {
            ui.label(RichText::new(m).small());
        }
    });
    if ed.conflict {
        ui.horizontal_wrapped(|ui| {
            ui.colored_label(Color32::from_rgb(255, 170, 90), format!("{} changed on disk while you had unsaved edits.", ed.editor.path().display()));
            if ui.button("Keep mine (save over it)").clicked() {
                ed.save(true);
            }
            if ui.button("Take the file's (mine stay in undo)").clicked() {
                match ed.editor.take_disk_version() {
                    Ok(()) => {
                        ed.conflict = false;
                        ed.message = Some("took the file's version; Undo brings yours back".into());
                        actions.push(CurveAction::Edited);
                    }
                    Err(e) => ed.message = Some(e.to_string()),
                }
            }
        });
    }
    let row = ed.row.min(h - 1);
    let hour_of = |x: f32| x * hours_per_day / w as f32;
    // The curves: columns at their hours, and column 0 again at the day's end (the wrap).
    let gradient_width = if ed.gradient { 28.0 } else { 0.0 };
    let size = egui::vec2((ui.available_width() - gradient_width - 8.0).max(120.0), 64.0);
    let (curves_rect, response) = ui.allocate_exact_size(size, egui::Sense::click_and_drag());
    let painter = ui.painter_at(curves_rect.expand(2.0));
    painter.rect_filled(curves_rect, 2.0, Color32::from_gray(24));
    let to_screen =
        |hour: f32, v: f32| egui::pos2(curves_rect.left() + hour / hours_per_day * curves_rect.width(), curves_rect.bottom() - v.clamp(0.0, 1.0) * curves_rect.height());
    for (k, (_, colour)) in CHANNELS.iter().enumerate() {
        let mut points: Vec<egui::Pos2> = (0..w).map(|x| to_screen(hour_of(x as f32), ed.editor.texel(x, row)[k])).collect();
        points.push(to_screen(hours_per_day, ed.editor.texel(0, row)[k]));
        let stroke = egui::Stroke::new(if k == ed.channel { 2.0 } else { 1.0 }, *colour);
        painter.add(egui::Shape::line(points.clone(), stroke));
        if k == ed.channel {
            for p in &points[..points.len() - 1] {
                painter.circle_filled(*p, 2.5, *colour);
            }
        }
    }
    let now = to_screen(hour.rem_euclid(hours_per_day), 0.0).x;
    painter.line_segment([egui::pos2(now, curves_rect.top()), egui::pos2(now, curves_rect.bottom())], egui::Stroke::new(1.0, Color32::YELLOW));
    if let Some(p) = response.interact_pointer_pos() {
        if response.dragged() || response.drag_started() || response.clicked() {
            let hour = ((p.x - curves_rect.left()) / curves_rect.width() * hours_per_day).clamp(0.0, hours_per_day);
            let x = ed.editor.column_of_hour(hour, hours_per_day);
            let value = (curves_rect.bottom() - p.y) / curves_rect.height();
            edited(ed, Edit::SetChannel { x, y: row, channel: ed.channel, value }, !response.drag_started() && !response.clicked(), &mut actions);
        }
    }
    // The colours themselves, column by column.
    let (strip, _) = ui.allocate_exact_size(egui::vec2(size.x, 10.0), egui::Sense::hover());
    for x in 0..w {
        let x0 = strip.left() + x as f32 / w as f32 * strip.width();
        let x1 = strip.left() + (x + 1) as f32 / w as f32 * strip.width();
        ui.painter().rect_filled(egui::Rect::from_min_max(egui::pos2(x0, strip.top()), egui::pos2(x1, strip.bottom())), 0.0, to32(ed.editor.texel(x, row)));
    }
    if ed.gradient {
        // The gradient at the current hour, zenith at the top.
        let column = ed.editor.column_of_hour(hour, hours_per_day);
        let left = curves_rect.right() + 8.0;
        for y in 0..h {
            let top = curves_rect.top() + y as f32 / h as f32 * curves_rect.height();
            let bottom = curves_rect.top() + (y + 1) as f32 / h as f32 * curves_rect.height();
            ui.painter().rect_filled(egui::Rect::from_min_max(egui::pos2(left, top), egui::pos2(left + gradient_width - 8.0, bottom)), 0.0, to32(ed.editor.texel(column, y)));
        }
    }
    ui.horizontal_wrapped(|ui| {
        let x = ed.editor.column_of_hour(hour, hours_per_day);
        let mut colour = ed.editor.texel(x, row);
        ui.label(format!("at {:.2} h (column {x}):", hour_of(x as f32)));
        if ui.color_edit_button_rgba_unmultiplied(&mut colour).changed() {
            edited(ed, Edit::SetColor { x, y: row, rgba: colour }, false, &mut actions);
        }
        if h > 1 && ui.button("to every row").on_hover_text("copy this hour's colour to the other rows").clicked() {
            let to_rows = (0..h).filter(|r| *r != row).collect();
            edited(ed, Edit::CopyColumn { x, from_row: row, to_rows }, false, &mut actions);
        }
        ui.separator();
        ui.label("hours");
        ui.add(egui::DragValue::new(&mut ed.span.0).range(0.0..=hours_per_day).speed(0.1));
        ui.label("to");
        ui.add(egui::DragValue::new(&mut ed.span.1).range(0.0..=hours_per_day).speed(0.1));
        let (from, to) = (ed.editor.column_of_hour(ed.span.0, hours_per_day), ed.editor.column_of_hour(ed.span.1, hours_per_day));
        if ui.button("smooth").clicked() {
            edited(ed, Edit::Smooth { y: row, from, to, passes: 1 }, false, &mut actions);
        }
        ui.add(egui::DragValue::new(&mut ed.shift).range(-(w as i32)..=w as i32).suffix(" columns"));
        if ui.button("shift").clicked() {
            edited(ed, Edit::Shift { y: row, from, to, by: ed.shift }, false, &mut actions);
        }
        if ui.button("bake model").on_hover_text("the sky model's colours over these hours (skytune bake's), as one edit").clicked() {
            actions.push(CurveAction::Bake { from, to });
        }
        ui.add(egui::DragValue::new(&mut ed.stretch_to).range(0.0..=hours_per_day).speed(0.1).prefix("end at "));
        if ui.button("stretch").clicked() {
            let new_to = ed.editor.column_of_hour(ed.stretch_to, hours_per_day);
            edited(ed, Edit::Stretch { y: row, from, to, new_to }, false, &mut actions);
        }
        if h > 1 {
            ui.separator();
            ui.add(egui::DragValue::new(&mut ed.blend.0).range(0..=h - 1).prefix("blend row "));
            ui.add(egui::DragValue::new(&mut ed.blend.1).range(0..=h - 1).prefix("and "));
            ui.add(egui::DragValue::new(&mut ed.blend.2).range(0.0..=1.0).speed(0.01).prefix("t "));
            if ui.button("into this row").clicked() {
                let (a, b, t) = ed.blend;
                edited(ed, Edit::BlendRows { a, b, t, into: row }, false, &mut actions);
            }
        }
    });
    CurveOutput { actions, curves_rect }
}
