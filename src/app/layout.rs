//! The window's layout: side panels that leave the sky the largest part of the window, sections
//! that open and close, what of it is remembered between runs, and the sky view's rectangle.
//!
//! The panels take at most [`PANELS_MAX_FRACTION`] of the window's width together, so the sky
//! view keeps at least the rest at every size; Tab hides them all. The sky is rendered at the
//! view's own size and placed there (see [`SkyViewport`]), so what the artist sees is the frame a
//! headless render of that size gives.

use serde::{Deserialize, Serialize};

/// Largest share of the window's width the side panels take together.
pub const PANELS_MAX_FRACTION: f32 = 0.36;
/// Narrowest a side panel gets, points (below this its text is unreadable).
pub const PANEL_MIN_WIDTH: f32 = 120.0;
/// Largest share of the window's height the errors panel takes.
pub const ERRORS_MAX_FRACTION: f32 = 0.3;

/// The panels' layout, kept with the window state.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct PanelLayout {
    /// Width of the controls panel (left), points, as last dragged.
    pub left_width: f32,
    /// Width of the objects panel (right), points.
    pub right_width: f32,
    /// The controls panel is shown.
    pub left_open: bool,
    /// The objects panel is shown.
    pub right_open: bool,
    /// Every panel is hidden (Tab), whatever the two above say.
    pub hidden: bool,
    /// Keys of the sections that are open.
    pub open_sections: Vec<String>,
}

impl Default for PanelLayout {
    fn default() -> Self {
        Self { left_width: 260.0, right_width: 200.0, left_open: true, right_open: true, hidden: false, open_sections: Vec::new() }
    }
}

impl PanelLayout {
    /// Whether the section `key` is open.
    pub fn is_open(&self, key: &str) -> bool {
        self.open_sections.iter().any(|k| k == key)
    }

    /// Opens or closes the section `key`.
    pub fn set_open(&mut self, key: &str, open: bool) {
        self.open_sections.retain(|k| k != key);
        if open {
            self.open_sections.push(key.to_string());
        }
    }

    /// Tab: hides every panel, or shows both again.
    pub fn toggle_hidden(&mut self) {
        if self.hidden || !(self.left_open || self.right_open) {
            (self.hidden, self.left_open, self.right_open) = (false, true, true);
        } else {
            self.hidden = true;
        }
    }

    /// Whether the controls panel shows this frame.
    pub fn shows_left(&self) -> bool {
        self.left_open && !self.hidden
    }

    /// Whether the objects panel shows this frame.
    pub fn shows_right(&self) -> bool {
        self.right_open && !self.hidden
    }

    /// The width range of the controls panel in a window `window_width` points wide: with the
    /// objects panel shown, the two share [`PANELS_MAX_FRACTION`] of the width (in proportion to
    /// their widths when both do not fit), else it may take all of it.
    pub fn left_range(&self, window_width: f32) -> (f32, f32) {
        let total = (window_width * PANELS_MAX_FRACTION).max(1.0);
        let (left, right) = (self.left_width.max(1.0), self.right_width.max(1.0));
        let max = match self.shows_right() {
            false => total,
            true if left + right > total => total * left / (left + right),
            true => total - right,
        };
        (PANEL_MIN_WIDTH.min(max), max)
    }

    /// The width range of the objects panel, once the controls panel took `left` points.
    pub fn right_range(&self, window_width: f32, left: f32) -> (f32, f32) {
        let total = (window_width * PANELS_MAX_FRACTION).max(1.0);
        let max = (total - if self.shows_left() { left } else { 0.0 }).max(1.0);
        (PANEL_MIN_WIDTH.min(max), max)
    }
}

/// Where the sky is drawn in the window, pixels: the part the panels leave.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SkyViewport {
    /// Left edge, pixels from the window's left.
    pub x: u32,
    /// Top edge, pixels from the window's top.
    pub y: u32,
    /// Width, pixels (at least 1).
    pub width: u32,
    /// Height, pixels (at least 1).
    pub height: u32,
}

impl SkyViewport {
    /// The whole surface.
    pub fn full(size: (u32, u32)) -> Self {
        Self { x: 0, y: 0, width: size.0.max(1), height: size.1.max(1) }
    }

    /// The pixels of `rect` (points, at `pixels_per_point`) inside a surface of `size`, edges
    /// rounded to whole pixels; never empty, so a window squeezed to nothing still renders.
    pub fn from_points(rect: egui::Rect, pixels_per_point: f32, size: (u32, u32)) -> Self {
        let (w, h) = (size.0.max(1), size.1.max(1));
        let px = |v: f32, max: u32| ((v * pixels_per_point).round().max(0.0) as u32).min(max);
        let (x0, y0) = (px(rect.min.x, w - 1), px(rect.min.y, h - 1));
        let (x1, y1) = (px(rect.max.x, w).max(x0 + 1), px(rect.max.y, h).max(y0 + 1));
        Self { x: x0, y: y0, width: x1 - x0, height: y1 - y0 }
    }

