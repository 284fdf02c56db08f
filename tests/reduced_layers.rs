//! Dome layers at reduced resolution (`FillStrategy::dome_resolution`): the frame stays close to
//! the full-resolution one on both targets, layers with finer texture detail than the reduced
//! buffer (the skydome's stars at night) stay at full resolution, and billboards never go there.

mod common;

use skytune::render::plan::strategy::{CostlyLayers, FlashPlacement, LayerCoordinates, LayerPairs, RunJoining, UnderBackground};
use skytune::render::{Camera, Divisor, DomeResolution, FillStrategy, RenderOptions};
use skytune::sky::builtin::default_sky;
use skytune::sky::particles::ParticleClock;
use skytune::sky::resolved::{SkyModel, SkyModelKind};
use skytune::sky::FrameInput;

#[test]
fn reduced_dome_layers_stay_close_to_full_resolution() {
    let sky = default_sky();
    // Large enough that the cloud textures are coarser than a half-resolution buffer's pixels.
    let mut h = common::headless(640, 360);
    h.set_sky(&sky).expect("uploaded");
    let camera = Camera { pitch_deg: 30.0, ..Camera::default() };
    let full = RenderOptions { glare: false, strategy: FillStrategy { dome_resolution: DomeResolution::Full, ..FillStrategy::software() }, ..Default::default() };
    let half = RenderOptions { strategy: FillStrategy { dome_resolution: DomeResolution::Half, ..full.strategy }, ..full };
    let auto = RenderOptions { strategy: FillStrategy { dome_resolution: DomeResolution::Auto, ..full.strategy }, ..full };
    let mut lut = FrameInput::new(10.0, 0.3);
    lut.sky_model = Some(SkyModel { kind: SkyModelKind::Lut, ..sky.model });
    for (what, input) in [
        ("bitmaps, 10:00", FrameInput::new(10.0, 0.3)),
        ("lut on the HDR target, 10:00", lut.clone()),
        ("lut display-referred, 10:00", lut),
        ("bitmaps, dusk", FrameInput::new(18.5, 0.6)),
        ("bitmaps, night", FrameInput::new(23.0, 0.0)),
    ] {
        let on_target = |o: RenderOptions| if what.contains("HDR target") { RenderOptions { strategy: o.strategy.with_hdr(), ..o } } else { o };
        let sharp = h.render(&sky, &input, &camera, &on_target(full)).expect("rendered");
        assert_eq!(h.renderer.stats.objects_reduced, 0, "{what}: full resolution reduces nothing");
        for options in [on_target(half), on_target(auto)] {
            let what = format!("{what}, {}", options.strategy.dome_resolution.name());
            let soft = h.render(&sky, &input, &camera, &options).expect("rendered");
            let s = h.renderer.stats.clone();
            assert!(s.objects_reduced >= 2, "{what}: the skydome and a cloud layer go to the reduced buffer ({s:?})");
            // Soft cloud edges move by a few levels; a wrong blend or composite moves whole areas.
            let (d, _) = common::diff(&sharp, &soft, 24);
            let (d6, _) = common::diff(&sharp, &soft, 6);
            eprintln!("{what}: >24 {:.5}, >6 {:.5}, runs {:?}", d.differing, d6.differing, s.reduced_runs);
            assert!(d.differing < 0.02, "{what}: {:.4} of the pixels differ by more than 24 levels (largest {})", d.differing, d.max);
            assert!(d6.differing < 0.01, "{what}: {:.4} of the pixels differ by more than 6 levels", d6.differing);
        }
    }
}

#[test]
fn fine_layers_and_billboards_stay_at_full_resolution() {
    let sky = default_sky();
    let mut h = common::headless(320, 180);
    h.set_sky(&sky).expect("uploaded");
    let camera = Camera { pitch_deg: 30.0, ..Camera::default() };
    let half = RenderOptions { glare: false, strategy: FillStrategy { dome_resolution: DomeResolution::Half, ..FillStrategy::software() }, ..Default::default() };
    let quarter = RenderOptions { strategy: FillStrategy { dome_resolution: DomeResolution::Quarter, ..half.strategy }, ..half };
    // By day the skydome's star stage is black and not sampled: it may go to the buffer.
    h.render(&sky, &FrameInput::new(12.0, 0.0), &camera, &half).expect("rendered");
    let day = h.renderer.stats.objects_reduced;
    // At night its tiled stars are finer than a half-resolution buffer's pixels: full resolution.
    h.render(&sky, &FrameInput::new(23.0, 0.0), &camera, &half).expect("rendered");
    let night = h.renderer.stats.clone();
    assert!(night.objects_reduced < night.objects_drawn, "billboards and the starry skydome stay sharp ({night:?})");
    assert!(day > 0, "by day dome layers are reduced");
    // A coarser buffer takes fewer layers.
    h.render(&sky, &FrameInput::new(12.0, 0.0), &camera, &quarter).expect("rendered");
    assert!(h.renderer.stats.objects_reduced <= day);
}

