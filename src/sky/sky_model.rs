//! A validated `[sky_model]`, in four parts: which model, each model's own settings, the camera
//! that turns radiance into display values, and the world the sky is seen from. The sky file
//! keeps one flat table (`super::model::SkyModelDef`); this is how the program holds it.

use super::model::{SkyModelKind, ToneMapper};
use crate::atmosphere::analytic::{AnalyticModel, AnalyticUnits, LinearParams, DEFAULT_TURBIDITY};
use crate::atmosphere::{LutSettings, PrecomputedSettings, SingleSettings};

/// A skydome colour source and its settings.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SkyModel {
    /// Which model.
    pub kind: SkyModelKind,
    /// The model also lights the main scene (fog colour, sun ambient and diffuse).
    pub drive_scene: bool,
    /// Each model's own knobs; a model reads only its own.
    pub settings: ModelSettings,
    /// How a physical model's radiance becomes display values.
    pub camera: CameraResponse,
    /// Where the sky is seen from.
    pub world: World,
    /// How the scene is given the atmosphere in front of it when the model lights it
    /// (`[aerial_perspective]`).
    pub aerial: crate::atmosphere::aerial::AerialSettings,
}

/// The knobs of each model, read only by that model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModelSettings {
    /// `single`.
    pub single: SingleSettings,
    /// `lut`.
    pub lut: LutSettings,
    /// `precomputed`.
    pub precomputed: PrecomputedSettings,
    /// `cells`: refinement iterations.
    pub cell_iterations: u32,
    /// `reference`: how densely the background still is sampled.
    pub reference: ReferenceSampling,
    /// `preetham`, `hosek`.
    pub analytic: AnalyticSettings,
    /// `linear`: Braun and Cohen's parameters.
    pub linear: LinearParams,
}

impl Default for ModelSettings {
    fn default() -> Self {
        Self {
            single: Default::default(),
            lut: Default::default(),
            precomputed: Default::default(),
            cell_iterations: 6,
            reference: Default::default(),
            analytic: Default::default(),
            linear: Default::default(),
        }
    }
}

/// `reference`: Monte Carlo paths and the coarse grid of directions they are traced on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ReferenceSampling {
    /// Paths per direction.
    pub paths: u32,
    /// The grid of directions (azimuths, elevations).
    pub grid: [u32; 2],
}

impl Default for ReferenceSampling {
    fn default() -> Self {
        Self { paths: 256, grid: [48, 27] }
    }
}

/// `preetham`, `hosek`: their one parameter and the unit of their radiance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AnalyticSettings {
    /// Atmospheric turbidity.
    pub turbidity: f32,
    /// The turbidity is the atmosphere's at the frame's weather (its `[atmosphere]` states the
    /// aerosol and `[sky_model]` no turbidity); moving the window's turbidity slider ends it.
    pub turbidity_from_atmosphere: bool,
    /// The unit of their radiance (calibrated to the physical models' by default).
    pub units: AnalyticUnits,
}

impl Default for AnalyticSettings {
    fn default() -> Self {
        Self { turbidity: DEFAULT_TURBIDITY as f32, turbidity_from_atmosphere: false, units: Default::default() }
    }
}

/// The camera's response: exposure and tone mapping of physical models.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraResponse {
    /// Exposure, stops: display = tone_map(radiance x 2^exposure_ev); with `auto_exposure`, a
    /// compensation on the metered exposure.
    pub exposure_ev: f32,
    /// Expose for the sky's mean luminance (then `exposure_ev` is a compensation).
    pub auto_exposure: bool,
    /// Tone mapper.
    pub tone_mapper: ToneMapper,
}

impl Default for CameraResponse {
    fn default() -> Self {
        Self { exposure_ev: 5.0, auto_exposure: false, tone_mapper: ToneMapper::Aces }
    }
}

/// Where the sky is seen from: the viewer's altitude and the ground under the atmosphere.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct World {
    /// Viewer altitude above the ground, km.
    pub camera_km: f32,
    /// Ground albedo seen by multiple scattering (and Hosek and Wilkie's model).
    pub ground_albedo: f32,
}

impl Default for World {
    fn default() -> Self {
        Self { camera_km: 0.0, ground_albedo: 0.3 }
    }
}

impl World {
    /// The ground of the CPU models, each number read as the decimal the file wrote (0.3, not
    /// the f32's 0.30000001), so that the benchmark's ground
    /// ([`crate::atmosphere::dome::Ground::BENCH`]) is recognised and its reference used.
    pub fn ground(&self) -> crate::atmosphere::dome::Ground {
        let decimal = |x: f32| x.to_string().parse::<f64>().unwrap_or(f64::from(x));
        crate::atmosphere::dome::Ground { camera_km: decimal(self.camera_km), albedo: decimal(self.ground_albedo) }
    }
}

impl SkyModel {
    /// Where the sky is seen from, as the CPU models take it ([`World::ground`]).
    pub fn ground(&self) -> crate::atmosphere::dome::Ground {
        self.world.ground()
    }

    /// The analytic model this is, if it is one.
    pub fn analytic(&self) -> Option<AnalyticModel> {
        let a = &self.settings.analytic;
        match self.kind {
            SkyModelKind::Preetham => Some(AnalyticModel::Preetham { turbidity: a.turbidity as f64, units: a.units }),
            SkyModelKind::Hosek => Some(AnalyticModel::Hosek { turbidity: a.turbidity as f64, albedo: self.world.ground_albedo as f64, units: a.units }),
            SkyModelKind::Linear => Some(AnalyticModel::Linear(self.settings.linear)),
            _ => None,
        }
    }
}
