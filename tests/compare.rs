//! `skytune compare` and the compare module on lavapipe: identical inputs, a known edit, the split
//! layout, and the tier comparison the render tests make.

mod common;

use std::path::Path;
use std::process::Command;

use skytune::render::{Camera, RenderOptions};
use skytune::sky::{load_sky_file, FrameInput, Tier};

fn skytune() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_skytune"));
    c.env("SKYTUNE_ADAPTER", "cpu").env_remove("DISPLAY");
    c
}

/// Runs `skytune compare`; returns (success, stdout + stderr).
fn compare(args: &[&str], out: &Path) -> (bool, String) {
    let o = skytune().arg("compare").args(args).arg("--out").arg(out).output().unwrap();
    (o.status.success(), format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr)))
}

/// The figures of the summary line: FLIP mean, pixels beyond the tolerance (%), mean channel difference.
fn figures(output: &str) -> (f64, f64, f64) {
    let line = output.lines().find(|l| l.starts_with("FLIP mean")).unwrap_or_else(|| panic!("no summary in {output}"));
    let number_after = |key: &str| -> f64 {
        let rest = &line[line.find(key).unwrap_or_else(|| panic!("{key} in {line}")) + key.len()..];
        rest.trim_start().split(|c: char| !(c.is_ascii_digit() || c == '.')).next().unwrap().parse().unwrap()
    };
    (number_after("FLIP mean"), number_after("/255:"), number_after("mean channel difference"))
}

#[test]
fn identical_sides_differ_by_nothing() {
    let (dir, sky) = common::default_sky_folder();
    let out = dir.path().join("same.png");
    let sky = sky.to_str().unwrap();
    let (ok, text) = compare(&[sky, sky, "--size", "96x54", "--hour", "18.5", "--max-flip-mean", "0", "--max-differing", "0"], &out);
    assert!(ok, "{text}");
    assert_eq!(figures(&text), (0.0, 0.0, 0.0), "{text}");
    assert!(image::open(&out).is_ok());
}

#[test]
fn a_darkened_gradient_bitmap_shows_in_the_sky_only_and_fails_a_threshold() {
    let (dir, sky) = common::default_sky_folder();
    let edited = dir.path().join("edited");
    std::fs::create_dir_all(&edited).unwrap();
    for entry in std::fs::read_dir(sky.parent().unwrap()).unwrap() {
        let path = entry.unwrap().path();
        if path.is_file() {
            std::fs::copy(&path, edited.join(path.file_name().unwrap())).unwrap();
        }
    }
    // The skydome's horizon-zenith gradients at half brightness (the fog and the scene's light
    // come from other bitmaps, so the ground must not change).
    for name in ["gradient_clear.png", "gradient_cloudy.png", "gradient_storm.png"] {
        let mut img = image::open(edited.join(name)).unwrap().to_rgba8();
        for p in img.pixels_mut() {
            for c in 0..3 {
                p[c] /= 2;
            }
        }
        img.save(edited.join(name)).unwrap();
    }
    let edited_sky = edited.join("sky.toml");
    let out = dir.path().join("diff.png");
    let (w, h) = (160u32, 90u32);
    let args = ["--size", "160x90", "--hour", "13", "--view", "south", "--no-glare", "--layout", "diff", "--max-flip-mean", "0.001"];
    let (ok, text) = compare(&[&[sky.to_str().unwrap(), edited_sky.to_str().unwrap()], &args[..]].concat(), &out);
    assert!(!ok, "the edit is above the threshold: {text}");
    assert!(text.contains("is above --max-flip-mean"), "{text}");

    // The same figures from renders made here, through the library.
    let camera = Camera::preset("south").unwrap();
    let opts = RenderOptions { glare: false, ..Default::default() };
    let render = |path: &Path| {
        let s = load_sky_file(path).unwrap();
        let mut hl = common::headless(w, h);
        hl.set_sky(&s).unwrap();
        hl.render(&s, &FrameInput::new(13.0, 0.0), &camera, &opts).unwrap()
    };
    let (a, b) = (render(&sky), render(&edited_sky));
    let d = skytune::measure::image_diff::difference(&a, &b, 12);
    let (flip, differing_pct, mean) = figures(&text);
    assert!(
        (flip - d.flip.mean as f64).abs() < 1e-4 && (differing_pct - d.pixels.differing * 100.0).abs() < 0.01 && (mean - d.pixels.mean).abs() < 1e-3,
        "{text} vs {}",
        d.summary()
    );

    // The heat map is black where the scene covers the sky (the bottom rows) and lit above.
    let heat = image::open(&out).unwrap().to_rgba8();
    assert_eq!(heat.dimensions(), (w, h + skytune::measure::image_diff::LEGEND_HEIGHT));
    let black = skytune::measure::image_diff::magma(0.0);
    let rows = |ys: std::ops::Range<u32>| ys.flat_map(|y| (0..w).map(move |x| (x, y))).collect::<Vec<_>>();
    assert!(rows(h - 15..h).iter().all(|&(x, y)| *heat.get_pixel(x, y) == black), "the ground did not change");
    let lit = rows(0..15).iter().filter(|&&(x, y)| *heat.get_pixel(x, y) != black).count();
    assert!(lit as f64 > 0.9 * (15 * w) as f64, "the upper sky changed everywhere: {lit}");
    // Half the gradient's brightness: the sky's channels drop by a large share.
    let sky_drop = rows(0..15).iter().map(|&(x, y)| (0..3).map(|c| a.get_pixel(x, y)[c] as f64 - b.get_pixel(x, y)[c] as f64).sum::<f64>()).sum::<f64>()
        / rows(0..15).iter().map(|&(x, y)| (0..3).map(|c| a.get_pixel(x, y)[c] as f64).sum::<f64>()).sum::<f64>();
    assert!((0.25..0.6).contains(&sky_drop), "the upper sky lost {sky_drop:.2} of its brightness");
}

