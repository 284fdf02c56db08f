//! Editing a sky's colour bitmaps in place (the curve editor's model): each edit changes exactly
//! the texels it should, saves write the same PNG back with only those pixels changed, undo
//! restores the original bytes, a change on disk is a conflict that loses nothing, and an edit
//! shows in the sky's next frame without a file round trip.

use skytune::files::bitmap_edit::{BitmapEditor, Edit, EditError};

mod common;

fn write_png(path: &std::path::Path, img: image::DynamicImage) {
    img.save_with_format(path, image::ImageFormat::Png).unwrap();
}

/// A 24 x 3 bitmap whose every texel differs.
fn day_bitmap() -> image::RgbaImage {
    image::RgbaImage::from_fn(24, 3, |x, y| image::Rgba([(x * 10) as u8, (y * 80 + x) as u8, (250 - x * 5) as u8, 255 - y as u8]))
}

fn changed(a: &std::path::Path, b: &image::RgbaImage) -> Vec<(u32, u32)> {
    let a = image::open(a).unwrap().to_rgba8();
    a.enumerate_pixels().filter(|(x, y, p)| *p != b.get_pixel(*x, *y)).map(|(x, y, _)| (x, y)).collect()
}

#[test]
fn edits_change_exactly_their_texels_and_undo_restores_the_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("sun_diffuse.png");
    let original = day_bitmap();
    write_png(&path, image::DynamicImage::ImageRgba8(original.clone()));
    let bytes = std::fs::read(&path).unwrap();
    let mut e = BitmapEditor::open(&path, "sun_diffuse.png").unwrap();
    assert_eq!(e.size(), (24, 3));
    assert_eq!(e.column_of_hour(18.5, 24.0), 19);
    // A drag on one column's red (three moves, one undo step), a colour at 18:00 of weather
    // row 2, and a smoothed span of row 0 from 20:00 to 02:00 across midnight.
    for v in [0.2, 0.5, 0.9] {
        e.apply(&Edit::SetChannel { x: 6, y: 1, channel: 0, value: v }, v != 0.2);
    }
    e.apply(&Edit::SetColor { x: 18, y: 2, rgba: [1.0, 0.5, 0.0, 1.0] }, false);
    e.apply(&Edit::Smooth { y: 0, from: 20, to: 2, passes: 1 }, false);
    assert!(e.is_dirty());
    e.save(false).unwrap();
    let mut expected: Vec<(u32, u32)> = vec![(6, 1), (18, 2)];
    // The span's inner columns 21, 22, 23, 0, 1 (red and blue are linear in x; but the wrap from
    // 23 to 0 is not, and green's step is at row 0 only where x wraps).
    let saved = image::open(&path).unwrap().to_rgba8();
    for x in [21, 22, 23, 0, 1] {
        if saved.get_pixel(x, 0) != original.get_pixel(x, 0) {
            expected.push((x, 0));
        }
    }
    assert!(expected.contains(&(23, 0)) && expected.contains(&(0, 0)), "the smoothing reaches across midnight: {expected:?}");
    let mut got = changed(&path, &original);
    got.sort();
    expected.sort();
    assert_eq!(got, expected, "only the edited texels changed");
    assert_eq!(saved.get_pixel(6, 1).0, [230, original.get_pixel(6, 1)[1], original.get_pixel(6, 1)[2], original.get_pixel(6, 1)[3]]);
    assert_eq!(saved.get_pixel(18, 2).0, [255, 128, 0, 255]);
    // The same PNG: size, colour type, bit depth.
    let decoded = image::open(&path).unwrap();
    assert_eq!((decoded.width(), decoded.height(), decoded.color()), (24, 3, image::ColorType::Rgba8));
    // Undo everything: the file as it was, byte for byte.
    assert!(e.undo() && e.undo() && e.undo() && !e.undo());
    e.save(false).unwrap();
    assert_eq!(std::fs::read(&path).unwrap(), bytes);
    // Redo brings the drag back.
    assert!(e.redo());
    assert_eq!(e.texel(6, 1)[0], 230.0 / 255.0);
}

