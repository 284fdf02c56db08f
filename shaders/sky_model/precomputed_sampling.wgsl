//! requires: sky_model/transmittance_map
// The `precomputed` model (after Bruneton 2017, precomputed atmospheric scattering): the layout of
// its tables, their parametrisations, and the sky radiance looked up from them. A library: the
// module that requires it declares `precomputed_tables` (read-only where the model is looked up,
// read-write in precomputed_tables.wgsl, which builds them).
//
// Everything lives in one storage buffer of vec4 (the stage's storage-buffer budget is 8):
// a header (`PrecomputedHeader`, 4 vec4), then the 2D tables (transmittance; irradiance; its
// delta of the order being built), then five 4D tables of the same size. Keep the header and the
// offsets in sync with src/render/atmosphere/tables.rs (the header) and precomputed_tables.rs.
struct PrecomputedHeader {
    sizes_2d: vec4<u32>, // transmittance width, height; irradiance width, height
    sizes_4d: vec4<u32>, // scattering table texels along nu, mu_s, mu (both halves), r
    steps: vec4<u32>,    // transmittance samples, samples along rays, density directions per half turn, precision (0 single, 1 half)
    ground: vec4<f32>,   // ground albedo, smallest sun cosine tabulated, unused
};

// The 4D tables, in order after the 2D ones.
const PRE_SCATTERING: u32 = 0u;   // single Rayleigh + every higher order divided by the Rayleigh phase
const PRE_SINGLE_MIE: u32 = 1u;   // single Mie, without its phase function
const PRE_DELTA: u32 = 2u;        // single Rayleigh of order 1, then the last order's scattering
const PRE_DELTA_MIE: u32 = 3u;    // single Mie of order 1 (read by order 2 only)
const PRE_DENSITY: u32 = 4u;      // scattering density of the order being built, km^-1 sr^-1
// With half-precision storage, the last build step packs the scattering and single-Mie tables
// into this one (the first delta's place, free once the build is done): per texel, six halves
// of the two tables times PRE_HALF_SCALE, so that one 16-byte read serves both.
const PRE_PACKED: u32 = 2u;
// Keeps twilight's small values normal halves (below 6e-5 a half loses precision). Values above
// 65504 / 4096 = 16 would be clamped; the tables hold radiance over a phase function, a few
// units at most at the horizon of a hazy sky (tests/sky_models.rs compares half with single
// precision in one).
const PRE_HALF_SCALE: f32 = 4096.0;
// The 2D tables after the transmittance.
const PRE_IRRADIANCE: u32 = 1u;       // indirect irradiance, every order so far
const PRE_DELTA_IRRADIANCE: u32 = 2u; // the last order's irradiance (direct for order 1)

fn pre_header() -> PrecomputedHeader {
    let a = bitcast<vec4<u32>>(precomputed_tables[0]);
    let b = bitcast<vec4<u32>>(precomputed_tables[1]);
    let c = bitcast<vec4<u32>>(precomputed_tables[2]);
    return PrecomputedHeader(a, b, c, precomputed_tables[3]);
}

const PRE_HEADER_TEXELS: u32 = 4u;

fn pre_texels_4d(h: PrecomputedHeader) -> u32 {
    return h.sizes_4d.x * h.sizes_4d.y * h.sizes_4d.z * h.sizes_4d.w;
}

// First texel of 2D table `table` (0: transmittance).
fn pre_offset_2d(h: PrecomputedHeader, table: u32) -> u32 {
    if (table == 0u) {
        return PRE_HEADER_TEXELS;
    }
    return PRE_HEADER_TEXELS + h.sizes_2d.x * h.sizes_2d.y + (table - 1u) * h.sizes_2d.z * h.sizes_2d.w;
}

fn pre_offset_4d(h: PrecomputedHeader, table: u32) -> u32 {
    return pre_offset_2d(h, 3u) + table * pre_texels_4d(h);
}

fn pre_bilinear(offset: u32, size: vec2<u32>, uv: vec2<f32>) -> vec3<f32> {
    let b = bilinear_index(size, uv);
    let k = offset + u32(b.x);
    let w = u32(b.y);
    let top = mix(precomputed_tables[k].xyz, precomputed_tables[k + 1u].xyz, b.z);
    let bottom = mix(precomputed_tables[k + w].xyz, precomputed_tables[k + w + 1u].xyz, b.z);
    return mix(top, bottom, b.w);
}

