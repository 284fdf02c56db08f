//! The speed-against-accuracy benchmark: its error figures, the committed reference dataset, the
//! cheap representations, and the quick benchmark end to end on lavapipe (CSV and both charts).

use skytune::atmosphere::dome::{self, DomeDir, Haze};
use skytune::atmosphere::reference::Case;
use skytune::atmosphere::represent::{self, Baked, DomeMapTable, Regression};
use skytune::atmosphere::Rgb;
use skytune::measure::model_points::{self, ChartRow};

#[test]
fn error_figures_are_zero_for_the_reference_and_scale_with_a_bias() {
    let dirs = dome::dome_directions(8, 12);
    let total: f64 = dirs.iter().map(|d| d.weight_sr).sum();
    assert!((total - 2.0 * std::f64::consts::PI).abs() < 1e-9, "the dome's weights cover the hemisphere");
    let reference: Vec<Rgb> = dirs.iter().map(|d| [0.01 + 0.001 * d.elev_deg.to_radians().cos(), 0.02, 0.03]).collect();
    let same = dome::dome_error(&dirs, &reference, &reference);
    assert_eq!(same.rel_rmse, [0.0; 3]);
    assert_eq!((same.psnr_db, same.de_mean, same.de_p95), (99.0, 0.0, 0.0));
    let brighter: Vec<Rgb> = reference.iter().map(|l| l.map(|c| c * 1.1)).collect();
    let e = dome::dome_error(&dirs, &reference, &brighter);
    for c in e.rel_rmse {
        assert!((c - 0.1).abs() < 1e-12, "a 10% bias is a relative RMSE of 0.1, found {c}");
    }
    assert!(e.de_mean > 0.5 && e.de_p95 >= e.de_mean && e.psnr_db < 60.0, "{e:?}");
    let much_brighter: Vec<Rgb> = reference.iter().map(|l| l.map(|c| c * 1.5)).collect();
    let e2 = dome::dome_error(&dirs, &reference, &much_brighter);
    assert!(e2.de_mean > e.de_mean && e2.psnr_db < e.psnr_db, "a larger error gives larger figures");
    // NaN or negative model values count as black, never as NaN figures.
    let broken: Vec<Rgb> = reference.iter().map(|_| [f64::NAN, -1.0, 0.0]).collect();
    let e3 = dome::dome_error(&dirs, &reference, &broken);
    assert!(e3.de_mean.is_finite() && e3.psnr_db.is_finite());
}

#[test]
fn de2000_matches_published_pairs_through_linear_rgb() {
    // Identical colours, symmetry, and a grey step, where dE2000 is its lightness term alone:
    // Y 0.18 is L* 49.50 and Y 0.28 is L* 59.89; S_L = 1 + 0.015 (L-bar - 50)^2 / sqrt(20 +
    // (L-bar - 50)^2) = 1.0511 at L-bar 54.69, so dE2000 = 10.39 / 1.0511 = 9.886.
    let grey = |y: f64| [y; 3];
    assert_eq!(dome::de2000(grey(0.18), grey(0.18)), 0.0);
    let (a, b) = (dome::de2000(grey(0.18), grey(0.28)), dome::de2000(grey(0.28), grey(0.18)));
    assert!((a - b).abs() < 1e-4);
    let l = |y: f64| 116.0 * y.cbrt() - 16.0;
    let (l1, l2) = (l(0.18), l(0.28));
    let mean = 0.5 * (l1 + l2) - 50.0;
    let expected = (l2 - l1) / (1.0 + 0.015 * mean * mean / (20.0 + mean * mean).sqrt());
    assert!((a - expected).abs() < 0.01, "dE2000 of L* {l1:.2} vs {l2:.2}: expected {expected:.3}, found {a}");
}

