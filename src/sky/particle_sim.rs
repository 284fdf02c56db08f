//! Particle emitters, simulated on the CPU in closed form: no state is carried between frames.
//!
//! An emitter has birth slots at a fixed rate (its rate, or what its cap can hold over a
//! lifetime if that is less); slot `k` is born at `k / slot_rate` seconds with random numbers
//! from a hash of (seed, emitter, k). A slot is born if, at its birth time, the emitter's
//! emission colour (a bitmap by hour and weather) is not black, its object is not hidden by its
//! ref colour, and a random draw passes the rate's scale (user parameters, the weather for
//! precipitation). Its state at a later time is a formula of its age (ballistic motion, snow
//! drift, size and colour over life). So the particles alive at time `t` are a function of `t`
//! alone: scrubbing the time slider is deterministic, the same hour and weather always give the
//! same picture, a particle outlives a birth condition that ended (an object hidden by its ref
//! colour keeps its particles until they die, as in NeL), and memory is bounded by the caps.
//! docs/performance.md measures this against the same evaluation as a GPU compute pass.

use glam::Vec3;

use super::bitmap::Rgba;
use super::eval::{FrameInput, FrameSky, Hidden, HIDDEN_ALPHA};
use super::model::{EmitterKind, ParamTarget, ParticleShape};
use super::particles::*;
use super::resolved::{Emitter, EmitterAttach, Sky};

/// SplitMix64 finaliser: random bits of a slot.
fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Random numbers of one slot.
struct SlotRng(u64);

impl SlotRng {
    fn new(seed: u64, emitter: usize, slot: i64) -> Self {
        Self(mix(seed ^ mix((emitter as u64) << 40) ^ (slot as u64).wrapping_mul(0xD6E8_FEB8_6659_FD93)))
    }

    /// Uniform in [0, 1).
    fn next(&mut self) -> f32 {
        self.0 = mix(self.0);
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }

    /// Uniform in [-1, 1).
    fn signed(&mut self) -> f32 {
        self.next() * 2.0 - 1.0
    }
}

/// Birth conditions at one moment.
#[derive(Debug, Clone, Copy)]
struct Conditions {
    /// Whether births happen at all.
    on: bool,
    /// Rate scale (0..1).
    rate: f32,
    /// Speed, size scale.
    speed: f32,
    size: f32,
    /// Colour: emission tint times the colour parameter.
    tint: Rgba,
    /// Precipitation: 0 rain .. 1 snow.
    rain_to_snow: f32,
}

/// Seconds per bucket of birth conditions: bitmaps are sampled once per bucket, not per slot.
const BUCKET_S: f64 = 1.0 / 16.0;

/// The emitter's birth conditions at `hour`.
fn conditions(sky: &Sky, e: &Emitter, hour: f32, weather: f32, object_live: bool) -> Conditions {
    let hpd = sky.hours_per_day;
    let hour = hour.rem_euclid(hpd);
    let tint = sky.color_at(&e.emission, hour, weather);
    let mut c = Conditions { on: tint[0].max(tint[1]).max(tint[2]) > 0.5 / 255.0, rate: 1.0, speed: 1.0, size: 1.0, tint, rain_to_snow: e.rain_to_snow };
    for (bitmap, target) in &e.params {
        let v = bitmap.sample(hour, hpd, weather)[0].clamp(0.0, 1.0);
        match target {
            ParamTarget::Rate => c.rate *= v,
            ParamTarget::Speed => c.speed *= v,
            ParamTarget::Size => c.size *= v,
            ParamTarget::Color => c.tint = [c.tint[0] * v, c.tint[1] * v, c.tint[2] * v, c.tint[3]],
            ParamTarget::RainToSnow => c.rain_to_snow = v,
        }
    }
    if e.kind == EmitterKind::Precipitation {
        c.rate *= weather.clamp(0.0, 1.0);
    }
    if let EmitterAttach::Object(index) = e.attach {
        // Hidden by its ref colour at that hour: no births (particles already born live on).
        c.on &= object_live && object_ref_visible(sky, index, hour, weather);
    }
    c
}

