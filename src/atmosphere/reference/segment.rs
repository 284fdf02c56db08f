//! A ray segment cut into panels with accurate optical depths: the reference's unit of work.

use glam::DVec3;

use crate::atmosphere::Rgb;

/// A ray segment inside the atmosphere, cut into panels with their optical depths.
pub(super) struct Segment {
    /// Where the segment starts, km from the planet's centre.
    pub origin: DVec3,
    /// Its unit direction.
    pub dir: DVec3,
    /// Panel boundaries, t in km: nodes[0] = 0, last = length.
    pub nodes: Vec<f64>,
    /// Optical depth from the origin to each node, per channel.
    pub tau: Vec<Rgb>,
    /// Whether the segment ends on the ground (else at the top of the atmosphere).
    pub ground: bool,
}

impl Segment {
    /// Its length, km.
    pub fn length(&self) -> f64 {
        *self.nodes.last().unwrap_or(&0.0)
    }

    /// Its whole optical depth per channel.
    pub fn total(&self) -> Rgb {
        *self.tau.last().unwrap_or(&[0.0; 3])
    }

    /// Optical depth per channel at t (linear within a panel) and the panel's extinction per channel.
    pub fn at(&self, t: f64) -> (Rgb, Rgb) {
        let i = self.nodes.partition_point(|&n| n <= t).clamp(1, self.nodes.len() - 1);
        let (a, b) = (self.nodes[i - 1], self.nodes[i]);
        let w = b - a;
        let f = if w > 0.0 { ((t - a) / w).clamp(0.0, 1.0) } else { 0.0 };
        let tau = std::array::from_fn(|c| self.tau[i - 1][c] + f * (self.tau[i][c] - self.tau[i - 1][c]));
        let slope = std::array::from_fn(|c| if w > 0.0 { (self.tau[i][c] - self.tau[i - 1][c]) / w } else { 0.0 });
        (tau, slope)
    }

    /// The t where channel `c`'s optical depth reaches `target` (< its total).
    pub fn invert(&self, c: usize, target: f64) -> f64 {
        let i = self.tau.partition_point(|x| x[c] <= target).clamp(1, self.tau.len() - 1);
        let (ta, tb) = (self.tau[i - 1][c], self.tau[i][c]);
        let (a, b) = (self.nodes[i - 1], self.nodes[i]);
        if tb > ta {
            (a + (target - ta) / (tb - ta) * (b - a)).clamp(a, b)
        } else {
            a
        }
    }
}
