//! requires: reduced/run, sky_model/tone
// Composite of a run of dome layers drawn at reduced resolution (src/render/passes/reduced_layers.rs).
// The run's buffer holds premultiplied colour and, in alpha, the transmittance of the run over
// what lies behind it; upsampled bilinearly, it goes over the frame as target = colour +
// transmittance * target (the pipeline's blend), depth-tested against the main scene like the
// layers themselves. (globals.wgsl is prepended by the loader.)

@group(1) @binding(1) var layers: texture_2d<f32>;
@group(1) @binding(2) var layers_sampler: sampler;

struct CompositeOut {
    @builtin(position) clip: vec4<f32>,
    // Texture coordinates of the whole frame (every buffer holds it), sampled as interpolated at
    // level 0: no arithmetic per pixel and no derivatives (lavapipe differences those of
    // coordinates computed per pixel, see sky_objects.wgsl).
    @location(0) uv: vec2<f32>,
};

@vertex
fn vs_main(@builtin(vertex_index) vi: u32) -> CompositeOut {
    let p = vec2<f32>(f32((vi << 1u) & 2u), f32(vi & 2u));
    var out: CompositeOut;
    // Inside the sky's depth range, as the layers' own draws.
    out.clip = vec4<f32>(p * 2.0 - vec2<f32>(1.0), 0.5, 1.0);
    out.uv = vec2<f32>(p.x, 1.0 - p.y);
    return out;
}

@fragment
fn fs_main(in: CompositeOut) -> @location(0) vec4<f32> {
    return textureSampleLevel(layers, layers_sampler, in.uv, 0.0);
}

// The first run of a frame as its background (drawn before the scene, over the clear colour,
// black): colour + transmittance x black, the target's alpha (1) kept.
@fragment
fn fs_background(in: CompositeOut) -> @location(0) vec4<f32> {
    return vec4<f32>(textureSampleLevel(layers, layers_sampler, in.uv, 0.0).rgb, 1.0);
}

// The joined runs combined at reduced resolution, the upper (the runs above, combined) over the
// lower, so that the background samples one buffer instead of one per run at every frame pixel.
// The lower run is the background (over black): what it lets through does not matter; alpha
// keeps the upper's transmittance, for what lies between them and is drawn before them (`fs_main`
// over it).
@fragment
fn fs_combine(in: CompositeOut) -> @location(0) vec4<f32> {
    let lower = textureSampleLevel(layers, layers_sampler, in.uv, 0.0);
    let upper = textureSampleLevel(run_layers, run_sampler, in.uv, 0.0);
    return vec4<f32>(upper.rgb + upper.a * lower.rgb, upper.a);
}

// A combination above the background's (a third joined run and up): what draws between the runs
// below it go under, so its transmittance is both runs'.
@fragment
fn fs_combine_above(in: CompositeOut) -> @location(0) vec4<f32> {
    let lower = textureSampleLevel(layers, layers_sampler, in.uv, 0.0);
    let upper = textureSampleLevel(run_layers, run_sampler, in.uv, 0.0);
    return vec4<f32>(upper.rgb + upper.a * lower.rgb, upper.a * lower.a);
}

// The lower run of a seeded frame taken back to exposed radiance texel by texel, at its own
// resolution, on a display-referred physical frame (`ReducedLayersPass::convert_seed`): what the
// seeded buffer's first layer blends over in radiance (`over_seed_in_radiance`). One inverse curve
// per texel of the lower run's buffer instead of one per pixel of the layer's finer one.
@fragment
fn fs_seed_radiance(in: CompositeOut) -> @location(0) vec4<f32> {
    let c = textureLoad(layers, vec2<i32>(in.clip.xy), 0);
    return vec4<f32>(exposed_from_display(c.rgb), c.a);
}
