//! requires: sky_model/transmittance_map
// The `lut` model (Hillaire 2020): look-up-table parametrisations, bilinear reads, and the sky
// radiance from the LUTs. A library: the module that requires it declares `lut_params`,
// `transmittance_lut` and `multiscattering_lut` (read-only where the LUTs are used, read-write
// in the pass that builds them). Keep `LutParams` in sync with src/render/atmosphere/uniforms.rs.
struct LutParams {
    sizes: vec4<u32>, // transmittance width, height; multiple-scattering size; sqrt of its direction count
    steps: vec4<u32>, // transmittance, multiple-scattering and view-ray samples; unused
    albedo_phase: vec4<f32>, // ground albedo (grey); Mie phase Legendre moments g_1, g_2; unused
};

// Values per multiple-scattering texel. Keep in sync with `MULTISCATTERING_LAYERS` in
// src/render/atmosphere/tables.rs.
const MS_LAYERS: u32 = 6u;

// The six real spherical harmonics (orthonormal, bands 0 to 2) even in z, of a direction d in a
// frame whose y is the local vertical and whose x points to the sun's azimuth. The radiance that
// arrives from the second order on is symmetric about the plane of the sun and the vertical, so
// the odd ones vanish.
fn ms_harmonics(d: vec3<f32>) -> array<f32, 6> {
    return array<f32, 6>(
        0.2820948,
        0.4886025 * d.y,
        0.4886025 * d.x,
        1.0925484 * d.x * d.y,
        0.3153916 * (3.0 * d.y * d.y - 1.0),
        0.5462742 * (d.x * d.x - d.z * d.z),
    );
}

fn sample_transmittance(atm: Atmosphere, r: f32, mu: f32) -> vec3<f32> {
    let b = bilinear_index(lut_params.sizes.xy, transmittance_uv(atm, r, mu));
    let k = u32(b.x);
    let w = u32(b.y);
    let top = mix(transmittance_lut[k].xyz, transmittance_lut[k + 1u].xyz, b.z);
    let bottom = mix(transmittance_lut[k + w].xyz, transmittance_lut[k + w + 1u].xyz, b.z);
    return mix(top, bottom, b.w);
}

// Transmittance to the sun from radius r at sun cosine mu_s, times the visible fraction of the
// sun's disc (0 behind the planet); the visible part is seen at grazing incidence at worst.
fn sun_transmittance(atm: Atmosphere, r: f32, mu_s: f32) -> vec3<f32> {
    let visible = sun_visible_fraction(atm, r, mu_s);
    if (visible <= 0.0) {
        return vec3<f32>(0.0);
    }
    return visible * sample_transmittance(atm, r, max(mu_s, horizon_mu(atm, r) + 1e-4));
}

// The multiple-scattering table's sun axis: u = (1 + sign(mu_s) sqrt(|mu_s|)) / 2, so texels
// crowd around the terminator (mu_s = 0), where the scattered light changes fastest with the sun.
fn ms_u_of_mu_s(mu_s: f32) -> f32 {
    return 0.5 * (1.0 + sign(mu_s) * sqrt(abs(mu_s)));
}

fn ms_mu_s_of_u(u: f32) -> f32 {
    let s = 2.0 * u - 1.0;
    return s * abs(s);
}

// Multiple-scattering table: u = ms_u_of_mu_s(mu_s), v = altitude / thickness; MS_LAYERS values
// per texel (see `ms_harmonics`), each bilinearly interpolated. Region 0 holds the sum of the
// orders from the second on, band 0 as its logarithm and the others as ratios to band 0, so that
// reads follow the light's exponential fall as the sun sets (`ms_encode`); region 1 holds the
// second order as it is while the table is built (sky_luts.wgsl).
fn sample_multiscattering(region: u32, atm: Atmosphere, r: f32, mu_s: f32) -> array<vec3<f32>, 6> {
    let n = lut_params.sizes.z;
    let uv = vec2<f32>(ms_u_of_mu_s(mu_s), (r - atm.shape.x) / (atm.shape.y - atm.shape.x));
    let b = bilinear_index(vec2<u32>(n, n), uv);
    let k = region * n * n * MS_LAYERS + u32(b.x) * MS_LAYERS;
    let row = n * MS_LAYERS;
    var out: array<vec3<f32>, 6>;
    for (var l = 0u; l < MS_LAYERS; l++) {
        let top = mix(multiscattering_lut[k + l].xyz, multiscattering_lut[k + MS_LAYERS + l].xyz, b.z);
        let bottom = mix(multiscattering_lut[k + row + l].xyz, multiscattering_lut[k + row + MS_LAYERS + l].xyz, b.z);
        out[l] = mix(top, bottom, b.w);
    }
    if (region == 0u) {
        return ms_decode(out);
    }
    return out;
}

