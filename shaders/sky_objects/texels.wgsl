//! requires: sky_objects/material, sky_objects/placement
// A sparse stage drawn texel by texel (src/render/sky_objects/texel_quads.rs): the stage these polygons stand
// for, in a term of its own that the specialising constants describe.
override TEXEL_STAGE: u32 = 0u;

// Keep in sync with `TexelVertex` in src/render/sky_objects/texel_quads.rs.
struct TexelOut {
    @builtin(position) clip: vec4<f32>,
    // Texels from the texel's centre, interpolated as the grid triangle under the polygon
    // interpolates texture coordinates.
    @location(0) offset: vec2<f32>,
    @location(1) @interpolate(flat) texel: vec4<f32>,
};

@vertex
fn vs_texels(@location(0) position: vec3<f32>, @location(1) offset: vec2<f32>, @location(2) texel: vec4<f32>) -> TexelOut {
    // Placed as it is: under a layer's coordinates per vertex the polygons were built on the
    // grid already moved onto the layer (src/render/sky_objects/upload.rs, `grid_on_layer`).
    var out: TexelOut;
    out.clip = sky_clip((draw.object_from_local * vec4<f32>(position, 0.0)).xyz);
    out.offset = offset;
    out.texel = texel;
    return out;
}

// The texel times its bilinear weight here, as the stage's term (its constant and the diffuse
// colour) on the display target, under the background's runs (`BACKGROUND` 2: times their
// transmittance). Added by the blend: the polygons of neighbouring texels sum to the sample.
@fragment
fn fs_texels(in: TexelOut) -> @location(0) vec4<f32> {
    let weight = max(1.0 - abs(in.offset.x), 0.0) * max(1.0 - abs(in.offset.y), 0.0);
    var c = in.texel * weight;
    let k = stage_constant(LAYER_OWN, draw, TEXEL_STAGE);
    if k < 4u { c = c * draw.constants[k]; }
    var rgb = to_target((c * draw.diffuse).rgb);
    if BACKGROUND == 2u {
        rgb = rgb * run_at(in.clip.xy).a;
    }
    return vec4<f32>(rgb, 0.0);
}
