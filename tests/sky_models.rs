//! GPU sky models against the double-precision reference, evaluated on lavapipe through the
//! radiance probe (the same path as `skytune radiance`). Thresholds per model and regime are
//! documented in docs/sky-models.md.

use skytune::atmosphere::reference::{Case, Reference, ReferenceSettings};
use skytune::atmosphere::{Atmosphere, OpticalDepth, SingleSettings};
use skytune::render::atmosphere::radiance_probe::RadianceProbe;
use skytune::render::{AdapterChoice, GpuContext, ShaderLibrary};

/// Sun elevations (fine near the horizon), view elevations and relative azimuths.
fn grid() -> Vec<Case> {
    let mut cases = Vec::new();
    for sun in [-6.0, -2.0, 0.0, 1.0, 3.0, 6.0, 10.0, 20.0, 45.0, 80.0] {
        for view in [-10.0, -1.0, 0.5, 2.0, 5.0, 15.0, 40.0, 90.0] {
            for az in [0.0, 60.0, 180.0] {
                cases.push(Case { camera_km: 0.2, albedo: 0.0, sun_elev_deg: sun, view_elev_deg: view, rel_azimuth_deg: az, distance_km: None });
            }
        }
    }
    cases
}

/// Worst relative error per regime (day: sun >= 10 deg; low sun: 0..10; twilight: below 0), over
/// values above 1% of the brightest value of the same sun elevation (darker ones are judged in
/// absolute terms by that 1%).
fn worst_errors(cases: &[Case], model: &[[f32; 3]], reference: &[[f64; 3]]) -> [f64; 3] {
    median_and_worst(cases, model, reference).map(|(_, worst)| worst)
}

#[test]
fn single_scattering_on_the_gpu_matches_the_reference() {
    let atm = Atmosphere::default();
    let cases = grid();
    let reference = Reference::new(atm, ReferenceSettings { max_order: 1, ..Default::default() });
    let exact: Vec<[f64; 3]> = cases.iter().map(|c| reference.radiance(c)).collect();
    let ctx = GpuContext::headless(AdapterChoice::Cpu).unwrap();
    let probe = RadianceProbe::new(&ctx, &ShaderLibrary::embedded()).unwrap();
    // Thresholds (day, low sun, twilight): see docs/sky-models.md.
    let runs = [
        ("erf, 32 view steps", SingleSettings { view_steps: 32, sun_steps: 16, optical_depth: OpticalDepth::Erf }, [0.03, 0.15, 0.6]),
        ("numerical, 32 x 32 steps", SingleSettings { view_steps: 32, sun_steps: 32, optical_depth: OpticalDepth::Numerical }, [0.015, 0.02, 0.03]),
        ("numerical, 128 x 128 steps", SingleSettings { view_steps: 128, sun_steps: 128, optical_depth: OpticalDepth::Numerical }, [0.002, 0.006, 0.008]),
    ];
    for (name, settings, limits) in runs {
        let gpu = probe.single(&ctx, &atm, &settings, &cases).unwrap();
        assert!(gpu.iter().flatten().all(|x| x.is_finite() && *x >= 0.0), "{name}: NaN or negative radiance");
        let worst = worst_errors(&cases, &gpu, &exact);
        eprintln!("single ({name}): worst relative error day {:.4}, low sun {:.4}, twilight {:.4}", worst[0], worst[1], worst[2]);
        for (regime, (w, limit)) in ["day", "low sun", "twilight"].iter().zip(worst.iter().zip(limits)) {
            assert!(*w <= limit, "single ({name}), {regime}: worst relative error {w:.4} > {limit}");
        }
    }
}

