//! The analytic and artist sky models a game would ship: Preetham, Shirley and Smits 1999,
//! Hosek and Wilkie 2012 (RGB, coefficients from the `hw-skymodel` crate) and Braun and Cohen's
//! simple luminance model (../shared/references/braun-cohen-simple-sky-model.txt). No GPU types
//! here: the renderer uploads [`AnalyticCoefficients`] and `shaders/sky_model/analytic.wgsl`
//! evaluates the same formulas per pixel.
//!
//! Units (docs/sky-models.md):
//! - `preetham`: luminance from the model (kcd m^-2) divided by the extraterrestrial solar
//!   illuminance [`SOLAR_ILLUMINANCE_KLX`], chromaticity (x, y) to linear Rec. 709, then (by
//!   default, [`AnalyticUnits::Calibrated`]) times [`PREETHAM_CALIBRATION`]: sr^-1 relative to a
//!   solar irradiance of 1, as the physical models. Published, the sky is about 2.2 times brighter.
//! - `hosek`: the RGB dataset's radiance, by default times [`HOSEK_CALIBRATION`], fitted the same
//!   way.
//! - `linear`: display values (sRGB-encoded, 0..1); the sky is one colour.
//!
//! Domains, and what happens outside them (every result stays finite and non-negative):
//! - Turbidity: Preetham's fit is clamped to [[`PREETHAM_MIN_TURBIDITY`], 10] (below about 1.3 its
//!   zenith luminance and chromaticity go negative); Hosek's data spans [1, 10], clamped.
//! - Sun below the horizon (neither model covers it): the sky of a sun on the horizon (same
//!   azimuth), darkened by [`twilight_fade`] (a decade every 3 degrees: 1e-2 at -6 degrees, 1e-6
//!   at -18), an artistic continuation, not a physical one.
//! - Hosek-Wilkie's coefficients are evaluated no lower than [`HOSEK_MIN_ELEVATION_DEG`] (their
//!   interpolation in the cube root of the elevation has an infinite slope at the horizon).
//! - View rays below the horizon: the horizon's value (the Perez and Hosek formulas blow up or
//!   mirror there).
//! - Colours outside the Rec. 709 gamut (Preetham's chromaticities near the horizon) clamp at 0.

use std::f64::consts::{FRAC_PI_2, PI};

use super::Rgb;

/// Extraterrestrial solar illuminance, klx (the solar constant in photometric units).
pub const SOLAR_ILLUMINANCE_KLX: f64 = 133.3;

/// Lowest turbidity at which Preetham's fit stays positive over every sun elevation (measured by
/// `tests/analytic.rs`; the published figure is about 1.3).
pub const PREETHAM_MIN_TURBIDITY: f64 = 1.7;

/// Turbidity of a sky that names none, and of the calibration ([`AnalyticUnits::Calibrated`]).
pub const DEFAULT_TURBIDITY: f64 = 2.5;

/// Factor from Preetham's published unit (luminance over the extraterrestrial solar illuminance)
/// to the reference's radiance, by sun elevation (degrees): the factor that gives the model, at
/// [`DEFAULT_TURBIDITY`], the reference's mean displayed luminance over the sky above the
/// horizon, for each sun of the committed reference dome in the default atmosphere
/// (`calibration` in src/measure/model_points.rs computes it; tests/analytic.rs checks these
/// against it). Preetham's sky darkens more slowly than the reference's as the sun sets, hence a
/// table.
pub const PREETHAM_CALIBRATION: [(f64, f64); 13] = [
    (0.0, 1.2267e-1),
    (1.0, 1.7349e-1),
    (2.0, 2.2008e-1),
    (3.0, 2.5961e-1),
    (5.0, 3.1660e-1),
    (8.0, 3.6396e-1),
    (12.0, 3.8993e-1),
    (20.0, 3.9876e-1),
    (30.0, 3.9593e-1),
    (45.0, 3.9937e-1),
    (60.0, 4.1482e-1),
    (75.0, 4.2148e-1),
    (90.0, 3.5755e-1),
];

/// Factor from the Hosek-Wilkie RGB dataset's radiance to the reference's, by sun elevation,
/// found as [`PREETHAM_CALIBRATION`].
pub const HOSEK_CALIBRATION: [(f64, f64); 13] = [
    (0.0, 1.4119e-3),
    (1.0, 2.0692e-3),
    (2.0, 2.7240e-3),
    (3.0, 2.7732e-3),
    (5.0, 2.8447e-3),
    (8.0, 2.8916e-3),
    (12.0, 2.8922e-3),
    (20.0, 2.8315e-3),
    (30.0, 2.7697e-3),
    (45.0, 2.7661e-3),
    (60.0, 2.8094e-3),
    (75.0, 2.7910e-3),
    (90.0, 2.6538e-3),
];