/// Whether an object's ref colour lets it show at `hour` (the evaluation's rule).
fn object_ref_visible(sky: &Sky, index: usize, hour: f32, weather: f32) -> bool {
    let input = FrameInput::new(hour, weather);
    sky.object_ref_alpha(index, &input) >= HIDDEN_ALPHA
}

/// A local frame around a dome direction: (right, up) tangent to the sky.
fn tangent_frame(centre: Vec3) -> (Vec3, Vec3) {
    let right = centre.cross(Vec3::Y).try_normalize().unwrap_or(Vec3::X);
    (right, right.cross(centre))
}

/// Directions within an angle of an axis, uniform in solid angle (the frame is computed once).
#[derive(Debug, Clone, Copy)]
struct Cone {
    axis: Vec3,
    a: Vec3,
    b: Vec3,
    one_minus_cos: f32,
}

impl Cone {
    fn new(axis: Vec3, cone_rad: f32) -> Self {
        let (a, b) = tangent_frame(axis);
        Self { axis, a, b, one_minus_cos: 1.0 - cone_rad.cos() }
    }

    /// A direction from two uniform numbers.
    fn sample(&self, u: f32, v: f32) -> Vec3 {
        let cos_t = 1.0 - u * self.one_minus_cos;
        let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
        let (s, c) = (v * std::f32::consts::TAU).sin_cos();
        self.axis * cos_t + (self.a * c + self.b * s) * sin_t
    }
}

/// A direction within `cone_rad` of `axis`, from two uniform numbers.
fn in_cone(axis: Vec3, cone_rad: f32, u: f32, v: f32) -> Vec3 {
    Cone::new(axis, cone_rad).sample(u, v)
}

/// Simulates every emitter of `sky` for the frame `frame` evaluated from `input`.
pub fn simulate(sky: &Sky, input: &FrameInput, frame: &FrameSky) -> ParticleFrame {
    let clock =
        input.particle_clock.unwrap_or(ParticleClock { time_s: input.game_hours * sky.particle_seconds_per_hour as f64, hours_per_s: 1.0 / sky.particle_seconds_per_hour as f64 });
    let mut out = ParticleFrame::default();
    for (index, e) in sky.emitters.iter().enumerate() {
        // Switched off; or precipitation around a viewer in an environment map of the sky.
        if input.disabled.iter().any(|d| d == &e.name) || (input.env_map && e.attach == EmitterAttach::Camera) {
            continue;
        }
        let f = simulate_emitter(sky, index, e, input, frame, clock);
        out.flash += f.flash;
        out.emitters.push(f);
    }
    out.flash = out.flash.min(2.0);
    out
}

