//! The reference: a CPU, double-precision integrator of sky radiance with every order of
//! scattering, ozone absorption and a Lambertian ground. Too slow for frames; the ground truth
//! the real-time models are measured against.
//!
//! - Single scattering is integrated deterministically: adaptive Simpson panels along the view
//!   ray (refined until the optical depth of each panel is accurate to `tau_tolerance`, and no
//!   longer than `max_panel_km`), Simpson's rule on each panel, the sun's transmittance at every
//!   node by the same adaptive quadrature.
//! - Orders 2 and up are estimated by Monte Carlo path tracing. Each path's first vertex is
//!   forced into the view ray; directions follow the medium's phase function (3/4) mixed with
//!   a lobe around the sun (1/4); distances follow free flight in one channel per path, every
//!   channel weighed by the whole path's pdf averaged over the three (spectral MIS per path, so
//!   no channel's weight grows with the bounces); a Lambertian ground of albedo `a`. Along each
//!   segment a path leaves a vertex by, the sunlight scattered towards the vertex is estimated
//!   by stratified sampling of the segment's sunlit part ([`sunlit::SunlitStrata`]): one sample
//!   where the segment is lit throughout, eight strata where the planet's shadow covers part of
//!   it (twilight: the sunlit air high and far, the sun's transmittance climbing steeply from
//!   the shadow's edge). The sunlit ground at a segment's end is added through the segment's
//!   transmittance. A fixed seed makes results repeatable, and truncating at `max_order` only
//!   drops terms, so radiance never decreases with more orders.
//!
//! The sun is a point source of irradiance 1 per channel (its disc is not part of the result)
//! whose light fades out smoothly while it sinks 0.1 degrees below a point's horizon
//! ([`Reference::sunlight`], as the GPU models do, so that no sky jumps as the sun sets);
//! the ground surface seen by a view ray that hits it is not part of the result either (only
//! the light scattered along the ray in front of it).

use std::f64::consts::PI;

use glam::DVec3;

mod many;
mod segment;
mod sun_table;
mod sunlit;

pub use many::estimate_many;

use segment::Segment;
use sun_table::SunTable;
use sunlit::SunlitStrata;

use super::{cornette_shanks_phase, henyey_greenstein_phase, rayleigh_phase, Atmosphere, Rgb};

/// How hard the reference works.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReferenceSettings {
    /// Absolute error allowed on each panel's optical depth.
    pub tau_tolerance: f64,
    /// Longest panel along a ray, km.
    pub max_panel_km: f64,
    /// Highest order of scattering (1: single scattering only).
    pub max_order: u32,
    /// Monte Carlo paths per radiance value for orders >= 2: all of them, or with
    /// `target_rel_se` the most a value may draw.
    pub paths: u32,
    /// Seed of the paths.
    pub seed: u64,
    /// Stop drawing paths once every channel's standard error is at most this fraction of its
    /// radiance (checked after each batch of [`BATCH_PATHS`], from `min_paths` on);
    /// `None` draws `paths` every time.
    pub target_rel_se: Option<f64>,
    /// With a target, the fewest paths before it may stop an estimate (rounded up to a whole
    /// batch); [`MIN_TARGET_PATHS`] unless a coarse estimate will do.
    pub min_paths: u32,
    /// How single scattering finds the sunlight at its nodes: by quadrature (exact; the
    /// default), or from the table orders 2 and up use (within 3.7e-4 of it, and five times
    /// faster where few paths are drawn: `auto`'s references).
    pub single_sunlight: SunlightBy,
}

impl Default for ReferenceSettings {
    fn default() -> Self {
        Self {
            tau_tolerance: 1e-7,
            max_panel_km: 1.0,
            max_order: 24,
            paths: 8192,
            seed: 0x5eed,
            target_rel_se: None,
            min_paths: MIN_TARGET_PATHS,
            single_sunlight: SunlightBy::Quadrature,
        }
    }
}

impl ReferenceSettings {
    /// How many paths each value draws, for reports: "8192 Monte Carlo paths per value", or
    /// with a target, the target, the least and the most.
    pub fn describe_paths(&self) -> String {
        match self.target_rel_se {
            Some(t) => format!(
                "Monte Carlo paths per value until a relative standard error of {t} per channel ({} to {}, in batches of {BATCH_PATHS})",
                self.min_paths.min(self.paths),
                self.paths
            ),
            None => format!("{} Monte Carlo paths per value", self.paths),
        }
    }
}

