//! `[[path]]` and `[[object]]`: sun and moon paths, sky objects, their versions, stages and colours.

use serde::Deserialize;
use toml::Spanned;

use super::*;

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

pub(super) fn white() -> [Unit; 4] {
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
