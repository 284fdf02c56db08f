//! `skytune bake`: the baked folder is a valid sky that renders, its bitmaps are what the model
//! gives at the baked hours (within 8-bit quantisation), and the command line writes the same.

mod common;

use skytune::atmosphere::dome;
use skytune::atmosphere::LutSettings;
use skytune::measure::model_points::{Evaluator, Method};
use skytune::render::{AdapterChoice, Camera, GpuContext, RenderOptions};
use skytune::sky::FrameInput;

#[test]
fn baked_folder_is_a_sky_that_matches_its_model_at_the_baked_hours() {
    let ctx = GpuContext::headless(AdapterChoice::Cpu).expect("lavapipe");
    let ev = Evaluator::new(&ctx).expect("probe");
    let sky = skytune::sky::builtin::default_sky();
    let method = Method::Lut(LutSettings::default());
    let baked = skytune::measure::bake::bake(&ev, &sky, method, 24, 2).expect("baked");
    assert_eq!((baked.rows, baked.gradient.len(), baked.halo_color.len()), (24, 2, 2));
    // The hazier weather step is whiter at the horizon than the clear one at noon.
    let horizon_row = 20;
    let px = |w: usize| baked.gradient[w][horizon_row * 24 + 12].map(f64::from);
    let saturation = |c: [f64; 3]| c[2] - c[0];
    assert!(saturation(px(1)) < saturation(px(0)), "clear {:?} vs hazy {:?}", px(0), px(1));

    // At a baked hour (no interpolation between columns) the bitmaps reproduce the model.
    let dirs = dome::dome_directions(6, 12);
    let hours = skytune::measure::bake::sun_elevations(&sky);
    let prepared = ev.prepare(&method, &skytune::measure::bake::weather_atmosphere(&sky, 0, 2), &[]).expect("prepared");
    for hour in [8usize, 12, 16] {
        let sun = hours[hour];
        let want = ev.radiance(&prepared, &skytune::measure::bake::weather_atmosphere(&sky, 0, 2), sun, &dome::cases(sun, &dirs)).expect("model");
        // The baked sky's own sun here is the sky's; azimuths are relative to it.
        let got = skytune::atmosphere::represent::over_dome(&dirs, |e, a| baked.radiance(0, hour as f64, sun, e, a));
        let e = dome::dome_error(&dirs, &want, &got);
        assert!(e.de_mean < 3.0, "hour {hour} (sun {sun:.1}): {e:?}");
    }

    let dir = tempfile::tempdir().expect("temp dir");
    skytune::measure::bake::write_folder(dir.path(), &sky, &baked, "lut").expect("written");
    let loaded = skytune::sky::load_sky_file(&dir.path().join("sky.toml")).unwrap_or_else(|e| panic!("the baked sky loads: {e}"));
    assert_eq!(loaded.objects.len(), 1);
    let mut h = common::headless(96, 64);
    h.set_sky(&loaded).expect("uploaded");
    let camera = Camera { pitch_deg: 30.0, ..Camera::default() };
    let noon = h.render(&loaded, &FrameInput::new(12.0, 0.0), &camera, &RenderOptions { scene: false, ..Default::default() }).expect("rendered");
    let night = h.render(&loaded, &FrameInput::new(0.0, 0.0), &camera, &RenderOptions { scene: false, ..Default::default() }).expect("rendered");
    let mean = |img: &image::RgbaImage| img.pixels().map(|p| p[0] as f64 + p[1] as f64 + p[2] as f64).sum::<f64>() / img.pixels().len() as f64;
    let blue = |img: &image::RgbaImage| img.pixels().map(|p| p[2] as f64 - p[0] as f64).sum::<f64>() / img.pixels().len() as f64;
    assert!(mean(&noon) > 4.0 * mean(&night).max(1.0), "noon {} vs night {}", mean(&noon), mean(&night));
    assert!(blue(&noon) > 10.0, "the baked noon sky is blue");
}

#[test]
fn bake_command_writes_a_sky_folder() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("baked");
    let status = std::process::Command::new(env!("CARGO_BIN_EXE_skytune"))
        .args(["bake", "--cpu", "--model", "preetham", "--rows", "8", "--weathers", "1", "--out"])
        .arg(&out)
        .status()
        .expect("running skytune");
    assert!(status.success());
    for f in ["sky.toml", "gradient_0.png", "halo.png", "halo_color.png", "fog.png", "sun_ambient.png", "sun_diffuse.png"] {
        assert!(out.join(f).exists(), "{f}");
    }
    assert_eq!(image::open(out.join("gradient_0.png")).expect("png").to_rgba8().dimensions(), (24, 8));
    let bad = std::process::Command::new(env!("CARGO_BIN_EXE_skytune")).args(["bake", "--cpu", "--rows", "1", "--out"]).arg(dir.path().join("x")).output().expect("ran");
    assert!(!bad.status.success() && String::from_utf8_lossy(&bad.stderr).contains("--rows"));
}