#[test]
fn alpha_layers_too_fine_for_half_resolution_go_whole_to_a_finer_buffer() {
    // At 640 x 360 and 70 degrees of field a frame has 5.14 pixels per degree. The cloudy layer's
    // finer texture (at its densest, towards the horizon of its cloud layer) is too fine for a
    // half-resolution buffer (2.57), and its terms cannot be split as an opaque layer's. `auto`
    // draws it whole in a buffer between 1.5 and 2 rather than on the frame; the clear layer's
    // needs less than 1.5, where a buffer costs more than it saves, and stays on the frame.
    // `half` keeps both on the frame.
    let sky = default_sky();
    let mut h = common::headless(640, 360);
    h.set_sky(&sky).expect("uploaded");
    let camera = Camera { pitch_deg: 40.0, ..Camera::default() };
    let input = FrameInput::new(12.0, 0.6);
    let full = RenderOptions { glare: false, strategy: FillStrategy { dome_resolution: DomeResolution::Full, ..FillStrategy::software() }, ..Default::default() };
    let sharp = h.render(&sky, &input, &camera, &full).expect("rendered");
    h.render(&sky, &input, &camera, &RenderOptions { strategy: FillStrategy { dome_resolution: DomeResolution::Half, ..full.strategy }, ..full }).expect("rendered");
    let half = h.renderer.stats.clone();
    assert!(half.reduced_runs.iter().all(|&d| d == Divisor::HALF), "{half:?}");
    let soft = h.render(&sky, &input, &camera, &RenderOptions { strategy: FillStrategy { dome_resolution: DomeResolution::Auto, ..full.strategy }, ..full }).expect("rendered");
    let auto = h.renderer.stats.clone();
    assert!(auto.reduced_runs.iter().any(|&d| d.reduces() && d.coarser() < Divisor::HALF.coarser()), "the cloudy layer between 1.5 and 2 ({auto:?})");
    assert_eq!(auto.objects_reduced, half.objects_reduced + 1, "one layer more in a buffer, the clear clouds still on the frame ({auto:?})");
    let (d, _) = common::diff(&sharp, &soft, 6);
    assert!(d.differing < 0.002, "{:.4} of the pixels differ from the full-resolution frame by more than 6 levels (largest {})", d.differing, d.max);
}

#[test]
fn runs_join_across_additive_draws_and_coarse_runs_go_to_coarser_buffers() {
    let sky = default_sky();
    let mut h = common::headless(640, 360);
    h.set_sky(&sky).expect("uploaded");
    let camera = Camera { pitch_deg: 30.0, ..Camera::default() };
    let night = FrameInput::new(23.0, 0.0);
    let half = RenderOptions { glare: false, strategy: FillStrategy { dome_resolution: DomeResolution::Half, ..FillStrategy::software() }, ..Default::default() };
    h.render(&sky, &night, &camera, &half).expect("rendered");
    // Reduced: the skydome's coarse terms, the galaxy and the fog dome. The skydome's fine stars
    // (added at full resolution) sit between the skydome and the galaxy, both additive on top of
    // it: the galaxy joins the skydome's run, and the fog (alpha blended, after the billboards)
    // makes the second run. Without the join there would be three.
    let s = h.renderer.stats.clone();
    assert_eq!((s.objects_reduced, s.reduced_runs.as_slice()), (3, &[Divisor::HALF; 2][..]), "{s:?}");
    // Gradient, halo, galaxy and fog band are coarse enough for a buffer an eighth of the size.
    let auto = RenderOptions { strategy: FillStrategy { dome_resolution: DomeResolution::Auto, ..half.strategy }, ..half };
    h.render(&sky, &night, &camera, &auto).expect("rendered");
    assert_eq!(h.renderer.stats.reduced_runs, [Divisor::whole(8); 2], "{:?}", h.renderer.stats);
    // A physical sky model's stage keeps its layer's run as fine as its map: down the frame, two
    // texels per degree (2.5 here, at 5.1 pixels per degree), finer than the painted gradient's
    // eighth; across it, its columns at 65 degrees up, 1.3 per degree (4 here).
    let mut lut = FrameInput::new(10.0, 0.3);
    lut.sky_model = Some(SkyModel { kind: SkyModelKind::Lut, ..sky.model });
    h.render(&sky, &lut, &camera, &auto).expect("rendered");
    let first = h.renderer.stats.reduced_runs.first().copied();
    assert!(first.is_some_and(|d| d.y() > 2.0 && d.y() < 3.0 && d.x() == 4.0), "{:?}", h.renderer.stats);
}

#[test]
fn frame_edges_are_covered_when_the_size_is_no_multiple_of_the_divisor() {
    // 322 x 181 is a multiple of neither 2 nor 4: the buffers' last row and column hold part of
    // a frame pixel. They must still be drawn (a buffer left clear there shows a dark edge).
    let sky = default_sky();
    let mut h = common::headless(322, 181);
    h.set_sky(&sky).expect("uploaded");
    let camera = Camera { pitch_deg: 40.0, ..Camera::default() };
    let input = FrameInput::new(11.0, 0.0);
    let full = RenderOptions { glare: false, strategy: FillStrategy { dome_resolution: DomeResolution::Full, ..FillStrategy::software() }, ..Default::default() };
    let sharp = h.render(&sky, &input, &camera, &full).expect("rendered");
    for resolution in [DomeResolution::Half, DomeResolution::Quarter] {
        let soft = h.render(&sky, &input, &camera, &RenderOptions { strategy: FillStrategy { dome_resolution: resolution, ..full.strategy }, ..full }).expect("rendered");
        assert!(h.renderer.stats.objects_reduced > 0, "{resolution:?}: something is reduced");
        let (w, h_px) = sharp.dimensions();
        let edge = |x: u32, y: u32| (0..3).map(|c| (sharp.get_pixel(x, y)[c] as i32 - soft.get_pixel(x, y)[c] as i32).abs()).max().unwrap_or(0);
        let worst_row = (0..w).map(|x| edge(x, 0).max(edge(x, h_px - 1))).max().unwrap_or(0);
        let worst_column = (0..h_px).map(|y| edge(0, y).max(edge(w - 1, y))).max().unwrap_or(0);
        assert!(worst_row <= 12 && worst_column <= 12, "{resolution:?}: the frame's edges differ by up to {worst_row} (rows) and {worst_column} (columns) levels");
    }
}

