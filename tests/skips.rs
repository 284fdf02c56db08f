//! The renderer's skips of work that contributes nothing: they change no pixel, and the frame's
//! counters say what was skipped (the app's stats panel and `skytune bench` report them).

mod common;

use skytune::render::plan::strategy::RunJoining;
use skytune::render::{Camera, DomeResolution, FillStrategy, FrameStats, Headless, RenderOptions, Skips};
use skytune::sky::builtin::default_sky;
use skytune::sky::resolved::{SkyModel, SkyModelKind};
use skytune::sky::{FrameInput, Sky};

/// Renders one frame with the skips `on` and again with `off`, asserts that no pixel differs by
/// more than `tolerance`, and returns both frames' counters. `what` names the frame for the
/// failure message, from the counters of the frame with the skips on.
fn same_pixels(
    h: &mut Headless,
    (sky, input, camera): (&Sky, &FrameInput, &Camera),
    (on, off): (&RenderOptions, &RenderOptions),
    tolerance: u8,
    what: impl FnOnce(&FrameStats) -> String,
) -> (FrameStats, FrameStats) {
    let with = h.render(sky, input, camera, on).expect("rendered");
    let with_stats = h.renderer.stats.clone();
    let without = h.render(sky, input, camera, off).expect("rendered");
    let without_stats = h.renderer.stats.clone();
    let (d, _) = common::diff(&with, &without, tolerance);
    assert_eq!(d.differing, 0.0, "{} moved {:.4} of the pixels (largest {})", what(&with_stats), d.differing, d.max);
    (with_stats, without_stats)
}

#[test]
fn skips_change_no_pixel_and_are_counted() {
    let sky = default_sky();
    let mut h = common::headless(160, 90);
    h.set_sky(&sky).expect("uploaded");
    let camera = Camera { pitch_deg: 35.0, ..Camera::default() };
    let mut input = FrameInput::new(13.0, 0.2);
    input.sky_model = Some(SkyModel { kind: SkyModelKind::Lut, ..sky.model });
    // At full resolution: a skipped stage can let a dome layer go to a reduced buffer, which
    // moves pixels by a level or two (tests/reduced_layers.rs bounds that).
    let on = RenderOptions { glare: false, strategy: FillStrategy { dome_resolution: DomeResolution::Full, ..FillStrategy::software() }, ..Default::default() };
    let off = RenderOptions {
        skips: Skips { dark_stages: false, invisible_stars: false, unchanged_tables: false, below_horizon: false, off_screen: false, unneeded_mips: false, covered_clears: false },
        ..on
    };
    // Two frames each: the second finds the tables and the map current.
    h.render(&sky, &input, &camera, &on).expect("rendered");
    let with = h.render(&sky, &input, &camera, &on).expect("rendered");
    let s = h.renderer.stats.clone();
    assert!(s.tables_skipped && s.map_skipped, "nothing moved: tables and map reused ({s:?})");
    assert!(s.stars_skipped, "the stars are transparent at 13:00 ({s:?})");
    assert!(s.stages_skipped > 0, "some stages are black by day ({s:?})");
    h.render(&sky, &input, &camera, &off).expect("rendered");
    let without = h.render(&sky, &input, &camera, &off).expect("rendered");
    let s = h.renderer.stats.clone();
    assert!(!s.tables_skipped && !s.map_skipped && !s.stars_skipped && s.stages_skipped == 0, "every skip off ({s:?})");
    let (d, _) = common::diff(&with, &without, 1);
    assert_eq!(d.differing, 0.0, "skipping changed {:.4} of the pixels (largest difference {})", d.differing, d.max);
    // At night the stars are drawn and not counted as skipped; the sun is far below the horizon,
    // behind the scene, and skipped without changing a pixel, even looking down at it.
    let down = Camera { pitch_deg: -30.0, ..Camera::default() };
    let night = FrameInput::new(0.5, 0.0);
    let with = h.render(&sky, &night, &down, &on).expect("rendered");
    let s = h.renderer.stats.clone();
    assert!(!s.stars_skipped && s.objects_below_horizon > 0, "{s:?}");
    let without = h.render(&sky, &night, &down, &off).expect("rendered");
    assert_eq!(h.renderer.stats.objects_below_horizon, 0);
    let (d, _) = common::diff(&with, &without, 1);
    assert_eq!(d.differing, 0.0, "skipping objects below the horizon changed {:.4} of the pixels", d.differing);
    // Looking at the zenith the fog band (20 degrees up at most) is out of view: not drawn, and
    // not a pixel moves, at full resolution or with dome layers in reduced buffers (where other
    // skips change which layers go to a buffer, so only this one is switched; and where the fog's
    // run, when drawn, would be joined with the skydome's, which rounds a level differently:
    // tests/reduced_layers.rs bounds that).
    let zenith = Camera::preset("zenith").expect("zenith view");
    for resolution in [DomeResolution::Full, DomeResolution::Auto] {
        let on = RenderOptions { strategy: FillStrategy { dome_resolution: resolution, runs: RunJoining::Separate, ..on.strategy }, ..on };
        let off = RenderOptions { skips: Skips { off_screen: false, ..on.skips }, ..on };
        let (s, without) = same_pixels(&mut h, (&sky, &night, &zenith), (&on, &off), 1, |_| format!("{resolution:?}: skipping dome layers out of view"));
        assert!(s.objects_off_screen > 0, "{resolution:?}: {s:?}");
        assert_eq!(without.objects_off_screen, 0);
    }
}

