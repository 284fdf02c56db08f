// A run of dome layers in its reduced buffer, read by full-resolution draws as bind group 2: the
// combination of two joined runs (reduced_layers.wgsl) and draws moved after a run's composite
// (sky objects, stars, dome particles: `Pass::draw_under_run`). Premultiplied colour and, in
// alpha, the run's transmittance. Bindings as `run_layout` in src/render/reduced_layers.rs.

// Keep in sync with `CompositeUniform` in src/render/reduced_layers.rs.
struct Composite {
    // Frame pixel to texture coordinates (1 / frame size): every buffer holds the whole frame.
    uv_from_pixel: vec4<f32>,
};

@group(2) @binding(0) var<uniform> run_composite: Composite;
@group(2) @binding(1) var run_layers: texture_2d<f32>;
@group(2) @binding(2) var run_sampler: sampler;

// The run at frame pixel `pixel` (a fragment's position), upsampled bilinearly.
fn run_at(pixel: vec2<f32>) -> vec4<f32> {
    return textureSampleLevel(run_layers, run_sampler, pixel * run_composite.uv_from_pixel.xy, 0.0);
}
