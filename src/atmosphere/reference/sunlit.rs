//! The sunlight a path gathers along one of its segments: an unbiased estimate by stratified
//! sampling of the segment's sunlit part.
//!
//! Sunlight scattered towards a path vertex along a segment is the line integral of
//! `T(0, t) S(t) T_sun(t)`. One free-flight sample of it (next-event estimation at the next
//! collision) is noisy where the integrand is not shaped like free flight's density: at twilight
//! the sunlit part is a small, far piece of the segment, and inside it the sun's transmittance
//! climbs by orders of magnitude from the shadow's edge. The estimate here takes one sample in
//! each of a few strata that cover the sunlit intervals only, cut both at equal lengths and at
//! equal free-flight mass, each sample drawn by free flight restricted to its stratum. Outside
//! the sunlit intervals the integrand is exactly 0 (the sun has faded out below the horizon).

use super::segment::Segment;
use crate::atmosphere::Rgb;

/// Cuts of each sunlit interval at equal lengths, and as many at equal free-flight mass, where
/// the planet's shadow covers part of the segment.
const CUTS_IN_PART_SHADOW: usize = 4;

/// Strata over a segment's sunlit intervals, each with its free-flight mass per channel.
pub(super) struct SunlitStrata {
    cells: Vec<(f64, f64, Rgb)>,
}

impl SunlitStrata {
    /// Strata over `intervals` (sorted, disjoint parts of `seg`). A segment lit throughout
    /// (nearly every one by day) gets one stratum, a free-flight sample over its whole length:
    /// there the sun's transmittance varies slowly, and more samples cost more than they save.
    pub fn new(seg: &Segment, intervals: &[(f64, f64)]) -> Self {
        let mut cells = Vec::new();
        let whole = intervals.len() == 1 && intervals[0].0 <= 1e-9 && intervals[0].1 >= seg.length() - 1e-9;
        let cuts_per_interval = if whole { 1 } else { CUTS_IN_PART_SHADOW };
        for &(a, b) in intervals {
            let mut cuts: Vec<f64> = (0..=cuts_per_interval).map(|k| a + (b - a) * k as f64 / cuts_per_interval as f64).collect();
            // Equal mass in the middle channel, whose density is between the other two's.
            let (tau_a, tau_b) = (seg.at(a).0[1], seg.at(b).0[1]);
            let (ea, eb) = ((-tau_a).exp(), (-tau_b).exp());
            if ea - eb > 1e-12 * ea {
                for k in 1..cuts_per_interval {
                    let e = ea - (ea - eb) * k as f64 / cuts_per_interval as f64;
                    cuts.push(seg.invert(1, -e.ln()).clamp(a, b));
                }
            }
            cuts.sort_by(f64::total_cmp);
            cuts.dedup_by(|x, y| (*x - *y).abs() <= 1e-9 * (b - a).max(1e-9));
            for w in cuts.windows(2) {
                let (ta, tb) = (seg.at(w[0]).0, seg.at(w[1]).0);
                let mass = std::array::from_fn(|c| ((-ta[c]).exp() - (-tb[c]).exp()).max(0.0));
                cells.push((w[0], w[1], mass));
            }
        }
        Self { cells }
    }

    /// Whether there is nothing to estimate (the segment is in shadow throughout).
    pub fn is_empty(&self) -> bool {
        self.cells.is_empty()
    }

    /// An unbiased estimate of the integral over the strata of `T(0, t) lit(t)` per channel,
    /// where `lit(t)` is the sunlight scattered per unit length at `t`.
    pub fn estimate(&self, seg: &Segment, rng: &mut fastrand::Rng, lit: impl Fn(f64) -> Rgb) -> Rgb {
        let mut sum = [0.0; 3];
        for &(a, b, mass) in &self.cells {
            let channels: Vec<usize> = (0..3).filter(|&c| mass[c] > 0.0).collect();
            let (t, pdf) = if channels.is_empty() {
                // Vacuum: uniform over the stratum.
                (a + (b - a) * rng.f64(), 1.0 / (b - a))
            } else {
                // Free flight of one of the channels, restricted to the stratum; the pdf is the
                // average of theirs, which keeps every channel's weight bounded.
                let j = channels[rng.usize(0..channels.len())];
                let e_a = (-seg.at(a).0[j]).exp();
                let target = -(e_a - rng.f64() * mass[j]).max(1e-300).ln();
                let t = seg.invert(j, target).clamp(a, b);
                let (tau, slope) = seg.at(t);
                let pdf = channels.iter().map(|&c| slope[c] * (-tau[c]).exp() / mass[c]).sum::<f64>() / channels.len() as f64;
                (t, pdf)
            };
            if pdf <= 0.0 || !pdf.is_finite() {
                continue;
            }
            let tau = seg.at(t).0;
            let l = lit(t);
            for c in 0..3 {
                sum[c] += (-tau[c]).exp() * l[c] / pdf;
            }
        }
        sum
    }
}