/// Billboards and quads wholly outside the frame are not drawn: round the compass, looking at
/// the horizon and up, at dusk and at night, not a pixel moves, and most views leave some out.
/// At full resolution and in reduced buffers without joined runs (leaving a billboard out can
/// let runs join, which rounds a level differently: tests/reduced_layers.rs bounds that).
#[test]
fn billboards_out_of_the_frame_are_skipped_and_change_no_pixel() {
    let sky = default_sky();
    let mut h = common::headless(160, 90);
    h.set_sky(&sky).expect("uploaded");
    let mut skipped = 0;
    let mut frames = 0;
    for input in [FrameInput::new(18.5, 0.3), FrameInput::new(23.0, 0.0), FrameInput::new(5.5, 0.2)] {
        for pitch_deg in [5.0, 40.0] {
            for k in 0..16 {
                let camera = Camera { yaw_deg: k as f32 * 22.5, pitch_deg, ..Camera::default() };
                for resolution in [DomeResolution::Full, DomeResolution::Auto] {
                    let on = RenderOptions {
                        glare: false,
                        scene: false,
                        strategy: FillStrategy { dome_resolution: resolution, runs: RunJoining::Separate, ..FillStrategy::software() },
                        ..Default::default()
                    };
                    let off = RenderOptions { skips: Skips { off_screen: false, ..on.skips }, ..on };
                    let (with, without) = same_pixels(&mut h, (&sky, &input, &camera), (&on, &off), 0, |s| {
                        format!("{camera:?}, {resolution:?}: skipping {} objects out of the frame", s.objects_off_screen)
                    });
                    skipped += with.objects_off_screen;
                    frames += usize::from(with.objects_off_screen > 0);
                    assert_eq!(without.objects_off_screen, 0);
                }
            }
        }
    }
    assert!(frames > 100 && skipped > 200, "the skip applies: {skipped} objects over {frames} of 192 frames");
}

