// The closed-form particle evaluation of src/sky/particles.rs as a compute pass, for
// `skytune bench frame` to weigh against the CPU's (docs/performance.md): one invocation per
// birth slot of a camera emitter (the precipitation case, the only one with thousands of
// particles), appending the live particles. Same formulas; its random numbers come from a 32-bit
// PCG hash (WGSL has no u64), so the particles differ from the CPU's one by one, not in kind.
// Keep `SimParams` in sync with `SimUniform` in src/render/particle_sim.rs.
struct SimParams {
    clock: vec4<f32>,     // x: time (s) minus first_slot / slot_rate, y: 1 / slot_rate, z: acceptance, w: slots
    life: vec4<f32>,      // lifetime, spread, speed, speed spread
    direction: vec4<f32>, // xyz unit, w: cone (rad)
    shape: vec4<f32>,     // gravity, box (m), size at birth, size at death
    color0: vec4<f32>,
    color1: vec4<f32>,
    misc: vec4<u32>,      // seed, cap, first slot (low bits), streak (f32 bits)
};

struct Particle {
    position: vec4<f32>,
    velocity: vec4<f32>,
    color: vec4<f32>,
    misc: vec4<u32>,
};

@group(1) @binding(0) var<uniform> sim: SimParams;
@group(1) @binding(1) var<storage, read_write> particles: array<Particle>;
@group(1) @binding(2) var<storage, read_write> alive: atomic<u32>;

fn pcg(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

struct Rng { state: u32 };

fn next(r: ptr<function, Rng>) -> f32 {
    (*r).state = pcg((*r).state);
    return f32((*r).state >> 8u) / 16777216.0;
}

fn in_cone(axis: vec3<f32>, cone: f32, u: f32, v: f32) -> vec3<f32> {
    let cos_t = 1.0 - u * (1.0 - cos(cone));
    let sin_t = sqrt(max(1.0 - cos_t * cos_t, 0.0));
    let phi = v * 2.0 * PI;
    var a = cross(axis, vec3<f32>(0.0, 1.0, 0.0));
    if (length(a) < 1e-4) { a = vec3<f32>(1.0, 0.0, 0.0); }
    a = normalize(a);
    let b = cross(a, axis);
    return normalize(axis * cos_t + (a * cos(phi) + b * sin(phi)) * sin_t);
}

@compute @workgroup_size(64)
fn cs_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (f32(gid.x) >= sim.clock.w) {
        return;
    }
    var rng = Rng(pcg(sim.misc.x ^ pcg(sim.misc.z + gid.x)));
    // Age of slot `first + i`: (t - first / rate) - i / rate.
    let age = sim.clock.x - f32(gid.x) * sim.clock.y;
    if (next(&rng) >= sim.clock.z) {
        return;
    }
    let life = sim.life.x * (1.0 + sim.life.y * (next(&rng) * 2.0 - 1.0));
    if (age < 0.0 || age >= life) {
        return;
    }
    let x = age / life;
    let speed = sim.life.z * (1.0 + sim.life.w * (next(&rng) * 2.0 - 1.0));
    let p0 = (vec3<f32>(next(&rng), next(&rng), next(&rng)) * 2.0 - vec3<f32>(1.0)) * (0.5 * sim.shape.y);
    var v = in_cone(sim.direction.xyz, sim.direction.w, next(&rng), next(&rng)) * speed;
    let p = p0 + v * age + vec3<f32>(0.0, -0.5 * sim.shape.x * age * age, 0.0);
    v.y -= sim.shape.x * age;
    let size = mix(sim.shape.z, sim.shape.w, x);
    let slot = atomicAdd(&alive, 1u);
    if (slot >= sim.misc.y) {
        return;
    }
    particles[slot] = Particle(vec4<f32>(p, 0.5 * size), vec4<f32>(v, bitcast<f32>(sim.misc.w)), mix(sim.color0, sim.color1, x), vec4<u32>(1u, rng.state, 1u, 0u));
}
