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