/// A calibration table's factor at `sun_elev_deg`, linear between its suns (a sun below the
/// lowest takes the lowest's: the models show a sun on the horizon, faded).
pub fn calibration_at(table: &[(f64, f64)], sun_elev_deg: f64) -> f64 {
    let Some(&(first_deg, first)) = table.first() else { return 1.0 };
    if sun_elev_deg <= first_deg {
        return first;
    }
    for w in table.windows(2) {
        let ((a, fa), (b, fb)) = (w[0], w[1]);
        if sun_elev_deg <= b {
            return fa + (fb - fa) * (sun_elev_deg - a) / (b - a);
        }
    }
    table[table.len() - 1].1
}

/// The unit an analytic model's radiance is given in.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AnalyticUnits {
    /// The physical models' unit, sr^-1 per unit of solar irradiance: the published values
    /// times a factor fitted once against the reference ([`PREETHAM_CALIBRATION`],
    /// [`HOSEK_CALIBRATION`]), so one exposure shows every model about equally bright.
    #[default]
    Calibrated,
    /// As published: Preetham's luminance over the solar illuminance, the Hosek-Wilkie RGB
    /// dataset's radiance.
    Published,
}

/// Lowest sun elevation at which Hosek-Wilkie's coefficients are evaluated, degrees (lower suns
/// use these coefficients; see [`Hosek::new`]).
pub const HOSEK_MIN_ELEVATION_DEG: f64 = 2.0;

/// The sky's brightness below the horizon relative to a sun on it: a decade every 3 degrees.
pub fn twilight_fade(sun_elevation_rad: f64) -> f64 {
    if sun_elevation_rad >= 0.0 {
        1.0
    } else {
        10f64.powf(sun_elevation_rad.to_degrees() / 3.0)
    }
}

/// A unit direction from elevation and azimuth (y up), as the radiance cases define them.
pub fn direction(elevation_rad: f64, azimuth_rad: f64) -> [f64; 3] {
    [elevation_rad.cos() * azimuth_rad.cos(), elevation_rad.sin(), elevation_rad.cos() * azimuth_rad.sin()]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The sun direction the analytic models are evaluated with: on the horizon when below it.
fn clamped_sun(towards_sun: [f64; 3]) -> ([f64; 3], f64) {
    let elevation = towards_sun[1].clamp(-1.0, 1.0).asin();
    if elevation >= 0.0 {
        return (towards_sun, elevation);
    }
    let h = (towards_sun[0] * towards_sun[0] + towards_sun[2] * towards_sun[2]).sqrt();
    let flat = if h > 1e-9 { [towards_sun[0] / h, 0.0, towards_sun[2] / h] } else { [1.0, 0.0, 0.0] };
    (flat, elevation)
}

/// Ramp of Braun and Cohen's light factor between its minimum and maximum.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Ramp {
    /// The paper's equations 1 and 2: straight lines.
    #[default]
    Linear,
    /// The exponential variation its conclusion recommends: geometric interpolation between the
    /// minimum and the maximum (equal ratios in equal times).
    Exponential,
}

/// Braun and Cohen's simple model: one colour for sky, ambient light and fog, from per-channel
/// light factors (0..255) that ramp up at sunrise and down at sunset.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinearParams {
    /// Per-channel light factor at night (`l_min`, 0..255).
    pub min: Rgb,
    /// Per-channel light factor by day (`l_max`, 0..255).
    pub max: Rgb,
    /// Hour the sunrise ramp starts (`st` of equation 1).
    pub sunrise_hour: f64,
    /// Hour the sunset ramp starts (`st` of equation 2).
    pub sunset_hour: f64,
    /// Length of each ramp, hours (`delta h f`).
    pub ramp_hours: f64,
    /// Shape of the ramps.
    pub ramp: Ramp,
    /// Hours in the sky's day (the ramps wrap around it).
    pub hours_per_day: f64,
}

