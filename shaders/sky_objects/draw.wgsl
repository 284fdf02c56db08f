// What one sky-object draw binds and what its vertices carry: the material's uniform and
// textures (group 1), the upper layer of a pair (group 3), the stages' mappings, and the vertex
// of the draw's shape shared by every entry point.

// Keep in sync with `StageUniform` in src/render/sky_objects/material.rs.
struct Stage {
    scale_offset: vec4<f32>, // uv scale (xy) and offset (zw), repeats
    params: vec4<f32>,       // sun: size_rad; quake: z_scale, z_offset, t_scale, time_scale; layer: height, radius (repeats), sin(fade elevation)
    cfg: vec4<u32>,          // op (0 add, 1 modulate), uv mode (4: white, folded into the stage before), constant index (4 = none), live (0: its term is black this frame, not sampled)
};

// Keep in sync with `DrawUniform` in src/render/sky_objects/material.rs.
struct Draw {
    // Columns: right * half size, up * half size, centre direction (quads); identity for domes.
    object_from_local: mat4x4<f32>,
    diffuse: vec4<f32>,
    constants: array<vec4<f32>, 4>,
    stages: array<Stage, 4>,
    misc: vec4<u32>,         // stage count, lighting (0 flat, 1 moon, 2 cloud), stage fed by the sky-view map (4 = none), cloud density (f32 bits)
};

@group(1) @binding(0) var<uniform> draw: Draw;
@group(1) @binding(1) var tex0: texture_2d<f32>;
@group(1) @binding(2) var tex1: texture_2d<f32>;
@group(1) @binding(3) var tex2: texture_2d<f32>;
@group(1) @binding(4) var tex3: texture_2d<f32>;
@group(1) @binding(5) var samp0: sampler;
@group(1) @binding(6) var samp1: sampler;
@group(1) @binding(7) var samp2: sampler;
@group(1) @binding(8) var samp3: sampler;
// A physical sky model's colour by direction (sky_view.wgsl), replacing the gradient stage.
@group(1) @binding(9) var sky_view: texture_2d<f32>;
@group(1) @binding(10) var sky_view_sampler: sampler;
// The upper layer of a pair drawn at once (`fs_pair`): the same bindings as group 1's, of the
// layer drawn over it.
@group(3) @binding(0) var<uniform> upper: Draw;
@group(3) @binding(1) var upper_tex0: texture_2d<f32>;
@group(3) @binding(2) var upper_tex1: texture_2d<f32>;
@group(3) @binding(3) var upper_tex2: texture_2d<f32>;
@group(3) @binding(4) var upper_tex3: texture_2d<f32>;
@group(3) @binding(5) var upper_samp0: sampler;
@group(3) @binding(6) var upper_samp1: sampler;
@group(3) @binding(7) var upper_samp2: sampler;
@group(3) @binding(8) var upper_samp3: sampler;
@group(3) @binding(9) var upper_sky_view: texture_2d<f32>;
@group(3) @binding(10) var upper_sky_view_sampler: sampler;

