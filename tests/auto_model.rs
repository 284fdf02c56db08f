//! `kind = "auto"`: the pick meets its budget on every committed sky, measured against the
//! reference at the sky's own hours (not the table sun elevations the pick was made on, and a
//! reference with another seed); a tighter budget never picks a cheaper model; picks are
//! reproducible; the sky file's keys are checked.

use skytune::atmosphere::dome;
use skytune::atmosphere::reference::{Case, Reference, ReferenceSettings};
use skytune::measure::auto_model;
use skytune::measure::model_points::{Evaluator, Method, Prepared};
use skytune::render::{AdapterChoice, GpuContext};
use skytune::sky::resolved::Budget;
use skytune::sky::Sky;

/// One evaluator for the tests of this file, so that `precomputed` tables built for one test's
/// candidates serve the others' (every committed sky has the default atmosphere; a default-size
/// build takes minutes on lavapipe). The tests take turns with it.
fn evaluator() -> std::sync::MutexGuard<'static, Evaluator<'static>> {
    static SHARED: std::sync::OnceLock<std::sync::Mutex<Evaluator<'static>>> = std::sync::OnceLock::new();
    SHARED
        .get_or_init(|| {
            let ctx: &'static GpuContext = Box::leak(Box::new(GpuContext::headless(AdapterChoice::Cpu).expect("lavapipe")));
            std::sync::Mutex::new(Evaluator::new(ctx).expect("probe"))
        })
        .lock()
        // A test that failed holding it leaves a usable evaluator.
        .unwrap_or_else(|e| e.into_inner())
}

fn committed_skies() -> Vec<Sky> {
    let mut skies = vec![skytune::sky::builtin::default_sky()];
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("skies");
    let mut paths: Vec<_> = std::fs::read_dir(&dir).expect("skies/").flatten().map(|e| e.path().join("sky.toml")).filter(|p| p.exists()).collect();
    paths.sort();
    for p in paths {
        skies.push(skytune::sky::load_sky_file(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display())));
    }
    skies
}

#[test]
fn auto_pick_meets_its_budget_against_the_reference_on_every_committed_sky() {
    let ev = evaluator();
    let budget = Budget { de2000: 2.0 };
    // An independent check: 4 x 6 directions offset from the benchmark's, another seed, the
    // sky's own sun at hours of its day that are not the table's sun elevations, and enough paths
    // that the reference's own noise (which adds to any error) stays small.
    let dirs = dome::dome_directions(4, 6);
    // Skies that share a sun path and an atmosphere share the reference's answers.
    let mut truths: std::collections::HashMap<String, Vec<[f64; 3]>> = std::collections::HashMap::new();
    for sky in committed_skies() {
        // As the sky loads: only the candidates that decide the pick are measured.
        let (pick, scored) = auto_model::pick(&sky, budget, &ev, &skytune::support::progress::Job::new()).expect("picked");
        assert!(pick.within_budget, "{}: no model within {budget:?}: {scored:?}", sky.name);
        let model = pick.model(&sky.model);
        // Mid-morning, noon, and the sunset's hardest moment: the sun just above the horizon.
        let sunset = (0..960)
            .map(|k| sky.hours_per_day * (0.5 + k as f32 / 1920.0))
            .find(|h| sky.path_at(sky.sun_path, *h).0.y.asin().to_degrees() < 1.0)
            .unwrap_or(sky.hours_per_day * 0.75);
        let hours = [sky.hours_per_day * 0.3, sky.hours_per_day * 0.5, sunset];
        for (w, atm) in auto_model::sky_atmospheres(&sky).iter().enumerate() {
            let reference = Reference::new(*atm, ReferenceSettings { paths: 2048, seed: 0xbeef + w as u64, ..Default::default() });
            let prepared = match pick.chosen.method {
                Method::Preetham | Method::Hosek => Prepared::Analytic(
                    pick.chosen.method,
                    skytune::measure::model_points::Fit { turbidity: model.settings.analytic.turbidity as f64, scale: 1.0, units: model.settings.analytic.units },
                ),
                m => ev.prepare(&m, atm, &[]).expect("prepared"),
            };
            for &hour in &hours {
                let sun = sky.path_at(sky.sun_path, hour).0.y.clamp(-1.0, 1.0).asin().to_degrees() as f64;
                let cases: Vec<Case> = dome::cases(sun, &dirs);
                let truth = truths.entry(format!("{atm:?} {sun:.6}")).or_insert_with(|| cases.iter().map(|c| reference.radiance(c)).collect()).clone();
                let got = ev.radiance(&prepared, atm, sun, &cases).expect("evaluated");
                let e = dome::dome_error(&dirs, &truth, &got);
                eprintln!("{}: {} at hour {hour:.2} (sun {sun:.1} deg): dE2000 {:.2}", sky.name, pick.chosen.id, e.de_mean);
                assert!(e.de_mean <= budget.de2000, "{}: {} at hour {hour} (sun {sun:.1} deg): dE2000 {:.2} over the budget", sky.name, pick.chosen.id, e.de_mean);
            }
        }
    }
}

