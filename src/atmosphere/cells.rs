//! The cell model of the procedural-sky text (../shared/references/procedural-sky-scattering-blog.txt):
//! the atmosphere cut into ring-shaped cells by altitude and by angle to the sun (the Earth-sun
//! system is symmetric about the sun's axis), each emitting the sunlight it scatters directly (kept
//! analytic) plus indirect light fitted with spherical harmonics in the cell's own frame, refined
//! over a few iterations; the sky is then ray-marched through the cells. CPU, f64: the text
//! computes it asynchronously and the renderer would only sample the resulting map.
//!
//! Emission J(y, e) is radiance per unit length (km^-1 sr^-1) leaving point y along direction e.
//! Iteration k turns the light received from every direction into new indirect emission, so after
//! k iterations the sky holds k + 1 orders of scattering (the ground lit by the sun included).

use std::f64::consts::PI;

use glam::DVec3;

use super::reference::{Case, Reference, ReferenceSettings};
use super::{cornette_shanks_phase, rayleigh_phase, Atmosphere, Rgb};

/// Resolution and effort of the cell model.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CellSettings {
    /// Cells by altitude (crowded near the ground).
    pub altitude_cells: usize,
    /// Cells by angle between the local vertical and the sun, over [0, pi].
    pub angle_cells: usize,
    /// Directions of the received-light integral: grid x grid, equal-area.
    pub direction_grid: usize,
    /// Samples along each ray.
    pub ray_steps: usize,
    /// Refinement iterations (the text uses 6); 0 gives single scattering.
    pub iterations: usize,
}

impl Default for CellSettings {
    fn default() -> Self {
        Self { altitude_cells: 16, angle_cells: 32, direction_grid: 8, ray_steps: 32, iterations: 6 }
    }
}

/// Real spherical harmonics up to band 2 (9 functions) of a unit vector.
fn sh9(v: DVec3) -> [f64; 9] {
    let (x, y, z) = (v.x, v.y, v.z);
    [
        0.282_094_791_773_878_1,
        0.488_602_511_902_919_9 * y,
        0.488_602_511_902_919_9 * z,
        0.488_602_511_902_919_9 * x,
        1.092_548_430_592_079 * x * y,
        1.092_548_430_592_079 * y * z,
        0.315_391_565_252_520_05 * (3.0 * z * z - 1.0),
        1.092_548_430_592_079 * x * z,
        0.546_274_215_296_039_5 * (x * x - y * y),
    ]
}

/// The solved model for one atmosphere, ground albedo and settings (any sun direction: cells are
/// defined relative to the sun).
pub struct CellModel {
    atm: Atmosphere,
    settings: CellSettings,
    albedo: f64,
    /// Altitude cell boundaries, km (the altitude goes as the square of the cell index).
    altitude_edges: Vec<f64>,
    /// Transmittance to the sun by (altitude, sun angle): a fine table from the reference's quadrature.
    sun_table: Vec<Rgb>,
    sun_table_size: (usize, usize),
    /// Indirect emission per cell: 9 SH coefficients per channel, in the cell's frame.
    indirect: Vec<[[f64; 9]; 3]>,
    /// Stratified unit directions of the received-light integral.
    directions: Vec<DVec3>,
}

/// The solver's sun: cells are rings around this axis.
const SUN: DVec3 = DVec3::Y;

impl CellModel {
    /// Builds the cells and runs `settings.iterations` refinements.
    pub fn solve(atm: Atmosphere, albedo: f64, settings: CellSettings) -> Self {
        let n_h = settings.altitude_cells.max(1);
        let top = atm.thickness_km();
        let altitude_edges = (0..=n_h).map(|k| top * (k as f64 / n_h as f64).powi(2)).collect();
        let g = settings.direction_grid.max(1);
        let directions = (0..g * g)
            .map(|k| {
                let (a, b) = (k / g, k % g);
                let cos = 1.0 - 2.0 * (a as f64 + 0.5) / g as f64;
                let phi = 2.0 * PI * (b as f64 + 0.5) / g as f64;
                let sin = (1.0 - cos * cos).max(0.0).sqrt();
                DVec3::new(sin * phi.cos(), cos, sin * phi.sin())
            })
            .collect();
        let mut model = Self {
            atm,
            settings,
            albedo,
            altitude_edges,
            sun_table: Vec::new(),
            sun_table_size: (64, 256),
            indirect: vec![[[0.0; 9]; 3]; n_h * settings.angle_cells.max(1)],
            directions,
        };
        model.fill_sun_table();
        for _ in 0..settings.iterations {
            model.iterate();
        }
        model
    }

    fn fill_sun_table(&mut self) {
        let reference = Reference::new(self.atm, ReferenceSettings { max_order: 1, tau_tolerance: 1e-6, ..Default::default() });
        let (nh, na) = self.sun_table_size;
        let top = self.atm.thickness_km();
        self.sun_table = (0..nh * na)
            .map(|k| {
                let (i, j) = (k / na, k % na);
                let h = top * (i as f64 / (nh - 1) as f64).powi(2);
                let angle = PI * j as f64 / (na - 1) as f64;
                let p = DVec3::new(0.0, self.atm.ground_radius_km + h, 0.0);
                reference.transmittance_to_space(p, DVec3::new(angle.sin(), angle.cos(), 0.0))
            })
            .collect();
    }

