//! Procedural star catalogue: uniform directions, magnitudes following the observed growth of
//! star counts (about x3.2 per magnitude), cut at the sky's magnitude limit.

use glam::Vec3;

use super::procedural::SplitMix;
use super::resolved::Stars;

/// Brightest magnitude generated (Sirius is about -1.5).
pub const BRIGHTEST: f32 = -1.5;
/// Faintest magnitude generated before the cutoff (naked-eye limit in a dark site).
pub const FAINTEST: f32 = 7.0;
/// log10 growth of the number of stars per magnitude.
pub const COUNT_SLOPE: f32 = 0.5;

/// One star in the celestial frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Star {
    /// Unit direction in the celestial frame.
    pub direction: Vec3,
    /// Visual magnitude (smaller is brighter).
    pub magnitude: f32,
}

impl Star {
    /// Linear brightness relative to a magnitude-0 star.
    pub fn brightness(&self) -> f32 {
        10f32.powf(-0.4 * self.magnitude)
    }
}

/// Generates `count` stars over [BRIGHTEST, FAINTEST] and keeps those at or below the cutoff.
pub fn generate(s: &Stars) -> Vec<Star> {
    let mut rng = SplitMix::new(s.seed);
    let span = FAINTEST - BRIGHTEST;
    // Inverse CDF of N(<m) ~ 10^(slope m): m = faintest + log10(u') / slope, u' in [10^(-slope span), 1].
    let floor = 10f32.powf(-COUNT_SLOPE * span);
    (0..s.count)
        .map(|_| {
            let z = rng.next_f32() * 2.0 - 1.0;
            let phi = rng.next_f32() * std::f32::consts::TAU;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let u = floor + (1.0 - floor) * rng.next_f32().max(1e-7);
            Star { direction: Vec3::new(r * phi.cos(), z, r * phi.sin()), magnitude: FAINTEST + u.log10() / COUNT_SLOPE }
        })
        .filter(|star| star.magnitude <= s.magnitude_cutoff)
        .collect()
}
