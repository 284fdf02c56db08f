//! How the sky-view map follows a moving sun: what the sky-view pass computes and shows each
//! frame, as data decided without a GPU.
//!
//! A physical model's map is a ray march per texel: on lavapipe the `lut` model's costs about
//! 9 ms at 96 x 108 (half the circle of azimuth), more than a painted frame. While the sun moves a little every frame (a
//! time-lapse) the map can be spread: each frame computes a slice of the next map (the work map)
//! for the sun of the frame that began it, and the frame shows the last two finished maps
//! blended by how far the slices have come, so the sky moves smoothly. Shown that way, a map
//! computed for the sun of the frame that began it would trail the sun by [`lead_frames`]; it is
//! computed instead for the sun that many frames on, turning as it turned over the last frame
//! ([`sun_ahead`]), so a steady time-lapse shows the sky where the sun is. A sun slower than
//! the map resolves (a clock at the game's pace) begins a map only once the sun it would be
//! computed for lies more than [`SUN_RESOLVED_DEG`] from the newest map's ([`sun_change`]), and
//! leaves the map idle in between. A still (the sun where
//! the work map's is), a jump of the sun, or any other change computes the whole map at once for
//! the frame's own sun and shows it exactly.

use std::ops::Range;

/// How the sky-view map is recomputed when only the sun moved, by a small step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MapUpdates {
    /// The whole map in the frame that needs it.
    Whole,
    /// A slice of the map per frame, over `slices` frames (1 is `Whole`).
    Spread {
        /// Frames one map is spread over.
        slices: u32,
    },
}

/// Largest move of the sun between two frames, degrees, that a spread update follows; a larger
/// one (a scrubbed slider, a new still) computes the whole map at once.
pub const SPREAD_MAX_STEP_DEG: f32 = 1.0;

/// How far, degrees, the sun a map begun this frame would be computed for may lie from the one
/// the newest map was computed for, while the sun moves, before another map is begun: a fifth of
/// the map's finest texel (its rows near the horizon are half a degree apart), which the map does
/// not resolve. A sun slower than this over a spread (a clock at the game's own pace) leaves the
/// map idle between updates; a time-lapse goes past it every frame.
pub const SUN_RESOLVED_DEG: f32 = 0.1;

/// What a sun that moved by a small step (at most [`SPREAD_MAX_STEP_DEG`], nothing else changed)
/// asks of the map: `from_newest_deg` is the angle between the sun the newest map was computed for
/// and the one a map begun this frame would be (ahead by the spread's lead). A work map under way
/// goes on either way ([`MapSchedule::step`]).
pub fn sun_change(from_newest_deg: f32) -> MapChange {
    if from_newest_deg > SUN_RESOLVED_DEG {
        MapChange::SunStep
    } else {
        MapChange::SunWithin
    }
}

/// Frames from the one that begins a spread map to the one that shows it alone: its slices, then
/// as many frames blending towards it from the map before (0 for whole maps, shown at once).
pub fn lead_frames(updates: MapUpdates) -> u32 {
    match updates {
        MapUpdates::Spread { slices } if slices > 1 => 2 * slices - 1,
        _ => 0,
    }
}

/// Unit vector towards the sun `frames` frames on, if it keeps turning every frame as it turned
/// from `previous` to `current` (a time-lapse turns it about the celestial pole at a steady
/// rate; the arc between two frames' suns turns it about a nearby axis, which over a spread's
/// lead of a few degrees stays within a fraction of a degree of the sun's path).
pub fn sun_ahead(previous: glam::Vec3, current: glam::Vec3, frames: u32) -> glam::Vec3 {
    let (axis, angle) = glam::Quat::from_rotation_arc(previous.normalize(), current.normalize()).to_axis_angle();
    if angle.abs() < 1e-7 || !axis.is_finite() {
        return current;
    }
    (glam::Quat::from_axis_angle(axis, angle * frames as f32) * current).normalize()
}

/// How this frame's sky relates to the newest map (the work map while one is being computed,
/// else the last finished one).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MapChange {
    /// The same: nothing new to compute.
    Same,
    /// Only the sun moved, by at most [`SPREAD_MAX_STEP_DEG`]: a map is begun or goes on.
    SunStep,
    /// Only the sun moved, by a small step, and a map begun now would lie within
    /// [`SUN_RESOLVED_DEG`] of the newest ([`sun_change`]): nothing is computed, and the shown
    /// map goes on towards the newest as a step would take it.
    SunWithin,
    /// Anything else: the model, the atmosphere, the exposure, a jump of the sun, no map yet.
    Other,
}

