//! `[stars]`: the point-star field.

use serde::Deserialize;

use super::*;

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