/// Stages that no pixel of a draw minifies are sampled from level 0 alone: the bound on their
/// texel density must hold wherever they are drawn, or a pixel would move. By day, at dusk, at
/// night and in a storm, at the horizon, the zenith and straight at the sun, at full and at
/// reduced resolution, on the built-in sky and the desert (Quake-mapped storm clouds).
#[test]
fn level0_samplers_change_no_pixel() {
    let desert = skytune::sky::load_sky_file(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("skies/desert/sky.toml")).expect("desert sky");
    let mut h = common::headless(480, 270);
    let mut level0 = 0;
    for sky in [default_sky(), desert] {
        h.set_sky(&sky).expect("uploaded");
        for (hour, weather) in [(12.0, 0.0), (18.5, 0.3), (23.0, 0.0), (15.0, 1.0)] {
            let input = FrameInput::new(hour, weather);
            let (yaw_deg, pitch_deg) = skytune::sky::eval::azimuth_elevation(sky.evaluate(&input).towards_sun);
            let at_sun = Camera { yaw_deg, pitch_deg, ..Camera::default() };
            for camera in [Camera::default(), Camera::preset("zenith").expect("zenith view"), at_sun] {
                for resolution in [DomeResolution::Full, DomeResolution::Auto] {
                    let on = RenderOptions { glare: false, strategy: FillStrategy { dome_resolution: resolution, ..FillStrategy::software() }, ..Default::default() };
                    let off = RenderOptions { skips: Skips { unneeded_mips: false, ..on.skips }, ..on };
                    let (with, without) =
                        same_pixels(&mut h, (&sky, &input, &camera), (&on, &off), 0, |_| format!("{hour} h, weather {weather}, {camera:?}, {resolution:?}: level-0 sampling"));
                    level0 += with.stages_level0;
                    assert_eq!(without.stages_level0, 0);
                }
            }
        }
    }
    assert!(level0 > 20, "the skip applies ({level0} stages over every frame)");
}

/// The celestial mapping is sampled from level 0 without derivatives where the frame keeps far
/// enough from the poles of its texture, round which the texture's columns crowd: a galaxy of
/// noise (detail everywhere, the poles included, unlike the built-in band) seen at several
/// angles from a pole, at full and reduced resolution, moves no pixel against mipmapped sampling
/// (a bound on the texture's density half as large, or a pole twice as far, moves some).
#[test]
fn the_celestial_mapping_from_level_0_changes_no_pixel() {
    let mut sky = default_sky();
    let (w, h) = (256u32, 128u32);
    let mut rng = fastrand::Rng::with_seed(5);
    let rgba8 = (0..w * h).flat_map(|_| [rng.u8(..), rng.u8(..), rng.u8(..), 255]).collect();
    let noise = std::sync::Arc::new(skytune::sky::resolved::TextureImage { key: "test: noise galaxy".into(), width: w, height: h, rgba8 });
    let galaxy = sky.objects.iter_mut().find(|o| o.name == "galaxy").expect("the built-in galaxy");
    galaxy.standard.stages[0].texture = Some(noise);
    let others: Vec<String> = sky.objects.iter().map(|o| o.name.clone()).filter(|n| n != "galaxy").collect();
    let input = FrameInput { disabled: others, ..FrameInput::new(23.0, 0.0) };
    let north = sky.evaluate(&input).celestial_from_world.inverse() * glam::Vec3::Y;
    let mut h = common::headless(320, 180);
    h.set_sky(&sky).expect("uploaded");
    let (mut level0, mut mipmapped) = (0, 0);
    // A narrow field of view has about as many pixels per degree at its edges as at its centre
    // (the bound takes the centre's): the frame's nearest pixels 1 to 20 degrees from the pole.
    let views = [(70.0, 0.0), (70.0, 35.0), (70.0, 65.0), (70.0, 90.0), (20.0, 21.0), (20.0, 23.0), (20.0, 26.0), (20.0, 30.0), (20.0, 40.0)];
    for (fov_y_deg, from_pole_deg) in views {
        for resolution in [DomeResolution::Full, DomeResolution::Auto] {
            let side = north.any_orthonormal_vector();
            let forward = glam::Quat::from_axis_angle(side, f32::to_radians(from_pole_deg)) * north;
            let up = if forward.y.abs() > 0.99 { glam::Vec3::Z } else { glam::Vec3::Y };
            let camera = Camera { look: Some((forward, up)), fov_y_deg, ..Camera::default() };
            let on = RenderOptions { glare: false, scene: false, strategy: FillStrategy { dome_resolution: resolution, ..FillStrategy::software() }, ..Default::default() };
            let off = RenderOptions { skips: Skips { unneeded_mips: false, ..on.skips }, ..on };
            let (with, _) = same_pixels(&mut h, (&sky, &input, &camera), (&on, &off), 0, |_| {
                format!("{from_pole_deg} degrees from the pole, {fov_y_deg} degrees of view, {resolution:?}: level-0 sampling")
            });
            if with.stages_level0 > 0 {
                level0 += 1;
            } else {
                mipmapped += 1;
            }
        }
    }
    assert!(level0 >= 2 && mipmapped >= 2, "both ways taken: {level0} frames from level 0, {mipmapped} mipmapped");
}

