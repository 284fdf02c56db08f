//! The GPU side under stress: targets of 1x1 and 8192 pixels wide, and a device that goes away.

mod common;

use skytune::render::{Camera, RenderOptions};
use skytune::sky::builtin::default_sky;
use skytune::sky::resolved::SkyModelKind;
use skytune::sky::FrameInput;

#[test]
fn extreme_target_sizes_render_without_a_panic() {
    let sky = default_sky();
    let mut h = common::headless(64, 36);
    h.set_sky(&sky).unwrap();
    let camera = Camera::default();
    let physical = FrameInput { sky_model: Some(skytune::sky::resolved::SkyModel { kind: SkyModelKind::Lut, ..sky.model }), ..FrameInput::new(15.0, 0.0) };
    for (w, h_px) in [(1, 1), (8192, 8), (3, 4096), (64, 36)] {
        h.resize(w, h_px);
        for input in [FrameInput::new(15.0, 0.0), physical.clone()] {
            let img = h.render(&sky, &input, &camera, &RenderOptions::default()).unwrap();
            assert_eq!(img.dimensions(), (w, h_px));
        }
    }
}

#[test]
fn a_lost_device_is_reported_and_a_new_one_takes_over() {
    let sky = default_sky();
    let mut h = common::headless(32, 18);
    h.set_sky(&sky).unwrap();
    let camera = Camera::default();
    let before = h.render(&sky, &FrameInput::new(12.0, 0.0), &camera, &RenderOptions::default()).unwrap();
    assert!(h.ctx.lost_reason().is_none());
    // The one way wgpu lets a test lose a device.
    h.ctx.device.destroy();
    let _ = h.ctx.wait_idle();
    assert!(h.ctx.lost_reason().is_some(), "the loss is reported");
    // Rendering with the dead device fails (or renders nothing) without a panic.
    let _ = h.render(&sky, &FrameInput::new(12.0, 0.0), &camera, &RenderOptions::default());
    // A new device renders the same picture.
    let mut fresh = common::headless(32, 18);
    fresh.set_sky(&sky).unwrap();
    let after = fresh.render(&sky, &FrameInput::new(12.0, 0.0), &camera, &RenderOptions::default()).unwrap();
    assert_eq!(common::diff(&before, &after, 0).0.differing, 0.0);
}
