//! The reference: a CPU, double-precision integrator of sky radiance with every order of
//! scattering, ozone absorption and a Lambertian ground. Too slow for frames; the ground truth
//! the real-time models are measured against.
//!
//! - Single scattering is integrated deterministically: adaptive Simpson panels along the view
//!   ray (refined until the optical depth of each panel is accurate to `tau_tolerance`, and no
//!   longer than `max_panel_km`), Simpson's rule on each panel, the sun's transmittance at every
//!   node by the same adaptive quadrature.
//! - Orders 2 and up are estimated by Monte Carlo path tracing with next-event estimation
//!   towards the sun: distances sampled by free flight (one channel chosen at random, weighed
//!   by the three channels' average density), directions from a mixture of
//!   Henyey-Greenstein(g) and uniform, a Lambertian ground of albedo `a`. Where the planet's
//!   shadow covers part of a path's segment (twilight: the sun below the camera's horizon, the
//!   sunlit air high above), free flight rarely stops in the sunlit part and next-event
//!   estimation mostly finds the shadow; each such segment also gets a second estimate of its
//!   sunlight, from a distance sampled in its sunlit part only, the two combined by multiple
//!   importance sampling (balance heuristic, Veach 1997) so the sum stays unbiased. A fixed seed makes results repeatable, and
//!   truncating at `max_order` only drops terms, so radiance never decreases with more orders.
//!
//! The sun is a point source of irradiance 1 per channel (its disc is not part of the result)
//! whose light fades out smoothly while it sinks 0.1 degrees below a point's horizon
//! ([`Reference::sunlight`], as the GPU models do, so that no sky jumps as the sun sets);
//! the ground surface seen by a view ray that hits it is not part of the result either (only
//! the light scattered along the ray in front of it).

use std::f64::consts::PI;

use glam::DVec3;

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
    /// Monte Carlo paths per radiance value for orders >= 2.
    pub paths: u32,
    /// Seed of the paths.
    pub seed: u64,
}

impl Default for ReferenceSettings {
    fn default() -> Self {
        Self { tau_tolerance: 1e-7, max_panel_km: 1.0, max_order: 24, paths: 8192, seed: 0x5eed }
    }
}

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
}

/// A ray segment inside the atmosphere, cut into panels with their optical depths.
struct Segment {
    origin: DVec3,
    dir: DVec3,
    /// Panel boundaries, t in km: nodes[0] = 0, last = length.
    nodes: Vec<f64>,
    /// Optical depth from the origin to each node, per channel.
    tau: Vec<Rgb>,
    /// Whether the segment ends on the ground (else at the top of the atmosphere).
    ground: bool,
}

impl Segment {
    fn length(&self) -> f64 {
        *self.nodes.last().unwrap_or(&0.0)
    }

    fn total(&self) -> Rgb {
        *self.tau.last().unwrap_or(&[0.0; 3])
    }

    /// Optical depth per channel at t (linear within a panel) and the panel's extinction per channel.
    fn at(&self, t: f64) -> (Rgb, Rgb) {
        let i = self.nodes.partition_point(|&n| n <= t).clamp(1, self.nodes.len() - 1);
        let (a, b) = (self.nodes[i - 1], self.nodes[i]);
        let w = b - a;
        let f = if w > 0.0 { ((t - a) / w).clamp(0.0, 1.0) } else { 0.0 };
        let tau = std::array::from_fn(|c| self.tau[i - 1][c] + f * (self.tau[i][c] - self.tau[i - 1][c]));
        let slope = std::array::from_fn(|c| if w > 0.0 { (self.tau[i][c] - self.tau[i - 1][c]) / w } else { 0.0 });
        (tau, slope)
    }

