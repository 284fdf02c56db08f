//! requires: sky_model/tone
// Sun glare: the occlusion-tested solar disc (no colour output) and the additive halo and
// lens-flare sprites. (globals.wgsl is prepended by the loader.)

// Keep in sync with `DiscUniform` in src/render/passes/glare.rs.
struct Disc {
    // Columns: right x half size, up x half size, towards_sun.
    sky_from_disc: mat4x4<f32>,
};
@group(1) @binding(0) var<uniform> disc: Disc;

@vertex
fn vs_disc(@location(0) corner: vec2<f32>) -> @builtin(position) vec4<f32> {
    let dir = (disc.sky_from_disc * vec4<f32>(corner, 1.0, 0.0)).xyz;
    var clip = globals.clip_from_sky * vec4<f32>(dir, 1.0);
    clip.z = clip.w * 0.5;
    return clip;
}

@fragment
fn fs_disc() -> @location(0) vec4<f32> {
    return vec4<f32>(0.0);
}

@group(1) @binding(1) var sprite_texture: texture_2d<f32>;
@group(1) @binding(2) var sprite_sampler: sampler;

struct SpriteOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
    @location(1) color: vec4<f32>,
};

// One sprite per instance: centre and half size in NDC, rotation in radians, colour.
@vertex
fn vs_sprite(
    @builtin(vertex_index) vi: u32,
    @location(0) centre_ndc: vec2<f32>,
    @location(1) half_size_ndc: vec2<f32>,
    @location(2) rotation: f32,
    @location(3) color: vec4<f32>,
) -> SpriteOut {
    var corners = array<vec2<f32>, 4>(vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, -1.0), vec2<f32>(-1.0, 1.0), vec2<f32>(1.0, 1.0));
    let c = corners[vi];
    let r = vec2<f32>(c.x * cos(rotation) - c.y * sin(rotation), c.x * sin(rotation) + c.y * cos(rotation));
    var out: SpriteOut;
    out.clip = vec4<f32>(centre_ndc + r * half_size_ndc, 0.0, 1.0);
    out.uv = c * vec2<f32>(0.5, -0.5) + vec2<f32>(0.5);
    out.color = color;
    return out;
}

@fragment
fn fs_sprite(in: SpriteOut) -> @location(0) vec4<f32> {
    let c = textureSample(sprite_texture, sprite_sampler, in.uv) * in.color;
    // Additive with the source alpha as factor: premultiplied here (the same sum on the display
    // target), so that on the HDR target the glare adds what it adds on a dark display.
    return vec4<f32>(to_target(c.rgb * c.a), 1.0);
}
