//! The cloud-layer mapping (`UvSource::Layer`) on the CPU: the twin of `layer_uv` and
//! `layer_fade` in shaders/sky_objects/material.wgsl, in f64, and how densely it puts texture
//! coordinates on the sky (for mip choices and buffer resolutions).
//!
//! The view ray from the camera meets a sphere of radius R + h whose centre lies R below the
//! camera; the point's horizontal displacement, in repeats of the texture, is the stage's
//! coordinate. Straight up that is the origin, approached from every azimuth at the same rate,
//! so the texture does not converge there as it does at the pole of a dome's mesh coordinates.

use crate::sky::resolved::UvSource;

/// A layer mapping's parameters as the shader reads them (`params` of its stage).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LayerParams {
    /// Height of the layer above the camera, in repeats of the texture.
    pub height: f64,
    /// Radius of the planet it curves round, in repeats of the texture.
    pub radius: f64,
    /// Sine of the elevation below which the stage fades (0: no fade).
    pub fade_sin: f64,
}

/// The parameters of `uv` when it is the layer mapping.
pub fn layer_params(uv: UvSource) -> Option<LayerParams> {
    match uv {
        UvSource::Layer { height_km, radius_km, size_km, horizon_fade_deg } => {
            let size = size_km.get() as f64;
            Some(LayerParams { height: height_km.get() as f64 / size, radius: radius_km.get() as f64 / size, fade_sin: (horizon_fade_deg.get() as f64).to_radians().sin() })
        }
        _ => None,
    }
}

impl LayerParams {
    /// Distance along unit direction `dir` (y up) to the layer, in repeats. The root of
    /// t^2 + 2 R y t - h (2 R + h) = 0 in the form that does not cancel on either side of the
    /// horizon (the shader's too).
    pub fn distance(&self, dir: [f64; 3]) -> f64 {
        let (h, r, y) = (self.height, self.radius, dir[1]);
        let c = h * (2.0 * r + h);
        let s = (r * r * y * y + c).max(0.0).sqrt();
        if y >= 0.0 {
            c / (r * y + s)
        } else {
            s - r * y
        }
    }

    /// Texture coordinates (before the stage's scale and offset) of unit direction `dir`.
    pub fn uv(&self, dir: [f64; 3]) -> [f64; 2] {
        let t = self.distance(dir);
        [dir[0] * t, dir[2] * t]
    }

    /// The factor the stage's sample is multiplied by at unit direction `dir`: smooth from 0 at
    /// the horizon (and below) to 1 at the fade's elevation.
    pub fn fade(&self, dir: [f64; 3]) -> f64 {
        if self.fade_sin <= 0.0 {
            return 1.0;
        }
        let x = (dir[1] / self.fade_sin).clamp(0.0, 1.0);
        x * x * (3.0 - 2.0 * x)
    }

    /// The most texture-coordinate units one radian of view direction crosses at elevation
    /// `e_rad`, along any direction: round the ring of that elevation the point moves t per
    /// radian (its horizontal distance is t cos e over a ring of radius cos e), across it by
    /// d(t cos e)/de.
    fn rate(&self, e_rad: f64) -> f64 {
        let along = self.distance([e_rad.cos(), e_rad.sin(), 0.0]);
        let rho = |e: f64| self.distance([e.cos(), e.sin(), 0.0]) * e.cos();
        let step = 1e-5;
        let across = ((rho(e_rad + step) - rho(e_rad - step)) / (2.0 * step)).abs();
        along.max(across)
    }

