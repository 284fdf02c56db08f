//! The sky description file, as written by artists (TOML, serde).
//!
//! These types know nothing of wgpu: the renderer converts them to GPU structs with `From`.
//! Range checks live in the field types themselves (`Priority`, `Finite`, ...) so that a bad
//! value is rejected by the deserializer with the exact TOML span of the offending field.

use serde::{Deserialize, Deserializer};
use toml::Spanned;

/// A path to a file, relative to the sky file, with its location in the sky file for errors.
pub type FileRef = Spanned<String>;

/// Top level of a sky file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SkyFile {
    /// Human-readable name shown in the app and in screenshot names.
    pub name: String,
    /// Number of game hours in one day; colour bitmaps span this many hours (default 24).
    #[serde(default = "default_hours")]
    pub hours_per_day: Positive,
    /// Labels of the weather steps, from weather 0 to weather 1 (UI only).
    #[serde(default)]
    pub weather_names: Vec<String>,
    /// Colour bitmap (x: time of day, y: weather) giving the main scene's fog colour.
    pub fog_color: FileRef,
    /// Colour bitmap giving the sun's ambient light on the main scene.
    pub sun_ambient: FileRef,
    /// Colour bitmap giving the sun's diffuse light on the main scene.
    pub sun_diffuse: FileRef,
    /// Name of the path (in `path`) that the sun follows; drives `towards_sun` for every pass.
    pub sun_path: Spanned<String>,
    /// Keyframed directions over the day, referenced by objects and by `sun_path`.
    #[serde(default, rename = "path")]
    pub paths: Vec<PathDef>,
    /// Sky objects, drawn by ascending transparency priority.
    #[serde(default, rename = "object")]
    pub objects: Vec<ObjectDef>,
    /// Optional point-star field (celestial pass).
    #[serde(default)]
    pub stars: Option<StarsDef>,
    /// Optional sun glare (occlusion-query driven halo and lens flare).
    #[serde(default)]
    pub glare: Option<GlareDef>,
    /// Where the skydome's colour comes from (default: the NeL gradient bitmaps).
    #[serde(default)]
    pub sky_model: Option<SkyModelDef>,
    /// Overrides of the physical models' atmosphere (default: Earth as in Hillaire 2020).
    #[serde(default)]
    pub atmosphere: Option<AtmosphereDef>,
    /// Particle emitters (`[[emitter]]`), attached to a sky object or to the camera.
    #[serde(default, rename = "emitter")]
    pub emitters: Vec<EmitterDef>,
    /// Seconds of particle simulation per game hour while the time slider drives it (default 180:
    /// a game day of 72 minutes, as Ryzom's).
    #[serde(default)]
    pub particle_seconds_per_hour: Option<Positive>,
}

/// A particle emitter (docs/sky-format.md, "Particles").
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EmitterDef {
    /// Unique name (UI toggles, errors).
    pub name: String,
    /// `camera` (precipitation around the viewer, in the main scene's depth range) or the name of
    /// a sky object (the particles move with it and live on the dome).
    pub attach: Spanned<String>,
    /// `particles` (plain), `precipitation` (rain to snow, amount from the weather) or
    /// `lightning` (bolts whose birth lifts the sky's and the scene's light).
    #[serde(default)]
    pub kind: EmitterKind,
    /// Procedural shape when no `texture` is given.
    #[serde(default)]
    pub shape: ParticleShape,
    /// Texture of each particle instead of the procedural shape.
    #[serde(default)]
    pub texture: Option<FileRef>,
    /// `alpha` or `additive` (default).
    #[serde(default = "additive")]
    pub blend: BlendMode,
    /// Particles per second at full emission (>= 0); capped at what `max_particles` can hold.
    pub rate: NonNegative,
    /// Life of a particle, s.
    pub lifetime_s: Positive,
    /// Random variation of the lifetime, as a fraction (0..1).
    #[serde(default)]
    pub lifetime_spread: Unit,
    /// Speed at birth: m/s for `attach = "camera"`, degrees/s on the dome otherwise.
    #[serde(default)]
    pub speed: NonNegative,
    /// Random variation of the speed, as a fraction (0..1).
    #[serde(default)]
    pub speed_spread: Unit,
    /// Direction of motion (world axes: x east, y up, -z north); on the dome, projected onto the
    /// sky at the particle; [0, 0, 0]: away from the emitter's centre (eruptions).
    #[serde(default)]
    pub direction: [Finite; 3],
    /// Random cone around `direction`, degrees (0..=180).
    #[serde(default)]
    pub spread_deg: NonNegative,
    /// Acceleration down, m/s^2 (camera) or degrees/s^2 (dome).
    #[serde(default)]
    pub gravity: Finite,
    /// Size at birth and at death: m (camera) or degrees (dome).
    #[serde(default = "default_particle_size")]
    pub size: [Positive; 2],
    /// RGBA at birth and at death (0..1), times the emission colour.
    #[serde(default = "default_particle_color")]
    pub color: [[Unit; 4]; 2],
    /// The most particles alive at once, 1..=100000 (64 bytes each on the GPU).
    pub max_particles: ParticleCap,
    /// Emission switch and tint: on while its colour (a bitmap by hour and weather, like every
    /// NeL bitmap) is not black; default always on.
    #[serde(default)]
    pub emission: ColorDef,
    /// Up to 4 user parameters: value = red / 255 of a bitmap, scaling one quantity.
    #[serde(default)]
    pub params: Vec<ParamDef>,
    /// Dome emitters on a placed object: birth within this angle of its centre, degrees
    /// (default 5); on a dome object: ignored (births over the sky above `min_elevation_deg`).
    #[serde(default)]
    pub region_deg: Option<Positive>,
    /// Dome emitters on a dome object: lowest birth elevation, degrees (default 15).
    #[serde(default)]
    pub min_elevation_deg: Option<Elevation>,
    /// Camera emitters: side of the box around the viewer particles are born in, m (default 24).
    #[serde(default)]
    pub box_m: Option<Positive>,
    /// Streaks: length as seconds of the particle's motion (default 0.04; 0: round sprites).
    #[serde(default)]
    pub streak_s: Option<NonNegative>,
    /// `lightning`: light lift at a bolt's birth (0..), fading over its life.
    #[serde(default)]
    pub flash: NonNegative,
    /// `precipitation`: 0 rain, 1 snow, in between sleet (a mix).
    #[serde(default)]
    pub rain_to_snow: Unit,
    /// Seed of the emitter's random numbers (the same seed, hour and weather give the same picture).
    #[serde(default)]
    pub seed: u64,
}

