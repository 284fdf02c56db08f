//! requires: sky_model/single, sky_model/lut_sampling, sky_model/precomputed_sampling, sky_model/tone, sky_model/sky_view_map, sky_model/analytic
// Sky-view pass (compute phase): the current physical model rendered into the sky-view map as
// exposed linear radiance, for the skydome's gradient stage to sample into the HDR target (the
// display phase, tone_map.wgsl, tone-maps the frame).
// Keep `SkyViewParams` in sync with src/render/atmosphere/sky_view.rs.
struct SkyViewParams {
    towards_sun: vec4<f32>, // xyz unit vector, w: camera altitude (km)
    exposure: vec4<f32>,    // x: radiance scale (2^EV), y: tone mapper as f32 (0 ACES, 1 neutral) for the scene's light, zw: map size (texels)
    model: vec4<f32>,       // x: 0 single, 1 lut, 2 radiance computed on the CPU (cells, reference), 3 analytic, 4 precomputed; y: 1 automatic exposure
};

@group(1) @binding(0) var<uniform> atmosphere: Atmosphere;
@group(1) @binding(1) var<uniform> single_settings: SingleSettings;
// Read-only storage rather than uniform: Mesa 22 lavapipe crashes when the camera altitude is a
// uniform-buffer value here (it runs fine as a storage value, as in radiance_probe.wgsl).
@group(1) @binding(2) var<storage, read> params: SkyViewParams;
// The work map: exposed linear radiance per texel, row-major. sky_view/blend.wgsl makes the shown
// map (rgba16float, copied into the sky-view texture) from the finished ones.
@group(1) @binding(3) var<storage, read_write> work: array<vec4<f32>>;
// The `lut` model's tables (sky_luts.wgsl builds them earlier in the compute phase).
@group(1) @binding(4) var<storage, read> lut_params: LutParams;
@group(1) @binding(5) var<storage, read> transmittance_lut: array<vec4<f32>>;
@group(1) @binding(6) var<storage, read> multiscattering_lut: array<vec4<f32>>;
// Radiance per texel computed on the CPU (the `cells` model), in the same texel order.
@group(1) @binding(7) var<storage, read> cpu_radiance: array<vec4<f32>>;
// [0].x: the exposure scale of this map: 2^EV, or with automatic exposure the scale that brings the
// sky's mean luminance to middle grey, times 2^EV as compensation. [1], [2], [3]: the main
// scene's fog colour, sun ambient and sun diffuse from the model, as display values (the scene
// shades with display-referred colours; `to_target` takes them back to exposed radiance), laid out
// as in `Globals` (sky_view.rs copies them there when the model drives the scene).
@group(1) @binding(8) var<storage, read_write> sky_light: array<vec4<f32>, 4>;
// The analytic models' coefficients for this sun (src/atmosphere/analytic.rs); [11].w the kind
// (2: Braun-Cohen, whose colour is a display value).
@group(1) @binding(9) var<uniform> analytic_coefficients: array<vec4<f32>, 12>;
// The `precomputed` model's tables (precomputed_tables.wgsl builds them earlier in the phase).
@group(1) @binding(10) var<storage, read> precomputed_tables: array<vec4<f32>>;
// The texels this frame computes: x the first (row-major), y how many (a slice of the map while
// the sun moves: src/render/plan/map_updates.rs).
@group(1) @binding(11) var<uniform> slice: vec4<u32>;

// Braun and Cohen's colour as the exposed radiance the frame's tone mapper takes back to it
// (its exposure scale is 1).
fn display_referred_radiance(display: vec3<f32>) -> vec3<f32> {
    let l = linear_from_display(display);
    if (params.exposure.y > 0.5) {
        return tone_map_neutral_inverse(l);
    }
    return tone_map_aces_inverse(l);
}

// Radiance of the frame's model along `dir` (texel `index` of the CPU map for `cells`).
fn model_radiance(dir: vec3<f32>, index: u32) -> vec3<f32> {
    if (params.model.x > 3.5) {
        return precomputed_radiance(atmosphere, params.towards_sun.w, dir, params.towards_sun.xyz);
    } else if (params.model.x > 2.5) {
        let radiance = analytic_radiance(analytic_coefficients, dir);
        if (analytic_coefficients[11].w > 1.5) {
            return display_referred_radiance(radiance);
        }
        return radiance;
    } else if (params.model.x > 1.5) {
        return cpu_radiance[index].xyz;
    } else if (params.model.x > 0.5) {
        return lut_radiance(atmosphere, params.towards_sun.w, dir, params.towards_sun.xyz);
    }
    return single_scattering(atmosphere, single_settings, params.towards_sun.w, dir, params.towards_sun.xyz);
}

