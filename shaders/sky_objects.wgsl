//! requires: sky_model/sky_view_map, sky_model/tone, reduced/run
// Sky objects: procedural shapes with a NeL-style material of up to 4 texture stages.
// The material is a sum of terms: an `add` stage starts a term (texture x constant), a
// `modulate` stage multiplies the current term; the result times the diffuse colour.
//
// (globals.wgsl is prepended by the loader.)

// Keep in sync with `StageUniform` in src/render/sky_objects/material.rs.
struct Stage {
    scale_offset: vec4<f32>, // uv scale (xy) and offset (zw), repeats
    params: vec4<f32>,       // sun: size_rad; quake: z_scale, z_offset, t_scale, time_scale
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

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
    @location(1) world_dir: vec3<f32>,
    // Each stage's texture coordinates under the mesh mapping (stages 0 and 1, then 2 and 3):
    // affine in the mesh's, so exact per vertex. Interpolated inputs sampled as they are cost
    // lavapipe much less than coordinates computed per pixel (it takes their derivatives from
    // the triangle's setup instead of differencing across pixels): about 2 ms per full-screen
    // layer of two stages at 1280x720.
    @location(2) mesh_uv01: vec4<f32>,
    @location(3) mesh_uv23: vec4<f32>,
};

// Stage `i` of draw `d`: its scale and offset applied to texture coordinates `uv`.
fn scaled(d: Draw, i: u32, uv: vec2<f32>) -> vec2<f32> {
    let so = d.stages[i].scale_offset;
    return uv * so.xy + so.zw;
}

// A vertex of the draw's shape, for `vs_main` and `vs_pair`.
fn sky_vertex(position: vec3<f32>, uv: vec2<f32>) -> VertexOut {
    let dir = (draw.object_from_local * vec4<f32>(position, 0.0)).xyz;
    var clip = globals.clip_from_sky * vec4<f32>(dir, 1.0);
    // Any depth inside the sky's viewport range works: the sky neither writes nor sorts by depth,
    // it only has to lose against the main scene drawn in [0, 0.95].
    clip.z = clip.w * 0.5;
    var out: VertexOut;
    out.clip = clip;
    out.uv = uv;
    out.world_dir = dir;
    out.mesh_uv01 = vec4<f32>(scaled(draw, 0u, uv), scaled(draw, 1u, uv));
    out.mesh_uv23 = vec4<f32>(scaled(draw, 2u, uv), scaled(draw, 3u, uv));
    return out;
}

@vertex
fn vs_main(@location(0) position: vec3<f32>, @location(1) uv: vec2<f32>) -> VertexOut {
    return sky_vertex(position, uv);
}

// One triangle over the frame, for a draw that maps nothing from its shape (the background
// where its sparse stage is drawn texel by texel: the runs' colour at the pixel), scissored to
// where the shape covers the frame. No vertex buffer; nothing but the position is meant to be read.
@vertex
fn vs_fullscreen(@builtin(vertex_index) vi: u32) -> VertexOut {
    let p = vec2<f32>(f32((vi << 1u) & 2u), f32(vi & 2u));
    var out: VertexOut;
    // Inside the sky's depth range, as `sky_vertex`.
    out.clip = vec4<f32>(p * 2.0 - vec2<f32>(1.0), 0.5, 1.0);
    out.uv = vec2<f32>(0.0);
    out.world_dir = vec3<f32>(0.0, 1.0, 0.0);
    out.mesh_uv01 = vec4<f32>(0.0);
    out.mesh_uv23 = vec4<f32>(0.0);
    return out;
}

