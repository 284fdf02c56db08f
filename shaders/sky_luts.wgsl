//! requires: sky_model/lut_sampling
// Sky LUTs pass (compute phase): the `lut` model's transmittance and multiple-scattering tables
// (Hillaire 2020), rebuilt only when the atmosphere or the LUT settings change. Tables are
// storage buffers of vec4 (rgb, unused) read with bilinear_index.
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

// One texel per invocation: Psi_ms = L_2nd / (1 - f_ms), both averaged over a stratified sphere
// of directions, each ray marched with isotropic phase (Hillaire 2020, section 5.5).
@compute @workgroup_size(64)
fn cs_multiscattering(@builtin(global_invocation_id) gid: vec3<u32>) {
    let n = lut_params.sizes.z;
    if (gid.x >= n * n) {
        return;
    }
    let id = vec2<u32>(gid.x % n, gid.x / n);
    let uv = vec2<f32>(id) / f32(n - 1u);
    let mu_s = uv.x * 2.0 - 1.0;
    let r = atmosphere.shape.x + max(uv.y * (atmosphere.shape.y - atmosphere.shape.x), 0.01);
    let sun = vec3<f32>(sqrt(max(1.0 - mu_s * mu_s, 0.0)), mu_s, 0.0);
    let albedo = lut_params.ground.x;
    let sqrt_dirs = max(lut_params.sizes.w, 1u);
    let steps = max(lut_params.steps.y, 1u);
    var l2 = vec3<f32>(0.0);
    var f_ms = vec3<f32>(0.0);
    for (var a = 0u; a < sqrt_dirs; a++) {
        for (var b = 0u; b < sqrt_dirs; b++) {
            // Equal-area stratification of the sphere.
            let cos_theta = 1.0 - 2.0 * (f32(a) + 0.5) / f32(sqrt_dirs);
            let phi = 2.0 * PI * (f32(b) + 0.5) / f32(sqrt_dirs);
            let sin_theta = sqrt(max(1.0 - cos_theta * cos_theta, 0.0));
            let dir = vec3<f32>(sin_theta * cos(phi), cos_theta, sin_theta * sin(phi));
            let mu = dir.y;
            let ground = distance_to_ground(atmosphere, r, mu);
            var ray_length = distance_to_top(atmosphere, r, mu);
            if (ground >= 0.0) {
                ray_length = ground;
            }
            let dt = ray_length / f32(steps);
            var tau = vec3<f32>(0.0);
            var l = vec3<f32>(0.0);
            var f = vec3<f32>(0.0);
            for (var i = 0u; i < steps; i++) {
                let t = (f32(i) + 0.5) * dt;
                let h = max(altitude_along(atmosphere, r, mu, t), 0.0);
                let e = extinction_at(atmosphere, h);
                let tau_mid = tau + e * (0.5 * dt);
                tau += e * dt;
                let p = vec3<f32>(0.0, r, 0.0) + dir * t;
                let r_p = atmosphere.shape.x + h;
                let mu_p = dot(p, sun) / max(length(p), 1e-3);
                let sigma_s = atmosphere.rayleigh.xyz * exp(-h / atmosphere.rayleigh.w) + atmosphere.mie_scattering.xyz * exp(-h / atmosphere.mie_scattering.w);
                let t_view = exp(-tau_mid);
                l += t_view * sigma_s * sun_transmittance(atmosphere, r_p, mu_p) / (4.0 * PI) * dt;
                f += t_view * sigma_s * dt;
            }
            if (ground >= 0.0 && albedo > 0.0) {
                let p = vec3<f32>(0.0, r, 0.0) + dir * ray_length;
                let normal = normalize(p);
                let mu_g = dot(normal, sun);
                l += exp(-tau) * sun_transmittance(atmosphere, atmosphere.shape.x, mu_g) * max(mu_g, 0.0) * albedo / PI;
            }
            l2 += l;
            f_ms += f;
        }
    }
    // Integrals over the sphere with the isotropic phase 1 / (4 pi) are means over directions.
    let count = f32(sqrt_dirs * sqrt_dirs);
    let second = l2 / count;
    let transfer = f_ms / count;
    multiscattering_lut[gid.x] = vec4<f32>(second / max(vec3<f32>(1.0) - transfer, vec3<f32>(1e-3)), 1.0);
}
