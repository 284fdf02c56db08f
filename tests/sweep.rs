//! Stability sweeps: the shipped models give no NaN, infinite, negative or discontinuous radiance
//! across and beyond their domains (a smaller sweep than `skytune sweep`'s 1e5 per model); the raw
//! published fits do fail where the literature says; the jump detector finds steps, not slopes.

use skytune::measure::model_points::Evaluator;
use skytune::measure::stability::{self, SweptModel};
use skytune::render::{AdapterChoice, GpuContext};

#[test]
fn shipped_models_have_zero_counters_and_raw_fits_fail() {
    let ctx = GpuContext::headless(AdapterChoice::Cpu).expect("lavapipe");
    let ev = Evaluator::new(&ctx).expect("probe");
    for model in SweptModel::ALL {
        let count = 10_000;
        let c = stability::sweep(&ev, model, count, 42, skytune::support::shard::Shard::WHOLE, &mut |_| {}).expect("swept");
        assert_eq!(c.evaluated, count as u64);
        if model.shipped() {
            assert_eq!(c.failures(), 0, "{}: {:?}", model.name(), c);
        }
        match model {
            SweptModel::PreethamRaw => assert!(c.negative > 0, "Preetham's fit goes negative below turbidity 1.3 and below the horizon"),
            SweptModel::HosekRaw => assert!(c.refused > 0, "the Hosek-Wilkie data has no sun below the horizon"),
            _ => {}
        }
    }
}

#[test]
fn jump_detector_finds_steps_and_not_steep_slopes() {
    let grey = |x: f64| [x; 3];
    // A step in the middle of the second interval.
    assert!(stability::jump_candidate([grey(1.0), grey(1.0), grey(2.0)]).is_some());
    assert!(stability::refined_is_jump(&[1.0, 1.0, 1.0, 1.0, 1.0, 2.0, 2.0, 2.0, 2.0, 2.0, 2.0]));
    // A steep exponential changes alike over both steps: no candidate.
    let e = |s: f64| grey((s * 8.0).exp());
    assert!(stability::jump_candidate([e(0.0), e(0.05), e(0.1)]).is_none());
    // A kink (flat, then a slope) spreads when refined, even with the kink in the last sub-step:
    // max(0, x) crossing zero there continues into the next sub-step.
    let ramp: Vec<f64> = (0..11).map(|k| k as f64).collect();
    assert!(!stability::refined_is_jump(&ramp));
    let clamp_at_end: Vec<f64> = (0..11).map(|k| (k as f64 - 8.5).max(0.0)).collect();
    assert!(!stability::refined_is_jump(&clamp_at_end));
    // Tiny changes under the floor are never jumps.
    assert!(stability::jump_candidate([grey(0.0), grey(0.0), grey(1e-9)]).is_none());
}

#[test]
fn sweeps_are_reproducible() {
    let a = stability::random_cases(500, 100, 9);
    let b = stability::random_cases(500, 100, 9);
    assert_eq!(a, b);
    assert!(a.iter().any(|c| c.case.camera_km > c.atmosphere.thickness_km()), "cameras above the atmosphere are swept");
    assert!(a.iter().any(|c| c.case.sun_elev_deg < -12.0) && a.iter().any(|c| c.case.view_elev_deg < -30.0));
    assert!(a.iter().any(|c| c.turbidity < 1.3) && a.iter().any(|c| c.turbidity > 10.0));
}
