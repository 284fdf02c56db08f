//! The Bright Star Catalogue: the embedded file decodes to the real stars, they sit where the sky
//! puts them, and the sky turns westward through the night.

use skytune::sky::builtin::default_sky;
use skytune::sky::model::StarSource;
use skytune::sky::starfield::{catalogue, celestial_direction, generate};
use skytune::sky::FrameInput;

#[test]
fn the_catalogue_holds_the_bright_star_catalogue() {
    let stars = catalogue();
    assert_eq!(stars.len(), 9096);
    // Brightest first: Sirius, then Canopus (declination, right ascension, magnitude).
    let sirius = stars[0];
    assert!((sirius.magnitude - -1.46).abs() < 0.006, "{sirius:?}");
    assert!((sirius.declination_deg - -16.716).abs() < 0.006, "{sirius:?}");
    assert!((sirius.right_ascension_deg / 15.0 - 6.7525).abs() < 0.001, "{sirius:?}");
    assert!((stars[1].declination_deg - -52.696).abs() < 0.006, "{:?}", stars[1]);
    assert!(stars.windows(2).all(|w| w[0].magnitude <= w[1].magnitude));
    // About 5,000 stars brighter than 6.0 (the naked-eye sky); Polaris is near the pole.
    let naked_eye = stars.iter().filter(|s| s.magnitude <= 6.0).count();
    assert!((4500..5500).contains(&naked_eye), "{naked_eye}");
    assert!(stars.iter().any(|s| s.declination_deg > 89.0 && s.magnitude < 2.1));
}

#[test]
fn catalogue_stars_sit_at_their_declination_and_hour_angle() {
    let stars = catalogue();
    let polaris = stars.iter().find(|s| s.declination_deg > 89.0 && s.magnitude < 2.1).unwrap();
    for latitude in [10.0f32, 45.0, 70.0] {
        // Polaris stands at the latitude's elevation above the north point.
        let d = celestial_direction(polaris, latitude, 0.0);
        let (azimuth, elevation) = skytune::sky::eval::azimuth_elevation(d);
        assert!((elevation - latitude).abs() < 1.0, "latitude {latitude}: elevation {elevation}");
        assert!(!(3.0..357.0).contains(&azimuth.rem_euclid(360.0)) || elevation > 85.0, "azimuth {azimuth}");
        // A star on the meridian culminates due south at 90 - latitude + declination.
        let sirius = stars[0];
        let on_meridian = celestial_direction(&sirius, latitude, sirius.right_ascension_deg);
        let (az, el) = skytune::sky::eval::azimuth_elevation(on_meridian);
        assert!((el - (90.0 - latitude + sirius.declination_deg)).abs() < 0.05, "{el}");
        assert!((az - 180.0).abs() < 0.05, "{az}");
    }
}

#[test]
fn the_sky_turns_westward_and_the_cutoff_holds() {
    let mut sky = default_sky();
    let stars = sky.stars.as_mut().unwrap();
    stars.source = StarSource::Catalogue;
    stars.magnitude_cutoff = 4.0;
    let field = generate(stars);
    assert!(field.iter().all(|s| s.magnitude <= 4.0));
    assert_eq!(field.len(), catalogue().iter().filter(|s| s.magnitude <= 4.0).count());
    // The world direction of a celestial one, as shaders/stars.wgsl computes it.
    let world = |hour: f32, dir: glam::Vec3| {
        let frame = sky.evaluate(&FrameInput::new(hour, 0.0));
        frame.celestial_from_world.inverse() * dir
    };
    // The star on the meridian at midnight has moved west an hour later and east an hour before.
    let stars = sky.stars.as_ref().unwrap();
    let on_meridian = celestial_direction(&catalogue()[0], stars.pole_elevation_deg, catalogue()[0].right_ascension_deg);
    let at = |h: f32| skytune::sky::eval::azimuth_elevation(world(h, on_meridian)).0.rem_euclid(360.0);
    assert!((at(0.0) - 180.0).abs() < 0.1, "{}", at(0.0));
    assert!(at(1.0) > 190.0, "an hour later at azimuth {}", at(1.0));
    assert!(at(23.0) < 170.0, "an hour earlier at azimuth {}", at(23.0));
}