/// The paper's parameter tables (its tables 1, 2 and 3), by name.
pub const LINEAR_PRESETS: [(&str, Rgb, Rgb); 3] =
    [("snow", [35.0, 35.0, 35.0], [200.0, 200.0, 200.0]), ("desert", [35.0, 35.0, 35.0], [188.0, 172.0, 146.0]), ("forest", [35.0, 35.0, 35.0], [150.0, 158.0, 85.0])];

impl LinearParams {
    /// A preset of the paper with its figures' timing: sunrise 5:00 to 9:00, sunset 17:00 to 21:00.
    pub fn preset(name: &str) -> Option<Self> {
        LINEAR_PRESETS.iter().find(|(n, _, _)| *n == name).map(|&(_, min, max)| Self { min, max, ..Self::default() })
    }

    /// Fraction of the way from night to day at `hour` (0 at night, 1 by day), before the ramp shape.
    fn day_fraction(&self, hour: f64) -> f64 {
        let day = self.hours_per_day.max(1e-6);
        let ramp = self.ramp_hours.clamp(1e-6, day / 2.0);
        let since = |start: f64| (hour - start).rem_euclid(day);
        let rise = since(self.sunrise_hour);
        let set = since(self.sunset_hour);
        // Equation 1 while the sunrise ramp runs, equation 2 while the sunset one does; the light
        // holds between them. Which plateau holds is whichever ramp ended last.
        if rise < ramp {
            rise / ramp
        } else if set < ramp {
            1.0 - set / ramp
        } else if rise < set {
            1.0
        } else {
            0.0
        }
    }

    /// The light factor `l` per channel at `hour`, 0..255.
    pub fn light_factor(&self, hour: f64) -> Rgb {
        let f = self.day_fraction(hour);
        std::array::from_fn(|c| {
            let (lo, hi) = (self.min[c], self.max[c]);
            match self.ramp {
                Ramp::Linear => lo + (hi - lo) * f,
                Ramp::Exponential => {
                    let (lo, hi) = (lo.max(1.0), hi.max(1.0));
                    lo * (hi / lo).powf(f)
                }
            }
        })
    }

    /// The sky, ambient and fog colour at `hour` (display values, 0..1).
    pub fn color(&self, hour: f64) -> Rgb {
        self.light_factor(hour).map(|l| (l / 255.0).clamp(0.0, 1.0))
    }

    /// Layer alpha (0..1) at `hour` of a daytime layer (equation 3: af = l - l_min) or a
    /// night-time one (equation 4: af = 255 - (l + l_min)); `l` is the mean of the channels.
    pub fn layer_alpha(&self, hour: f64, night: bool) -> f64 {
        let l = self.light_factor(hour).iter().sum::<f64>() / 3.0;
        let lmin = self.min.iter().sum::<f64>() / 3.0;
        let af = if night { 255.0 - (l + lmin) } else { l - lmin };
        (af / 255.0).clamp(0.0, 1.0)
    }
}

impl Default for LinearParams {
    fn default() -> Self {
        Self { min: [35.0; 3], max: [200.0; 3], sunrise_hour: 5.0, sunset_hour: 17.0, ramp_hours: 4.0, ramp: Ramp::Linear, hours_per_day: 24.0 }
    }
}

/// Perez et al.'s distribution: (1 + A e^(B / cos theta)) (1 + C e^(D gamma) + E cos^2 gamma).
fn perez(c: [f64; 5], cos_theta: f64, gamma: f64) -> f64 {
    (1.0 + c[0] * (c[1] / cos_theta.max(1e-3)).exp()) * (1.0 + c[2] * (c[3] * gamma).exp() + c[4] * gamma.cos().powi(2))
}

/// Preetham's coefficients at one turbidity and sun.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Preetham {
    /// Perez coefficients A..E of luminance Y and chromaticities x, y.
    pub perez: [[f64; 5]; 3],
    /// Zenith Y (sr^-1, relative to the solar illuminance), x, y.
    pub zenith: [f64; 3],
    /// Sun zenith angle the model is evaluated at, rad (at most pi / 2).
    pub sun_zenith: f64,
    /// Sun direction the model is evaluated at (on the horizon when the sun is below).
    pub towards_sun: [f64; 3],
    /// [`twilight_fade`] of the real sun.
    pub fade: f64,
}

impl Preetham {
    /// The model for `turbidity` (clamped to its domain) and a sun towards `towards_sun`.
    pub fn new(turbidity: f64, towards_sun: [f64; 3]) -> Self {
        let t = if turbidity.is_finite() { turbidity.clamp(PREETHAM_MIN_TURBIDITY, 10.0) } else { 2.5 };
        let (sun, elevation) = clamped_sun(towards_sun);
        let mut p = Self::unclamped(t, elevation.max(0.0), sun);
        p.zenith[0] = p.zenith[0].max(0.0);
        p.fade = twilight_fade(elevation);
        p
    }

