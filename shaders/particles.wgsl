//! requires: particle/shape, sky_model/tone
// Particles on the dome (sky phase): emitters attached to sky objects, in directions, at the
// sky's depth like the objects they belong to; also the lightning flash over the sky (shape 5,
// a full-screen triangle). (globals.wgsl is prepended by the loader.)

@group(1) @binding(0) var sprite: texture_2d<f32>;
@group(1) @binding(1) var sprite_sampler: sampler;

@vertex
fn vs_main(@builtin(vertex_index) vi: u32, p: Particle) -> ParticleOut {
    var out: ParticleOut;
    out.color = p.color;
    out.misc = p.misc;
    let corner = sprite_corner(vi);
    out.local = corner;
    if (p.misc.x == 5u) {
        // Flash: a triangle strip over the whole screen.
        out.clip = vec4<f32>(corner * 3.0 - vec2<f32>(1.0), 0.5, 1.0);
        return out;
    }
    let view = normalize(p.position.xyz);
    let dir = view + sprite_offset(corner, view, p.velocity.xyz, p.position.w, p.velocity.w);
    var clip = globals.clip_from_sky * vec4<f32>(dir, 1.0);
    clip.z = clip.w * 0.5;
    out.clip = clip;
    return out;
}

@fragment
fn fs_main(in: ParticleOut) -> @location(0) vec4<f32> {
    var coverage = 1.0;
    if (in.misc.x == 4u) {
        let t = textureSample(sprite, sprite_sampler, in.local * 0.5 + vec2<f32>(0.5));
        return vec4<f32>(to_target(in.color.rgb * t.rgb * in.color.a * t.a), 1.0);
    } else if (in.misc.x != 5u) {
        coverage = sprite_coverage(in.local, in.misc.x, in.misc.y);
    }
    // Additive, premultiplied (to_target is not linear): see stars.wgsl.
    return vec4<f32>(to_target(in.color.rgb * in.color.a * coverage), 1.0);
}

@fragment
fn fs_alpha(in: ParticleOut) -> @location(0) vec4<f32> {
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
