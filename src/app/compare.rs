//! The app's compare view: the current view rendered twice, A (the sky as it is now) and B (its
//! last good version, a snapshot, another sky model, another GPU tier or another hour), shown side
//! by side, as a draggable split or as a FLIP heat map, with the frame's figures. Renders go
//! through [`Headless`] at a reduced size and only when something changed; a B that computes in
//! the background (the reference model) shows a progress bar and never blocks the window.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};

use crate::measure::image_diff::{self, Difference, Layout};
use crate::render::{Camera, GpuContext, Headless, RenderOptions, ShaderLibrary};
use crate::sky::resolved::SkyModelKind;
use crate::sky::{FrameInput, Sky, Tier};

/// What side B shows.
#[derive(Debug, Clone, PartialEq)]
pub enum CompareB {
    /// The sky before the last successful reload.
    LastGood,
    /// A saved snapshot's sky file.
    Snapshot(PathBuf),
    /// The same sky with another sky model.
    Model(SkyModelKind),
    /// The same sky at another GPU tier.
    Tier(Tier),
    /// The same sky at another hour.
    Hour(f32),
    /// The same sky in another weather.
    Weather(f32),
}

impl CompareB {
    /// Parses `last-good`, `model=NAME`, `tier=N`, `hour=H`, `weather=W` or `snapshot=NAME` (a snapshot of
    /// `sky_file`).
    pub fn parse(s: &str, sky_file: Option<&std::path::Path>) -> Result<Self, String> {
        if s == "last-good" {
            return Ok(CompareB::LastGood);
        }
        let (key, value) = s.split_once('=').ok_or_else(|| format!("expected last-good, model=NAME, tier=N, hour=H or snapshot=NAME, found \"{s}\""))?;
        match key {
            "model" => SkyModelKind::ALL.into_iter().find(|k| k.name() == value).map(CompareB::Model).ok_or_else(|| format!("unknown model \"{value}\"")),
            "tier" => value.parse().ok().and_then(Tier::new).map(CompareB::Tier).ok_or_else(|| format!("tier: expected 4, 2 or 1, found \"{value}\"")),
            "hour" => value.parse::<f32>().ok().filter(|h| h.is_finite()).map(CompareB::Hour).ok_or_else(|| format!("hour: expected a number, found \"{value}\"")),
            "weather" => value.parse::<f32>().ok().filter(|w| (0.0..=1.0).contains(w)).map(CompareB::Weather).ok_or_else(|| format!("weather: expected 0..1, found \"{value}\"")),
            "snapshot" => {
                let file = sky_file.ok_or("snapshots need a sky file")?;
                crate::files::snapshot::list(file)
                    .into_iter()
                    .find(|snap| snap.name == value)
                    .map(|snap| CompareB::Snapshot(snap.sky_file))
                    .ok_or_else(|| format!("no snapshot \"{value}\" next to {}", file.display()))
            }
            _ => Err(format!("unknown key \"{key}\"")),
        }
    }

    /// Short description for the panel.
    pub fn label(&self) -> String {
        match self {
            CompareB::LastGood => "last good version".into(),
            CompareB::Snapshot(p) => format!("snapshot {}", p.parent().and_then(|d| d.file_name()).map_or_else(|| p.display().to_string(), |n| n.to_string_lossy().into_owned())),
            CompareB::Model(k) => format!("model {}", k.name()),
            CompareB::Tier(t) => format!("tier {}", t.stages()),
            CompareB::Hour(h) => format!("hour {h:.2}"),
            CompareB::Weather(w) => format!("weather {w:.2}"),
        }
    }
}

/// The compare view's settings (part of the panels' controls).
#[derive(Debug, Clone, PartialEq)]
pub struct CompareControls {
    /// The compare window is open.
    pub open: bool,
    /// What B is.
    pub b: CompareB,
    /// How the two are shown.
    pub layout: Layout,
    /// Position of the split, 0..1 of the width.
    pub split: f32,
}

impl Default for CompareControls {
    fn default() -> Self {
        Self { open: false, b: CompareB::Model(SkyModelKind::Lut), layout: Layout::Split, split: 0.5 }
    }
}

