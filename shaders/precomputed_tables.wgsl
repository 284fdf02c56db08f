//! requires: sky_model/precomputed_sampling
// Precomputed-tables pass (compute phase): builds the `precomputed` model's tables (after
// Bruneton 2017) only when the atmosphere, the settings or the ground albedo change.
// Transmittance, direct irradiance and single scattering first; then, per higher order, its
// scattering density, the irradiance of the order below, and the order's scattering, each added
// to the totals. One invocation per texel; the header and layout are in
// sky_model/precomputed_sampling.wgsl. Keep in sync with src/render/atmosphere/precomputed_tables.rs.
@group(1) @binding(0) var<uniform> atmosphere: Atmosphere;
@group(1) @binding(1) var<storage, read_write> precomputed_tables: array<vec4<f32>>;
// This dispatch's slice of its table: first texel, texel count (at a dynamic offset per step;
// a software rasteriser spreads a build over frames).
@group(1) @binding(2) var<uniform> cursor: vec4<u32>;

// The texel of invocation `gid` in this dispatch's slice, or none past its end or `texels`.
fn slice_texel(gid: u32, texels: u32) -> u32 {
    if (gid >= cursor.y || cursor.x + gid >= texels) {
        return 0xffffffffu;
    }
    return cursor.x + gid;
}

@compute @workgroup_size(64)
fn cs_transmittance(@builtin(global_invocation_id) gid: vec3<u32>) {
    let h = pre_header();
    let size = h.sizes_2d.xy;
    let texel = slice_texel(gid.x, size.x * size.y);
    if (texel == 0xffffffffu) {
        return;
    }
    let uv = vec2<f32>(vec2<u32>(texel % size.x, texel / size.x)) / vec2<f32>(size - vec2<u32>(1u));
    precomputed_tables[pre_offset_2d(h, 0u) + texel] = vec4<f32>(transmittance_texel(atmosphere, uv, h.steps.x), 1.0);
}

fn irradiance_texel(h: PrecomputedHeader, index: u32) -> vec2<f32> {
    let size = h.sizes_2d.zw;
    let uv = vec2<f32>(vec2<u32>(index % size.x, index / size.x)) / vec2<f32>(size - vec2<u32>(1u));
    return vec2<f32>(atmosphere.shape.x + uv.y * (atmosphere.shape.y - atmosphere.shape.x), 2.0 * uv.x - 1.0);
}

// Direct irradiance on a horizontal surface (the order-1 ground light); the total indirect
// irradiance starts at zero.
@compute @workgroup_size(64)
fn cs_direct_irradiance(@builtin(global_invocation_id) gid: vec3<u32>) {
    let h = pre_header();
    let texel = slice_texel(gid.x, h.sizes_2d.z * h.sizes_2d.w);
    if (texel == 0xffffffffu) {
        return;
    }
    let r_mu_s = irradiance_texel(h, texel);
    let direct = pre_sun_transmittance(atmosphere, h, r_mu_s.x, r_mu_s.y) * max(r_mu_s.y, 0.0);
    precomputed_tables[pre_offset_2d(h, PRE_DELTA_IRRADIANCE) + texel] = vec4<f32>(direct, 1.0);
    precomputed_tables[pre_offset_2d(h, PRE_IRRADIANCE) + texel] = vec4<f32>(0.0, 0.0, 0.0, 1.0);
}

// Length of a texel's ray: to the ground for the ground half (to the tangent point where
// rounding misses the ground), else to the top.
fn ray_length(g: PreGeometry) -> f32 {
    if (g.ground) {
        let d = distance_to_ground(atmosphere, g.r, g.mu);
        return select(sqrt(max(g.r * g.r - atmosphere.shape.x * atmosphere.shape.x, 0.0)), d, d >= 0.0);
    }
    return distance_to_top(atmosphere, g.r, g.mu);
}

// Sample i of n along a texel's ray of `length`: its midpoint and length, crowded towards the
// ray's lowest point where the air is densest (its start going up, its end on the ground, the
// tangent point between for rays that dip and leave). Samples come in order of distance.
fn ray_sample(g: PreGeometry, length: f32, i: u32, n: u32) -> vec2<f32> {
    if (g.ground) {
        let s = crowded_sample(length, n - 1u - i, n);
        return vec2<f32>(length - s.x, s.y);
    }
    if (g.mu >= 0.0 || n < 2u) {
        return crowded_sample(length, i, n);
    }
    let lowest = min(-g.r * g.mu, length);
    let first = n / 2u;
    if (i < first) {
        let s = crowded_sample(lowest, first - 1u - i, first);
        return vec2<f32>(lowest - s.x, s.y);
    }
    let s = crowded_sample(length - lowest, i - first, n - first);
    return vec2<f32>(lowest + s.x, s.y);
}

