//! `[sky_model]`: which model colours the skydome, and its settings (`[sky_model.precomputed]`,
//! `[sky_model.linear]`, the `auto` budget).

use serde::Deserialize;
use toml::Spanned;

use super::*;

/// The skydome's colour source.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SkyModelKind {
    /// The NeL gradient bitmaps, indexed by (time of day, weather).
    #[default]
    Bitmap,
    /// Physical single scattering, ray-marched on the GPU (see docs/sky-models.md).
    Single,
    /// Multiple scattering from look-up tables, in the manner of Hillaire 2020.
    Lut,
    /// Every scattering order precomputed into 4D tables, after Bruneton 2017.
    Precomputed,
    /// The cell model of the procedural-sky text, solved on the CPU in the background.
    Cells,
    /// The double-precision reference, computed on the CPU in the background (a still).
    Reference,
    /// Preetham, Shirley and Smits 1999: the Perez distribution at a turbidity.
    Preetham,
    /// Hosek and Wilkie 2012, RGB: coefficients from the `hw-skymodel` crate.
    Hosek,
    /// Braun and Cohen's simple model: one colour from per-channel light factors that ramp at
    /// sunrise and sunset (`[sky_model.linear]`).
    Linear,
}

impl SkyModelKind {
    /// Every model, in the order the app lists them.
    pub const ALL: [SkyModelKind; 9] = [
        SkyModelKind::Bitmap,
        SkyModelKind::Linear,
        SkyModelKind::Preetham,
        SkyModelKind::Hosek,
        SkyModelKind::Single,
        SkyModelKind::Lut,
        SkyModelKind::Precomputed,
        SkyModelKind::Cells,
        SkyModelKind::Reference,
    ];

    /// Name in the sky file and the CLI.
    pub fn name(self) -> &'static str {
        match self {
            SkyModelKind::Bitmap => "bitmap",
            SkyModelKind::Single => "single",
            SkyModelKind::Lut => "lut",
            SkyModelKind::Precomputed => "precomputed",
            SkyModelKind::Cells => "cells",
            SkyModelKind::Reference => "reference",
            SkyModelKind::Preetham => "preetham",
            SkyModelKind::Hosek => "hosek",
            SkyModelKind::Linear => "linear",
        }
    }

    /// The model of a name ([`Self::name`]), if one has it.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.name() == name)
    }

    /// Whether the model is evaluated from a few coefficients per sun (`shaders/sky_model/analytic.wgsl`).
    pub fn is_analytic(self) -> bool {
        matches!(self, SkyModelKind::Preetham | SkyModelKind::Hosek | SkyModelKind::Linear)
    }

    /// Whether the model produces radiance (and so needs exposure and a tone mapper).
    pub fn is_physical(self) -> bool {
        self != SkyModelKind::Bitmap
    }

    /// Whether the model is computed on the CPU in the background.
    pub fn on_cpu(self) -> bool {
        matches!(self, SkyModelKind::Cells | SkyModelKind::Reference)
    }
}

/// Curve from exposed radiance to display values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ToneMapper {
    /// Stephen Hill's fit of the ACES reference rendering and output transforms.
    #[default]
    Aces,
    /// Khronos PBR Neutral: colours below 0.76 pass unchanged, highlights compress and desaturate.
    Neutral,
}

impl ToneMapper {
    /// Every tone mapper.
    pub const ALL: [ToneMapper; 2] = [ToneMapper::Aces, ToneMapper::Neutral];

    /// Name in the sky file.
    pub fn name(self) -> &'static str {
        match self {
            ToneMapper::Aces => "aces",
            ToneMapper::Neutral => "neutral",
        }
    }
}

