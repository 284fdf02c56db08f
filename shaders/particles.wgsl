//! requires: particle/shape, reduced/run
// Particles on the dome (sky phase): emitters attached to sky objects, in directions, at the
// sky's depth like the objects they belong to; also the lightning flash over the sky (shape 5,
// a full-screen triangle). (globals.wgsl is prepended by the loader.)

@vertex
fn vs_main(@builtin(vertex_index) vi: u32, p: Particle) -> ParticleOut {
    var out = sprite_vertex(vi, p);
    let corner = out.local;
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

// The fragment stages of the sprites are particle/shape.wgsl's.

// The flash: the instance's colour over the whole sky, additive. Its own pipeline, so that no
// sprite shape is evaluated over the screen (a SIMD rasteriser runs every branch of fs_main).
@fragment
fn fs_flash(in: ParticleOut) -> @location(0) vec4<f32> {
    let add = in.color.rgb * in.color.a;
    if globals.output.z > 0.5 {
        // A display-referred physical frame matched to the HDR picture: what the HDR path's sum
        // leaves over the model's sky, taken at its mean (globals.cloud_ambient, the map's mean
        // radiance as a display value) for one colour over the frame.
        let under = globals.cloud_ambient.rgb;
        let tone = frame_tone_mapper();
        return vec4<f32>(display_from_exposed(exposed_from_display(under) + exposed_from_display(add), tone) - under, 1.0);
    }
    return vec4<f32>(to_target(add), 1.0);
}

// Dome emitters' particles drawn after the composite of the run of reduced layers above them
// (src/render/passes/particles.rs, `Placement::UnderRun`).

// Additive under the run: the added light shows through its transmittance.
@fragment
fn fs_main_under_run(in: ParticleOut) -> @location(0) vec4<f32> {
    let c = sprite_additive(in);
    return vec4<f32>(c.rgb * run_at(in.clip.xy).a, c.a);
}

// Alpha under the run (premultiplied, blended One, OneMinusSrcAlpha): a (T m + C) over (1 - a)
// of the frame leaves C + T (a m + (1 - a) target).
@fragment
fn fs_alpha_under_run(in: ParticleOut) -> @location(0) vec4<f32> {
    let c = sprite_alpha(in);
    let run = run_alone_at(in.clip.xy);
    return vec4<f32>(c.a * (run.a * c.rgb + run.rgb), c.a);
}