    /// The steepest rate over elevations `bottom_deg..top_deg`, texture-coordinate units per
    /// radian, each weighted by `weight(elevation)`: `|_| 1` for where texels land on pixels (mip
    /// choices), the fade for how much detail reaches the image (buffer resolutions). Densely
    /// sampled: the rate varies smoothly, fastest near the horizon.
    pub fn steepest(&self, bottom_deg: f32, top_deg: f32, weight: impl Fn(f64) -> f64) -> f64 {
        const SAMPLES: u32 = 512;
        let (lo, hi) = ((bottom_deg.min(top_deg) as f64).to_radians(), (bottom_deg.max(top_deg) as f64).to_radians().min(std::f64::consts::FRAC_PI_2 - 1e-4));
        let mut steepest: f64 = 0.0;
        for i in 0..=SAMPLES {
            let e = lo + (hi - lo) * i as f64 / SAMPLES as f64;
            steepest = steepest.max(self.rate(e) * weight(e));
        }
        // Sampling may step over the peak between two samples by a little; the rate changes by
        // less than this between neighbouring samples for any layer above the camera.
        steepest * 1.01
    }

    /// The fade at elevation `e_rad`, for weighting [`Self::steepest`].
    pub fn fade_at(&self, e_rad: f64) -> f64 {
        self.fade([e_rad.cos(), e_rad.sin(), 0.0])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sky::model::{Angle90, Positive};

    fn layer(h: f32, r: f32, size: f32, fade: f32) -> LayerParams {
        layer_params(UvSource::Layer { height_km: Positive(h), radius_km: Positive(r), size_km: Positive(size), horizon_fade_deg: Angle90(fade) }).unwrap()
    }

    fn dir(e_deg: f64, a_deg: f64) -> [f64; 3] {
        let (e, a) = (e_deg.to_radians(), a_deg.to_radians());
        [e.cos() * a.sin(), e.sin(), e.cos() * a.cos()]
    }

    #[test]
    fn the_point_lies_on_the_layer() {
        for p in [layer(2.0, 6360.0, 10.0, 10.0), layer(2.0, 20.0, 5.0, 0.0), layer(5.0, 1.0, 1.0, 30.0)] {
            for e in [-60.0, -5.0, 0.0, 0.5, 10.0, 45.0, 89.9, 90.0] {
                let d = dir(e, 37.0);
                let t = p.distance(d);
                let point = [d[0] * t, d[1] * t + p.radius, d[2] * t];
                let from_centre = (point[0].powi(2) + point[1].powi(2) + point[2].powi(2)).sqrt();
                assert!((from_centre - (p.radius + p.height)).abs() < 1e-9 * (p.radius + p.height), "e {e}: {from_centre}");
            }
            assert!((p.distance([0.0, 1.0, 0.0]) - p.height).abs() < 1e-12);
        }
    }

    /// The rate of change of the coordinates over pairs of nearby directions in a disc of
    /// `radius_deg` round (elevation, azimuth): its largest over its smallest, in radians of view.
    fn spread(uv: &dyn Fn([f64; 3]) -> [f64; 2], centre_e: f64, radius_deg: f64) -> f64 {
        let mut rng = fastrand::Rng::with_seed(3);
        let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
        for _ in 0..4000 {
            // Points spread over the disc about a centre on the y-z plane, stepped a little in a
            // random screen direction.
            let (r, a) = (radius_deg * rng.f64().sqrt(), rng.f64() * 360.0);
            let p = [r * a.to_radians().cos(), r * a.to_radians().sin()];
            let step = 1e-4;
            let b = rng.f64() * std::f64::consts::TAU;
            let q = [p[0] + step * b.cos(), p[1] + step * b.sin()];
            let at = |p: [f64; 2]| {
                // Tangent-plane offsets (degrees) round the centre direction.
                let c = dir(centre_e, 0.0);
                let right = [1.0, 0.0, 0.0];
                let up = [0.0, centre_e.to_radians().cos(), -centre_e.to_radians().sin()];
                let v: Vec<f64> = (0..3).map(|k| c[k] + right[k] * p[0].to_radians() + up[k] * p[1].to_radians()).collect();
                let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
                [v[0] / n, v[1] / n, v[2] / n]
            };
            let (dp, dq) = (at(p), at(q));
            let angle = ((dp[0] - dq[0]).powi(2) + (dp[1] - dq[1]).powi(2) + (dp[2] - dq[2]).powi(2)).sqrt();
            let (u, v) = (uv(dp), uv(dq));
            let rate = ((u[0] - v[0]).powi(2) + (u[1] - v[1]).powi(2)).sqrt() / angle;
            lo = lo.min(rate);
            hi = hi.max(rate);
        }
        hi / lo
    }

    #[test]
    fn nothing_converges_at_the_zenith() {
        // The derivatives of the coordinates vary about as little in a disc round the zenith as in
        // one 20 degrees away; under the dome's mesh coordinates (u round the azimuth, v down from
        // the top, 3 x 2 repeats as the built-in clouds had) they diverge at the pole.
        let mesh = |d: [f64; 3]| {
            let e = d[1].clamp(-1.0, 1.0).asin().to_degrees();
            [3.0 * (d[0].atan2(d[2]) / std::f64::consts::TAU + 0.5), 2.0 * (90.0 - e) / 95.0]
        };
        let (near, away) = (spread(&mesh, 90.0, 3.0), spread(&mesh, 70.0, 3.0));
        assert!(near > 20.0 * away, "the mesh mapping's spread {near} at the zenith, {away} 20 degrees away");
        for p in [layer(2.0, 6360.0, 10.0, 10.0), layer(1.5, 30.0, 6.0, 8.0), layer(2.0, 2.0, 4.0, 0.0)] {
            let uv = |d: [f64; 3]| p.uv(d);
            let (near, away) = (spread(&uv, 90.0, 3.0), spread(&uv, 70.0, 3.0));
            assert!(near < 1.5 && away < 1.5, "{p:?}: spread {near} at the zenith, {away} 20 degrees away");
        }
    }

    #[test]
    fn the_density_bound_holds_and_is_reached() {
        let mut rng = fastrand::Rng::with_seed(5);
        for (p, bottom) in [(layer(2.0, 6360.0, 10.0, 10.0), -5.0), (layer(2.0, 30.0, 6.0, 0.0), -5.0), (layer(1.0, 1.0, 1.0, 0.0), -20.0), (layer(3.0, 100.0, 2.0, 5.0), 10.0)] {
            let bound = p.steepest(bottom as f32, 90.0, |_| 1.0);
            let mut seen: f64 = 0.0;
            for _ in 0..20_000 {
                let e = bottom + (90.0 - bottom) * rng.f64();
                let a = rng.f64() * 360.0;
                let (de, da) = ((rng.f64() - 0.5) * 1e-3, (rng.f64() - 0.5) * 1e-3);
                let (d, q) = (dir(e, a), dir((e + de).min(90.0), a + da));
                let angle = ((d[0] - q[0]).powi(2) + (d[1] - q[1]).powi(2) + (d[2] - q[2]).powi(2)).sqrt();
                if angle < 1e-9 {
                    continue;
                }
                let (u, v) = (p.uv(d), p.uv(q));
                let rate = ((u[0] - v[0]).powi(2) + (u[1] - v[1]).powi(2)).sqrt() / angle;
                assert!(rate <= bound, "{p:?}: {rate} per rad at elevation {e} above the bound {bound}");
                seen = seen.max(rate);
            }
            assert!(seen > bound * 0.8, "{p:?}: bound {bound} per rad far above the steepest seen, {seen}");
        }
    }

    #[test]
    fn the_fade_runs_from_the_horizon_to_its_elevation() {
        let p = layer(2.0, 6360.0, 10.0, 10.0);
        assert_eq!(p.fade(dir(-3.0, 0.0)), 0.0);
        assert_eq!(p.fade(dir(0.0, 0.0)), 0.0);
        assert!((p.fade(dir(5.0, 0.0)) - 0.5).abs() < 0.01);
        assert_eq!(p.fade(dir(10.0, 0.0)), 1.0);
        assert_eq!(layer(2.0, 6360.0, 10.0, 0.0).fade(dir(-3.0, 0.0)), 1.0);
    }
}
