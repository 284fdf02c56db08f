//! Exports: linear light (OpenEXR, Radiance HDR) reads back with the values rendered, in radiance
//! units whatever the exposure; cube faces meet without seams; the equirectangular map puts the
//! sun where it is.

mod common;

use skytune::files::export::{self, Format, CUBE_FACES};
use skytune::render::{Camera, RenderOptions};
use skytune::sky::builtin::default_sky;
use skytune::sky::model::SkyModelKind;
use skytune::sky::resolved::{CameraResponse, SkyModel};
use skytune::sky::FrameInput;

fn input(kind: SkyModelKind, exposure_ev: f32, hour: f32) -> FrameInput {
    let sky = default_sky();
    FrameInput { sky_model: Some(SkyModel { kind, camera: CameraResponse { exposure_ev, ..sky.model.camera }, ..sky.model }), ..FrameInput::new(hour, 0.0) }
}

#[test]
fn exr_reads_back_the_linear_values_whatever_the_exposure() {
    let sky = default_sky();
    let mut h = common::headless(64, 36);
    h.set_sky(&sky).unwrap();
    let camera = Camera { pitch_deg: 30.0, ..Camera::default() };
    let options = RenderOptions { scene: false, glare: false, ..Default::default() };
    // The model alone (the gradient pass of the skydome at tier 1, every other object off): the
    // NeL layers are display-referred, so their radiance equivalent follows the exposure.
    let model_only = |ev: f32| FrameInput {
        tier: skytune::sky::Tier::new(1).unwrap(),
        disabled: sky.objects.iter().map(|o| o.name.clone()).filter(|n| n != "skydome").collect(),
        ..input(SkyModelKind::Lut, ev, 10.0)
    };
    let a = export::render_linear(&mut h, &sky, &model_only(5.0), &camera, &options).unwrap();
    let b = export::render_linear(&mut h, &sky, &model_only(3.0), &camera, &options).unwrap();
    // Radiance, not exposed values: two exposures agree within half precision.
    let sky_px: Vec<(f32, f32)> = a.pixels().zip(b.pixels()).map(|(p, q)| (p[2], q[2])).filter(|(p, _)| *p > 0.0).collect();
    let agree = sky_px.iter().filter(|(p, q)| (p - q).abs() <= 4e-3 * p.max(*q) + 1e-7).count();
    assert!(agree as f64 >= 0.95 * sky_px.len() as f64, "{agree} of {} pixels agree", sky_px.len());
    // Blue sky radiance of the default atmosphere at 10 h: about 0.01 to 0.2 sr^-1.
    let mean_blue = sky_px.iter().map(|(p, _)| *p as f64).sum::<f64>() / sky_px.len() as f64;
    assert!((0.005..0.3).contains(&mean_blue), "mean blue radiance {mean_blue}");

    let dir = tempfile::tempdir().unwrap();
    for format in [Format::Exr, Format::Hdr] {
        let path = dir.path().join(format!("sky.{}", format.extension()));
        export::save(&a, format, &path).unwrap();
        let back = image::open(&path).unwrap().to_rgba32f();
        assert_eq!(back.dimensions(), a.dimensions());
        // EXR keeps f32 exactly; RGBE keeps 8 bits of mantissa under an exponent shared by the
        // pixel's channels (so relative to its largest channel).
        let tolerance = if format == Format::Exr { 0.0 } else { 1.0 / 128.0 };
        for (p, q) in a.pixels().zip(back.pixels()) {
            let largest = p[0].max(p[1]).max(p[2]);
            for c in 0..3 {
                assert!((p[c] - q[c]).abs() <= tolerance * largest + 1e-9, "{format:?}: {p:?} -> {q:?}");
            }
        }
    }
}