#[test]
fn multiple_scattering_models_match_the_reference() {
    let atm = Atmosphere::default();
    let mut cases = Vec::new();
    for sun in [-4.0, 2.0, 8.0, 30.0, 70.0] {
        for view in [-5.0, 3.0, 20.0, 80.0] {
            for az in [30.0, 150.0] {
                cases.push(Case { camera_km: 0.2, albedo: 0.3, sun_elev_deg: sun, view_elev_deg: view, rel_azimuth_deg: az, distance_km: None });
            }
        }
    }
    let reference = Reference::new(atm, ReferenceSettings { paths: 2048, ..Default::default() });
    let exact: Vec<[f64; 3]> = cases.iter().map(|c| reference.radiance(c)).collect();
    let ctx = GpuContext::headless(AdapterChoice::Cpu).unwrap();
    let probe = RadianceProbe::new(&ctx, &ShaderLibrary::embedded()).unwrap();
    let lut = probe.lut(&ctx, &atm, &skytune::atmosphere::LutSettings::default(), &cases).unwrap();
    assert!(lut.iter().flatten().all(|x| x.is_finite() && *x >= 0.0), "NaN or negative radiance");
    let errors = median_and_worst(&cases, &lut, &exact);
    eprintln!("lut (defaults), median and worst relative error per regime: {errors:.4?}");
    // Thresholds (median, worst; day, low sun, twilight): see docs/sky-models.md; they include
    // the reference's noise.
    for (regime, ((median, worst), (median_limit, worst_limit))) in ["day", "low sun", "twilight"].iter().zip(errors.iter().zip([(0.02, 0.06), (0.02, 0.1), (0.04, 0.3)])) {
        assert!(*median <= median_limit && *worst <= worst_limit, "lut, {regime}: median {median:.4}, worst {worst:.4}");
    }
    // Multiple scattering is there: the lut sky is brighter than single scattering alone.
    let single = probe.single(&ctx, &atm, &SingleSettings { view_steps: 32, sun_steps: 32, optical_depth: OpticalDepth::Numerical }, &cases).unwrap();
    let brighter = lut.iter().zip(&single).filter(|(l, s)| l[2] > s[2] * 1.05).count();
    assert!(brighter > cases.len() / 2, "{brighter} of {} cases gain blue from multiple scattering", cases.len());

    // The cell model (CPU): iteration 0 is single scattering; 6 iterations approach every order.
    use skytune::atmosphere::cells::{CellModel, CellSettings};
    let by_iterations: Vec<Vec<[f32; 3]>> = [0, 1, 6]
        .iter()
        .map(|n| {
            let model = CellModel::solve(atm, 0.3, CellSettings { iterations: *n, ..Default::default() });
            cases.iter().map(|c| model.radiance(c).map(|x| x as f32)).collect()
        })
        .collect();
    let single_reference = Reference::new(atm, ReferenceSettings { max_order: 1, ..Default::default() });
    let single_exact: Vec<[f64; 3]> = cases.iter().map(|c| single_reference.radiance(c)).collect();
    let worst0 = worst_errors(&cases, &by_iterations[0], &single_exact);
    let worst6 = worst_errors(&cases, &by_iterations[2], &exact);
    eprintln!("cells, 0 iterations against single scattering: day {:.4}, low sun {:.4}, twilight {:.4}", worst0[0], worst0[1], worst0[2]);
    eprintln!("cells, 6 iterations against all orders: day {:.4}, low sun {:.4}, twilight {:.4}", worst6[0], worst6[1], worst6[2]);
    for (regime, (w, limit)) in ["day", "low sun", "twilight"].iter().zip(worst0.iter().zip([0.03, 0.06, 0.1])) {
        assert!(*w <= limit, "cells, 0 iterations, {regime}: worst relative error {w:.4} > {limit}");
    }
    for (regime, (w, limit)) in ["day", "low sun", "twilight"].iter().zip(worst6.iter().zip([0.1, 0.25, 4.0])) {
        assert!(*w <= limit, "cells, 6 iterations, {regime}: worst relative error {w:.4} > {limit}");
    }
    // Each iteration adds light, the first the most.
    let blue = |run: &Vec<[f32; 3]>| run.iter().map(|c| c[2] as f64).sum::<f64>();
    let (b0, b1, b6) = (blue(&by_iterations[0]), blue(&by_iterations[1]), blue(&by_iterations[2]));
    assert!(b1 > b0 && b6 > b1 && b6 - b1 < b1 - b0, "blue sums by iteration: {b0} {b1} {b6}");
}