/// What the sky-view pass does in one frame.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct MapFrame {
    /// Compute the exposure (and the scene's light) for this frame's sun: a new work map starts.
    pub exposure: bool,
    /// Texels of the work map computed this frame (row-major texel indices).
    pub texels: Option<Range<u32>>,
    /// After computing: the work map is finished. It becomes the newest finished map (the
    /// previous newest the older one), or with `whole` both.
    pub finish: bool,
    /// The finished work map replaces both finished maps (nothing to blend from).
    pub whole: bool,
    /// Write the shown map as the older and the newer finished maps blended by this weight of the
    /// newer (1: the newer as it is); `None`: the shown map stays.
    pub show: Option<f32>,
}

impl MapFrame {
    /// Whether the frame computes nothing and shows the same map.
    pub fn is_idle(&self) -> bool {
        !self.exposure && self.texels.is_none() && !self.finish && self.show.is_none()
    }
}

/// The spread's state between frames.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MapSchedule {
    /// Slices of the work map done, while one is being computed.
    done: Option<u32>,
    /// Weight of the newer finished map in the shown one.
    shown: f32,
}

impl MapSchedule {
    /// Whether the shown map is the newest finished one, with no work map under way: what a
    /// still waits for.
    pub fn settled(&self) -> bool {
        self.done.is_none() && self.shown >= 1.0
    }

    /// Whether a work map is being computed (the pass keeps its key as the newest).
    pub fn computing(&self) -> bool {
        self.done.is_some()
    }

