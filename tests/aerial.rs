//! Aerial perspective against the double-precision reference: the light scattered into a view
//! ray that stops at a scene point, and the ray's transmittance. The `lut` model's exact
//! per-pixel integration (`lut_aerial` in shaders/sky_model/lut_sampling.wgsl) is evaluated on
//! lavapipe through the radiance probe, the path `skytune radiance` takes.

use skytune::atmosphere::aerial::AerialSettings;
use skytune::atmosphere::reference::{Case, Estimate, Reference, ReferenceSettings};
use skytune::atmosphere::{Atmosphere, LutSettings};
use skytune::measure::aerial;
use skytune::render::atmosphere::aerial_probe::AerialProbe;
use skytune::render::atmosphere::radiance_probe::{ProbeAnswers, RadianceProbe};
use skytune::render::{AdapterChoice, GpuContext, ShaderLibrary};

/// Viewers low and high, suns by day, low and below the horizon, views from below the horizon
/// to high, towards and away from the sun, rays from 0.5 to 50 km.
fn cases() -> Vec<Case> {
    let mut out = Vec::new();
    for camera_km in [0.2, 2.0] {
        for sun_elev_deg in [30.0, 4.0, -3.0] {
            for view_elev_deg in [-2.0, 1.0, 15.0] {
                for rel_azimuth_deg in [0.0, 150.0] {
                    for d in [0.5, 5.0, 50.0] {
                        out.push(Case { camera_km, albedo: 0.3, sun_elev_deg, view_elev_deg, rel_azimuth_deg, distance_km: Some(d) });
                    }
                }
            }
        }
    }
    out
}

/// The reference's rays for `cases` and its sky in the same directions (what an in-scatter error
/// is relative to, so that short rays with little in-scatter do not dominate), at `paths`.
fn reference_rays(atm: &Atmosphere, cases: &[Case], paths: u32) -> (Vec<Estimate>, Vec<Estimate>) {
    let reference = Reference::new(*atm, ReferenceSettings { paths, ..Default::default() });
    let jobs: Vec<_> = cases.iter().map(|c| (&reference, *c)).collect();
    let rays = skytune::atmosphere::reference::estimate_many(&jobs, &|_, _| Ok(())).unwrap();
    let sky_jobs: Vec<_> = cases.iter().map(|c| (&reference, Case { distance_km: None, ..*c })).collect();
    let sky = skytune::atmosphere::reference::estimate_many(&sky_jobs, &|_, _| Ok(())).unwrap();
    (rays, sky)
}

/// [median, p95, worst] per sun band (day, low, twilight) of the in-scatter error as a fraction
/// of the sky in the same direction, and of the transmittance's absolute error.
fn errors(cases: &[Case], gpu: &ProbeAnswers, rays: &[Estimate], sky: &[Estimate]) -> ([[f64; 3]; 3], [[f64; 3]; 3]) {
    for (k, c) in cases.iter().enumerate() {
        for ch in 0..3 {
            let (l, t) = (gpu.radiance[k][ch], gpu.transmittance[k][ch]);
            assert!(l.is_finite() && l >= 0.0 && (0.0..=1.0).contains(&t), "case {c:?}: in-scatter {l}, transmittance {t}");
        }
    }
    let e = aerial::ray_errors(cases, &gpu.radiance, &gpu.transmittance, rays, sky);
    let bands = aerial::by_group(cases, &e, 3, aerial::sun_band);
    (std::array::from_fn(|b| bands[b].in_scatter), std::array::from_fn(|b| bands[b].transmittance))
}

#[test]
fn lut_aerial_perspective_matches_the_reference() {
    let atm = Atmosphere::default();
    let cases = cases();
    let (rays, sky) = reference_rays(&atm, &cases, 2048);
    let ctx = GpuContext::headless(AdapterChoice::Cpu).unwrap();
    let probe = RadianceProbe::new(&ctx, &ShaderLibrary::embedded()).unwrap();
    let gpu = probe.lut_rays(&ctx, &atm, &LutSettings::default(), &cases).unwrap();
    let (in_scatter, transmittance) = errors(&cases, &gpu, &rays, &sky);
    eprintln!("lut aerial perspective against the reference, [median, p95, worst] per sun band (day, low, twilight): in-scatter / sky {in_scatter:.4?}, transmittance {transmittance:.5?}");
    // The accuracy targets (median 1%, p95 3% of the sky; transmittance 0.003 and 0.01)
    // and a bound on the worst case. Measured on lavapipe against 2048 reference paths, [median,
    // p95, worst] beyond the noise: day [0, 0.0039, 0.0075], low sun [0, 0.0028, 0.0054],
    // twilight [0, 0.0232, 0.0609] (50 km rays away from a sun 3 degrees down, where the lut
    // model's own sky is off by as much); transmittance 9e-5 at worst.
    for (name, [median, p95, worst], worst_limit) in [("day", in_scatter[0], 0.02), ("low sun", in_scatter[1], 0.02), ("twilight", in_scatter[2], 0.1)] {
        assert!(median <= 0.01 && p95 <= 0.03 && worst <= worst_limit, "in-scatter, {name}: median {median:.4}, p95 {p95:.4}, worst {worst:.4}");
    }
    for (name, [median, p95, worst]) in ["day", "low sun", "twilight"].iter().zip(transmittance) {
        assert!(median <= 0.003 && p95 <= 0.01 && worst <= 0.001, "transmittance, {name}: median {median:.5}, p95 {p95:.5}, worst {worst:.5}");
    }
}

