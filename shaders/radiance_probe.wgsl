//! requires: sky_model/single, sky_model/lut_sampling, sky_model/analytic, sky_model/precomputed_sampling
// Evaluates a sky model for a list of radiance cases (`skytune radiance`, tests, benchmarks).
// Keep in sync with src/render/atmosphere/radiance_probe.rs.
@group(1) @binding(0) var<uniform> atmosphere: Atmosphere;
@group(1) @binding(1) var<uniform> single_settings: SingleSettings;
// Two vectors per case: camera_km, sun_elev_deg, view_elev_deg, rel_azimuth_deg; then where its
// view ray stops, km (0: the edge of the atmosphere).
@group(1) @binding(2) var<storage, read> cases: array<vec4<f32>>;
// Two vectors per case: the radiance, then the ray's transmittance (cs_lut; ones from the
// others, written beforehand).
@group(1) @binding(3) var<storage, read_write> radiance: array<vec4<f32>>;
// The `lut` model's tables, built by sky_luts.wgsl before cs_lut runs.
@group(1) @binding(4) var<storage, read> lut_params: LutParams;
@group(1) @binding(5) var<storage, read> transmittance_lut: array<vec4<f32>>;
@group(1) @binding(6) var<storage, read> multiscattering_lut: array<vec4<f32>>;
// The analytic models' coefficients, 12 vectors per case (src/atmosphere/analytic.rs).
@group(1) @binding(7) var<storage, read> analytic: array<vec4<f32>>;
// The `precomputed` model's tables, built by precomputed_tables.wgsl before cs_precomputed runs.
@group(1) @binding(8) var<storage, read> precomputed_tables: array<vec4<f32>>;

fn direction(elevation_deg: f32, azimuth_deg: f32) -> vec3<f32> {
    let e = radians(elevation_deg);
    let a = radians(azimuth_deg);
    return vec3<f32>(cos(e) * cos(a), sin(e), cos(e) * sin(a));
}

@compute @workgroup_size(64)
fn cs_single(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= arrayLength(&cases) / 2u) {
        return;
    }
    let c = cases[2u * id.x];
    let sun = direction(c.y, 0.0);
    let view = direction(c.z, c.w);
    radiance[2u * id.x] = vec4<f32>(single_scattering(atmosphere, single_settings, c.x, view, sun), 1.0);
}

@compute @workgroup_size(64)
fn cs_lut(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= arrayLength(&cases) / 2u) {
        return;
    }
    let c = cases[2u * id.x];
    let sun = direction(c.y, 0.0);
    let view = direction(c.z, c.w);
    let d = cases[2u * id.x + 1u].x;
    let ray = lut_aerial(atmosphere, c.x, view, sun, select(FAR_KM, d, d > 0.0));
    radiance[2u * id.x] = vec4<f32>(ray.in_scatter, 1.0);
    radiance[2u * id.x + 1u] = vec4<f32>(ray.transmittance, 1.0);
}

@compute @workgroup_size(64)
fn cs_analytic(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= arrayLength(&cases) / 2u) {
        return;
    }
    let c = cases[2u * id.x];
    var coefficients: array<vec4<f32>, 12>;
    for (var k = 0u; k < 12u; k++) {
        coefficients[k] = analytic[12u * id.x + k];
    }
    radiance[2u * id.x] = vec4<f32>(analytic_radiance(coefficients, direction(c.z, c.w)), 1.0);
}

@compute @workgroup_size(64)
fn cs_precomputed(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= arrayLength(&cases) / 2u) {
        return;
    }
    let c = cases[2u * id.x];
    radiance[2u * id.x] = vec4<f32>(precomputed_radiance(atmosphere, c.x, direction(c.z, c.w), direction(c.y, 0.0)), 1.0);
}