fn simulate_emitter(sky: &Sky, index: usize, e: &Emitter, input: &FrameInput, frame: &FrameSky, clock: ParticleClock) -> EmitterFrame {
    let t = clock.time_s;
    let max_life = (e.lifetime_s * (1.0 + e.lifetime_spread)) as f64;
    // What the cap can hold over a lifetime: a full emitter drops its newest births.
    let slot_rate = (e.rate as f64).min(e.max_particles as f64 / max_life).max(0.0);
    // The object: hidden now for a reason other than its ref colour stops births (and draws).
    let (object_live, placement) = match e.attach {
        EmitterAttach::Camera => (true, None),
        EmitterAttach::Object(i) => {
            let of = frame.objects.iter().find(|o| o.index == i);
            let live = of.is_some_and(|o| matches!(&o.versions, Ok(_) | Err(Hidden::RefAlphaZero(_))));
            (live, of.and_then(|o| o.placement).map(|(d, _)| d))
        }
    };
    let cap = e.max_particles as usize;
    let cone = Cone::new(e.direction.try_normalize().unwrap_or(Vec3::NEG_Y), e.spread_deg.to_radians());
    let env = Births { sky, index, e, frame, clock, object_live, placement, slot_rate, cone };
    let (mut instances, mut flash) = (Vec::new(), 0.0f32);
    let on_gpu = input.gpu_particles && e.attach == EmitterAttach::Camera && e.kind != EmitterKind::Lightning;
    let mut gpu = None;
    if on_gpu && slot_rate > 0.0 {
        gpu = Some(env.gpu_births(max_life));
    } else if slot_rate > 0.0 && object_live {
        let first = ((t - max_life) * slot_rate).ceil() as i64;
        let last = (t * slot_rate).floor() as i64;
        let slots = (last - first + 1).max(0);
        // Large emitters split their slots over the cores (each chunk in birth order, so the cap
        // still keeps the oldest).
        let workers = if slots >= 4096 { std::thread::available_parallelism().map_or(1, |n| n.get()).min(8) as i64 } else { 1 };
        let chunk = (slots + workers - 1) / workers.max(1);
        let parts: Vec<(Vec<ParticleInstance>, f32)> = if workers > 1 {
            std::thread::scope(|scope| {
                let handles: Vec<_> = (0..workers)
                    .map(|w| {
                        let env = &env;
                        scope.spawn(move || env.run(first + w * chunk, (first + (w + 1) * chunk - 1).min(last), cap))
                    })
                    .collect();
                handles.into_iter().map(|h| h.join().unwrap_or_default()).collect()
            })
        } else {
            vec![env.run(first, last, cap)]
        };
        instances.reserve(parts.iter().map(|p| p.0.len()).sum::<usize>().min(cap));
        for (part, f) in parts {
            let room = cap.saturating_sub(instances.len());
            instances.extend(part.into_iter().take(room));
            flash += f;
        }
    }
    let mut bucket: Option<(i64, Conditions)> = None;
    let mut cond_at = |birth: f64| env.conditions_cached(&mut bucket, birth);
    // Bursts: born at once, whatever the switch says (within what the GPU's slots leave of the cap).
    let cap = cap.saturating_sub(gpu.as_ref().map_or(0, |g: &GpuBirths| g.slots as usize));
    for (n, burst) in input.bursts.iter().filter(|b| b.emitter == e.name).enumerate() {
        let age = (t - burst.time_s) as f32;
        if !(0.0..max_life as f32).contains(&age) {
            continue;
        }
        let c = Conditions { on: true, ..cond_at(burst.time_s) };
        for j in 0..burst.count.min(e.max_particles) {
            if instances.len() >= cap {
                break;
            }
            let mut rng = SlotRng::new(e.seed ^ mix(burst.time_s.to_bits()) ^ (n as u64), index, -1 - j as i64);
            rng.next();
            if let Some(p) = particle(e, &mut rng, age, &c, placement, &env.cone, &mut flash) {
                instances.push(p);
            }
        }
    }
    let emitting = object_live && slot_rate > 0.0 && {
        let c = cond_at(t);
        c.on && c.rate > 0.0
    };
    EmitterFrame { emitter: index, instances, emitting, flash, gpu }
}

/// What the births of one emitter depend on this frame.
struct Births<'a> {
    sky: &'a Sky,
    index: usize,
    e: &'a Emitter,
    frame: &'a FrameSky,
    clock: ParticleClock,
    object_live: bool,
    placement: Option<Vec3>,
    slot_rate: f64,
    /// Camera emitters: the directions of motion.
    cone: Cone,
}