#[test]
fn spans_move_and_rows_mix() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("fog.png");
    // Row 0: red = column index; row 1: red 200; row 2: red 0.
    write_png(&path, image::DynamicImage::ImageRgb8(image::RgbImage::from_fn(8, 3, |x, y| image::Rgb([[x as u8 * 10, 200, 0][y as usize], 0, 0]))));
    let mut e = BitmapEditor::open(&path, "fog.png").unwrap();
    let red = |e: &BitmapEditor, y: u32| (0..8).map(|x| (e.texel(x, y)[0] * 255.0).round() as u32).collect::<Vec<_>>();
    // Hours 1..=2 moved two columns later: they land on 3..=4, and 3..=4 move back to 1..=2.
    e.apply(&Edit::Shift { y: 0, from: 1, to: 2, by: 2 }, false);
    assert_eq!(red(&e, 0), [0, 30, 40, 10, 20, 50, 60, 70]);
    e.undo();
    // 1..=3 stretched onto 1..=5.
    e.apply(&Edit::Stretch { y: 0, from: 1, to: 3, new_to: 5 }, false);
    assert_eq!(red(&e, 0), [0, 10, 15, 20, 25, 30, 60, 70]);
    e.undo();
    e.apply(&Edit::CopyColumn { x: 4, from_row: 0, to_rows: vec![1, 2] }, false);
    assert_eq!((red(&e, 1)[4], red(&e, 2)[4], red(&e, 1)[3]), (40, 40, 200));
    e.apply(&Edit::BlendRows { a: 1, b: 2, t: 0.25, into: 2 }, false);
    assert_eq!(red(&e, 2)[0], 150);
    // 8-bit RGB stays 8-bit RGB.
    e.save(false).unwrap();
    assert_eq!(image::open(&path).unwrap().color(), image::ColorType::Rgb8);
}

#[test]
fn sixteen_bit_files_stay_sixteen_bit_and_exact() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("ambient.png");
    let original = image::ImageBuffer::<image::Rgb<u16>, Vec<u16>>::from_fn(24, 2, |x, y| image::Rgb([x as u16 * 2711 + 3, y as u16 * 30011 + 7, 65535 - x as u16 * 17]));
    write_png(&path, image::DynamicImage::ImageRgb16(original.clone()));
    let mut e = BitmapEditor::open(&path, "ambient.png").unwrap();
    e.apply(&Edit::SetChannel { x: 3, y: 1, channel: 2, value: 0.5 }, false);
    e.save(false).unwrap();
    let saved = image::open(&path).unwrap();
    assert_eq!(saved.color(), image::ColorType::Rgb16);
    let saved = saved.to_rgb16();
    for (x, y, p) in original.enumerate_pixels() {
        if (x, y) == (3, 1) {
            assert_eq!(saved.get_pixel(x, y).0, [p[0], p[1], 32768]);
        } else {
            assert_eq!(saved.get_pixel(x, y), p, "({x}, {y})");
        }
    }
}

#[test]
fn a_change_on_disk_during_edits_is_a_conflict_that_loses_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("sun_diffuse.png");
    write_png(&path, image::DynamicImage::ImageRgba8(day_bitmap()));
    let mut e = BitmapEditor::open(&path, "sun_diffuse.png").unwrap();
    e.apply(&Edit::SetColor { x: 5, y: 0, rgba: [0.0, 0.0, 1.0, 1.0] }, false);
    // Someone repaints the file in an image editor meanwhile.
    let mut theirs = day_bitmap();
    theirs.put_pixel(9, 1, image::Rgba([1, 2, 3, 4]));
    write_png(&path, image::DynamicImage::ImageRgba8(theirs.clone()));
    assert!(e.changed_on_disk());
    assert!(matches!(e.save(false), Err(EditError::Conflict { .. })));
    // Both versions are there: the file's on disk, ours in the editor.
    assert_eq!(e.disk_version().unwrap().to_rgba8(), theirs);
    assert_eq!(e.texel(5, 0), [0.0, 0.0, 1.0, 1.0]);
    // Taking theirs keeps ours one undo away.
    e.take_disk_version().unwrap();
    assert_eq!(e.texel(9, 1), [1.0 / 255.0, 2.0 / 255.0, 3.0 / 255.0, 4.0 / 255.0]);
    assert!(!e.is_dirty() && !e.changed_on_disk());
    assert!(e.undo());
    assert_eq!(e.texel(5, 0), [0.0, 0.0, 1.0, 1.0]);
    // Keeping ours: an explicit overwrite.
    e.save(true).unwrap();
    assert_eq!(image::open(&path).unwrap().to_rgba8().get_pixel(5, 0).0, [0, 0, 255, 255]);
}

#[test]
fn an_edit_shows_in_the_next_frame() {
    let (_dir, sky_path) = common::default_sky_folder();
    let mut sky = skytune::sky::load_sky_file(&sky_path).unwrap();
    let folder = sky_path.parent().unwrap();
    let input = skytune::sky::FrameInput::new(12.0, 0.0);
    let mut h = common::headless(96, 64);
    h.set_sky(&sky).unwrap();
    let camera = skytune::render::Camera::default();
    let options = skytune::render::RenderOptions { scene: false, glare: false, ..Default::default() };
    let before = h.render(&sky, &input, &camera, &options).unwrap();
    // The clear-weather sky gradient at noon turned red, every position from the zenith down.
    let mut e = BitmapEditor::open(&folder.join("gradient_clear.png"), "gradient_clear.png").unwrap();
    let x = e.column_of_hour(12.0, sky.hours_per_day);
    let (_, rows) = e.size();
    let texels = (0..rows).flat_map(|y| [(x, y), ((x + 1) % e.size().0, y)]).map(|(x, y)| (x, y, [1.0, 0.0, 0.0, 1.0])).collect();
    e.apply(&Edit::Replace { texels }, false);
    assert!(sky.replace_bitmap(e.key(), e.color_bitmap()) >= 2, "both domes use the clear gradient");
    let after = h.render(&sky, &input, &camera, &options).unwrap();
    let redder = before.pixels().zip(after.pixels()).filter(|(a, b)| b[0] as i32 - a[0] as i32 > 40 && (b[2] as i32) < a[2] as i32).count();
    assert!(redder > (96 * 64) / 4, "only {redder} pixels turned red");
    // Nothing was written.
    assert!(!e.changed_on_disk() && e.is_dirty());
}