/// The built-in sky with shooting stars frequent enough to be seen, uploaded to a 640x360
/// headless renderer.
fn night_sky_with_shooting_stars() -> (skytune::sky::Sky, skytune::render::Headless) {
    let mut sky = default_sky();
    if let Some(e) = sky.emitters.iter_mut().find(|e| e.name == "shooting_stars") {
        e.rate = 200.0;
        e.max_particles = 1000;
    }
    let mut h = common::headless(640, 360);
    h.set_sky(&sky).expect("uploaded");
    (sky, h)
}

#[test]
fn joined_runs_give_the_same_picture_with_one_composite_less() {
    // The skydome's run and the clouds' run, with the sun, the moons, the planet, the star field
    // and the shooting stars between them: composited at once, the rest drawn afterwards under
    // the clouds' run. In a storm, lightning bolts between the clouds and the fog dome: three
    // runs joined, the bolts under the fog's run and the billboards under both.
    let (sky, mut h) = night_sky_with_shooting_stars();
    let mut lut = FrameInput::new(17.0, 0.5);
    lut.sky_model = Some(SkyModel { kind: SkyModelKind::Lut, ..sky.model });
    let mut storm = sky.clone();
    if let Some(e) = storm.emitters.iter_mut().find(|e| e.name == "lightning") {
        e.rate = 200.0;
        e.max_particles = 40;
    }
    // Towards the sun, so that the billboards between the skydome and the clouds are in the
    // frame (out of it they are not drawn, and the two runs become one).
    let (sun_yaw_deg, _) = skytune::sky::eval::azimuth_elevation(sky.evaluate(&FrameInput::new(15.0, 1.0)).towards_sun);
    let horizon = Camera { yaw_deg: sun_yaw_deg, pitch_deg: 12.0, ..Camera::default() };
    // The storm's clouds resolve into a reduced buffer at the full size only.
    let mut big = common::headless(1280, 720);
    for (what, sky, input, camera, runs) in [
        ("dusk towards the sun", &sky, FrameInput::new(17.5, 0.4), Camera { yaw_deg: 270.0, pitch_deg: 10.0, ..Camera::default() }, 2),
        ("noon, clouds", &sky, FrameInput::new(12.0, 0.2), Camera { pitch_deg: 40.0, ..Camera::default() }, 2),
        ("night, stars and moons", &sky, FrameInput::new(2.0, 0.3), Camera { pitch_deg: 35.0, ..Camera::default() }, 2),
        ("lut on the HDR target", &sky, lut.clone(), Camera { yaw_deg: 250.0, pitch_deg: 15.0, ..Camera::default() }, 2),
        ("lut display-referred", &sky, lut, Camera { yaw_deg: 250.0, pitch_deg: 15.0, ..Camera::default() }, 2),
        ("storm, lightning", &storm, FrameInput::new(15.0, 1.0), horizon, 3),
        (
            "storm, lightning, lut on the HDR target",
            &storm,
            FrameInput { sky_model: Some(SkyModel { kind: SkyModelKind::Lut, ..sky.model }), ..FrameInput::new(15.0, 1.0) },
            horizon,
            3,
        ),
    ] {
        let h = if runs == 3 { &mut big } else { &mut h };
        h.set_sky(sky).expect("uploaded");
        let strategy = if what.contains("HDR target") { FillStrategy::software().with_hdr() } else { FillStrategy::software() };
        let joined = RenderOptions { glare: false, strategy, ..Default::default() };
        let apart = RenderOptions { strategy: FillStrategy { runs: RunJoining::Separate, ..joined.strategy }, ..joined };
        let one = h.render(sky, &input, &camera, &joined).expect("rendered");
        let s = h.renderer.stats.clone();
        assert!(s.reduced_runs.len() == runs && s.composites == 1, "{what}: {runs} runs joined ({s:?})");
        eprintln!("{what}: {} particles, {} stars", s.particles, s.stars);
        let two = h.render(sky, &input, &camera, &apart).expect("rendered");
        assert_eq!(h.renderer.stats.composites as usize, h.renderer.stats.reduced_runs.len(), "{what}");
        // The same sums in another order: rounding of the 8-bit target moves a level or two. A
        // seeded buffer also interpolates the product of the upper run's transmittance and the
        // lower run's colour where the composites multiply interpolated values: a few levels
        // more at cloud edges, the more detail a buffer pixel of the clouds holds: noon's cloud
        // layers, whose texels crowd towards their horizon, 0.5% of the pixels, 19 levels at
        // most (5 when the clouds were on the dome's mesh coordinates).
        let (d, _) = common::diff(&one, &two, 2);
        assert!(d.differing < 0.006 && d.max <= 24, "{what}: {:.4} of the pixels differ by more than 2 levels (largest {})", d.differing, d.max);
        // Two runs: the second's buffer seeded with the first holds their combination, and the
        // draws between them take the first off again; the same picture as combining them in a
        // pass of their own. A second run coarser than the first (a physical model's sky stays at
        // half resolution) is combined in a pass; so are three runs here, the billboards lying
        // between the first two (seeded under a combination: the next test).
        let seeds = runs == 2 && s.reduced_runs[1].resolves(s.reduced_runs[0]);
        assert_eq!(s.seeded, seeds, "{what}: seeded ({s:?})");
        if seeds {
            let combined = h.render(sky, &input, &camera, &RenderOptions { strategy: FillStrategy { runs: RunJoining::Combined, ..joined.strategy }, ..joined }).expect("rendered");
            assert!(!h.renderer.stats.seeded, "{what}");
            let (d, _) = common::diff(&one, &combined, 2);
            let physical = input.sky_model.map_or(sky.model.kind, |m| m.kind).is_physical();
            let (share, largest) = over_seed_limits(skytune::render::plan::matches_hdr_picture(physical, &joined.strategy));
            assert!(d.differing < share && d.max <= largest, "{what}: seeded against combined, {:.4} of the pixels differ by more than 2 levels (largest {})", d.differing, d.max);
        }
    }
}

