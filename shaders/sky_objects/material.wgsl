//! requires: sky_objects/signature, sky_model/sky_view_map, sky_model/tone
// The NeL material: stage mappings, sampling, the sum of terms, lit clouds.

// Plate carree coordinates of world direction `dir` in the rotating celestial frame; u wraps
// from 1 to 0 on the frame's meridian behind -z.
fn celestial_uv(dir: vec3<f32>) -> vec2<f32> {
    let c = (globals.celestial_from_world * vec4<f32>(dir, 0.0)).xyz;
    return vec2<f32>(atan2(c.x, -c.z) / (2.0 * PI) + 0.5, 0.5 - asin(clamp(c.y, -1.0, 1.0)) / PI);
}

// A cloud layer's texture coordinates along unit direction `dir`: where the ray meets a sphere of
// radius R + h whose centre lies R below the camera (p.x = h, p.y = R, in repeats), as horizontal
// displacement. The root of t^2 + 2 R y t - h (2 R + h) = 0 is taken in the form that does not
// cancel on either side of the horizon. CPU twin: src/render/sky_objects/layer_map.rs.
fn layer_uv(p: vec4<f32>, dir: vec3<f32>) -> vec2<f32> {
    return dir.xz * layer_distance(p, dir);
}

// The distance along unit direction `dir` to the layer, in repeats (`layer_uv`).
fn layer_distance(p: vec4<f32>, dir: vec3<f32>) -> f32 {
    let c = p.x * (2.0 * p.y + p.x);
    let s = sqrt(max(p.y * p.y * dir.y * dir.y + c, 0.0));
    var t = s - p.y * dir.y;
    if dir.y >= 0.0 { t = c / (p.y * dir.y + s); }
    return t;
}

// The factor a cloud layer's sample is multiplied by: smooth from 0 at the horizon to 1 at the
// fade's elevation (p.z, its sine; 0: no fade), where the layer's texels crowd together.
fn layer_fade(p: vec4<f32>, dir: vec3<f32>) -> f32 {
    if p.z <= 0.0 { return 1.0; }
    return smoothstep(0.0, p.z, dir.y);
}

// Where a layer's fragment lies: the view direction (any length) and each stage's texture
// coordinates under the mesh mapping or a cloud layer's per vertex (stages 0 and 1, then 2 and
// 3), as the vertex shader interpolated them.
struct Place {
    world_dir: vec3<f32>,
    mesh_uv01: vec4<f32>,
    mesh_uv23: vec4<f32>,
};

// Stage `i`'s texture coordinates under its mapping `mode`: the mesh's and a layer's per vertex
// come from the vertex shader, the others from the view direction.
fn stage_uv(d: Draw, i: u32, mode: u32, at: Place) -> vec2<f32> {
    if mode == UV_MESH || mode == UV_LAYER_VERTEX {
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
    } else if mode == UV_LAYER {
        uv = layer_uv(s.params, dir);
    }
    return scaled(d, i, uv);
}

// Whether this layer holds a physical model's map and draws onto the display target (a
// display-referred frame, `PhysicalTarget::DisplayMatched` or `DisplayAsPainted`): its terms are
// then summed in exposed radiance, as on the HDR target, and tone-mapped by the layer itself, so
// the skydome is the HDR path's to the pixel and the frame needs no display phase.
fn view_on_display(l: u32, d: Draw) -> bool {
    return view_stage(l, d) < 4u && on_display_target();
}

// The model's sky along `dir` on a display-referred physical frame: its exposed radiance, and
// that radiance tone-mapped (what the layer holding the map leaves under the layers above it).
struct ModelSky {
    radiance: vec3<f32>,
    display: vec3<f32>,
};

// The model's sky along `dir`, from the sky-view map.
fn model_sky(dir: vec3<f32>, view_map: texture_2d<f32>, view_sampler: sampler) -> ModelSky {
    let sky = textureSampleLevel(view_map, view_sampler, sky_view_uv(dir, globals.towards_sun.xyz), 0.0).rgb;
    return ModelSky(sky, display_from_exposed(sky, frame_tone_mapper()));
}

// The colour and coverage (straight alpha, display values) whose alpha blend over `under` leaves
// `over`, for a layer covering `coverage`: the coverage is raised where that colour would pass 1
// in some channel (the target clamps it).
fn matched_alpha_blend(over: vec3<f32>, under: vec3<f32>, coverage: f32) -> vec4<f32> {
    var a = coverage;
    let rgb = (over - (1.0 - a) * under) / a;
    if max(rgb.r, max(rgb.g, rgb.b)) > 1.0 {
        // Coverage a' with (over - (1 - a') under) / a' <= 1 in every channel.
        let need = (over - under) / max(vec3<f32>(1.0) - under, vec3<f32>(1e-4));
        a = clamp(max(need.r, max(need.g, need.b)), a, 1.0);
    }
    return vec4<f32>(clamp((over - (1.0 - a) * under) / a, vec3<f32>(0.0), vec3<f32>(1.0)), a);
}

