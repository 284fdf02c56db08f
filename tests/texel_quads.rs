//! A sparse stage drawn texel by texel (`SparseStages::TexelPolygons`, src/render/sky_objects/texel_quads.rs):
//! the skydome's stars times their mask, in the fused background, as one polygon per lit texel
//! where they are sampled from level 0. The polygons add up to the bilinear sample: frames with
//! and without them differ by the blend's rounding of each texel's share (a level or two).

mod common;

use skytune::render::plan::strategy::SparseStages;
use skytune::render::{Camera, FillStrategy, RenderOptions};
use skytune::sky::builtin::default_sky;
use skytune::sky::resolved::{SkyModel, SkyModelKind};
use skytune::sky::FrameInput;

#[test]
fn stars_drawn_texel_by_texel_give_the_sampled_picture() {
    let lakes = skytune::sky::load_sky_file(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("skies/lakes/sky.toml")).expect("lakes loads");
    let mut h = common::headless(640, 360);
    // 9 pixels per degree: the stars' texels (5.8 per degree down the dome) land on level 0
    // away from the pole, as at 1280 x 720 and 70 degrees.
    let views = [("horizon", Camera { pitch_deg: 10.0, fov_y_deg: 40.0, ..Camera::default() }), ("zenith", Camera { pitch_deg: 89.0, fov_y_deg: 40.0, ..Camera::default() })];
    let on = RenderOptions { glare: false, scene: false, ..Default::default() };
    let off = RenderOptions { strategy: FillStrategy { sparse_stages: SparseStages::Sampled, ..on.strategy }, ..on };
    for (name, sky) in [("built-in", default_sky()), ("lakes", lakes)] {
        h.set_sky(&sky).expect("uploaded");
        for (hour, weather) in [(18.5, 0.3), (23.0, 0.0), (2.0, 0.6)] {
            let input = FrameInput::new(hour, weather);
            for (view, camera) in &views {
                let what = format!("{name} at {hour} h, weather {weather}, {view}");
                let with = h.render(&sky, &input, camera, &on).expect("rendered");
                let s = h.renderer.stats.clone();
                assert!(s.background_fused && s.texel_triangles > 0, "{what}: the stars drawn texel by texel ({s:?})");
                let without = h.render(&sky, &input, camera, &off).expect("rendered");
                assert_eq!(h.renderer.stats.texel_triangles, 0, "{what}");
                let (d, _) = common::diff(&with, &without, 2);
                assert_eq!(d.differing, 0.0, "{what}: {:.4} of the pixels moved by more than 2 (largest {})", d.differing, d.max);
            }
        }
    }
    // On the HDR target (a physical sky model) the term goes through the inverse tone curve,
    // which does not add up texel by texel: sampled.
    let sky = default_sky();
    h.set_sky(&sky).expect("uploaded");
    let mut input = FrameInput::new(23.0, 0.0);
    input.sky_model = Some(SkyModel { kind: SkyModelKind::Lut, ..sky.model });
    let hdr = RenderOptions { strategy: on.strategy.with_hdr(), ..on };
    h.render(&sky, &input, &views[0].1, &hdr).expect("rendered");
    assert_eq!(h.renderer.stats.texel_triangles, 0, "{:?}", h.renderer.stats);
    // Display-referred, the stars split off the map's layer add display values, as over a
    // painted sky: texel by texel, the same picture as sampled.
    let with = h.render(&sky, &input, &views[0].1, &on).expect("rendered");
    assert!(h.renderer.stats.texel_triangles > 0, "{:?}", h.renderer.stats);
    let without = h.render(&sky, &input, &views[0].1, &off).expect("rendered");
    let (d, _) = common::diff(&with, &without, 2);
    assert_eq!(d.differing, 0.0, "lut display-referred: {:.4} of the pixels moved by more than 2 (largest {})", d.differing, d.max);
}

#[test]
fn the_background_drawn_without_the_grid_where_the_polygons_stand_in_gives_the_same_bytes() {
    // Where the polygons stand for the stars, the rest of the background maps nothing from the
    // dome's grid: it goes as one triangle over the frame, scissored round the rings that still
    // sample the stars and the rows below the dome, and inside those as one band of quads per run
    // of rings (`SparseStages::TexelPolygonsOnBands`), which must cover exactly the grid's pixels. Each
    // frame follows one of another hour, whose pixels a draw that left some out would keep (the
    // background's frame is not cleared first).
    let lakes = skytune::sky::load_sky_file(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("skies/lakes/sky.toml")).expect("lakes loads");
    let mut h = common::headless(640, 360);
    let views = [
        ("horizon", Camera { pitch_deg: 10.0, fov_y_deg: 40.0, ..Camera::default() }),
        ("zenith", Camera { pitch_deg: 89.0, fov_y_deg: 40.0, ..Camera::default() }),
        ("looking up, to the east", Camera { yaw_deg: 75.0, pitch_deg: 55.0, fov_y_deg: 40.0, ..Camera::default() }),
    ];
    let bands = RenderOptions { glare: false, scene: false, ..Default::default() };
    let grid = RenderOptions { strategy: FillStrategy { sparse_stages: SparseStages::TexelPolygons, ..bands.strategy }, ..bands };
    for (name, sky) in [("built-in", default_sky()), ("lakes", lakes)] {
        h.set_sky(&sky).expect("uploaded");
        for (hour, weather) in [(18.5, 0.3), (23.0, 0.0)] {
            let input = FrameInput::new(hour, weather);
            for (view, camera) in &views {
                let what = format!("{name} at {hour} h, weather {weather}, {view}");
                let on_grid = h.render(&sky, &input, camera, &grid).expect("rendered");
                h.render(&sky, &FrameInput::new(12.0, 1.0), camera, &bands).expect("rendered");
                let as_bands = h.render(&sky, &input, camera, &bands).expect("rendered");
                let s = &h.renderer.stats;
                assert!(s.texel_triangles > 0 && s.background_rects > 0, "{what}: no polygons, or the background not on one triangle ({s:?})");
                let differing = on_grid.as_raw().iter().zip(as_bands.as_raw()).filter(|(a, b)| a != b).count();
                assert_eq!(differing, 0, "{what}: {differing} bytes differ between the grid and the bands");
            }
        }
    }
}