/// Paths drawn between two looks at a target standard error. Fixed, so that where an estimate
/// stops depends on the seed and the target only, never on how many threads drew the batches.
pub const BATCH_PATHS: u32 = 64;

/// Fewest paths before a target standard error may stop an estimate, by default: the variance
/// of fewer paths is itself too noisy to trust (a twilight case's rare bright paths are not yet
/// seen).
pub const MIN_TARGET_PATHS: u32 = 256;

/// One radiance query: where the camera is, where the sun is, where it looks.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Case {
    /// Camera altitude above the ground, km.
    pub camera_km: f64,
    /// Lambertian ground albedo (grey).
    pub albedo: f64,
    /// Sun elevation above the camera's horizon, degrees.
    pub sun_elev_deg: f64,
    /// View elevation above the camera's horizon, degrees.
    pub view_elev_deg: f64,
    /// Azimuth of the view relative to the sun's, degrees (0 = towards the sun).
    pub rel_azimuth_deg: f64,
    /// Where the view ray stops, km from the camera: at a surface that emits and reflects
    /// nothing, so the answer is the light scattered into the ray on the way (aerial
    /// perspective). `None`: at the edge of the atmosphere or the ground, the sky's radiance.
    pub distance_km: Option<f64>,
}

/// The reference's answer for one case, sr^-1 per unit of solar irradiance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    /// Single scattering (deterministic quadrature).
    pub single: Rgb,
    /// Every order up to `max_order`.
    pub all: Rgb,
    /// Standard error of `all` (Monte Carlo noise of orders >= 2).
    pub std_err: Rgb,
    /// Monte Carlo paths drawn (0 when only single scattering is asked for).
    pub paths: u32,
    /// Transmittance of the view ray from the camera to where it stops (the case's distance,
    /// the ground or the edge of the atmosphere), per channel.
    pub transmittance: Rgb,
}

/// Running sums of the paths' contributions, added in path order (the same bytes however the
/// batches were drawn).
#[derive(Default)]
struct PathSums {
    sum: Rgb,
    sum_sq: Rgb,
    n: u32,
}

impl PathSums {
    fn add(&mut self, x: Rgb) {
        self.sum = add(self.sum, x);
        self.sum_sq = add(self.sum_sq, x.map(|v| v * v));
        self.n += 1;
    }

    /// (mean, standard error of the mean) per channel.
    fn mean_and_error(&self) -> (Rgb, Rgb) {
        if self.n == 0 {
            return ([0.0; 3], [0.0; 3]);
        }
        let n = self.n as f64;
        let mean = scale(self.sum, 1.0 / n);
        (mean, std::array::from_fn(|c| ((self.sum_sq[c] / n - mean[c] * mean[c]).max(0.0) / n).sqrt()))
    }

    /// Whether every channel's standard error is within `target` of `single` plus the mean.
    fn within(&self, single: Rgb, target: f64) -> bool {
        let (mean, err) = self.mean_and_error();
        (0..3).all(|c| {
            let total = single[c] + mean[c];
            if total > 0.0 {
                err[c] <= target * total
            } else {
                err[c] <= 0.0
            }
        })
    }
}

/// Henyey-Greenstein asymmetry of the direction-sampling lobe around the sun.
const SUN_LOBE_G: f64 = 0.6;

/// A path's throughput per channel under spectral MIS: the product of each channel's
/// transmittances and scattering (over the directions' pdfs), over the average of the three
/// channels' products of distance pdfs. Both are rescaled as they go so that the average stays 1
/// (no underflow on long paths).
struct PathWeight {
    /// Each channel's transmittances, scattering and albedo, over the average distance pdf.
    num: Rgb,
    /// Each channel's product of distance pdfs, over their average.
    den: Rgb,
}

impl Default for PathWeight {
    fn default() -> Self {
        Self { num: [1.0; 3], den: [1.0; 3] }
    }
}

impl PathWeight {
    /// A flight with transmittance `tr` per channel, which channel c's free flight samples with
    /// density `pdf[c]` (hero channel chosen uniformly: the path's pdf is their average).
    fn distance(&mut self, tr: Rgb, pdf: Rgb) {
        let den: Rgb = std::array::from_fn(|c| self.den[c] * pdf[c]);
        let avg = den.iter().sum::<f64>() / 3.0;
        if avg > 0.0 && avg.is_finite() {
            self.num = std::array::from_fn(|c| self.num[c] * tr[c] / avg);
            self.den = den.map(|x| x / avg);
        } else {
            self.num = [0.0; 3];
        }
    }

