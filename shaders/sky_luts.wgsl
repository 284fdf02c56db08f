//! requires: sky_model/lut_sampling
// Sky LUTs pass (compute phase): the `lut` model's transmittance and multiple-scattering tables
// (after Hillaire 2020), rebuilt only when the atmosphere or the LUT settings change. Tables are
// storage buffers of vec4 (rgb, unused) read with bilinear_index. The multiple-scattering table
// is built order by order (cs_multiscattering, then cs_multiscattering_later).
@group(1) @binding(0) var<uniform> atmosphere: Atmosphere;
@group(1) @binding(1) var<storage, read> lut_params: LutParams;
@group(1) @binding(2) var<storage, read_write> transmittance_lut: array<vec4<f32>>;
@group(1) @binding(3) var<storage, read_write> multiscattering_lut: array<vec4<f32>>;

@compute @workgroup_size(64)
fn cs_transmittance(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = lut_params.sizes.xy;
    if (gid.x >= size.x * size.y) {
        return;
    }
    let id = vec2<u32>(gid.x % size.x, gid.x / size.x);
    let uv = vec2<f32>(id) / vec2<f32>(size - vec2<u32>(1u));
    transmittance_lut[gid.x] = vec4<f32>(transmittance_texel(atmosphere, uv, lut_params.steps.x), 1.0);
}

// cos_theta of the fraction x (0: zenith, 1: nadir) of the direction grid's polar bands:
// (1 - 2x)^3, so the bands narrow towards the horizon (equal-area bands, 1 - 2x, put a quarter of
// them within 14 degrees of it and miss its peak: 2.5% median error by day against 0.9%).
fn horizon_crowded(x: f32) -> f32 {
    let c = 1.0 - 2.0 * x;
    return c * c * c;
}

// Direction (a, b) of the multiple-scattering integral's grid, with its share of 4 pi sr in w.
// The half sphere z >= 0 stands for the whole at twice the azimuthal resolution: the field is
// symmetric about the plane of the sun and the vertical, and so are the harmonics kept. Bands of
// cos_theta crowd towards the horizon, where the light arriving at a point peaks (long paths).
fn ms_direction(a: u32, b: u32, n: u32) -> vec4<f32> {
    let c0 = horizon_crowded(f32(a) / f32(n));
    let c1 = horizon_crowded((f32(a) + 1.0) / f32(n));
    let cos_theta = horizon_crowded((f32(a) + 0.5) / f32(n));
    let phi = PI * (f32(b) + 0.5) / f32(n);
    let sin_theta = sqrt(max(1.0 - cos_theta * cos_theta, 0.0));
    return vec4<f32>(sin_theta * cos(phi), cos_theta, sin_theta * sin(phi), 0.5 * (c0 - c1) / f32(n));
}

// The point (radius, km) and the sun of a multiple-scattering texel, in the texel's frame: y up,
// the sun in the xy plane towards +x.
struct MsTexel {
    r: f32,
    sun: vec3<f32>,
};

fn ms_texel(index: u32) -> MsTexel {
    let n = lut_params.sizes.z;
    let uv = vec2<f32>(vec2<u32>(index % n, index / n)) / f32(n - 1u);
    let mu_s = ms_mu_s_of_u(uv.x);
    let r = atmosphere.shape.x + max(uv.y * (atmosphere.shape.y - atmosphere.shape.x), 0.01);
    return MsTexel(r, vec3<f32>(sqrt(max(1.0 - mu_s * mu_s, 0.0)), mu_s, 0.0));
}

// The radiance of one order arriving at a texel's point, projected on `ms_harmonics` over the
// direction grid: each direction's ray is marched back to the top of the atmosphere or the
// ground, gathering what its points scatter towards the texel's point. The order after the
// sun's (`source` = MS_FROM_SUN) scatters sunlight with the phase functions and reflects the
// sunlit ground; each later one scatters and reflects the previous order's table region `source`.
const MS_FROM_SUN: u32 = 0u;

struct MsOrder {
    harmonics: array<vec3<f32>, 6>,
    // Hillaire 2020's f_ms: the share of uniform unit radiance around the point that the air
    // (and the ground) return to it after one more scattering (reflection).
    transfer: vec3<f32>,
};

