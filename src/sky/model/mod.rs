//! The sky description file, as written by artists (TOML, serde).
//!
//! These types know nothing of wgpu: the renderer converts them to GPU structs with `From`.
//! Range checks live in the field types themselves (`Priority`, `Finite`, ...) so that a bad
//! value is rejected by the deserializer with the exact TOML span of the offending field.

use serde::Deserialize;
use toml::Spanned;

/// A path to a file, relative to the sky file, with its location in the sky file for errors.
pub type FileRef = Spanned<String>;

mod aerial;
mod atmosphere;
mod emitters;
mod glare;
mod objects;
mod sky_model;
mod stars;
mod values;

pub use aerial::*;
pub use atmosphere::*;
pub use emitters::*;
pub use glare::*;
pub use objects::*;
pub use sky_model::*;
pub use stars::*;
pub use values::*;

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
    /// How the scene is given the atmosphere in front of it when the model lights it.
    #[serde(default)]
    pub aerial_perspective: Option<AerialDef>,
    /// Particle emitters (`[[emitter]]`), attached to a sky object or to the camera.
    #[serde(default, rename = "emitter")]
    pub emitters: Vec<EmitterDef>,
    /// Seconds of particle simulation per game hour while the time slider drives it (default 180:
    /// a game day of 72 minutes, as Ryzom's).
    #[serde(default)]
    pub particle_seconds_per_hour: Option<Positive>,
}

fn default_hours() -> Positive {
    Positive(24.0)
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