    /// The published fit as it stands, at any turbidity and sun elevation (no clamp, no fade):
    /// what the stability sweep shows failing outside the domain.
    pub fn unclamped(t: f64, sun_elevation_rad: f64, towards_sun: [f64; 3]) -> Self {
        let ts = FRAC_PI_2 - sun_elevation_rad;
        let perez = [
            [0.1787 * t - 1.4630, -0.3554 * t + 0.4275, -0.0227 * t + 5.3251, 0.1206 * t - 2.5771, -0.0670 * t + 0.3703],
            [-0.0193 * t - 0.2592, -0.0665 * t + 0.0008, -0.0004 * t + 0.2125, -0.0641 * t - 0.8989, -0.0033 * t + 0.0452],
            [-0.0167 * t - 0.2608, -0.0950 * t + 0.0092, -0.0079 * t + 0.2102, -0.0441 * t - 1.6537, -0.0109 * t + 0.0529],
        ];
        let chi = (4.0 / 9.0 - t / 120.0) * (PI - 2.0 * ts);
        let yz_kcd = (4.0453 * t - 4.9710) * chi.tan() - 0.2155 * t + 2.4192;
        let (t2, s, s2, s3) = (t * t, ts, ts * ts, ts * ts * ts);
        let xz =
            t2 * (0.00166 * s3 - 0.00375 * s2 + 0.00209 * s) + t * (-0.02903 * s3 + 0.06377 * s2 - 0.03202 * s + 0.00394) + (0.11693 * s3 - 0.21196 * s2 + 0.06052 * s + 0.25886);
        let yz =
            t2 * (0.00275 * s3 - 0.00610 * s2 + 0.00317 * s) + t * (-0.04214 * s3 + 0.08970 * s2 - 0.04153 * s + 0.00516) + (0.15346 * s3 - 0.26756 * s2 + 0.06670 * s + 0.26688);
        Self { perez, zenith: [yz_kcd / SOLAR_ILLUMINANCE_KLX, xz, yz], sun_zenith: ts, towards_sun, fade: 1.0 }
    }

    /// Luminance and chromaticity (Y relative, x, y) towards `view` (unit, y up), unclamped.
    pub fn xy_y(&self, view: [f64; 3]) -> [f64; 3] {
        let cos_theta = view[1].max(0.0);
        let gamma = dot(view, self.towards_sun).clamp(-1.0, 1.0).acos();
        std::array::from_fn(|i| self.zenith[i] * perez(self.perez[i], cos_theta, gamma) / perez(self.perez[i], 1.0, self.sun_zenith))
    }

    /// Radiance towards `view`, linear Rec. 709, sr^-1 relative to a solar irradiance of 1.
    pub fn radiance(&self, view: [f64; 3]) -> Rgb {
        let [y_lum, x, y] = self.xy_y(view);
        xyy_to_rec709(x, y, y_lum * self.fade)
    }
}

/// CIE xyY to linear Rec. 709, negative components clamped to 0.
pub fn xyy_to_rec709(x: f64, y: f64, lum: f64) -> Rgb {
    let y = y.max(1e-6);
    let (cx, cy, cz) = (x / y * lum, lum, (1.0 - x - y) / y * lum);
    [3.2406 * cx - 1.5372 * cy - 0.4986 * cz, -0.9689 * cx + 1.8758 * cy + 0.0415 * cz, 0.0557 * cx - 0.2040 * cy + 1.0570 * cz]
        .map(|v| if v.is_finite() { v.max(0.0) } else { 0.0 })
}

/// Hosek and Wilkie's RGB model at one turbidity, albedo and sun.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hosek {
    /// The crate's state: 9 coefficients per channel (A..I) and the channels' radiance.
    pub state: hw_skymodel::rgb::SkyState,
    /// Sun direction the model is evaluated at (on the horizon when the sun is below).
    pub towards_sun: [f64; 3],
    /// [`twilight_fade`] of the real sun.
    pub fade: f64,
}