    /// Transmittance to the sun at a point (bilinear in the table).
    fn sun_transmittance(&self, p: DVec3, sun: DVec3) -> Rgb {
        let (nh, na) = self.sun_table_size;
        let top = self.atm.thickness_km();
        let h = (p.length() - self.atm.ground_radius_km).clamp(0.0, top);
        let angle = (p.normalize().dot(sun)).clamp(-1.0, 1.0).acos();
        let x = (h / top).sqrt() * (nh - 1) as f64;
        let y = angle / PI * (na - 1) as f64;
        let (i, j) = ((x.floor() as usize).min(nh - 2), (y.floor() as usize).min(na - 2));
        let (fx, fy) = (x - i as f64, y - j as f64);
        let at = |a: usize, b: usize| self.sun_table[a * na + b];
        std::array::from_fn(|c| {
            let top_row = at(i, j)[c] * (1.0 - fy) + at(i, j + 1)[c] * fy;
            let next_row = at(i + 1, j)[c] * (1.0 - fy) + at(i + 1, j + 1)[c] * fy;
            top_row * (1.0 - fx) + next_row * fx
        })
    }

    /// A point's local frame: tangent towards the sun, up, side.
    fn frame(p: DVec3, sun: DVec3) -> [DVec3; 3] {
        let up = p.normalize();
        let toward_sun = (sun - up * up.dot(sun)).try_normalize().unwrap_or_else(|| up.any_orthogonal_vector().normalize());
        [toward_sun, up, up.cross(toward_sun)]
    }

    /// Centre of cell (altitude index, angle index): its altitude (km) and angle to the sun (rad).
    fn cell_centre(&self, i: usize, j: usize) -> (f64, f64) {
        let n_h = self.altitude_edges.len() - 1;
        let n_a = self.settings.angle_cells.max(1);
        (self.atm.thickness_km() * ((i as f64 + 0.5) / n_h as f64).powi(2), PI * (j as f64 + 0.5) / n_a as f64)
    }

    /// Indirect coefficients at a point, blended bilinearly between the centres of the four
    /// nearest cells (nearest-cell values would show the cell edges as seams in the sky).
    fn indirect_at(&self, p: DVec3, sun: DVec3) -> [[f64; 9]; 3] {
        let n_h = self.altitude_edges.len() - 1;
        let n_a = self.settings.angle_cells.max(1);
        let h = (p.length() - self.atm.ground_radius_km).clamp(0.0, self.atm.thickness_km());
        let angle = p.normalize().dot(sun).clamp(-1.0, 1.0).acos();
        let fi = ((h / self.atm.thickness_km()).sqrt() * n_h as f64 - 0.5).clamp(0.0, (n_h - 1) as f64);
        let fj = (angle / PI * n_a as f64 - 0.5).clamp(0.0, (n_a - 1) as f64);
        let (i0, j0) = (fi.floor() as usize, fj.floor() as usize);
        let (i1, j1) = ((i0 + 1).min(n_h - 1), (j0 + 1).min(n_a - 1));
        let (ti, tj) = (fi - i0 as f64, fj - j0 as f64);
        let mut out = [[0.0; 9]; 3];
        for (i, j, w) in [(i0, j0, (1.0 - ti) * (1.0 - tj)), (i0, j1, (1.0 - ti) * tj), (i1, j0, ti * (1.0 - tj)), (i1, j1, ti * tj)] {
            let c = &self.indirect[i * n_a + j];
            for ch in 0..3 {
                for k in 0..9 {
                    out[ch][k] += w * c[ch][k];
                }
            }
        }
        out
    }

    fn local(frame: &[DVec3; 3], d: DVec3) -> DVec3 {
        DVec3::new(d.dot(frame[0]), d.dot(frame[1]), d.dot(frame[2]))
    }

    /// Emission leaving `p` along `e` (km^-1 sr^-1): direct sunlight plus the cell's indirect light.
    fn emission(&self, p: DVec3, e: DVec3, sun: DVec3, with_indirect: bool) -> Rgb {
        let m = self.atm.medium(p.length() - self.atm.ground_radius_km);
        let cos = -sun.dot(e);
        let (pr, pm) = (rayleigh_phase(cos), cornette_shanks_phase(cos, self.atm.mie_g));
        let t_sun = self.sun_transmittance(p, sun);
        let mut j: Rgb = std::array::from_fn(|c| (m.rayleigh[c] * pr + m.mie[c] * pm) * t_sun[c]);
        if with_indirect {
            let coeffs = self.indirect_at(p, sun);
            let y = sh9(Self::local(&Self::frame(p, sun), e));
            for (c, jc) in j.iter_mut().enumerate() {
                *jc += coeffs[c].iter().zip(&y).map(|(a, b)| a * b).sum::<f64>().max(0.0);
            }
        }
        j
    }

