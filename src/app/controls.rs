//! What the panels read and write: the user's controls (kept across frames, saved with the
//! window's layout), the facts a frame gives the panels, and the sections that keep their open
//! state in the controls. Both the panels ([`super::ui`]) and their statistics section
//! ([`super::diagnostics`]) build on these.

use std::collections::VecDeque;
use std::path::PathBuf;
use std::sync::Arc;

use crate::render::passes::glare::GlareState;
use crate::render::{Camera, FrameStats, RenderOptions};
use crate::sky::bitmap::ColorBitmap;
use crate::sky::eval::{FrameSky, Tier};
use crate::sky::resolved::SkyModel;
use crate::sky::Sky;

use super::layout::PanelLayout;

/// Everything the user controls from the panels and the keyboard.
#[derive(Debug, Clone)]
pub struct Controls {
    /// Time of day, game hours.
    pub hour: f32,
    /// Total game hours elapsed (panners).
    pub game_hours: f64,
    /// Weather 0..1.
    pub weather: f32,
    /// Time runs.
    pub playing: bool,
    /// Game hours per real second while playing.
    pub speed: f32,
    /// Emulated GPU tier.
    pub tier: Tier,
    /// Season index (continent files).
    pub season: usize,
    /// Camera.
    pub camera: Camera,
    /// Scene, depth split, glare.
    pub options: RenderOptions,
    /// Median frame time with every skip on, taken when one was switched off.
    pub skips_baseline_ms: Option<f32>,
    /// Objects switched off.
    pub disabled: Vec<String>,
    /// Help overlay open.
    pub show_help: bool,
    /// Bitmap inspector target: (label, object index or None for the sky's own bitmaps, slot).
    pub inspect: Option<InspectTarget>,
    /// Text of the "open" field.
    pub path_input: String,
    /// Contact sheet grid: hours x weathers.
    pub sheet_grid: (u32, u32),
    /// Keep the glare's measured visibility as it is.
    pub freeze_glare: bool,
    /// Skydome colour source chosen in the panel instead of the sky file's (None: the file's).
    pub sky_model: Option<SkyModel>,
    /// The compare view.
    pub compare: super::compare::CompareControls,
    /// Particles run in real time (else their time follows the time slider, deterministically).
    pub particles_real_time: bool,
    /// Real seconds of particle time so far (real-time mode).
    pub particle_time_s: f64,
    /// Bursts asked for with the burst buttons, recent ones.
    pub bursts: Vec<crate::sky::particles::Burst>,
    /// Panel widths, which panels and sections are open (kept with the window state).
    pub layout: PanelLayout,
    /// The curve editor, when a bitmap is open in it.
    pub curves: Option<Box<super::curve_editor::CurveEditor>>,
    /// Why a bitmap could not be opened in the curve editor.
    pub curves_error: Option<String>,
    /// Bitmaps edited earlier in this window and closed or switched away from: reopening one
    /// brings its undo history back.
    pub curves_closed: Vec<Box<super::curve_editor::CurveEditor>>,
}

impl Controls {
    /// The particles' clock for this frame: real seconds, or the slider's game hours.
    pub fn particle_clock(&self, sky: &crate::sky::Sky) -> crate::sky::particles::ParticleClock {
        use crate::sky::particles::ParticleClock;
        if self.particles_real_time {
            ParticleClock { time_s: self.particle_time_s, hours_per_s: if self.playing { self.speed as f64 } else { 0.0 } }
        } else {
            ParticleClock { time_s: self.game_hours * sky.particle_seconds_per_hour as f64, hours_per_s: 1.0 / sky.particle_seconds_per_hour as f64 }
        }
    }
}

impl Default for Controls {
    fn default() -> Self {
        Self {
            hour: 17.5,
            game_hours: 17.5,
            weather: 0.1,
            playing: false,
            speed: 0.25,
            tier: Tier::FOUR,
            season: 1,
            camera: Camera::default(),
            options: RenderOptions::default(),
            disabled: Vec::new(),
            show_help: false,
            inspect: None,
            path_input: String::new(),
            sheet_grid: (8, 4),
            freeze_glare: false,
            sky_model: None,
            compare: Default::default(),
            particles_real_time: true,
            particle_time_s: 0.0,
            bursts: Vec::new(),
            skips_baseline_ms: None,
            layout: PanelLayout::default(),
            curves: None,
            curves_error: None,
            curves_closed: Vec::new(),
        }
    }
}