    /// A factor that takes no sampling decision (scattering over a direction's pdf, albedo).
    fn scale(&mut self, k: Rgb) {
        self.num = std::array::from_fn(|c| self.num[c] * k[c]);
    }

    /// The weight per channel of the path so far.
    fn throughput(&self) -> Rgb {
        self.num
    }
}

/// A direction at angle `acos(cos)` from `axis`, uniform in azimuth.
fn around(axis: DVec3, cos: f64, rng: &mut fastrand::Rng) -> DVec3 {
    let phi = 2.0 * PI * rng.f64();
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let (t, b) = axis.any_orthonormal_pair();
    (axis * cos + t * (sin * phi.cos()) + b * (sin * phi.sin())).normalize()
}

/// The cosine of a sample of the Rayleigh phase function, (3/8)(1 + cos^2) in cos: the root of
/// the cubic its distribution function gives (Cardano).
fn sample_rayleigh_cos(rng: &mut fastrand::Rng) -> f64 {
    let q = 4.0 * rng.f64() - 2.0;
    let r = (q * q + 1.0).sqrt();
    ((q + r).cbrt() + (q - r).cbrt()).clamp(-1.0, 1.0)
}

/// The cosine of a Henyey-Greenstein(g) sample (uniform where g is 0).
fn sample_hg_cos(g: f64, rng: &mut fastrand::Rng) -> f64 {
    if g.abs() < 1e-6 {
        return 2.0 * rng.f64() - 1.0;
    }
    let k = (1.0 - g * g) / (1.0 - g + 2.0 * g * rng.f64());
    ((1.0 + g * g - k * k) / (2.0 * g)).clamp(-1.0, 1.0)
}

/// Henyey-Greenstein(g)'s density at a cosine, sr^-1.
fn hg_pdf(cos: f64, g: f64) -> f64 {
    if g.abs() < 1e-6 {
        1.0 / (4.0 * PI)
    } else {
        henyey_greenstein_phase(cos, g)
    }
}

/// The reference integrator for one atmosphere.
pub struct Reference {
    atm: Atmosphere,
    /// Quadrature and sampling settings.
    pub settings: ReferenceSettings,
    /// The sun's optical depth for orders 2 and up, made on the first path.
    sun_table: std::sync::OnceLock<SunTable>,
}

/// How a point's sunlight is found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SunlightBy {
    /// The adaptive quadrature along the ray to the sun (single scattering).
    Quadrature,
    /// The tabulated optical depth (reference/sun_table.rs; orders 2 and up).
    Table,
}

/// Distances along `p + t d` where it crosses a sphere of `radius` centred on the planet.
fn ray_sphere(p: DVec3, d: DVec3, radius: f64) -> Option<(f64, f64)> {
    let b = p.dot(d);
    let c = p.length_squared() - radius * radius;
    let disc = b * b - c;
    (disc >= 0.0).then(|| {
        let s = disc.sqrt();
        (-b - s, -b + s)
    })
}

fn add(a: Rgb, b: Rgb) -> Rgb {
    std::array::from_fn(|c| a[c] + b[c])
}

fn scale(a: Rgb, k: f64) -> Rgb {
    a.map(|x| x * k)
}

impl Reference {
    /// A reference for `atm` (which should be valid: see [`Atmosphere::validate`]).
    pub fn new(atm: Atmosphere, settings: ReferenceSettings) -> Self {
        Self { atm, settings, sun_table: std::sync::OnceLock::new() }
    }

    /// The atmosphere.
    pub fn atmosphere(&self) -> &Atmosphere {
        &self.atm
    }

    fn altitude(&self, p: DVec3) -> f64 {
        p.length() - self.atm.ground_radius_km
    }

    /// Extinction per channel at a point, km^-1.
    fn extinction(&self, p: DVec3) -> Rgb {
        self.atm.medium(self.altitude(p)).extinction
    }

    /// Length of the ray from `p` along `d` inside the atmosphere, and whether it ends on the ground.
    /// `p` must be inside the atmosphere (or on its boundary).
    fn extent(&self, p: DVec3, d: DVec3) -> (f64, bool) {
        if let Some((t0, t1)) = ray_sphere(p, d, self.atm.ground_radius_km) {
            // A ray starting on the ground and leaving it has t1 ~ 0; one entering it has t0 ~ 0.
            if t0 >= -1e-9 && t1 > 1e-9 {
                return (t0.max(0.0), true);
            }
        }
        let t = ray_sphere(p, d, self.atm.top_radius_km).map_or(0.0, |(_, t1)| t1.max(0.0));
        (t, false)
    }