#[test]
fn after_a_save_the_reload_shows_what_was_on_screen() {
    let (_dir, sky_path) = common::default_sky_folder();
    let mut sky = skytune::sky::load_sky_file(&sky_path).unwrap();
    let mut e = BitmapEditor::open(&sky_path.parent().unwrap().join("sun_diffuse.png"), "sun_diffuse.png").unwrap();
    e.apply(&Edit::SetColor { x: 17, y: 0, rgba: [0.9, 0.4, 0.1, 1.0] }, false);
    e.apply(&Edit::Smooth { y: 0, from: 14, to: 20, passes: 2 }, false);
    sky.replace_bitmap(e.key(), e.color_bitmap());
    e.save(false).unwrap();
    // What hot reload reads from disk is what the window showed.
    let reloaded = skytune::sky::load_sky_file(&sky_path).unwrap();
    assert_eq!(reloaded.sun_diffuse.texels, sky.sun_diffuse.texels);
    for hour in [16.0, 17.0, 17.5, 19.0] {
        let (a, b) = (reloaded.evaluate(&skytune::sky::FrameInput::new(hour, 0.2)), sky.evaluate(&skytune::sky::FrameInput::new(hour, 0.2)));
        assert_eq!(a.sun_diffuse, b.sun_diffuse, "{hour}");
    }
    assert!(!e.changed_on_disk() && !e.is_dirty());
}

#[test]
fn a_bake_fills_a_span_of_hours_as_one_edit() {
    use skytune::measure::bake::{self, BakeTarget};
    let (_dir, sky_path) = common::default_sky_folder();
    let mut sky = skytune::sky::load_sky_file(&sky_path).unwrap();
    sky.model.kind = skytune::sky::model::SkyModelKind::Hosek;
    let sky = std::sync::Arc::new(sky);
    assert_eq!(bake::bake_target(&sky, "fog.png"), Some(BakeTarget::Fog));
    assert_eq!(bake::bake_target(&sky, "gradient_cloudy.png"), Some(BakeTarget::Gradient { step: 1, steps: 3 }));
    assert_eq!(bake::bake_target(&sky, "moon.png"), None);
    let mut e = BitmapEditor::open(&sky_path.parent().unwrap().join("fog.png"), "fog.png").unwrap();
    let ctx = skytune::render::GpuContext::headless(skytune::render::AdapterChoice::Cpu).unwrap();
    // 22:00 to 01:00 across midnight, on the window's worker.
    let job = skytune::app::curve_bake::CurveBake::start(&sky, &sky.model, "fog.png", e.size(), (22, 1), &ctx).unwrap();
    let started = std::time::Instant::now();
    let edit = loop {
        if let Some(r) = job.poll() {
            break r.unwrap();
        }
        assert!(started.elapsed().as_secs() < 120, "the bake did not finish");
        std::thread::sleep(std::time::Duration::from_millis(20));
    };
    let before: Vec<_> = (0..e.size().1).flat_map(|y| (0..e.size().0).map(move |x| (x, y))).map(|(x, y)| e.texel(x, y)).collect();
    e.apply(&edit, false);
    let (w, h) = e.size();
    let baked = {
        let ev = skytune::measure::model_points::Evaluator::new(&ctx).unwrap();
        let (rows, weathers) = bake::bake_shape(BakeTarget::Fog, h);
        bake::bake(&ev, &sky, skytune::measure::model_points::Method::Hosek, rows, weathers).unwrap()
    };
    for y in 0..h {
        for x in 0..w {
            let t = e.texel(x, y);
            if [22, 23, 0, 1].contains(&x) {
                let c = bake::scene_colour(&baked, BakeTarget::Fog, y as usize, (x as usize * 24 / w as usize) % 24);
                assert_eq!(t[..3].iter().map(|v| (v * 255.0).round() as u8).collect::<Vec<_>>(), c, "({x}, {y})");
            } else {
                assert_eq!(t, before[(y * w + x) as usize], "({x}, {y}) is outside the span");
            }
        }
    }
    assert!(e.undo() && !e.is_dirty());
    // The bitmap model has nothing to bake from.
    let bitmap_model = skytune::sky::resolved::SkyModel { kind: skytune::sky::model::SkyModelKind::Bitmap, ..sky.model };
    assert!(skytune::app::curve_bake::CurveBake::start(&sky, &bitmap_model, "fog.png", e.size(), (0, 3), &ctx).is_err());
}