#[test]
fn two_seeded_runs_under_a_combination_give_the_same_picture_as_three_combined() {
    // Lakes in a storm: the rain between the clouds and the fog parts the runs; the skydome,
    // coarser than the clouds, splits off their run and seeds its buffer, and the fog's run is
    // combined over the seeded buffer, the rain under it. Painted and with `lut`.
    let lakes = skytune::sky::load_sky_file(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("skies/lakes/sky.toml")).expect("the lakes sky loads");
    let mut h = common::headless(1280, 720);
    h.set_sky(&lakes).expect("uploaded");
    let camera = Camera { pitch_deg: 10.0, ..Camera::default() };
    let storm = FrameInput::new(15.0, 1.0);
    let lut = FrameInput { sky_model: Some(SkyModel { kind: SkyModelKind::Lut, ..lakes.model }), ..storm.clone() };
    // With the scene, which covers the skydome's cut 20 degrees below the horizon: drawn at the
    // skydome's own resolution there, its steps are coarser than at the clouds'.
    let seeded = RenderOptions { glare: false, ..Default::default() };
    for (what, input) in [("painted", &storm), ("lut", &lut)] {
        let one = h.render(&lakes, input, &camera, &seeded).expect("rendered");
        let s = h.renderer.stats.clone();
        assert!(s.seeded && s.seed_folded && s.reduced_runs.len() == 3 && s.composites == 1, "{what}: seeded under a combination ({s:?})");
        let combined = RenderOptions { strategy: FillStrategy { runs: RunJoining::Combined, ..seeded.strategy }, ..seeded };
        let two = h.render(&lakes, input, &camera, &combined).expect("rendered");
        let t = h.renderer.stats.clone();
        assert!(!t.seeded && t.reduced_runs.len() == 2 && t.composites == 1, "{what}: combined, the skydome in the clouds' run ({t:?})");
        // The skydome drawn at its own resolution (8 x 5 here) under the clouds rather than at
        // theirs (2.25), and with `lut` the clouds blended in radiance over it rather than matched
        // over the model's map (`over_seed_limits`): a handful of pixels at the edges of dark
        // clouds up to 8 levels apart (painted: 2, 0.0000 of the pixels more than 2; `lut`: 7).
        let (d, _) = common::diff(&one, &two, 2);
        assert!(d.differing < 0.0005 && d.max <= 8, "{what}: {:.5} of the pixels differ by more than 2 levels (largest {})", d.differing, d.max);
    }
}

