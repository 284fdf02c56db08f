//! Particle emitters' frame data: the instances the GPU draws, the clock that drives them, the
//! births handed to the GPU, and every emitter's particles this frame. The simulation that
//! makes them is [`super::particle_sim`].

use bytemuck::{Pod, Zeroable};

/// One particle as the GPU draws it. Keep in sync with `Particle` in shaders/particles.wgsl and
/// shaders/precipitation.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct ParticleInstance {
    /// Dome: unit direction (xyz); camera: metres from the eye (xyz). w: half size (rad or m).
    pub position: [f32; 4],
    /// Velocity (rad/s on the dome, m/s around the camera); w: streak length, s of motion.
    pub velocity: [f32; 4],
    /// RGBA (not premultiplied).
    pub color: [f32; 4],
    /// x: shape (0 dot, 1 streak, 2 flake, 3 bolt, 4 texture), y: random bits, zw: unused.
    pub misc: [u32; 4],
}
const _: () = assert!(std::mem::size_of::<ParticleInstance>() == 64);

/// What drives the particles' time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParticleClock {
    /// Simulation time, s.
    pub time_s: f64,
    /// Game hours per second of simulation: how the hour at a particle's birth is found (the
    /// sky's `1 / particle_seconds_per_hour` when the time slider drives the particles, 0 when
    /// real time does while the hour stands still).
    pub hours_per_s: f64,
}

/// Extra particles born at once (the app's "burst" button), regardless of the emission switch.
#[derive(Debug, Clone, PartialEq)]
pub struct Burst {
    /// Emitter name.
    pub emitter: String,
    /// Simulation time of the burst, s.
    pub time_s: f64,
    /// Particles.
    pub count: u32,
}

/// Most buckets of birth conditions handed to the GPU (longer lives get longer buckets).
pub const MAX_GPU_BUCKETS: usize = 1024;

/// A camera emitter's births for the GPU to evaluate (`shaders/particle_sim.wgsl`): the same
/// closed form, one invocation per slot, written in slot order (dead slots as empty sprites), so
/// the picture is as deterministic as the CPU's.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct GpuBirths {
    /// Slots evaluated (and instances drawn), at most the cap.
    pub slots: u32,
    /// Age of the first (oldest) slot, s.
    pub first_age_s: f32,
    /// Seconds between slots.
    pub slot_interval_s: f32,
    /// The emitter's rate over the slot rate (before the conditions' scale).
    pub acceptance: f32,
    /// The first slot's number (random seeds), low 32 bits.
    pub first_slot: u32,
    /// Seconds from the start of the first bucket to the first slot's birth.
    pub bucket_offset_s: f32,
    /// Length of a bucket, s.
    pub bucket_s: f32,
    /// Per bucket: [on, rate, speed, size], tint RGBA, [rain_to_snow, 0, 0, 0].
    pub conditions: Vec<[f32; 4]>,
}

/// One emitter's particles this frame.
#[derive(Debug, Clone, Default)]
pub struct EmitterFrame {
    /// Index into `Sky::emitters`.
    pub emitter: usize,
    /// The particles alive, oldest first (at most the cap).
    pub instances: Vec<ParticleInstance>,
    /// Whether the emitter is giving birth now.
    pub emitting: bool,
    /// Light lift of its lightning bolts now.
    pub flash: f32,
    /// Camera emitters evaluated on the GPU: their births (`instances` then holds only bursts).
    pub gpu: Option<GpuBirths>,
}

/// Every emitter's particles this frame.
#[derive(Debug, Clone, Default)]
pub struct ParticleFrame {
    /// Per emitter that is not switched off, in the sky's order.
    pub emitters: Vec<EmitterFrame>,
    /// Total light lift from lightning (0 = none), applied to the scene's light and the sky.
    pub flash: f32,
}

impl ParticleFrame {
    /// Particles alive in all on the CPU, plus the slots the GPU evaluates (an upper bound of its).
    pub fn alive(&self) -> usize {
        self.emitters.iter().map(|e| e.instances.len() + e.gpu.as_ref().map_or(0, |g| g.slots as usize)).sum()
    }
}