    /// Adaptive Simpson on the optical depth of [a, b]; appends accepted panels.
    #[allow(clippy::too_many_arguments)]
    fn refine(&self, p: DVec3, d: DVec3, (a, b): (f64, f64), (fa, fm, fb): (Rgb, Rgb, Rgb), depth: u32, out: &mut Vec<(f64, Rgb)>) {
        let m = 0.5 * (a + b);
        let (lm, rm) = (0.5 * (a + m), 0.5 * (m + b));
        let (flm, frm) = (self.extinction(p + d * lm), self.extinction(p + d * rm));
        let simpson = |h: f64, x: f64, y: f64, z: f64| h / 6.0 * (x + 4.0 * y + z);
        let whole: Rgb = std::array::from_fn(|c| simpson(b - a, fa[c], fm[c], fb[c]));
        let left: Rgb = std::array::from_fn(|c| simpson(m - a, fa[c], flm[c], fm[c]));
        let right: Rgb = std::array::from_fn(|c| simpson(b - m, fm[c], frm[c], fb[c]));
        let err = (0..3).map(|c| (left[c] + right[c] - whole[c]).abs()).fold(0.0, f64::max);
        let too_long = b - a > self.settings.max_panel_km;
        if depth < 40 && (too_long || err > 15.0 * self.settings.tau_tolerance * ((b - a) / self.settings.max_panel_km).clamp(1e-3, 1.0)) {
            self.refine(p, d, (a, m), (fa, flm, fm), depth + 1, out);
            self.refine(p, d, (m, b), (fm, frm, fb), depth + 1, out);
        } else {
            let tau: Rgb = std::array::from_fn(|c| left[c] + right[c] + (left[c] + right[c] - whole[c]) / 15.0);
            out.push((b, tau));
        }
    }

    /// The ray from `p` along `d` to the ground or the top, cut into accurate panels.
    fn segment(&self, p: DVec3, d: DVec3) -> Segment {
        self.segment_within(p, d, f64::INFINITY)
    }

    /// [`Self::segment`] stopped after `limit_km` if it is still in the air there (then it ends
    /// on neither the ground nor the top: `ground` is false and nothing lies beyond).
    fn segment_within(&self, p: DVec3, d: DVec3, limit_km: f64) -> Segment {
        let (extent, reaches_ground) = self.extent(p, d);
        let (length, ground) = if limit_km < extent { (limit_km.max(0.0), false) } else { (extent, reaches_ground) };
        let mut panels = Vec::new();
        if length > 0.0 {
            // Simpson's error estimate misses kinks: cut the ray where it crosses the ozone tent's corners.
            let mut cuts = vec![0.0, length];
            let a = &self.atm;
            for h in [a.ozone_center_km - a.ozone_half_width_km, a.ozone_center_km, a.ozone_center_km + a.ozone_half_width_km] {
                if let Some((t0, t1)) = ray_sphere(p, d, a.ground_radius_km + h) {
                    cuts.extend([t0, t1].into_iter().filter(|t| *t > 1e-9 && *t < length - 1e-9));
                }
            }
            cuts.sort_by(f64::total_cmp);
            for w in cuts.windows(2) {
                let (t0, t1) = (w[0], w[1]);
                let (fa, fm, fb) = (self.extinction(p + d * t0), self.extinction(p + d * (0.5 * (t0 + t1))), self.extinction(p + d * t1));
                self.refine(p, d, (t0, t1), (fa, fm, fb), 0, &mut panels);
            }
        }
        let mut nodes = vec![0.0];
        let mut tau = vec![[0.0; 3]];
        for (b, t) in panels {
            nodes.push(b);
            tau.push(add(*tau.last().expect("non-empty"), t));
        }
        if nodes.len() == 1 {
            nodes.push(0.0);
            tau.push([0.0; 3]);
        }
        Segment { origin: p, dir: d, nodes, tau, ground }
    }

    /// Transmittance from `p` to space along `d`, per channel (0 if the ray hits the ground).
    pub fn transmittance_to_space(&self, p: DVec3, d: DVec3) -> Rgb {
        let s = self.segment(p, d);
        if s.ground {
            return [0.0; 3];
        }
        s.tau.last().expect("non-empty").map(|t| (-t).exp())
    }

