//! requires: sky_model/lut_sampling
// Aerial perspective (Hillaire 2020's froxel volume): what the atmosphere adds to and takes from
// the light of a scene point between it and the viewer, per screen cell and depth slice, from the
// frame's atmosphere and the shared transmittance and multiple-scattering tables. A library: the
// volume's builder (aerial_perspective.wgsl) marches it; its readers (sky_model/aerial_lookup)
// read it. The slice layout is the GPU form of
// `AerialSettings` in src/atmosphere/aerial.rs (its tests pin the same mapping).
// Keep `AerialParams` in sync with `AerialUniform` in src/render/atmosphere/uniforms.rs.
struct AerialParams {
    world_from_clip: mat4x4<f32>, // the camera the volume follows, clip -> world (m)
    camera: vec4<f32>,            // xyz its position (m); w its altitude in the atmosphere (km)
    towards_sun: vec4<f32>,       // xyz unit vector; w the method: 0 none (the scene keeps its fog), 1 volume, 2 exact
    size: vec4<u32>,              // cells across, down and in depth; view-ray samples per slice
    shape: vec4<f32>,             // x the last slice's end (km); y the spread (0 quadratic, 1 linear); z 1 with the multiple-scattering orders; w unused
};

// The largest volume, cells per axis: its textures' size. Keep in sync with
// `AerialSettings::MAX_SIZE` in src/atmosphere/aerial.rs.
const AERIAL_MAX_SIZE: vec3<f32> = vec3<f32>(64.0, 64.0, 128.0);

// Distance at which slice k ends, km.
fn aerial_slice_distance_km(p: AerialParams, k: u32) -> f32 {
    let w = (f32(k) + 1.0) / f32(p.size.z);
    if (p.shape.y > 0.5) {
        return p.shape.x * w;
    }
    return p.shape.x * w * w;
}

// Where a point at `distance_km` reads the volume along depth: x the coordinate in slices (texel
// centres at k + 0.5, clamped to the first and last), y the fraction of the first slice's values
// to take (below 1 only nearer than its end).
fn aerial_slice_position(p: AerialParams, distance_km: f32) -> vec2<f32> {
    let n = f32(p.size.z);
    let x = max(distance_km / p.shape.x, 0.0);
    var w = sqrt(x);
    if (p.shape.y > 0.5) {
        w = x;
    }
    let texel = clamp(w * n - 1.0, 0.0, n - 1.0);
    return vec2<f32>(texel + 0.5, min(w * n, 1.0));
}

// A view ray's march so far: optical depth and gathered light (units: sr^-1 per unit of solar
// irradiance).
struct AerialMarch {
    tau: vec3<f32>,
    sum: vec3<f32>,
};

// The multiple-scattering table's harmonics at distance t along `ray` (view direction `view`):
// the light arriving there from the second order on. The light arriving at a point changes
// slowly along a ray (as `MS_SAMPLES_PER_READ` in lut_sampling.wgsl), and this 24-value read is
// most of a slice's cost on a software rasteriser, so the builder reads it once for several
// slices (`AERIAL_SLICES_PER_MS_READ`).
fn aerial_ms_at(atm: Atmosphere, ray: ViewRay, view: vec3<f32>, sun: vec3<f32>, t: f32) -> array<vec3<f32>, 6> {
    let q = vec3<f32>(0.0, ray.r, 0.0) + view * t;
    let r_q = atm.shape.x + max(altitude_along(atm, ray.r, ray.mu, t), 0.0);
    return sample_multiscattering(0u, atm, r_q, dot(q, sun) / max(length(q), 1e-3));
}

// Slices per read of the multiple-scattering table in the volume's march.
const AERIAL_SLICES_PER_MS_READ: u32 = 4u;

// Marches `ray` (view direction `view`) from t0 to t1 km in `steps` midpoint samples, adding to
// `state` what each scatters towards the viewer (`scattered_at`, with the multiple-scattering
// harmonics `c` read near the segment: `aerial_ms_at`). Nothing beyond the ray's end.
fn aerial_advance(atm: Atmosphere, ray: ViewRay, view: vec3<f32>, sun: vec3<f32>, t0: f32, t1: f32, steps: u32, multiple: bool, c: array<vec3<f32>, 6>, state: ptr<function, AerialMarch>) {
    let a = min(t0, ray.distance_km);
    let b = min(t1, ray.distance_km);
    if (b <= a) {
        return;
    }
    let dt = (b - a) / f32(steps);
    var tau = (*state).tau;
    var sum = (*state).sum;
    for (var i = 0u; i < steps; i++) {
        let step = march_step(atm, ray.r, ray.mu, vec2<f32>(a + (f32(i) + 0.5) * dt, dt), &tau);
        sum += scattered_at(atm, ray, view, sun, step, c, multiple) * exp(-step.tau_mid) * step.dt;
    }
    (*state).tau = tau;
    (*state).sum = sum;
}

// The view direction through the centre of volume cell (i, j) of the camera in `p`.
fn aerial_cell_view(p: AerialParams, cell: vec2<u32>) -> vec3<f32> {
    let uv = (vec2<f32>(cell) + 0.5) / vec2<f32>(p.size.xy);
    let far = p.world_from_clip * vec4<f32>(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0, 1.0, 1.0);
    return normalize(far.xyz / far.w - p.camera.xyz);
}
