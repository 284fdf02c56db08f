//! Culling: which sky objects this frame draws at all, from their shapes and where they are,
//! the camera and the frame's elevations. Pure: the sky objects pass asks, per object, and
//! counts the answers in `FrameStats`.

use glam::Vec3;

use crate::render::frame::camera::Camera;
use crate::sky::resolved::Shape;

/// The main-scene stand-in covers every direction more than this far below the horizon, degrees
/// (its terrain reaches 2.5 km at a viewer height of 2 m; its lowest dip is 40 m down).
pub const SCENE_COVERS_BELOW_DEG: f32 = 2.0;

/// What culling knows about the frame.
#[derive(Debug, Clone, Copy)]
pub struct CullFacts {
    /// The frame's camera and width over height.
    pub camera: Camera,
    /// The frame's width over height.
    pub aspect: f32,
    /// The lowest and highest elevation the frame shows, degrees, with the margin of the
    /// dome's chords ([`Camera::elevation_range_deg`]).
    pub elevations_deg: (f32, f32),
    /// The main scene is drawn and covers what lies more than [`SCENE_COVERS_BELOW_DEG`] below
    /// the horizon (`RenderOptions::scene` and `Skips::below_horizon`).
    pub scene_covers_below: bool,
    /// Objects outside the frame are left out (`Skips::off_screen`).
    pub off_screen: bool,
}

/// Whether an object is drawn this frame, and if not, why.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Visibility {
    /// Drawn (some of its versions may still leave nothing: the pass decides per version).
    Drawn,
    /// A billboard or quad wholly below the horizon, behind the main scene.
    BelowHorizon,
    /// Wholly outside the frame: a dome layer outside its elevations, a billboard or quad
    /// outside its sides.
    OffScreen,
}

/// Whether an object drawn as `shapes` (one per version drawn this frame), centred on the unit
/// direction `towards_object` where it is placed in the sky (billboards, quads), shows in the frame.
pub fn visibility(towards_object: Option<Vec3>, shapes: &[Shape], facts: &CullFacts) -> Visibility {
    if towards_object.is_some_and(|dir| facts.scene_covers_below && shapes.iter().all(|s| behind_scene(dir, s))) {
        return Visibility::BelowHorizon;
    }
    if !facts.off_screen {
        return Visibility::Drawn;
    }
    let outside_elevations = shapes.iter().all(|s| !in_elevations(s, facts.elevations_deg));
    let outside_sides = towards_object.is_some_and(|dir| shapes.iter().all(|s| outside_frame(dir, s, facts)));
    if outside_elevations || outside_sides {
        Visibility::OffScreen
    } else {
        Visibility::Drawn
    }
}

/// Whether `shape` may reach the elevations `(lowest, highest)` the frame shows (half a degree of
/// margin for the chords); billboards and quads always may.
pub fn in_elevations(shape: &Shape, (lowest_deg, highest_deg): (f32, f32)) -> bool {
    match *shape {
        Shape::Dome { bottom_deg } => bottom_deg.get() - 0.5 <= highest_deg,
        Shape::DomeBand { bottom_deg, top_deg } => {
            let (lo, hi) = (bottom_deg.get().min(top_deg.get()), bottom_deg.get().max(top_deg.get()));
            lo - 0.5 <= highest_deg && hi + 0.5 >= lowest_deg
        }
        Shape::Billboard { .. } | Shape::Quad { .. } => true,
    }
}

/// A billboard or quad centred on `dir` whose highest corner at any roll (half the square's
/// diagonal above its centre) lies below what the scene covers.
fn behind_scene(dir: Vec3, shape: &Shape) -> bool {
    let elevation_deg = dir.y.clamp(-1.0, 1.0).asin().to_degrees();
    match *shape {
        Shape::Billboard { size_deg } | Shape::Quad { size_deg } => elevation_deg + size_deg.get() * std::f32::consts::FRAC_1_SQRT_2 < -SCENE_COVERS_BELOW_DEG,
        _ => false,
    }
}

