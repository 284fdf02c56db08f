//! Physical atmospheres: parameters in documented units, density profiles, phase functions, and
//! the double-precision reference integrator ([`reference`]) that every sky model is judged by.
//! No GPU types here.
//!
//! Units: lengths in km, coefficients in km^-1, angles in radians unless a name says `_deg`.
//! Radiance is in sr^-1 relative to a solar irradiance of 1 per channel at the top of the atmosphere.

pub mod aerial;
pub mod aerosol;
pub mod analytic;
pub mod cases;
pub mod cells;
pub mod dome;
pub mod error;
pub mod precomputed;
pub mod reference;
pub use error::AtmosphereError;
pub use precomputed::{PrecomputedSettings, TablePrecision};
pub mod represent;

use std::f64::consts::PI;

use serde::Deserialize;

/// RGB triple of f64 (per-channel coefficients or radiance).
pub type Rgb = [f64; 3];

/// An atmosphere. The default is the Earth of Hillaire 2020 ("A Scalable and Production Ready
/// Sky and Atmosphere Rendering Technique"), the same as Bruneton's 2017 demo.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Atmosphere {
    /// Planet radius, km.
    pub ground_radius_km: f64,
    /// Radius of the top of the atmosphere, km (nothing above it).
    pub top_radius_km: f64,
    /// Rayleigh scattering at sea level, km^-1 (no absorption).
    pub rayleigh_scattering_per_km: Rgb,
    /// Rayleigh density falls as exp(-altitude / this), km.
    pub rayleigh_scale_height_km: f64,
    /// Mie (aerosol) scattering at sea level, km^-1, per channel (680, 550, 440 nm): grey when
    /// the three are equal, falling towards red when the aerosol has an Angstrom exponent.
    pub mie_scattering_per_km: Rgb,
    /// Mie extinction at sea level, km^-1 (scattering + absorption), per channel.
    pub mie_extinction_per_km: Rgb,
    /// Mie density falls as exp(-altitude / this), km.
    pub mie_scale_height_km: f64,
    /// Asymmetry of the Cornette-Shanks Mie phase function.
    pub mie_g: f64,
    /// Ozone absorption at the peak of its profile, km^-1 (no scattering).
    pub ozone_absorption_per_km: Rgb,
    /// Altitude of the ozone peak, km (tent profile).
    pub ozone_center_km: f64,
    /// Half width of the ozone tent, km: density 0 at center +- this.
    pub ozone_half_width_km: f64,
    /// Angular radius of the sun's disc, rad.
    pub sun_angular_radius_rad: f64,
}

impl Default for Atmosphere {
    fn default() -> Self {
        Self {
            ground_radius_km: 6360.0,
            top_radius_km: 6460.0,
            rayleigh_scattering_per_km: [5.802e-3, 13.558e-3, 33.1e-3],
            rayleigh_scale_height_km: 8.0,
            mie_scattering_per_km: [3.996e-3; 3],
            mie_extinction_per_km: [4.440e-3; 3],
            mie_scale_height_km: 1.2,
            mie_g: 0.8,
            ozone_absorption_per_km: [0.650e-3, 1.881e-3, 0.085e-3],
            ozone_center_km: 25.0,
            ozone_half_width_km: 15.0,
            sun_angular_radius_rad: 0.004675,
        }
    }
}

/// Scattering and extinction at one point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Medium {
    /// Rayleigh scattering, km^-1.
    pub rayleigh: Rgb,
    /// Mie scattering, km^-1.
    pub mie: Rgb,
    /// Total extinction (scattering + absorption), km^-1.
    pub extinction: Rgb,
}