// Specialisation: a pipeline per material signature sets SPECIALISED and the constants below from
// the draw's uniform (src/render/sky_objects/variants.rs, `VariantKey`), so the compiler drops what the draw
// does not use. This matters on SIMD rasterisers such as lavapipe, which run both sides of every
// branch (a uniform condition included) under a lane mask and sample textures even in lanes that
// are off: every branch left on a uniform costs as if taken. The generic pipeline keeps the
// defaults and reads everything from the uniform.
override SPECIALISED: bool = false;
override STAGE_COUNT: u32 = 4u;
override UV_MODE_0: u32 = 0u;
override UV_MODE_1: u32 = 0u;
override UV_MODE_2: u32 = 0u;
override UV_MODE_3: u32 = 0u;
// Stage op (0 add, 1 modulate), constant index (4: none), live (0: its term is black this frame).
override OP_0: u32 = 0u;
override OP_1: u32 = 0u;
override OP_2: u32 = 0u;
override OP_3: u32 = 0u;
override CONSTANT_0: u32 = 4u;
override CONSTANT_1: u32 = 4u;
override CONSTANT_2: u32 = 4u;
override CONSTANT_3: u32 = 4u;
override LIVE_0: bool = true;
override LIVE_1: bool = true;
override LIVE_2: bool = true;
override LIVE_3: bool = true;
// The stage the sky-view map feeds (4: none) and the lighting (0 flat, 1 moon, 2 cloud). What
// the target holds comes with TARGET_KIND and TONE_KIND (tone.wgsl).
override VIEW_STAGE: u32 = 4u;
override LIGHTING: u32 = 0u;
// Drawn after the composite of the run above it (src/render/sky_objects/variants.rs, `UNDER_RUN_BLENDS`),
// with its blend (0 opaque, 1 alpha, 2 additive weighted by alpha, 3 additive).
override UNDER_RUN: bool = false;
override BLEND_KIND: u32 = 0u;
// An additive draw that spans the frame drawn as the frame's background, first onto it
// (src/render/frame/pass.rs, `Placement::Background`): it writes the background run's colour plus
// its own term, neither blended nor depth-tested, in place of the background's composite. 0: not;
// 1: the background is one run, which lies under the draw; 2: it is the joined runs' combination,
// whose transmittance (the runs above the draw) weighs the term.
override BACKGROUND: u32 = 0u;
// The first layer of a seeded reduced buffer drawn over the lower run itself (group 2), replacing
// the buffer's clear colour, unblended (src/render/frame/pass.rs, `Placement::OverSeed`).
override OVER_SEED: bool = false;
// The upper layer of a pair (`fs_pair`, group 3), specialised as the draw's own constants above.
override UPPER_STAGE_COUNT: u32 = 0u;
override UPPER_UV_MODE_0: u32 = 0u;
override UPPER_UV_MODE_1: u32 = 0u;
override UPPER_UV_MODE_2: u32 = 0u;
override UPPER_UV_MODE_3: u32 = 0u;
override UPPER_OP_0: u32 = 0u;
override UPPER_OP_1: u32 = 0u;
override UPPER_OP_2: u32 = 0u;
override UPPER_OP_3: u32 = 0u;
override UPPER_CONSTANT_0: u32 = 4u;
override UPPER_CONSTANT_1: u32 = 4u;
override UPPER_CONSTANT_2: u32 = 4u;
override UPPER_CONSTANT_3: u32 = 4u;
override UPPER_LIVE_0: bool = true;
override UPPER_LIVE_1: bool = true;
override UPPER_LIVE_2: bool = true;
override UPPER_LIVE_3: bool = true;
override UPPER_VIEW_STAGE: u32 = 4u;
override UPPER_LIGHTING: u32 = 0u;

// Layers of a draw: its own (group 1), and the upper one of a pair (group 3). The functions below
// take the layer, constant where they are called, and its uniform: the upper layer is always
// specialised, the draw's own reads its uniform where not.
const LAYER_OWN: u32 = 0u;
const LAYER_UPPER: u32 = 1u;

fn stage_count(l: u32, d: Draw) -> u32 {
    if l == LAYER_UPPER {
        return UPPER_STAGE_COUNT;
    }
    if SPECIALISED {
        return STAGE_COUNT;
    }
    return d.misc.x;
}