#[test]
fn the_command_line_writes_the_same_exr() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("noon.exr");
    let status = std::process::Command::new(env!("CARGO_BIN_EXE_skytune"))
        .env("SKYTUNE_ADAPTER", "cpu")
        .args(["render", "--sky-model", "hosek", "--hour", "12", "--no-scene", "--size", "48x27", "--out"])
        .arg(&out)
        .status()
        .unwrap();
    assert!(status.success());
    let from_cli = image::open(&out).unwrap().to_rgba32f();
    let sky = default_sky();
    let mut h = common::headless(48, 27);
    h.set_sky(&sky).unwrap();
    let input = FrameInput { sky_model: Some(SkyModel { kind: SkyModelKind::Hosek, ..sky.model }), ..FrameInput::new(12.0, 0.0) };
    let camera = Camera::preset("south").unwrap();
    let lib = export::render_linear(&mut h, &sky, &input, &camera, &RenderOptions { scene: false, ..Default::default() }).unwrap();
    assert_eq!(from_cli.as_raw(), lib.as_raw());
}

#[test]
fn cube_faces_meet_without_seams() {
    let sky = default_sky();
    let face = 48;
    let mut h = common::headless(face, face);
    h.set_sky(&sky).unwrap();
    for (kind, hour) in [(SkyModelKind::Bitmap, 13.0), (SkyModelKind::Lut, 17.0)] {
        let faces = export::cube_faces(&mut h, &sky, &input(kind, 5.0, hour), &RenderOptions::default(), face, false).unwrap();
        // Every edge texel against the texel across the edge: the direction through the edge
        // point seen from both faces (each sampled at its own border).
        let mut diffs = Vec::new();
        for (i, &(_, forward, up)) in CUBE_FACES.iter().enumerate() {
            let right = forward.cross(up);
            for k in 0..face {
                let t = (k as f32 + 0.5) / face as f32 * 2.0 - 1.0;
                for (sx, sy) in [(-1.0, t), (1.0, t), (t, -1.0), (t, 1.0)] {
                    let dir = (forward + right * sx + up * sy).normalize();
                    // Just inside this face, and just across in the neighbour.
                    let inside = (dir - 1e-3 * (right * sx.signum() * (sx.abs() == 1.0) as i32 as f32 + up * sy.signum() * (sy.abs() == 1.0) as i32 as f32)).normalize();
                    let outside = (dir + 2e-2 * (right * sx.signum() * (sx.abs() == 1.0) as i32 as f32 + up * sy.signum() * (sy.abs() == 1.0) as i32 as f32)).normalize();
                    let (fa, xa, ya) = export::cube_texel(inside, face);
                    let (fb, xb, yb) = export::cube_texel(outside, face);
                    assert_eq!(fa, i);
                    assert_ne!(fb, i);
                    let a = faces[fa].get_pixel((xa as u32).min(face - 1), (ya as u32).min(face - 1)).0;
                    let b = faces[fb].get_pixel((xb as u32).min(face - 1), (yb as u32).min(face - 1)).0;
                    diffs.push((0..3).map(|c| (a[c] - b[c]).abs()).fold(0.0, f32::max));
                }
            }
        }
        diffs.sort_by(f32::total_cmp);
        let mean = diffs.iter().sum::<f32>() / diffs.len() as f32;
        let p95 = diffs[diffs.len() * 95 / 100];
        // Neighbouring texels of a smooth sky: a seam would show as a large mean offset.
        assert!(mean < 6.0 / 255.0 && p95 < 20.0 / 255.0, "{kind:?}: edge texels differ by {:.1}/255 on average, p95 {:.1}/255", mean * 255.0, p95 * 255.0);
    }
}

#[test]
fn the_equirectangular_map_puts_the_sun_where_it_is() {
    let sky = default_sky();
    let mut h = common::headless(64, 64);
    h.set_sky(&sky).unwrap();
    let input = input(SkyModelKind::Hosek, 0.0, 10.0);
    let towards_sun = sky.evaluate(&input).towards_sun;
    let faces = export::cube_faces(&mut h, &sky, &input, &RenderOptions { scene: false, glare: false, ..Default::default() }, 48, true).unwrap();
    let (w, ht) = (192, 96);
    let map = export::equirect_from_cube(&faces, w, ht);
    let (mut best, mut at) = (f32::MIN, (0, 0));
    for (x, y, p) in map.enumerate_pixels() {
        let l = 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
        if l > best {
            best = l;
            at = (x, y);
        }
    }
    let dir = export::equirect_direction(at.0, at.1, w, ht);
    let angle = dir.dot(towards_sun).clamp(-1.0, 1.0).acos().to_degrees();
    assert!(angle < 6.0, "brightest texel {angle:.1} degrees from the sun");
}