    /// The t where channel `c`'s optical depth reaches `target` (< its total).
    fn invert(&self, c: usize, target: f64) -> f64 {
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

/// Distances along a segment sampled in its sunlit intervals only: one channel chosen at random,
/// then its free-flight density restricted to those intervals (the pdf is the three channels'
/// average, as for free flight).
struct SunlitSampler {
    intervals: Vec<(f64, f64)>,
    /// Probability, per channel, that free flight would stop in each interval.
    mass: Vec<Rgb>,
    /// Their sum, per channel.
    total: Rgb,
}

impl SunlitSampler {
    /// A sampler for `seg`'s sunlit `intervals`; None where they cover the whole segment or
    /// nothing (free flight alone serves both).
    fn new(seg: &Segment, intervals: Vec<(f64, f64)>) -> Option<Self> {
        let length = seg.length();
        let whole = intervals.len() == 1 && intervals[0].0 <= 1e-9 && intervals[0].1 >= length - 1e-9;
        if intervals.is_empty() || whole {
            return None;
        }
        let mass: Vec<Rgb> = intervals
            .iter()
            .map(|&(a, b)| {
                let (ta, tb) = (seg.at(a).0, seg.at(b).0);
                std::array::from_fn(|c| ((-ta[c]).exp() - (-tb[c]).exp()).max(0.0))
            })
            .collect();
        let total = mass.iter().fold([0.0; 3], |acc, m| add(acc, *m));
        total.iter().any(|m| *m > 0.0).then_some(Self { intervals, mass, total })
    }

    /// A distance, or None (the channel chosen has no mass there).
    fn sample(&self, seg: &Segment, rng: &mut fastrand::Rng) -> Option<f64> {
        let j = rng.usize(0..3);
        if self.total[j] <= 0.0 {
            return None;
        }
        let mut r = rng.f64() * self.total[j];
        for (&(a, b), m) in self.intervals.iter().zip(&self.mass) {
            if r < m[j] || (a, b) == *self.intervals.last().expect("non-empty") {
                let t_a = (-seg.at(a).0[j]).exp();
                let tau = -(t_a - r.min(m[j])).max(1e-300).ln();
                return Some(seg.invert(j, tau).clamp(a, b));
            }
            r -= m[j];
        }
        None
    }

    /// The density of [`Self::sample`] at `t`, given the optical depth and extinction there.
    fn pdf(&self, t: f64, (tau, slope): (Rgb, Rgb)) -> f64 {
        if !self.intervals.iter().any(|&(a, b)| t >= a && t <= b) {
            return 0.0;
        }
        (0..3).filter(|&c| self.total[c] > 0.0).map(|c| slope[c] * (-tau[c]).exp() / self.total[c]).sum::<f64>() / 3.0
    }
}

/// The reference integrator for one atmosphere.
pub struct Reference {
    atm: Atmosphere,
    /// Quadrature and sampling settings.
    pub settings: ReferenceSettings,
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
        Self { atm, settings }
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
        let (length, ground) = self.extent(p, d);
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
        self.transmittance_to_space(p, dir).map(|t| t * fraction)
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
    fn sun_scattered(&self, y: DVec3, d: DVec3, towards_sun: DVec3) -> Rgb {
        let t_sun = self.sunlight(y, towards_sun);
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
        std::array::from_fn(|c| m.rayleigh[c] * pr + m.mie * pm)
    }

    /// Single-scattered radiance arriving at `p` from direction `d`, sr^-1.
    fn single(&self, seg: &Segment, towards_sun: DVec3) -> Rgb {
        let mut sum = [0.0; 3];
        let j = |t: f64, tau: Rgb| -> Rgb {
            let s = self.sun_scattered(seg.origin + seg.dir * t, seg.dir, towards_sun);
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

    /// A direction around `d` from the mixture 1/2 Henyey-Greenstein(g) + 1/2 uniform, and its pdf.
    fn sample_direction(&self, d: DVec3, rng: &mut fastrand::Rng) -> (DVec3, f64) {
        let g = self.atm.mie_g;
        let cos = if rng.bool() || g.abs() < 1e-6 {
            2.0 * rng.f64() - 1.0
        } else {
            let k = (1.0 - g * g) / (1.0 - g + 2.0 * g * rng.f64());
            ((1.0 + g * g - k * k) / (2.0 * g)).clamp(-1.0, 1.0)
        };
        let phi = 2.0 * PI * rng.f64();
        let sin = (1.0 - cos * cos).max(0.0).sqrt();
        let (t, b) = d.any_orthonormal_pair();
        let out = (d * cos + t * (sin * phi.cos()) + b * (sin * phi.sin())).normalize();
        let pdf = 0.5 / (4.0 * PI) + 0.5 * if g.abs() < 1e-6 { 1.0 / (4.0 * PI) } else { henyey_greenstein_phase(cos, g) };
        (out, pdf)
    }

    /// Orders 2..=max_order by path tracing; `seg` is the view ray. Distances are sampled in one
    /// channel chosen at random and weighted by the average pdf of the three (spectral MIS), which
    /// keeps every channel's weight bounded.
    /// Returns the estimate and its standard error per channel.
    fn multiple(&self, seg: &Segment, towards_sun: DVec3, albedo: f64) -> (Rgb, Rgb) {
        let max_order = self.settings.max_order;
        let total = seg.total();
        if max_order < 2 || total.iter().all(|t| *t <= 0.0) || self.settings.paths == 0 {
            return ([0.0; 3], [0.0; 3]);
        }
        // Probability that a forced collision lands anywhere in the view segment, per channel.
        let p_in = total.map(|t| -(-t).exp_m1());
        let (mut sum, mut sum_sq) = ([0.0; 3], [0.0; 3]);
        for path in 0..self.settings.paths {
            let mut path_sum = [0.0; 3];
            // One stream per path: truncating at an order changes no other path.
            let rng = &mut fastrand::Rng::with_seed(self.settings.seed.wrapping_mul(0x9e37_79b9_7f4a_7c15).wrapping_add(path as u64));
            // Vertex 1: forced into the view segment (its own sunlight is order 1, done exactly).
            let j = rng.usize(0..3);
            if p_in[j] <= 0.0 {
                continue;
            }
            let t = seg.invert(j, -(1.0 - rng.f64() * p_in[j]).ln());
            let (tau, slope) = seg.at(t);
            let pdf = (0..3).filter(|c| p_in[*c] > 0.0).map(|c| slope[c] * (-tau[c]).exp() / p_in[c]).sum::<f64>() / 3.0;
            if pdf <= 0.0 {
                continue;
            }
            let mut thr: Rgb = std::array::from_fn(|c| (-tau[c]).exp() / pdf);
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
                    thr = scale(thr, albedo);
                    (n * (1.0 - u).sqrt() + t1 * (r * v.cos()) + t2 * (r * v.sin())).normalize()
                } else {
                    let (dir, pdf) = self.sample_direction(d_in, rng);
                    let s = self.scattering(pos, d_in.dot(dir));
                    thr = std::array::from_fn(|c| thr[c] * s[c] / pdf);
                    dir
                };
                if thr.iter().all(|x| *x <= 0.0) {
                    break;
                }
                let next = self.segment(pos, dir);
                let total = next.total();
                // Part of it in the planet's shadow: its sunlight also from a distance sampled
                // where the sun lights it, weighed against free flight's (balance heuristic).
                let sunlit = SunlitSampler::new(&next, self.sunlit(&next, towards_sun));
                let free_pdf = |(tau, slope): (Rgb, Rgb)| (0..3).map(|c| slope[c] * (-tau[c]).exp()).sum::<f64>() / 3.0;
                if let Some(t2) = sunlit.as_ref().and_then(|s| s.sample(&next, rng)) {
                    let at = next.at(t2);
                    let pdf = free_pdf(at) + sunlit.as_ref().map_or(0.0, |s| s.pdf(t2, at));
                    if pdf > 0.0 {
                        let lit = self.sun_scattered(pos + dir * t2, dir, towards_sun);
                        path_sum = add(path_sum, std::array::from_fn(|c| thr[c] * (-at.0[c]).exp() * lit[c] / pdf));
                    }
                }
                let j = rng.usize(0..3);
                let target = -(1.0 - rng.f64()).ln();
                if target < total[j] {
                    let t = next.invert(j, target);
                    let at = next.at(t);
                    let pdf = free_pdf(at);
                    if pdf <= 0.0 {
                        break;
                    }
                    let weight = sunlit.as_ref().map_or(1.0, |s| pdf / (pdf + s.pdf(t, at)));
                    thr = std::array::from_fn(|c| thr[c] * (-at.0[c]).exp() / pdf);
                    pos += dir * t;
                    d_in = dir;
                    on_ground = false;
                    k += 1;
                    let lit = self.sun_scattered(pos, d_in, towards_sun);
                    path_sum = add(path_sum, std::array::from_fn(|c| weight * thr[c] * lit[c]));
                } else if next.ground {
                    // Reached by the channels whose sampled flight passed the whole segment.
                    let pass = (0..3).map(|c| (-total[c]).exp()).sum::<f64>() / 3.0;
                    thr = std::array::from_fn(|c| thr[c] * (-total[c]).exp() / pass);
                    let n = (pos + dir * next.length()).normalize();
                    pos = n * self.atm.ground_radius_km;
                    on_ground = true;
                    k += 1;
                    let cos_sun = n.dot(towards_sun);
                    if cos_sun > 0.0 && albedo > 0.0 {
                        let t_sun = self.sunlight(pos, towards_sun);
                        path_sum = add(path_sum, std::array::from_fn(|c| thr[c] * albedo / PI * cos_sun * t_sun[c]));
                    }
                } else {
                    break;
                }
            }
            sum = add(sum, path_sum);
            sum_sq = add(sum_sq, path_sum.map(|x| x * x));
        }
        let n = self.settings.paths as f64;
        let mean = scale(sum, 1.0 / n);
        let std_err = std::array::from_fn(|c| ((sum_sq[c] / n - mean[c] * mean[c]).max(0.0) / n).sqrt());
        (mean, std_err)
    }

    /// Sky radiance for a case, sr^-1 per unit of solar irradiance: (single scattering, all orders
    /// up to `max_order`).
    pub fn radiance_split(&self, case: &Case) -> (Rgb, Rgb) {
        let e = self.estimate(case);
        (e.single, e.all)
    }

    /// Sky radiance for a case with the Monte Carlo standard error of its orders >= 2.
    pub fn estimate(&self, case: &Case) -> Estimate {
        let p = DVec3::new(0.0, self.atm.ground_radius_km + case.camera_km.max(0.0), 0.0);
        let se = case.sun_elev_deg.to_radians();
        let towards_sun = DVec3::new(se.cos(), se.sin(), 0.0);
        let (ve, az) = (case.view_elev_deg.to_radians(), case.rel_azimuth_deg.to_radians());
        let d = DVec3::new(ve.cos() * az.cos(), ve.sin(), ve.cos() * az.sin()).normalize();
        let seg = self.segment(p, d);
        let single = self.single(&seg, towards_sun);
        let (multiple, std_err) = self.multiple(&seg, towards_sun, case.albedo.clamp(0.0, 1.0));
        Estimate { single, all: add(single, multiple), std_err }
    }

    /// Sky radiance for a case (all orders up to `max_order`), sr^-1 per unit of solar irradiance.
    pub fn radiance(&self, case: &Case) -> Rgb {
        self.radiance_split(case).1
    }
}