impl Atmosphere {
    /// Checks every parameter's domain; all problems at once.
    pub fn validate(&self) -> Result<(), Vec<AtmosphereError>> {
        let mut errors = Vec::new();
        let mut check = |field: &'static str, ok: bool, message: String| {
            if !ok {
                errors.push(AtmosphereError { field, message });
            }
        };
        let positive = |v: f64| v.is_finite() && v > 0.0;
        let non_negative = |v: f64| v.is_finite() && v >= 0.0;
        check("ground_radius_km", positive(self.ground_radius_km), format!("expected a positive number of km, found {}", self.ground_radius_km));
        check(
            "top_radius_km",
            self.top_radius_km.is_finite() && self.top_radius_km > self.ground_radius_km,
            format!("expected more than ground_radius_km ({}), found {}", self.ground_radius_km, self.top_radius_km),
        );
        for (field, v) in [("rayleigh_scattering_per_km", self.rayleigh_scattering_per_km), ("ozone_absorption_per_km", self.ozone_absorption_per_km)] {
            check(field, v.iter().all(|c| non_negative(*c)), format!("expected three coefficients >= 0 km^-1, found {v:?}"));
        }
        check(
            "mie_scattering_per_km",
            self.mie_scattering_per_km.iter().all(|c| non_negative(*c)),
            format!("expected coefficients >= 0 km^-1, found {:?}", self.mie_scattering_per_km),
        );
        check(
            "mie_extinction_per_km",
            (0..3).all(|c| self.mie_extinction_per_km[c].is_finite() && self.mie_extinction_per_km[c] >= self.mie_scattering_per_km[c]),
            format!("expected at least mie_scattering_per_km ({:?}) km^-1 in every channel, found {:?}", self.mie_scattering_per_km, self.mie_extinction_per_km),
        );
        for (field, v) in
            [("rayleigh_scale_height_km", self.rayleigh_scale_height_km), ("mie_scale_height_km", self.mie_scale_height_km), ("ozone_half_width_km", self.ozone_half_width_km)]
        {
            check(field, positive(v), format!("expected a positive number of km, found {v}"));
        }
        check("ozone_center_km", self.ozone_center_km.is_finite(), format!("expected a finite altitude, found {}", self.ozone_center_km));
        check("mie_g", self.mie_g.is_finite() && self.mie_g.abs() < 1.0, format!("expected -1 < g < 1, found {}", self.mie_g));
        check(
            "sun_angular_radius_rad",
            self.sun_angular_radius_rad.is_finite() && self.sun_angular_radius_rad > 0.0 && self.sun_angular_radius_rad < 0.5,
            format!("expected 0 < radius < 0.5 rad, found {}", self.sun_angular_radius_rad),
        );
        if errors.is_empty() {
            Ok(())
        } else {
            Err(errors)
        }
    }

    /// Thickness of the atmosphere, km.
    pub fn thickness_km(&self) -> f64 {
        self.top_radius_km - self.ground_radius_km
    }

    /// Relative densities (Rayleigh, Mie, ozone) at an altitude, km.
    pub fn densities(&self, altitude_km: f64) -> (f64, f64, f64) {
        let h = altitude_km.max(0.0);
        let ozone = (1.0 - (h - self.ozone_center_km).abs() / self.ozone_half_width_km).max(0.0);
        ((-h / self.rayleigh_scale_height_km).exp(), (-h / self.mie_scale_height_km).exp(), ozone)
    }

    /// Scattering and extinction at an altitude, km.
    pub fn medium(&self, altitude_km: f64) -> Medium {
        let (r, m, o) = self.densities(altitude_km);
        let rayleigh = self.rayleigh_scattering_per_km.map(|b| b * r);
        let mie = self.mie_scattering_per_km.map(|b| b * m);
        let extinction = std::array::from_fn(|c| rayleigh[c] + self.mie_extinction_per_km[c] * m + self.ozone_absorption_per_km[c] * o);
        Medium { rayleigh, mie, extinction }
    }

    /// The same atmosphere with every coefficient multiplied by `k` (optically thin limits, turbidity).
    pub fn scaled(&self, k: f64) -> Self {
        Self {
            rayleigh_scattering_per_km: self.rayleigh_scattering_per_km.map(|b| b * k),
            mie_scattering_per_km: self.mie_scattering_per_km.map(|b| b * k),
            mie_extinction_per_km: self.mie_extinction_per_km.map(|b| b * k),
            ozone_absorption_per_km: self.ozone_absorption_per_km.map(|b| b * k),
            ..*self
        }
    }

    /// Field by field linear interpolation: `self` at t = 0, `other` at t = 1.
    pub fn lerp(&self, other: &Self, t: f64) -> Self {
        let l = |a: f64, b: f64| a + (b - a) * t;
        let l3 = |a: Rgb, b: Rgb| std::array::from_fn(|c| l(a[c], b[c]));
        Self {
            ground_radius_km: l(self.ground_radius_km, other.ground_radius_km),
            top_radius_km: l(self.top_radius_km, other.top_radius_km),
            rayleigh_scattering_per_km: l3(self.rayleigh_scattering_per_km, other.rayleigh_scattering_per_km),
            rayleigh_scale_height_km: l(self.rayleigh_scale_height_km, other.rayleigh_scale_height_km),
            mie_scattering_per_km: l3(self.mie_scattering_per_km, other.mie_scattering_per_km),
            mie_extinction_per_km: l3(self.mie_extinction_per_km, other.mie_extinction_per_km),
            mie_scale_height_km: l(self.mie_scale_height_km, other.mie_scale_height_km),
            mie_g: l(self.mie_g, other.mie_g),
            ozone_absorption_per_km: l3(self.ozone_absorption_per_km, other.ozone_absorption_per_km),
            ozone_center_km: l(self.ozone_center_km, other.ozone_center_km),
            ozone_half_width_km: l(self.ozone_half_width_km, other.ozone_half_width_km),
            sun_angular_radius_rad: l(self.sun_angular_radius_rad, other.sun_angular_radius_rad),
        }
    }

    /// The atmosphere at `weather` (0..1) from one atmosphere per weather step, evenly spaced.
    pub fn at_weather(steps: &[Atmosphere], weather: f64) -> Option<Atmosphere> {
        match steps {
            [] => None,
            [one] => Some(*one),
            _ => {
                let x = weather.clamp(0.0, 1.0) * (steps.len() - 1) as f64;
                let i = (x.floor() as usize).min(steps.len() - 2);
                Some(steps[i].lerp(&steps[i + 1], x - i as f64))
            }
        }
    }

    /// Optical depth of a vertical column from `altitude_km` to the top, per channel, in closed
    /// form (the check of every numerical integrator).
    pub fn vertical_optical_depth(&self, altitude_km: f64) -> Rgb {
        let top = self.thickness_km();
        let h = altitude_km.clamp(0.0, top);
        let exp_column = |scale: f64| scale * ((-h / scale).exp() - (-top / scale).exp());
        let r = exp_column(self.rayleigh_scale_height_km);
        let m = exp_column(self.mie_scale_height_km);
        // Integral of the tent from h to the top.
        let tent = |x: f64| {
            // Antiderivative of max(0, 1 - |x - c| / w), from -inf.
            let (c, w) = (self.ozone_center_km, self.ozone_half_width_km);
            let u = ((x - c) / w).clamp(-1.0, 1.0);
            w * if u < 0.0 { 0.5 * (1.0 + u) * (1.0 + u) } else { 1.0 - 0.5 * (1.0 - u) * (1.0 - u) }
        };
        let o = tent(top) - tent(h);
        std::array::from_fn(|c| self.rayleigh_scattering_per_km[c] * r + self.mie_extinction_per_km[c] * m + self.ozone_absorption_per_km[c] * o)
    }
}