// One of four per-stage constants by stage index.
fn pick_u32(i: u32, c: vec4<u32>) -> u32 {
    switch i {
        case 0u: { return c.x; }
        case 1u: { return c.y; }
        case 2u: { return c.z; }
        default: { return c.w; }
    }
}

// One of four per-stage flags by stage index.
fn pick_bool(i: u32, c0: bool, c1: bool, c2: bool, c3: bool) -> bool {
    switch i {
        case 0u: { return c0; }
        case 1u: { return c1; }
        case 2u: { return c2; }
        default: { return c3; }
    }
}

fn uv_mode(l: u32, d: Draw, i: u32) -> u32 {
    if l == LAYER_UPPER {
        return pick_u32(i, vec4<u32>(UPPER_UV_MODE_0, UPPER_UV_MODE_1, UPPER_UV_MODE_2, UPPER_UV_MODE_3));
    }
    if SPECIALISED {
        return pick_u32(i, vec4<u32>(UV_MODE_0, UV_MODE_1, UV_MODE_2, UV_MODE_3));
    }
    return d.stages[i].cfg.y;
}

fn stage_op(l: u32, d: Draw, i: u32) -> u32 {
    if l == LAYER_UPPER {
        return pick_u32(i, vec4<u32>(UPPER_OP_0, UPPER_OP_1, UPPER_OP_2, UPPER_OP_3));
    }
    if SPECIALISED {
        return pick_u32(i, vec4<u32>(OP_0, OP_1, OP_2, OP_3));
    }
    return d.stages[i].cfg.x;
}

fn stage_constant(l: u32, d: Draw, i: u32) -> u32 {
    if l == LAYER_UPPER {
        return pick_u32(i, vec4<u32>(UPPER_CONSTANT_0, UPPER_CONSTANT_1, UPPER_CONSTANT_2, UPPER_CONSTANT_3));
    }
    if SPECIALISED {
        return pick_u32(i, vec4<u32>(CONSTANT_0, CONSTANT_1, CONSTANT_2, CONSTANT_3));
    }
    return d.stages[i].cfg.z;
}

fn stage_live(l: u32, d: Draw, i: u32) -> bool {
    if l == LAYER_UPPER {
        return pick_bool(i, UPPER_LIVE_0, UPPER_LIVE_1, UPPER_LIVE_2, UPPER_LIVE_3);
    }
    if SPECIALISED {
        return pick_bool(i, LIVE_0, LIVE_1, LIVE_2, LIVE_3);
    }
    return d.stages[i].cfg.w != 0u;
}

fn view_stage(l: u32, d: Draw) -> u32 {
    if l == LAYER_UPPER {
        return UPPER_VIEW_STAGE;
    }
    if SPECIALISED {
        return VIEW_STAGE;
    }
    return d.misc.z;
}

fn lighting(l: u32, d: Draw) -> u32 {
    if l == LAYER_UPPER {
        return UPPER_LIGHTING;
    }
    if SPECIALISED {
        return LIGHTING;
    }
    return d.misc.y;
}

// Plate carree coordinates of world direction `dir` in the rotating celestial frame; u wraps
// from 1 to 0 on the frame's meridian behind -z.
fn celestial_uv(dir: vec3<f32>) -> vec2<f32> {
    let c = (globals.celestial_from_world * vec4<f32>(dir, 0.0)).xyz;
    return vec2<f32>(atan2(c.x, -c.z) / (2.0 * PI) + 0.5, 0.5 - asin(clamp(c.y, -1.0, 1.0)) / PI);
}

// Where a layer's fragment lies: the view direction and each stage's texture coordinates under
// the mesh mapping (stages 0 and 1, then 2 and 3), as the vertex shader interpolated them.
struct Place {
    world_dir: vec3<f32>,
    mesh_uv01: vec4<f32>,
    mesh_uv23: vec4<f32>,
};