impl Hosek {
    /// The model for `turbidity` and `albedo` (each clamped to its domain), sun towards `towards_sun`.
    pub fn new(turbidity: f64, albedo: f64, towards_sun: [f64; 3]) -> Self {
        let (sun, elevation) = clamped_sun(towards_sun);
        let t = if turbidity.is_finite() { turbidity.clamp(1.0, 10.0) } else { 2.5 };
        let a = if albedo.is_finite() { albedo.clamp(0.0, 1.0) } else { 0.3 };
        // The dataset is interpolated in the cube root of the elevation, whose slope is infinite at
        // the horizon: the sky would pop as the sun sets (`skytune sweep`). Below
        // HOSEK_MIN_ELEVATION_DEG the coefficients stay those of that elevation.
        let coefficient_elevation = elevation.clamp(HOSEK_MIN_ELEVATION_DEG.to_radians(), FRAC_PI_2);
        let params = hw_skymodel::rgb::SkyParams { elevation: (coefficient_elevation as f32).min(std::f32::consts::FRAC_PI_2), turbidity: t as f32, albedo: [a as f32; 3] };
        // Every parameter is clamped into the crate's ranges above, so this cannot fail.
        let state = hw_skymodel::rgb::SkyState::new(&params).unwrap_or_else(|e| unreachable!("clamped Hosek parameters rejected: {e}"));
        Self { state, towards_sun: sun, fade: twilight_fade(elevation) }
    }

    /// Radiance towards `view`, linear Rec. 709, in the dataset's unit (the crate's evaluation).
    pub fn radiance(&self, view: [f64; 3]) -> Rgb {
        let theta = view[1].clamp(0.0, 1.0).acos() as f32;
        let gamma = dot(view, self.towards_sun).clamp(-1.0, 1.0).acos() as f32;
        use hw_skymodel::rgb::Channel;
        [Channel::R, Channel::G, Channel::B].map(|c| (self.state.radiance(theta, gamma, c) as f64 * self.fade).max(0.0))
    }
}

/// Which analytic model, with its settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum AnalyticModel {
    /// Preetham 1999 at a turbidity.
    Preetham {
        /// Atmospheric turbidity (2: very clear, 10: hazy).
        turbidity: f64,
        /// The unit of its radiance.
        units: AnalyticUnits,
    },
    /// Hosek-Wilkie 2012 RGB.
    Hosek {
        /// Atmospheric turbidity, 1..10.
        turbidity: f64,
        /// Ground albedo, 0..1.
        albedo: f64,
        /// The unit of its radiance.
        units: AnalyticUnits,
    },
    /// Braun and Cohen's simple model.
    Linear(LinearParams),
}

/// Numbers the GPU needs to evaluate an analytic model for one sun (and hour): keep in sync with
/// `analytic_radiance` in shaders/sky_model/analytic.wgsl.
/// - preetham: [0..5] Perez A..E as (Y, x, y, 0); [5] zenith (Y, x, y, fade); [6] (F_Y, F_x, F_y
///   at the zenith, sun zenith angle); [11] sun direction used.
/// - preetham's zenith .w is its fade times its unit's scale ([`AnalyticModel::scale`]);
/// - hosek: [0..9] coefficients A..I as (r, g, b, 0); [9] radiance (r, g, b) times scale and fade;
///   [11] sun direction used.
/// - linear: [0] the colour (display values).
/// - every model: [11].w the kind.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AnalyticCoefficients {
    /// 0 preetham, 1 hosek, 2 linear.
    pub kind: u32,
    /// The vectors described above.
    pub vectors: [[f32; 4]; 12],
}