/// How far below a point's horizon the sun's light fades out, rad (a tenth of a degree): the
/// sunlight a point receives goes smoothly from all to nothing while the sun sinks this far below
/// its horizon. A point sun would switch ray-march samples off one by one and skies would jump as
/// it sets (`skytune sweep`); a fade as wide as the sun's disc would light grazing samples enough
/// to move low-sun skies by 1%. Keep in sync with `SUN_SET_FADE_RAD` in
/// shaders/sky_model/atmosphere.wgsl.
pub const SUN_SET_FADE_RAD: f64 = 0.0017453;

/// The fraction of sunlight at a point whose horizon the sun is `above_horizon_rad` above
/// (smoothstep from -[`SUN_SET_FADE_RAD`] to 0).
pub fn sun_set_fade(above_horizon_rad: f64) -> f64 {
    let t = ((above_horizon_rad + SUN_SET_FADE_RAD) / SUN_SET_FADE_RAD).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Rayleigh phase function, sr^-1, of the cosine of the scattering angle.
pub fn rayleigh_phase(cos_theta: f64) -> f64 {
    3.0 / (16.0 * PI) * (1.0 + cos_theta * cos_theta)
}

/// Cornette-Shanks phase function (Mie), sr^-1.
pub fn cornette_shanks_phase(cos_theta: f64, g: f64) -> f64 {
    let g2 = g * g;
    3.0 / (8.0 * PI) * (1.0 - g2) / (2.0 + g2) * (1.0 + cos_theta * cos_theta) / (1.0 + g2 - 2.0 * g * cos_theta).powf(1.5)
}

/// The Legendre moments g_1 and g_2 of the Cornette-Shanks phase function of asymmetry `g`:
/// g_l = 2 pi times the integral of p(x) P_l(x) over x in -1..1 (g_0 = 1; Rayleigh's are 0 and
/// 0.1). Convolving a radiance field's spherical-harmonic band l with the phase function scales
/// it by g_l (Funk-Hecke), which is how the `lut` model scatters its second order anisotropically.
pub fn cornette_shanks_moments(g: f64) -> [f64; 2] {
    // Asked for every frame (the LUT passes' keys) with the same g: the last answer is kept.
    static LAST: std::sync::Mutex<Option<(u64, [f64; 2])>> = std::sync::Mutex::new(None);
    let mut last = LAST.lock().unwrap_or_else(|e| e.into_inner());
    match *last {
        Some((bits, moments)) if bits == g.to_bits() => moments,
        _ => {
            let moments = integrate_cornette_shanks_moments(g);
            *last = Some((g.to_bits(), moments));
            moments
        }
    }
}

fn integrate_cornette_shanks_moments(g: f64) -> [f64; 2] {
    // Midpoint rule in theta: the forward peak of g near 1 is narrow in x but not in theta.
    let n = 4096;
    let (mut g1, mut g2) = (0.0, 0.0);
    for i in 0..n {
        let theta = PI * (i as f64 + 0.5) / n as f64;
        let x = theta.cos();
        let w = 2.0 * PI * cornette_shanks_phase(x, g) * theta.sin() * PI / n as f64;
        g1 += w * x;
        g2 += w * 0.5 * (3.0 * x * x - 1.0);
    }
    [g1, g2]
}

/// Henyey-Greenstein phase function, sr^-1 (used to importance-sample the Mie lobe).
pub fn henyey_greenstein_phase(cos_theta: f64, g: f64) -> f64 {
    let g2 = g * g;
    (1.0 - g2) / (4.0 * PI * (1.0 + g2 - 2.0 * g * cos_theta).powf(1.5))
}

/// How the `single` model finds the optical depth towards the sun.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OpticalDepth {
    /// The analytic erf approximation of the procedural-sky text (both regimes, and through the
    /// ray's lowest point when it goes down).
    #[default]
    Erf,
    /// Numerical integration (midpoint rule), for comparison.
    Numerical,
}

