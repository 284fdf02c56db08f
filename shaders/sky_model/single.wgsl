//! requires: sky_model/atmosphere
// Single scattering by ray marching (the `single` sky model). Radiance in sr^-1 per unit of solar
// irradiance. Keep `SingleSettings` in sync with `SingleUniform` in src/render/atmosphere/uniforms.rs.
struct SingleSettings {
    view_steps: u32,    // samples along the view ray
    sun_steps: u32,     // samples towards the sun (numerical optical depth only)
    numeric: u32,       // 0: erf optical depth towards the sun, 1: numerical integration
    _pad: u32,
};

fn sun_optical_depth(atm: Atmosphere, s: SingleSettings, r: f32, h: f32, mu_s: f32) -> vec3<f32> {
    if (s.numeric != 0u) {
        return numeric_optical_depth(atm, r, mu_s, s.sun_steps);
    }
    return erf_optical_depth(atm, r, h, mu_s);
}

// Sky radiance seen from `camera_km` along the unit `view` (y up), sun along the unit `sun`.
fn single_scattering(atm: Atmosphere, s: SingleSettings, camera_km: f32, view: vec3<f32>, sun: vec3<f32>) -> vec3<f32> {
    let ray = view_ray(atm, camera_km, view, sun);
    let r = ray.r;
    let mu = ray.mu;
    let n = max(s.view_steps, 1u);
    var tau = vec3<f32>(0.0);
    var sum = vec3<f32>(0.0);
    for (var i = 0u; i < n; i++) {
        let step = march_step(atm, r, mu, crowded_sample(ray.distance_km, i, n), &tau);
        let h = step.altitude_km;
        // The sample's own frame: radius and the sun's cosine to its vertical.
        let p = vec3<f32>(0.0, r, 0.0) + view * step.t;
        let r_p = atm.shape.x + h;
        let mu_s = dot(p, sun) / max(length(p), 1e-3);
        // The visible part of the sun's disc is seen at grazing incidence at worst.
        let visible = sun_visible_fraction(atm, r_p, mu_s);
        if (visible > 0.0) {
            let tau_sun = sun_optical_depth(atm, s, r_p, h, max(mu_s, horizon_mu(atm, r_p) + 1e-4));
            if (tau_sun.x >= 0.0) {
                let sigma = scattering_at(atm, h);
                let scattering = sigma.rayleigh * ray.phase_r + sigma.mie * ray.phase_m;
                sum += visible * scattering * exp(-(step.tau_mid + tau_sun)) * step.dt;
            }
        }
    }
    return sum;
}
