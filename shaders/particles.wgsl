//! requires: particle/shape, reduced/run
// Particles on the dome (sky phase): emitters attached to sky objects, in directions, at the
// sky's depth like the objects they belong to; also the lightning flash over the sky (shape 5,
// a full-screen triangle). (globals.wgsl is prepended by the loader.)

@vertex
fn vs_main(@builtin(vertex_index) vi: u32, p: Particle) -> ParticleOut {
    var out = sprite_vertex(vi, p);
    let corner = out.local;
    if (p.misc.x == 5u) {
        // Flash: a triangle strip over the whole screen, one colour (`flash_blend`).
        out.clip = vec4<f32>(corner * 3.0 - vec2<f32>(1.0), 0.5, 1.0);
        out.color = flash_blend(p.color.rgb * p.color.a);
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

// What the flash writes (premultiplied: colour + (1 - alpha) x target, `FLASH_BLEND` and
// `FLASH_RUN_BLEND` in src/render/passes/particles.rs) for the display value `add` it adds over
// the sky. Added as it is, or as exposed radiance on the HDR target. On a display-referred
// physical frame matched to the HDR picture, where the HDR path's sum over a pixel showing d is
// g(d) = T(E(d) + E(add)): the line through g at the sky's mean m (`cloud_ambient()`, the
// map's mean radiance as a display value) with g's mean slope there, clamped to [0, 1], so the
// flash washes the sky out and flattens its contrast as the HDR frame does, exact at m. Constant
// over the frame: computed per vertex.
fn flash_blend(add: vec3<f32>) -> vec4<f32> {
    if globals.output.z > 0.5 {
        let m = cloud_ambient();
        let flash = exposed_from_display(add);
        let at_mean = flashed(m, flash);
        // A secant over a tenth of the display range about m (within [0, 1]): g's slope where
        // the sky lies, without the toe's kink at black.
        let lo = max(m - vec3<f32>(0.05), vec3<f32>(0.0));
        let hi = min(m + vec3<f32>(0.05), vec3<f32>(1.0));
        let slopes = (flashed(hi, flash) - flashed(lo, flash)) / max(hi - lo, vec3<f32>(1e-4));
        let slope = clamp((slopes.r + slopes.g + slopes.b) / 3.0, 0.0, 1.0);
        return vec4<f32>(max(at_mean - slope * m, vec3<f32>(0.0)), 1.0 - slope);
    }
    return vec4<f32>(to_target(add), 0.0);
}

// g(d) of `flash_blend`: the HDR path's sum of the flash's exposed radiance `flash` over a pixel
// showing display value `d`, tone-mapped.
fn flashed(d: vec3<f32>, flash: vec3<f32>) -> vec3<f32> {
    return display_from_exposed(exposed_from_display(d) + flash, frame_tone_mapper());
}

// The flash: its colour over the whole sky (`flash_blend`, from the vertices). Its own pipeline,
// so that no sprite shape is evaluated over the screen (a SIMD rasteriser runs every branch of
// fs_main).
@fragment
fn fs_flash(in: ParticleOut) -> @location(0) vec4<f32> {
    return in.color;
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