#[test]
fn committed_reference_covers_every_atmosphere_and_sun() {
    let r = dome::committed_reference().expect("assets/reference_dome.csv matches the benchmark's settings");
    for h in Haze::ALL {
        for s in dome::SUN_ELEVATIONS_DEG {
            let sun = r.sun(h, s).unwrap_or_else(|| panic!("{} sun {s} missing", h.name()));
            assert_eq!(sun.radiance.len(), 96);
            assert!(sun.radiance.iter().flatten().all(|v| v.is_finite() && *v >= 0.0));
        }
    }
    // Day is brighter than night, hazy skies are whiter at the horizon than clean ones.
    let zenith_blue = |h: Haze, s: f64| r.sun(h, s).map(|d| d.radiance[95][2]).unwrap_or(0.0);
    assert!(zenith_blue(Haze::Default, 45.0) > 100.0 * zenith_blue(Haze::Default, -10.0));
    let horizon_ratio = |h: Haze| r.sun(h, 30.0).map(|d| d.radiance[6][0] / d.radiance[6][2]).unwrap_or(0.0);
    assert!(horizon_ratio(Haze::Hazy) > horizon_ratio(Haze::Clean));
}

/// A smooth made-up sky for the representations: brighter towards the sun and the horizon.
fn smooth(sun: f64, elev: f64, az: f64) -> Rgb {
    let c = represent::cos_to_sun(sun, elev, az);
    let k = (1.0 + sun.max(-10.0) / 100.0) * (1.0 + 0.5 * c * c) * (1.0 + (1.0 - elev.to_radians().sin()).powi(2));
    [0.01 * k, 0.015 * k, 0.03 * k]
}

fn source(sun: f64, cases: &[Case]) -> anyhow::Result<Vec<Rgb>> {
    Ok(cases.iter().map(|c| smooth(sun, c.view_elev_deg, c.rel_azimuth_deg)).collect())
}

#[test]
fn dome_map_reproduces_its_texels_and_converges() {
    let table = DomeMapTable::build(24, &mut source).expect("built");
    // Away from the edges, where the text's margin puts texel centres outside the mapping's range.
    for (j, i) in [(1, 1), (5, 17), (22, 22)] {
        let (e, a) = DomeMapTable::texel_direction(24, i, j);
        let (got, want) = (table.radiance(represent::TABLE_SUNS_DEG[9], e, a), smooth(represent::TABLE_SUNS_DEG[9], e, a));
        for c in 0..3 {
            assert!((got[c] - want[c]).abs() < 1e-12, "texel ({i}, {j}): {got:?} vs {want:?}");
        }
    }
    let dirs = dome::dome_directions(8, 12);
    let err = |res: usize| {
        let t = DomeMapTable::build(res, &mut source).expect("built");
        let m = represent::over_dome(&dirs, |e, a| t.radiance(20.0, e, a));
        let r = represent::over_dome(&dirs, |e, a| smooth(20.0, e, a));
        dome::dome_error(&dirs, &r, &m).rel_rmse_mean()
    };
    assert!(err(48) < err(8), "a finer map is closer");
}

#[test]
fn regression_fits_its_own_basis_exactly() {
    // 0.02 + 0.01 cos^2: inside the regression's basis, so reconstructed to rounding.
    let mut in_basis = |sun: f64, cases: &[Case]| -> anyhow::Result<Vec<Rgb>> {
        Ok(cases.iter().map(|c| [0.02 + 0.01 * represent::cos_to_sun(sun, c.view_elev_deg, c.rel_azimuth_deg).powi(2); 3]).collect())
    };
    let r = Regression::build(&mut in_basis).expect("fitted");
    for (e, a) in [(5.0, 10.0), (45.0, 170.0), (80.0, 90.0)] {
        let want = 0.02 + 0.01 * represent::cos_to_sun(30.0, e, a).powi(2);
        let got = r.radiance(represent::TABLE_SUNS_DEG[12], e, a)[1];
        let exact = 0.02 + 0.01 * represent::cos_to_sun(represent::TABLE_SUNS_DEG[12], e, a).powi(2);
        assert!((got - exact).abs() < 1e-9, "{got} vs {exact} (at 30 degrees {want})");
    }
}

