//! The viewer: a free-look camera standing in the main scene, looking at the sky.

use glam::{Mat4, Vec3};

use crate::sky::eval::direction;

/// A free-look camera. Yaw is a compass direction (0 north, 90 east), pitch is above the horizon.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// Compass direction of the view, degrees.
    pub yaw_deg: f32,
    /// Elevation of the view, degrees (-89..89).
    pub pitch_deg: f32,
    /// Vertical field of view, degrees.
    pub fov_y_deg: f32,
    /// Eye height above the ground at the origin, m.
    pub eye_height_m: f32,
    /// An explicit view (unit forward, unit up) instead of yaw and pitch: environment-map faces
    /// look straight up and down, which yaw and pitch (clamped short of the poles) cannot.
    pub look: Option<(Vec3, Vec3)>,
}

impl Default for Camera {
    fn default() -> Self {
        // Facing south, slightly up: the noon sun and the horizon are both in view.
        Self { yaw_deg: 180.0, pitch_deg: 12.0, fov_y_deg: 70.0, eye_height_m: 1.8, look: None }
    }
}

/// Named views for the UI and the CLI.
pub const PRESETS: [(&str, f32, f32); 5] = [("south", 180.0, 12.0), ("east", 90.0, 8.0), ("west", 270.0, 8.0), ("north", 0.0, 12.0), ("zenith", 180.0, 89.0)];

impl Camera {
    /// Distance of the near plane, m (depth 0 before the viewport's range).
    pub const NEAR_M: f32 = 0.05;
    /// Distance of the far plane, m (depth 1): the stand-in scene (40 km across, its corners 28
    /// km from the viewer) ends inside it.
    pub const FAR_M: f32 = 40000.0;

    /// A preset view by name (`south`, `east`, `west`, `north`, `zenith`).
    pub fn preset(name: &str) -> Option<Camera> {
        PRESETS.iter().find(|p| p.0 == name).map(|&(_, yaw, pitch)| Camera { yaw_deg: yaw, pitch_deg: pitch, ..Camera::default() })
    }

    /// A preset view by name, or an error naming `--view` and the presets (the CLI and the window).
    pub fn preset_arg(name: &str) -> Result<Camera, String> {
        Self::preset(name).ok_or_else(|| format!("--view: unknown view \"{name}\"; expected {}", PRESETS.map(|p| p.0).join(", ")))
    }

    /// Unit view direction.
    pub fn forward(&self) -> Vec3 {
        if let Some((forward, _)) = self.look {
            return forward;
        }
        direction(self.yaw_deg, self.pitch_deg.clamp(-89.0, 89.0))
    }

    /// Eye position in the world, m.
    pub fn position(&self) -> Vec3 {
        Vec3::new(0.0, self.eye_height_m, 0.0)
    }

    /// Unit "up" of the screen, in world space.
    pub fn screen_up(&self) -> Vec3 {
        let f = self.forward();
        if let Some((_, up)) = self.look {
            return up;
        }
        let right = f.cross(Vec3::Y).try_normalize().unwrap_or(Vec3::X);
        right.cross(f)
    }

    /// The lowest and highest elevation the frame shows, degrees (within a tenth of a degree:
    /// sampled along the frame's border, plus the zenith or nadir when inside the frame).
    pub fn elevation_range_deg(&self, aspect: f32) -> (f32, f32) {
        let (_, clip_from_sky) = self.matrices(aspect);
        let sky_from_clip = clip_from_sky.inverse();
        let elevation = |x: f32, y: f32| {
            let d = sky_from_clip.project_point3(Vec3::new(x, y, 0.5)).normalize_or_zero();
            d.y.clamp(-1.0, 1.0).asin().to_degrees()
        };
        const STEPS: usize = 64;
        let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
        for i in 0..=STEPS {
            let t = -1.0 + 2.0 * i as f32 / STEPS as f32;
            for e in [elevation(t, -1.0), elevation(t, 1.0), elevation(-1.0, t), elevation(1.0, t)] {
                lo = lo.min(e);
                hi = hi.max(e);
            }
        }
        // A pole inside the frame is its extreme.
        let inside = |dir: Vec3| {
            let c = clip_from_sky * dir.extend(1.0);
            c.w > 0.0 && c.x.abs() <= c.w && c.y.abs() <= c.w
        };
        if inside(Vec3::Y) {
            hi = 90.0;
        }
        if inside(Vec3::NEG_Y) {
            lo = -90.0;
        }
        (lo, hi)
    }

