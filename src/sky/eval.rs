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
    /// Seconds since the previous frame, for systems that simulate (glare, particles).
    pub dt_s: f32,
    /// Frame number, counted by whoever drives the frames (see [`Clock`]).
    pub frame: u64,
    /// Colour source of the skydome instead of the sky file's (the app's selector).
    pub sky_model: Option<SkyModel>,
    /// Particle time (default: the game hours times the sky's `particle_seconds_per_hour`, so
    /// the time slider drives the particles deterministically).
    pub particle_clock: Option<super::particles::ParticleClock>,
    /// Bursts of particles asked for (the app's burst button), recent ones.
    pub bursts: Vec<super::particles::Burst>,
    /// Camera emitters' births are evaluated by the renderer on the GPU (measured faster from a
    /// few thousand particles: docs/performance.md); false keeps every particle on the CPU.
    pub gpu_particles: bool,
}

impl FrameInput {
    /// A frame at (hour, weather) with the best tier, the first frame, no time elapsed.
    pub fn new(hour: f32, weather: f32) -> Self {
        Self {
            hour,
            game_hours: hour as f64,
            weather,
            tier: Tier::FOUR,
            env_map: false,
            disabled: Vec::new(),
            dt_s: 0.0,
            frame: 0,
            sky_model: None,
            particle_clock: None,
            bursts: Vec::new(),
            gpu_particles: true,
        }
    }
}

/// How simulation time advances from frame to frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Stepping {
    /// Wall-clock time between frames (the window), clamped to [`Clock::MAX_DT_S`].
    RealTime,
    /// The same step every frame: deterministic stills, tests and contact sheets.
    Fixed {
        /// Seconds per frame.
        dt_s: f32,
    },
}

/// Counts frames and measures the time step of each one.
#[derive(Debug, Clone)]
pub struct Clock {
    /// How time advances.
    pub stepping: Stepping,
    frame: u64,
    last: Option<std::time::Instant>,
}

impl Clock {
    /// Longest real-time step: a stall (a drag of the window, a breakpoint) is not a jump in time.
    pub const MAX_DT_S: f32 = 0.25;

    /// A clock at frame 0.
    pub fn new(stepping: Stepping) -> Self {
        Self { stepping, frame: 0, last: None }
    }

    /// Frames ticked so far.
    pub fn frames(&self) -> u64 {
        self.frame
    }

    /// Advances one frame: returns (seconds since the previous tick, this frame's number).
    pub fn tick(&mut self) -> (f32, u64) {
        let dt_s = match self.stepping {
            Stepping::Fixed { dt_s } => dt_s,
            Stepping::RealTime => {
                let now = std::time::Instant::now();
                let dt = self.last.map_or(0.0, |l| now.duration_since(l).as_secs_f32().min(Self::MAX_DT_S));
                self.last = Some(now);
                dt
            }
        };
        self.frame += 1;
        (dt_s, self.frame)
    }