/// A colour bitmap picked in the inspector.
#[derive(Debug, Clone, PartialEq)]
pub struct InspectTarget {
    /// What is shown, e.g. `skydome.standard.constants[0]`.
    pub label: String,
    /// The bitmap.
    pub bitmap: Arc<ColorBitmap>,
}

/// What the compare window shows.
pub struct CompareInfo {
    /// The composed picture and its size, once a comparison exists.
    pub texture: Option<(egui::TextureId, [usize; 2])>,
    /// What B was, the summary line and the FLIP figures of the latest comparison.
    pub summary: Option<(String, String, crate::measure::image_diff::FlipSummary)>,
    /// Progress of B computing in the background.
    pub progress: Option<f32>,
    /// Why the comparison could not be made.
    pub error: Option<String>,
    /// Snapshots of the sky file.
    pub snapshots: Vec<crate::files::snapshot::Snapshot>,
    /// Whether the sky shown has a file (snapshots need one).
    pub has_file: bool,
}

/// Read-only facts for the panels.
pub struct UiInfo<'a> {
    /// Current sky.
    pub sky: &'a Sky,
    /// Its evaluation this frame.
    pub frame: &'a FrameSky,
    /// Renderer counters.
    pub stats: &'a FrameStats,
    /// Glare state, if any.
    pub glare: Option<&'a GlareState>,
    /// Errors to show (reload, shaders, GPU).
    pub errors: &'a [String],
    /// Adapter description.
    pub adapter: &'a str,
    /// The fill strategy the adapter defaults to ([`crate::render::FillStrategy::for_device`]).
    pub adapter_strategy: crate::render::FillStrategy,
    /// What is shown (path or "default").
    pub source: &'a str,
    /// Whether the source is a continent file.
    pub continent: bool,
    /// Recent files.
    pub recent: &'a [PathBuf],
    /// Frame times, ms, oldest first.
    pub frame_times_ms: &'a VecDeque<f32>,
    /// CPU time per frame section, ms.
    pub cpu_ms: &'a [(&'static str, f32)],
    /// GPU time per phase, ms (when timestamp queries work).
    pub gpu_ms: &'a [(&'static str, f32)],
    /// Contact sheet progress (done, total).
    pub sheet_progress: Option<(usize, usize)>,
    /// Last capture message.
    pub last_capture: &'a str,
    /// Progress (0..1) of a sky model computed in the background, while it runs.
    pub model_progress: Option<f32>,
    /// The compare window's content, when it is open.
    pub compare: Option<CompareInfo>,
    /// The GPU device was lost (the errors panel offers to recreate it).
    pub device_lost: bool,
    /// The fill-rate floor at the window's size, ms (see `render::passes::baseline`), once measured.
    pub floor_ms: Option<f32>,
    /// `kind = "auto"`: the pick (model, error, cost, runner-up), what is shown meanwhile, or why
    /// there is none.
    pub auto_model: Option<String>,
    /// `kind = "auto"`: progress (0..1) and stage of the pick being measured on a worker.
    pub auto_progress: Option<(f32, String)>,
    /// `kind = "auto"`: the picked point's id on the benchmark chart.
    pub auto_point: Option<String>,
}

/// A collapsible section whose open state lives in the controls' layout (so it is remembered),
/// under `key`; `body` gets the controls back.
pub fn section<R>(ui: &mut egui::Ui, c: &mut Controls, key: &str, title: impl Into<egui::WidgetText>, body: impl FnOnce(&mut egui::Ui, &mut Controls) -> R) -> Option<R> {
    let open = c.layout.is_open(key);
    let response = egui::CollapsingHeader::new(title).id_salt(key).open(Some(open)).show(ui, |ui| body(ui, c));
    if response.header_response.clicked() {
        c.layout.set_open(key, !open);
    }
    response.body_returned
}
