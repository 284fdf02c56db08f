//! The sky-view map's coordinates of a direction (`sky_view_uv` in
//! shaders/sky_model/sky_view_map.wgsl, read per fragment by every layer over a physical sky),
//! run on lavapipe and compared with their definition in double precision: the azimuth from the
//! sun's by `atan2` of compass azimuths, folded onto half the circle; elevation by `asin` of the
//! normalised direction, square-root spaced rows.

mod common;

use skytune::render::plan::resolution::SKY_VIEW_SIZE;
use skytune::render::{AdapterChoice, GpuContext, ShaderLibrary};

/// Directions probed: a grid over azimuth and elevation (the poles, the horizon and the
/// azimuth's seam included), each at several lengths (the layers pass unnormalised ones).
const AZIMUTHS: u32 = 181;
const ELEVATIONS: u32 = 121;
const LENGTHS: [f32; 3] = [1.0, 0.37, 23.0];

/// Suns probed (unit vectors, and one of another length): compass azimuths either side of the
/// seam, low and high.
const SUNS: [[f32; 3]; 4] = [[0.0, 0.5, -0.8660254], [0.9063, 0.0872, 0.4132], [-0.0848, 0.866, 0.4924], [-1.3, 0.2, -0.4]];

/// The coordinates' entry point: pairs of a direction and a sun in, uv and the round trip of the
/// uv through `sky_view_direction` out.
const PROBE: &str = "
@group(0) @binding(15) var<storage, read_write> probe_out: array<vec4<f32>>;
@group(0) @binding(16) var<storage, read> probe_dirs: array<vec4<f32>>;

@compute @workgroup_size(64)
fn cs_uv(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= arrayLength(&probe_out) { return; }
    let sun = probe_dirs[2u * id.x + 1u].xyz;
    let uv = sky_view_uv(probe_dirs[2u * id.x].xyz, sun);
    probe_out[id.x] = vec4<f32>(uv, sky_view_uv(sky_view_direction(uv, sun), sun));
}
";

/// The definition: the compass azimuths (from -z towards +x) of the direction and the sun, their
/// difference folded onto 0 to 180 degrees; elevation's square root spaced about the horizon in
/// the middle.
fn exact_uv(d: [f64; 3], sun: [f64; 3]) -> [f64; 2] {
    use std::f64::consts::{FRAC_PI_2, PI, TAU};
    let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    let from_sun = (d[0].atan2(-d[2]) - sun[0].atan2(-sun[2])).rem_euclid(TAU);
    let elevation = (d[1] / len).clamp(-1.0, 1.0).asin();
    let e = elevation.signum() * (elevation.abs() / FRAC_PI_2).sqrt();
    [from_sun.min(TAU - from_sun) / PI, 0.5 - 0.5 * e]
}

fn directions() -> Vec<[f32; 3]> {
    let mut out = Vec::new();
    for i in 0..AZIMUTHS {
        let az = (i as f64 / (AZIMUTHS - 1) as f64 - 0.5) * std::f64::consts::TAU;
        for j in 0..ELEVATIONS {
            let el = (j as f64 / (ELEVATIONS - 1) as f64 - 0.5) * std::f64::consts::PI;
            for len in LENGTHS {
                let l = f64::from(len);
                out.push([(l * az.sin() * el.cos()) as f32, (l * el.sin()) as f32, (-l * az.cos() * el.cos()) as f32]);
            }
        }
    }
    out
}

#[test]
fn map_coordinates_hold_to_a_hundredth_of_a_texel() {
    let ctx = GpuContext::headless(AdapterChoice::Cpu).expect("lavapipe (mesa-vulkan-drivers) is required: run scripts/setup.sh");
    let dirs = directions();
    let source = ShaderLibrary::embedded().source("sky_model/sky_view_map").expect("sky_view_map.wgsl") + PROBE;
    let pairs: Vec<([f32; 3], [f32; 3])> = SUNS.iter().flat_map(|s| dirs.iter().map(move |d| (*d, *s))).collect();
    let padded: Vec<[f32; 4]> = pairs.iter().flat_map(|(d, s)| [[d[0], d[1], d[2], 0.0], [s[0], s[1], s[2], 0.0]]).collect();
    let bytes = common::run_compute_probe(&ctx, source, "cs_uv", &[], Some(bytemuck::cast_slice(&padded)), pairs.len() as u32, 16);
    let got: &[[f32; 4]] = bytemuck::cast_slice(&bytes);
    let (w, h) = SKY_VIEW_SIZE;
    let texels = [f64::from(w), f64::from(h)];
    let (mut worst, mut worst_trip) = (0.0f64, 0.0f64);
    for ((d, sun), g) in pairs.iter().zip(got) {
        let d64 = d.map(f64::from);
        let exact = exact_uv(d64, sun.map(f64::from));
        // At the poles every azimuth is the same direction.
        let pole = d64[0].hypot(d64[2]) < 1e-6 * d64[1].abs();
        for c in 0..2 {
            if c == 0 && pole {
                continue;
            }
            let err = (f64::from(g[c]) - exact[c]).abs();
            let trip = (f64::from(g[2 + c]) - f64::from(g[c])).abs();
            worst = worst.max(err * texels[c]);
            worst_trip = worst_trip.max(trip * texels[c]);
        }
    }
    eprintln!("sky_view_uv: worst {worst:.2e} texels from the definition, round trip {worst_trip:.2e} texels");
    assert!(worst < 0.01, "sky_view_uv is {worst} texels from the definition");
    assert!(worst_trip < 0.01, "sky_view_uv(sky_view_direction(uv, sun), sun) is {worst_trip} texels from uv");
}