    /// Stamps `input` with the next frame's step and number.
    pub fn advance(&mut self, input: &mut FrameInput) {
        (input.dt_s, input.frame) = self.tick();
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

/// Evaluated state of one version of an object: its standard version, or one of its fallback
/// passes (NeL's term, kept in the sky format).
#[derive(Debug, Clone, PartialEq)]
pub struct VersionFrame {
    /// 0 = standard, 1.. = fallback version number.
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
    /// Transparency priority (0..63): the draw order of the sky phase.
    pub priority: u8,
    /// Versions to draw (the standard one, or the fallback versions that fit), or why none are.
    pub versions: Result<Vec<VersionFrame>, Hidden>,
    /// Whether the fallback versions were chosen.
    pub fallback: bool,
    /// Fallback passes skipped because they need more stages than the tier has: (pass, stages needed).
    pub dropped: Vec<(usize, usize)>,
    /// Unit direction from the viewer (x east, y up, -z north) and roll, for placed objects.
    pub placement: Option<(Vec3, f32)>,
}

/// The point stars of a frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StarsFrame {
    /// Tint (rgb) and visibility (alpha).
    pub color: Rgba,
    /// Drawn after the objects of this priority or lower.
    pub priority: u8,
}

/// Everything the renderer needs for one frame: the evaluated sky and the frame's clock.
#[derive(Debug, Clone)]
pub struct FrameSky {
    /// Time of day used, game hours (wrapped into the day).
    pub hour: f32,
    /// Game hours in a day of this sky.
    pub hours_per_day: f32,
    /// Total elapsed game hours (panners).
    pub game_hours: f64,
    /// Weather used, 0..1.
    pub weather: f32,
    /// Seconds since the previous frame.
    pub dt_s: f32,
    /// Frame number.
    pub frame: u64,
    /// GPU tier emulated.
    pub tier: Tier,
    /// Environment-map view instead of the main view.
    pub env_map: bool,
    /// Colour source of the skydome's gradient stage.
    pub sky_model: SkyModel,
    /// Atmosphere of the physical models.
    pub atmosphere: crate::atmosphere::Atmosphere,
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
    /// Star colour and priority, if the sky has stars.
    pub stars: Option<StarsFrame>,
    /// Glare colour, if the sky has glare.
    pub glare: Option<Rgba>,
    /// Particles alive this frame, per emitter.
    pub particles: super::particles::ParticleFrame,
}

/// Below this ref alpha (half an 8-bit step) an object would contribute nothing: it is hidden and
/// its fill skipped, and its emitters give no birth.
pub const HIDDEN_ALPHA: f32 = 0.5 / 255.0;

/// The alpha of a version's ref colour, from its diffuse colour and its constants (by index;
/// unused ones white).
pub(super) fn ref_alpha(ref_color: RefColor, diffuse: Rgba, constant: impl Fn(usize) -> Rgba) -> f32 {
    match ref_color {
        RefColor::None => 1.0,
        RefColor::Diffuse => diffuse[3],
        RefColor::Constant0 => constant(0)[3],
        RefColor::Constant1 => constant(1)[3],
        RefColor::Constant2 => constant(2)[3],
        RefColor::Constant3 => constant(3)[3],
    }
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
    if !(-0.9995..=0.9995).contains(&cos) {
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

    /// A colour slot's value at (hour, weather): its constant, the fog colour, or its bitmap
    /// (NeL's sampling: docs/sky-format.md).
    pub fn color_at(&self, c: &Color, hour: f32, weather: f32) -> Rgba {
        let hpd = self.hours_per_day;
        let fog = || self.fog_color.sample(hour, hpd, weather);
        match c.mode {
            ColorMode::Unused => c.value,
            ColorMode::Fog => fog(),
            ColorMode::Bitmap => c.bitmap.as_ref().map_or(c.value, |b| b.sample(hour, hpd, weather)),
            ColorMode::BitmapTimesFog => c.bitmap.as_ref().map_or_else(fog, |b| bitmap::mul(b.sample(hour, hpd, weather), fog())),
        }
    }

    /// The alpha of an object's ref colour at this input's hour and weather, for its version at
    /// the best tier (what decides whether it is hidden by its ref colour, and whether its
    /// emitters give birth).
    pub fn object_ref_alpha(&self, index: usize, input: &FrameInput) -> f32 {
        let Some(o) = self.objects.get(index) else { return 0.0 };
        let hour = input.hour.rem_euclid(self.hours_per_day);
        let weather = input.weather.clamp(0.0, 1.0);
        let color = |c: &Color| self.color_at(c, hour, weather);
        // The version the evaluation would draw: the standard one if the tier has its stages,
        // else the first fallback version that fits.
        let tier = input.tier.stages();
        let v = if o.standard.stages.len() <= tier { &o.standard } else { o.fallback.iter().find(|v| v.stages.len() <= tier).unwrap_or(&o.standard) };
        ref_alpha(v.ref_color, color(&v.diffuse), |k| v.constants.get(k).map_or([1.0; 4], color))
    }

    /// Index of an object by name.
    pub fn object_index(&self, name: &str) -> Option<usize> {
        self.objects.iter().position(|o| o.name == name)
    }
}