    /// Optical depth from `altitude_km` to space along a direction `view_elev_deg` above the
    /// horizon, per channel (infinite through the ground).
    pub fn optical_depth(&self, altitude_km: f64, view_elev_deg: f64) -> Rgb {
        let p = DVec3::new(0.0, self.atm.ground_radius_km + altitude_km, 0.0);
        let e = view_elev_deg.to_radians();
        let s = self.segment(p, DVec3::new(e.cos(), e.sin(), 0.0));
        if s.ground {
            [f64::INFINITY; 3]
        } else {
            *s.tau.last().expect("non-empty")
        }
    }

    /// The sunlight reaching `p`, per channel: the transmittance to space towards the sun while
    /// the sun is above `p`'s horizon; below it, fading smoothly to 0 over
    /// [`super::SUN_SET_FADE_RAD`], lit along the horizon (the GPU models do the same, so that no
    /// model's sky jumps as the sun sets).
    pub fn sunlight(&self, p: DVec3, towards_sun: DVec3) -> Rgb {
        self.sunlight_by(p, towards_sun, SunlightBy::Quadrature)
    }

    /// [`Self::sunlight`], its transmittance found `by` quadrature or the table.
    pub fn sunlight_by(&self, p: DVec3, towards_sun: DVec3, by: SunlightBy) -> Rgb {
        let (up, mu_s, mu_h, above) = self.sun_geometry(p, towards_sun);
        let fraction = super::sun_set_fade(above);
        if fraction <= 0.0 {
            return [0.0; 3];
        }
        let dir = if above >= 1e-6 {
            towards_sun
        } else {
            // Just above the horizon, towards the sun's azimuth.
            let side = (towards_sun - up * mu_s).try_normalize().unwrap_or_else(|| up.any_orthogonal_vector().normalize());
            let mu = (mu_h.asin() + 1e-6).sin();
            up * mu + side * (1.0 - mu * mu).max(0.0).sqrt()
        };
        match by {
            SunlightBy::Quadrature => self.transmittance_to_space(p, dir).map(|t| t * fraction),
            SunlightBy::Table => {
                let r = p.length();
                let table = self.sun_table.get_or_init(|| SunTable::new(self));
                table.optical_depth(r, p.dot(dir) / r).map(|tau| (-tau).exp() * fraction)
            }
        }
    }

    /// At `p`: the local up, the cosines of the sun's zenith angle and of the horizon's, and the
    /// sun's angle above that horizon, radians.
    fn sun_geometry(&self, p: DVec3, towards_sun: DVec3) -> (DVec3, f64, f64, f64) {
        let up = p.normalize();
        let mu_s = up.dot(towards_sun).clamp(-1.0, 1.0);
        let sin_horizon = (self.atm.ground_radius_km / p.length().max(self.atm.ground_radius_km)).min(1.0);
        let mu_h = -(1.0 - sin_horizon * sin_horizon).max(0.0).sqrt();
        (up, mu_s, mu_h, mu_s.asin() - mu_h.asin())
    }

    /// Whether any sunlight reaches `p` (the sun has not faded out below its horizon).
    fn lit(&self, p: DVec3, towards_sun: DVec3) -> bool {
        super::sun_set_fade(self.sun_geometry(p, towards_sun).3) > 0.0
    }

    /// The parts of `seg` the sun lights, as intervals of t: the lit state at every node (panels
    /// are at most `max_panel_km` long), each change refined by bisection. Only a sampling
    /// density is made of them, so a shadow narrower than a panel, missed, costs variance, not
    /// bias.
    fn sunlit(&self, seg: &Segment, towards_sun: DVec3) -> Vec<(f64, f64)> {
        // On the sun's side of the plane through the planet's centre facing it, the sun is above
        // every point's horizon (mu_s >= 0 > mu_h): a segment with both ends there is lit
        // throughout, and needs no scan (every segment by day, nearly).
        let end = seg.origin + seg.dir * seg.length();
        if seg.origin.dot(towards_sun) >= 0.0 && end.dot(towards_sun) >= 0.0 {
            return vec![(0.0, seg.length())];
        }
        let lit = |t: f64| self.lit(seg.origin + seg.dir * t, towards_sun);
        let mut out = Vec::new();
        let mut from = lit(0.0).then_some(0.0);
        let (mut last_t, mut last_lit) = (0.0, from.is_some());
        for &t in &seg.nodes[1..] {
            let now = lit(t);
            if now != last_lit {
                let (mut a, mut b) = (last_t, t);
                for _ in 0..32 {
                    let m = 0.5 * (a + b);
                    if lit(m) == last_lit {
                        a = m;
                    } else {
                        b = m;
                    }
                }
                let edge = 0.5 * (a + b);
                match from.take() {
                    Some(start) => out.push((start, edge)),
                    None => from = Some(edge),
                }
            }
            (last_t, last_lit) = (t, now);
        }
        if let Some(start) = from {
            out.push((start, seg.length()));
        }
        out.retain(|(a, b)| b > a);
        out
    }