    /// Whether a frame of `aspect` may show a direction within `radius_deg` of unit direction
    /// `dir`: false only when that cone lies wholly outside one of the frame's four sides (a
    /// cone near a corner, outside two sides but inside each, counts as shown).
    pub fn sees_cone(&self, aspect: f32, dir: Vec3, radius_deg: f32) -> bool {
        self.cone_test(aspect)(dir, radius_deg)
    }

    /// [`Self::sees_cone`] for many cones of one frame: the frame's sides computed once.
    pub fn cone_test(&self, aspect: f32) -> impl Fn(Vec3, f32) -> bool {
        let (_, clip_from_sky) = self.matrices(aspect);
        let row = |i: usize| Vec3::new(clip_from_sky.x_axis[i], clip_from_sky.y_axis[i], clip_from_sky.z_axis[i]);
        let (x, y, w) = (row(0), row(1), row(3));
        // The sides are the planes |x| = w and |y| = w of clip space, through the eye: a
        // direction shows where it lies on the inner side of all four.
        let sides = [w + x, w - x, w + y, w - y].map(|side| side.try_normalize());
        move |dir, radius_deg| {
            let reach = radius_deg.max(0.0).to_radians().sin();
            radius_deg >= 90.0 || sides.iter().all(|n| n.is_none_or(|n| n.dot(dir) >= -reach))
        }
    }

    /// A rectangle of a `size` frame's pixels (x, y, width, height; y down) that holds every
    /// pixel whose view direction lies below `elevation_deg`, or None when none does. A little
    /// larger than the tightest such rectangle: elevations are sampled on a grid, and the grid's
    /// cells bound how far a pixel's elevation strays from its corners'.
    pub fn pixels_below_elevation(&self, size: (u32, u32), elevation_deg: f32) -> Option<[u32; 4]> {
        let (w, h) = size;
        if w == 0 || h == 0 {
            return None;
        }
        let aspect = w as f32 / h as f32;
        let (_, clip_from_sky) = self.matrices(aspect);
        let sky_from_clip = clip_from_sky.inverse();
        const CELLS: u32 = 64;
        // On the image plane at distance 1 a cell's diagonal is 2 / CELLS of the frame's
        // half-diagonal, and no angle subtended by a stretch of that plane exceeds its length.
        let tan_half_fov = (self.fov_y_deg.to_radians() * 0.5).tan();
        let cell_rad = 2.0 / CELLS as f32 * tan_half_fov * (1.0 + aspect * aspect).sqrt();
        let sin_below = (elevation_deg.to_radians() + cell_rad).min(std::f32::consts::FRAC_PI_2).sin();
        let (mut lo, mut hi) = ((CELLS, CELLS), (0, 0));
        let mut any = false;
        for j in 0..=CELLS {
            for i in 0..=CELLS {
                let ndc = Vec3::new(-1.0 + 2.0 * i as f32 / CELLS as f32, -1.0 + 2.0 * j as f32 / CELLS as f32, 0.5);
                let d = sky_from_clip.project_point3(ndc).normalize_or_zero();
                if d.y < sin_below {
                    any = true;
                    lo = (lo.0.min(i), lo.1.min(j));
                    hi = (hi.0.max(i), hi.1.max(j));
                }
            }
        }
        if !any {
            return None;
        }
        // One cell more on each side: a pixel lies in a cell whose corners were sampled.
        let (i0, i1) = (lo.0.saturating_sub(1), (hi.0 + 1).min(CELLS));
        let (j0, j1) = (lo.1.saturating_sub(1), (hi.1 + 1).min(CELLS));
        let x0 = (u64::from(i0) * u64::from(w) / u64::from(CELLS)) as u32;
        let x1 = (u64::from(i1) * u64::from(w)).div_ceil(u64::from(CELLS)) as u32;
        // NDC y points up, pixel rows down.
        let y0 = (u64::from(CELLS - j1) * u64::from(h) / u64::from(CELLS)) as u32;
        let y1 = (u64::from(CELLS - j0) * u64::from(h)).div_ceil(u64::from(CELLS)) as u32;
        Some([x0, y0, x1.min(w) - x0, y1.min(h) - y0])
    }