/// The default volume, read as the scene reads it, against the reference on two drawn sets: seed
/// 67, on which the volume's march through the ground was found and fixed (in sample), and seed
/// 68, drawn afterwards and changed nothing (held out).
#[test]
fn the_default_volume_matches_the_reference() {
    let atm = Atmosphere::default();
    let ctx = GpuContext::headless(AdapterChoice::Cpu).unwrap();
    let probe = AerialProbe::new(&ctx, &ShaderLibrary::embedded()).unwrap();
    for seed in [67, 68] {
        let cases = aerial::draw_cases(seed, 96, &atm);
        let (rays, sky) = reference_rays(&atm, &cases, 1024);
        let gpu = probe.volume_rays(&ctx, &atm, &LutSettings::default(), &AerialSettings::default(), true, &cases).unwrap();
        let (in_scatter, transmittance) = errors(&cases, &gpu, &rays, &sky);
        eprintln!("default volume against the reference, seed {seed}, [median, p95, worst] per sun band (day, low, twilight): in-scatter / sky {in_scatter:.4?}, transmittance {transmittance:.5?}");
        // The targets (median 1%, p95 3% of the sky; transmittance 0.003 and 0.01), and
        // a bound on the worst case. Measured on lavapipe, 1024 reference paths, [median, p95,
        // worst], the default volume (16 x 32 x 32, one sample a slice): seed 67 in-scatter day
        // [0.0002, 0.0076, 0.0298], low [0.0005, 0.0087, 0.0148], twilight [0, 0.0009,
        // 0.0136], transmittance worst 0.0032; seed 68 (held out) day [0.0002, 0.0042, 0.0173],
        // low [0.0002, 0.0106, 0.0167], twilight [0, 0.0015, 0.053], transmittance worst 0.0113
        // (a view 0.4 degrees up at 99 km, read between cells 2.2 degrees apart: the volume's
        // resolution down the screen at the horizon). The worst bounds are loose on purpose: the
        // held-out worst cases passed twice set 67's. Stopping the volume's rays at the planet's
        // ground (the bug fixed) read low-sun p95 0.035, worst 0.12, transmittance worst 0.098
        // on seed 67 (then 32 x 32 x 32, two samples a slice).
        for (name, [median, p95, worst]) in ["day", "low sun", "twilight"].iter().zip(in_scatter) {
            assert!(median <= 0.01 && p95 <= 0.03 && worst <= 0.1, "seed {seed}, in-scatter, {name}: median {median:.4}, p95 {p95:.4}, worst {worst:.4}");
        }
        for (name, [median, p95, worst]) in ["day", "low sun", "twilight"].iter().zip(transmittance) {
            assert!(median <= 0.003 && p95 <= 0.01 && worst <= 0.02, "seed {seed}, transmittance, {name}: median {median:.5}, p95 {p95:.5}, worst {worst:.5}");
        }
    }
}

/// A ray stopped past the edge of the atmosphere is the sky's own ray, on the GPU too; a nearer
/// scene point lets more through and gathers less.
#[test]
fn lut_finite_rays_approach_the_sky() {
    let atm = Atmosphere::default();
    let ctx = GpuContext::headless(AdapterChoice::Cpu).unwrap();
    let probe = RadianceProbe::new(&ctx, &ShaderLibrary::embedded()).unwrap();
    let base = Case { camera_km: 0.5, albedo: 0.3, sun_elev_deg: 20.0, view_elev_deg: 3.0, rel_azimuth_deg: 90.0, distance_km: None };
    let distances = [Some(1.0), Some(10.0), Some(100.0), Some(1e6), None];
    let cases: Vec<Case> = distances.iter().map(|&distance_km| Case { distance_km, ..base }).collect();
    let gpu = probe.lut_rays(&ctx, &atm, &LutSettings::default(), &cases).unwrap();
    let sky = probe.lut(&ctx, &atm, &LutSettings::default(), &[base]).unwrap()[0];
    assert_eq!(gpu.radiance[3], sky, "a ray stopped past the edge");
    assert_eq!(gpu.radiance[4], sky, "no distance");
    for k in 0..3 {
        for ch in 0..3 {
            assert!(gpu.radiance[k][ch] < gpu.radiance[k + 1][ch], "{:?}", gpu.radiance);
            assert!(gpu.transmittance[k][ch] > gpu.transmittance[k + 1][ch], "{:?}", gpu.transmittance);
        }
    }
}