/// A billboard or quad centred on `dir` wholly outside one of the frame's sides: a draw that
/// shows nothing still costs its vertices and its state.
fn outside_frame(dir: Vec3, shape: &Shape, facts: &CullFacts) -> bool {
    match *shape {
        // The square's half diagonal, flat at its distance, and half a degree of margin.
        Shape::Billboard { size_deg } | Shape::Quad { size_deg } => {
            let half_diagonal_deg = ((size_deg.get() * 0.5).to_radians().tan() * std::f32::consts::SQRT_2).atan().to_degrees();
            size_deg.get() < 170.0 && !facts.camera.sees_cone(facts.aspect, dir, half_diagonal_deg + 0.5)
        }
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sky::model::{Elevation, Positive};

    fn facts(camera: Camera) -> CullFacts {
        let aspect = 16.0 / 9.0;
        CullFacts { camera, aspect, elevations_deg: camera.elevation_range_deg(aspect), scene_covers_below: true, off_screen: true }
    }

    fn billboard(size_deg: f32) -> Shape {
        Shape::Billboard { size_deg: Positive(size_deg) }
    }

    fn towards(azimuth_deg: f32, elevation_deg: f32) -> Vec3 {
        crate::sky::eval::direction(azimuth_deg, elevation_deg)
    }

    #[test]
    fn domes_outside_the_frames_elevations_are_culled() {
        let looking_down = facts(Camera { yaw_deg: 0.0, pitch_deg: -60.0, ..Camera::default() });
        let looking_up = facts(Camera { yaw_deg: 0.0, pitch_deg: 70.0, ..Camera::default() });
        let high_band = Shape::DomeBand { bottom_deg: Elevation(60.0), top_deg: Elevation(80.0) };
        let low_band = Shape::DomeBand { bottom_deg: Elevation(-5.0), top_deg: Elevation(5.0) };
        assert!(looking_down.elevations_deg.1 < 59.5, "{:?}", looking_down.elevations_deg);
        assert_eq!(visibility(None, &[high_band], &looking_down), Visibility::OffScreen);
        assert_eq!(visibility(None, &[high_band], &looking_up), Visibility::Drawn);
        // 70 degrees up with 70 of field: nothing below about 24 degrees shows (the corners).
        assert!(looking_up.elevations_deg.0 > 20.0, "{:?}", looking_up.elevations_deg);
        assert_eq!(visibility(None, &[low_band], &looking_up), Visibility::OffScreen);
        // One version in view keeps the object.
        let level = facts(Camera { yaw_deg: 0.0, pitch_deg: 0.0, ..Camera::default() });
        assert!(level.elevations_deg.1 < 59.5, "{:?}", level.elevations_deg);
        assert_eq!(visibility(None, &[high_band], &level), Visibility::OffScreen);
        assert_eq!(visibility(None, &[high_band, low_band], &level), Visibility::Drawn);
        // A whole dome reaches the zenith: only a frame wholly below its bottom misses it.
        assert!(looking_down.elevations_deg.1 < -10.5, "{:?}", looking_down.elevations_deg);
        assert_eq!(visibility(None, &[Shape::Dome { bottom_deg: Elevation(-10.0) }], &looking_down), Visibility::OffScreen);
        assert_eq!(visibility(None, &[Shape::Dome { bottom_deg: Elevation(-80.0) }], &looking_down), Visibility::Drawn);
        assert_eq!(visibility(None, &[high_band], &CullFacts { off_screen: false, ..looking_down }), Visibility::Drawn);
    }

    #[test]
    fn billboards_outside_the_frames_sides_are_culled_with_their_diagonal() {
        let f = facts(Camera { yaw_deg: 0.0, pitch_deg: 0.0, ..Camera::default() });
        // Facing azimuth 0: one ahead, one behind, one just outside the right side by less than
        // its half diagonal.
        assert_eq!(visibility(Some(towards(0.0, 10.0)), &[billboard(5.0)], &f), Visibility::Drawn);
        assert_eq!(visibility(Some(towards(180.0, 10.0)), &[billboard(5.0)], &f), Visibility::OffScreen);
        let half_fov_x_deg = ((f.camera.fov_y_deg * 0.5).to_radians().tan() * f.aspect).atan().to_degrees();
        let edge = |size: f32| {
            let az = [-1.0f32, 1.0].map(|side| side * (half_fov_x_deg + 3.0));
            az.map(|a| visibility(Some(towards(a, 0.0)), &[billboard(size)], &f))
        };
        assert_eq!(edge(10.0), [Visibility::Drawn; 2], "a 10-degree square 3 degrees outside still shows a corner");
        assert_eq!(edge(2.0), [Visibility::OffScreen; 2]);
        // Squares of 170 degrees and more are never culled by the sides.
        assert_eq!(visibility(Some(towards(180.0, 10.0)), &[billboard(175.0)], &f), Visibility::Drawn);
        assert_eq!(visibility(Some(towards(180.0, 10.0)), &[billboard(5.0)], &CullFacts { off_screen: false, ..f }), Visibility::Drawn);
    }

    #[test]
    fn billboards_below_the_horizon_hide_behind_the_scene_only_with_it() {
        let f = facts(Camera { yaw_deg: 0.0, pitch_deg: -20.0, ..Camera::default() });
        // 4 degrees wide: its top corner at any roll reaches 2.83 above its centre.
        let sun = [billboard(4.0)];
        assert_eq!(visibility(Some(towards(0.0, -5.0)), &sun, &f), Visibility::BelowHorizon);
        assert_eq!(visibility(Some(towards(0.0, -4.5)), &sun, &f), Visibility::Drawn);
        assert_eq!(visibility(Some(towards(0.0, -5.0)), &sun, &CullFacts { scene_covers_below: false, ..f }), Visibility::Drawn);
        // Domes are never behind the scene as a whole (their rows are, per ring).
        assert_eq!(visibility(Some(towards(0.0, -30.0)), &[Shape::DomeBand { bottom_deg: Elevation(-20.0), top_deg: Elevation(-10.0) }], &f), Visibility::Drawn);
    }
}