const UV_MESH: u32 = 0u;
const UV_SUN: u32 = 1u;
const UV_CELESTIAL: u32 = 2u;
const UV_QUAKE: u32 = 3u;
// A stage folded into the one before it at load (src/render/sky_objects/stage_fold.rs): white, not sampled.
// Keep in sync with `UV_WHITE` in src/render/sky_objects/material.rs.
const UV_WHITE: u32 = 4u;
// The celestial mapping where no pixel of the draw minifies its texture this frame (a variant
// only, set by src/render/sky_objects/): level 0, without the derivatives below. Keep in sync
// with `UV_CELESTIAL_LEVEL0` in src/render/sky_objects/material.rs.
const UV_CELESTIAL_LEVEL0: u32 = 5u;
// A cloud layer's point seen along the view direction (`layer_uv`). Keep in sync with `UV_LAYER`
// in src/render/sky_objects/material.rs.
const UV_LAYER: u32 = 6u;
// The cloud-layer mapping computed per vertex of the dome's grid, the grid moved onto the layer
// (a variant only, `LayerCoordinates::PerVertex`). Keep in sync with `UV_LAYER_VERTEX` in
// src/render/sky_objects/material.rs.
const UV_LAYER_VERTEX: u32 = 7u;

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
    @location(1) world_dir: vec3<f32>,
    // Each stage's texture coordinates under the mesh mapping (stages 0 and 1, then 2 and 3):
    // affine in the mesh's, so exact per vertex; or a cloud layer's per vertex (`sky_vertex`).
    // Interpolated inputs sampled as they are cost lavapipe much less than coordinates computed
    // per pixel (it takes their derivatives from the triangle's setup instead of differencing
    // across pixels): about 2 ms per full-screen layer of two stages at 1280x720.
    @location(2) mesh_uv01: vec4<f32>,
    @location(3) mesh_uv23: vec4<f32>,
};

// Stage `i` of draw `d`: its scale and offset applied to texture coordinates `uv`.
fn scaled(d: Draw, i: u32, uv: vec2<f32>) -> vec2<f32> {
    let so = d.stages[i].scale_offset;
    return uv * so.xy + so.zw;
}

// Where sky direction `dir` (any length) lands on the frame.
fn sky_clip(dir: vec3<f32>) -> vec4<f32> {
    var clip = globals.clip_from_sky * vec4<f32>(dir, 1.0);
    // Any depth inside the sky's viewport range works: the sky neither writes nor sorts by depth,
    // it only has to lose against the main scene drawn in [0, 0.95].
    clip.z = clip.w * 0.5;
    return clip;
}

// The first stage whose cloud-layer coordinates are computed per vertex (4: none). Every such
// stage maps the same layer (src/render/sky_objects/upload.rs, `vertex_layer_modes`).
fn vertex_layer_stage(l: u32, d: Draw) -> u32 {
    for (var i = 0u; i < 4u; i++) {
        if uv_mode(l, d, i) == UV_LAYER_VERTEX { return i; }
    }
    return 4u;
}

// Stage `i`'s coordinates at a vertex: the mesh's, or the layer's at `on_layer` (the vertex moved
// onto the layer) under `UV_LAYER_VERTEX`.
fn vertex_uv(l: u32, d: Draw, i: u32, uv: vec2<f32>, on_layer: vec3<f32>) -> vec2<f32> {
    if uv_mode(l, d, i) == UV_LAYER_VERTEX { return scaled(d, i, on_layer.xz); }
    return scaled(d, i, uv);
}

// A vertex of the draw's shape, for `vs_main` and `vs_pair`. With cloud-layer coordinates per
// vertex, the vertex moves along its ray onto the layer: the same ray, so the same pixels, but the
// rasteriser's perspective-correct interpolation then runs over chords of the layer, on which its
// coordinates are the points' own horizontal ones (exact for a flat layer, off by the chords' sag
// for a curved one). The interpolated direction stays on the view ray.
fn sky_vertex(position: vec3<f32>, uv: vec2<f32>) -> VertexOut {
    var dir = (draw.object_from_local * vec4<f32>(position, 0.0)).xyz;
    let k = vertex_layer_stage(LAYER_OWN, draw);
    if k < 4u {
        let unit = normalize(dir);
        dir = unit * layer_distance(draw.stages[k].params, unit);
    }
    var out: VertexOut;
    out.clip = sky_clip(dir);
    out.uv = uv;
    out.world_dir = dir;
    out.mesh_uv01 = vec4<f32>(vertex_uv(LAYER_OWN, draw, 0u, uv, dir), vertex_uv(LAYER_OWN, draw, 1u, uv, dir));
    out.mesh_uv23 = vec4<f32>(vertex_uv(LAYER_OWN, draw, 2u, uv, dir), vertex_uv(LAYER_OWN, draw, 3u, uv, dir));
    return out;
}
