//! Aerial perspective measured against the reference: the accuracy set (finite rays drawn over
//! the range an artist's scene spans), and the error statistics per sun band and per distance
//! band that `skytune validate-aerial` tabulates and tests/aerial.rs bounds. No GPU types: the
//! answers come from whatever evaluated the rays.

use crate::atmosphere::reference::{Case, Estimate};
use crate::atmosphere::Atmosphere;

/// Sun bands: day (10 to 60 degrees), low (0 to 10), twilight (-6 to 0).
pub const SUN_BANDS: [&str; 3] = ["day", "low", "twilight"];
/// Distance bands, km: [0.1, 1), [1, 10), [10, 100].
pub const DISTANCE_BANDS: [&str; 3] = ["0.1-1 km", "1-10 km", "10-100 km"];

/// Sun band of a case (index into [`SUN_BANDS`]).
pub fn sun_band(c: &Case) -> usize {
    if c.sun_elev_deg >= 10.0 {
        0
    } else if c.sun_elev_deg >= 0.0 {
        1
    } else {
        2
    }
}

/// Distance band of a case (index into [`DISTANCE_BANDS`]); a case with no distance is the last.
pub fn distance_band(c: &Case) -> usize {
    match c.distance_km {
        Some(d) if d < 1.0 => 0,
        Some(d) if d < 10.0 => 1,
        _ => 2,
    }
}

/// The accuracy set, drawn with `seed`: viewers 0 to 5 km up, views -10 to +30 degrees at any
/// azimuth from the sun, distances 0.1 to 100 km spread in log distance, the suns in turn in each
/// band (day 10 to 60 degrees, low 0 to 10, twilight -6 to 0), ground albedo 0.3. A scene point
/// is in the air: a draw whose point lies beyond the planet's ground (of `atmosphere`) is drawn
/// again.
pub fn draw_cases(seed: u64, n: usize, atmosphere: &Atmosphere) -> Vec<Case> {
    let mut rng = fastrand::Rng::with_seed(seed);
    let mut between = |lo: f64, hi: f64| lo + (hi - lo) * rng.f64();
    let ground = atmosphere.ground_radius_km;
    let mut out = Vec::new();
    while out.len() < n {
        let sun_elev_deg = match out.len() % 3 {
            0 => between(10.0, 60.0),
            1 => between(0.0, 10.0),
            _ => between(-6.0, 0.0),
        };
        let c = Case {
            camera_km: between(0.0, 5.0),
            albedo: 0.3,
            sun_elev_deg,
            view_elev_deg: between(-10.0, 30.0),
            rel_azimuth_deg: between(0.0, 180.0),
            distance_km: Some(10f64.powf(between(-1.0, 2.0))),
        };
        let (r, mu) = (ground + c.camera_km, c.view_elev_deg.to_radians().sin());
        let disc = r * r * mu * mu - (r * r - ground * ground);
        let to_ground = if mu < 0.0 && disc >= 0.0 { -r * mu - disc.sqrt() } else { f64::INFINITY };
        if c.distance_km.is_some_and(|d| d < to_ground) {
            out.push(c);
        }
    }
    out
}

/// Median, 95th percentile and largest of `v` (zeros when empty).
pub fn spread(mut v: Vec<f64>) -> [f64; 3] {
    if v.is_empty() {
        return [0.0; 3];
    }
    v.sort_by(f64::total_cmp);
    let at = |q: f64| v[((v.len() - 1) as f64 * q).round() as usize];
    [at(0.5), at(0.95), at(1.0)]
}

/// One case's errors per channel: the in-scatter's beyond twice the reference's standard error,
/// as a fraction of the sky's radiance in the same direction (or of 1% of the brightest sky of
/// its sun band where the sky is darker), and the transmittance's, absolute.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RayError {
    /// In-scatter error / sky, per channel.
    pub in_scatter: [f64; 3],
    /// Transmittance error, per channel.
    pub transmittance: [f64; 3],
}

/// Each case's [`RayError`] for answers `radiance` and `transmittance` against the reference's
/// `rays` and its `sky` along the same directions.
pub fn ray_errors(cases: &[Case], radiance: &[[f32; 3]], transmittance: &[[f32; 3]], rays: &[Estimate], sky: &[Estimate]) -> Vec<RayError> {
    let mut peak = [0.0f64; 3];
    for (s, c) in sky.iter().zip(cases) {
        peak[sun_band(c)] = s.all.iter().fold(peak[sun_band(c)], |m, x| m.max(*x));
    }
    cases
        .iter()
        .enumerate()
        .map(|(k, c)| {
            let floor = 0.01 * peak[sun_band(c)];
            RayError {
                in_scatter: std::array::from_fn(|ch| {
                    let off = ((radiance[k][ch] as f64 - rays[k].all[ch]).abs() - 2.0 * rays[k].std_err[ch]).max(0.0);
                    off / sky[k].all[ch].max(floor).max(1e-30)
                }),
                transmittance: std::array::from_fn(|ch| (transmittance[k][ch] as f64 - rays[k].transmittance[ch]).abs()),
            }
        })
        .collect()
}

/// The errors of one group of cases: how many, and [median, p95, worst] of the in-scatter and
/// transmittance errors, every channel a sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GroupErrors {
    /// Cases in the group.
    pub cases: usize,
    /// In-scatter error / sky.
    pub in_scatter: [f64; 3],
    /// Transmittance error.
    pub transmittance: [f64; 3],
}

/// The [`GroupErrors`] of each group that `group` sorts the cases into (`groups` of them).
pub fn by_group(cases: &[Case], errors: &[RayError], groups: usize, group: impl Fn(&Case) -> usize) -> Vec<GroupErrors> {
    (0..groups)
        .map(|g| {
            let picked: Vec<&RayError> = cases.iter().zip(errors).filter(|(c, _)| group(c) == g).map(|(_, e)| e).collect();
            GroupErrors {
                cases: picked.len(),
                in_scatter: spread(picked.iter().flat_map(|e| e.in_scatter).collect()),
                transmittance: spread(picked.iter().flat_map(|e| e.transmittance).collect()),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_drawn_set_spans_the_range_in_the_air() {
        let atm = Atmosphere::default();
        let cases = draw_cases(1, 300, &atm);
        assert_eq!(cases.len(), 300);
        let counts = |f: &dyn Fn(&Case) -> usize| (0..3).map(|g| cases.iter().filter(|c| f(c) == g).count()).collect::<Vec<_>>();
        assert_eq!(counts(&sun_band), [100, 100, 100]);
        // Log-uniform over three decades: about a third each (the ground takes some far ones).
        assert!(counts(&distance_band).iter().all(|&n| n > 60), "{:?}", counts(&distance_band));
        assert!(cases.iter().all(|c| (0.0..=5.0).contains(&c.camera_km) && (-10.0..=30.0).contains(&c.view_elev_deg)));
        assert_eq!(draw_cases(1, 300, &atm), cases, "the same seed draws the same set");
    }

    #[test]
    fn spreads_are_median_p95_and_worst() {
        assert_eq!(spread((0..=100).map(f64::from).collect()), [50.0, 95.0, 100.0]);
        assert_eq!(spread(Vec::new()), [0.0; 3]);
    }
}