fn additive() -> BlendMode {
    BlendMode::Additive
}

fn default_particle_size() -> [Positive; 2] {
    [Positive(0.2), Positive(0.2)]
}

fn default_particle_color() -> [[Unit; 4]; 2] {
    [[Unit(1.0); 4], [Unit(1.0), Unit(1.0), Unit(1.0), Unit(0.0)]]
}

/// What an emitter is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EmitterKind {
    /// Plain particles.
    #[default]
    Particles,
    /// Rain to snow around the camera: amount times the weather, shape and motion from
    /// `rain_to_snow`.
    Precipitation,
    /// Bolts: each birth lifts the sky's and the scene's light by `flash`, fading over its life.
    Lightning,
}

/// Procedural particle shapes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ParticleShape {
    /// A soft round dot.
    #[default]
    Dot,
    /// A line stretched along the motion (by `streak_s`).
    Streak,
    /// A six-armed flake.
    Flake,
    /// A jagged bolt along the motion.
    Bolt,
}

/// A user parameter of an emitter.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParamDef {
    /// Colour bitmap by hour and weather; the value is red / 255.
    pub bitmap: FileRef,
    /// What it scales.
    pub scales: ParamTarget,
}

/// What a user parameter scales.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ParamTarget {
    /// The emission rate.
    Rate,
    /// The speed at birth.
    Speed,
    /// The size.
    Size,
    /// The colour (rgb).
    Color,
    /// `precipitation`: replaces `rain_to_snow`.
    RainToSnow,
}

/// Most particles one emitter may hold.
pub const MAX_PARTICLES_PER_EMITTER: u32 = 100_000;

/// An emitter's particle cap, 1..=[`MAX_PARTICLES_PER_EMITTER`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ParticleCap(pub u32);

impl<'de> Deserialize<'de> for ParticleCap {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = i64::deserialize(d)?;
        if (1..=MAX_PARTICLES_PER_EMITTER as i64).contains(&v) {
            Ok(ParticleCap(v as u32))
        } else {
            Err(serde::de::Error::custom(format!("expected a particle cap in 1..={MAX_PARTICLES_PER_EMITTER} (64 bytes each on the GPU), found {v}")))
        }
    }
}

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

