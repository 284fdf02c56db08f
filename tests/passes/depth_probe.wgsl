// Test pass of the compute phase (tests/depth.rs): samples the renderer's scene depth, which holds
// the last frame's scene, at eight pixels and writes what globals.wgsl makes of it.
@group(1) @binding(0) var scene_depth: texture_depth_2d;
@group(1) @binding(1) var<storage, read_write> probe: array<vec4<f32>, 9>;

// The probed pixels, as fractions of the frame (below the horizon of a camera pitched down).
const PROBED: array<vec2<f32>, 8> = array<vec2<f32>, 8>(
    vec2<f32>(0.5, 0.6), vec2<f32>(0.5, 0.7), vec2<f32>(0.5, 0.8), vec2<f32>(0.5, 0.95),
    vec2<f32>(0.2, 0.75), vec2<f32>(0.8, 0.75), vec2<f32>(0.05, 0.9), vec2<f32>(0.95, 0.9),
);

@compute @workgroup_size(8)
fn cs_main(@builtin(local_invocation_index) i: u32) {
    let pixel = floor(PROBED[i] * globals.viewport.xy);
    let stored = textureLoad(scene_depth, vec2<u32>(pixel), 0);
    let centre = pixel + 0.5;
    probe[i] = vec4<f32>(scene_distance_m(stored, centre), stored, centre);
    if (i == 0u) {
        probe[8] = globals.previous_clip_from_world[3];
    }
}