#[test]
fn baked_bitmaps_round_trip_within_their_quantisation() {
    let hours: [f64; 24] = std::array::from_fn(|h| represent::equinox_elevation_deg(h as f64));
    let baked = Baked::build(64, &hours, &mut [&mut source]).expect("baked");
    assert_eq!(baked.gradient.len(), 1);
    assert_eq!(baked.gradient[0].len(), 64 * 24);
    let dirs: Vec<DomeDir> = dome::dome_directions(8, 12);
    // At a whole hour (no interpolation between columns) the display image is within a few
    // 8-bit steps of the source's: dE2000 small.
    let sun = represent::equinox_elevation_deg(9.0);
    let got = represent::over_dome(&dirs, |e, a| baked.radiance(0, 9.0, sun, e, a));
    let want = represent::over_dome(&dirs, |e, a| smooth(sun, e, a));
    let e = dome::dome_error(&dirs, &want, &got);
    assert!(e.de_mean < 2.5, "baked at a whole hour: {e:?}");
}

#[test]
fn pareto_front_has_no_dominated_point() {
    let row = |id: &str, ms: f64, de: f64| ChartRow {
        id: id.into(),
        model: "x".into(),
        rel_rmse_r: 0.0,
        rel_rmse_g: 0.0,
        rel_rmse_b: 0.0,
        psnr_db: 0.0,
        de_mean: de,
        de_p95: de,
        rmse_day: 0.0,
        rmse_low_sun: 0.0,
        rmse_twilight: 0.0,
        noise_day: 0.0,
        noise_low_sun: 0.0,
        noise_twilight: 0.0,
        de_day: de,
        de_low_sun: de,
        de_twilight: de,
        model_gpu_ms_moving: 0.0,
        model_gpu_ms_still: 0.0,
        cpu_ms: 0.0,
        frame_ms_moving: ms,
        frame_ms_still: ms,
        floor_ms: 1.0,
        build_ms: 0.0,
        fit_turbidity: None,
        fit_scale: None,
        pareto: false,
    };
    let mut rows = vec![row("cheap", 1.0, 5.0), row("dominated", 2.0, 6.0), row("accurate", 3.0, 1.0), row("equal-cost-worse", 3.0, 2.0)];
    model_points::mark_pareto(&mut rows);
    let front: Vec<&str> = rows.iter().filter(|r| r.pareto).map(|r| r.id.as_str()).collect();
    assert_eq!(front, ["cheap", "accurate"]);
    let back = model_points::rows_from_csv(&model_points::rows_to_csv(&rows)).expect("round trip");
    assert_eq!(back, rows);
}

#[test]
fn committed_benchmark_lists_every_point() {
    let rows = model_points::rows_from_csv(model_points::COMMITTED_CSV).expect("docs/models.csv parses");
    for p in model_points::points() {
        assert!(rows.iter().any(|r| r.id == p.id), "docs/models.csv lacks {}: re-run skytune bench models", p.id);
    }
}