#[test]
fn the_seeded_buffers_first_layer_drawn_over_the_seed_gives_the_same_picture() {
    // The skydome's run seeds the clouds' buffer; the clouds' first layer is drawn over the seed
    // itself (`RunJoining::SeededFolded`) instead of over a seeding pass's output. At the horizon without the
    // scene the frame reaches below the clouds' dome (-5 degrees), where the seeding pass still
    // runs, confined to those rows; looking up it does not run at all.
    let sky = default_sky();
    let mut h = common::headless(1280, 720);
    h.set_sky(&sky).expect("uploaded");
    let horizon = Camera { pitch_deg: 5.0, ..Camera::default() };
    let up = Camera { pitch_deg: 80.0, ..Camera::default() };
    let folded = RenderOptions { glare: false, ..Default::default() };
    let alone = RenderOptions { scene: false, ..folded };
    for (what, input, camera, options) in [
        ("noon at the horizon, no scene", FrameInput::new(12.0, 0.3), horizon, alone),
        ("noon at the horizon", FrameInput::new(12.0, 0.3), horizon, folded),
        ("dusk looking up", FrameInput::new(18.5, 0.4), up, alone),
        ("night at the horizon, no scene", FrameInput::new(23.0, 0.2), horizon, alone),
    ] {
        folded_and_not(&mut h, &sky, what, (&input, &camera, &options));
    }
    // On the HDR target a physical model's sky stays at half resolution, and clouds seeded with it
    // must be at least as fine: the cloudy layer's finer texture tiled twice as densely (5.4
    // texels per degree) goes whole to 1.75 and takes the clear layer's run with it.
    let mut fine = sky.clone();
    let cloudy = fine.objects.iter_mut().find(|o| o.name == "clouds_cloudy").expect("cloudy layer");
    cloudy.standard.stages[1].uv_scale = cloudy.standard.stages[1].uv_scale.map(|s| s * 2.0);
    h.set_sky(&fine).expect("uploaded");
    let mut lut = FrameInput::new(10.0, 0.6);
    lut.sky_model = Some(SkyModel { kind: SkyModelKind::Lut, ..sky.model });
    let looking_up = Camera { pitch_deg: 60.0, ..Camera::default() };
    let hdr = RenderOptions { strategy: alone.strategy.with_hdr(), ..alone };
    folded_and_not(&mut h, &fine, "lut on the HDR target, looking up", (&lut, &looking_up, &hdr));
    folded_and_not(&mut h, &fine, "lut display-referred, looking up", (&lut, &looking_up, &alone));
}

/// Renders a seeded frame with the seeded buffer's first layer over the seed and without, and
/// holds the two to within 2 levels.
fn folded_and_not(h: &mut skytune::render::Headless, sky: &skytune::sky::Sky, what: &str, (input, camera, options): (&FrameInput, &Camera, &RenderOptions)) {
    let one = h.render(sky, input, camera, options).expect("rendered");
    let s = h.renderer.stats.clone();
    let two = h.render(sky, input, camera, &RenderOptions { strategy: FillStrategy { runs: RunJoining::Seeded, ..options.strategy }, ..*options }).expect("rendered");
    let t = h.renderer.stats.clone();
    assert!(s.seeded && s.seed_folded, "{what}: folded ({s:?})");
    assert!(t.seeded && !t.seed_folded, "{what}: not folded ({t:?})");
    let (d, _) = common::diff(&one, &two, 2);
    let physical = input.sky_model.map_or(sky.model.kind, |m| m.kind).is_physical();
    let (share, largest) = over_seed_limits(skytune::render::plan::matches_hdr_picture(physical, &options.strategy));
    assert!(d.differing < share && d.max <= largest, "{what}: {:.4} of the pixels differ by more than 2 levels (largest {})", d.differing, d.max);
}

/// How far a frame whose seeded buffer's first layer is drawn over the seed may be from the same
/// frame drawn otherwise: the share of pixels more than 2 levels off, and the largest difference.
/// On a display-referred physical frame matched to the HDR picture (`matched`) that layer is
/// blended in radiance over what the seed shows (`over_seed_in_radiance`), where drawn otherwise
/// it is matched over the model's map: the seed's 8-bit colour taken back through the tone curve
/// moves a few dark pixels by up to 4 levels.
fn over_seed_limits(matched: bool) -> (f64, u8) {
    if matched {
        (0.005, 6)
    } else {
        (0.001, 255)
    }
}