/// `[atmosphere]`: any of the default atmosphere's parameters (km, km^-1, rad); the rest keep
/// Hillaire 2020's Earth values. Cross-field rules (top above ground, Mie extinction >= Mie
/// scattering) are checked after loading.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AtmosphereDef {
    /// Planet radius, km.
    pub ground_radius_km: Option<Positive>,
    /// Radius of the top of the atmosphere, km.
    pub top_radius_km: Option<Positive>,
    /// Rayleigh scattering at sea level, km^-1 (r, g, b).
    pub rayleigh_scattering_per_km: Option<[NonNegative; 3]>,
    /// Rayleigh scale height, km.
    pub rayleigh_scale_height_km: Option<Positive>,
    /// Mie scattering at sea level, km^-1: one grey number or (r, g, b).
    pub mie_scattering_per_km: Option<Coefficients>,
    /// Mie extinction at sea level, km^-1: one grey number or (r, g, b).
    pub mie_extinction_per_km: Option<Coefficients>,
    /// Mie scale height, km.
    pub mie_scale_height_km: Option<Positive>,
    /// Mie asymmetry, (-1, 1).
    pub mie_g: Option<Asymmetry>,
    /// Ozone absorption at its peak, km^-1 (r, g, b).
    pub ozone_absorption_per_km: Option<[NonNegative; 3]>,
    /// Altitude of the ozone peak, km.
    pub ozone_center_km: Option<Finite>,
    /// Half width of the ozone tent, km.
    pub ozone_half_width_km: Option<Positive>,
    /// Sun's angular radius, rad.
    pub sun_angular_radius_rad: Option<Positive>,
    /// A named aerosol (`clean`, `continental`, `hazy`, `urban`, `desert_dust`, `maritime`,
    /// `high_altitude`): its optical depth, Angstrom exponent, albedo, g and scale height.
    pub aerosol: Option<crate::atmosphere::aerosol::AerosolPreset>,
    /// Vertical aerosol optical depth at 550 nm (instead of Mie coefficients).
    pub aerosol_optical_depth: Option<NonNegative>,
    /// Preetham's turbidity, total over Rayleigh optical depth at 550 nm, >= 1 (instead of
    /// `aerosol_optical_depth`).
    pub turbidity: Option<Finite>,
    /// Visibility at the ground, km (Koschmieder; instead of `aerosol_optical_depth`).
    pub visibility_km: Option<Positive>,
    /// How the aerosol optical depth falls with wavelength (default 1.3, or the preset's).
    pub angstrom_exponent: Option<Finite>,
    /// Aerosol single-scattering albedo, (0, 1] (default the atmosphere's, or the preset's).
    pub aerosol_albedo: Option<Unit>,
    /// Per weather step, from weather 0 to weather 1, overrides on top of these (e.g. aerosols
    /// rising with the storm); the atmosphere is interpolated between steps like a NeL bitmap.
    #[serde(default)]
    pub weather: Vec<AtmosphereDef>,
}

impl AtmosphereDef {
    /// The ways this definition states an aerosol amount.
    fn amounts(&self) -> Vec<crate::atmosphere::aerosol::AerosolAmount> {
        use crate::atmosphere::aerosol::AerosolAmount as A;
        let tau = self.aerosol_optical_depth.map(|v| A::OpticalDepth(v.get() as f64));
        let t = self.turbidity.map(|v| A::Turbidity(v.get() as f64));
        let v = self.visibility_km.map(|v| A::VisibilityKm(v.get() as f64));
        [tau, t, v].into_iter().flatten().collect()
    }

    /// Whether this definition says anything about the aerosol (coefficients, amount, preset,
    /// slope or albedo).
    pub fn states_aerosol(&self) -> bool {
        self.has_coefficients() || self.aerosol.is_some() || !self.amounts().is_empty() || self.angstrom_exponent.is_some() || self.aerosol_albedo.is_some()
    }

    /// Whether this definition gives Mie coefficients by hand.
    fn has_coefficients(&self) -> bool {
        self.mie_scattering_per_km.is_some() || self.mie_extinction_per_km.is_some()
    }