#[test]
fn stars_too_faint_to_add_half_a_level_are_not_drawn_and_change_no_pixel() {
    let forest = skytune::sky::load_sky_file(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("skies/forest/sky.toml")).expect("forest sky");
    let mut h = common::headless(320, 180);
    h.set_sky(&forest).expect("uploaded");
    let on = RenderOptions { glare: false, ..Default::default() };
    let off = RenderOptions { skips: Skips { invisible_stars: false, ..Skips::default() }, ..on };
    let mut lut = FrameInput::new(18.5, 0.3);
    lut.sky_model = Some(SkyModel { kind: SkyModelKind::Lut, ..forest.model });
    let mut partly = 0;
    // Dusk and dawn, where the brighter stars show and the fainter ones add nothing; night, where
    // every star of the field shows; looking up and towards the horizon.
    for (what, input, tolerance) in [
        ("dusk", FrameInput::new(18.5, 0.3), 0),
        ("dawn", FrameInput::new(6.0, 0.0), 0),
        ("night", FrameInput::new(23.0, 0.0), 0),
        // On the HDR target every star is drawn (the tone map's toe can lift half a level by more).
        ("dusk, lut on the HDR target", lut.clone(), 0),
        // Display-referred, the stars add display values as over the painted sky.
        ("dusk, lut display-referred", lut, 0),
    ] {
        let hdr = |o: RenderOptions| if what.contains("HDR") { RenderOptions { strategy: o.strategy.with_hdr(), ..o } } else { o };
        for pitch_deg in [10.0, 60.0] {
            let camera = Camera { pitch_deg, ..Camera::default() };
            let (with, without) = same_pixels(&mut h, (&forest, &input, &camera), (&hdr(on), &hdr(off)), tolerance, |s| {
                format!("{what}, pitch {pitch_deg}: leaving out {} of {} stars", s.stars - s.stars_drawn, s.stars)
            });
            assert_eq!(without.stars_drawn, without.stars, "{what}: every star drawn with the skip off ({without:?})");
            assert!(with.stars_drawn <= with.stars, "{with:?}");
            partly += u32::from(with.stars_drawn > 0 && with.stars_drawn < with.stars);
            if what == "night" || what.contains("HDR") {
                assert_eq!(with.stars_drawn, with.stars, "{what}: every star of the field drawn ({with:?})");
            }
        }
    }
    assert!(partly >= 4, "some frames draw some of the stars and leave out others ({partly})");
}