fn texel_index(uv: vec2<f32>, size: vec2<u32>) -> u32 {
    let t = min(vec2<u32>(uv * vec2<f32>(size)), size - vec2<u32>(1u));
    return t.y * size.x + t.x;
}

var<workgroup> radiance_samples: array<vec3<f32>, 64>;

// One workgroup, before cs_main: the mean luminance (Rec. 709) of 64 equal-area directions of the
// upper sky sets the exposure (middle grey 0.18); the same samples give the scene's light: the
// sky's mean radiance as ambient, the lowest band (0 to 7 degrees) as fog, and the sun's
// transmittance (irradiance 1 scattered by a white Lambertian surface: T / pi) as diffuse.
@compute @workgroup_size(64)
fn cs_exposure(@builtin(local_invocation_index) i: u32) {
    let size = vec2<u32>(params.exposure.zw);
    let cos_theta = 1.0 - (f32(i / 8u) + 0.5) / 8.0;
    let phi = 2.0 * PI * (f32(i % 8u) + 0.5) / 8.0;
    let sin_theta = sqrt(max(1.0 - cos_theta * cos_theta, 0.0));
    let dir = vec3<f32>(sin_theta * cos(phi), cos_theta, sin_theta * sin(phi));
    radiance_samples[i] = model_radiance(dir, texel_index(sky_view_uv(dir, params.towards_sun.xyz), size));
    workgroupBarrier();
    if (i == 0u) {
        var mean = vec3<f32>(0.0);
        var horizon = vec3<f32>(0.0);
        for (var k = 0u; k < 64u; k++) {
            mean += radiance_samples[k] / 64.0;
            if (k >= 56u) {
                horizon += radiance_samples[k] / 8.0;
            }
        }
        var scale = params.exposure.x;
        if (params.model.y > 0.5) {
            scale = params.exposure.x * 0.18 / max(dot(mean, vec3<f32>(0.2126, 0.7152, 0.0722)), 1e-6);
        }
        let r = atmosphere.shape.x + params.towards_sun.w;
        var sun = numeric_optical_depth(atmosphere, r, params.towards_sun.y, 64u);
        var t_sun = exp(-sun);
        if (sun.x < 0.0) {
            t_sun = vec3<f32>(0.0);
        }
        sky_light[0] = vec4<f32>(scale, 0.0, 0.0, 0.0);
        let tone = u32(params.exposure.y);
        sky_light[1] = vec4<f32>(display_from_exposed(horizon * scale, tone), 1.0);
        sky_light[2] = vec4<f32>(display_from_exposed(mean * scale, tone), 1.0);
        sky_light[3] = vec4<f32>(display_from_exposed(t_sun / PI * scale, tone), 1.0);
        if (params.model.x > 2.5 && analytic_coefficients[11].w > 1.5) {
            // Braun and Cohen: one colour for sky, fog and ambient light; no directional light.
            let c = analytic_coefficients[0].rgb;
            sky_light[1] = vec4<f32>(c, 1.0);
            sky_light[2] = vec4<f32>(c, 1.0);
            sky_light[3] = vec4<f32>(0.0, 0.0, 0.0, 1.0);
        }
    }
}

@compute @workgroup_size(64)
fn cs_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = vec2<u32>(params.exposure.zw);
    let texel = slice.x + gid.x;
    if (gid.x >= slice.y || texel >= size.x * size.y) {
        return;
    }
    let id = vec2<u32>(texel % size.x, texel / size.x);
    let uv = (vec2<f32>(id) + 0.5) / vec2<f32>(size);
    let dir = sky_view_direction(uv, params.towards_sun.xyz);
    let radiance = model_radiance(dir, texel);
    // Finite in half precision (65504) whatever the exposure.
    work[texel] = vec4<f32>(clamp(radiance * sky_light[0].x, vec3<f32>(0.0), vec3<f32>(60000.0)), 1.0);
}
