//! Per-frame evaluation of a sky at (time of day, weather, GPU tier): colours, visibility, paths,
//! fallback choice and gradients. The renderer only uploads what this produces.

use glam::{Quat, Vec3};

use super::bitmap::{self, Rgba};
use super::resolved::*;

/// Texture stages a GPU tier offers (the NeL fallback tiers).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Tier(u8);

impl Tier {
    /// All tiers, best first.
    pub const ALL: [Tier; 3] = [Tier(4), Tier(2), Tier(1)];
    /// Four texture stages: every standard material fits.
    pub const FOUR: Tier = Tier(4);

    /// A tier from its stage count (1, 2 or 4).
    pub fn new(stages: u8) -> Option<Tier> {
        matches!(stages, 1 | 2 | 4).then_some(Tier(stages))
    }

    /// Texture stages available.
    pub fn stages(self) -> usize {
        self.0 as usize
    }
}

impl Default for Tier {
    fn default() -> Self {
        Tier::FOUR
    }
}

/// What the user chose for this frame.
#[derive(Debug, Clone)]
pub struct FrameInput {
    /// Time of day, game hours (wrapped into the day).
    pub hour: f32,
    /// Total elapsed game hours, for panners (defaults to `hour`).
    pub game_hours: f64,
    /// Weather 0..1.
    pub weather: f32,
    /// GPU tier to emulate.
    pub tier: Tier,
    /// Rendering the environment map instead of the main view.
    pub env_map: bool,
    /// Objects switched off by name (UI toggles).
    pub disabled: Vec<String>,
}

impl FrameInput {
    /// A frame at (hour, weather) with the best tier.
    pub fn new(hour: f32, weather: f32) -> Self {
        Self { hour, game_hours: hour as f64, weather, tier: Tier::FOUR, env_map: false, disabled: Vec::new() }
    }
}

/// Why an object is not drawn this frame.
#[derive(Debug, Clone, PartialEq)]
pub enum Hidden {
    /// Its ref colour's alpha is 0 at this (time, weather).
    RefAlphaZero(RefColor),
    /// It needs more texture stages than the tier has and no fallback fits.
    Tier {
        /// Stages needed by the cheapest usable version.
        needs: usize,
        /// Stages the tier has.
        has: usize,
    },
    /// Switched off in the UI.
    Toggled,
    /// Not visible in this kind of view (`visible_in_main_scene` / `visible_in_env_map`).
    NotInView,
}

impl std::fmt::Display for Hidden {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Hidden::RefAlphaZero(c) => {
                let name = match c {
                    RefColor::None => "none",
                    RefColor::Diffuse => "diffuse",
                    RefColor::Constant0 => "constant0",
                    RefColor::Constant1 => "constant1",
                    RefColor::Constant2 => "constant2",
                    RefColor::Constant3 => "constant3",
                };
                write!(f, "ref_color {name} has alpha 0")
            }
            Hidden::Tier { needs, has } => write!(f, "needs {needs} texture stages, tier has {has}, no fallback fits"),
            Hidden::Toggled => write!(f, "switched off"),
            Hidden::NotInView => write!(f, "not visible in this view"),
        }
    }
}

/// Evaluated state of one pass (a version or one fallback pass).
#[derive(Debug, Clone, PartialEq)]
pub struct PassFrame {
    /// 0 = standard, 1.. = fallback pass number.
    pub version: usize,
    /// Diffuse colour.
    pub diffuse: Rgba,
    /// Constant colours 0..3 (unused ones white).
    pub constants: [Rgba; 4],
    /// UV offset per stage (panner + offset bitmap), in repeats.
    pub uv_offsets: [[f32; 2]; 4],
    /// 1xH gradient for the gradient-fed stage.
    pub gradient: Option<Vec<Rgba>>,
}

/// Evaluated state of one object.
#[derive(Debug, Clone, PartialEq)]
pub struct ObjectFrame {
    /// Index into `Sky::objects`.
    pub index: usize,
    /// Passes to draw, or why none are.
    pub passes: Result<Vec<PassFrame>, Hidden>,
    /// Whether the fallback passes were chosen.
    pub fallback: bool,
    /// Fallback passes skipped because they need more stages than the tier has: (pass, stages needed).
    pub dropped: Vec<(usize, usize)>,
    /// Unit direction from the viewer (x east, y up, -z north) and roll, for placed objects.
    pub placement: Option<(Vec3, f32)>,
}

