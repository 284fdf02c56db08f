//! requires: reduced/run, sky_model/tone
// Where a draw goes on the frame, as its pipeline sees it (`Slot` in
// src/render/sky_objects/variants.rs): the switches of a `Placement` and what each does to
// the draw's colour against the run buffers (group 2).

// Drawn after the composite of the run above it (src/render/sky_objects/variants.rs, `UNDER_RUN_BLENDS`),
// with its blend (0 opaque, 1 alpha, 2 additive weighted by alpha, 3 additive).
override UNDER_RUN: bool = false;
override BLEND_KIND: u32 = 0u;
// An additive draw that spans the frame drawn as the frame's background, first onto it
// (src/render/frame/pass.rs, `Placement::Background`): it writes the background run's colour plus
// its own term, neither blended nor depth-tested, in place of the background's composite. 0: not;
// 1: the background is one run, which lies under the draw; 2: it is the joined runs' combination,
// whose transmittance (the runs above the draw) weighs the term.
override BACKGROUND: u32 = 0u;
// The first layer of a seeded reduced buffer drawn over the lower run itself (group 2), replacing
// the buffer's clear colour, unblended (src/render/frame/pass.rs, `Placement::OverSeed`).
override OVER_SEED: bool = false;

// What the layer's blend into a reduced buffer (`REDUCED_BLENDS` in src/render/passes/reduced_layers.rs)
// would leave over the seed, the lower run's colour with transmittance 1: premultiplied colour
// and the transmittance left.
fn over_seed(color: vec4<f32>, pixel: vec2<f32>) -> vec4<f32> {
    let seed = run_at_seeded(pixel).rgb;
    switch BLEND_KIND {
        case 0u: { return vec4<f32>(color.rgb, 0.0); }
        case 1u: { return vec4<f32>(color.a * color.rgb + (1.0 - color.a) * seed, 1.0 - color.a); }
        default: { return vec4<f32>(seed + color.a * color.rgb, 1.0); }
    }
}

// The first layer of a seeded buffer on a display-referred physical frame (`OVER_SEED` with
// `OVER_MODEL_SKY`): the lower run is what lies under the layer, so the layer's exposed radiance
// `over` (premultiplied by its coverage) is added to the lower run's radiance `seed`
// (`run_radiance_at_seeded`), weighed by the transmittance `through`, and tone-mapped, as the HDR
// path's blend would leave it there (exact over whatever the lower run holds, not only over the
// model's sky: no sample of the map, no matching of the colour to it). Written with the
// transmittance left.
fn over_seed_in_radiance(over: vec3<f32>, through: f32, seed: vec3<f32>) -> vec4<f32> {
    return vec4<f32>(display_from_exposed(over + through * seed, frame_tone_mapper()), through);
}

// What an additive draw writes as the frame's background (`BACKGROUND`): the run's colour C plus
// the draw's term, times the transmittance T of the runs above it when joined; the frame's alpha
// is 1 as the background composite's. The same sum as the draw added to the cleared frame and the
// background composited over it (C + T x target).
fn as_background(color: vec4<f32>, pixel: vec2<f32>) -> vec4<f32> {
    let run = run_at(pixel);
    var term = color.rgb;
    if BLEND_KIND == 2u {
        term = color.a * color.rgb;
    }
    var t = 1.0;
    if BACKGROUND == 2u {
        t = run.a;
    }
    return vec4<f32>(run.rgb + t * term, 1.0);
}

// What a draw writes after the run above it is already in the frame, so that the frame ends as
// C + T x (this draw over what was there), with the run's colour C and transmittance T here.
fn under_run(color: vec4<f32>, pixel: vec2<f32>) -> vec4<f32> {
    // Additive draws read only the transmittance, which a seeded buffer holds as it is.
    var run: vec4<f32>;
    if BLEND_KIND <= 1u {
        run = run_alone_at(pixel);
    } else {
        run = run_at(pixel);
    }
    switch BLEND_KIND {
        case 0u: { return vec4<f32>(run.rgb + run.a * color.rgb, color.a); }
        case 1u: { return vec4<f32>(color.a * (run.a * color.rgb + run.rgb), color.a); }
        case 2u: { return vec4<f32>(run.a * color.a * color.rgb, color.a); }
        default: { return vec4<f32>(run.a * color.rgb, color.a); }
    }
}
