//! requires: reduced/run
// Composite of a run of dome layers drawn at reduced resolution (src/render/reduced_layers.rs).
// The run's buffer holds premultiplied colour and, in alpha, the transmittance of the run over
// what lies behind it; upsampled bilinearly, it goes over the frame as target = colour +
// transmittance * target (the pipeline's blend), depth-tested against the main scene like the
// layers themselves. (globals.wgsl is prepended by the loader.)

@group(1) @binding(0) var<uniform> composite: Composite;
@group(1) @binding(1) var layers: texture_2d<f32>;
@group(1) @binding(2) var layers_sampler: sampler;

@vertex
fn vs_main(@builtin(vertex_index) vi: u32) -> @builtin(position) vec4<f32> {
    let p = vec2<f32>(f32((vi << 1u) & 2u), f32(vi & 2u));
    // Inside the sky's depth range, as the layers' own draws.
    return vec4<f32>(p * 2.0 - vec2<f32>(1.0), 0.5, 1.0);
}

@fragment
fn fs_main(@builtin(position) pixel: vec4<f32>) -> @location(0) vec4<f32> {
    return textureSample(layers, layers_sampler, pixel.xy * composite.uv_from_pixel.xy);
}

// The first run of a frame as its background (drawn before the scene, over the clear colour,
// black): colour + transmittance x black, the target's alpha (1) kept.
@fragment
fn fs_background(@builtin(position) pixel: vec4<f32>) -> @location(0) vec4<f32> {
    return vec4<f32>(textureSample(layers, layers_sampler, pixel.xy * composite.uv_from_pixel.xy).rgb, 1.0);
}

// Two runs at once as the background: the upper (group 2, reduced/run.wgsl) over the lower
// (group 1), over black. Only the pair's pipeline layout has group 2.
@fragment
fn fs_pair_background(@builtin(position) pixel: vec4<f32>) -> @location(0) vec4<f32> {
    let lower = textureSample(layers, layers_sampler, pixel.xy * composite.uv_from_pixel.xy);
    let upper = run_at(pixel.xy);
    return vec4<f32>(upper.rgb + upper.a * lower.rgb, 1.0);
}
