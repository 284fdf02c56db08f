// Atmosphere parameters, density profiles, phase functions and optical depths shared by the
// physical sky models. Units: km, km^-1, radians. Keep in sync with `AtmosphereUniform` in
// src/render/atmosphere/uniforms.rs.
struct Atmosphere {
    rayleigh: vec4<f32>, // scattering rgb (km^-1), scale height (km)
    mie_scattering: vec4<f32>, // scattering rgb (km^-1), scale height (km)
    mie_extinction: vec4<f32>, // extinction rgb (km^-1), Cornette-Shanks g
    ozone: vec4<f32>,    // absorption rgb (km^-1), tent centre (km)
    shape: vec4<f32>,    // ground radius, top radius (km), ozone tent half width (km), sun angular radius (rad)
};


fn rayleigh_phase(cos_theta: f32) -> f32 {
    return 3.0 / (16.0 * PI) * (1.0 + cos_theta * cos_theta);
}

fn cornette_shanks_phase(cos_theta: f32, g: f32) -> f32 {
    let g2 = g * g;
    return 3.0 / (8.0 * PI) * (1.0 - g2) / (2.0 + g2) * (1.0 + cos_theta * cos_theta) / pow(1.0 + g2 - 2.0 * g * cos_theta, 1.5);
}

fn ozone_density(atm: Atmosphere, altitude_km: f32) -> f32 {
    return max(0.0, 1.0 - abs(altitude_km - atm.ozone.w) / atm.shape.z);
}

// Relative densities of the air (x, Rayleigh) and of the aerosol (y, Mie) at an altitude (km;
// below the ground, the ground's): 1 at the ground, falling off with their scale heights.
fn densities_at(atm: Atmosphere, altitude_km: f32) -> vec2<f32> {
    let h = max(altitude_km, 0.0);
    return vec2<f32>(exp(-h / atm.rayleigh.w), exp(-h / atm.mie_scattering.w));
}

// Scattering coefficients at an altitude (km^-1, rgb; phase functions not applied). The one
// place every marching shader takes them from.
struct Scattering {
    rayleigh: vec3<f32>,
    mie: vec3<f32>,
};

fn scattering_at(atm: Atmosphere, altitude_km: f32) -> Scattering {
    let d = densities_at(atm, altitude_km);
    return Scattering(atm.rayleigh.xyz * d.x, atm.mie_scattering.xyz * d.y);
}

// Extinction at an altitude, km^-1.
fn extinction_at(atm: Atmosphere, altitude_km: f32) -> vec3<f32> {
    let h = max(altitude_km, 0.0);
    let d = densities_at(atm, h);
    return atm.rayleigh.xyz * d.x + atm.mie_extinction.xyz * d.y + atm.ozone.xyz * ozone_density(atm, h);
}

// Altitude of p + t d for a point at radius r with direction cosine mu (to the local vertical),
// without the cancellation of length(p) - R in f32.
fn altitude_along(atm: Atmosphere, r: f32, mu: f32, t: f32) -> f32 {
    let r2 = r * r + t * (t + 2.0 * r * mu);
    return (r2 - atm.shape.x * atm.shape.x) / (sqrt(max(r2, 0.0)) + atm.shape.x);
}

// Distance to the top of the atmosphere from radius r along cosine mu (r inside).
fn distance_to_top(atm: Atmosphere, r: f32, mu: f32) -> f32 {
    let top = atm.shape.y;
    let disc = r * r * (mu * mu - 1.0) + top * top;
    return max(0.0, -r * mu + sqrt(max(disc, 0.0)));
}