#[test]
fn additive_draws_under_the_background_give_the_same_picture() {
    // The skydome's fine stars, the shooting stars and the star field right after the
    // background: drawn first onto the cleared frame, the background composited over them,
    // against the same draws depth-tested in the sky phase. Looking up (no scene in view: there
    // they go first) and at the horizon (the scene in view: they stay in the sky phase); by day
    // only billboards would go, and they stay. The skydome's fine stars are the background itself
    // (`UnderBackground::AdditiveFused`), checked against the composite over them too.
    let (sky, mut h) = night_sky_with_shooting_stars();
    let mut lut = FrameInput::new(22.0, 0.2);
    lut.sky_model = Some(SkyModel { kind: SkyModelKind::Lut, ..sky.model });
    let up = Camera { pitch_deg: 60.0, ..Camera::default() };
    let no_scene = RenderOptions { scene: false, ..Default::default() };
    // Thick, broad clouds at night (coarse enough for a reduced buffer at this size, so their
    // run lies above the stars): the stars under them are dimmed by that run's transmittance.
    let mut overcast = sky.clone();
    let clouds = overcast.object_index("clouds_clear").expect("the built-in sky has clear-weather clouds");
    let version = &mut overcast.objects[clouds].standard;
    version.diffuse = skytune::sky::resolved::Color { mode: skytune::sky::model::ColorMode::Unused, bitmap: None, value: [0.2, 0.2, 0.25, 0.8] };
    for stage in &mut version.stages {
        stage.uv_scale = [0.5, 0.5];
    }
    // (what, sky, input, camera, options, drawn first, fused)
    for (what, sky, input, camera, base, goes_first, fuses) in [
        ("night, looking up", &sky, FrameInput::new(23.0, 0.0), up, RenderOptions::default(), true, true),
        ("night under clouds, looking up", &sky, FrameInput::new(2.0, 0.4), Camera { yaw_deg: 180.0, ..up }, RenderOptions::default(), true, true),
        ("night under thick clouds, looking up", &overcast, FrameInput::new(23.0, 0.0), up, RenderOptions::default(), true, true),
        ("dusk, looking up", &sky, FrameInput::new(18.5, 0.3), up, RenderOptions::default(), true, true),
        ("lut on the HDR target, looking up", &sky, lut.clone(), up, RenderOptions::default().with_strategy(FillStrategy::software().with_hdr()), true, true),
        ("lut display-referred, looking up", &sky, lut, up, RenderOptions::default(), true, true),
        ("night, horizon", &sky, FrameInput::new(23.0, 0.0), Camera { pitch_deg: 10.0, ..Camera::default() }, RenderOptions::default(), false, false),
        // No scene, the frame reaching below the skydome's lowest row (-20 degrees): fused, the
        // background composited below that row first (`Caps::background_gap`).
        ("night, no scene, horizon", &sky, FrameInput::new(23.0, 0.0), Camera::default(), no_scene, true, true),
        ("dusk, no scene, looking down", &sky, FrameInput::new(18.5, 0.3), Camera { pitch_deg: -5.0, ..Camera::default() }, no_scene, true, true),
        (
            "night under thick clouds, no scene, looking down",
            &overcast,
            FrameInput::new(23.0, 0.0),
            Camera { pitch_deg: -5.0, yaw_deg: 90.0, ..Camera::default() },
            no_scene,
            true,
            true,
        ),
        // The sun alone would not pay for blending the background.
        ("noon, looking up", &sky, FrameInput::new(12.0, 0.0), Camera { yaw_deg: 180.0, ..up }, RenderOptions::default(), false, false),
    ] {
        h.set_sky(sky).expect("uploaded");
        for runs in [RunJoining::SeededFolded, RunJoining::Separate] {
            let join_runs = runs != RunJoining::Separate;
            let first = RenderOptions { glare: false, strategy: FillStrategy { runs, ..base.strategy }, ..base };
            let one = h.render(sky, &input, &camera, &first).expect("rendered");
            let (drawn_first, fused) = (h.renderer.stats.drawn_first, h.renderer.stats.background_fused);
            assert_eq!(drawn_first > 0, goes_first, "{what}, joined {join_runs}: {drawn_first} draws first ({:?})", h.renderer.stats);
            assert_eq!(fused, fuses, "{what}, joined {join_runs}: fused {fused} ({:?})", h.renderer.stats);
            let two = h
                .render(sky, &input, &camera, &RenderOptions { strategy: FillStrategy { under_background: UnderBackground::Nothing, ..first.strategy }, ..first })
                .expect("rendered");
            assert_eq!(h.renderer.stats.drawn_first, 0);
            assert!(!h.renderer.stats.background_fused);
            // The same sums in another order: rounding of the 8-bit target (and of the
            // combination's transmittance) moves a level or two.
            let (d, _) = common::diff(&one, &two, 2);
            assert!(d.differing < 0.001, "{what}, joined {join_runs}: {:.4} of the pixels differ by more than 2 levels (largest {})", d.differing, d.max);
            if fuses {
                let composited = h
                    .render(sky, &input, &camera, &RenderOptions { strategy: FillStrategy { under_background: UnderBackground::Additive, ..first.strategy }, ..first })
                    .expect("rendered");
                assert!(!h.renderer.stats.background_fused && h.renderer.stats.drawn_first == drawn_first);
                // One rounding less; only where overlapping sprites saturate the 8-bit target
                // (clamped before or after the background's transmittance) does a pixel move by
                // more (a term left unweighed by the runs above it moves 0.8% of them by tens).
                let (d, _) = common::diff(&one, &composited, 2);
                assert!(
                    d.differing < 0.0005,
                    "{what}, joined {join_runs}: fused against composited, {:.5} of the pixels differ by more than 2 levels (largest {})",
                    d.differing,
                    d.max
                );
            }
        }
    }
}

#[test]
fn the_lightning_flash_added_to_the_run_before_it_gives_the_same_picture() {
    let sky = default_sky();
    // A storm moment with a bright flash (the built-in sky's lightning, in the storm clouds).
    let at = |i: u32| FrameInput { particle_clock: Some(ParticleClock { time_s: f64::from(i) * 0.05, hours_per_s: 0.0 }), ..FrameInput::new(15.0, 1.0) };
    let input = (0..8000).map(at).find(|input| sky.evaluate(input).particles.flash > 0.3).expect("a flash within 400 s of storm");
    // The storm's clouds resolve into a reduced buffer at the full size only.
    let mut h = common::headless(1280, 720);
    h.set_sky(&sky).expect("uploaded");
    let lut = FrameInput { sky_model: Some(SkyModel { kind: SkyModelKind::Lut, ..sky.model }), ..input.clone() };
    let towards_sun = Camera { yaw_deg: 250.0, pitch_deg: 15.0, ..Camera::default() };
    // (what, input, camera, scene, strategy, share of pixels allowed beyond 2 levels)
    for (what, input, camera, scene, strategy, allowed) in [
        ("horizon", &input, Camera { pitch_deg: 10.0, ..Camera::default() }, false, FillStrategy::software(), 0.001),
        ("horizon, scene", &input, Camera { pitch_deg: 5.0, ..Camera::default() }, true, FillStrategy::software(), 0.001),
        ("zenith", &input, Camera::preset("zenith").expect("zenith view"), false, FillStrategy::software(), 0.001),
        ("lut on the HDR target", &lut, towards_sun, false, FillStrategy::software().with_hdr(), 0.001),
        // Display-referred, the physical sky is brighter than the painted one, and the 8-bit
        // buffers clamp the flash where it is added (to the run, or over the frame) at more
        // pixels: 0.28% beyond 2 levels, 39 at most (measured).
        ("lut display-referred", &lut, towards_sun, false, FillStrategy::software(), 0.005),
    ] {
        let in_run = RenderOptions { glare: false, scene, strategy, ..Default::default() };
        let over = RenderOptions { strategy: FillStrategy { flash: FlashPlacement::OverFrame, ..in_run.strategy }, ..in_run };
        let one = h.render(&sky, input, &camera, &in_run).expect("rendered");
        let s = h.renderer.stats.clone();
        assert_eq!(s.joined_runs_only, 1, "{what}: the flash joins a run ({s:?})");
        let two = h.render(&sky, input, &camera, &over).expect("rendered");
        assert_eq!(h.renderer.stats.joined_runs_only, 0, "{what}");
        // The same sum in another order: rounding of the 8-bit buffers moves a level or two.
        let (d, _) = common::diff(&one, &two, 2);
        assert!(d.differing < allowed, "{what}: {:.4} of the pixels differ by more than 2 levels (largest {})", d.differing, d.max);
    }
}

