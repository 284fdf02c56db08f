//! `[glare]`: the sun's halo and lens flares.

use serde::Deserialize;

use super::*;

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