// Radius and sun cosine at distance t along a texel's ray.
fn along(g: PreGeometry, t: f32) -> vec2<f32> {
    let r_t = clamp(sqrt(max(t * t + 2.0 * g.r * g.mu * t + g.r * g.r, 0.0)), atmosphere.shape.x, atmosphere.shape.y);
    return vec2<f32>(r_t, clamp((g.r * g.mu_s + t * g.nu) / r_t, -1.0, 1.0));
}

// One sample of a texel's ray march: its distance, radius and sun cosine there (`along`), its
// altitude, and its weight: the view ray's transmittance to the sample's middle times its length.
// Adds the sample's optical depth to `tau` (samples come in order of distance).
struct MarchSample {
    t: f32,
    at: vec2<f32>,
    alt: f32,
    weight: vec3<f32>,
};

fn march_sample(g: PreGeometry, length: f32, i: u32, n: u32, tau: ptr<function, vec3<f32>>) -> MarchSample {
    let step = march_step(atmosphere, g.r, g.mu, ray_sample(g, length, i, n), tau);
    return MarchSample(step.t, along(g, step.t), max(step.altitude_km, 0.0), exp(-step.tau_mid) * step.dt);
}

// Single scattering by the midpoint rule (`ray_sample`), the view ray's optical depth summed along the march
// (exact for the samples, unlike ratios of table values near the horizon) and the sun's from the
// transmittance table. Rayleigh and Mie without their phase functions.
@compute @workgroup_size(64)
fn cs_single(@builtin(global_invocation_id) gid: vec3<u32>) {
    let h = pre_header();
    let texel = slice_texel(gid.x, pre_texels_4d(h));
    if (texel == 0xffffffffu) {
        return;
    }
    let g = pre_geometry(atmosphere, h, texel);
    let n = max(h.steps.y, 1u);
    let length = ray_length(g);
    var tau = vec3<f32>(0.0);
    var rayleigh = vec3<f32>(0.0);
    var mie = vec3<f32>(0.0);
    for (var i = 0u; i < n; i++) {
        let m = march_sample(g, length, i, n, &tau);
        let light = m.weight * pre_sun_transmittance(atmosphere, h, m.at.x, m.at.y);
        let density = densities_at(atmosphere, m.alt);
        rayleigh += light * density.x;
        mie += light * density.y;
    }
    rayleigh *= atmosphere.rayleigh.xyz;
    mie *= atmosphere.mie_scattering.xyz;
    precomputed_tables[pre_offset_4d(h, PRE_DELTA) + texel] = vec4<f32>(rayleigh, 1.0);
    precomputed_tables[pre_offset_4d(h, PRE_DELTA_MIE) + texel] = vec4<f32>(mie, 1.0);
    precomputed_tables[pre_offset_4d(h, PRE_SCATTERING) + texel] = vec4<f32>(rayleigh, 1.0);
    precomputed_tables[pre_offset_4d(h, PRE_SINGLE_MIE) + texel] = vec4<f32>(mie, 1.0);
}

// Radiance of the previous order arriving at radius r from direction cosine mu (sun cosine mu_s,
// cosine nu between the direction and the sun): single scattering with its phase functions after
// order 1, else the previous order's table.
fn incoming(h: PrecomputedHeader, r: f32, mu: f32, mu_s: f32, nu: f32, ground: bool, after_single: bool) -> vec3<f32> {
    let c = pre_coords(atmosphere, r, mu, mu_s, nu, ground, h.ground.y);
    if (after_single) {
        return pre_read_4d(h, PRE_DELTA, c) * rayleigh_phase(nu) + pre_read_4d(h, PRE_DELTA_MIE, c) * cornette_shanks_phase(nu, atmosphere.mie_extinction.w);
    }
    return pre_read_4d(h, PRE_DELTA, c);
}

// The sun for a texel: y up, the view in the x-y plane at cosine mu.
fn sun_for(mu: f32, mu_s: f32, nu: f32) -> vec3<f32> {
    let sin_mu = sqrt(max(1.0 - mu * mu, 0.0));
    let x = select(0.0, (nu - mu * mu_s) / sin_mu, sin_mu > 1e-5);
    return vec3<f32>(x, mu_s, sqrt(max(1.0 - x * x - mu_s * mu_s, 0.0)));
}