// Stage `i`'s texture coordinates under its mapping `mode`: the mesh's come from the vertex
// shader, the others from the view direction.
fn stage_uv(d: Draw, i: u32, mode: u32, at: Place) -> vec2<f32> {
    if mode == UV_MESH {
        switch i {
            case 0u: { return at.mesh_uv01.xy; }
            case 1u: { return at.mesh_uv01.zw; }
            case 2u: { return at.mesh_uv23.xy; }
            default: { return at.mesh_uv23.zw; }
        }
    }
    let s = d.stages[i];
    let dir = normalize(at.world_dir);
    var uv = vec2<f32>(0.0);
    if mode == UV_SUN {
        let sun = globals.towards_sun.xyz;
        var right = cross(sun, vec3<f32>(0.0, 1.0, 0.0));
        if length(right) < 1e-4 { right = vec3<f32>(1.0, 0.0, 0.0); }
        right = normalize(right);
        let up = cross(right, sun);
        let t = dir - sun * dot(dir, sun);
        let angle = acos(clamp(dot(dir, sun), -1.0, 1.0));
        let along = vec2<f32>(dot(t, right), dot(t, up));
        let l = max(length(along), 1e-6);
        uv = vec2<f32>(0.5) + along / l * angle / s.params.x;
        return uv;
    } else if mode == UV_CELESTIAL {
        uv = celestial_uv(dir);
    } else if mode == UV_QUAKE {
        var q = dir;
        q.y = q.y * s.params.x + s.params.y;
        let scroll = globals.time.w * s.params.w;
        uv = vec2<f32>(scroll) + q.xz * (s.params.z / max(length(q), 1e-4));
    }
    return scaled(d, i, uv);
}

// Adds one term of the material (display values, times the diffuse colour) to the sum. On the
// display target as they are; on the HDR target through `to_target`, or as a factor of the sky
// model's exposed radiance for the term that holds it.
fn add_term(d: Draw, sum: vec4<f32>, term_display: vec4<f32>, view: vec3<f32>, has_view: bool) -> vec4<f32> {
    let t = term_display * d.diffuse;
    var rgb: vec3<f32>;
    if has_view {
        rgb = view * linear_from_display(t.rgb);
    } else {
        rgb = to_target(t.rgb);
    }
    return vec4<f32>(sum.rgb + rgb, max(sum.a, t.a));
}

// The material's running sum: finished terms plus the open one.
struct Terms {
    sum: vec4<f32>,
    term: vec4<f32>,
    has_term: bool,
    term_has_view: bool,
};

// Folds stage `i` (its sample `c`) into the sum. Called with constant indices: a loop over a
// dynamically indexed array of samples spills to memory on SIMD rasterisers (lavapipe).
fn fold_stage(l: u32, d: Draw, acc_in: Terms, i: u32, c_in: vec4<f32>, view: vec3<f32>) -> Terms {
    var acc = acc_in;
    var c = c_in;
    let k = stage_constant(l, d, i);
    if k < 4u { c = c * d.constants[k]; }
    if stage_op(l, d, i) == 1u {
        acc.term = acc.term * c;
    } else {
        if acc.has_term { acc.sum = add_term(d, acc.sum, acc.term, view, acc.term_has_view); }
        acc.term = c;
        acc.has_term = true;
        acc.term_has_view = false;
    }
    acc.term_has_view = acc.term_has_view || i == view_stage(l, d);
    return acc;
}