impl Births<'_> {
    /// Birth conditions at simulation time `time_s`: the hour then, from the frame's hour and the clock.
    fn conditions_at(&self, time_s: f64) -> Conditions {
        let hour = self.frame.hour as f64 - (self.clock.time_s - time_s) * self.clock.hours_per_s;
        conditions(self.sky, self.e, hour as f32, self.frame.weather, self.object_live)
    }

    /// Birth conditions at `birth` (s), computed once per bucket of [`BUCKET_S`].
    fn conditions_cached(&self, bucket: &mut Option<(i64, Conditions)>, birth: f64) -> Conditions {
        let b = (birth / BUCKET_S).floor() as i64;
        match *bucket {
            Some((k, c)) if k == b => c,
            _ => {
                let c = self.conditions_at(b as f64 * BUCKET_S);
                *bucket = Some((b, c));
                c
            }
        }
    }

    /// The slots of the last lifetime and their birth conditions, for the GPU.
    fn gpu_births(&self, max_life: f64) -> GpuBirths {
        let t = self.clock.time_s;
        let first = ((t - max_life) * self.slot_rate).ceil() as i64;
        let last = (t * self.slot_rate).floor() as i64;
        let slots = ((last - first + 1).max(0) as u64).min(self.e.max_particles as u64) as u32;
        let first_birth = first as f64 / self.slot_rate;
        let span = slots as f64 / self.slot_rate;
        let bucket_s = BUCKET_S.max(span / MAX_GPU_BUCKETS as f64);
        let first_bucket = (first_birth / bucket_s).floor();
        let buckets = (((first_birth + span) / bucket_s).floor() - first_bucket + 1.0).clamp(1.0, MAX_GPU_BUCKETS as f64 + 1.0) as usize;
        let mut table = Vec::with_capacity(buckets * 3);
        for b in 0..buckets {
            let c = self.conditions_at((first_bucket + b as f64) * bucket_s);
            table.push([if c.on { 1.0 } else { 0.0 }, c.rate, c.speed, c.size]);
            table.push(c.tint);
            table.push([c.rain_to_snow, 0.0, 0.0, 0.0]);
        }
        // No bucket of the last lifetime gave birth (fair weather, daytime): nothing to evaluate
        // nor draw.
        let any_births = table.chunks(3).any(|c| c[0][0] > 0.5 && c[0][1] > 0.0);
        GpuBirths {
            slots: if any_births { slots } else { 0 },
            first_age_s: (t - first_birth) as f32,
            slot_interval_s: (1.0 / self.slot_rate) as f32,
            acceptance: (self.e.rate as f64 / self.slot_rate).min(1.0) as f32,
            first_slot: first as u32,
            bucket_offset_s: (first_birth - first_bucket * bucket_s) as f32,
            bucket_s: bucket_s as f32,
            conditions: table,
        }
    }

    /// The live particles of slots `first..=last`, oldest first, at most `cap`; and their flash.
    fn run(&self, first: i64, last: i64, cap: usize) -> (Vec<ParticleInstance>, f32) {
        let (t, e) = (self.clock.time_s, self.e);
        let mut out = Vec::with_capacity(((last - first + 1).max(0) as usize).min(cap));
        let mut flash = 0.0f32;
        let mut bucket = None;
        for k in first..=last {
            if out.len() >= cap {
                break;
            }
            let birth = k as f64 / self.slot_rate;
            let c = self.conditions_cached(&mut bucket, birth);
            if !c.on {
                continue;
            }
            let mut rng = SlotRng::new(e.seed, self.index, k);
            if rng.next() as f64 >= (e.rate as f64 * c.rate as f64 / self.slot_rate).min(1.0) {
                continue;
            }
            if let Some(p) = particle(e, &mut rng, (t - birth) as f32, &c, self.placement, &self.cone, &mut flash) {
                out.push(p);
            }
        }
        (out, flash)
    }
}