#[test]
fn split_layout_shows_a_left_and_b_right() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("split.png");
    let (ok, text) = compare(&["@hour=12", "@hour=21", "--size", "120x68", "--no-glare", "--layout", "split", "--split", "0.5"], &out);
    assert!(ok, "{text}");
    let picture = image::open(&out).unwrap().to_rgba8();
    let camera = Camera::preset("south").unwrap();
    let sky = skytune::sky::builtin::default_sky();
    let mut hl = common::headless(120, 68);
    hl.set_sky(&sky).unwrap();
    let opts = RenderOptions { glare: false, ..Default::default() };
    let day = hl.render(&sky, &FrameInput::new(12.0, 0.0), &camera, &opts).unwrap();
    let night = hl.render(&sky, &FrameInput::new(21.0, 0.0), &camera, &opts).unwrap();
    let half = |img: &image::RgbaImage, x0: u32, x1: u32| image::imageops::crop_imm(img, x0, 0, x1 - x0, 68).to_image();
    assert_eq!(common::diff(&half(&picture, 0, 59), &half(&day, 0, 59), 2).0.differing, 0.0, "left half is A");
    assert_eq!(common::diff(&half(&picture, 61, 120), &half(&night, 61, 120), 2).0.differing, 0.0, "right half is B");
    assert!(common::diff(&day, &night, 12).0.differing > 0.3, "the two sides really differ");
}

#[test]
fn tier_comparison_reproduces_the_tier_test() {
    // The settings of tests/render.rs `tier_two_draws_fallback_passes_close_to_tier_four`.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("tiers.png");
    let (ok, text) = compare(&["@tier=4", "@tier=2", "--size", "160x90", "--hour", "21.5", "--yaw", "220", "--pitch", "20", "--no-glare", "--tolerance", "12"], &out);
    assert!(ok, "{text}");
    let sky = skytune::sky::builtin::default_sky();
    let camera = Camera { yaw_deg: 220.0, pitch_deg: 20.0, ..Camera::default() };
    let opts = RenderOptions { glare: false, ..Default::default() };
    let mut hl = common::headless(160, 90);
    hl.set_sky(&sky).unwrap();
    let mut input = FrameInput::new(21.5, 0.0);
    let tier4 = hl.render(&sky, &input, &camera, &opts).unwrap();
    input.tier = Tier::new(2).unwrap();
    let tier2 = hl.render(&sky, &input, &camera, &opts).unwrap();
    let (d, _) = common::diff(&tier2, &tier4, 12);
    let (_, differing_pct, mean) = figures(&text);
    assert!((differing_pct - d.differing * 100.0).abs() < 0.01 && (mean - d.mean).abs() < 1e-3, "{text} vs {d:?}");
    // And the bounds that test asserts.
    assert!(differing_pct / 100.0 <= 0.02 && mean <= 2.0, "{text}");
}