// Stage `i`'s sample: not placed nor sampled when its term is black this frame or left to another
// draw of the layer (reads as 0), white when the sky-view map stands in for it.
fn stage_sample(l: u32, d: Draw, i: u32, t: texture_2d<f32>, smp: sampler, at: Place) -> vec4<f32> {
    if !stage_live(l, d, i) { return vec4<f32>(0.0); }
    let mode = uv_mode(l, d, i);
    if view_stage(l, d) == i || mode == UV_WHITE { return vec4<f32>(1.0); }
    if mode == UV_CELESTIAL_LEVEL0 {
        return textureSampleLevel(t, smp, scaled(d, i, celestial_uv(normalize(at.world_dir))), 0.0);
    }
    if mode == UV_CELESTIAL {
        // Differenced across the wrap of u, the derivative spans the whole texture and picks
        // its smallest level: a dashed line of the texture's mean along the meridian. The same
        // coordinates turned by half a turn wrap on the far side; per axis the smaller of the two
        // derivatives is the true one. (Taking u back by a turn in the 2x2 quads that straddle
        // the wrap, for implicit derivatives, left the line on lavapipe.)
        let c = celestial_uv(normalize(at.world_dir));
        let uv = scaled(d, i, c);
        let turned = scaled(d, i, vec2<f32>(fract(c.x + 0.5), c.y));
        let dx = select(dpdx(uv), dpdx(turned), abs(dpdx(turned).x) < abs(dpdx(uv).x));
        let dy = select(dpdy(uv), dpdy(turned), abs(dpdy(turned).x) < abs(dpdy(uv).x));
        return textureSampleGrad(t, smp, uv, dx, dy);
    }
    return textureSample(t, smp, stage_uv(d, i, mode, at));
}

// The procedural-sky text's 2D cloud: along the view ray a constant scattering strength rho over
// a fake depth D, an isotropic phase function, so L = (E_sun / (4 pi) + L_ambient) (1 - exp(-rho D)).
// `depth` is rho D (the material's alpha times the density); the sun term is modulated by a
// normal faked from the depth's screen-space slope (thicker towards the middle of a cloud, so its
// edges face outwards). The light is the sky model's (globals.cloud_sun = E T / pi as a display
// value, so E T / (4 pi) is a quarter of it), in the target's space.
fn lit_cloud(world_dir: vec3<f32>, depth: f32) -> vec4<f32> {
    let dir = normalize(world_dir);
    let d_depth = vec2<f32>(dpdx(depth), dpdy(depth));
    let d_dir_x = dpdx(world_dir);
    let d_dir_y = dpdy(world_dir);
    let gx = d_dir_x / max(dot(d_dir_x, d_dir_x), 1e-12);
    let gy = d_dir_y / max(dot(d_dir_y, d_dir_y), 1e-12);
    // Depth slope per radian of view direction, scaled to a bump of a few degrees.
    let slope = (d_depth.x * gx + d_depth.y * gy) * 0.03;
    let n = normalize(-dir - slope);
    let sun_dir = globals.towards_sun.xyz;
    let sun_facing = clamp(1.0 + 2.0 * dot(n, sun_dir), 0.0, 3.0);
    let sun = to_target(globals.cloud_sun.rgb) * 0.25 * sun_facing;
    let ambient = to_target(globals.cloud_ambient.rgb);
    let coverage = 1.0 - exp(-max(depth, 0.0));
    return vec4<f32>(sun + ambient, coverage);
}

