// Camera emitters' particles on the GPU (precipitation pass, compute phase): the closed form of
// src/sky/particles.rs, one invocation per birth slot of the last lifetime, each writing its
// slot of the instance buffer (a dead slot writes an empty sprite), so the output is in slot
// order and as deterministic as the CPU's. Birth conditions come per bucket of time from the CPU
// (emission switch, user parameters, weather). Its random numbers are a 32-bit PCG hash (WGSL
// has no u64): the particles are the CPU's in kind, not one by one.
// Keep `SimParams` in sync with `SimUniform` in src/render/passes/particle_sim.rs.
struct SimParams {
    clock: vec4<f32>,     // x: age of the first slot (s), y: seconds between slots, z: acceptance, w: slots
    life: vec4<f32>,      // lifetime, spread, speed, speed spread
    direction: vec4<f32>, // xyz unit, w: cone (rad)
    shape: vec4<f32>,     // gravity, box (m), size at birth, size at death
    color0: vec4<f32>,
    color1: vec4<f32>,
    misc: vec4<u32>,      // seed, precipitation (1), first slot (low bits), streak (f32 bits)
    buckets: vec4<f32>,   // x: offset of the first birth in its bucket (s), y: bucket length (s), z: buckets, w: shape
};

struct Particle {
    position: vec4<f32>,
    velocity: vec4<f32>,
    color: vec4<f32>,
    misc: vec4<u32>,
};

@group(1) @binding(0) var<uniform> sim: SimParams;
@group(1) @binding(1) var<storage, read_write> particles: array<Particle>;
// Per bucket: [on, rate, speed, size], tint, [rain_to_snow, 0, 0, 0].
@group(1) @binding(2) var<storage, read> conditions: array<vec4<f32>>;

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
    return axis * cos_t + (a * cos(phi) + b * sin(phi)) * sin_t;
}

@compute @workgroup_size(64)
fn cs_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (f32(gid.x) >= sim.clock.w) {
        return;
    }
    let i = gid.x;
    particles[i] = Particle(vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0), vec4<u32>(0u));
    let fi = f32(i);
    let bucket = min(u32(max(floor((sim.buckets.x + fi * sim.clock.y) / sim.buckets.y), 0.0)), u32(sim.buckets.z) - 1u);
    let c0 = conditions[3u * bucket];
    let tint = conditions[3u * bucket + 1u];
    let rain_to_snow = conditions[3u * bucket + 2u].x;
    if (c0.x < 0.5) {
        return;
    }
    var rng = Rng(pcg(sim.misc.x ^ pcg(sim.misc.z + i)));
    if (next(&rng) >= sim.clock.z * c0.y) {
        return;
    }
    let age = sim.clock.x - fi * sim.clock.y;
    let life = sim.life.x * (1.0 + sim.life.y * (next(&rng) * 2.0 - 1.0));
    if (age < 0.0 || age >= life || life <= 0.0) {
        return;
    }
    let x = age / life;
    let speed = sim.life.z * c0.z * (1.0 + sim.life.w * (next(&rng) * 2.0 - 1.0));
    var size = mix(sim.shape.z, sim.shape.w, x) * c0.w;
    var color = mix(sim.color0, sim.color1, x) * tint;
    let p0 = (vec3<f32>(next(&rng), next(&rng), next(&rng)) * 2.0 - vec3<f32>(1.0)) * (0.5 * sim.shape.y);
    var v = in_cone(sim.direction.xyz, sim.direction.w, next(&rng), next(&rng)) * speed;
    var p = p0 + v * age + vec3<f32>(0.0, -0.5 * sim.shape.x * age * age, 0.0);
    v.y -= sim.shape.x * age;
    var shape = u32(sim.buckets.w);
    var streak = bitcast<f32>(sim.misc.w);
    if (sim.misc.y == 1u && next(&rng) < rain_to_snow) {
        // Snow: slow, drifting flakes; rain keeps its streaks.
        let phase = next(&rng) * 2.0 * PI;
        v *= 0.12;
        p = p0 + v * age + vec3<f32>(sin(age * 1.3 + phase), 0.0, cos(age * 0.9 + phase)) * 0.4;
        if (shape != 4u) { shape = 2u; }
        streak = 0.0;
        size *= 1.8;
        color.a = max(color.a, 0.5 * max(sim.color0.a, sim.color1.a));
    }
    particles[i] = Particle(vec4<f32>(p, 0.5 * size), vec4<f32>(v, streak), max(color, vec4<f32>(0.0)), vec4<u32>(shape, rng.state, 1u, 0u));
}