// Region 0's form of a texel's harmonics (see `sample_multiscattering`).
fn ms_encode(c: array<vec3<f32>, 6>) -> array<vec3<f32>, 6> {
    var out = c;
    let band0 = max(c[0], vec3<f32>(1e-30));
    out[0] = log(band0);
    for (var l = 1u; l < MS_LAYERS; l++) {
        out[l] = c[l] / band0;
    }
    return out;
}

fn ms_decode(c: array<vec3<f32>, 6>) -> array<vec3<f32>, 6> {
    var out = c;
    out[0] = exp(c[0]);
    for (var l = 1u; l < MS_LAYERS; l++) {
        out[l] = c[l] * out[0];
    }
    return out;
}

// Radiance that the orders in table region `region` scatter at a point p (km from the planet's
// centre, radius r_p, sun cosine mu_s) towards a camera looking along `view`: the harmonics of
// the light arriving at p, each band scaled by the phase functions' Legendre moments (Rayleigh:
// 1, 0, 0.1; Mie: 1, g_1, g_2; Funk-Hecke), summed at the view direction in p's frame.
fn multiple_scattering_from(region: u32, atm: Atmosphere, p: vec3<f32>, r_p: f32, mu_s: f32, view: vec3<f32>, sun: vec3<f32>, sigma_r: vec3<f32>, sigma_m: vec3<f32>) -> vec3<f32> {
    return multiple_scattering_of(sample_multiscattering(region, atm, r_p, mu_s), p, view, sun, sigma_r, sigma_m);
}

// What the table's harmonics `c` (read for a point near p) scatter at p towards `view`
// (`multiple_scattering_from`).
fn multiple_scattering_of(c: array<vec3<f32>, 6>, p: vec3<f32>, view: vec3<f32>, sun: vec3<f32>, sigma_r: vec3<f32>, sigma_m: vec3<f32>) -> vec3<f32> {
    let up = p / max(length(p), 1e-3);
    let across = sun - up * dot(sun, up);
    let across_len = length(across);
    // With the sun overhead the field is symmetric about the vertical and the x harmonics vanish.
    let x_axis = select(vec3<f32>(0.0), across / across_len, across_len > 1e-4);
    let vx = dot(view, x_axis);
    let vy = dot(view, up);
    let y = ms_harmonics(vec3<f32>(vx, vy, sqrt(max(1.0 - vx * vx - vy * vy, 0.0))));
    let band1 = sigma_m * lut_params.albedo_phase.y;
    let band2 = 0.1 * sigma_r + sigma_m * lut_params.albedo_phase.z;
    let sum = (sigma_r + sigma_m) * c[0] * y[0] + band1 * (c[1] * y[1] + c[2] * y[2]) + band2 * (c[3] * y[3] + c[4] * y[4] + c[5] * y[5]);
    // A band-limited field can dip below zero where the true one is small.
    return max(sum, vec3<f32>(0.0));
}

// Irradiance on the ground (units of the table) from the orders in region `region`, the sun at
// cosine mu_s: the harmonics convolved with the clamped cosine (Ramamoorthi and Hanrahan 2001:
// pi, 2 pi / 3, pi / 4 per band) at the vertical, where only the zonal harmonics are non-zero.
fn ms_ground_irradiance(region: u32, atm: Atmosphere, mu_s: f32) -> vec3<f32> {
    let c = sample_multiscattering(region, atm, atm.shape.x, mu_s);
    let y = ms_harmonics(vec3<f32>(0.0, 1.0, 0.0));
    return max(PI * c[0] * y[0] + (2.0 * PI / 3.0) * c[1] * y[1] + (PI / 4.0) * c[4] * y[4], vec3<f32>(0.0));
}

// View-ray samples per read of the multiple-scattering table. The table holds the light arriving
// at a point, which changes slowly along a ray (the air's density, which changes fast, is still
// taken per sample), and its bilinear read, 24 values, is most of a sample's cost on a software
// rasteriser. Read once for two samples, where they meet, the sky moves by at most 0.7% over 2730
// cases (cameras 0.2 to 30 km, sun -8 to 89 degrees; docs/sky-models.md) and its map takes 0.71 of
// the time on lavapipe.
const MS_SAMPLES_PER_READ: u32 = 2u;

