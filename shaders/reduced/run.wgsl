// A run of dome layers in its reduced buffer, read by full-resolution draws as bind group 2: the
// combination of two joined runs (reduced_layers.wgsl) and draws moved after a run's composite
// (sky objects, stars, dome particles: `Placement::UnderRun`). Premultiplied colour and, in
// alpha, the run's transmittance. Bindings as `run_layout` in src/render/passes/reduced_layers.rs.

// Keep in sync with `CompositeUniform` in src/render/passes/reduced_layers.rs.
struct Composite {
    // Pixel to texture coordinates (every buffer holds the whole frame): xy of a frame pixel
    // (1 / frame size), zw of a pixel of the seeded buffer (1 / its size).
    uv_from_pixel: vec4<f32>,
};

@group(2) @binding(0) var<uniform> run_composite: Composite;
@group(2) @binding(1) var run_layers: texture_2d<f32>;
@group(2) @binding(2) var run_sampler: sampler;
// The run below, where this run's buffer was seeded with it (then the buffer holds both runs'
// combination, ReducedLayersPass::seed in src/render/passes/reduced_layers.rs); else black.
@group(2) @binding(3) var run_lower: texture_2d<f32>;

// The run at frame pixel `pixel` (a fragment's position), upsampled bilinearly.
fn run_at(pixel: vec2<f32>) -> vec4<f32> {
    return textureSampleLevel(run_layers, run_sampler, pixel * run_composite.uv_from_pixel.xy, 0.0);
}

// The run at pixel `pixel` of the buffer it seeds (a fragment's position there).
fn run_at_seeded(pixel: vec2<f32>) -> vec4<f32> {
    return textureSampleLevel(run_layers, run_sampler, pixel * run_composite.uv_from_pixel.zw, 0.0);
}

// The run's exposed radiance at pixel `pixel` of the buffer it seeds, on a display-referred
// physical frame: its colour taken back to radiance once, at its own resolution
// (`ReducedLayersPass::convert_seed`), and bound as `run_lower` of the seed's bind group.
fn run_radiance_at_seeded(pixel: vec2<f32>) -> vec3<f32> {
    return textureSampleLevel(run_lower, run_sampler, pixel * run_composite.uv_from_pixel.zw, 0.0).rgb;
}

// The run alone at frame pixel `pixel`, for draws that lie under it and read its colour: a seeded
// buffer holds C + T x (the run below), which this takes off again (nothing where not seeded).
fn run_alone_at(pixel: vec2<f32>) -> vec4<f32> {
    let uv = pixel * run_composite.uv_from_pixel.xy;
    let run = textureSampleLevel(run_layers, run_sampler, uv, 0.0);
    let lower = textureSampleLevel(run_lower, run_sampler, uv, 0.0).rgb;
    return vec4<f32>(max(run.rgb - run.a * lower, vec3<f32>(0.0)), run.a);
}