#[test]
fn quick_benchmark_writes_the_csv_and_both_charts() {
    let out = tempfile::tempdir().expect("temp dir");
    let status = std::process::Command::new(env!("CARGO_BIN_EXE_skytune"))
        .args(["bench", "models", "--quick", "--cpu", "--frames", "3", "--size", "320x180", "--out"])
        .arg(out.path())
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .status()
        .expect("running skytune");
    assert!(status.success());
    let csv = std::fs::read_to_string(out.path().join("models.csv")).expect("models.csv");
    let rows = model_points::rows_from_csv(&csv).expect("parses");
    let quick: Vec<String> = model_points::points().into_iter().filter(|p| p.quick).map(|p| p.id).collect();
    assert_eq!(rows.iter().map(|r| r.id.clone()).collect::<Vec<_>>(), quick);
    assert!(rows.iter().all(|r| r.de_mean.is_finite() && r.frame_ms_moving > 0.0 && r.floor_ms > 0.0 && r.floor_ratio_still() > 1.0), "{rows:?}");
    // The model's own cost: a sky-view map recomputed when the sun moves, none for the bitmaps.
    let row = |id: &str| rows.iter().find(|r| r.id == id).unwrap_or_else(|| panic!("no {id}"));
    assert!(row("lut-default").model_gpu_ms_moving > 0.0 && row("lut-default").model_gpu_ms_moving > row("lut-default").model_gpu_ms_still, "{:?}", row("lut-default"));
    assert!(rows.iter().filter(|r| r.model == "baked").all(|r| r.model_gpu_ms_moving == 0.0), "{rows:?}");
    // Every regime has an error and the reference's noise as its error bar.
    for r in &rows {
        for g in dome::Regime::ALL {
            let (e, n) = r.regime(g);
            assert!(e.is_finite() && e > 0.0 && n > 0.0 && n < 0.5, "{} {g:?}: {e} +- {n}", r.id);
        }
    }
    assert!(rows.iter().any(|r| r.pareto));
    // lut (multiple scattering) is closer to the reference than single scattering.
    let de = |id: &str| rows.iter().find(|r| r.id == id).map_or(f64::NAN, |r| r.de_mean);
    assert!(de("lut-default") < de("single-erf-32"));
    for (stem, size) in [("models-cost", (1800, 720)), ("models-by-sun", (1100, 700))] {
        let svg = std::fs::read_to_string(out.path().join(format!("{stem}.svg"))).expect("svg");
        assert!(svg.contains("<svg") && svg.contains("lut-default"), "{stem}.svg has the points' labels");
        let png = image::open(out.path().join(format!("{stem}.png"))).expect("png").to_rgb8();
        assert_eq!(png.dimensions(), size);
        assert!(png.pixels().any(|p| p.0 != [255, 255, 255]), "{stem}.png is not blank");
    }
    let by_sun = std::fs::read_to_string(out.path().join("models-by-sun.csv")).expect("by sun");
    assert_eq!(by_sun.lines().count(), 1 + quick.len() * dome::QUICK_SUN_ELEVATIONS_DEG.len());
    let md = std::fs::read_to_string(out.path().join("models.md")).expect("md");
    assert!(md.contains("dE2000") && md.contains("model GPU ms, sun moving / still") && md.contains("frame / floor"), "{md}");
    assert!(md.contains("## Accuracy by regime") && md.contains("twilight (sun 0 deg and below) rel. RMSE"), "{md}");
    assert!(md.contains("the reference's relative standard error per value"), "{md}");
    // `precomputed` per pixel and through the map, side by side: both measured, the map's
    // lookups far fewer than a frame's pixels.
    let section = md.split("## Per-pixel lookup against the sky-view map").nth(1).expect("the per-pixel against map section");
    let cells = |path: &str| -> Vec<f64> {
        let line = section.lines().find(|l| l.starts_with("| precomputed-small |") && l.contains(&format!("| {path} |"))).unwrap_or_else(|| panic!("no {path} row"));
        line.split('|').skip(3).filter_map(|c| c.trim().parse().ok()).collect()
    };
    let (pixel, map) = (cells("per pixel"), cells("sky-view map"));
    assert_eq!(pixel[0], 320.0 * 180.0, "{section}");
    assert!(map[0] < pixel[0] && pixel.iter().chain(&map).all(|v| v.is_finite() && *v > 0.0), "{section}");

    // The error part in 3 shards, merged folder by folder: the unsharded run's file, byte for byte.
    let shards = tempfile::tempdir().expect("temp dir");
    let run = |args: &[&str]| {
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_skytune")).args(args).current_dir(env!("CARGO_MANIFEST_DIR")).output().expect("running skytune");
        assert!(o.status.success(), "skytune {args:?}: {}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    let dir = |k: usize| shards.path().join(format!("part{k}")).display().to_string();
    for k in 1..=3 {
        run(&["bench", "models", "--quick", "--cpu", "--part", "errors", "--shard", &format!("{k}/3"), "--out", &dir(k)]);
    }
    // A complete shard is not computed again.
    assert!(run(&["bench", "models", "--quick", "--cpu", "--part", "errors", "--shard", "2/3", "--out", &dir(2)]).contains("skipped"));
    let merged = shards.path().join("merged");
    run(&["merge", "--out", &merged.display().to_string(), &dir(3), &dir(1), &dir(2)]);
    assert_eq!(std::fs::read_to_string(merged.join("models-by-sun.csv")).expect("merged"), by_sun, "3 shards of the errors merged differ from the unsharded run");
}
