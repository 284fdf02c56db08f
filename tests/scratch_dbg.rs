mod common;
use skytune::render::plan::strategy::RunJoining;
use skytune::render::{Camera, FillStrategy, RenderOptions};
use skytune::sky::builtin::default_sky;
use skytune::sky::resolved::{SkyModel, SkyModelKind};
use skytune::sky::FrameInput;
#[test]
fn dbg() {
    let sky = default_sky();
    let mut lut = FrameInput::new(17.0, 0.5);
    lut.sky_model = Some(SkyModel { kind: SkyModelKind::Lut, ..sky.model });
    let camera = Camera { yaw_deg: 250.0, pitch_deg: 15.0, ..Camera::default() };
    let mut h = common::headless(640, 360);
    h.set_sky(&sky).unwrap();
    for (n, base) in [("dr", FillStrategy::software()), ("hdr", FillStrategy::software().with_hdr())] {
        let joined = RenderOptions { glare: false, strategy: base, ..Default::default() };
        let apart = RenderOptions { strategy: FillStrategy { runs: RunJoining::Separate, ..joined.strategy }, ..joined };
        let one = h.render(&sky, &lut, &camera, &joined).unwrap();
        eprintln!("{n} {:?}", h.renderer.stats);
        let two = h.render(&sky, &lut, &camera, &apart).unwrap();
        let (d, img) = common::diff(&one, &two, 2);
        eprintln!("{n} {d:?}");
        one.save(format!("/tmp/j_{n}_one.png")).unwrap();
        two.save(format!("/tmp/j_{n}_two.png")).unwrap();
        img.save(format!("/tmp/j_{n}_diff.png")).unwrap();
    }
}