/// Size of each side's render, pixels.
pub const COMPARE_SIZE: (u32, u32) = (480, 270);
/// Shortest time between two comparisons while the inputs keep changing (time playing).
const MIN_INTERVAL: Duration = Duration::from_millis(500);

/// The latest comparison.
pub struct CompareResult {
    /// Side A's render.
    pub a: image::RgbaImage,
    /// Side B's render.
    pub b: image::RgbaImage,
    /// Their difference.
    pub diff: Difference,
    /// What B was.
    pub b_label: String,
}

/// The compare view's renderers and its latest result.
#[derive(Default)]
pub struct CompareView {
    /// Renderers of A and B, and which sky each holds.
    sides: Option<[(Headless, Option<u64>); 2]>,
    /// The inputs the result (or the render in progress) shows.
    key: Option<String>,
    last_run: Option<Instant>,
    /// B is computing in the background.
    pub pending: bool,
    /// Progress of B's background work (0..1), while pending.
    pub progress: Option<f32>,
    /// The latest comparison.
    pub result: Option<CompareResult>,
    /// Why the last comparison could not be made.
    pub error: Option<String>,
    /// A snapshot's sky, loaded once per path.
    snapshot: Option<(PathBuf, Arc<Sky>)>,
    /// The texture showing the composed picture, and the (layout, split) it was composed with.
    pub texture: Option<(egui::TextureHandle, Layout, f32)>,
}