// Scattering density of the next order at a texel: light of the previous order from every
// direction (and from the ground, lit by the previous order's irradiance) scattered towards the
// texel's view direction, km^-1 sr^-1.
fn density(invocation: u32, after_single: bool) {
    let h = pre_header();
    let gid = slice_texel(invocation, pre_texels_4d(h));
    if (gid == 0xffffffffu) {
        return;
    }
    let g = pre_geometry(atmosphere, h, gid);
    let view = vec3<f32>(sqrt(max(1.0 - g.mu * g.mu, 0.0)), g.mu, 0.0);
    let sun = sun_for(g.mu, g.mu_s, g.nu);
    let alt = g.r - atmosphere.shape.x;
    let scattering = scattering_at(atmosphere, alt);
    let sigma_r = scattering.rayleigh;
    let sigma_m = scattering.mie;
    let n_theta = max(h.steps.z, 2u);
    let d_angle = PI / f32(n_theta);
    let albedo = h.ground.x;
    var sum = vec3<f32>(0.0);
    for (var i = 0u; i < n_theta; i++) {
        let theta = (f32(i) + 0.5) * d_angle;
        let cos_t = cos(theta);
        let sin_t = sin(theta);
        let d_ground = distance_to_ground(atmosphere, g.r, cos_t);
        let hits = d_ground >= 0.0;
        var t_ground = vec3<f32>(0.0);
        if (hits && albedo > 0.0) {
            // Transmittance to the ground: up from the ground through this point, over the part above it.
            let mu_ground = (g.r * cos_t + d_ground) / atmosphere.shape.x;
            t_ground = min(pre_transmittance(atmosphere, h, atmosphere.shape.x, -mu_ground) / max(pre_transmittance(atmosphere, h, g.r, -cos_t), vec3<f32>(1e-20)), vec3<f32>(1.0));
        }
        for (var j = 0u; j < 2u * n_theta; j++) {
            let phi = (f32(j) + 0.5) * d_angle;
            let w = vec3<f32>(sin_t * cos(phi), cos_t, sin_t * sin(phi));
            let nu_w = dot(w, sun);
            var light = incoming(h, g.r, cos_t, g.mu_s, nu_w, hits, after_single);
            if (hits && albedo > 0.0) {
                let normal = normalize(vec3<f32>(0.0, g.r, 0.0) + w * d_ground);
                light += t_ground * (albedo / PI) * pre_irradiance(atmosphere, h, PRE_DELTA_IRRADIANCE, atmosphere.shape.x, dot(normal, sun));
            }
            let cos_view = dot(view, w);
            let phase = sigma_r * rayleigh_phase(cos_view) + sigma_m * cornette_shanks_phase(cos_view, atmosphere.mie_extinction.w);
            sum += light * phase * (sin_t * d_angle * d_angle);
        }
    }
    precomputed_tables[pre_offset_4d(h, PRE_DENSITY) + gid] = vec4<f32>(sum, 1.0);
}

@compute @workgroup_size(64)
fn cs_density_second(@builtin(global_invocation_id) gid: vec3<u32>) {
    density(gid.x, true);
}

@compute @workgroup_size(64)
fn cs_density_higher(@builtin(global_invocation_id) gid: vec3<u32>) {
    density(gid.x, false);
}

// Irradiance on a horizontal surface from the previous order's sky, added to the total.
fn indirect_irradiance(invocation: u32, after_single: bool) {
    let h = pre_header();
    let gid = slice_texel(invocation, h.sizes_2d.z * h.sizes_2d.w);
    if (gid == 0xffffffffu) {
        return;
    }
    let r_mu_s = irradiance_texel(h, gid);
    let sun = vec3<f32>(sqrt(max(1.0 - r_mu_s.y * r_mu_s.y, 0.0)), r_mu_s.y, 0.0);
    let n_theta = max(h.steps.z / 2u, 1u);
    let d_angle = 0.5 * PI / f32(n_theta);
    var sum = vec3<f32>(0.0);
    for (var i = 0u; i < n_theta; i++) {
        let theta = (f32(i) + 0.5) * d_angle;
        let cos_t = cos(theta);
        let sin_t = sin(theta);
        for (var j = 0u; j < 4u * n_theta; j++) {
            let phi = (f32(j) + 0.5) * d_angle;
            let w = vec3<f32>(sin_t * cos(phi), cos_t, sin_t * sin(phi));
            sum += incoming(h, r_mu_s.x, cos_t, r_mu_s.y, dot(w, sun), false, after_single) * (cos_t * sin_t * d_angle * d_angle);
        }
    }
    precomputed_tables[pre_offset_2d(h, PRE_DELTA_IRRADIANCE) + gid] = vec4<f32>(sum, 1.0);
    let total = pre_offset_2d(h, PRE_IRRADIANCE) + gid;
    precomputed_tables[total] = vec4<f32>(precomputed_tables[total].xyz + sum, 1.0);
}