    /// (clip_from_world, clip_from_sky): the scene camera and its rotation-only twin for the sky.
    pub fn matrices(&self, aspect: f32) -> (Mat4, Mat4) {
        let proj = Mat4::perspective_rh(self.fov_y_deg.to_radians(), aspect, Self::NEAR_M, Self::FAR_M);
        let f = self.forward();
        let up = self.look.map_or(Vec3::Y, |(_, up)| up);
        let view = Mat4::look_to_rh(self.position(), f, up);
        let view_rot = Mat4::look_to_rh(Vec3::ZERO, f, up);
        (proj * view, proj * view_rot)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cones_in_view_are_seen_and_those_behind_are_not() {
        let mut rng = fastrand::Rng::with_seed(11);
        let mut unseen = 0;
        for (camera, aspect) in [
            (Camera::default(), 16.0 / 9.0),
            (Camera { yaw_deg: 120.0, pitch_deg: 70.0, ..Camera::default() }, 1.0),
            (Camera { pitch_deg: -40.0, fov_y_deg: 100.0, ..Camera::default() }, 2.0),
            (Camera { look: Some((Vec3::new(0.3, 0.2, -1.0).normalize(), Vec3::new(0.4, 1.0, 0.0).normalize())), ..Camera::default() }, 16.0 / 9.0),
        ] {
            let (_, clip_from_sky) = camera.matrices(aspect);
            let shown = |d: Vec3| {
                let c = clip_from_sky * d.extend(1.0);
                c.w > 0.0 && c.x.abs() <= c.w && c.y.abs() <= c.w
            };
            assert!(camera.sees_cone(aspect, camera.forward(), 0.1));
            assert!(!camera.sees_cone(aspect, -camera.forward(), 5.0));
            for _ in 0..2000 {
                let dir = Vec3::new(rng.f32() * 2.0 - 1.0, rng.f32() * 2.0 - 1.0, rng.f32() * 2.0 - 1.0).normalize_or(Vec3::Y);
                let radius_deg = rng.f32() * 10.0;
                if camera.sees_cone(aspect, dir, radius_deg) {
                    continue;
                }
                unseen += 1;
                // Not seen: no direction of the cone shows (its centre and rings of its edge).
                let side = dir.any_orthonormal_vector();
                for ring in [0.0, 0.5, 1.0] {
                    for k in 0..32 {
                        let about = glam::Quat::from_axis_angle(dir, k as f32 / 32.0 * std::f32::consts::TAU);
                        let d = glam::Quat::from_axis_angle(about * side, radius_deg.to_radians() * ring) * dir;
                        assert!(!shown(d), "{camera:?}: {d:?} of the cone round {dir:?} ({radius_deg} degrees) shows");
                    }
                }
            }
        }
        assert!(unseen > 1000, "most random cones lie out of view ({unseen})");
    }

    #[test]
    fn elevation_range_holds_every_pixel_and_is_tight() {
        for (camera, aspect) in [
            (Camera::default(), 16.0 / 9.0),
            (Camera { pitch_deg: 89.0, ..Camera::default() }, 16.0 / 9.0),
            (Camera { pitch_deg: -60.0, yaw_deg: 30.0, ..Camera::default() }, 1.0),
            (Camera { pitch_deg: 45.0, fov_y_deg: 100.0, ..Camera::default() }, 2.0),
        ] {
            let (lo, hi) = camera.elevation_range_deg(aspect);
            let (_, clip_from_sky) = camera.matrices(aspect);
            let inv = clip_from_sky.inverse();
            let (mut seen_lo, mut seen_hi) = (f32::INFINITY, f32::NEG_INFINITY);
            for i in 0..=200 {
                for j in 0..=200 {
                    let (x, y) = (-1.0 + i as f32 / 100.0, -1.0 + j as f32 / 100.0);
                    let e = inv.project_point3(Vec3::new(x, y, 0.5)).normalize().y.asin().to_degrees();
                    assert!(e >= lo - 0.05 && e <= hi + 0.05, "{camera:?}: elevation {e} outside {lo}..{hi}");
                    (seen_lo, seen_hi) = (seen_lo.min(e), seen_hi.max(e));
                }
            }
            assert!(seen_lo - lo < 0.5 && hi - seen_hi < 0.5, "{camera:?}: {lo}..{hi} loose against {seen_lo}..{seen_hi}");
        }
    }

    #[test]
    fn pixels_below_an_elevation_lie_in_their_rectangle() {
        let (w, h) = (320u32, 180u32);
        let rolled = Camera { look: Some((Vec3::new(0.0, -0.2, -1.0).normalize(), Vec3::new(0.4, 1.0, -0.2).normalize())), ..Camera::default() };
        for (camera, below_deg) in [
            (Camera::default(), -19.5),
            (Camera { pitch_deg: 0.0, ..Camera::default() }, -19.5),
            (Camera { pitch_deg: -40.0, yaw_deg: 30.0, ..Camera::default() }, -19.5),
            (Camera { pitch_deg: 45.0, fov_y_deg: 100.0, ..Camera::default() }, 10.0),
            (rolled, -5.0),
            (Camera { pitch_deg: 60.0, ..Camera::default() }, -19.5),
        ] {
            let rect = camera.pixels_below_elevation((w, h), below_deg);
            let (_, clip_from_sky) = camera.matrices(w as f32 / h as f32);
            let inv = clip_from_sky.inverse();
            let mut tight: Option<[u32; 4]> = None;
            for y in 0..h {
                for x in 0..w {
                    let ndc = Vec3::new((x as f32 + 0.5) / w as f32 * 2.0 - 1.0, 1.0 - (y as f32 + 0.5) / h as f32 * 2.0, 0.5);
                    if inv.project_point3(ndc).normalize().y.asin().to_degrees() >= below_deg {
                        continue;
                    }
                    let [x0, y0, x1, y1] = tight.unwrap_or([x, y, x, y]);
                    tight = Some([x0.min(x), y0.min(y), x1.max(x), y1.max(y)]);
                    let Some([rx, ry, rw, rh]) = rect else { panic!("{camera:?}: pixel ({x}, {y}) below {below_deg} but no rectangle") };
                    assert!(x >= rx && x < rx + rw && y >= ry && y < ry + rh, "{camera:?}: pixel ({x}, {y}) outside {rect:?}");
                }
            }
            match (tight, rect) {
                // Larger than the tight box by a small part of the frame.
                (Some([x0, y0, x1, y1]), Some([_, _, rw, rh])) => {
                    let slack = (rw * rh - (x1 - x0 + 1) * (y1 - y0 + 1)) as f32 / (w * h) as f32;
                    assert!(slack < 0.15, "{camera:?}: {rect:?} loose around {tight:?}: {slack}");
                }
                (None, Some(r)) => assert!(r[2] as f32 * r[3] as f32 <= 0.1 * (w * h) as f32, "{camera:?}: {r:?} where no pixel is below"),
                _ => {}
            }
        }
    }
}