    /// `base` with these overrides. `parent` is the `[atmosphere]` a weather step sits in (and
    /// `base` its atmosphere). Errors name the keys.
    pub fn apply(&self, base: crate::atmosphere::Atmosphere, parent: Option<&AtmosphereDef>) -> Result<crate::atmosphere::Atmosphere, Vec<crate::atmosphere::AtmosphereError>> {
        use crate::atmosphere::aerosol::{Aerosol, DEFAULT_ANGSTROM_EXPONENT};
        use crate::atmosphere::AtmosphereError;
        let raw = self.apply_coefficients(base);
        let amounts = self.amounts();
        let mut errors = Vec::new();
        if amounts.len() > 1 {
            let keys: Vec<&str> = amounts.iter().map(|a| a.key()).collect();
            errors.push(AtmosphereError { field: amounts[1].key(), message: format!("give the aerosol amount one way, found {}", keys.join(" and ")) });
        }
        if self.has_coefficients() && (self.aerosol.is_some() || !amounts.is_empty()) {
            let field = if self.mie_scattering_per_km.is_some() { "mie_scattering_per_km" } else { "mie_extinction_per_km" };
            errors.push(AtmosphereError {
                field,
                message: "give the aerosol either as Mie coefficients or by aerosol, aerosol_optical_depth, turbidity or visibility_km, not both".into(),
            });
        }
        if !errors.is_empty() {
            return Err(errors);
        }
        let stated = |d: &AtmosphereDef| d.aerosol.is_some() || !d.amounts().is_empty() || d.angstrom_exponent.is_some() || d.aerosol_albedo.is_some();
        if !stated(self) {
            return Ok(raw);
        }
        // `base` already holds the parent's aerosol: a step changes what it states and keeps
        // the rest, its spectral slope included once the parent gave one or the coefficients
        // have one; grey coefficients given an amount get the default slope.
        let mut aerosol = match self.aerosol {
            Some(p) => p.aerosol(),
            None if parent.is_some_and(stated) || raw.mie_extinction_per_km[0] != raw.mie_extinction_per_km[2] => Aerosol::of(&raw),
            None => Aerosol { angstrom_exponent: DEFAULT_ANGSTROM_EXPONENT, ..Aerosol::of(&raw) },
        };
        // Keys written beside a preset refine it.
        if let Some(g) = self.mie_g {
            aerosol.g = g.get() as f64;
        }
        if let Some(h) = self.mie_scale_height_km {
            aerosol.scale_height_km = h.get() as f64;
        }
        if let Some(a) = self.angstrom_exponent {
            aerosol.angstrom_exponent = a.get() as f64;
        }
        if let Some(w) = self.aerosol_albedo {
            aerosol.single_scattering_albedo = w.get() as f64;
        }
        if let Some(amount) = amounts.first().copied() {
            aerosol.optical_depth_550 = amount.optical_depth_550(&raw, aerosol.scale_height_km).map_err(|e| vec![e])?;
        }
        aerosol.validate()?;
        Ok(aerosol.apply(raw))
    }

    /// `base` with the coefficients written here.
    fn apply_coefficients(&self, base: crate::atmosphere::Atmosphere) -> crate::atmosphere::Atmosphere {
        let f = |v: Option<Positive>, d: f64| v.map_or(d, |x| x.get() as f64);
        let rgb = |v: Option<[NonNegative; 3]>, d: [f64; 3]| v.map_or(d, |x| x.map(|c| c.get() as f64));
        crate::atmosphere::Atmosphere {
            ground_radius_km: f(self.ground_radius_km, base.ground_radius_km),
            top_radius_km: f(self.top_radius_km, base.top_radius_km),
            rayleigh_scattering_per_km: rgb(self.rayleigh_scattering_per_km, base.rayleigh_scattering_per_km),
            rayleigh_scale_height_km: f(self.rayleigh_scale_height_km, base.rayleigh_scale_height_km),
            mie_scattering_per_km: self.mie_scattering_per_km.map_or(base.mie_scattering_per_km, Coefficients::rgb),
            mie_extinction_per_km: self.mie_extinction_per_km.map_or(base.mie_extinction_per_km, Coefficients::rgb),
            mie_scale_height_km: f(self.mie_scale_height_km, base.mie_scale_height_km),
            mie_g: self.mie_g.map_or(base.mie_g, |g| g.get() as f64),
            ozone_absorption_per_km: rgb(self.ozone_absorption_per_km, base.ozone_absorption_per_km),
            ozone_center_km: self.ozone_center_km.map_or(base.ozone_center_km, |x| x.get() as f64),
            ozone_half_width_km: f(self.ozone_half_width_km, base.ozone_half_width_km),
            sun_angular_radius_rad: f(self.sun_angular_radius_rad, base.sun_angular_radius_rad),
        }
    }
}

/// A sample count of a physical model, 1..=1024.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StepCount(pub u32);

impl<'de> Deserialize<'de> for StepCount {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = i64::deserialize(d)?;
        if (1..=1024).contains(&v) {
            Ok(StepCount(v as u32))
        } else {
            Err(serde::de::Error::custom(format!("expected a sample count in 1..=1024, found {v}")))
        }
    }
}

fn default_hours() -> Positive {
    Positive(24.0)
}

/// A keyframed direction on the sky sphere over the day.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PathDef {
    /// Name referenced by objects (`path = "..."`) and by `sun_path`.
    pub name: String,
    /// Keys, in any order; interpolated along the great circle, wrapping over midnight.
    #[serde(default)]
    pub keys: Vec<PathKey>,
    /// Follow another path instead of having keys (e.g. a moon trailing the sun).
    #[serde(default)]
    pub follow: Option<Spanned<String>>,
    /// With `follow`: how many hours behind the followed path this one runs.
    #[serde(default)]
    pub lag_hours: Finite,
    /// With `follow`: extra azimuth added to the followed path's, in degrees.
    #[serde(default)]
    pub azimuth_offset_deg: Finite,
    /// With `follow`: extra elevation added to the followed path's, in degrees.
    #[serde(default)]
    pub elevation_offset_deg: Finite,
}