    /// Decides this frame's step for a map of `texels` texels and advances the state.
    pub fn step(&mut self, change: MapChange, updates: MapUpdates, texels: u32) -> MapFrame {
        let slices = match updates {
            MapUpdates::Spread { slices } if slices > 1 => slices.min(texels.max(1)),
            _ => 1,
        };
        let slice = |i: u32| (i * texels / slices)..((i + 1) * texels / slices);
        // A work map under way is finished whatever the sun.
        let change = if change == MapChange::SunWithin && self.done.is_some() { MapChange::SunStep } else { change };
        let whole = MapFrame { exposure: true, texels: Some(0..texels), finish: true, whole: true, show: Some(1.0) };
        // Whole: any other change, or a spread no longer asked for (a work map under way included).
        if change == MapChange::Other || (slices == 1 && (change == MapChange::SunStep || self.done.is_some())) {
            *self = Self { done: None, shown: 1.0 };
            return whole;
        }
        match (change, self.done) {
            (MapChange::SunStep, None) => {
                // Begin a work map for this sun; the shown map goes on towards the newer one.
                self.done = Some(1);
                self.shown = (self.shown + 1.0 / slices as f32).min(1.0);
                MapFrame { exposure: true, texels: Some(slice(0)), show: Some(self.shown), ..MapFrame::default() }
            }
            (MapChange::SunStep, Some(done)) if done + 1 < slices => {
                // The sun moved on: this work map is finished first (the next one takes the sun).
                self.done = Some(done + 1);
                self.shown = (self.shown + 1.0 / slices as f32).min(1.0);
                MapFrame { texels: Some(slice(done)), show: Some(self.shown), ..MapFrame::default() }
            }
            (MapChange::SunStep, Some(done)) => {
                // The last slice: the work map becomes the newer map, shown from the older.
                *self = Self { done: None, shown: 0.0 };
                MapFrame { texels: Some(slice(done)), finish: true, show: Some(0.0), ..MapFrame::default() }
            }
            (MapChange::Same, Some(done)) => {
                // The sun stopped where the work map's is: the rest at once, shown as it is.
                *self = Self { done: None, shown: 1.0 };
                MapFrame { texels: Some(slice(done).start..texels), finish: true, show: Some(1.0), ..MapFrame::default() }
            }
            (MapChange::Same, None) if self.shown < 1.0 => {
                self.shown = 1.0;
                MapFrame { show: Some(1.0), ..MapFrame::default() }
            }
            (MapChange::SunWithin, _) if self.shown < 1.0 => {
                self.shown = (self.shown + 1.0 / slices as f32).min(1.0);
                MapFrame { show: Some(self.shown), ..MapFrame::default() }
            }
            (MapChange::Same | MapChange::SunWithin, _) | (MapChange::Other, _) => MapFrame::default(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEXELS: u32 = 100;
    const SPREAD: MapUpdates = MapUpdates::Spread { slices: 4 };

    #[test]
    fn whole_updates_compute_every_change_at_once() {
        let mut s = MapSchedule::default();
        for change in [MapChange::Other, MapChange::SunStep, MapChange::SunStep] {
            let f = s.step(change, MapUpdates::Whole, TEXELS);
            assert_eq!(f, MapFrame { exposure: true, texels: Some(0..TEXELS), finish: true, whole: true, show: Some(1.0) });
            assert!(s.settled());
        }
        assert!(s.step(MapChange::Same, MapUpdates::Whole, TEXELS).is_idle());
    }

    #[test]
    fn a_moving_sun_spreads_each_map_over_its_slices_and_blends_the_finished_ones() {
        let mut s = MapSchedule::default();
        s.step(MapChange::Other, SPREAD, TEXELS);
        let mut computed = Vec::new();
        let mut shown = Vec::new();
        for frame in 0..8 {
            let f = s.step(MapChange::SunStep, SPREAD, TEXELS);
            assert_eq!(f.exposure, frame % 4 == 0, "frame {frame}: a new work map starts every 4 frames");
            assert_eq!(f.finish, frame % 4 == 3, "frame {frame}");
            assert!(!f.whole && !s.settled());
            computed.push(f.texels.expect("a slice every frame"));
            shown.push(f.show.expect("the shown map moves every frame"));
        }
        // Each map's slices cover its texels once, in order.
        assert_eq!(computed[..4], [0..25, 25..50, 50..75, 75..100]);
        assert_eq!(computed[4..], computed[..4]);
        // The shown blend rises to the newer map and starts again from it when a map is finished
        // (the newer becoming the older): no jump in what is shown.
        assert_eq!(shown[..4], [1.0, 1.0, 1.0, 0.0], "after a whole map there is nothing to blend");
        assert_eq!(shown[4..], [0.25, 0.5, 0.75, 0.0]);
    }

    #[test]
    fn a_still_after_a_step_finishes_the_work_map_at_once_and_shows_it_exactly() {
        let mut s = MapSchedule::default();
        s.step(MapChange::Other, SPREAD, TEXELS);
        s.step(MapChange::SunStep, SPREAD, TEXELS);
        let f = s.step(MapChange::Same, SPREAD, TEXELS);
        assert_eq!(f, MapFrame { texels: Some(25..TEXELS), finish: true, show: Some(1.0), ..MapFrame::default() });
        assert!(s.settled());
        assert!(s.step(MapChange::Same, SPREAD, TEXELS).is_idle());
        // A map finished by the last slice is shown blended from the older one: a still then
        // shows the newer one as it is.
        for _ in 0..4 {
            s.step(MapChange::SunStep, SPREAD, TEXELS);
        }
        assert!(!s.settled());
        assert_eq!(s.step(MapChange::Same, SPREAD, TEXELS), MapFrame { show: Some(1.0), ..MapFrame::default() });
        assert!(s.settled());
    }

    #[test]
    fn any_other_change_drops_the_work_map_and_computes_the_whole_one() {
        let mut s = MapSchedule::default();
        s.step(MapChange::Other, SPREAD, TEXELS);
        s.step(MapChange::SunStep, SPREAD, TEXELS);
        assert!(s.computing());
        let f = s.step(MapChange::Other, SPREAD, TEXELS);
        assert!(f.whole && f.exposure && f.texels == Some(0..TEXELS) && f.show == Some(1.0));
        assert!(s.settled() && !s.computing());
    }

    #[test]
    fn switching_the_spread_off_under_way_computes_the_whole_map() {
        let mut s = MapSchedule::default();
        s.step(MapChange::Other, SPREAD, TEXELS);
        s.step(MapChange::SunStep, SPREAD, TEXELS);
        for change in [MapChange::Same, MapChange::SunStep] {
            let mut t = s;
            assert!(t.step(change, MapUpdates::Whole, TEXELS).whole, "{change:?}");
            assert!(t.settled());
        }
    }

    #[test]
    fn a_spread_map_is_shown_alone_its_lead_after_it_begins() {
        let slices = 4;
        let updates = MapUpdates::Spread { slices };
        let mut s = MapSchedule::default();
        s.step(MapChange::Other, updates, TEXELS);
        // A map begins at an exposure step; it is shown alone at the second finish after that
        // (the first makes it the newer map, shown from 0; the next map's finish makes it the
        // older one, shown with weight 0 of the newer: as it is).
        let (mut begins, mut finishes) = (Vec::new(), Vec::new());
        for frame in 0..4 * slices {
            let f = s.step(MapChange::SunStep, updates, TEXELS);
            if f.exposure {
                begins.push(frame);
            }
            if f.finish {
                finishes.push(frame);
            }
        }
        for (k, begin) in begins.iter().enumerate().take(3) {
            assert_eq!(finishes[k + 1], begin + lead_frames(updates), "map {k}");
        }
        assert_eq!(lead_frames(MapUpdates::Whole), 0);
        assert_eq!(lead_frames(MapUpdates::Spread { slices: 1 }), 0);
    }

    #[test]
    fn the_sun_ahead_keeps_turning_on_its_path() {
        // A sun on a circle of declination 20 degrees about a tilted pole, a quarter of a degree
        // of hour angle a frame.
        let pole = glam::Vec3::new(0.0, 0.8, 0.6).normalize();
        let start = (glam::Quat::from_rotation_arc(glam::Vec3::Y, pole) * glam::Vec3::new(70f32.to_radians().sin(), 70f32.to_radians().cos(), 0.0)).normalize();
        let at = |frame: f32| glam::Quat::from_axis_angle(pole, (0.25 * frame).to_radians()) * start;
        for frames in [1, 11, 23] {
            let ahead = sun_ahead(at(0.0), at(1.0), frames);
            let off_deg = ahead.angle_between(at(1.0 + frames as f32)).to_degrees();
            assert!(off_deg < 0.01 * frames as f32, "{frames} frames on: {off_deg} degrees off");
        }
        let still = glam::Vec3::new(0.3, 0.5, -0.8).normalize();
        assert_eq!(sun_ahead(still, still, 11), still);
    }

    #[test]
    fn a_slow_sun_leaves_the_map_idle_until_it_has_moved_more_than_the_map_resolves() {
        assert_eq!(sun_change(SUN_RESOLVED_DEG * 0.5), MapChange::SunWithin);
        assert_eq!(sun_change(SUN_RESOLVED_DEG * 1.5), MapChange::SunStep);
        // A work map under way goes on, its next slice, whatever the sun.
        let mut under_way = MapSchedule::default();
        under_way.step(MapChange::Other, SPREAD, TEXELS);
        under_way.step(MapChange::SunStep, SPREAD, TEXELS);
        assert_eq!(under_way.step(MapChange::SunWithin, SPREAD, TEXELS).texels, Some(25..50), "a work map under way goes on");
        // A sun a twentieth of the tolerance a frame, from a fresh map: a map begun every 21
        // frames, spread over its four slices, and the shown blend moving on after it.
        let mut s = MapSchedule::default();
        s.step(MapChange::Other, SPREAD, TEXELS);
        let mut newest_at = 0.0f32;
        let (mut computing_frames, mut idle_frames, mut shown) = (0, 0, Vec::new());
        for frame in 1..=60 {
            let sun = frame as f32 * SUN_RESOLVED_DEG / 20.0;
            let change = sun_change(sun - newest_at);
            let f = s.step(change, SPREAD, TEXELS);
            if f.exposure {
                newest_at = sun;
            }
            if f.texels.is_some() {
                computing_frames += 1;
            }
            if f.is_idle() {
                idle_frames += 1;
            }
            shown.extend(f.show);
        }
        assert_eq!(computing_frames, 2 * 4, "two maps of four slices in 60 frames");
        assert!(idle_frames >= 40, "{idle_frames} idle frames");
        // The blend never jumps back: it rises to 1, and starts from 0 only where a map finishes.
        assert!(shown.windows(2).all(|w| w[1] >= w[0] || w[1] == 0.0), "{shown:?}");
        // Whole updates leave the map as it is too.
        let mut whole = MapSchedule::default();
        whole.step(MapChange::Other, MapUpdates::Whole, TEXELS);
        assert!(whole.step(MapChange::SunWithin, MapUpdates::Whole, TEXELS).is_idle());
    }

    #[test]
    fn slices_never_outnumber_texels() {
        let mut s = MapSchedule::default();
        s.step(MapChange::Other, MapUpdates::Spread { slices: 8 }, 3);
        let spans: Vec<Range<u32>> = (0..3).filter_map(|_| s.step(MapChange::SunStep, MapUpdates::Spread { slices: 8 }, 3).texels).collect();
        assert_eq!(spans, [0..1, 1..2, 2..3]);
    }
}