@compute @workgroup_size(64)
fn cs_indirect_first(@builtin(global_invocation_id) gid: vec3<u32>) {
    indirect_irradiance(gid.x, true);
}

@compute @workgroup_size(64)
fn cs_indirect_higher(@builtin(global_invocation_id) gid: vec3<u32>) {
    indirect_irradiance(gid.x, false);
}

// Largest ratio of one order to the one below that the tail assumes: a texel whose orders do not
// fall (rounding where both are nearly zero) adds at most its last order again.
const TAIL_MAX_RATIO: f32 = 0.5;
// Sun cosines at a texel's point over which the tail fades out below the horizon (0 to about -6
// degrees).
const TAIL_FADE_MU_S: vec2<f32> = vec2<f32>(-0.1, 0.0);

// The next order's scattering: its density integrated along the texel's ray, written as the new
// delta and added to the total divided by the Rayleigh phase (the lookup multiplies it back).
// After the last order (`last`, from order 3 on) the orders above it are added as a geometric
// series with the ratio of this order to the one below, per texel and channel: orders fall by a
// nearly constant factor once the light has forgotten the sun's direction, and that factor is
// highest in blue, which four orders alone left 3% too dark. In the Earth's shadow the orders
// have not settled into that fall (the first ones are missing, the next ones rise), so the ratio
// of the last two overstates the rest: there the tail fades out (measured: twilight 8% too
// bright at -6 degrees with it, p95 20% against 15% without).
fn multiple(invocation: u32, last: bool) {
    let h = pre_header();
    let texel = slice_texel(invocation, pre_texels_4d(h));
    if (texel == 0xffffffffu) {
        return;
    }
    let g = pre_geometry(atmosphere, h, texel);
    let n = max(h.steps.y, 1u);
    let length = ray_length(g);
    var tau = vec3<f32>(0.0);
    var sum = vec3<f32>(0.0);
    for (var i = 0u; i < n; i++) {
        let m = march_sample(g, length, i, n, &tau);
        let mu_t = clamp((g.r * g.mu + m.t) / m.at.x, -1.0, 1.0);
        let c = pre_coords(atmosphere, m.at.x, mu_t, m.at.y, g.nu, g.ground, h.ground.y);
        sum += m.weight * pre_read_4d(h, PRE_DENSITY, c);
    }
    let delta = pre_offset_4d(h, PRE_DELTA) + texel;
    var added = sum;
    if (last) {
        let below = precomputed_tables[delta].xyz;
        let ratio = clamp(sum / max(below, vec3<f32>(1e-30)), vec3<f32>(0.0), vec3<f32>(TAIL_MAX_RATIO));
        let lit = smoothstep(TAIL_FADE_MU_S.x, TAIL_FADE_MU_S.y, g.mu_s);
        added = sum + lit * sum * ratio / (vec3<f32>(1.0) - ratio);
    }
    precomputed_tables[delta] = vec4<f32>(sum, 1.0);
    let total = pre_offset_4d(h, PRE_SCATTERING) + texel;
    precomputed_tables[total] = vec4<f32>(precomputed_tables[total].xyz + added / rayleigh_phase(g.nu), 1.0);
}

@compute @workgroup_size(64)
fn cs_multiple(@builtin(global_invocation_id) gid: vec3<u32>) {
    multiple(gid.x, false);
}

@compute @workgroup_size(64)
fn cs_multiple_last(@builtin(global_invocation_id) gid: vec3<u32>) {
    multiple(gid.x, true);
}

// Half-precision storage: packs the finished scattering and single-Mie tables into one
// (`pre_pack_half`), the last step of the build.
@compute @workgroup_size(64)
fn cs_pack_half(@builtin(global_invocation_id) gid: vec3<u32>) {
    let h = pre_header();
    let texel = slice_texel(gid.x, pre_texels_4d(h));
    if (texel == 0xffffffffu) {
        return;
    }
    let s = precomputed_tables[pre_offset_4d(h, PRE_SCATTERING) + texel].xyz;
    let m = precomputed_tables[pre_offset_4d(h, PRE_SINGLE_MIE) + texel].xyz;
    precomputed_tables[pre_offset_4d(h, PRE_PACKED) + texel] = pre_pack_half(s, m);
}