    /// Radiance arriving at `p` from direction `d` (light travelling along -d): emission along
    /// the ray plus, where it meets the ground, the sunlit ground (Lambertian).
    fn march(&self, p: DVec3, d: DVec3, sun: DVec3, with_indirect: bool, with_ground: bool) -> Rgb {
        let r = p.length();
        let mu = p.dot(d) / r;
        let ground_r = self.atm.ground_radius_km;
        let disc_g = r * r * (mu * mu - 1.0) + ground_r * ground_r;
        let hits_ground = mu < 0.0 && disc_g >= 0.0;
        let top_r = self.atm.top_radius_km;
        let length = if hits_ground { (-r * mu - disc_g.sqrt()).max(0.0) } else { (-r * mu + (r * r * (mu * mu - 1.0) + top_r * top_r).max(0.0).sqrt()).max(0.0) };
        let n = self.settings.ray_steps.max(1);
        let mut tau = [0.0; 3];
        let mut sum = [0.0; 3];
        for k in 0..n {
            // Crowded near the start, where the air is densest.
            let (a, b) = (k as f64 / n as f64, (k + 1) as f64 / n as f64);
            let (t0, t1) = (length * a * a, length * b * b);
            let (t, dt) = (0.5 * (t0 + t1), t1 - t0);
            let y = p + d * t;
            let ext = self.atm.medium(y.length() - ground_r).extinction;
            let j = self.emission(y, -d, sun, with_indirect);
            for c in 0..3 {
                let mid = tau[c] + 0.5 * ext[c] * dt;
                sum[c] += j[c] * (-mid).exp() * dt;
                tau[c] += ext[c] * dt;
            }
        }
        if hits_ground && with_ground && self.albedo > 0.0 {
            let g = p + d * length;
            let n_g = g.normalize();
            let cos_sun = n_g.dot(sun);
            if cos_sun > 0.0 {
                let t_sun = self.sun_transmittance(n_g * (ground_r + 1e-6), sun);
                for c in 0..3 {
                    sum[c] += (-tau[c]).exp() * self.albedo / PI * cos_sun * t_sun[c];
                }
            }
        }
        sum
    }

    /// One refinement: every cell's indirect emission from the light it receives now.
    fn iterate(&mut self) {
        let n_a = self.settings.angle_cells.max(1);
        let n_h = self.altitude_edges.len() - 1;
        let weight = 4.0 * PI / self.directions.len() as f64;
        let next: Vec<[[f64; 9]; 3]> = (0..n_h * n_a)
            .map(|cell| {
                let (h, angle) = self.cell_centre(cell / n_a, cell % n_a);
                let p = DVec3::new(angle.sin(), angle.cos(), 0.0) * (self.atm.ground_radius_km + h);
                let frame = Self::frame(p, SUN);
                let m = self.atm.medium(h);
                let received: Vec<Rgb> = self.directions.iter().map(|d| self.march(p, *d, SUN, true, true)).collect();
                let mut coeffs = [[0.0; 9]; 3];
                for e in &self.directions {
                    // Scattered into e from every received direction (light travelling along -d).
                    let mut out = [0.0; 3];
                    for (d, l) in self.directions.iter().zip(&received) {
                        let cos = -d.dot(*e);
                        let (pr, pm) = (rayleigh_phase(cos), cornette_shanks_phase(cos, self.atm.mie_g));
                        for c in 0..3 {
                            out[c] += l[c] * (m.rayleigh[c] * pr + m.mie[c] * pm) * weight;
                        }
                    }
                    let y = sh9(Self::local(&frame, *e));
                    for c in 0..3 {
                        for (k, yk) in y.iter().enumerate() {
                            coeffs[c][k] += out[c] * yk * weight;
                        }
                    }
                }
                coeffs
            })
            .collect();
        self.indirect = next;
    }

    /// Sky radiance for a case (its albedo must be the model's), sr^-1 per unit of solar irradiance.
    pub fn radiance(&self, case: &Case) -> Rgb {
        let se = case.sun_elev_deg.to_radians();
        let sun = DVec3::new(se.cos(), se.sin(), 0.0);
        let (ve, az) = (case.view_elev_deg.to_radians(), case.rel_azimuth_deg.to_radians());
        let view = DVec3::new(ve.cos() * az.cos(), ve.sin(), ve.cos() * az.sin()).normalize();
        self.radiance_towards(case.camera_km, view, sun)
    }

    /// Sky radiance seen from `camera_km` along the unit `view` (y up), sun along the unit `towards_sun`.
    pub fn radiance_towards(&self, camera_km: f64, view: DVec3, towards_sun: DVec3) -> Rgb {
        let p = DVec3::new(0.0, self.atm.ground_radius_km + camera_km.max(0.0), 0.0);
        // The ground surface in front of the camera is not part of the sky.
        self.march(p, view, towards_sun, self.settings.iterations > 0, false)
    }

    /// Whether this solution was made for these inputs.
    pub fn solved_for(&self, atm: &Atmosphere, albedo: f64, settings: &CellSettings) -> bool {
        self.atm == *atm && self.albedo == albedo && self.settings == *settings
    }
}