// Layer `l`'s material (uniform `d`, its stages' textures and samplers, its sky-view map) at
// `at`, lit clouds included: display values, alpha its coverage.
fn material(
    l: u32,
    d: Draw,
    t0: texture_2d<f32>, t1: texture_2d<f32>, t2: texture_2d<f32>, t3: texture_2d<f32>,
    s0: sampler, s1: sampler, s2: sampler, s3: sampler,
    view_map: texture_2d<f32>, view_sampler: sampler,
    at: Place,
) -> vec4<f32> {
    // Stages past the material's count are neither placed nor sampled.
    let count = stage_count(l, d);
    // A physical model's radiance (already exposed, on the HDR target) in place of its stage; that
    // stage's colour then counts as white in its term.
    var view = vec3<f32>(1.0);
    if view_stage(l, d) < 4u {
        view = textureSample(view_map, view_sampler, sky_view_uv(normalize(at.world_dir))).rgb;
    }
    var acc = Terms(vec4<f32>(0.0), vec4<f32>(0.0), false, false);
    if count > 0u { acc = fold_stage(l, d, acc, 0u, stage_sample(l, d, 0u, t0, s0, at), view); }
    if count > 1u { acc = fold_stage(l, d, acc, 1u, stage_sample(l, d, 1u, t1, s1, at), view); }
    if count > 2u { acc = fold_stage(l, d, acc, 2u, stage_sample(l, d, 2u, t2, s2, at), view); }
    if count > 3u { acc = fold_stage(l, d, acc, 3u, stage_sample(l, d, 3u, t3, s3, at), view); }
    var sum = acc.sum;
    if acc.has_term { sum = add_term(d, sum, acc.term, view, acc.term_has_view); }
    // Lit clouds. The lighting is per draw (uniform control flow), so the derivatives `lit_cloud`
    // takes are computed only by the draws that use them.
    if lighting(l, d) == 2u {
        return lit_cloud(at.world_dir, sum.a * bitcast<f32>(d.misc.w));
    }
    return sum;
}

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    let at = Place(in.world_dir, in.mesh_uv01, in.mesh_uv23);
    var color = material(LAYER_OWN, draw, tex0, tex1, tex2, tex3, samp0, samp1, samp2, samp3, sky_view, sky_view_sampler, at);
    if lighting(LAYER_OWN, draw) == 1u {
        // Moon: a lit sphere seen from the dome centre; the sun side is bright, so phases show.
        let p = in.uv * 2.0 - vec2<f32>(1.0);
        let r2 = dot(p, p);
        let right = normalize(draw.object_from_local[0].xyz);
        let up = normalize(draw.object_from_local[1].xyz);
        let towards_viewer = -normalize(draw.object_from_local[2].xyz);
        let n = normalize(p.x * right - p.y * up + sqrt(max(1.0 - r2, 0.0)) * towards_viewer);
        let lit = max(dot(n, globals.towards_sun.xyz), 0.0);
        // The unlit side is dark but also transparent: in daylight the sky shows through it.
        let coverage = mix(0.35, 1.0, smoothstep(0.0, 0.25, lit));
        color = vec4<f32>(color.rgb * (0.04 + 0.96 * lit), color.a * coverage * step(r2, 1.0));
    }
    if UNDER_RUN {
        color = under_run(color, in.clip.xy);
    }
    if BACKGROUND != 0u {
        color = as_background(color, in.clip.xy);
    }
    if OVER_SEED {
        color = over_seed(color, in.clip.xy);
    }
    return color;
}

// What the layer's blend into a reduced buffer (`REDUCED_BLENDS` in src/render/passes/reduced_layers.rs)
// would leave over the seed, the lower run's colour with transmittance 1: premultiplied colour
// and the transmittance left.
fn over_seed(color: vec4<f32>, pixel: vec2<f32>) -> vec4<f32> {
    let seed = run_at_seeded(pixel).rgb;
    switch BLEND_KIND {
        case 0u: { return vec4<f32>(color.rgb, 0.0); }
        case 1u: { return vec4<f32>(color.a * color.rgb + (1.0 - color.a) * seed, 1.0 - color.a); }
        default: { return vec4<f32>(seed + color.a * color.rgb, 1.0); }
    }
}

// What an additive draw writes as the frame's background (`BACKGROUND`): the run's colour C plus
// the draw's term, times the transmittance T of the runs above it when joined; the frame's alpha
// is 1 as the background composite's. The same sum as the draw added to the cleared frame and the
// background composited over it (C + T x target).
fn as_background(color: vec4<f32>, pixel: vec2<f32>) -> vec4<f32> {
    let run = run_at(pixel);
    var term = color.rgb;
    if BLEND_KIND == 2u {
        term = color.a * color.rgb;
    }
    var t = 1.0;
    if BACKGROUND == 2u {
        t = run.a;
    }
    return vec4<f32>(run.rgb + t * term, 1.0);
}