#[test]
fn two_alpha_layers_drawn_at_once_give_the_same_picture() {
    // Two alpha-blended layers next to each other in a run drawn at once (`LayerPairs::AtOnce`): one
    // shader evaluating both, one blend, against one after the other. The clear and cloudy cloud
    // layers share a mesh; the cloudy and storm layers a shape (the Quake layer on its outline, the
    // pair on the cloudy layer's grid). Over the seed and after a seeding pass, with and without
    // the scene, and on the HDR target.
    let sky = default_sky();
    // Large enough for both cloud layers to go to a reduced buffer (at 960 x 540 the clear one,
    // densest towards its layer's horizon, needs a finer one than `auto` makes).
    let mut h = common::headless(1280, 720);
    h.set_sky(&sky).expect("uploaded");
    let horizon = Camera { pitch_deg: 5.0, ..Camera::default() };
    let up = Camera { pitch_deg: 80.0, ..Camera::default() };
    let paired = RenderOptions { glare: false, ..Default::default() };
    let alone = RenderOptions { scene: false, ..paired };
    let unfolded = RenderOptions { strategy: FillStrategy { runs: RunJoining::Seeded, ..alone.strategy }, ..alone };
    let mut lut = FrameInput::new(16.0, 0.5);
    lut.sky_model = Some(SkyModel { kind: SkyModelKind::Lut, ..sky.model });
    for (what, input, camera, options) in [
        ("dusk looking up, over the seed", FrameInput::new(18.5, 0.4), up, alone),
        ("dusk looking up, after a seeding pass", FrameInput::new(18.5, 0.4), up, unfolded),
        ("dusk at the horizon", FrameInput::new(18.5, 0.4), horizon, paired),
        ("storm at the horizon, no scene", FrameInput::new(15.0, 1.0), horizon, alone),
        ("storm looking up", FrameInput::new(15.0, 1.0), up, alone),
        ("lut on the HDR target, looking up", lut.clone(), up, RenderOptions { strategy: alone.strategy.with_hdr(), ..alone }),
    ] {
        let one = h.render(&sky, &input, &camera, &options).expect("rendered");
        let s = h.renderer.stats.clone();
        let two = h.render(&sky, &input, &camera, &RenderOptions { strategy: FillStrategy { pairs: LayerPairs::OneByOne, ..options.strategy }, ..options }).expect("rendered");
        assert!(s.layers_paired >= 1, "{what}: a pair drawn at once ({s:?})");
        assert_eq!(h.renderer.stats.layers_paired, 0, "{what}");
        // One blend rounds once where two rounded twice.
        let (d, _) = common::diff(&one, &two, 2);
        assert!(d.differing < 0.001, "{what}: {:.4} of the pixels differ by more than 2 levels (largest {})", d.differing, d.max);
    }
    // On a display-referred physical frame the pair is matched to the HDR picture as one layer:
    // the HDR path's two blends over the model's sky, tone-mapped once, where one by one each
    // layer is matched as if over the bare sky. So where the layers stack the pair is the HDR
    // picture, and closer to it than the layers one by one.
    for (what, input) in [("afternoon", lut.clone()), ("dusk", FrameInput { sky_model: lut.sky_model, ..FrameInput::new(18.5, 0.4) })] {
        let hdr = h.render(&sky, &input, &up, &RenderOptions { strategy: alone.strategy.with_hdr(), ..alone }).expect("rendered");
        let paired = h.render(&sky, &input, &up, &alone).expect("rendered");
        assert!(h.renderer.stats.layers_paired >= 1, "{what}: a pair drawn at once");
        let one_by_one = h.render(&sky, &input, &up, &RenderOptions { strategy: FillStrategy { pairs: LayerPairs::OneByOne, ..alone.strategy }, ..alone }).expect("rendered");
        let (p, _) = common::diff(&paired, &hdr, 10);
        let (o, _) = common::diff(&one_by_one, &hdr, 10);
        eprintln!("{what}: against the HDR frame, paired {p:?}, one by one {o:?}");
        assert!(p.mean <= o.mean && p.differing <= o.differing, "{what}: paired {p:?} further from the HDR frame than one by one {o:?}");
        assert!(p.mean < 1.0 && p.differing < 0.01, "{what}: paired {p:?} against the HDR frame");
    }
}