// The multiple-scattering table's harmonics for the samples from `i` of a view ray of `steps`
// crowded samples: read where the group's middle two meet (a lone last sample: at its midpoint).
fn ms_for_samples(atm: Atmosphere, ray: ViewRay, view: vec3<f32>, sun: vec3<f32>, i: u32, steps: u32) -> array<vec3<f32>, 6> {
    let middle = i + MS_SAMPLES_PER_READ / 2u;
    var t = crowded_sample(ray.distance_km, i, steps).x;
    if (middle < steps) {
        let b = f32(middle) / f32(steps);
        t = ray.distance_km * b * b;
    }
    let q = vec3<f32>(0.0, ray.r, 0.0) + view * t;
    let r_q = atm.shape.x + max(altitude_along(atm, ray.r, ray.mu, t), 0.0);
    return sample_multiscattering(0u, atm, r_q, dot(q, sun) / max(length(q), 1e-3));
}

// What a view ray gathers before it stops (aerial perspective): the light scattered into it and
// its transmittance, per channel.
struct Aerial {
    in_scatter: vec3<f32>,
    transmittance: vec3<f32>,
};

// Sky radiance by the LUT method: single scattering with LUT transmittance to the sun plus what
// the multiple-scattering table's orders scatter towards the camera (Hillaire 2020's
// sigma_s x Psi_ms, made anisotropic).
fn lut_radiance(atm: Atmosphere, camera_km: f32, view: vec3<f32>, sun: vec3<f32>) -> vec3<f32> {
    return lut_aerial(atm, camera_km, view, sun, FAR_KM).in_scatter;
}

// No distance: a ray stopped here leaves the atmosphere or meets the ground first.
const FAR_KM: f32 = 1e30;

// `lut_radiance` along a ray that stops at `max_km` (a surface there adds nothing; the ground
// or the edge of the atmosphere, if nearer, stop it first), and the ray's transmittance: the
// exact per-pixel integration of aerial perspective, with the sky's own samples spread over the
// shorter ray.
fn lut_aerial(atm: Atmosphere, camera_km: f32, view: vec3<f32>, sun: vec3<f32>, max_km: f32) -> Aerial {
    var ray = view_ray(atm, camera_km, view, sun);
    ray.distance_km = min(ray.distance_km, max_km);
    let r = ray.r;
    let mu = ray.mu;
    let steps = max(lut_params.steps.z, 1u);
    var tau = vec3<f32>(0.0);
    var sum = vec3<f32>(0.0);
    var c: array<vec3<f32>, 6>;
    for (var i = 0u; i < steps; i++) {
        if (i % MS_SAMPLES_PER_READ == 0u) {
            c = ms_for_samples(atm, ray, view, sun, i, steps);
        }
        let step = march_step(atm, r, mu, crowded_sample(ray.distance_km, i, steps), &tau);
        sum += scattered_at(atm, ray, view, sun, step, c, true) * exp(-step.tau_mid) * step.dt;
    }
    return Aerial(sum, exp(-tau));
}

// The light a march step of `ray` (view direction `view`) scatters towards the viewer, per km
// before the way back: single scattering with the table's transmittance to the sun (the Earth's
// shadow in it) and, with `multiple`, what the multiple-scattering harmonics `c` (read near the
// step) scatter. The one sample of `lut_aerial` and of the aerial-perspective volume's march.
fn scattered_at(atm: Atmosphere, ray: ViewRay, view: vec3<f32>, sun: vec3<f32>, step: MarchStep, c: array<vec3<f32>, 6>, multiple: bool) -> vec3<f32> {
    let h = max(step.altitude_km, 0.0);
    let p = vec3<f32>(0.0, ray.r, 0.0) + view * step.t;
    let r_p = atm.shape.x + h;
    let mu_s = dot(p, sun) / max(length(p), 1e-3);
    let scattering = scattering_at(atm, h);
    let single = (scattering.rayleigh * ray.phase_r + scattering.mie * ray.phase_m) * sun_transmittance(atm, r_p, mu_s);
    if (!multiple) {
        return single;
    }
    return single + multiple_scattering_of(c, p, view, sun, scattering.rayleigh, scattering.mie);
}