/// Everything the renderer needs for one frame.
#[derive(Debug, Clone)]
pub struct FrameSky {
    /// Time of day used.
    pub hour: f32,
    /// Weather used.
    pub weather: f32,
    /// Fog colour of the main scene.
    pub fog_color: Rgba,
    /// Sun ambient light.
    pub sun_ambient: Rgba,
    /// Sun diffuse light.
    pub sun_diffuse: Rgba,
    /// Unit vector towards the sun.
    pub towards_sun: Vec3,
    /// Rotation taking world directions to the celestial frame (stars, galaxy).
    pub celestial_from_world: Quat,
    /// Objects in draw order.
    pub objects: Vec<ObjectFrame>,
    /// Star colour (alpha scales visibility), if the sky has stars.
    pub stars: Option<Rgba>,
    /// Glare colour, if the sky has glare.
    pub glare: Option<Rgba>,
}

/// Converts compass azimuth and elevation (degrees) to a unit direction.
pub fn direction(azimuth_deg: f32, elevation_deg: f32) -> Vec3 {
    let (az, el) = (azimuth_deg.to_radians(), elevation_deg.to_radians());
    Vec3::new(az.sin() * el.cos(), el.sin(), -az.cos() * el.cos())
}

/// Inverse of [`direction`]: (azimuth, elevation) in degrees.
pub fn azimuth_elevation(d: Vec3) -> (f32, f32) {
    (d.x.atan2(-d.z).to_degrees(), d.y.clamp(-1.0, 1.0).asin().to_degrees())
}

fn slerp(a: Vec3, b: Vec3, t: f32) -> Vec3 {
    let cos = a.dot(b).clamp(-1.0, 1.0);
    if cos > 0.9995 || cos < -0.9995 {
        return a.lerp(b, t).try_normalize().unwrap_or(a);
    }
    let theta = cos.acos();
    ((a * ((1.0 - t) * theta).sin() + b * (t * theta).sin()) / theta.sin()).normalize()
}

impl Sky {
    /// Direction and roll of a path at a time of day: great-circle interpolation between keys,
    /// wrapping from the last key of the day to the first.
    pub fn path_at(&self, path: usize, hour: f32) -> (Vec3, f32) {
        let day = self.hours_per_day;
        match &self.paths[path].kind {
            PathKind::Keys(keys) => {
                let h = hour.rem_euclid(day);
                let n = keys.len();
                let next = keys.iter().position(|k| k.hour > h).unwrap_or(n);
                let (a, b) = (keys[(next + n - 1) % n], keys[next % n]);
                let span = (b.hour - a.hour).rem_euclid(day);
                let t = if span > 0.0 { (h - a.hour).rem_euclid(day) / span } else { 0.0 };
                let d = slerp(direction(a.azimuth_deg, a.elevation_deg), direction(b.azimuth_deg, b.elevation_deg), t);
                (d, a.roll_deg + (b.roll_deg - a.roll_deg) * t)
            }
            PathKind::Follow { target, lag_hours, azimuth_offset_deg, elevation_offset_deg } => {
                let (d, roll) = self.path_at(*target, hour - lag_hours);
                let (az, el) = azimuth_elevation(d);
                (direction(az + azimuth_offset_deg, (el + elevation_offset_deg).clamp(-90.0, 90.0)), roll)
            }
        }
    }