#[test]
fn tighter_budgets_never_pick_cheaper_models_and_picks_are_reproducible() {
    let ev = evaluator();
    let sky = skytune::sky::builtin::default_sky();
    let scored = auto_model::score(&sky, &ev, &skytune::support::progress::Job::new()).expect("scored");
    assert_eq!(scored, auto_model::score(&sky, &ev, &skytune::support::progress::Job::new()).expect("scored again"), "same inputs, same scores");
    assert!(scored.windows(2).all(|w| w[0].cost_ms <= w[1].cost_ms), "candidates cheapest first");
    let mut last_cost = 0.0;
    for de2000 in [50.0, 20.0, 10.0, 5.0, 3.0, 2.0, 1.5, 1.2, 1.0, 0.5] {
        let pick = auto_model::choose(&scored, Budget { de2000 }, auto_model::sky_suns(&sky));
        if pick.within_budget {
            assert!(pick.chosen.de2000 <= de2000);
            assert!(pick.chosen.cost_ms >= last_cost, "budget {de2000}: {} is cheaper than the looser budget's pick", pick.chosen.id);
            last_cost = pick.chosen.cost_ms;
            // Nothing cheaper was within the budget.
            assert!(scored.iter().filter(|s| s.cost_ms < pick.chosen.cost_ms).all(|s| s.de2000 > de2000));
            if let Some(r) = &pick.runner_up {
                assert!(r.cost_ms >= pick.chosen.cost_ms && r.de2000 <= de2000);
            }
            // The fast rule stops before the candidates past the runner-up and picks the same.
            let empty = auto_model::Scores::empty(scored.iter().map(|s| s.quick).collect());
            let fast = auto_model::measure_in_order(empty, Some(Budget { de2000 }), |n| Ok::<_, ()>(scored[n].clone())).expect("in order");
            assert_eq!(fast.pick(Budget { de2000 }, auto_model::sky_suns(&sky)), Some(pick.clone()), "budget {de2000}");
        } else {
            let best = scored.iter().map(|s| s.de2000).fold(f64::MAX, f64::min);
            assert!(best > de2000 && pick.chosen.de2000 == best, "over budget: the most accurate model");
        }
    }
    // The fast pick on the GPU (the committed skies' atmosphere) against these full scores.
    fast_pick_matches("default", &sky, &scored, &ev);
}

/// `auto_model::pick` on `sky` (candidates measured only until they decide it) against `full`, the
/// full measurement, at the default budget and at a tight and a loose one: the same pick and
/// runner-up, the same scores for what it measured. Returns whether it skipped any candidate.
fn fast_pick_matches(name: &str, sky: &Sky, full: &[auto_model::Scored], ev: &Evaluator<'static>) -> bool {
    let job = skytune::support::progress::Job::new();
    let mut skipped_any = false;
    for de2000 in [skytune::sky::load::DEFAULT_DE2000_BUDGET, 1.0, 4.0] {
        let budget = Budget { de2000 };
        let (fast, scores) = auto_model::pick(sky, budget, ev, &job).expect("fast pick");
        let expected = auto_model::choose(full, budget, auto_model::sky_suns(sky));
        let measured = scores.measured().len();
        eprintln!("{name}, budget {de2000}: {measured} of {} candidates measured; {}", full.len(), fast.describe());
        assert_eq!(fast, expected, "{name}, budget {de2000}: the fast pick differs from the full measurement's");
        for (slot, whole) in scores.slots.iter().zip(full) {
            assert!(slot.as_ref().is_none_or(|s| s == whole), "{name}: {slot:?} is not the full measurement's {whole:?}");
        }
        skipped_any |= measured < full.len();
    }
    skipped_any
}

