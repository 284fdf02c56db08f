//! A validated sky: references resolved to indices, bitmaps decoded. Still no wgpu here.

use std::path::PathBuf;
use std::sync::Arc;

use super::bitmap::{ColorBitmap, Rgba};
/// The error budget of `kind = "auto"` (`budget = { de2000 = 2.0 }`): the sky's, read by the
/// measurement that picks the model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Budget {
    /// Largest mean CIE dE2000 over the dome, at any of the sky's sun elevations and weathers.
    pub de2000: f64,
}

pub use super::model::{BlendMode, ColorMode, Lighting, RefColor, Shape, SkyModelKind, StageOp, ToneMapper, UvSource};
pub use super::sky_model::{AnalyticSettings, CameraResponse, ModelSettings, ReferenceSampling, SkyModel, World};

/// Most texture stages a material may use (the best GPU tier).
pub const MAX_STAGES: usize = 4;
/// Most lens-flare sprites.
pub const MAX_FLARES: usize = 10;

/// A decoded texture image, RGBA8.
#[derive(Debug, Clone, PartialEq)]
pub struct TextureImage {
    /// Where it came from; also the GPU cache key.
    pub key: String,
    /// Width, texels.
    pub width: u32,
    /// Height, texels.
    pub height: u32,
    /// Row-major RGBA8.
    pub rgba8: Vec<u8>,
}

/// A validated sky scene.
#[derive(Debug, Clone)]
pub struct Sky {
    /// Display name.
    pub name: String,
    /// Game hours in a day.
    pub hours_per_day: f32,
    /// Labels of the weather steps.
    pub weather_names: Vec<String>,
    /// The sky file it was loaded from (or `<built-in>`).
    pub source_name: String,
    /// Main-scene fog colour over (time, weather).
    pub fog_color: Arc<ColorBitmap>,
    /// Sun ambient light over (time, weather).
    pub sun_ambient: Arc<ColorBitmap>,
    /// Sun diffuse light over (time, weather).
    pub sun_diffuse: Arc<ColorBitmap>,
    /// Index in `paths` of the sun's path.
    pub sun_path: usize,
    /// Keyframed directions.
    pub paths: Vec<SkyPath>,
    /// Objects sorted by ascending priority (file order among equals).
    pub objects: Vec<SkyObject>,
    /// Particle emitters, in file order.
    pub emitters: Vec<Emitter>,
    /// Seconds of particle simulation per game hour while the time slider drives it.
    pub particle_seconds_per_hour: f32,
    /// Point-star field.
    pub stars: Option<Stars>,
    /// Sun glare.
    pub glare: Option<Glare>,
    /// Every file on disk the sky was built from, except the sky file itself.
    pub watched_files: Vec<PathBuf>,
    /// Colour source of the skydome's gradient stage.
    pub model: SkyModel,
    /// Atmosphere of the physical models.
    pub atmosphere: crate::atmosphere::Atmosphere,
    /// One atmosphere per weather step (empty: `atmosphere` in every weather).
    pub atmosphere_by_weather: Vec<crate::atmosphere::Atmosphere>,
    /// `kind = "auto"`: the error budget; `model` holds `lut` until `auto_model::resolve` picks.
    pub auto_model: Option<Budget>,
    /// What the loader found questionable without refusing the sky (file, line and field each).
    pub warnings: Vec<super::error::SkyError>,
}

/// A named path over the day.
#[derive(Debug, Clone)]
pub struct SkyPath {
    /// Name.
    pub name: String,
    /// Keys, or a reference to another path.
    pub kind: PathKind,
}

/// How a path is defined.
#[derive(Debug, Clone)]
pub enum PathKind {
    /// Keyframes sorted by hour.
    Keys(Vec<PathKeyframe>),
    /// Another path, delayed and offset.
    Follow {
        /// Index of the followed path.
        target: usize,
        /// Hours behind the target.
        lag_hours: f32,
        /// Added azimuth, degrees.
        azimuth_offset_deg: f32,
        /// Added elevation, degrees.
        elevation_offset_deg: f32,
    },
}

/// One keyframe.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PathKeyframe {
    /// Game hour.
    pub hour: f32,
    /// Compass direction, degrees (0 north, 90 east).
    pub azimuth_deg: f32,
    /// Elevation, degrees.
    pub elevation_deg: f32,
    /// Roll around the direction, degrees.
    pub roll_deg: f32,
}

