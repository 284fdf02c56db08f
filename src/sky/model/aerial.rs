//! `[aerial_perspective]`: how the scene is given the atmosphere in front of it when the sky's
//! physical model lights it (`crate::atmosphere::aerial::AerialSettings`; docs/scene-format.md).

use serde::Deserialize;

use super::*;

/// `[aerial_perspective] method`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AerialMethodDef {
    /// The froxel volume.
    Volume,
    /// The sky's own march per scene vertex.
    Exact,
    /// The model's fog colour at the NeL scene's fixed density.
    Fog,
}

/// `[aerial_perspective] slices`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SliceSpreadDef {
    /// Slice ends at D (k / n)^2.
    Quadratic,
    /// Slices of equal length.
    Linear,
}

/// `[aerial_perspective]`; each key left out keeps its default.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AerialDef {
    /// `volume` (default), `exact` or `fog`.
    pub method: Option<AerialMethodDef>,
    /// Cells across, down and in depth (default [16, 32, 32]; at most [64, 64, 128]).
    pub volume_size: Option<[StepCount; 3]>,
    /// Distance the last slice ends at, km (default 128).
    pub distance_km: Option<Positive>,
    /// `quadratic` (default) or `linear`.
    pub slices: Option<SliceSpreadDef>,
    /// View-ray samples per slice (default 1).
    pub steps_per_slice: Option<StepCount>,
}

impl AerialDef {
    /// The settings this table states, over the defaults (not yet validated).
    pub fn settings(&self) -> crate::atmosphere::aerial::AerialSettings {
        use crate::atmosphere::aerial::{AerialMethod, AerialSettings, SliceSpread};
        let d = AerialSettings::default();
        AerialSettings {
            method: self.method.map_or(d.method, |m| match m {
                AerialMethodDef::Volume => AerialMethod::Volume,
                AerialMethodDef::Exact => AerialMethod::Exact,
                AerialMethodDef::Fog => AerialMethod::Fog,
            }),
            volume_size: self.volume_size.map_or(d.volume_size, |s| s.map(|x| x.0)),
            distance_km: self.distance_km.map_or(d.distance_km, |x| x.get() as f64),
            slices: self.slices.map_or(d.slices, |s| match s {
                SliceSpreadDef::Quadratic => SliceSpread::Quadratic,
                SliceSpreadDef::Linear => SliceSpread::Linear,
            }),
            steps_per_slice: self.steps_per_slice.map_or(d.steps_per_slice, |s| s.0),
        }
    }
}
