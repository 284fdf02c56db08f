// The sky-view pass's shown map (src/render/atmosphere/sky_view.rs): the older and the newer finished
// maps (exposed linear radiance per texel) blended by the newer's weight, as the rgba16float texels
// copied into the sky-view texture. While the sun moves with the map spread over frames
// (src/render/plan/map_updates.rs) the weight rises frame by frame, so the sky moves smoothly;
// otherwise it is 1 and the newer map is shown as it is.
// Keep `BlendParams` in sync with src/render/atmosphere/sky_view.rs.
struct BlendParams {
    settings: vec4<f32>, // x: weight of the newer map, y: texels
};

@group(1) @binding(0) var<storage, read> older: array<vec4<f32>>;
@group(1) @binding(1) var<storage, read> newer: array<vec4<f32>>;
// Texels as rgba16float (two u32 each), copied into the sky-view texture after the phase, so the
// compute work only writes buffers (as radiance_probe.wgsl does).
@group(1) @binding(2) var<storage, read_write> shown: array<u32>;
@group(1) @binding(3) var<uniform> blend: BlendParams;

// IEEE half-precision bits of a value in [0, 65504], rounded to nearest. (pack2x16float needs a
// shader capability that not every adapter has; this needs none.)
fn half_bits(x: f32) -> u32 {
    if (x < 6.103515625e-5) {
        // Subnormal halves: multiples of 2^-24.
        return u32(round(x * 16777216.0));
    }
    let b = bitcast<u32>(x);
    // Rebias the exponent (127 -> 15) and keep 10 mantissa bits; the rounding carry may step the
    // exponent up, which is the correctly rounded result.
    return ((b - (112u << 23u)) + 0x1000u) >> 13u;
}

@compute @workgroup_size(64)
fn cs_blend(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (gid.x >= u32(blend.settings.y)) {
        return;
    }
    let w = blend.settings.x;
    // Exactly the newer map at weight 1 (older x 0 + newer x 1).
    let c = older[gid.x].rgb * (1.0 - w) + newer[gid.x].rgb * w;
    shown[2u * gid.x] = half_bits(c.r) | (half_bits(c.g) << 16u);
    shown[2u * gid.x + 1u] = half_bits(c.b) | (half_bits(1.0) << 16u);
}
