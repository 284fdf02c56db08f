//! The sun's transmittance for orders 2 and up, tabulated: every scattering event a path meets
//! needs the sunlight there, and integrating it along a ray to space each time was most of the
//! reference's cost (a day path spends about half its time there). Single scattering, the
//! deterministic and dominant part, keeps the exact quadrature.
//!
//! The optical depth to space depends only on the point's radius `r` and the cosine `mu` of the
//! direction's zenith angle. It is tabulated at the nodes of Bruneton's (2017) transmittance
//! parameterisation, written here from the paper: `x_r` uniform in the distance to the horizon
//! `rho = sqrt(r^2 - R_g^2)`, `x_mu` in the distance `d` to the top of the atmosphere between its
//! least (straight up) and greatest (along the horizon) for that `r`, here squared towards the
//! horizon. Optical depth
//! is smooth in both, steepest towards the horizon, where `d` spreads the nodes. Values come
//! from the reference's own adaptive quadrature, and are interpolated bilinearly.
//! `tests/reference.rs` measures the table against the quadrature.

use glam::DVec3;

use super::{Reference, Rgb};

/// Radii tabulated.
const N_R: usize = 256;
/// Direction cosines tabulated per radius.
const N_MU: usize = 384;

/// Optical depth to space over (radius, direction cosine), per channel.
pub(super) struct SunTable {
    ground_radius_km: f64,
    top_radius_km: f64,
    /// `sqrt(R_t^2 - R_g^2)`: the distance to the horizon from the top, km.
    horizon_km: f64,
    /// `N_R` rows of `N_MU` optical depths.
    tau: Vec<Rgb>,
}

impl SunTable {
    /// Tabulates `reference`'s optical depth to space, on every core (a second or so, once per
    /// reference). The rays are integrated with longer panels than the reference's own (the
    /// optical depth is smooth along them, and the adaptive error control still holds each
    /// panel to a tenth of the reference's tolerance).
    pub(super) fn new(reference: &Reference) -> Self {
        let (rg, rt) = (reference.atm.ground_radius_km, reference.atm.top_radius_km);
        let coarse = Reference::new(reference.atm, super::ReferenceSettings { max_panel_km: 32.0, tau_tolerance: reference.settings.tau_tolerance * 0.1, ..reference.settings });
        let mut table = Self { ground_radius_km: rg, top_radius_km: rt, horizon_km: (rt * rt - rg * rg).max(0.0).sqrt(), tau: Vec::new() };
        let row = |i: usize| -> Vec<Rgb> {
            (0..N_MU)
                .map(|j| {
                    let (r, mu) = table.node(i as f64 / (N_R - 1) as f64, j as f64 / (N_MU - 1) as f64);
                    let seg = coarse.segment(DVec3::new(0.0, r, 0.0), DVec3::new((1.0 - mu * mu).max(0.0).sqrt(), mu, 0.0));
                    *seg.tau.last().expect("non-empty")
                })
                .collect()
        };
        let workers = std::thread::available_parallelism().map_or(1, |n| n.get()).min(N_R);
        let rows: Vec<Vec<Rgb>> = std::thread::scope(|s| {
            let handles: Vec<_> = (0..workers).map(|w| s.spawn(move || (w..N_R).step_by(workers).map(|i| (i, row(i))).collect::<Vec<_>>())).collect();
            let mut rows = vec![Vec::new(); N_R];
            for h in handles {
                for (i, r) in h.join().unwrap_or_else(|p| std::panic::resume_unwind(p)) {
                    rows[i] = r;
                }
            }
            rows
        });
        table.tau = rows.concat();
        table
    }

    /// The direction cosine just above the horizon at radius `r` (as [`Reference::sunlight`]
    /// looks along when the sun is below it): the table's last column.
    fn horizon_mu(&self, r: f64) -> f64 {
        let sin_horizon = (self.ground_radius_km / r.max(self.ground_radius_km)).min(1.0);
        let mu_h = -(1.0 - sin_horizon * sin_horizon).max(0.0).sqrt();
        (mu_h.asin() + 1e-6).sin()
    }

    /// (rho, d_min, d_max) at radius `r`.
    fn span(&self, r: f64) -> (f64, f64, f64) {
        let rho = (r * r - self.ground_radius_km * self.ground_radius_km).max(0.0).sqrt();
        (rho, (self.top_radius_km - r).max(0.0), rho + self.horizon_km)
    }

    /// Distance from radius `r` to the top along cosine `mu`.
    fn distance_to_top(&self, r: f64, mu: f64) -> f64 {
        (-r * mu + (r * r * (mu * mu - 1.0) + self.top_radius_km * self.top_radius_km).max(0.0).sqrt()).max(0.0)
    }

    /// (r, mu) of the texture coordinates (x_r, x_mu) in [0, 1]^2.
    fn node(&self, x_r: f64, x_mu: f64) -> (f64, f64) {
        let rho = x_r * self.horizon_km;
        let r = (rho * rho + self.ground_radius_km * self.ground_radius_km).sqrt().min(self.top_radius_km);
        let (_, d_min, d_max) = self.span(r);
        // Nodes crowd towards the horizon, where the optical depth climbs fastest.
        let d = d_min + (1.0 - (1.0 - x_mu) * (1.0 - x_mu)) * (d_max - d_min);
        let mu = if d <= 0.0 { 1.0 } else { ((self.horizon_km * self.horizon_km - rho * rho - d * d) / (2.0 * r * d)).clamp(-1.0, 1.0) };
        (r, mu.max(self.horizon_mu(r)))
    }

    /// Optical depth to space from radius `r` along cosine `mu` (at or above
    /// [`Self::horizon_mu`]), interpolated.
    pub(super) fn optical_depth(&self, r: f64, mu: f64) -> Rgb {
        let r = r.clamp(self.ground_radius_km, self.top_radius_km);
        let (rho, d_min, d_max) = self.span(r);
        let x_r = (rho / self.horizon_km).clamp(0.0, 1.0);
        let d = self.distance_to_top(r, mu.max(self.horizon_mu(r)));
        let x_mu = if d_max > d_min { 1.0 - (1.0 - ((d - d_min) / (d_max - d_min)).clamp(0.0, 1.0)).sqrt() } else { 0.0 };
        let (fi, fj) = (x_r * (N_R - 1) as f64, x_mu * (N_MU - 1) as f64);
        let (i, j) = ((fi as usize).min(N_R - 2), (fj as usize).min(N_MU - 2));
        let (a, b) = (fi - i as f64, fj - j as f64);
        let at = |i: usize, j: usize| self.tau[i * N_MU + j];
        let (t00, t01, t10, t11) = (at(i, j), at(i, j + 1), at(i + 1, j), at(i + 1, j + 1));
        std::array::from_fn(|c| (1.0 - a) * ((1.0 - b) * t00[c] + b * t01[c]) + a * ((1.0 - b) * t10[c] + b * t11[c]))
    }
}