fn pre_transmittance(atm: Atmosphere, h: PrecomputedHeader, r: f32, mu: f32) -> vec3<f32> {
    return pre_bilinear(pre_offset_2d(h, 0u), h.sizes_2d.xy, transmittance_uv(atm, r, mu));
}

// Transmittance to the sun times its visible fraction, as the other models take it
// (`sun_transmittance` in lut_sampling.wgsl).
fn pre_sun_transmittance(atm: Atmosphere, h: PrecomputedHeader, r: f32, mu_s: f32) -> vec3<f32> {
    let visible = sun_visible_fraction(atm, r, mu_s);
    if (visible <= 0.0) {
        return vec3<f32>(0.0);
    }
    return visible * pre_transmittance(atm, h, r, max(mu_s, horizon_mu(atm, r) + 1e-4));
}

// Irradiance tables: u = (mu_s + 1) / 2, v = altitude / thickness.
fn pre_irradiance_uv(atm: Atmosphere, r: f32, mu_s: f32) -> vec2<f32> {
    return vec2<f32>(0.5 * (mu_s + 1.0), (r - atm.shape.x) / (atm.shape.y - atm.shape.x));
}

fn pre_irradiance(atm: Atmosphere, h: PrecomputedHeader, table: u32, r: f32, mu_s: f32) -> vec3<f32> {
    return pre_bilinear(pre_offset_2d(h, table), h.sizes_2d.zw, pre_irradiance_uv(atm, r, mu_s));
}

// A point of the 4D tables: coordinates in [0, 1] along nu, mu_s, mu (within its half) and r, and
// the half of the mu axis: 0 for rays that end on the ground, 1 for rays that leave the
// atmosphere. Interpolation never mixes the halves, so the horizon stays sharp.
struct PreCoords {
    x: vec4<f32>,
    half_index: u32,
};

// A texel's geometry (the inverse of `pre_coords`).
struct PreGeometry {
    r: f32,
    mu: f32,
    mu_s: f32,
    nu: f32,
    ground: bool,
};

fn pre_h(atm: Atmosphere) -> f32 {
    return sqrt(max(atm.shape.y * atm.shape.y - atm.shape.x * atm.shape.x, 0.0));
}

// Half the range of nu that mu and mu_s allow: nu = mu mu_s + cos(azimuth) spread.
fn pre_nu_spread(mu: f32, mu_s: f32) -> f32 {
    return sqrt(max((1.0 - mu * mu) * (1.0 - mu_s * mu_s), 0.0));
}

// The nu axis is the cosine of the azimuth between the view and the sun rather than nu itself
// (Bruneton's axis): every texel is then a possible geometry, so none is clamped, and a fixed
// azimuth reads the same geometry from neighbouring mu_s and mu texels. With nu itself, a view
// near the sun's azimuth or opposite it read neighbours clamped to other azimuths: with the sun
// 60 to 75 degrees up, where the mu_s texels lie far apart, the sky was 7% too bright towards the
// sun's azimuth and 5% too dark away from it. Where the azimuth is undefined (view or sun
// vertical) nothing depends on it.
fn pre_cos_azimuth(mu: f32, mu_s: f32, nu: f32) -> f32 {
    let spread = pre_nu_spread(mu, mu_s);
    return select(1.0, clamp((nu - mu * mu_s) / spread, -1.0, 1.0), spread > 1e-6);
}

// The sun axis: Bruneton's mapping (the distance to the top from the ground: fine around the
// horizon, nothing below `mu_s_min`) plus a term linear in the sun's elevation. Bruneton's
// mapping alone is quadratic in the sun's zenith angle near the zenith: at 32 texels its last one
// spanned the sun from 53 to 90 degrees up, and a sun between them read 4.5% off towards and away
// from its azimuth (42 dB where the rest of the day reads 46 to 53). The linear term bounds the
// spacing there and costs little near the horizon, where Bruneton's term is steep.
const PRE_MU_S_LINEAR: f32 = 0.15; // per radian of elevation, against Bruneton's 0..1