// How much of the sun lights a point at radius r, for the sun's cosine mu_s to the point's
// vertical: all of it while the sun is above the point's horizon, fading smoothly to nothing as
// it sinks SUN_SET_FADE_RAD below (the reference does the same: `Reference::sunlight`). A point
// sun alone switches ray-march samples off one by one and the sky jumps as the sun sets
// (`skytune sweep`). Keep in sync with SUN_SET_FADE_RAD in src/atmosphere/mod.rs.
const SUN_SET_FADE_RAD: f32 = 0.0017453;
fn sun_visible_fraction(atm: Atmosphere, r: f32, mu_s: f32) -> f32 {
    let horizon = horizon_mu(atm, r);
    // asin's slope is at least 1, so cosines 0.01 apart are angles at least 0.01 rad apart, far
    // beyond the fade: the same 1 or 0 without the two asin (a software rasteriser evaluates them
    // in code), for nearly every sample of a march.
    if (mu_s > horizon + 0.01) {
        return 1.0;
    }
    if (mu_s < horizon - 0.01) {
        return 0.0;
    }
    let above = asin(clamp(mu_s, -1.0, 1.0)) - asin(horizon);
    return smoothstep(-SUN_SET_FADE_RAD, 0.0, above);
}

// Cosine to the vertical of the geometric horizon seen from radius r (at most 0).
fn horizon_mu(atm: Atmosphere, r: f32) -> f32 {
    let sin_horizon = clamp(atm.shape.x / max(r, atm.shape.x), 0.0, 1.0);
    return -sqrt(max(1.0 - sin_horizon * sin_horizon, 0.0));
}

// Distance to the ground along cosine mu, or -1 when the ray misses it.
fn distance_to_ground(atm: Atmosphere, r: f32, mu: f32) -> f32 {
    let ground = atm.shape.x;
    // r^2 (mu^2 - 1) + R^2, written to keep precision for r close to R.
    let disc = r * r * mu * mu - (r - ground) * (r + ground);
    if (mu >= 0.0 || disc < 0.0) {
        return -1.0;
    }
    return max(0.0, -r * mu - sqrt(disc));
}

// Integral from 0 to infinity of exp(-(a x^2 + b x)) dx for b >= 0, with the two regimes of
// the procedural-sky text: the asymptotic series when b > 7 sqrt(a), else a rational fit of
// erfc (Abramowitz and Stegun 7.1.25).
fn erf_column(a: f32, b: f32) -> f32 {
    let sa = sqrt(a);
    if (b > 7.0 * sa) {
        let b2 = b * b;
        return (1.0 / b) * (1.0 - 2.0 * a / b2 + 12.0 * a * a / (b2 * b2));
    }
    let p = 2.0 * sa / (2.0 * sa + 0.47047 * b);
    return sqrt(PI) / (2.0 * sa) * (0.3480242 * p - 0.0958798 * p * p + 0.7478556 * p * p * p);
}

// Optical-depth integral of exp(-altitude / scale) from altitude h (radius r) along cosine mu to
// infinity, in km, by the erf approximation; a negative value means the ray hits the ground.
fn erf_optical_length(atm: Atmosphere, r: f32, h: f32, mu: f32, scale: f32) -> f32 {
    let ground = atm.shape.x;
    if (mu >= 0.0) {
        let a = (1.0 - mu * mu) / (2.0 * r * scale);
        return exp(-h / scale) * erf_column(a, mu / scale);
    }
    // Downwards: through the ray's lowest point, unless that is below the ground.
    let r_min = r * sqrt(max(1.0 - mu * mu, 0.0));
    let h_min = r_min - ground;
    if (h_min < 0.0) {
        return -1.0;
    }
    let to_lowest = -mu * r;
    let before = 0.5 * to_lowest * (exp(-h / scale) + exp(-h_min / scale));
    let a = 1.0 / (2.0 * r_min * scale);
    return before + exp(-h_min / scale) * erf_column(a, 0.0);
}

// Ozone tent column above an altitude, km (closed form).
fn ozone_column_above(atm: Atmosphere, h: f32) -> f32 {
    let w = atm.shape.z;
    let u = clamp((h - atm.ozone.w) / w, -1.0, 1.0);
    var below: f32;
    if (u < 0.0) {
        below = 0.5 * (1.0 + u) * (1.0 + u);
    } else {
        below = 1.0 - 0.5 * (1.0 - u) * (1.0 - u);
    }
    return w * (1.0 - below);
}