fn ms_order(index: u32, source: u32) -> MsOrder {
    let texel = ms_texel(index);
    let r = texel.r;
    let sun = texel.sun;
    let albedo = lut_params.albedo_phase.x;
    let grid = max(lut_params.sizes.w, 1u);
    let steps = max(lut_params.steps.y, 1u);
    var harmonics: array<vec3<f32>, 6>;
    var transfer = vec3<f32>(0.0);
    for (var a = 0u; a < grid; a++) {
        for (var b = 0u; b < grid; b++) {
            let d = ms_direction(a, b, grid);
            let dir = d.xyz;
            let mu = dir.y;
            let ground = distance_to_ground(atmosphere, r, mu);
            var ray_length = distance_to_top(atmosphere, r, mu);
            if (ground >= 0.0) {
                ray_length = ground;
            }
            let nu = dot(dir, sun);
            let phase_r = rayleigh_phase(nu);
            let phase_m = cornette_shanks_phase(nu, atmosphere.mie_extinction.w);
            var tau = vec3<f32>(0.0);
            var l = vec3<f32>(0.0);
            var f = vec3<f32>(0.0);
            for (var i = 0u; i < steps; i++) {
                let step = march_step(atmosphere, r, mu, crowded_sample(ray_length, i, steps), &tau);
                let t = step.t;
                let dt = step.dt;
                let h = max(step.altitude_km, 0.0);
                let tau_mid = step.tau_mid;
                let p = vec3<f32>(0.0, r, 0.0) + dir * t;
                let r_p = atmosphere.shape.x + h;
                let mu_p = dot(p, sun) / max(length(p), 1e-3);
                let scattering = scattering_at(atmosphere, h);
                let sigma_r = scattering.rayleigh;
                let sigma_m = scattering.mie;
                var scattered: vec3<f32>;
                if (source == MS_FROM_SUN) {
                    scattered = (sigma_r * phase_r + sigma_m * phase_m) * sun_transmittance(atmosphere, r_p, mu_p);
                } else {
                    scattered = multiple_scattering_from(source, atmosphere, p, r_p, mu_p, dir, sun, sigma_r, sigma_m);
                }
                l += exp(-tau_mid) * scattered * dt;
                f += exp(-tau_mid) * (sigma_r + sigma_m) * dt;
            }
            if (ground >= 0.0 && albedo > 0.0) {
                let g = vec3<f32>(0.0, r, 0.0) + dir * ray_length;
                let mu_g = dot(normalize(g), sun);
                var irradiance: vec3<f32>;
                if (source == MS_FROM_SUN) {
                    irradiance = sun_transmittance(atmosphere, atmosphere.shape.x, mu_g) * max(mu_g, 0.0);
                } else {
                    irradiance = ms_ground_irradiance(source, atmosphere, mu_g);
                }
                l += exp(-tau) * irradiance * albedo / PI;
                f += exp(-tau) * albedo;
            }
            let y = ms_harmonics(dir);
            for (var k = 0u; k < MS_LAYERS; k++) {
                harmonics[k] += l * (y[k] * 4.0 * PI * d.w);
            }
            transfer += f * d.w;
        }
    }
    return MsOrder(harmonics, transfer);
}

// Adds one order's harmonics to region 0, the sum of the orders that the model reads (in its own
// form: `ms_encode`).
fn ms_add_to_sum(index: u32, harmonics: array<vec3<f32>, 6>, first: bool) {
    let texel = index * MS_LAYERS;
    var sum = harmonics;
    if (!first) {
        var previous: array<vec3<f32>, 6>;
        for (var k = 0u; k < MS_LAYERS; k++) {
            previous[k] = multiscattering_lut[texel + k].xyz;
        }
        let decoded = ms_decode(previous);
        for (var k = 0u; k < MS_LAYERS; k++) {
            sum[k] += decoded[k];
        }
    }
    let encoded = ms_encode(sum);
    for (var k = 0u; k < MS_LAYERS; k++) {
        multiscattering_lut[texel + k] = vec4<f32>(encoded[k], 1.0);
    }
}

// The second order (the first after the sun's), one texel per invocation, into region 1
// (Hillaire 2020's L_2nd, section 5.5, with the first scattering's phase functions kept).
@compute @workgroup_size(64)
fn cs_multiscattering(@builtin(global_invocation_id) gid: vec3<u32>) {
    let n = lut_params.sizes.z;
    if (gid.x >= n * n) {
        return;
    }
    let second = ms_order(gid.x, MS_FROM_SUN).harmonics;
    let n2 = n * n * MS_LAYERS;
    for (var k = 0u; k < MS_LAYERS; k++) {
        multiscattering_lut[n2 + gid.x * MS_LAYERS + k] = vec4<f32>(second[k], 1.0);
    }
    ms_add_to_sum(gid.x, second, true);
}

// The third order from the second (region 1), and every order above it by extrapolation: each
// further order is taken as the one before times q = Hillaire's transfer factor f (the share of
// uniform light that the air and the ground return to the point; `MsOrder::transfer`, per texel
// and channel), so orders 4 and on add order 3 times q / (1 - q). Instead of Hillaire's isotropic series L_2nd / (1 - f_ms), the
// orders that matter most are iterated as Bruneton 2017 does with its 4D tables: the 2D table is
// exact for a spherically symmetric atmosphere but for the band limit of its harmonics.
@compute @workgroup_size(64)
fn cs_multiscattering_later(@builtin(global_invocation_id) gid: vec3<u32>) {
    let n = lut_params.sizes.z;
    if (gid.x >= n * n) {
        return;
    }
    let order = ms_order(gid.x, 1u);
    var third = order.harmonics;
    let q = min(order.transfer, vec3<f32>(0.9));
    for (var k = 0u; k < MS_LAYERS; k++) {
        third[k] *= 1.0 / (1.0 - q);
    }
    ms_add_to_sum(gid.x, third, false);
}