fn pre_mu_s_bruneton(atm: Atmosphere, mu_s: f32, mu_s_min: f32) -> f32 {
    let hh = pre_h(atm);
    let d_min = atm.shape.y - atm.shape.x;
    let d_max = hh;
    let a = (distance_to_top(atm, atm.shape.x, mu_s) - d_min) / (d_max - d_min);
    let big_a = (distance_to_top(atm, atm.shape.x, mu_s_min) - d_min) / (d_max - d_min);
    return max(1.0 - a / big_a, 0.0) / (1.0 + a);
}

fn pre_mu_s_warp(atm: Atmosphere, mu_s: f32, mu_s_min: f32) -> f32 {
    return pre_mu_s_bruneton(atm, mu_s, mu_s_min) + PRE_MU_S_LINEAR * asin(clamp(mu_s, -1.0, 1.0));
}

// The warp at `mu_s_min` and at the zenith, where Bruneton's term is 0 and 1 by construction.
fn pre_mu_s_warp_range(mu_s_min: f32) -> vec2<f32> {
    return vec2<f32>(PRE_MU_S_LINEAR * asin(clamp(mu_s_min, -1.0, 1.0)), 1.0 + PRE_MU_S_LINEAR * 0.5 * PI);
}

fn pre_x_mu_s(atm: Atmosphere, mu_s: f32, mu_s_min: f32) -> f32 {
    let range = pre_mu_s_warp_range(mu_s_min);
    return clamp((pre_mu_s_warp(atm, max(mu_s, mu_s_min), mu_s_min) - range.x) / (range.y - range.x), 0.0, 1.0);
}