/// The fast pick is the full measurement's pick (`fast_pick_matches`) on a hazy atmosphere (the
/// benchmark's, four times the aerosols) and a stormy one (twelve times, outside the benchmark:
/// its reference is computed); the committed skies' atmosphere is checked with the scores of
/// `tighter_budgets_never_pick_cheaper_models_and_picks_are_reproducible`.
#[test]
fn the_fast_pick_is_the_full_measurements_pick() {
    let ev = evaluator();
    let job = skytune::support::progress::Job::new();
    let aerosols = |k: f64| {
        let a = skytune::atmosphere::Atmosphere::default();
        skytune::atmosphere::Atmosphere { mie_scattering_per_km: a.mie_scattering_per_km.map(|b| b * k), mie_extinction_per_km: a.mie_extinction_per_km.map(|b| b * k), ..a }
    };
    let mut skipped_any = false;
    for (name, atm) in [("hazy", dome::Haze::Hazy.atmosphere()), ("stormy", aerosols(12.0))] {
        let mut sky = skytune::sky::builtin::default_sky();
        sky.atmosphere = atm;
        sky.atmosphere_by_weather.clear();
        let full = auto_model::score(&sky, &ev, &job).expect("full measurement");
        skipped_any |= fast_pick_matches(name, &sky, &full, &ev);
    }
    assert!(skipped_any, "the fast pick measured every candidate every time");
}

fn load(text: &str) -> Result<Sky, String> {
    let dir = tempfile::tempdir().expect("temp dir");
    skytune::sky::builtin::write_sky_folder(dir.path(), &skytune::sky::procedural::PRESETS[0], 1).expect("written");
    let path = dir.path().join("sky.toml");
    let mut toml = std::fs::read_to_string(&path).expect("read");
    toml.push_str(text);
    std::fs::write(&path, toml).expect("write");
    skytune::sky::load_sky_file(&path).map_err(|e| e.to_string())
}

#[test]
fn sky_file_keys_of_auto() {
    let sky = load("\n[sky_model]\nkind = \"auto\"\nbudget = { de2000 = 3.5 }\n").expect("auto parses");
    assert_eq!(sky.auto_model, Some(Budget { de2000: 3.5 }));
    let default = load("\n[sky_model]\nkind = \"auto\"\n").expect("auto without budget");
    assert_eq!(default.auto_model, Some(Budget { de2000: skytune::sky::load::DEFAULT_DE2000_BUDGET }));
    assert_eq!(load("\n[sky_model]\nkind = \"lut\"\n").expect("lut").auto_model, None);
    let e = load("\n[sky_model]\nkind = \"lut\"\nbudget = { de2000 = 1.0 }\n").expect_err("budget without auto");
    assert!(e.contains("sky_model.budget") && e.contains("auto"), "{e}");
    let e = load("\n[sky_model]\nkind = \"automatic\"\n").expect_err("unknown kind");
    assert!(e.contains("automatic") && e.contains("expected auto"), "{e}");
    let e = load("\n[sky_model]\nkind = \"auto\"\nbudget = { de2000 = -1 }\n").expect_err("negative budget");
    assert!(e.contains("de2000"), "{e}");
}

/// `auto` measures where the sky's camera is: at 5 km, against a reference computed there (the
/// committed one is seen from the ground), so the errors it reports are not the ground's.
#[test]
fn auto_measures_at_the_skys_camera_altitude() {
    let ev = evaluator();
    let ground = skytune::sky::builtin::default_sky();
    assert_eq!(ground.model.ground(), dome::Ground::BENCH, "the default sky is seen from the benchmark's ground: the committed reference serves it");
    let mut high = ground.clone();
    high.model.world.camera_km = 5.0;
    assert_ne!(auto_model::scores_key(&ground), auto_model::scores_key(&high), "the altitude is part of the scores' key");
    let job = skytune::support::progress::Job::new();
    let (low_scores, high_scores) = (auto_model::score(&ground, &ev, &job).expect("scored"), auto_model::score(&high, &ev, &job).expect("scored"));
    for (a, b) in low_scores.iter().zip(&high_scores) {
        eprintln!("{}: dE2000 {:.2} on the ground, {:.2} at 5 km", a.id, a.de2000, b.de2000);
    }
    let moved = low_scores.iter().zip(&high_scores).filter(|(a, b)| (a.de2000 - b.de2000).abs() > 0.05).count();
    assert!(moved * 2 >= low_scores.len(), "at most half the candidates' errors moved with the camera: {low_scores:?} {high_scores:?}");
}
