//! requires: particle/shape
// Particles around the viewer (scene-after-sky phase): rain and snow in metres from the eye,
// depth-tested in the main scene's depth range so the scene stand-in hides what is behind it.
// (globals.wgsl is prepended by the loader.)

@vertex
fn vs_main(@builtin(vertex_index) vi: u32, p: Particle) -> ParticleOut {
    var out = sprite_vertex(vi, p);
    let corner = out.local;
    let view = normalize(p.position.xyz);
    let world = globals.camera_position.xyz + p.position.xyz + sprite_offset(corner, view, p.velocity.xyz, p.position.w, p.velocity.w);
    out.clip = globals.clip_from_world * vec4<f32>(world, 1.0);
    return out;
}

// The fragment stage is particle/shape.wgsl's.