    /// Sunlight scattered once towards `-d` at `y`, per unit length: S(y, d·s) T_sun(y).
    fn sun_scattered(&self, y: DVec3, d: DVec3, towards_sun: DVec3, by: SunlightBy) -> Rgb {
        let t_sun = self.sunlight_by(y, towards_sun, by);
        if t_sun.iter().all(|t| *t == 0.0) {
            return [0.0; 3];
        }
        let s = self.scattering(y, d.dot(towards_sun));
        std::array::from_fn(|c| s[c] * t_sun[c])
    }

    /// Phase-weighted scattering at a point for a scattering-angle cosine, km^-1 sr^-1.
    fn scattering(&self, y: DVec3, cos_theta: f64) -> Rgb {
        let m = self.atm.medium(self.altitude(y));
        let (pr, pm) = (rayleigh_phase(cos_theta), cornette_shanks_phase(cos_theta, self.atm.mie_g));
        std::array::from_fn(|c| m.rayleigh[c] * pr + m.mie[c] * pm)
    }

    /// Single-scattered radiance arriving at `p` from direction `d`, sr^-1.
    fn single(&self, seg: &Segment, towards_sun: DVec3) -> Rgb {
        let mut sum = [0.0; 3];
        let j = |t: f64, tau: Rgb| -> Rgb {
            let s = self.sun_scattered(seg.origin + seg.dir * t, seg.dir, towards_sun, self.settings.single_sunlight);
            std::array::from_fn(|c| s[c] * (-tau[c]).exp())
        };
        let mut j_a = j(seg.nodes[0], seg.tau[0]);
        for i in 1..seg.nodes.len() {
            let (a, b) = (seg.nodes[i - 1], seg.nodes[i]);
            if b <= a {
                continue;
            }
            let m = 0.5 * (a + b);
            // Optical depth to the panel's middle: Simpson on its first half.
            let (ea, em, eq) = (self.extinction(seg.origin + seg.dir * a), self.extinction(seg.origin + seg.dir * m), self.extinction(seg.origin + seg.dir * (0.5 * (a + m))));
            let tau_m: Rgb = std::array::from_fn(|c| seg.tau[i - 1][c] + (m - a) / 6.0 * (ea[c] + 4.0 * eq[c] + em[c]));
            let j_m = j(m, tau_m);
            let j_b = j(b, seg.tau[i]);
            sum = add(sum, std::array::from_fn(|c| (b - a) / 6.0 * (j_a[c] + 4.0 * j_m[c] + j_b[c])));
            j_a = j_b;
        }
        sum
    }

    /// A direction leaving `pos` that arrived along `d_in`, and its pdf: 3/4 from the medium's
    /// own phase function there (Rayleigh or Henyey-Greenstein(g) for the aerosols, chosen in
    /// proportion to their scattering averaged over the channels), 1/4 from
    /// Henyey-Greenstein([`SUN_LOBE_G`]) around `towards_sun`, where the sunlit sky is brightest
    /// (above all at twilight). Following the phase function keeps the path's weight nearly
    /// constant from bounce to bounce, which the high orders need.
    fn sample_direction(&self, pos: DVec3, d_in: DVec3, towards_sun: DVec3, rng: &mut fastrand::Rng) -> (DVec3, f64) {
        let g = self.atm.mie_g;
        let m = self.atm.medium(self.altitude(pos));
        let rayleigh = m.rayleigh.iter().sum::<f64>() / 3.0;
        let mie = m.mie.iter().sum::<f64>() / 3.0;
        let p_rayleigh = if rayleigh + mie > 0.0 { rayleigh / (rayleigh + mie) } else { 1.0 };
        let u = rng.f64();
        let out = if u < 0.25 {
            around(towards_sun, sample_hg_cos(SUN_LOBE_G, rng), rng)
        } else if u < 0.25 + 0.75 * p_rayleigh {
            around(d_in, sample_rayleigh_cos(rng), rng)
        } else {
            around(d_in, sample_hg_cos(g, rng), rng)
        };
        let cos = d_in.dot(out);
        let pdf = 0.25 * hg_pdf(towards_sun.dot(out), SUN_LOBE_G) + 0.75 * (p_rayleigh * rayleigh_phase(cos) + (1.0 - p_rayleigh) * hg_pdf(cos, g));
        (out, pdf)
    }