/// One key of a path: where the object is at `hour`.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PathKey {
    /// Game hour of this key, in [0, hours_per_day).
    pub hour: Finite,
    /// Compass direction in degrees: 0 north, 90 east.
    pub azimuth_deg: Finite,
    /// Angle above the horizon in degrees, -90..90.
    pub elevation_deg: Elevation,
    /// Rotation of the object around its direction, in degrees (quads only).
    #[serde(default)]
    pub roll_deg: Finite,
}

/// A sky object: a standard version plus optional fallback versions for weaker GPUs.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectDef {
    /// Unique name (UI, errors, hidden-object reports).
    pub name: String,
    /// Transparency priority 0..63: draw order, ascending.
    #[serde(default)]
    pub priority: Priority,
    /// Drawn in the main view.
    #[serde(default = "yes")]
    pub visible_in_main_scene: bool,
    /// Drawn when rendering the environment map.
    #[serde(default = "yes")]
    pub visible_in_env_map: bool,
    /// With the `linear` sky model: a daytime or night-time layer whose alpha follows the light.
    #[serde(default)]
    pub layer: Option<LayerKind>,
    /// Name of the path that places this object (billboards and quads); domes ignore it.
    #[serde(default)]
    pub path: Option<Spanned<String>>,
    /// The full-quality version.
    pub standard: VersionDef,
    /// Up to two passes drawn one after the other when the GPU tier lacks the standard's stages.
    #[serde(default)]
    pub fallback: Vec<VersionDef>,
}

fn yes() -> bool {
    true
}

/// One version (or fallback version) of a sky object: shape, material stages and colours.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VersionDef {
    /// Procedural geometry.
    pub shape: Shape,
    /// How the result is blended over what is already drawn.
    #[serde(default)]
    pub blend: BlendMode,
    /// Texture stages, at most 4.
    #[serde(default, rename = "stage")]
    pub stages: Vec<StageDef>,
    /// Colour multiplied into the final result.
    #[serde(default)]
    pub diffuse: ColorDef,
    /// Constant colours 0..3, referenced by stages (`constant = N`).
    #[serde(default)]
    pub constants: Vec<ColorDef>,
    /// Which colour's alpha hides the object: alpha 0 means "not drawn" (saves fill rate).
    #[serde(default)]
    pub ref_color: RefColor,
    /// Per-weather gradient bitmaps feeding one stage with a 1xH texture each frame.
    #[serde(default)]
    pub weather_gradients: Option<WeatherGradients>,
    /// Shading: `flat`, `moon` (billboards: a lit sphere showing its phase) or `cloud` (a layer
    /// lit by the sky model's sun and ambient light).
    #[serde(default)]
    pub lighting: Lighting,
    /// `lighting = "cloud"`: optical depth of a texel of alpha 1 (default 3).
    #[serde(default)]
    pub cloud_density: Option<Positive>,
}

/// Procedural sky geometry. Directions: x east, y up, -z north.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Shape {
    /// Hemisphere plus a skirt down to `bottom_deg`; v runs 0 at the zenith to 1 at the bottom.
    Dome {
        /// Lowest elevation of the skirt, degrees (negative hides the horizon line).
        #[serde(default = "default_dome_bottom")]
        bottom_deg: Elevation,
    },
    /// A band between two elevations, anchored at the horizon; v runs 0 at the top to 1 at the bottom.
    DomeBand {
        /// Lower edge, degrees.
        bottom_deg: Elevation,
        /// Upper edge, degrees.
        top_deg: Elevation,
    },
    /// A camera-facing square centred on the object's path direction.
    Billboard {
        /// Angular size (full width), degrees.
        size_deg: Positive,
    },
    /// A square tangent to the sky sphere at the path direction, rotated by the path's roll.
    Quad {
        /// Angular size (full width), degrees.
        size_deg: Positive,
    },
}

fn default_dome_bottom() -> Elevation {
    Elevation(-20.0)
}

/// Blending of a version over the framebuffer.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BlendMode {
    /// Replace (alpha ignored).
    #[default]
    Opaque,
    /// src * alpha + dst * (1 - alpha).
    Alpha,
    /// src * alpha + dst.
    Additive,
}

/// Billboard shading.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Lighting {
    /// Plain texture.
    #[default]
    Flat,
    /// Lit sphere: the disc is shaded by the sun direction, so it shows phases.
    Moon,
    /// Lit cloud layer (the procedural-sky text's 2D clouds): the material's alpha is the cloud's
    /// optical depth (times `cloud_density`); it scatters the sky model's sun (isotropically,
    /// modulated by a normal faked from the texture's slope) and ambient light, and hides what is
    /// behind by exp(-depth). The material's colour is ignored.
    Cloud,
}