/// A sky object.
#[derive(Debug, Clone)]
pub struct SkyObject {
    /// Unique name.
    pub name: String,
    /// Transparency priority 0..63.
    pub priority: u8,
    /// Drawn in the main view.
    pub visible_in_main_scene: bool,
    /// Drawn into environment maps.
    pub visible_in_env_map: bool,
    /// Braun and Cohen's layer kind (alpha from the light factor with the `linear` model).
    pub layer: Option<super::model::LayerKind>,
    /// Index of the placing path.
    pub path: Option<usize>,
    /// Full-quality version.
    pub standard: Version,
    /// Fallback passes (0..=2).
    pub fallback: Vec<Version>,
}

/// A version or fallback version.
#[derive(Debug, Clone)]
pub struct Version {
    /// Geometry.
    pub shape: Shape,
    /// Framebuffer blending.
    pub blend: BlendMode,
    /// Texture stages (at most 4).
    pub stages: Vec<Stage>,
    /// Diffuse colour.
    pub diffuse: Color,
    /// Constant colours.
    pub constants: Vec<Color>,
    /// Colour whose alpha hides the object.
    pub ref_color: RefColor,
    /// Weather gradients feeding one stage.
    pub gradients: Option<Gradients>,
    /// Shading.
    pub lighting: Lighting,
    /// Lit clouds: optical depth of a texel of alpha 1.
    pub cloud_density: f32,
}

/// A texture stage.
#[derive(Debug, Clone)]
pub struct Stage {
    /// Texture (None only for the gradient-fed stage).
    pub texture: Option<Arc<TextureImage>>,
    /// Combine operation.
    pub op: StageOp,
    /// Index of the multiplying constant colour.
    pub constant: Option<usize>,
    /// UV source.
    pub uv: UvSource,
    /// Repeats, (u, v).
    pub uv_scale: [f32; 2],
    /// Panner, repeats per game hour.
    pub panner: [f32; 2],
    /// UV offset bitmap and factor.
    pub uv_offset: Option<(Arc<ColorBitmap>, f32)>,
    /// Clamp instead of repeat.
    pub clamp: bool,
}

/// Where an emitter's particles live.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EmitterAttach {
    /// Around the viewer, in metres, drawn in the main scene's depth range.
    Camera,
    /// On the dome with an object (index into `Sky::objects`), in directions.
    Object(usize),
}

/// A particle emitter, checked (docs/sky-format.md, "Particles").
#[derive(Debug, Clone)]
pub struct Emitter {
    /// Unique name.
    pub name: String,
    /// What it is attached to.
    pub attach: EmitterAttach,
    /// Plain, precipitation or lightning.
    pub kind: super::model::EmitterKind,
    /// Procedural shape (unless `texture`).
    pub shape: super::model::ParticleShape,
    /// Sprite texture.
    pub texture: Option<Arc<TextureImage>>,
    /// Alpha or additive.
    pub blend: BlendMode,
    /// Particles per second at full emission.
    pub rate: f32,
    /// Life, s.
    pub lifetime_s: f32,
    /// Lifetime variation, fraction.
    pub lifetime_spread: f32,
    /// Speed at birth: m/s (camera) or degrees/s (dome).
    pub speed: f32,
    /// Speed variation, fraction.
    pub speed_spread: f32,
    /// Direction of motion (zero: away from the emitter's centre).
    pub direction: glam::Vec3,
    /// Cone around the direction, degrees.
    pub spread_deg: f32,
    /// Acceleration down: m/s^2 or degrees/s^2.
    pub gravity: f32,
    /// Size at birth and death: m or degrees.
    pub size: [f32; 2],
    /// RGBA at birth and death.
    pub color: [Rgba; 2],
    /// Most particles alive.
    pub max_particles: u32,
    /// Emission switch and tint.
    pub emission: Color,
    /// User parameters: bitmap (value = red) and what it scales.
    pub params: Vec<(Arc<ColorBitmap>, super::model::ParamTarget)>,
    /// Birth region around a placed object's centre, degrees.
    pub region_deg: f32,
    /// Lowest birth elevation on a dome object, degrees.
    pub min_elevation_deg: f32,
    /// Side of the birth box around the viewer, m.
    pub box_m: f32,
    /// Streak length as seconds of motion.
    pub streak_s: f32,
    /// Lightning light lift.
    pub flash: f32,
    /// Precipitation: 0 rain .. 1 snow.
    pub rain_to_snow: f32,
    /// Random seed.
    pub seed: u64,
}

