//! requires: particle/shape, sky_model/tone
// Particles around the viewer (scene-after-sky phase): rain and snow in metres from the eye,
// depth-tested in the main scene's depth range so the scene stand-in hides what is behind it.
// (globals.wgsl is prepended by the loader.)

@group(1) @binding(0) var sprite: texture_2d<f32>;
@group(1) @binding(1) var sprite_sampler: sampler;

@vertex
fn vs_main(@builtin(vertex_index) vi: u32, p: Particle) -> ParticleOut {
    var out: ParticleOut;
    out.color = p.color;
    out.misc = p.misc;
    let corner = sprite_corner(vi);
    out.local = corner;
    let view = normalize(p.position.xyz);
    let world = globals.camera_position.xyz + p.position.xyz + sprite_offset(corner, view, p.velocity.xyz, p.position.w, p.velocity.w);
    out.clip = globals.clip_from_world * vec4<f32>(world, 1.0);
    return out;
}

@fragment
fn fs_main(in: ParticleOut) -> @location(0) vec4<f32> {
    if (in.misc.x == 4u) {
        let t = textureSample(sprite, sprite_sampler, in.local * 0.5 + vec2<f32>(0.5));
        return vec4<f32>(to_target(in.color.rgb * t.rgb * in.color.a * t.a), 1.0);
    }
    let coverage = sprite_coverage(in.local, in.misc.x, in.misc.y);
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
