// Fill-rate floor of `skytune bench frame`: one full-screen triangle sampling one 128 x 128
// texture. What a frame of the same size costs at the least on this adapter. (globals.wgsl is
// prepended by the loader; bind group 0 is unused here.)

@group(1) @binding(0) var floor_texture: texture_2d<f32>;
@group(1) @binding(1) var floor_sampler: sampler;

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
};

@vertex
fn vs_main(@builtin(vertex_index) vi: u32) -> VertexOut {
    let uv = vec2<f32>(f32((vi << 1u) & 2u), f32(vi & 2u));
    var out: VertexOut;
    out.clip = vec4<f32>(uv * 2.0 - vec2<f32>(1.0), 0.0, 1.0);
    // Several repeats of the texture over the screen, as a sky layer would.
    out.uv = uv * 4.0;
    return out;
}

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    return textureSample(floor_texture, floor_sampler, in.uv);
}