    /// Orders 2..=max_order by path tracing; `seg` is the view ray, `single` the deterministic
    /// first order (what a target standard error is relative to). Returns the estimate, its
    /// standard error per channel and the paths drawn.
    ///
    /// Paths go in batches of [`BATCH_PATHS`], up to `threads` batches at once; their
    /// contributions are added in path order and a target is checked after each batch in
    /// order, so the result is the same on any number of threads (batches drawn past the stop
    /// are thrown away).
    fn multiple(&self, seg: &Segment, towards_sun: DVec3, albedo: f64, single: Rgb, threads: usize) -> (Rgb, Rgb, u32) {
        let max_order = self.settings.max_order;
        let total = seg.total();
        if max_order < 2 || total.iter().all(|t| *t <= 0.0) || self.settings.paths == 0 {
            return ([0.0; 3], [0.0; 3], 0);
        }
        // Probability that a forced collision lands anywhere in the view segment, per channel.
        let p_in = total.map(|t| -(-t).exp_m1());
        let cap = self.settings.paths;
        let batches = cap.div_ceil(BATCH_PATHS);
        let batch = |b: u32| -> Vec<Rgb> { (b * BATCH_PATHS..((b + 1) * BATCH_PATHS).min(cap)).map(|i| self.path(seg, towards_sun, albedo, p_in, u64::from(i))).collect() };
        let mut sums = PathSums::default();
        let mut next = 0;
        'batches: while next < batches {
            let round = (threads.max(1) as u32).min(batches - next);
            let drawn: Vec<Vec<Rgb>> = if round == 1 {
                vec![batch(next)]
            } else {
                std::thread::scope(|s| {
                    let handles: Vec<_> = (next..next + round).map(|b| s.spawn(move || batch(b))).collect();
                    handles.into_iter().map(|h| h.join().unwrap_or_else(|p| std::panic::resume_unwind(p))).collect()
                })
            };
            for paths in drawn {
                for x in paths {
                    sums.add(x);
                }
                if let Some(target) = self.settings.target_rel_se {
                    if sums.n >= self.settings.min_paths && sums.within(single, target) {
                        break 'batches;
                    }
                }
            }
            next += round;
        }
        let (mean, std_err) = sums.mean_and_error();
        (mean, std_err, sums.n)
    }

    /// One path's contribution (orders 2 and up), path number `path` of the seed's stream.
    ///
    /// Distances are sampled by free flight in one channel per path (chosen at random) and
    /// every channel is weighed by the average over the three of the whole path's distance pdf
    /// (spectral MIS per path): each channel's weight stays below 3 however long the path, where
    /// averaging per segment lets a channel's weight grow with every bounce (heavy tails in the
    /// high orders at twilight, where paths are long).
    fn path(&self, seg: &Segment, towards_sun: DVec3, albedo: f64, p_in: Rgb, path: u64) -> Rgb {
        let max_order = self.settings.max_order;
        let mut path_sum = [0.0; 3];
        // One stream per path: truncating at an order changes no other path.
        let rng = &mut fastrand::Rng::with_seed(self.settings.seed.wrapping_mul(0x9e37_79b9_7f4a_7c15).wrapping_add(path));
        let hero = rng.usize(0..3);
        if p_in[hero] <= 0.0 {
            return [0.0; 3];
        }
        // Vertex 1: forced into the view segment (its own sunlight is order 1, done exactly).
        let t = seg.invert(hero, -(1.0 - rng.f64() * p_in[hero]).ln());
        let (tau, slope) = seg.at(t);
        let mut weight = PathWeight::default();
        weight.distance(std::array::from_fn(|c| (-tau[c]).exp()), std::array::from_fn(|c| if p_in[c] > 0.0 { slope[c] * (-tau[c]).exp() / p_in[c] } else { 0.0 }));
        let mut pos = seg.origin + seg.dir * t;
        let mut d_in = seg.dir;
        let mut k = 1;
        let mut on_ground = false;
        while k < max_order {
            // Leave the vertex: scatter in the air, or reflect off the ground.
            let dir = if on_ground {
                let n = pos.normalize();
                let (u, v) = (rng.f64(), 2.0 * PI * rng.f64());
                let (t1, t2) = n.any_orthonormal_pair();
                let r = u.sqrt();
                weight.scale([albedo; 3]);
                (n * (1.0 - u).sqrt() + t1 * (r * v.cos()) + t2 * (r * v.sin())).normalize()
            } else {
                let (dir, pdf) = self.sample_direction(pos, d_in, towards_sun, rng);
                let s = self.scattering(pos, d_in.dot(dir));
                weight.scale(s.map(|x| x / pdf));
                dir
            };
            if weight.throughput().iter().all(|x| *x <= 0.0) {
                break;
            }
            let (lit, next) = self.gathered(pos, dir, weight.throughput(), towards_sun, albedo, rng);
            path_sum = add(path_sum, lit);
            let total = next.total();
            let target = -(1.0 - rng.f64()).ln();
            if target < total[hero] {
                let t = next.invert(hero, target);
                let (tau, slope) = next.at(t);
                let tr = tau.map(|x| (-x).exp());
                weight.distance(tr, std::array::from_fn(|c| slope[c] * tr[c]));
                pos += dir * t;
                d_in = dir;
                on_ground = false;
                k += 1;
            } else if next.ground {
                // Every channel's flight passes the whole segment with its transmittance.
                let tr = total.map(|x| (-x).exp());
                weight.distance(tr, tr);
                pos = (pos + dir * next.length()).normalize() * self.atm.ground_radius_km;
                on_ground = true;
                k += 1;
            } else {
                break;
            }
        }
        path_sum
    }

    /// The light a path gathers leaving `pos` along `dir` with throughput `thr` (one order more
    /// than the vertex's), and the segment: the sunlight scattered towards `pos` along it, by
    /// stratified sampling of its sunlit part (so the next collision only carries the path on),
    /// and the sunlit ground at its end seen through all of it.
    fn gathered(&self, pos: DVec3, dir: DVec3, thr: Rgb, towards_sun: DVec3, albedo: f64, rng: &mut fastrand::Rng) -> (Rgb, Segment) {
        let next = self.segment(pos, dir);
        let mut sum = [0.0; 3];
        let strata = SunlitStrata::new(&next, &self.sunlit(&next, towards_sun));
        if !strata.is_empty() {
            let lit = strata.estimate(&next, rng, |t| self.sun_scattered(pos + dir * t, dir, towards_sun, SunlightBy::Table));
            sum = add(sum, std::array::from_fn(|c| thr[c] * lit[c]));
        }
        if next.ground && albedo > 0.0 {
            let n = (pos + dir * next.length()).normalize();
            let cos_sun = n.dot(towards_sun);
            if cos_sun > 0.0 {
                let t_sun = self.sunlight_by(n * self.atm.ground_radius_km, towards_sun, SunlightBy::Table);
                let total = next.total();
                sum = add(sum, std::array::from_fn(|c| thr[c] * (-total[c]).exp() * albedo / PI * cos_sun * t_sun[c]));
            }
        }
        (sum, next)
    }

    /// Sky radiance for a case, sr^-1 per unit of solar irradiance: (single scattering, all orders
    /// up to `max_order`).
    pub fn radiance_split(&self, case: &Case) -> (Rgb, Rgb) {
        let e = self.estimate(case);
        (e.single, e.all)
    }

    /// Sky radiance for a case with the Monte Carlo standard error of its orders >= 2.
    pub fn estimate(&self, case: &Case) -> Estimate {
        self.estimate_on(case, 1)
    }

    /// [`Self::estimate`] with the case's paths drawn on up to `threads` threads (the same
    /// result on any number): for when there are fewer cases than cores.
    pub fn estimate_on(&self, case: &Case, threads: usize) -> Estimate {
        let p = DVec3::new(0.0, self.atm.ground_radius_km + case.camera_km.max(0.0), 0.0);
        let se = case.sun_elev_deg.to_radians();
        let towards_sun = DVec3::new(se.cos(), se.sin(), 0.0);
        let (ve, az) = (case.view_elev_deg.to_radians(), case.rel_azimuth_deg.to_radians());
        let d = DVec3::new(ve.cos() * az.cos(), ve.sin(), ve.cos() * az.sin()).normalize();
        let seg = self.segment_within(p, d, case.distance_km.unwrap_or(f64::INFINITY));
        let single = self.single(&seg, towards_sun);
        let (multiple, std_err, paths) = self.multiple(&seg, towards_sun, case.albedo.clamp(0.0, 1.0), single, threads);
        Estimate { single, all: add(single, multiple), std_err, paths, transmittance: seg.total().map(|t| (-t).exp()) }
    }

    /// Sky radiance for a case (all orders up to `max_order`), sr^-1 per unit of solar irradiance.
    pub fn radiance(&self, case: &Case) -> Rgb {
        self.radiance_split(case).1
    }
}
