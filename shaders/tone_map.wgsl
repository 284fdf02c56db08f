//! requires: sky_model/tone
// Display phase: the frame's HDR target (exposed linear radiance, and display-referred colours
// decoded to linear) through the sky model's tone mapper and sRGB encoding into the display
// target. One full-screen triangle. (globals.wgsl is prepended by the loader.)

// Keep in sync with `ToneMapUniform` in src/render/passes/tone_map.rs.
struct ToneMapParams {
    settings: vec4<u32>, // x: tone mapper (0 ACES fitted, 1 Khronos PBR Neutral)
};
@group(1) @binding(0) var<uniform> params: ToneMapParams;
@group(1) @binding(1) var hdr: texture_2d<f32>;

@vertex
fn vs_main(@builtin(vertex_index) vi: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((vi << 1u) & 2u), f32(vi & 2u));
    return vec4<f32>(uv * 2.0 - vec2<f32>(1.0), 0.0, 1.0);
}

@fragment
fn fs_main(@builtin(position) pixel: vec4<f32>) -> @location(0) vec4<f32> {
    let exposed = textureLoad(hdr, vec2<i32>(pixel.xy), 0).rgb;
    return vec4<f32>(display_from_exposed(exposed, params.settings.x), 1.0);
}