#[test]
fn a_physical_night_sky_drawn_in_parts_is_the_one_drawn_whole() {
    // On the HDR target a display black converts to no light: the skydome drawn as a reduced part
    // (the model's map) and a full-resolution one (its stars), each reading the other's stages as
    // black, adds nothing for them. (Converted by the ACES fit's inverse, each black term added
    // the foot of its toe, and the `software` frame came out 8 levels brighter than `plain`'s.)
    let sky = default_sky();
    let mut h = common::headless(320, 180);
    h.set_sky(&sky).expect("uploaded");
    let camera = Camera { pitch_deg: 89.0, ..Camera::default() };
    for hour in [23.0, 1.0] {
        let mut input = FrameInput::new(hour, 0.0);
        input.sky_model = Some(SkyModel { kind: SkyModelKind::Lut, ..sky.model });
        // The stars' layer coordinates per vertex as the software strategy has them: the test
        // is about the parts (per pixel they land up to a few texels away near the horizon).
        let plain = FillStrategy { layer_coordinates: LayerCoordinates::PerVertex, ..FillStrategy::plain() };
        let whole = h.render(&sky, &input, &camera, &RenderOptions::default().with_strategy(plain)).unwrap();
        let parts = h.render(&sky, &input, &camera, &common::hdr_options()).unwrap();
        assert!(h.renderer.stats.objects_reduced > 0, "the skydome drawn in parts");
        let (d, _) = common::diff(&parts, &whole, 2);
        // Looking up, the skydome's run goes to an eighth (the map is that coarse there), where
        // the galaxy's brightest knot comes out a few levels off full resolution, as on the
        // painted frame (0.17% of the pixels by more than 2); 8 levels over the frame was the bug.
        assert!(d.mean < 0.1 && d.differing < 0.004, "hour {hour}: {d:?}");
    }
}

#[test]
fn a_costly_layer_drawn_apart_gives_the_same_picture() {
    // On a display-referred physical frame the fog's band is matched over the model's sky (a
    // sample of the map and three tone curves per fragment) and needs an eighth of the frame's
    // resolution, but shares the clouds' much finer buffer: drawn apart at its own resolution
    // (`CostlyLayers::OwnBuffer`) and composited into the clouds' buffer, against drawn there.
    // Looking at the horizon, where the band covers most of the frame.
    let horizon = Camera { yaw_deg: 180.0, pitch_deg: 10.0, ..Camera::default() };
    let apart = RenderOptions { glare: false, ..Default::default() };
    let in_run = RenderOptions { strategy: FillStrategy { costly_layers: CostlyLayers::InRun, ..apart.strategy }, ..apart };
    let lakes = skytune::sky::load_sky_file(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("skies/lakes/sky.toml")).expect("the lakes sky loads");
    let mut h = common::headless(1280, 720);
    for (what, sky, hour, weather) in [("built-in sky at dusk", default_sky(), 18.5, 0.3), ("lakes at noon", lakes.clone(), 12.0, 0.0), ("lakes at night", lakes, 23.0, 0.0)] {
        h.set_sky(&sky).expect("uploaded");
        let input = FrameInput { sky_model: Some(SkyModel { kind: SkyModelKind::Lut, ..sky.model }), ..FrameInput::new(hour, weather) };
        let one = h.render(&sky, &input, &horizon, &apart).expect("rendered");
        let s = h.renderer.stats.clone();
        assert_eq!(s.own_buffers, 1, "{what}: the fog drawn apart ({s:?})");
        let two = h.render(&sky, &input, &horizon, &in_run).expect("rendered");
        assert_eq!(h.renderer.stats.own_buffers, 0, "{what}");
        let hdr = h.render(&sky, &input, &horizon, &RenderOptions { strategy: apart.strategy.with_hdr(), ..apart }).expect("rendered");
        // The band's match follows the map at the map's resolution; upsampled, its soft parts
        // move by a level or two. (Its hard lower edge, 20 degrees below the horizon, lies
        // behind the scene; drawn alone over nothing it softens over a pixel or two, as any
        // layer drawn at its own resolution does.)
        let (d2, _) = common::diff(&one, &two, 2);
        let (d8, _) = common::diff(&one, &two, 8);
        let (a, _) = common::diff(&one, &hdr, 10);
        let (b, _) = common::diff(&two, &hdr, 10);
        eprintln!("{what}: apart against in the run {d2:?} (>8: {d8:?}); against the HDR frame, apart {a:?}, in the run {b:?}");
        assert!(d2.mean < 0.5 && d2.differing < 0.02 && d8.differing < 0.001, "{what}: apart {d2:?}, >8 {d8:?}");
        assert!(a.mean <= b.mean + 0.1 && a.differing <= b.differing + 0.001, "{what}: apart {a:?} further from the HDR frame than in the run {b:?}");
    }
}