/// `[sky_model]`: which model colours the skydome's gradient stage, and its settings.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SkyModelDef {
    /// `bitmap` (NeL gradients), `single`, `lut`, `cells`, `reference`, `preetham`, `hosek`,
    /// `linear`, or `auto` (the cheapest model within `budget`).
    #[serde(default)]
    pub kind: ModelChoice,
    /// `auto`: the error budget, e.g. `{ de2000 = 2.0 }`.
    #[serde(default)]
    pub budget: Option<BudgetDef>,
    /// Exposure in stops: display = tone_map(radiance x 2^exposure_ev), radiance in sr^-1 per unit
    /// of solar irradiance (default 5); with `auto_exposure`, a compensation (default 0).
    #[serde(default)]
    pub exposure_ev: Option<Finite>,
    /// Tone mapper of physical models.
    #[serde(default)]
    pub tone_mapper: ToneMapper,
    /// `single`: samples along the view ray.
    #[serde(default = "default_view_steps")]
    pub view_steps: StepCount,
    /// `single`: samples towards the sun (numerical optical depth only).
    #[serde(default = "default_sun_steps")]
    pub sun_steps: StepCount,
    /// `single`: `erf` (analytic approximation) or `numerical` optical depth towards the sun.
    #[serde(default)]
    pub optical_depth: crate::atmosphere::OpticalDepth,
    /// Altitude of the viewer above the ground, km.
    #[serde(default)]
    pub camera_km: NonNegative,
    /// Ground albedo seen by multiple scattering (`lut`).
    #[serde(default = "default_albedo")]
    pub ground_albedo: Unit,
    /// `lut`: transmittance table [width, height], texels (at most 512 x 256).
    #[serde(default)]
    pub transmittance_size: Option<[StepCount; 2]>,
    /// `lut`: samples per transmittance texel.
    #[serde(default)]
    pub transmittance_steps: Option<StepCount>,
    /// `lut`: multiple-scattering table side, texels (at most 64).
    #[serde(default)]
    pub multiscattering_size: Option<StepCount>,
    /// `lut`: the multiple-scattering integral uses grid polar bands x grid azimuths over the half sphere (mirrored: grid x 2 grid).
    #[serde(default)]
    pub multiscattering_grid: Option<StepCount>,
    /// `lut`: samples per direction of the multiple-scattering integral.
    #[serde(default)]
    pub multiscattering_steps: Option<StepCount>,
    /// `cells`: refinement iterations, 1..=32 (the text uses 6).
    #[serde(default)]
    pub cell_iterations: Option<StepCount>,
    /// Expose for the sky's mean luminance (middle grey), with `exposure_ev` as compensation.
    #[serde(default)]
    pub auto_exposure: bool,
    /// `reference`: Monte Carlo paths per direction, 1..=1024.
    #[serde(default)]
    pub reference_paths: Option<StepCount>,
    /// `reference`: the coarse grid of directions [azimuths, elevations] it is evaluated on.
    #[serde(default)]
    pub reference_grid: Option<[StepCount; 2]>,
    /// The model also lights the main scene: fog colour, sun ambient and sun diffuse come from
    /// it instead of the bitmaps.
    #[serde(default)]
    pub drive_scene: bool,
    /// `preetham`, `hosek`: atmospheric turbidity, 1..=10 (default: the turbidity of the
    /// `[atmosphere]` when it states its aerosol, else 2.5; Preetham clamps below 1.7).
    #[serde(default)]
    pub turbidity: Option<Turbidity>,
    /// `preetham`, `hosek`: `calibrated` (default: the physical models' unit, so one exposure
    /// suits every model) or `published` (the papers' own scale; Preetham's is about 2.2 times
    /// brighter).
    #[serde(default)]
    pub analytic_units: crate::atmosphere::analytic::AnalyticUnits,
    /// `linear`: Braun and Cohen's parameters.
    #[serde(default)]
    pub linear: Option<LinearDef>,
    /// `precomputed`: table sizes and orders (`[sky_model.precomputed]`).
    #[serde(default)]
    pub precomputed: Option<PrecomputedDef>,
}

/// `[sky_model.precomputed]`: the `precomputed` model's settings; each key left out keeps its
/// default (`crate::atmosphere::PrecomputedSettings`).
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PrecomputedDef {
    /// Scattering tables [nu, mu_s, mu, r], texels (mu even: half for rays that meet the ground).
    pub scattering_size: Option<[StepCount; 4]>,
    /// Scattering orders, 1 (single scattering) ..= 16.
    pub orders: Option<StepCount>,
    /// Transmittance table [width, height], texels.
    pub transmittance_size: Option<[StepCount; 2]>,
    /// Irradiance tables [width, height], texels.
    pub irradiance_size: Option<[StepCount; 2]>,
    /// Samples along each scattering texel's ray.
    pub ray_steps: Option<StepCount>,
    /// Directions per half turn of the scattering-density integral.
    pub density_directions: Option<StepCount>,
    /// Storage of the looked-up tables: `single` or `half`.
    pub precision: Option<crate::atmosphere::TablePrecision>,
}