// Optical depth to the sun by the erf approximation (Rayleigh, Mie); ozone by its vertical column
// times the slant factor at the tent's centre (an approximation: the text has no ozone).
// Returns -1 when the ground blocks the sun.
fn erf_optical_depth(atm: Atmosphere, r: f32, h: f32, mu: f32) -> vec3<f32> {
    let lr = erf_optical_length(atm, r, h, mu, atm.rayleigh.w);
    if (lr < 0.0) {
        return vec3<f32>(-1.0);
    }
    let lm = erf_optical_length(atm, r, h, mu, atm.mie_scattering.w);
    let rc = atm.shape.x + atm.ozone.w;
    let s = clamp(r / rc, 0.0, 1.0) * sqrt(max(1.0 - mu * mu, 0.0));
    let slant = 1.0 / sqrt(max(1.0 - s * s, 1e-4));
    var column = ozone_column_above(atm, h);
    if (mu < 0.0) {
        // Down through the lowest point and up again.
        let h_min = r * sqrt(max(1.0 - mu * mu, 0.0)) - atm.shape.x;
        column = 2.0 * ozone_column_above(atm, h_min) - column;
    }
    return atm.rayleigh.xyz * lr + atm.mie_extinction.xyz * lm + atm.ozone.xyz * column * slant;
}

// Optical depth to the top of the atmosphere by the midpoint rule with `steps` samples;
// -1 when the ground blocks the ray.
fn numeric_optical_depth(atm: Atmosphere, r: f32, mu: f32, steps: u32) -> vec3<f32> {
    if (distance_to_ground(atm, r, mu) >= 0.0) {
        return vec3<f32>(-1.0);
    }
    let ray_length = distance_to_top(atm, r, mu);
    let dt = ray_length / f32(steps);
    var tau = vec3<f32>(0.0);
    for (var i = 0u; i < steps; i++) {
        let t = (f32(i) + 0.5) * dt;
        tau += extinction_at(atm, altitude_along(atm, r, mu, t)) * dt;
    }
    return tau;
}

// A view ray from the camera: its start radius, cosine to the vertical, length inside the
// atmosphere (to the ground if it meets it) and the phase functions towards the sun.
struct ViewRay {
    r: f32,
    mu: f32,
    distance_km: f32,
    phase_r: f32,
    phase_m: f32,
};

fn view_ray(atm: Atmosphere, camera_km: f32, view: vec3<f32>, sun: vec3<f32>) -> ViewRay {
    let r = atm.shape.x + camera_km;
    let mu = view.y;
    let ground = distance_to_ground(atm, r, mu);
    var distance_km = distance_to_top(atm, r, mu);
    if (ground >= 0.0) {
        distance_km = ground;
    }
    let nu = dot(view, sun);
    return ViewRay(r, mu, distance_km, rayleigh_phase(nu), cornette_shanks_phase(nu, atm.mie_extinction.w));
}

// One step of a march along a view ray from radius r with cosine mu to the vertical: `sample`
// holds the step's midpoint distance and its length (km; `crowded_sample`). Adds the step's
// optical depth to `tau` (steps come in order of distance). The altitude is not clamped: a ray
// that meets the ground may end a hair below it.
struct MarchStep {
    t: f32,
    dt: f32,
    altitude_km: f32,
    // Optical depth from the ray's start to the step's middle.
    tau_mid: vec3<f32>,
};

fn march_step(atm: Atmosphere, r: f32, mu: f32, sample: vec2<f32>, tau: ptr<function, vec3<f32>>) -> MarchStep {
    let altitude_km = altitude_along(atm, r, mu, sample.x);
    let e = extinction_at(atm, altitude_km);
    let tau_mid = *tau + e * (0.5 * sample.y);
    *tau += e * sample.y;
    return MarchStep(sample.x, sample.y, altitude_km, tau_mid);
}

// Sample i of n along a ray of `distance_km`, crowded near its start where the air is densest
// (boundaries at distance (k / n)^2): the sample's midpoint and length.
fn crowded_sample(distance_km: f32, i: u32, n: u32) -> vec2<f32> {
    let a = f32(i) / f32(n);
    let b = (f32(i) + 1.0) / f32(n);
    let t0 = distance_km * a * a;
    let t1 = distance_km * b * b;
    return vec2<f32>(0.5 * (t0 + t1), t1 - t0);
}