/// One texture stage of a material. Stages combine as a sum of terms: `add` starts a new term
/// (texture x constant), `modulate` multiplies the current term; the result is the sum.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StageDef {
    /// Texture image; may be omitted on the stage fed by `weather_gradients`.
    #[serde(default)]
    pub texture: Option<FileRef>,
    /// How this stage joins the previous ones.
    #[serde(default)]
    pub op: StageOp,
    /// Which constant colour multiplies this stage (index into `constants`), if any.
    #[serde(default)]
    pub constant: Option<Spanned<u32>>,
    /// Texture coordinates source.
    #[serde(default)]
    pub uv: UvSource,
    /// Repeats of the texture over the shape, (u, v).
    #[serde(default = "unit_scale")]
    pub uv_scale: Spanned<[Finite; 2]>,
    /// UV panner, in repeats per game hour (offset = frac(panner x game hours)).
    #[serde(default)]
    pub panner: [Finite; 2],
    /// Colour bitmap whose red/green (0.5 = none) offset the UVs, times `uv_offset_factor`.
    #[serde(default)]
    pub uv_offset_bitmap: Option<FileRef>,
    /// Scale of the offset read from `uv_offset_bitmap`, in repeats.
    #[serde(default = "unit")]
    pub uv_offset_factor: Finite,
    /// Clamp the texture instead of repeating it.
    #[serde(default)]
    pub clamp: bool,
}

fn unit() -> Finite {
    Finite(1.0)
}
fn unit_scale() -> Spanned<[Finite; 2]> {
    Spanned::new(0..0, [Finite(1.0), Finite(1.0)])
}

/// How a stage joins the material.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StageOp {
    /// Start a new term: texture x constant.
    #[default]
    Add,
    /// Multiply the current term by texture x constant.
    Modulate,
}

/// Where a stage's texture coordinates come from.
#[derive(Debug, Clone, Copy, Default, PartialEq, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum UvSource {
    /// The shape's own UVs.
    #[default]
    Mesh,
    /// Around the sun: (0.5, 0.5) at the sun, `size_deg` across (sun halos).
    Sun {
        /// Angular width covered by the texture, degrees.
        size_deg: Positive,
    },
    /// Plate-carree (equirectangular) in the slowly rotating celestial frame (galactic background).
    Celestial,
    /// Quake's curved-sky mapping of the view direction (flattened dome).
    Quake {
        /// Vertical squash of the direction before normalising (Quake: 3).
        #[serde(default = "quake_z_scale")]
        z_scale: Finite,
        /// Added to the squashed vertical component.
        #[serde(default)]
        z_offset: Finite,
        /// Texture repeats per unit of flattened distance (Quake: 6 * 63 / 128).
        #[serde(default = "quake_t_scale")]
        t_scale: Finite,
        /// Scroll speed, repeats per game hour.
        #[serde(default)]
        time_scale: Finite,
    },
    /// A cloud layer: where the view ray meets a layer `height_km` above the camera that curves
    /// round a planet of `radius_km` (smaller is more curved), in repeats of `size_km` along the
    /// layer's x and z. Straight up is the layer's middle, not a pole: nothing converges there.
    /// The stage's panner moves the texture within the layer (wind); `uv_scale` repeats it.
    Layer {
        /// Height of the layer above the camera, km.
        #[serde(default = "layer_height_km")]
        height_km: Positive,
        /// Radius of the planet the layer curves round, km (the Earth's by default).
        #[serde(default = "layer_radius_km")]
        radius_km: Positive,
        /// Length of the layer one repeat of the texture covers, km.
        #[serde(default = "layer_size_km")]
        size_km: Positive,
        /// Elevation below which the stage fades, to nothing at the horizon and below (where
        /// the layer's texels crowd together), degrees; 0: no fade.
        #[serde(default = "layer_fade_deg")]
        horizon_fade_deg: Angle90,
    },
}

fn layer_height_km() -> Positive {
    Positive(2.0)
}
fn layer_radius_km() -> Positive {
    Positive(6360.0)
}
fn layer_size_km() -> Positive {
    Positive(10.0)
}
fn layer_fade_deg() -> Angle90 {
    Angle90(10.0)
}

fn quake_z_scale() -> Finite {
    Finite(3.0)
}
fn quake_t_scale() -> Finite {
    Finite(6.0 * 63.0 / 128.0)
}

/// A colour slot of a material and where its value comes from.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ColorDef {
    /// Source of the colour.
    #[serde(default)]
    pub mode: ColorMode,
    /// Colour bitmap (time x weather) for `bitmap` and `bitmap_times_fog`.
    #[serde(default)]
    pub bitmap: Option<FileRef>,
    /// Value used when `mode = "unused"`, RGBA 0..1 (default opaque white).
    #[serde(default = "white")]
    pub value: [Unit; 4],
}

