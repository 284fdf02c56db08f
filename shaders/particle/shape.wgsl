//! requires: sky_model/tone
// Particle sprites shared by particles.wgsl (on the dome) and precipitation.wgsl (around the
// viewer): instance layout, sprite geometry, shapes, and the fragment stage of both (each file
// adds its vertex stage). Keep `Particle` in sync with `ParticleInstance` in src/sky/particles.rs.

@group(1) @binding(0) var sprite: texture_2d<f32>;
@group(1) @binding(1) var sprite_sampler: sampler;
struct Particle {
    @location(0) position: vec4<f32>, // dome: unit direction; camera: m from the eye. w: half size
    @location(1) velocity: vec4<f32>, // per second; w: streak length, s of motion
    @location(2) color: vec4<f32>,    // RGBA, not premultiplied
    @location(3) misc: vec4<u32>,     // x: shape (0 dot, 1 streak, 2 flake, 3 bolt, 4 texture, 5 flash), y: random bits
};

struct ParticleOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) local: vec2<f32>,
    @location(1) color: vec4<f32>,
    @location(2) @interpolate(flat) misc: vec4<u32>,
};

// A corner of the sprite around `centre` seen along `view` (unit): stretched along the motion on
// screen for streaks, square otherwise. Returns the corner's offset from the centre.
fn sprite_offset(corner: vec2<f32>, view: vec3<f32>, velocity: vec3<f32>, half: f32, streak: f32) -> vec3<f32> {
    let across = velocity - view * dot(velocity, view);
    let moving = length(across) * streak;
    var axis = normalize(cross(view, vec3<f32>(0.0, 1.0, 0.0) + vec3<f32>(1e-4, 0.0, 0.0)));
    if (moving > 1e-6) {
        axis = across / length(across);
    }
    let side = normalize(cross(view, axis));
    let half_length = max(half, 0.5 * moving);
    return axis * corner.x * half_length + side * corner.y * half;
}

fn sprite_corner(vi: u32) -> vec2<f32> {
    var corners = array<vec2<f32>, 4>(vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, -1.0), vec2<f32>(-1.0, 1.0), vec2<f32>(1.0, 1.0));
    return corners[vi];
}

// The vertex output of corner `vi` of particle `p`, all but its clip position.
fn sprite_vertex(vi: u32, p: Particle) -> ParticleOut {
    var out: ParticleOut;
    out.color = p.color;
    out.misc = p.misc;
    out.local = sprite_corner(vi);
    return out;
}

// Coverage of the procedural shapes at `local` (x along the motion, y across, both -1..1).
fn sprite_coverage(local: vec2<f32>, shape: u32, bits: u32) -> f32 {
    let r2 = dot(local, local);
    if (shape == 1u) {
        // Streak: thin across, fading towards both ends.
        return exp(-8.0 * local.y * local.y) * (1.0 - local.x * local.x);
    } else if (shape == 2u) {
        // Flake: six soft arms.
        let a = atan2(local.y, local.x);
        let arms = pow(abs(cos(3.0 * a)), 6.0);
        return exp(-3.0 * r2) * (0.35 + 0.65 * arms) * step(r2, 1.0);
    } else if (shape == 3u) {
        // Bolt: a jagged line along the motion, different for every particle.
        let s = f32(bits & 1023u) * 0.01;
        let x = local.x * 3.0;
        let offset = 0.45 * (0.55 * sin(x * 2.3 + s) + 0.3 * sin(x * 6.1 + 2.0 * s) + 0.15 * sin(x * 13.7 + 3.0 * s));
        let d = local.y - offset;
        return (exp(-60.0 * d * d) + 0.3 * exp(-6.0 * d * d)) * (1.0 - local.x * local.x);
    }
    return exp(-4.0 * r2) * step(r2, 1.0);
}

// Additive blending, premultiplied (to_target is not linear): see stars.wgsl. Shape 5 (the
// lightning flash over the sky) covers everything.
@fragment
fn fs_main(in: ParticleOut) -> @location(0) vec4<f32> {
    return sprite_additive(in);
}

fn sprite_additive(in: ParticleOut) -> vec4<f32> {
    if (in.misc.x == 4u) {
        let t = textureSample(sprite, sprite_sampler, in.local * 0.5 + vec2<f32>(0.5));
        return vec4<f32>(to_target(in.color.rgb * t.rgb * in.color.a * t.a), 1.0);
    }
    var coverage = 1.0;
    if (in.misc.x != 5u) {
        coverage = sprite_coverage(in.local, in.misc.x, in.misc.y);
    }
    return vec4<f32>(to_target(in.color.rgb * in.color.a * coverage), 1.0);
}

// Alpha blending.
@fragment
fn fs_alpha(in: ParticleOut) -> @location(0) vec4<f32> {
    return sprite_alpha(in);
}

fn sprite_alpha(in: ParticleOut) -> vec4<f32> {
    var coverage = 1.0;
    var rgb = in.color.rgb;
    if (in.misc.x == 4u) {
        let t = textureSample(sprite, sprite_sampler, in.local * 0.5 + vec2<f32>(0.5));
        rgb = rgb * t.rgb;
        coverage = t.a;
    } else {
        coverage = sprite_coverage(in.local, in.misc.x, in.misc.y);
    }
    return vec4<f32>(to_target(rgb), in.color.a * coverage);
}