// A blended layer's colour `c` (display values, alpha its coverage) on a display-referred
// physical frame (`OVER_MODEL_SKY`), as what its blend onto the model's sky along `dir` must write
// so that the pixel ends as the HDR path would leave it there: the layer's exposed radiance
// blended with the sky's, then tone-mapped. Exact over the bare sky; over other layers it is the
// display-space blend of a colour chosen for the sky. Alpha (BLEND_KIND 1): the colour that
// leaves H = T(a E(c) + (1 - a) R) over D = T(R) (`matched_alpha_blend`); additive (2 and 3):
// H - D with the sky's radiance R under the layer's added radiance.
// `shade` scales the layer's radiance (the moon's lit side, which the HDR path applies to radiance).
fn over_model_sky(c: vec4<f32>, shade: f32, dir: vec3<f32>, view_map: texture_2d<f32>, view_sampler: sampler) -> vec4<f32> {
    // Nothing over the sky here (most of a cloud layer's pixels): written as it is. First, so that
    // a software rasteriser skips the rest where a whole block of pixels is clear.
    if c.a < 1e-3 || (BLEND_KIND >= 2u && max(c.r, max(c.g, c.b)) <= 0.0) {
        return c;
    }
    let sky = model_sky(dir, view_map, view_sampler);
    let tone = frame_tone_mapper();
    if BLEND_KIND >= 2u {
        var weight = 1.0;
        if BLEND_KIND == 2u { weight = c.a; }
        return vec4<f32>(display_from_exposed(sky.radiance + weight * shade * exposed_from_display(c.rgb), tone) - sky.display, 1.0);
    }
    let over = display_from_exposed(c.a * shade * exposed_from_display(c.rgb) + (1.0 - c.a) * sky.radiance, tone);
    return matched_alpha_blend(over, sky.display, c.a);
}

// Adds one term of the material (display values, times the diffuse colour) to the sum. On the
// display target as they are; on the HDR target (and in a layer that tone-maps itself,
// `view_on_display`) as exposed radiance, or as a factor of the sky model's exposed radiance for
// the term that holds it.
fn add_term(l: u32, d: Draw, sum: vec4<f32>, term_display: vec4<f32>, view: vec3<f32>, has_view: bool) -> vec4<f32> {
    let t = term_display * d.diffuse;
    var rgb: vec3<f32>;
    if has_view {
        rgb = view * linear_from_display(t.rgb);
    } else if view_on_display(l, d) {
        rgb = exposed_from_display(t.rgb);
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
        if acc.has_term { acc.sum = add_term(l, d, acc.sum, acc.term, view, acc.term_has_view); }
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
    let c = textureSample(t, smp, stage_uv(d, i, mode, at));
    if mode == UV_LAYER || mode == UV_LAYER_VERTEX { return c * layer_fade(d.stages[i].params, normalize(at.world_dir)); }
    return c;
}

// The procedural-sky text's 2D cloud: along the view ray a constant scattering strength rho over
// a fake depth D, an isotropic phase function, so L = (E_sun / (4 pi) + L_ambient) (1 - exp(-rho D)).
// `depth` is rho D (the material's alpha times the density); the sun term is modulated by a
// normal faked from the depth's screen-space slope (thicker towards the middle of a cloud, so its
// edges face outwards). The light is the sky model's (`cloud_sun()` = E T / pi as a display
// value, so E T / (4 pi) is a quarter of it), in the target's space.
fn lit_cloud(world_dir: vec3<f32>, depth: f32) -> vec4<f32> {
    // The interpolated direction is a point on the grid's chords, or the layer's (any length).
    let dir = normalize(world_dir);
    let d_depth = vec2<f32>(dpdx(depth), dpdy(depth));
    let d_dir_x = dpdx(dir);
    let d_dir_y = dpdy(dir);
    let gx = d_dir_x / max(dot(d_dir_x, d_dir_x), 1e-12);
    let gy = d_dir_y / max(dot(d_dir_y, d_dir_y), 1e-12);
    // Depth slope per radian of view direction, scaled to a bump of a few degrees.
    let slope = (d_depth.x * gx + d_depth.y * gy) * 0.03;
    let n = normalize(-dir - slope);
    let sun_dir = globals.towards_sun.xyz;
    let sun_facing = clamp(1.0 + 2.0 * dot(n, sun_dir), 0.0, 3.0);
    let sun = to_target(cloud_sun()) * 0.25 * sun_facing;
    let ambient = to_target(cloud_ambient());
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
        view = textureSample(view_map, view_sampler, sky_view_uv(at.world_dir, globals.towards_sun.xyz)).rgb;
    }
    var acc = Terms(vec4<f32>(0.0), vec4<f32>(0.0), false, false);
    if count > 0u { acc = fold_stage(l, d, acc, 0u, stage_sample(l, d, 0u, t0, s0, at), view); }
    if count > 1u { acc = fold_stage(l, d, acc, 1u, stage_sample(l, d, 1u, t1, s1, at), view); }
    if count > 2u { acc = fold_stage(l, d, acc, 2u, stage_sample(l, d, 2u, t2, s2, at), view); }
    if count > 3u { acc = fold_stage(l, d, acc, 3u, stage_sample(l, d, 3u, t3, s3, at), view); }
    var sum = acc.sum;
    if acc.has_term { sum = add_term(l, d, sum, acc.term, view, acc.term_has_view); }
    if view_on_display(l, d) {
        return vec4<f32>(display_from_exposed(sum.rgb, frame_tone_mapper()), sum.a);
    }
    // Lit clouds. The lighting is per draw (uniform control flow), so the derivatives `lit_cloud`
    // takes are computed only by the draws that use them.
    if lighting(l, d) == 2u {
        return lit_cloud(at.world_dir, sum.a * bitcast<f32>(d.misc.w));
    }
    return sum;
}
