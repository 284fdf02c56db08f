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
    /// A preset view by name (`south`, `east`, `west`, `north`, `zenith`).
    pub fn preset(name: &str) -> Option<Camera> {
        PRESETS.iter().find(|p| p.0 == name).map(|&(_, yaw, pitch)| Camera { yaw_deg: yaw, pitch_deg: pitch, ..Camera::default() })
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

    /// (clip_from_world, clip_from_sky): the scene camera and its rotation-only twin for the sky.
    pub fn matrices(&self, aspect: f32) -> (Mat4, Mat4) {
        let proj = Mat4::perspective_rh(self.fov_y_deg.to_radians(), aspect, 0.05, 5000.0);
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
}