impl Default for ColorDef {
    fn default() -> Self {
        Self { mode: ColorMode::Unused, bitmap: None, value: white() }
    }
}

fn white() -> [Unit; 4] {
    [Unit(1.0); 4]
}

/// The four NeL colour modes.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ColorMode {
    /// Constant `value`.
    #[default]
    Unused,
    /// Sampled from `bitmap` at (time of day, weather).
    Bitmap,
    /// The current fog colour of the main scene.
    Fog,
    /// Bitmap colour x fog colour.
    BitmapTimesFog,
}

/// Which colour's alpha decides visibility.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RefColor {
    /// Always drawn.
    #[default]
    None,
    /// The diffuse colour.
    Diffuse,
    /// Constant colour 0.
    Constant0,
    /// Constant colour 1.
    Constant1,
    /// Constant colour 2.
    Constant2,
    /// Constant colour 3.
    Constant3,
}

/// Per-weather gradient bitmaps: x = time of day, y = position along the dome.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WeatherGradients {
    /// Texture stage (0..3) that receives the 1xH gradient.
    pub stage: Spanned<u32>,
    /// One bitmap per weather step, from weather 0 to weather 1.
    pub bitmaps: Vec<FileRef>,
}

/// Procedural point-star field with a magnitude cutoff.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StarsDef {
    /// `procedural` (invented stars, for invented skies) or `catalogue` (the Bright Star
    /// Catalogue's 9,096 stars at their real positions and magnitudes).
    #[serde(default)]
    pub source: StarSource,
    /// `catalogue`: local sidereal time at hour 0, hours: the right ascension on the meridian at
    /// midnight (0 near the September equinox, 12 near the March one).
    #[serde(default)]
    pub sidereal_hours_at_midnight: Finite,
    /// `procedural`: stars generated before the cutoff.
    #[serde(default = "default_star_count")]
    pub count: u32,
    /// Stars fainter than this visual magnitude are dropped.
    #[serde(default = "default_cutoff")]
    pub magnitude_cutoff: Finite,
    /// Seed of the generator, so a sky always has the same stars.
    #[serde(default)]
    pub seed: u64,
    /// Elevation of the celestial pole above the northern horizon, degrees (latitude).
    #[serde(default = "default_pole")]
    pub pole_elevation_deg: Elevation,
    /// Brightness/visibility over the day (alpha scales every star).
    #[serde(default)]
    pub color: ColorDef,
    /// Apparent size of a magnitude-0 star, pixels.
    #[serde(default = "default_star_px")]
    pub size_px: Positive,
    /// Drawn after the objects of this priority or lower, before the others.
    #[serde(default = "default_star_priority")]
    pub priority: Priority,
}

/// Where the point stars come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StarSource {
    /// Uniform random directions, magnitudes following the observed star counts.
    #[default]
    Procedural,
    /// The Yale Bright Star Catalogue (5th revised edition), embedded (assets/bsc5.bin).
    Catalogue,
}

fn default_star_priority() -> Priority {
    Priority(2)
}

fn default_star_count() -> u32 {
    3000
}
fn default_cutoff() -> Finite {
    Finite(5.5)
}
fn default_pole() -> Elevation {
    Elevation(45.0)
}
fn default_star_px() -> Positive {
    Positive(3.0)
}

/// Sun glare: halo billboard plus flare sprites, driven by occlusion queries.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GlareDef {
    /// Halo texture drawn at the sun.
    pub halo: FileRef,
    /// Angular size of the halo, degrees.
    #[serde(default = "default_halo_size")]
    pub halo_size_deg: Positive,
    /// Angular size of the occlusion-tested solar disc, degrees.
    #[serde(default = "default_disc")]
    pub disc_size_deg: Positive,
    /// Seconds for the glare to follow the measured visibility (0 = instant).
    #[serde(default = "unit_nonneg")]
    pub persistence_s: NonNegative,
    /// Shrink sprites as the sun disappears.
    #[serde(default)]
    pub shrink: bool,
    /// Rotate sprites as the sun disappears (radians per unit of lost visibility).
    #[serde(default)]
    pub rotate: Finite,
    /// Colour of the glare over the day (alpha scales it).
    #[serde(default)]
    pub color: ColorDef,
    /// Flare sprites along the line from the sun to the screen centre, at most 10.
    #[serde(default, rename = "flare")]
    pub flares: Vec<FlareDef>,
}

fn default_halo_size() -> Positive {
    Positive(30.0)
}
fn default_disc() -> Positive {
    Positive(1.0)
}
fn unit_nonneg() -> NonNegative {
    NonNegative(1.0)
}