/// Settings of the `single` model: the accuracy axis of the benchmark.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SingleSettings {
    /// Samples along the view ray.
    pub view_steps: u32,
    /// Samples towards the sun (numerical optical depth only).
    pub sun_steps: u32,
    /// How the optical depth towards the sun is found.
    pub optical_depth: OpticalDepth,
}

impl Default for SingleSettings {
    fn default() -> Self {
        Self { view_steps: 32, sun_steps: 16, optical_depth: OpticalDepth::Erf }
    }
}

/// Settings of the `lut` model (Hillaire 2020): table sizes and sample counts, the accuracy axis
/// of the benchmark.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LutSettings {
    /// Transmittance table, texels (width: view angle, height: altitude).
    pub transmittance_size: [u32; 2],
    /// Samples per transmittance texel.
    pub transmittance_steps: u32,
    /// Multiple-scattering table side, texels (sun angle x altitude).
    pub multiscattering_size: u32,
    /// The multiple-scattering integral uses grid polar bands x grid azimuths over the half
    /// sphere (mirrored: grid x 2 grid over the sphere).
    pub multiscattering_grid: u32,
    /// Samples per direction of the multiple-scattering integral.
    pub multiscattering_steps: u32,
    /// Samples along each view ray.
    pub view_steps: u32,
}