    /// Evaluates the whole sky for one frame.
    pub fn evaluate(&self, input: &FrameInput) -> FrameSky {
        let (hour, hpd) = (input.hour.rem_euclid(self.hours_per_day), self.hours_per_day);
        let weather = input.weather.clamp(0.0, 1.0);
        let fog = self.fog_color.sample(hour, hpd, weather);
        let color = |c: &Color| -> Rgba {
            match c.mode {
                ColorMode::Unused => c.value,
                ColorMode::Fog => fog,
                ColorMode::Bitmap => c.bitmap.as_ref().map_or(c.value, |b| b.sample(hour, hpd, weather)),
                ColorMode::BitmapTimesFog => c.bitmap.as_ref().map_or(fog, |b| bitmap::mul(b.sample(hour, hpd, weather), fog)),
            }
        };
        let pass = |version: usize, v: &Version| -> PassFrame {
            let mut constants = [[1.0; 4]; 4];
            for (k, c) in v.constants.iter().enumerate() {
                constants[k] = color(c);
            }
            let mut uv_offsets = [[0.0; 2]; 4];
            for (k, s) in v.stages.iter().enumerate() {
                let mut off = [0, 1].map(|i| (s.panner[i] as f64 * input.game_hours).rem_euclid(1.0) as f32);
                if let Some((b, factor)) = &s.uv_offset {
                    let c = b.sample(hour, hpd, weather);
                    off[0] += (c[0] - 0.5) * factor;
                    off[1] += (c[1] - 0.5) * factor;
                }
                uv_offsets[k] = off;
            }
            let gradient = v.gradients.as_ref().map(|g| bitmap::weather_gradient(&g.bitmaps, hour, hpd, weather));
            PassFrame { version, diffuse: color(&v.diffuse), constants, uv_offsets, gradient }
        };

        let objects = self
            .objects
            .iter()
            .enumerate()
            .map(|(index, o)| {
                let placement = o.path.map(|p| self.path_at(p, hour));
                let in_view = if input.env_map { o.visible_in_env_map } else { o.visible_in_main_scene };
                let (versions, fallback): (Vec<(usize, &Version)>, bool) = if o.standard.stages.len() <= input.tier.stages() {
                    (vec![(0, &o.standard)], false)
                } else {
                    (o.fallback.iter().enumerate().map(|(i, v)| (i + 1, v)).collect(), true)
                };
                let tier = input.tier.stages();
                let dropped: Vec<(usize, usize)> =
                    versions.iter().filter(|(_, v)| v.stages.len() > tier).map(|(i, v)| (*i, v.stages.len())).collect();
                let fitting: Vec<(usize, &Version)> = versions.iter().copied().filter(|(_, v)| v.stages.len() <= tier).collect();
                let passes = if !in_view {
                    Err(Hidden::NotInView)
                } else if input.disabled.iter().any(|d| d == &o.name) {
                    Err(Hidden::Toggled)
                } else if fitting.is_empty() {
                    let needs = versions.iter().map(|(_, v)| v.stages.len()).min().unwrap_or(o.standard.stages.len());
                    Err(Hidden::Tier { needs, has: tier })
                } else {
                    let passes: Vec<PassFrame> = fitting.iter().map(|&(i, v)| pass(i, v)).collect();
                    let first = &passes[0];
                    let ref_alpha = match fitting[0].1.ref_color {
                        RefColor::None => 1.0,
                        RefColor::Diffuse => first.diffuse[3],
                        RefColor::Constant0 => first.constants[0][3],
                        RefColor::Constant1 => first.constants[1][3],
                        RefColor::Constant2 => first.constants[2][3],
                        RefColor::Constant3 => first.constants[3][3],
                    };
                    // Below half an 8-bit step the object would contribute nothing: skip its fill.
                    if ref_alpha < 0.5 / 255.0 {
                        Err(Hidden::RefAlphaZero(fitting[0].1.ref_color))
                    } else {
                        Ok(passes)
                    }
                };
                ObjectFrame { index, passes, fallback, dropped, placement }
            })
            .collect();

        let stars = self.stars.as_ref().map(|s| color(&s.color));
        let pole = self.stars.as_ref().map_or(45.0, |s| s.pole_elevation_deg);
        let axis = direction(0.0, pole);
        // One turn of the celestial sphere per day, around the pole, westward as seen from the ground.
        let celestial_from_world = Quat::from_axis_angle(axis, -std::f32::consts::TAU * hour / hpd);
        FrameSky {
            hour,
            weather,
            fog_color: fog,
            sun_ambient: self.sun_ambient.sample(hour, hpd, weather),
            sun_diffuse: self.sun_diffuse.sample(hour, hpd, weather),
            towards_sun: self.path_at(self.sun_path, hour).0,
            celestial_from_world,
            objects,
            stars,
            glare: self.glare.as_ref().map(|g| color(&g.color)),
        }
    }

    /// Index of an object by name.
    pub fn object_index(&self, name: &str) -> Option<usize> {
        self.objects.iter().position(|o| o.name == name)
    }
}