impl AnalyticModel {
    /// Name in the sky file and the CLI.
    pub fn name(&self) -> &'static str {
        match self {
            AnalyticModel::Preetham { .. } => "preetham",
            AnalyticModel::Hosek { .. } => "hosek",
            AnalyticModel::Linear(_) => "linear",
        }
    }

    /// Units of what [`Self::radiance`] returns.
    pub fn units(&self) -> String {
        match *self {
            AnalyticModel::Preetham { units: AnalyticUnits::Calibrated, .. } => {
                "sr^-1 per unit of solar irradiance: Preetham's luminance over the extraterrestrial solar illuminance (133.3 klx), chromaticity to linear Rec. 709, times PREETHAM_CALIBRATION by sun elevation (calibrated against the reference)".into()
            }
            AnalyticModel::Preetham { units: AnalyticUnits::Published, .. } => {
                "as published: Preetham's luminance (kcd m^-2) over the extraterrestrial solar illuminance (133.3 klx), chromaticity to linear Rec. 709".into()
            }
            AnalyticModel::Hosek { units: AnalyticUnits::Calibrated, .. } => {
                "sr^-1 per unit of solar irradiance: the Hosek-Wilkie RGB dataset's radiance times HOSEK_CALIBRATION by sun elevation (calibrated against the reference)".into()
            }
            AnalyticModel::Hosek { units: AnalyticUnits::Published, .. } => "as published: the Hosek-Wilkie RGB dataset's radiance".into(),
            AnalyticModel::Linear(_) => "display values (sRGB-encoded, 0..1): Braun and Cohen's light factor / 255, the same for every direction".into(),
        }
    }

    /// The factor from the model's published unit to the one it is given in, with the sun
    /// towards `towards_sun`.
    pub fn scale(&self, towards_sun: [f64; 3]) -> f64 {
        let sun_elev_deg = || towards_sun[1].clamp(-1.0, 1.0).asin().to_degrees();
        match *self {
            AnalyticModel::Preetham { units: AnalyticUnits::Calibrated, .. } => calibration_at(&PREETHAM_CALIBRATION, sun_elev_deg()),
            AnalyticModel::Hosek { units: AnalyticUnits::Calibrated, .. } => calibration_at(&HOSEK_CALIBRATION, sun_elev_deg()),
            _ => 1.0,
        }
    }

    /// Radiance towards `view` with the sun towards `towards_sun` at `hour` (only `linear` reads it).
    pub fn radiance(&self, view: [f64; 3], towards_sun: [f64; 3], hour: f64) -> Rgb {
        let k = self.scale(towards_sun);
        match *self {
            AnalyticModel::Preetham { turbidity, .. } => Preetham::new(turbidity, towards_sun).radiance(view).map(|x| x * k),
            AnalyticModel::Hosek { turbidity, albedo, .. } => Hosek::new(turbidity, albedo, towards_sun).radiance(view).map(|x| x * k),
            AnalyticModel::Linear(p) => p.color(hour),
        }
    }

    /// The GPU's numbers for a sun towards `towards_sun` at `hour`.
    pub fn coefficients(&self, towards_sun: [f64; 3], hour: f64) -> AnalyticCoefficients {
        let mut v = [[0.0f32; 4]; 12];
        let kind = match *self {
            AnalyticModel::Preetham { turbidity, .. } => {
                let p = Preetham::new(turbidity, towards_sun);
                for (k, row) in v.iter_mut().take(5).enumerate() {
                    *row = [p.perez[0][k] as f32, p.perez[1][k] as f32, p.perez[2][k] as f32, 0.0];
                }
                v[5] = [p.zenith[0] as f32, p.zenith[1] as f32, p.zenith[2] as f32, (p.fade * self.scale(towards_sun)) as f32];
                let f0: [f64; 3] = std::array::from_fn(|i| perez(p.perez[i], 1.0, p.sun_zenith));
                v[6] = [f0[0] as f32, f0[1] as f32, f0[2] as f32, p.sun_zenith as f32];
                v[11] = [p.towards_sun[0] as f32, p.towards_sun[1] as f32, p.towards_sun[2] as f32, 0.0];
                0
            }
            AnalyticModel::Hosek { turbidity, albedo, .. } => {
                let h = Hosek::new(turbidity, albedo, towards_sun);
                let (params, radiances) = h.state.raw();
                for (k, row) in v.iter_mut().take(9).enumerate() {
                    *row = [params[k], params[9 + k], params[18 + k], 0.0];
                }
                let s = (self.scale(towards_sun) * h.fade) as f32;
                v[9] = [radiances[0] * s, radiances[1] * s, radiances[2] * s, 0.0];
                v[11] = [h.towards_sun[0] as f32, h.towards_sun[1] as f32, h.towards_sun[2] as f32, 0.0];
                1
            }
            AnalyticModel::Linear(p) => {
                let c = p.color(hour);
                v[0] = [c[0] as f32, c[1] as f32, c[2] as f32, 1.0];
                2
            }
        };
        v[11][3] = kind as f32;
        AnalyticCoefficients { kind, vectors: v }
    }
}

/// The hour of an equinox day at the equator at which the morning sun stands at `elevation_deg`
/// (6:00 on the horizon, 15 degrees an hour): how `skytune radiance --model linear` turns a
/// case's sun elevation into the model's time of day.
pub fn equinox_morning_hour(elevation_deg: f64) -> f64 {
    6.0 + elevation_deg / 15.0
}