impl LutSettings {
    /// Largest transmittance table the GPU buffers hold.
    pub const MAX_TRANSMITTANCE: [u32; 2] = [512, 256];
    /// Largest multiple-scattering table side.
    pub const MAX_MULTISCATTERING: u32 = 64;

    /// Checks every setting's domain.
    pub fn validate(&self) -> Result<(), AtmosphereError> {
        let [w, h] = self.transmittance_size;
        let bad = |field: &'static str, message: String| Err(AtmosphereError { field, message });
        if !(2..=Self::MAX_TRANSMITTANCE[0]).contains(&w) || !(2..=Self::MAX_TRANSMITTANCE[1]).contains(&h) {
            return bad("transmittance_size", format!("expected 2..={} x 2..={} texels, found {w} x {h}", Self::MAX_TRANSMITTANCE[0], Self::MAX_TRANSMITTANCE[1]));
        }
        if !(2..=Self::MAX_MULTISCATTERING).contains(&self.multiscattering_size) {
            return bad("multiscattering_size", format!("expected 2..={} texels, found {}", Self::MAX_MULTISCATTERING, self.multiscattering_size));
        }
        for (field, v) in [
            ("transmittance_steps", self.transmittance_steps),
            ("multiscattering_grid", self.multiscattering_grid),
            ("multiscattering_steps", self.multiscattering_steps),
            ("view_steps", self.view_steps),
        ] {
            if !(1..=1024).contains(&v) {
                return bad(field, format!("expected 1..=1024, found {v}"));
            }
        }
        Ok(())
    }
}

impl Default for LutSettings {
    fn default() -> Self {
        // Hillaire 2020's sizes: 256 x 64 transmittance, 32 x 32 multiple scattering, 64 directions.
        Self { transmittance_size: [256, 64], transmittance_steps: 40, multiscattering_size: 32, multiscattering_grid: 8, multiscattering_steps: 20, view_steps: 32 }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cornette_shanks_moments_match_their_closed_forms() {
        // At g = 0 Cornette-Shanks is Rayleigh's phase function: moments 0 and 0.1.
        let [g1, g2] = cornette_shanks_moments(0.0);
        assert!(g1.abs() < 1e-9 && (g2 - 0.1).abs() < 1e-6, "{g1} {g2}");
        // Its mean cosine is 3g (4 + g^2) / (5 (2 + g^2)) (Cornette and Shanks 1992).
        for g in [-0.5, 0.3, 0.8, 0.95] {
            let mean = 3.0 * g * (4.0 + g * g) / (5.0 * (2.0 + g * g));
            let [g1, _] = cornette_shanks_moments(g);
            assert!((g1 - mean).abs() < 1e-4, "g {g}: g_1 {g1}, closed form {mean}");
        }
        // Asked again (kept) and after another g (recomputed): the same answers.
        assert_eq!(cornette_shanks_moments(0.8), integrate_cornette_shanks_moments(0.8));
    }
}