/// What a comparison needs from the app.
pub struct CompareInputs<'a> {
    /// The sky shown now and its generation.
    pub sky: (&'a Sky, u64),
    /// The sky before the last successful reload, and its generation.
    pub previous: Option<(&'a Sky, u64)>,
    /// The frame the panels describe (no clock).
    pub input: FrameInput,
    /// The viewer.
    pub camera: Camera,
    /// Scene, split, glare.
    pub options: RenderOptions,
}

/// Sky identities of B that are not generations of the live sky.
const SNAPSHOT_ID: u64 = u64::MAX - 1;

impl CompareView {
    /// Renders and measures again when the inputs changed (at most every [`MIN_INTERVAL`]), or
    /// polls a B still computing. Errors are kept in `self.error`; the window never stops.
    pub fn step(&mut self, ctx: &GpuContext, library: &ShaderLibrary, controls: &CompareControls, inputs: &CompareInputs<'_>) {
        let snapshot = match self.snapshot_sky(&controls.b) {
            Ok(s) => s,
            Err(e) => {
                self.error = Some(e);
                return;
            }
        };
        let (sky_b, id_b) = match (&controls.b, &snapshot, inputs.previous) {
            (CompareB::Snapshot(_), Some(sky), _) => (sky.as_ref(), SNAPSHOT_ID),
            (CompareB::LastGood, _, Some(previous)) => previous,
            (CompareB::LastGood, _, None) => {
                self.error = Some("no earlier version yet: B shows the sky as it was before the next successful reload".into());
                return;
            }
            _ => inputs.sky,
        };
        let mut input_b = inputs.input.clone();
        match &controls.b {
            CompareB::Model(kind) => {
                let mut model = input_b.sky_model.unwrap_or(inputs.sky.0.model);
                model.kind = *kind;
                input_b.sky_model = Some(model);
            }
            CompareB::Tier(t) => input_b.tier = *t,
            CompareB::Hour(h) => {
                input_b.game_hours += (*h - input_b.hour) as f64;
                input_b.hour = *h;
            }
            CompareB::Weather(w) => input_b.weather = *w,
            CompareB::LastGood | CompareB::Snapshot(_) => {}
        }
        let key = format!("{}|{id_b}|{:?}|{:?}|{:?}|{:?}", inputs.sky.1, inputs.input, input_b, inputs.camera, inputs.options);
        let changed = self.key.as_deref() != Some(key.as_str());
        if !changed && !self.pending {
            return;
        }
        if changed && !self.pending && self.last_run.is_some_and(|t| t.elapsed() < MIN_INTERVAL) {
            return;
        }
        self.last_run = Some(Instant::now());
        self.key = Some(key);
        match self.run(ctx, library, inputs, (sky_b, id_b), &input_b, &controls.b) {
            Ok(()) => self.error = None,
            Err(e) => {
                self.pending = false;
                self.error = Some(format!("{e:#}"));
            }
        }
    }

    /// The snapshot's sky when B is a snapshot (loaded once per path).
    fn snapshot_sky(&mut self, b: &CompareB) -> Result<Option<Arc<Sky>>, String> {
        let CompareB::Snapshot(path) = b else { return Ok(None) };
        if self.snapshot.as_ref().is_none_or(|(p, _)| p != path) {
            let sky = crate::sky::load_sky_file(path).map_err(|e| format!("snapshot {}: {e}", path.display()))?;
            self.snapshot = Some((path.clone(), Arc::new(sky)));
            // A new snapshot: B's renderer must upload it.
            if let Some(sides) = self.sides.as_mut() {
                sides[1].1 = None;
            }
        }
        Ok(self.snapshot.as_ref().map(|(_, s)| s.clone()))
    }

    fn run(&mut self, ctx: &GpuContext, library: &ShaderLibrary, inputs: &CompareInputs<'_>, (sky_b, id_b): (&Sky, u64), input_b: &FrameInput, b: &CompareB) -> anyhow::Result<()> {
        if self.sides.is_none() {
            let (w, h) = COMPARE_SIZE;
            let a = Headless::with_library(ctx.clone(), library.clone(), w, h)?;
            let b = Headless::with_library(ctx.clone(), library.clone(), w, h)?;
            self.sides = Some([(a, None), (b, None)]);
        }
        let sides = self.sides.as_mut().expect("just created");
        let (sky_a, id_a) = inputs.sky;
        for ((hl, held), (sky, id)) in sides.iter_mut().zip([(sky_a, id_a), (sky_b, id_b)]) {
            if *held != Some(id) {
                hl.set_sky(sky)?;
                *held = Some(id);
            }
        }
        let Some(image_b) = sides[1].0.try_render(sky_b, input_b, &inputs.camera, &inputs.options)? else {
            self.pending = true;
            self.progress = sides[1].0.renderer.pass::<crate::render::atmosphere::sky_view::SkyViewPass>().and_then(|p| p.progress());
            return Ok(());
        };
        self.pending = false;
        self.progress = None;
        let image_a = sides[0].0.render(sky_a, &inputs.input, &inputs.camera, &inputs.options)?;
        let diff = image_diff::difference(&image_a, &image_b, 12);
        log::info!("compare: B = {}: {}", b.label(), diff.summary());
        self.result = Some(CompareResult { a: image_a, b: image_b, diff, b_label: b.label() });
        // Recomposed by `picture` on the next paint.
        self.texture = self.texture.take().map(|(t, _, _)| (t, Layout::SideBySide, f32::NAN));
        Ok(())
    }

    /// The texture of the latest comparison in `layout`, recomposed when the layout or split moved.
    pub fn picture(&mut self, egui_ctx: &egui::Context, layout: Layout, split: f32) -> Option<(egui::TextureId, [usize; 2])> {
        let result = self.result.as_ref()?;
        let stale = self.texture.as_ref().is_none_or(|(_, l, s)| *l != layout || *s != split);
        if stale {
            let img = image_diff::compose(&result.a, &result.b, &result.diff, layout, split);
            let color = egui::ColorImage::from_rgba_unmultiplied([img.width() as usize, img.height() as usize], img.as_raw());
            match self.texture.as_mut() {
                Some((handle, l, s)) => {
                    handle.set(color, egui::TextureOptions::LINEAR);
                    (*l, *s) = (layout, split);
                }
                None => self.texture = Some((egui_ctx.load_texture("compare", color, egui::TextureOptions::LINEAR), layout, split)),
            }
        }
        self.texture.as_ref().map(|(t, _, _)| (t.id(), t.size()))
    }

    /// Drops the renderers (after a shader reload: the next comparison rebuilds them).
    pub fn reset(&mut self) {
        self.sides = None;
        self.key = None;
    }
}