// The inverse of `pre_x_mu_s`, by bisection on the elevation (the warp is increasing; only the
// build calls this, once per texel).
fn pre_mu_s_from_x(atm: Atmosphere, x: f32, mu_s_min: f32) -> f32 {
    var lo = asin(clamp(mu_s_min, -1.0, 1.0));
    var hi = 0.5 * PI;
    let range = pre_mu_s_warp_range(mu_s_min);
    let target_warp = mix(range.x, range.y, clamp(x, 0.0, 1.0));
    for (var i = 0u; i < 32u; i++) {
        let mid = 0.5 * (lo + hi);
        if (pre_mu_s_warp(atm, sin(mid), mu_s_min) < target_warp) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    return sin(0.5 * (lo + hi));
}

fn pre_coords(atm: Atmosphere, r_in: f32, mu: f32, mu_s: f32, nu: f32, ground: bool, mu_s_min: f32) -> PreCoords {
    let hh = pre_h(atm);
    let r = clamp(r_in, atm.shape.x, atm.shape.y);
    let rho = sqrt(max(r * r - atm.shape.x * atm.shape.x, 0.0));
    var x_mu: f32;
    var half_index: u32;
    if (ground) {
        // Distance to the ground, from straight down (r - R) to the horizon (rho).
        let disc = r * r * mu * mu - rho * rho;
        let d = -r * mu - sqrt(max(disc, 0.0));
        let d_min = r - atm.shape.x;
        let d_max = rho;
        x_mu = select(0.0, (d - d_min) / (d_max - d_min), d_max > d_min + 1e-6);
        half_index = 0u;
    } else {
        // Distance to the top, from straight up (T - r) to the horizon (rho + H).
        let d = distance_to_top(atm, r, mu);
        let d_min = atm.shape.y - r;
        let d_max = rho + hh;
        x_mu = (d - d_min) / max(d_max - d_min, 1e-6);
        half_index = 1u;
    }
    let x = vec4<f32>(0.5 * (pre_cos_azimuth(mu, mu_s, nu) + 1.0), pre_x_mu_s(atm, mu_s, mu_s_min), x_mu, rho / hh);
    return PreCoords(clamp(x, vec4<f32>(0.0), vec4<f32>(1.0)), half_index);
}

// The geometry of texel `index` of a 4D table (texels at coordinates i / (n - 1) in each half).
fn pre_geometry(atm: Atmosphere, h: PrecomputedHeader, index: u32) -> PreGeometry {
    let n = h.sizes_4d;
    let half_mu = n.z / 2u;
    let i_nu = index % n.x;
    let i_mu_s = (index / n.x) % n.y;
    let i_mu_all = (index / (n.x * n.y)) % n.z;
    let i_r = index / (n.x * n.y * n.z);
    let half_index = i_mu_all / half_mu;
    let x_mu = f32(i_mu_all % half_mu) / f32(half_mu - 1u);
    let hh = pre_h(atm);
    let rho = hh * f32(i_r) / f32(n.w - 1u);
    let r = sqrt(rho * rho + atm.shape.x * atm.shape.x);
    var mu: f32;
    if (half_index == 0u) {
        let d_min = r - atm.shape.x;
        let d = d_min + x_mu * (rho - d_min);
        mu = select(-1.0, -(rho * rho + d * d) / (2.0 * r * d), d > 1e-6);
    } else {
        let d_min = atm.shape.y - r;
        let d = d_min + x_mu * (rho + hh - d_min);
        mu = select(1.0, (hh * hh - rho * rho - d * d) / (2.0 * r * d), d > 1e-6);
    }
    mu = clamp(mu, -1.0, 1.0);
    let mu_s = pre_mu_s_from_x(atm, f32(i_mu_s) / f32(n.y - 1u), h.ground.y);
    let cos_azimuth = 2.0 * f32(i_nu) / f32(n.x - 1u) - 1.0;
    let nu = clamp(mu * mu_s + cos_azimuth * pre_nu_spread(mu, mu_s), -1.0, 1.0);
    return PreGeometry(r, mu, mu_s, nu, half_index == 0u);
}

// The cell of the 4D tables around `c`: its first corner, the fractions towards the last, and the
// texels per axis (mu within its half).
struct PreCell {
    first: vec4<u32>,
    f: vec4<f32>,
    n: vec4<u32>,
    half_index: u32,
};

fn pre_cell(h: PrecomputedHeader, c: PreCoords) -> PreCell {
    let n = vec4<u32>(h.sizes_4d.x, h.sizes_4d.y, h.sizes_4d.z / 2u, h.sizes_4d.w);
    let p = c.x * vec4<f32>(n - vec4<u32>(1u));
    let i = min(vec4<u32>(floor(p)), n - vec4<u32>(2u));
    return PreCell(i, p - vec4<f32>(i), n, c.half_index);
}

// Corner `corner` (bits: nu, mu_s, mu, r) of `cell`: its texel index in a 4D table and its weight.
struct PreCorner {
    index: u32,
    weight: f32,
};

fn pre_corner(h: PrecomputedHeader, cell: PreCell, corner: u32) -> PreCorner {
    let o = vec4<u32>(corner & 1u, (corner >> 1u) & 1u, (corner >> 2u) & 1u, (corner >> 3u) & 1u);
    let w4 = select(vec4<f32>(1.0) - cell.f, cell.f, o == vec4<u32>(1u));
    let k = cell.first + o;
    let mu_index = cell.half_index * cell.n.z + k.z;
    return PreCorner(((k.w * h.sizes_4d.z + mu_index) * cell.n.y + k.y) * cell.n.x + k.x, w4.x * w4.y * w4.z * w4.w);
}

// Quadrilinear read of 4D table `table` at `c`.
fn pre_read_4d(h: PrecomputedHeader, table: u32, c: PreCoords) -> vec3<f32> {
    let base = pre_offset_4d(h, table);
    let cell = pre_cell(h, c);
    var sum = vec3<f32>(0.0);
    for (var corner = 0u; corner < 16u; corner++) {
        let k = pre_corner(h, cell, corner);
        sum += precomputed_tables[base + k.index].xyz * k.weight;
    }
    return sum;
}

// What the lookup reads at a point of the 4D tables: the scattering table (single Rayleigh and
// the higher orders over the Rayleigh phase) and single Mie (without its phase).
struct PreScattering {
    rayleigh: vec3<f32>,
    mie: vec3<f32>,
};

// Half-float bits of a non-negative `x`, rounded to nearest (the largest half where it would
// overflow), in integer arithmetic: `pack2x16float` needs a capability downlevel adapters lack.
fn pre_half_bits(x: f32) -> u32 {
    let b = bitcast<u32>(max(x, 0.0));
    // The half's exponent field: the f32's, rebiased from 127 to 15.
    let e = i32(b >> 23u) - 112;
    if (e >= 31) {
        return 0x7bffu;
    }
    if (e <= 0) {
        // A subnormal half: the significand with its implicit bit, in units of 2^-24.
        let shift = u32(14 - e);
        if (shift > 24u) {
            return 0u;
        }
        let m = (b & 0x7fffffu) | 0x800000u;
        return (m + (1u << (shift - 1u))) >> shift;
    }
    // A carry out of the significand rounds into the exponent, as it should.
    return min(((u32(e) << 10u) | ((b >> 13u) & 0x3ffu)) + ((b >> 12u) & 1u), 0x7bffu);
}

fn pre_half_value(h: u32) -> f32 {
    let e = (h >> 10u) & 0x1fu;
    let m = h & 0x3ffu;
    if (e == 0u) {
        return f32(m) * 5.9604645e-8; // 2^-24
    }
    return bitcast<f32>(((e + 112u) << 23u) | (m << 13u));
}

fn pre_half_pair(lo: f32, hi: f32) -> u32 {
    return pre_half_bits(lo) | (pre_half_bits(hi) << 16u);
}

// Three pairs of halves: scattering rgb and single Mie rgb, scaled. The words travel as f32 bits,
// as the header's integers do (loads, stores and bitcasts move bits; only arithmetic may flush).
fn pre_pack_half(s: vec3<f32>, m: vec3<f32>) -> vec4<f32> {
    let a = s * PRE_HALF_SCALE;
    let b = m * PRE_HALF_SCALE;
    return bitcast<vec4<f32>>(vec4<u32>(pre_half_pair(a.x, a.y), pre_half_pair(a.z, b.x), pre_half_pair(b.y, b.z), 0u));
}

fn pre_unpack_half(t: vec4<f32>) -> PreScattering {
    let u = bitcast<vec4<u32>>(t);
    let lo = vec3<f32>(pre_half_value(u.x & 0xffffu), pre_half_value(u.y & 0xffffu), pre_half_value(u.z & 0xffffu));
    let hi = vec3<f32>(pre_half_value(u.x >> 16u), pre_half_value(u.y >> 16u), pre_half_value(u.z >> 16u));
    return PreScattering(vec3<f32>(lo.x, hi.x, lo.y) / PRE_HALF_SCALE, vec3<f32>(hi.y, lo.z, hi.z) / PRE_HALF_SCALE);
}

// Both looked-up tables at `c`, from one loop over the corners: two single-precision tables, or
// the packed half-precision one.
fn pre_read_scattering(h: PrecomputedHeader, c: PreCoords) -> PreScattering {
    var out = PreScattering(vec3<f32>(0.0), vec3<f32>(0.0));
    let cell = pre_cell(h, c);
    if (h.steps.w == 1u) {
        let base = pre_offset_4d(h, PRE_PACKED);
        for (var corner = 0u; corner < 16u; corner++) {
            let k = pre_corner(h, cell, corner);
            let t = pre_unpack_half(precomputed_tables[base + k.index]);
            out.rayleigh += t.rayleigh * k.weight;
            out.mie += t.mie * k.weight;
        }
        return out;
    }
    let base_r = pre_offset_4d(h, PRE_SCATTERING);
    let base_m = pre_offset_4d(h, PRE_SINGLE_MIE);
    for (var corner = 0u; corner < 16u; corner++) {
        let k = pre_corner(h, cell, corner);
        out.rayleigh += precomputed_tables[base_r + k.index].xyz * k.weight;
        out.mie += precomputed_tables[base_m + k.index].xyz * k.weight;
    }
    return out;
}

// Sky radiance seen from `camera_km` along `view`, sr^-1 per unit of solar irradiance: single
// Rayleigh and every higher order from the scattering table with the Rayleigh phase, single Mie
// from its own table with the Mie phase.
fn precomputed_radiance(atm: Atmosphere, camera_km: f32, view: vec3<f32>, sun: vec3<f32>) -> vec3<f32> {
    let h = pre_header();
    let ray = view_ray(atm, camera_km, view, sun);
    let ground = distance_to_ground(atm, ray.r, ray.mu) >= 0.0;
    let c = pre_coords(atm, ray.r, ray.mu, sun.y, dot(view, sun), ground, h.ground.y);
    let t = pre_read_scattering(h, c);
    return t.rayleigh * ray.phase_r + t.mie * ray.phase_m;
}
