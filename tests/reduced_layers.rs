//! Dome layers at reduced resolution (`RenderOptions::dome_resolution`): the frame stays close to
//! the full-resolution one on both targets, layers with finer texture detail than the reduced
//! buffer (the skydome's stars at night) stay at full resolution, and billboards never go there.

mod common;

use skytune::render::{Camera, DomeResolution, RenderOptions};
use skytune::sky::builtin::default_sky;
use skytune::sky::resolved::{SkyModel, SkyModelKind};
use skytune::sky::FrameInput;

#[test]
fn reduced_dome_layers_stay_close_to_full_resolution() {
    let sky = default_sky();
    // Large enough that the cloud textures are coarser than a half-resolution buffer's pixels.
    let mut h = common::headless(640, 360);
    h.set_sky(&sky).expect("uploaded");
    let camera = Camera { pitch_deg: 30.0, ..Camera::default() };
    let full = RenderOptions { glare: false, dome_resolution: DomeResolution::Full, ..Default::default() };
    let half = RenderOptions { dome_resolution: DomeResolution::Half, ..full };
    let mut lut = FrameInput::new(10.0, 0.3);
    lut.sky_model = Some(SkyModel { kind: SkyModelKind::Lut, ..sky.model });
    for (what, input) in [
        ("bitmaps, 10:00", FrameInput::new(10.0, 0.3)),
        ("lut on the HDR target, 10:00", lut),
        ("bitmaps, dusk", FrameInput::new(18.5, 0.6)),
        ("bitmaps, night", FrameInput::new(23.0, 0.0)),
    ] {
        let sharp = h.render(&sky, &input, &camera, &full).expect("rendered");
        assert_eq!(h.renderer.stats.objects_reduced, 0, "{what}: full resolution reduces nothing");
        let soft = h.render(&sky, &input, &camera, &half).expect("rendered");
        let s = h.renderer.stats.clone();
        assert!(s.objects_reduced >= 2, "{what}: the skydome and a cloud layer go to the reduced buffer ({s:?})");
        // Soft cloud edges move by a few levels; a wrong blend or composite moves whole areas.
        let (d, _) = common::diff(&sharp, &soft, 24);
        eprintln!("{what}: >24 {:.5}", d.differing);
        let (d6, _) = common::diff(&sharp, &soft, 6);
        eprintln!("{what}: >6 {:.5}", d6.differing);
        assert!(d.differing < 0.02, "{what}: {:.4} of the pixels differ by more than 24 levels (largest {})", d.differing, d.max);
        let (d, _) = common::diff(&sharp, &soft, 6);
        assert!(d.differing < 0.01, "{what}: {:.4} of the pixels differ by more than 6 levels", d.differing);
    }
}

#[test]
fn fine_layers_and_billboards_stay_at_full_resolution() {
    let sky = default_sky();
    let mut h = common::headless(320, 180);
    h.set_sky(&sky).expect("uploaded");
    let camera = Camera { pitch_deg: 30.0, ..Camera::default() };
    let half = RenderOptions { glare: false, dome_resolution: DomeResolution::Half, ..Default::default() };
    let quarter = RenderOptions { dome_resolution: DomeResolution::Quarter, ..half };
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