/// Solid-angle-weighted sum of the displayed luminance (Rec. 709 weights of the sRGB-decoded
/// pixels) over the pixels of a square render by `camera` (90 degrees across) that look above
/// the horizon, and the solid angle they cover, sr.
fn sky_luminance(img: &image::RgbaImage, camera: &skytune::render::Camera) -> (f64, f64) {
    let decode = |v: u8| skytune::atmosphere::dome::srgb_decode(v as f64 / 255.0);
    let (w, h) = (img.width() as f32, img.height() as f32);
    let sky_from_clip = camera.matrices(w / h).1.inverse();
    let (mut sum, mut sr) = (0.0, 0.0);
    for (x, y, p) in img.enumerate_pixels() {
        let (u, v) = ((x as f32 + 0.5) / w * 2.0 - 1.0, 1.0 - (y as f32 + 0.5) / h * 2.0);
        let d = sky_from_clip * glam::Vec4::new(u, v, 0.5, 1.0);
        if (d.truncate() / d.w).normalize().y > 0.0 {
            // A pixel of a face at distance 1 covers (2 / w)^2 / (1 + u^2 + v^2)^(3/2) sr.
            let weight = (4.0 / (w * h)) as f64 / (1.0 + (u * u + v * v) as f64).powf(1.5);
            sum += weight * (0.2126 * decode(p[0]) + 0.7152 * decode(p[1]) + 0.0722 * decode(p[2]));
            sr += weight;
        }
    }
    (sum, sr)
}