impl PrecomputedDef {
    /// The settings this table states, over the defaults.
    pub fn settings(&self) -> crate::atmosphere::PrecomputedSettings {
        let d = crate::atmosphere::PrecomputedSettings::default();
        crate::atmosphere::PrecomputedSettings {
            scattering_size: self.scattering_size.map_or(d.scattering_size, |s| s.map(|x| x.0)),
            orders: self.orders.map_or(d.orders, |s| s.0),
            transmittance_size: self.transmittance_size.map_or(d.transmittance_size, |s| s.map(|x| x.0)),
            irradiance_size: self.irradiance_size.map_or(d.irradiance_size, |s| s.map(|x| x.0)),
            ray_steps: self.ray_steps.map_or(d.ray_steps, |s| s.0),
            density_directions: self.density_directions.map_or(d.density_directions, |s| s.0),
            precision: self.precision.unwrap_or(d.precision),
            ..d
        }
    }
}

/// `[sky_model] kind`: a model, or `auto`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ModelChoice {
    /// This model.
    Model(SkyModelKind),
    /// The cheapest model within the budget (`crate::measure::auto_model`).
    Auto,
}

impl Default for ModelChoice {
    fn default() -> Self {
        ModelChoice::Model(SkyModelKind::Bitmap)
    }
}

impl<'de> Deserialize<'de> for ModelChoice {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let name = String::deserialize(d)?;
        if name == "auto" {
            return Ok(ModelChoice::Auto);
        }
        SkyModelKind::ALL
            .into_iter()
            .find(|k| k.name() == name)
            .map(ModelChoice::Model)
            .ok_or_else(|| serde::de::Error::custom(format!("unknown model \"{name}\"; expected auto, {}", SkyModelKind::ALL.map(|k| k.name()).join(", "))))
    }
}

/// `budget = { de2000 = 2.0 }` of `kind = "auto"`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BudgetDef {
    /// Largest mean CIE dE2000 over the dome, at any hour and weather of the sky (> 0).
    pub de2000: Positive,
}

/// `[sky_model.linear]`: Braun and Cohen's light parameters. `preset` starts from one of the
/// paper's tables (snow, desert, forest); `min` and `max` override it.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LinearDef {
    /// `snow`, `desert` or `forest` (the paper's tables 1 to 3); default snow.
    #[serde(default)]
    pub preset: Option<Spanned<String>>,
    /// Light factor at night per channel, 0..=255 (`l_min`).
    #[serde(default)]
    pub min: Option<[LightFactor; 3]>,
    /// Light factor by day per channel, 0..=255 (`l_max`).
    #[serde(default)]
    pub max: Option<[LightFactor; 3]>,
    /// Hour the sunrise ramp starts (default 5).
    #[serde(default)]
    pub sunrise_hour: Option<NonNegative>,
    /// Hour the sunset ramp starts (default 17).
    #[serde(default)]
    pub sunset_hour: Option<NonNegative>,
    /// Length of each ramp, hours (default 4).
    #[serde(default)]
    pub ramp_hours: Option<Positive>,
    /// `linear` (the paper's equations) or `exponential` (its recommendation).
    #[serde(default)]
    pub ramp: crate::atmosphere::analytic::Ramp,
}

/// Which of Braun and Cohen's layer kinds an object is: its alpha follows the light factor
/// (equation 3 by day, equation 4 by night) when the sky model is `linear`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LayerKind {
    /// Clouds, the sun: alpha = l - l_min.
    Day,
    /// Stars, the moon: alpha = 255 - (l + l_min).
    Night,
}

fn default_albedo() -> Unit {
    Unit(0.3)
}

fn default_view_steps() -> StepCount {
    StepCount(32)
}

fn default_sun_steps() -> StepCount {
    StepCount(16)
}
