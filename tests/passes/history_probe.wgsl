// Test pass of the compute phase (tests/history.rs): each frame, its history's texels become the
// last frame's plus one (x), and say where they are (y: the column).
@group(1) @binding(0) var previous: texture_2d<f32>;
@group(1) @binding(1) var current: texture_storage_2d<rgba16float, write>;
// x: 1 on the history's first frame, when `previous` holds nothing.
@group(1) @binding(2) var<uniform> first: vec4<f32>;

@compute @workgroup_size(8, 8)
fn cs_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(current);
    if (gid.x >= size.x || gid.y >= size.y) {
        return;
    }
    var count = 0.0;
    if (first.x < 0.5) {
        count = textureLoad(previous, vec2<i32>(gid.xy), 0).x;
    }
    textureStore(current, vec2<i32>(gid.xy), vec4<f32>(count + 1.0, f32(gid.x), 0.0, 1.0));
}