/// An artist flipping the model selector sees the same brightness: the skydome alone (no clouds,
/// no scene, no glare), rendered at the default exposure by `lut`, `hosek` and `preetham` at noon
/// and with the sun 10 degrees up, has nearly the same mean displayed luminance over the sky
/// above the horizon (the five upper faces of a cube round the camera, by solid angle).
#[test]
fn switching_models_keeps_the_exposure() {
    use skytune::render::{Camera, Headless, RenderOptions};
    use skytune::sky::resolved::{SkyModel, SkyModelKind};
    use skytune::sky::FrameInput;
    let mut sky = skytune::sky::builtin::default_sky();
    sky.objects.retain(|o| o.name == "skydome");
    let mut h = Headless::new(GpuContext::headless(AdapterChoice::Cpu).unwrap(), 64, 64).unwrap();
    h.set_sky(&sky).unwrap();
    // The morning hour whose sun stands 10 degrees up, by bisection (the sun rises till noon).
    let elevation = |hour: f32| skytune::sky::eval::azimuth_elevation(sky.path_at(sky.sun_path, hour).0).1;
    let (mut lo, mut hi) = (0.0f32, 12.0f32);
    for _ in 0..30 {
        let mid = 0.5 * (lo + hi);
        if elevation(mid) < 10.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let options = RenderOptions { scene: false, glare: false, ..RenderOptions::default() };
    // Below the horizon the analytic models repeat the horizon, the physical ones darken
    // towards the ground: the sky above it is what is compared.
    let views = [(0.0, 0.0), (90.0, 0.0), (180.0, 0.0), (270.0, 0.0), (0.0, 90.0)];
    for (hour, label) in [(12.0, "noon"), (hi, "sun at 10 degrees")] {
        let means: Vec<(SkyModelKind, f64)> = [SkyModelKind::Lut, SkyModelKind::Hosek, SkyModelKind::Preetham]
            .into_iter()
            .map(|kind| {
                let input = FrameInput { sky_model: Some(SkyModel { kind, ..sky.model }), ..FrameInput::new(hour, 0.0) };
                let (sum, sr) = views.iter().fold((0.0, 0.0), |(s, n), &(yaw_deg, pitch_deg)| {
                    let camera = Camera { yaw_deg, pitch_deg, fov_y_deg: 90.0, ..Camera::default() };
                    let (a, b) = sky_luminance(&h.render(&sky, &input, &camera, &options).unwrap(), &camera);
                    (s + a, n + b)
                });
                (kind, sum / sr)
            })
            .collect();
        eprintln!("{label}: {means:?}");
        let (lo, hi) = means.iter().fold((f64::INFINITY, 0.0f64), |(a, b), m| (a.min(m.1), b.max(m.1)));
        assert!(hi / lo < 1.1, "{label}: mean displayed luminance {means:?} differs by {:.0}%", (hi / lo - 1.0) * 100.0);
    }
}

/// Median and worst of the per-channel relative errors (as in [`worst_errors`]) per regime.
fn median_and_worst(cases: &[Case], model: &[[f32; 3]], reference: &[[f64; 3]]) -> [(f64, f64); 3] {
    let mut errors: [Vec<f64>; 3] = Default::default();
    for (i, c) in cases.iter().enumerate() {
        let peak = cases.iter().zip(reference).filter(|(d, _)| d.sun_elev_deg == c.sun_elev_deg).flat_map(|(_, r)| r.iter().copied()).fold(0.0, f64::max);
        let regime = if c.sun_elev_deg >= 10.0 {
            0
        } else if c.sun_elev_deg >= 0.0 {
            1
        } else {
            2
        };
        for ch in 0..3 {
            errors[regime].push((model[i][ch] as f64 - reference[i][ch]).abs() / reference[i][ch].max(0.01 * peak).max(1e-30));
        }
    }
    errors.map(|mut e| {
        if e.is_empty() {
            return (0.0, 0.0);
        }
        e.sort_by(f64::total_cmp);
        (e[e.len() / 2], e[e.len() - 1])
    })
}

#[test]
fn precomputed_matches_the_reference() {
    use skytune::atmosphere::PrecomputedSettings;
    let atm = Atmosphere::default();
    let ctx = GpuContext::headless(AdapterChoice::Cpu).unwrap();
    let probe = RadianceProbe::new(&ctx, &ShaderLibrary::embedded()).unwrap();
    // Order 1 alone against the reference's single scattering: the tables' parametrisation and
    // interpolation (thresholds day, low sun, twilight: docs/sky-models.md). The worst cases are
    // the Earth's shadow near the anti-solar horizon with the sun between two texels of mu_s.
    let cases = grid();
    let single_reference = Reference::new(atm, ReferenceSettings { max_order: 1, ..Default::default() });
    let single_exact: Vec<[f64; 3]> = cases.iter().map(|c| single_reference.radiance(c)).collect();
    let order1 = probe.precomputed(&ctx, &atm, &PrecomputedSettings { orders: 1, ..Default::default() }, &cases).unwrap();
    assert!(order1.iter().flatten().all(|x| x.is_finite() && *x >= 0.0), "NaN or negative radiance");
    let errors = median_and_worst(&cases, &order1, &single_exact);
    eprintln!("precomputed, order 1 against single scattering (median, worst): {errors:.4?}");
    for (regime, ((median, worst), (median_limit, worst_limit))) in ["day", "low sun", "twilight"].iter().zip(errors.iter().zip([(0.005, 0.04), (0.01, 0.1), (0.05, 1.2)])) {
        assert!(*median <= median_limit && *worst <= worst_limit, "precomputed order 1, {regime}: median {median:.4}, worst {worst:.4}");
    }
    // Every order at the defaults against the reference with every order (its Monte Carlo noise
    // is part of the error).
    let mut cases = Vec::new();
    for sun in [-4.0, 2.0, 8.0, 30.0, 70.0] {
        for view in [-5.0, 3.0, 20.0, 80.0] {
            for az in [30.0, 150.0] {
                cases.push(Case { camera_km: 0.2, albedo: 0.3, sun_elev_deg: sun, view_elev_deg: view, rel_azimuth_deg: az, distance_km: None });
            }
        }
    }
    let reference = Reference::new(atm, ReferenceSettings { paths: 2048, ..Default::default() });
    let exact: Vec<[f64; 3]> = cases.iter().map(|c| reference.radiance(c)).collect();
    let all = probe.precomputed(&ctx, &atm, &PrecomputedSettings::default(), &cases).unwrap();
    assert!(all.iter().flatten().all(|x| x.is_finite() && *x >= 0.0), "NaN or negative radiance");
    let errors = median_and_worst(&cases, &all, &exact);
    eprintln!("precomputed, every order against the reference (median, worst): {errors:.4?}");
    for (regime, ((median, worst), (median_limit, worst_limit))) in ["day", "low sun", "twilight"].iter().zip(errors.iter().zip([(0.03, 0.12), (0.03, 0.15), (0.08, 0.3)])) {
        assert!(*median <= median_limit && *worst <= worst_limit, "precomputed, {regime}: median {median:.4}, worst {worst:.4}");
    }
    // A second evaluation with the same atmosphere, settings and albedo reuses the tables.
    let builds = probe.precomputed_builds.get();
    probe.precomputed(&ctx, &atm, &PrecomputedSettings::default(), &cases[..4]).unwrap();
    assert_eq!(probe.precomputed_builds.get(), builds, "nothing changed: the tables stay");
    // Orders add light: with every order the sky is brighter than with one.
    let one = probe.precomputed(&ctx, &atm, &PrecomputedSettings { orders: 1, ..Default::default() }, &cases).unwrap();
    let brighter = all.iter().zip(&one).filter(|(a, o)| a[2] > o[2] * 1.05).count();
    assert!(brighter > cases.len() / 2, "{brighter} of {} cases gain blue from higher orders", cases.len());
}

#[test]
fn half_precision_tables_read_as_single_precision_ones() {
    use skytune::atmosphere::{PrecomputedSettings, TablePrecision};
    let ctx = GpuContext::headless(AdapterChoice::Cpu).unwrap();
    let probe = RadianceProbe::new(&ctx, &ShaderLibrary::embedded()).unwrap();
    let cases = grid();
    // A dense, hazy atmosphere too: its horizon holds the tables' largest values.
    let hazy = skytune::atmosphere::dome::Haze::Hazy.atmosphere();
    for atm in [Atmosphere::default(), hazy] {
        let single = PrecomputedSettings { precision: TablePrecision::Single, ..PrecomputedSettings::SMALL };
        let half = PrecomputedSettings { precision: TablePrecision::Half, ..single };
        let a = probe.precomputed(&ctx, &atm, &single, &cases).unwrap();
        let builds = probe.precomputed_builds.get();
        let b = probe.precomputed(&ctx, &atm, &half, &cases).unwrap();
        assert_eq!(probe.precomputed_builds.get(), builds + 1, "a change of storage rebuilds the tables");
        let peak = a.iter().flatten().cloned().fold(0.0f32, f32::max);
        // A half holds 11 significant bits: 0.05% per texel, a little more after interpolation;
        // values far below the peak (the Earth's shadow) are compared against 1e-4 of it.
        let worst = a.iter().zip(&b).flat_map(|(x, y)| (0..3).map(move |c| (x[c] - y[c]).abs() / x[c].max(1e-4 * peak))).fold(0.0f32, f32::max);
        eprintln!("half against single precision: worst relative difference {worst}");
        assert!(worst < 2e-3, "half against single precision: worst relative difference {worst}");
        // The single-precision tables stay in the buffer after packing: rounding shows that the
        // lookup read the packed one.
        assert!(a != b, "half precision read the single-precision tables");
        // Both stay kept: going back to single precision builds nothing, and reads the same.
        let builds = probe.precomputed_builds.get();
        assert_eq!(probe.precomputed(&ctx, &atm, &single, &cases).unwrap(), a, "the kept single-precision tables read as before");
        assert_eq!(probe.precomputed_builds.get(), builds, "tables built before another set are kept");
    }
}
