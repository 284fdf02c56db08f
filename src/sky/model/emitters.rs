//! `[[emitter]]`: particle emitters on a sky object or on the camera.

use serde::{Deserialize, Deserializer};
use toml::Spanned;

use super::*;

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