/// A colour slot.
#[derive(Debug, Clone)]
pub struct Color {
    /// Source.
    pub mode: ColorMode,
    /// Bitmap for the bitmap modes.
    pub bitmap: Option<Arc<ColorBitmap>>,
    /// Constant for `unused`.
    pub value: Rgba,
}

/// Weather gradient bitmaps of a version.
#[derive(Debug, Clone)]
pub struct Gradients {
    /// Stage receiving the 1xH gradient.
    pub stage: usize,
    /// One bitmap per weather step.
    pub bitmaps: Vec<Arc<ColorBitmap>>,
}

/// Point-star field settings.
#[derive(Debug, Clone)]
pub struct Stars {
    /// Procedural or catalogue stars.
    pub source: super::model::StarSource,
    /// `catalogue`: local sidereal time at hour 0, hours.
    pub sidereal_hours_at_midnight: f32,
    /// Stars generated before the cutoff.
    pub count: u32,
    /// Faintest visual magnitude kept.
    pub magnitude_cutoff: f32,
    /// Generator seed.
    pub seed: u64,
    /// Celestial pole elevation, degrees.
    pub pole_elevation_deg: f32,
    /// Colour/visibility over the day.
    pub color: Color,
    /// Size of a magnitude-0 star, pixels.
    pub size_px: f32,
    /// Drawn after objects of this priority or lower.
    pub priority: u8,
}

/// Sun glare settings.
#[derive(Debug, Clone)]
pub struct Glare {
    /// Halo texture.
    pub halo: Arc<TextureImage>,
    /// Halo size, degrees.
    pub halo_size_deg: f32,
    /// Occlusion-tested disc size, degrees.
    pub disc_size_deg: f32,
    /// Seconds of retinal persistence.
    pub persistence_s: f32,
    /// Shrink sprites as the sun disappears.
    pub shrink: bool,
    /// Rotation of sprites per unit of lost visibility, radians.
    pub rotate: f32,
    /// Glare colour over the day.
    pub color: Color,
    /// Flare sprites.
    pub flares: Vec<Flare>,
}

/// A lens-flare sprite.
#[derive(Debug, Clone)]
pub struct Flare {
    /// Texture.
    pub texture: Arc<TextureImage>,
    /// 0 at the sun, 1 at the screen centre.
    pub position: f32,
    /// Fraction of the screen height.
    pub size: f32,
    /// Tint.
    pub tint: Rgba,
}

impl Sky {
    /// Every colour-bitmap slot of the sky: scene colours, objects' colours, constants,
    /// gradients and UV offsets, emitters' emission and parameters, the stars' and the glare's
    /// colours.
    pub fn color_bitmaps_mut(&mut self) -> Vec<&mut Arc<ColorBitmap>> {
        let mut out: Vec<&mut Arc<ColorBitmap>> = vec![&mut self.fog_color, &mut self.sun_ambient, &mut self.sun_diffuse];
        for o in &mut self.objects {
            for v in std::iter::once(&mut o.standard).chain(o.fallback.iter_mut()) {
                out.extend(v.diffuse.bitmap.as_mut());
                out.extend(v.constants.iter_mut().filter_map(|c| c.bitmap.as_mut()));
                if let Some(g) = v.gradients.as_mut() {
                    out.extend(g.bitmaps.iter_mut());
                }
                out.extend(v.stages.iter_mut().filter_map(|s| s.uv_offset.as_mut().map(|u| &mut u.0)));
            }
        }
        for e in &mut self.emitters {
            out.extend(e.emission.bitmap.as_mut());
            out.extend(e.params.iter_mut().map(|p| &mut p.0));
        }
        if let Some(s) = self.stars.as_mut() {
            out.extend(s.color.bitmap.as_mut());
        }
        if let Some(g) = self.glare.as_mut() {
            out.extend(g.color.bitmap.as_mut());
        }
        out
    }

    /// Shows `bitmap` wherever the sky uses the file the sky names `source`, from the next
    /// frame; returns how many slots changed.
    pub fn replace_bitmap(&mut self, source: &str, bitmap: ColorBitmap) -> usize {
        let new = Arc::new(bitmap.with_source(source));
        let mut n = 0;
        for slot in self.color_bitmaps_mut() {
            if slot.source.as_deref() == Some(source) {
                *slot = new.clone();
                n += 1;
            }
        }
        n
    }
}