    /// Whether it covers the whole surface of `size`.
    pub fn is_full(&self, size: (u32, u32)) -> bool {
        *self == Self::full(size)
    }

    /// Its share of a surface of `size`, 0..1.
    pub fn share_of(&self, size: (u32, u32)) -> f64 {
        (self.width as f64 * self.height as f64) / (size.0.max(1) as f64 * size.1.max(1) as f64)
    }

    /// Its rectangle in points.
    pub fn to_points(self, pixels_per_point: f32) -> egui::Rect {
        let p = |v: u32| v as f32 / pixels_per_point;
        egui::Rect::from_min_max(egui::pos2(p(self.x), p(self.y)), egui::pos2(p(self.x + self.width), p(self.y + self.height)))
    }
}

/// The parts of `screen` outside `sky` (up to four rectangles), to paint under the panels: the
/// surface keeps last frame's pixels there, and the sky is copied into `sky` alone.
pub fn around(screen: egui::Rect, sky: egui::Rect) -> Vec<egui::Rect> {
    let sky = sky.intersect(screen);
    let parts = [
        egui::Rect::from_min_max(screen.min, egui::pos2(screen.max.x, sky.min.y)),
        egui::Rect::from_min_max(egui::pos2(screen.min.x, sky.max.y), screen.max),
        egui::Rect::from_min_max(egui::pos2(screen.min.x, sky.min.y), egui::pos2(sky.min.x, sky.max.y)),
        egui::Rect::from_min_max(egui::pos2(sky.max.x, sky.min.y), egui::pos2(screen.max.x, sky.max.y)),
    ];
    parts.into_iter().filter(|r| r.width() > 0.0 && r.height() > 0.0).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn panels_leave_the_sky_most_of_the_width_at_every_size() {
        for layout in [PanelLayout::default(), PanelLayout { left_width: 900.0, right_width: 700.0, ..PanelLayout::default() }] {
            for width in [400.0f32, 800.0, 1280.0, 1920.0, 3840.0] {
                let (l_min, l_max) = layout.left_range(width);
                let left = layout.left_width.clamp(l_min, l_max);
                let (r_min, r_max) = layout.right_range(width, left);
                let right = layout.right_width.clamp(r_min, r_max);
                assert!(left + right <= width * PANELS_MAX_FRACTION + 0.01, "{width}: {left} + {right}");
                assert!(l_min <= l_max && r_min <= r_max);
                if width >= 1920.0 && layout == PanelLayout::default() {
                    assert_eq!((left, right), (layout.left_width, layout.right_width), "room for both as they are");
                }
            }
        }
        // One panel alone may take the whole share.
        let one = PanelLayout { right_open: false, left_width: 900.0, ..PanelLayout::default() };
        assert_eq!(one.left_range(1000.0).1, 360.0);
    }

    #[test]
    fn tab_hides_and_shows_every_panel() {
        let mut l = PanelLayout::default();
        l.toggle_hidden();
        assert!(!l.shows_left() && !l.shows_right());
        l.toggle_hidden();
        assert!(l.shows_left() && l.shows_right());
        l.left_open = false;
        l.right_open = false;
        l.toggle_hidden();
        assert!(l.shows_left() && l.shows_right(), "with both closed, Tab opens them");
    }

    #[test]
    fn the_viewport_is_whole_pixels_inside_the_surface() {
        let r = egui::Rect::from_min_max(egui::pos2(290.4, 0.0), egui::pos2(1050.6, 720.0));
        let v = SkyViewport::from_points(r, 1.0, (1280, 720));
        assert_eq!(v, SkyViewport { x: 290, y: 0, width: 761, height: 720 });
        let squeezed = SkyViewport::from_points(egui::Rect::from_min_max(egui::pos2(2000.0, 10.0), egui::pos2(2000.0, 10.0)), 2.0, (1280, 720));
        assert!(squeezed.x + squeezed.width <= 1280 && squeezed.width >= 1 && squeezed.height >= 1);
        assert!(SkyViewport::full((1280, 720)).is_full((1280, 720)));
        let screen = egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1280.0, 720.0));
        let parts = around(screen, v.to_points(1.0));
        let area: f32 = parts.iter().map(|p| p.area()).sum();
        assert!((area + v.to_points(1.0).area() - screen.area()).abs() < 1e-3, "{parts:?}");
    }
}