/// The particle of a slot at `age` seconds, if still alive.
#[allow(clippy::too_many_arguments)]
fn particle(e: &Emitter, rng: &mut SlotRng, age: f32, c: &Conditions, placement: Option<Vec3>, cone: &Cone, flash: &mut f32) -> Option<ParticleInstance> {
    let life = e.lifetime_s * (1.0 + e.lifetime_spread * rng.signed());
    if !(0.0..life).contains(&age) || life <= 0.0 {
        return None;
    }
    let x = age / life;
    let speed = e.speed * c.speed * (1.0 + e.speed_spread * rng.signed());
    let mut size = (e.size[0] + (e.size[1] - e.size[0]) * x) * c.size;
    let lerp = |a: f32, b: f32| a + (b - a) * x;
    let [c0, c1] = e.color;
    let mut color = [lerp(c0[0], c1[0]) * c.tint[0], lerp(c0[1], c1[1]) * c.tint[1], lerp(c0[2], c1[2]) * c.tint[2], lerp(c0[3], c1[3]) * c.tint[3]];
    let mut shape = match e.shape {
        ParticleShape::Dot => 0,
        ParticleShape::Streak => 1,
        ParticleShape::Flake => 2,
        ParticleShape::Bolt => 3,
    };
    if e.texture.is_some() {
        shape = 4;
    }
    let mut streak = e.streak_s;
    let (u1, u2, u3, u4, u5) = (rng.next(), rng.next(), rng.next(), rng.next(), rng.next());
    let bits = (rng.next() * 16_777_216.0) as u32;
    let spread = e.spread_deg.to_radians();
    let (position, velocity) = match e.attach {
        EmitterAttach::Camera => {
            let half = e.box_m * 0.5;
            let p0 = Vec3::new(u1 * 2.0 - 1.0, u2 * 2.0 - 1.0, u3 * 2.0 - 1.0) * half;
            let mut v = cone.sample(u4, u5) * speed;
            let mut p = p0 + v * age + Vec3::NEG_Y * (0.5 * e.gravity * age * age);
            v += Vec3::NEG_Y * (e.gravity * age);
            if e.kind == EmitterKind::Precipitation && rng.next() < c.rain_to_snow {
                // Snow: slow, drifting flakes; rain keeps its streaks.
                let phase = rng.next() * std::f32::consts::TAU;
                v *= 0.12;
                p = p0 + v * age + Vec3::new((age * 1.3 + phase).sin(), 0.0, (age * 0.9 + phase).cos()) * 0.4;
                shape = if e.texture.is_some() { 4 } else { 2 };
                streak = 0.0;
                size *= 1.8;
                color[3] = color[3].max(0.5 * c0[3].max(c1[3]));
            }
            (p, v)
        }
        EmitterAttach::Object(_) => {
            let (p0, tangent_dir) = match placement {
                Some(centre) => {
                    // Born within `region_deg` of the object's centre, moving with it.
                    let p0 = in_cone(centre, e.region_deg.to_radians(), u1, u2);
                    let out = (p0 - centre * p0.dot(centre)).try_normalize().unwrap_or(tangent_frame(centre).0);
                    (p0, out)
                }
                None => {
                    // Over the sky above `min_elevation_deg`, uniform in solid angle.
                    let lo = e.min_elevation_deg.to_radians().sin();
                    let y = lo + (1.0 - lo) * u1;
                    let r = (1.0 - y * y).max(0.0).sqrt();
                    let phi = u2 * std::f32::consts::TAU;
                    let p0 = Vec3::new(r * phi.cos(), y, r * phi.sin());
                    (p0, tangent_frame(p0).0)
                }
            };
            let wanted = if e.direction.length_squared() > 0.0 { e.direction.normalize() } else { tangent_dir };
            let dir = in_cone(wanted, spread, u3, u4);
            // Motion along the sky: the direction's part tangent to it at the birth point.
            let tangent = (dir - p0 * dir.dot(p0)).try_normalize().unwrap_or(tangent_dir);
            let w = speed.to_radians();
            let down = (Vec3::NEG_Y - p0 * (-p0.y)).try_normalize().unwrap_or(Vec3::ZERO);
            let g = e.gravity.to_radians();
            let p = (p0 + tangent * (w * age) + down * (0.5 * g * age * age)).normalize_or(p0);
            let v = tangent * w + down * (g * age);
            size = size.to_radians();
            (p, v)
        }
    };
    if e.kind == EmitterKind::Lightning {
        *flash += e.flash * (1.0 - x) * (1.0 - x);
    }
    let values = [position.x, position.y, position.z, size * 0.5, velocity.x, velocity.y, velocity.z, streak];
    if values.iter().any(|v| !v.is_finite()) || color.iter().any(|v| !v.is_finite()) {
        return None;
    }
    Some(ParticleInstance {
        position: [position.x, position.y, position.z, size * 0.5],
        velocity: [velocity.x, velocity.y, velocity.z, streak],
        color: color.map(|v| v.max(0.0)),
        misc: [shape, bits, matches!(e.attach, EmitterAttach::Camera) as u32, 0],
    })
}