// What a draw writes after the run above it is already in the frame, so that the frame ends as
// C + T x (this draw over what was there), with the run's colour C and transmittance T here.
fn under_run(color: vec4<f32>, pixel: vec2<f32>) -> vec4<f32> {
    // Additive draws read only the transmittance, which a seeded buffer holds as it is.
    var run: vec4<f32>;
    if BLEND_KIND <= 1u {
        run = run_alone_at(pixel);
    } else {
        run = run_at(pixel);
    }
    switch BLEND_KIND {
        case 0u: { return vec4<f32>(run.rgb + run.a * color.rgb, color.a); }
        case 1u: { return vec4<f32>(color.a * (run.a * color.rgb + run.rgb), color.a); }
        case 2u: { return vec4<f32>(run.a * color.a * color.rgb, color.a); }
        default: { return vec4<f32>(run.a * color.rgb, color.a); }
    }
}

// A pair of alpha-blended dome layers on the same mesh drawn at once into a reduced buffer
// (src/render/sky_objects/pairs.rs, `Placement::Pair`): each one's mesh coordinates.
struct PairOut {
    @builtin(position) clip: vec4<f32>,
    @location(1) world_dir: vec3<f32>,
    @location(2) mesh_uv01: vec4<f32>,
    @location(3) mesh_uv23: vec4<f32>,
    @location(4) upper_uv01: vec4<f32>,
    @location(5) upper_uv23: vec4<f32>,
};

@vertex
fn vs_pair(@location(0) position: vec3<f32>, @location(1) uv: vec2<f32>) -> PairOut {
    let own = sky_vertex(position, uv);
    var out: PairOut;
    out.clip = own.clip;
    out.world_dir = own.world_dir;
    out.mesh_uv01 = own.mesh_uv01;
    out.mesh_uv23 = own.mesh_uv23;
    out.upper_uv01 = vec4<f32>(scaled(upper, 0u, uv), scaled(upper, 1u, uv));
    out.upper_uv23 = vec4<f32>(scaled(upper, 2u, uv), scaled(upper, 3u, uv));
    return out;
}

// The upper layer over the draw's own, as the two alpha blends one after the other would leave
// them: premultiplied colour, and in alpha what the pair covers (the buffer's transmittance is
// multiplied by what it lets through: `PAIR_BLEND` in src/render/sky_objects/variants.rs). Over the seed
// (`OVER_SEED`), written as it is, with the transmittance left.
@fragment
fn fs_pair(in: PairOut) -> @location(0) vec4<f32> {
    let own = material(LAYER_OWN, draw, tex0, tex1, tex2, tex3, samp0, samp1, samp2, samp3, sky_view, sky_view_sampler, Place(in.world_dir, in.mesh_uv01, in.mesh_uv23));
    let up = material(
        LAYER_UPPER, upper, upper_tex0, upper_tex1, upper_tex2, upper_tex3, upper_samp0, upper_samp1, upper_samp2, upper_samp3, upper_sky_view, upper_sky_view_sampler,
        Place(in.world_dir, in.upper_uv01, in.upper_uv23),
    );
    let rgb = up.a * up.rgb + (1.0 - up.a) * own.a * own.rgb;
    let through = (1.0 - own.a) * (1.0 - up.a);
    if OVER_SEED {
        return vec4<f32>(rgb + through * run_at_seeded(in.clip.xy).rgb, through);
    }
    return vec4<f32>(rgb, 1.0 - through);
}

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
    let own = sky_vertex(position, vec2<f32>(0.0));
    var out: TexelOut;
    out.clip = own.clip;
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
