//! requires: sky_model/atmosphere
// The transmittance table's parametrisation (Bruneton 2017), shared by the `lut` and `precomputed`
// models, the texel build, and the bilinear addressing of tables stored as arrays of texel centres.

// Bruneton's transmittance mapping: u from the distance to the top, v from the radius.
fn transmittance_uv(atm: Atmosphere, r: f32, mu: f32) -> vec2<f32> {
    let ground = atm.shape.x;
    let top = atm.shape.y;
    let h = sqrt(max(top * top - ground * ground, 0.0));
    let rho = sqrt(max(r * r - ground * ground, 0.0));
    let d = distance_to_top(atm, r, mu);
    let d_min = top - r;
    let d_max = rho + h;
    return vec2<f32>(clamp((d - d_min) / max(d_max - d_min, 1e-6), 0.0, 1.0), clamp(rho / h, 0.0, 1.0));
}

fn transmittance_r_mu(atm: Atmosphere, uv: vec2<f32>) -> vec2<f32> {
    let ground = atm.shape.x;
    let top = atm.shape.y;
    let h = sqrt(max(top * top - ground * ground, 0.0));
    let rho = h * uv.y;
    let r = sqrt(rho * rho + ground * ground);
    let d_min = top - r;
    let d_max = rho + h;
    let d = d_min + uv.x * (d_max - d_min);
    var mu = 1.0;
    if (d > 1e-6) {
        mu = clamp((h * h - rho * rho - d * d) / (2.0 * r * d), -1.0, 1.0);
    }
    return vec2<f32>(r, mu);
}

// Bilinear read of a width x height table of texel centres spanning uv in [0, 1].
fn bilinear_index(size: vec2<u32>, uv: vec2<f32>) -> vec4<f32> {
    let p = clamp(uv, vec2<f32>(0.0), vec2<f32>(1.0)) * vec2<f32>(size - vec2<u32>(1u));
    let i = min(vec2<u32>(floor(p)), size - vec2<u32>(2u));
    let f = p - vec2<f32>(i);
    return vec4<f32>(f32(i.y * size.x + i.x), f32(size.x), f.x, f.y);
}

// Transmittance from radius r along cosine mu to the top of the atmosphere for the texel at `uv`,
// by the midpoint rule with `steps` samples (rays of this table never meet the ground: mu is above
// the horizon by construction).
fn transmittance_texel(atm: Atmosphere, uv: vec2<f32>, steps: u32) -> vec3<f32> {
    let r_mu = transmittance_r_mu(atm, uv);
    let length_km = distance_to_top(atm, r_mu.x, r_mu.y);
    let n = max(steps, 1u);
    let dt = length_km / f32(n);
    var tau = vec3<f32>(0.0);
    for (var i = 0u; i < n; i++) {
        tau += extinction_at(atm, altitude_along(atm, r_mu.x, r_mu.y, (f32(i) + 0.5) * dt)) * dt;
    }
    return exp(-tau);
}