/// One lens-flare sprite.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FlareDef {
    /// Sprite texture.
    pub texture: FileRef,
    /// Position along sun -> screen centre: 0 at the sun, 1 at the centre, 2 mirrored.
    pub position: Finite,
    /// Size as a fraction of the screen height.
    #[serde(default = "default_flare_size")]
    pub size: Positive,
    /// Tint multiplied into the sprite.
    #[serde(default = "white")]
    pub tint: [Unit; 4],
}

fn default_flare_size() -> Positive {
    Positive(0.1)
}

/// A continent file: which sky each season uses.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContinentFile {
    /// Continent name.
    pub name: String,
    /// Sky file per season, relative to the continent file.
    pub seasons: SeasonSkies,
}

/// One sky per season.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SeasonSkies {
    /// Spring sky file.
    pub spring: FileRef,
    /// Summer sky file.
    pub summer: FileRef,
    /// Autumn sky file.
    pub autumn: FileRef,
    /// Winter sky file.
    pub winter: FileRef,
}

macro_rules! checked_f32 {
    ($(#[$doc:meta])* $name:ident, $check:expr, $expect:literal) => {
        $(#[$doc])*
        #[derive(Debug, Clone, Copy, Default, PartialEq, PartialOrd)]
        pub struct $name(pub f32);
        impl<'de> Deserialize<'de> for $name {
            fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                let v = f64::deserialize(d)?;
                let ok: fn(f64) -> bool = $check;
                if v.is_finite() && ok(v) {
                    Ok($name(v as f32))
                } else {
                    Err(serde::de::Error::custom(format!("expected {}, found {v}", $expect)))
                }
            }
        }
        impl $name {
            /// The checked value.
            pub fn get(self) -> f32 {
                self.0
            }
        }
    };
}

checked_f32!(
    /// Any finite number (NaN and infinities are rejected).
    Finite, |_| true, "a finite number");
checked_f32!(
    /// A finite number > 0.
    Positive, |v| v > 0.0, "a finite number > 0");
checked_f32!(
    /// A finite number >= 0.
    NonNegative, |v| v >= 0.0, "a finite number >= 0");
checked_f32!(
    /// A number in [0, 1].
    Unit, |v| (0.0..=1.0).contains(&v), "a number in [0, 1]");
checked_f32!(
    /// A phase-function asymmetry, strictly between -1 and 1.
    Asymmetry, |v| v > -1.0 && v < 1.0, "a number strictly between -1 and 1");
checked_f32!(
    /// Atmospheric turbidity, [1, 10].
    Turbidity, |v| (1.0..=10.0).contains(&v), "a turbidity in [1, 10]");
checked_f32!(
    /// A light factor of Braun and Cohen's model, [0, 255].
    LightFactor, |v| (0.0..=255.0).contains(&v), "a light factor in [0, 255]");
checked_f32!(
    /// An angle in degrees within [0, 90].
    Angle90, |v| (0.0..=90.0).contains(&v), "an angle in degrees within [0, 90]");
checked_f32!(
    /// An elevation in degrees, [-90, 90].
    Elevation, |v| (-90.0..=90.0).contains(&v), "an elevation in degrees within [-90, 90]");

/// Per-channel coefficients >= 0 (km^-1): one number for all three channels (grey), or three.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Coefficients(pub [NonNegative; 3]);

impl Coefficients {
    /// The coefficients as f64, r g b.
    pub fn rgb(self) -> [f64; 3] {
        self.0.map(|c| c.get() as f64)
    }
}

impl<'de> Deserialize<'de> for Coefficients {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Form {
            Grey(f64),
            Rgb(Vec<f64>),
        }
        let expect = "one number >= 0 (grey) or three, [r, g, b]";
        let (values, found) = match Form::deserialize(d).map_err(|_| serde::de::Error::custom(format!("expected {expect}")))? {
            Form::Grey(v) => (vec![v; 3], v.to_string()),
            Form::Rgb(v) => (v.clone(), format!("{v:?}")),
        };
        match values[..] {
            [r, g, b] if values.iter().all(|v| v.is_finite() && *v >= 0.0) => Ok(Coefficients([r, g, b].map(|v| NonNegative(v as f32)))),
            _ => Err(serde::de::Error::custom(format!("expected {expect}, found {found}"))),
        }
    }
}

/// Transparency priority, 0..=63.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, PartialOrd, Ord)]
pub struct Priority(pub u8);

impl<'de> Deserialize<'de> for Priority {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = i64::deserialize(d)?;
        if (0..=63).contains(&v) {
            Ok(Priority(v as u8))
        } else {
            Err(serde::de::Error::custom(format!("expected a priority in 0..=63, found {v}")))
        }
    }
}