#[test]
fn clears_left_out_where_the_background_or_an_untouched_depth_makes_them_unneeded_change_no_pixel() {
    let sky = default_sky();
    let mut h = common::headless(160, 90);
    h.set_sky(&sky).expect("uploaded");
    let zenith = Camera::preset("zenith").expect("zenith view");
    // Looking down: the frame shows what lies below the skydome (20 degrees down), which only the
    // clear paints when no background covers the frame.
    let down = Camera { pitch_deg: -25.0, ..Camera::default() };
    let horizon = Camera { pitch_deg: 5.0, ..Camera::default() };
    let on = RenderOptions { scene: false, glare: false, ..Default::default() };
    let off = RenderOptions { skips: Skips { covered_clears: false, ..on.skips }, ..on };
    for (what, input, camera, resolution) in [
        ("dusk looking up (the background fused with the stars)", FrameInput::new(18.5, 0.3), &zenith, DomeResolution::Auto),
        ("noon looking down (the background composited)", FrameInput::new(12.0, 0.0), &down, DomeResolution::Auto),
        ("night looking down at full resolution (no background)", FrameInput::new(23.0, 0.0), &down, DomeResolution::Full),
        ("dusk at the horizon at full resolution (every layer depth-tested)", FrameInput::new(18.5, 0.3), &horizon, DomeResolution::Full),
    ] {
        let (on, off) = (
            RenderOptions { strategy: FillStrategy { dome_resolution: resolution, ..on.strategy }, ..on },
            RenderOptions { strategy: FillStrategy { dome_resolution: resolution, ..off.strategy }, ..off },
        );
        // Each frame follows one with the main scene drawn, whose colour and depth a clear left out
        // where needed would keep: the sky failing the depth test where the terrain was, or the
        // terrain's colour left below the dome.
        h.render(&sky, &input, camera, &RenderOptions { scene: true, ..on }).expect("rendered");
        let with = h.render(&sky, &input, camera, &on).expect("rendered");
        let counted = h.renderer.stats.clears_skipped;
        h.render(&sky, &input, camera, &RenderOptions { scene: true, ..on }).expect("rendered");
        let without = h.render(&sky, &input, camera, &off).expect("rendered");
        assert_eq!(h.renderer.stats.clears_skipped, 0);
        let (d, _) = common::diff(&with, &without, 0);
        assert_eq!(d.differing, 0.0, "{what}: leaving clears out moved {:.4} of the pixels (largest {})", d.differing, d.max);
        // A second frame without the scene finds the depth still clear; the colour is left
        // uncleared only under a background.
        h.render(&sky, &input, camera, &on).expect("rendered");
        let both = h.renderer.stats.clears_skipped;
        match resolution {
            DomeResolution::Full => assert_eq!(both, 1, "{what}: the depth's clear only"),
            _ => assert_eq!(both, 2, "{what}: the colour's and the depth's clears"),
        }
        assert!(counted <= both, "{what}");
    }
}

#[test]
fn blended_draws_black_and_transparent_are_left_out_without_moving_a_pixel() {
    // At tier 2 by day the skydome's second card (stars x mask, added) has every term black:
    // left out, and nothing moves (full resolution: a skipped stage can also change which layers
    // go to a reduced buffer, which tests/reduced_layers.rs bounds).
    let sky = default_sky();
    let mut h = common::headless(160, 90);
    h.set_sky(&sky).expect("uploaded");
    let on = RenderOptions { glare: false, strategy: FillStrategy { dome_resolution: DomeResolution::Full, ..FillStrategy::software() }, ..Default::default() };
    let off = RenderOptions { skips: Skips { dark_stages: false, ..Skips::default() }, ..on };
    for (hour, tier) in [(13.0, 2), (16.0, 2), (13.0, 4)] {
        let input = FrameInput { tier: skytune::sky::Tier::new(tier).expect("a tier"), ..FrameInput::new(hour, 0.3) };
        for camera in [Camera { pitch_deg: 35.0, ..Camera::default() }, Camera::preset("zenith").expect("zenith view")] {
            let (with, without) = same_pixels(&mut h, (&sky, &input, &camera), (&on, &off), 0, |s| format!("tier {tier} at {hour} h ({s:?})"));
            assert_eq!(without.draws_dark, 0);
            if tier == 2 {
                assert!(with.draws_dark >= 1 && with.draw_calls < without.draw_calls, "tier 2 at {hour} h: the stars card drawn ({with:?})");
            }
        }
    }
}
