//! requires: sky_model/transmittance_map
// The `lut` model (Hillaire 2020): look-up-table parametrisations, bilinear reads, and the sky
// radiance from the LUTs. A library: the module that requires it declares `lut_params`,
// `transmittance_lut` and `multiscattering_lut` (read-only where the LUTs are used, read-write
// in the pass that builds them). Keep `LutParams` in sync with src/render/passes/sky_model.rs.
struct LutParams {
    sizes: vec4<u32>, // transmittance width, height; multiple-scattering size; sqrt of its direction count
    steps: vec4<u32>, // transmittance, multiple-scattering and view-ray samples; unused
    ground: vec4<f32>, // ground albedo (grey); unused
};

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

// Multiple-scattering table: u = (mu_s + 1) / 2, v = altitude / thickness.
fn sample_multiscattering(atm: Atmosphere, r: f32, mu_s: f32) -> vec3<f32> {
    let n = lut_params.sizes.z;
    let uv = vec2<f32>(0.5 * (mu_s + 1.0), (r - atm.shape.x) / (atm.shape.y - atm.shape.x));
    let b = bilinear_index(vec2<u32>(n, n), uv);
    let k = u32(b.x);
    let top = mix(multiscattering_lut[k].xyz, multiscattering_lut[k + 1u].xyz, b.z);
    let bottom = mix(multiscattering_lut[k + n].xyz, multiscattering_lut[k + n + 1u].xyz, b.z);
    return mix(top, bottom, b.w);
}

// Sky radiance by the LUT method: single scattering with LUT transmittance to the sun plus
// the isotropic multiple-scattering term sigma_s x Psi_ms.
fn lut_radiance(atm: Atmosphere, camera_km: f32, view: vec3<f32>, sun: vec3<f32>) -> vec3<f32> {
    let ray = view_ray(atm, camera_km, view, sun);
    let r = ray.r;
    let mu = ray.mu;
    let steps = max(lut_params.steps.z, 1u);
    var tau = vec3<f32>(0.0);
    var sum = vec3<f32>(0.0);
    for (var i = 0u; i < steps; i++) {
        let sample = crowded_sample(ray.distance_km, i, steps);
        let t = sample.x;
        let dt = sample.y;
        let h = max(altitude_along(atm, r, mu, t), 0.0);
        let e = extinction_at(atm, h);
        let tau_mid = tau + e * (0.5 * dt);
        tau += e * dt;
        let p = vec3<f32>(0.0, r, 0.0) + view * t;
        let r_p = atm.shape.x + h;
        let mu_s = dot(p, sun) / max(length(p), 1e-3);
        let sigma_r = atm.rayleigh.xyz * exp(-h / atm.rayleigh.w);
        let sigma_m = atm.mie_scattering.xyz * exp(-h / atm.mie_scattering.w);
        let single = (sigma_r * ray.phase_r + sigma_m * ray.phase_m) * sun_transmittance(atm, r_p, mu_s);
        let multiple = (sigma_r + sigma_m) * sample_multiscattering(atm, r_p, mu_s);
        sum += (single + multiple) * exp(-tau_mid) * dt;
    }
    return sum;
}
