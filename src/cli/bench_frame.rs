//! `skytune bench frame`: whole frames of every sky against the adapter's fill-rate floor (one
//! full-screen triangle sampling one 128 x 128 texture into the same target), measured side by
//! side: floor and sky frames alternate, so a noisy machine's drifts hit both alike. Also the
//! per-object cost (each object left out in turn), the CPU cost of evaluating a sky of 50 objects,
//! and the latency from a file write to the first frame showing it.

mod report;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::{anyhow, Context as _};

use crate::cli::{self, FrameBenchArgs};
use skytune::files::hot_reload::{LiveSky, ReloadEvent, SkySpec};
use skytune::render::passes::baseline::Baseline;
use skytune::render::plan::strategy::PRESETS;
use skytune::render::{AdapterChoice, Camera, FillStrategy, GpuContext, Headless, RenderOptions, ShaderLibrary, OFFSCREEN_FORMAT};
use skytune::sky::builtin::default_sky;
use skytune::sky::resolved::SkyModelKind;
use skytune::sky::{FrameInput, Sky};

/// The middle value (the upper of the two for an even count; NaN for none).
pub(crate) fn median(v: &[f64]) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    s[s.len() / 2]
}

/// (hour, weather) pairs measured for every sky: noon, dusk, night, storm.
const TIMES: [(f32, f32); 4] = [(12.0, 0.0), (18.5, 0.3), (23.0, 0.0), (15.0, 1.0)];

/// One measured case.
struct Case {
    sky: String,
    /// The skydome's colour source (`[sky_model] kind`).
    model: SkyModelKind,
    /// The fill strategy's preset.
    strategy: &'static str,
    hour: f32,
    weather: f32,
    view: &'static str,
    /// The frame with the sun still (the same frame again), ms.
    sky_ms: f64,
    /// The frame with the sun moving every frame (a time-lapse: 0.02 h a frame), ms.
    moving_ms: f64,
    /// Every measured frame of `sky_ms` and `moving_ms` in the order measured, ms: frame `i` of
    /// a physical case was measured beside frame `i` of its painted twin.
    samples: [Vec<f64>; 2],
    floor_ms: f64,
    /// The same frame with the main-scene stand-in drawn (terrain and buildings in front of the
    /// sky at the horizon), ms.
    with_scene_ms: f64,
    phases: Vec<(&'static str, f64)>,
}

/// The renderers and options of one strategy.
struct Measured {
    name: &'static str,
    options: RenderOptions,
    with_scene: RenderOptions,
    /// Timed frames (no timestamps recorded).
    plain: Headless,
    /// Timed frames with the sun moving: a renderer of its own, so that `plain` keeps its map.
    moving: Headless,
    /// The same frames, recording timestamps for the phase columns.
    timing: Headless,
}

/// The frame times of one case and strategy, ms, and the phases' GPU times.
#[derive(Default)]
struct Samples {
    floor_ms: Vec<f64>,
    sky_ms: Vec<f64>,
    moving_ms: Vec<f64>,
    scene_ms: Vec<f64>,
    phases: Vec<Vec<(&'static str, f32)>>,
}

/// Wall time of one frame recorded by `record`, submitted and waited for, ms.
pub(crate) fn timed(ctx: &GpuContext, record: impl FnOnce(&mut wgpu::CommandEncoder)) -> anyhow::Result<f64> {
    let t = Instant::now();
    let mut encoder = ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("BenchFrame::encoder") });
    record(&mut encoder);
    ctx.queue.submit([encoder.finish()]);
    ctx.wait_idle()?;
    Ok(t.elapsed().as_secs_f64() * 1000.0)
}

/// After a frame timed by [`timed`]: its GPU timestamps read back, so that the renderer's phase
/// times are this frame's (not the one before, of another case or options) and the next frame
/// records its own.
pub(crate) fn settle(ctx: &GpuContext, hl: &mut Headless) -> anyhow::Result<()> {
    hl.renderer.after_submit();
    ctx.wait_idle()?;
    hl.renderer.collect_gpu_timings();
    Ok(())
}

/// The skies: the built-in one and every `DIR/*/sky.toml`.
fn skies(dir: &Path) -> anyhow::Result<Vec<(String, Sky)>> {
    let mut out = vec![("built-in".to_string(), default_sky())];
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir).map(|d| d.filter_map(|e| e.ok()).map(|e| e.path().join("sky.toml")).filter(|p| p.is_file()).collect()).unwrap_or_default();
    files.sort();
    for f in files {
        let sky = skytune::sky::load_sky_file(&f).map_err(|e| anyhow!("{e}"))?;
        let name = f.parent().and_then(|p| p.file_name()).map_or_else(|| f.display().to_string(), |n| n.to_string_lossy().into_owned());
        out.push((name, sky));
    }
    Ok(out)
}

pub fn run(args: &FrameBenchArgs) -> anyhow::Result<()> {
    let (w, h) = if args.quick { (160, 90) } else { cli::parse_size(&args.size)? };
    let frames = if args.quick { 2 } else { args.frames.max(1) };
    let ctx = GpuContext::headless(if args.cpu { AdapterChoice::Cpu } else { AdapterChoice::from_env() })?;
    let adapter = ctx.adapter_line();
    println!("adapter: {adapter}");
    // Each preset `--strategy` names (software and plain without it) measured side by side in
    // every case; the adapter's own is the one the summary line is about.
    let strategies: Vec<(&'static str, FillStrategy)> = if args.strategy.is_empty() {
        PRESETS.iter().copied().filter(|(n, _)| ["software", "plain"].contains(n)).collect()
    } else {
        args.strategy.iter().map(|s| (s.name(), *s)).collect()
    };
    let adapter_strategy = FillStrategy::resolve(None, ctx.adapter.get_info().device_type).name();
    let summarised = strategies.iter().find(|(n, _)| *n == adapter_strategy).unwrap_or(&strategies[0]).0;
    // The timed frames come from renderers that record no timestamps (they cost lavapipe about
    // 3% of a sky frame, and the floor records none); `timing` renders the same frames for the
    // phase columns. One pair of renderers per strategy: each keeps its own buffers.
    let untimed = ctx.without_timestamps();
    let floor = Baseline::new(&ctx.device, &ctx.queue, &ShaderLibrary::embedded(), OFFSCREEN_FORMAT)?;
    let skies = with_models(skies(&args.skies)?, &args.sky_models);
    let views: [(&str, Camera); 2] =
        [("horizon", Camera { yaw_deg: 180.0, pitch_deg: 10.0, ..Camera::default() }), ("zenith", Camera::preset("zenith").ok_or_else(|| anyhow!("no zenith view"))?)];
    // The sky alone, filling the frame (what the goal is about); the frame with the main-scene
    // stand-in is measured beside it, for reference. One set of renderers per twin (a sky and its
    // copies with other models), so that the twins' frames alternate and keep their maps.
    let twins = skies.iter().map(|(_, t)| t.len()).max().unwrap_or(1);
    let mut measured: Vec<Vec<Measured>> = (0..twins)
        .map(|_| {
            strategies
                .iter()
                .map(|&(name, strategy)| {
                    let mut strategy = strategy;
                    if let Some(r) = args.dome_resolution {
                        strategy.dome_resolution = r;
                    }
                    let options = RenderOptions { scene: false, strategy, ..Default::default() };
                    Ok(Measured {
                        name,
                        options,
                        with_scene: RenderOptions { scene: true, ..options },
                        plain: Headless::new(untimed.clone(), w, h)?,
                        moving: Headless::new(untimed.clone(), w, h)?,
                        timing: Headless::new(ctx.clone(), w, h)?,
                    })
                })
                .collect::<anyhow::Result<Vec<_>>>()
        })
        .collect::<anyhow::Result<_>>()?;

    let cases = measure_cases(&ctx, &floor, (&skies, &views), &mut measured, frames)?;
    // Per strategy, over the painted (bitmap) cases: worst and median ratio, and each case's
    // frame against the summarised strategy's.
    let per_strategy: Vec<(&str, f64, f64, f64)> = measured[0]
        .iter()
        .map(|m| {
            let painted = || cases.iter().filter(|c| c.strategy == m.name && !c.model.is_physical());
            let r: Vec<f64> = painted().map(|c| c.sky_ms / c.floor_ms).collect();
            let against: Vec<f64> =
                painted().filter_map(|c| cases.iter().find(|o| o.strategy == summarised && o.model == c.model && o.same_view(c)).map(|o| c.sky_ms / o.sky_ms)).collect();
            (m.name, r.iter().copied().fold(0.0, f64::max), median(&r), median(&against))
        })
        .collect();
    let all_cases = cases;
    let physical = physical_ratios(&all_cases, summarised);
    let cases: Vec<&Case> = all_cases.iter().filter(|c| c.strategy == summarised && !c.model.is_physical()).collect();
    let (_, worst, med, _) = per_strategy.iter().copied().find(|s| s.0 == summarised).ok_or_else(|| anyhow!("no cases of {summarised}"))?;
    let Measured { mut plain, timing: mut hl, options, .. } =
        measured.swap_remove(0).into_iter().find(|m| m.name == summarised).ok_or_else(|| anyhow!("no renderer for {summarised}"))?;
    let scene_ratios: Vec<f64> = cases.iter().map(|c| c.with_scene_ms / c.floor_ms).collect();
    let (scene_worst, scene_med) = (scene_ratios.iter().copied().fold(0.0, f64::max), median(&scene_ratios));
    let stand_in_ms = median(&cases.iter().filter(|c| c.view == "horizon").map(|c| c.with_scene_ms - c.sky_ms).collect::<Vec<_>>());

    // Per object: the built-in sky at dusk, horizon view, each object left out in turn; and the
    // same for each of its copies with another skydome colour source (`--sky-models`), so that a
    // physical sky's costs read beside the painted one's.
    let mut per_object = Vec::new();
    for sky in skies.first().map_or(&[][..], |(_, t)| t) {
        let costs = per_object_costs(&ctx, sky, (&mut plain, Headless::new(untimed.clone(), w, h)?), (&options, &views[0].1), frames)?;
        per_object.push((sky.model.kind, costs));
    }

    // CPU: evaluating a sky of 50 objects.
    let (eval_us, objects) = evaluation_cost(if args.quick { 200 } else { 2000 })?;
    // Reload latency: a file written to the first frame that shows it.
    let latency = reload_latency(&mut hl, if args.quick { 2 } else { 7 })?;
    let shader_ms = shader_latency(&ctx, (w, h), if args.quick { 1 } else { 5 })?;
    // Particles: the CPU's closed-form evaluation plus its upload against the same as a compute pass.
    let particles = particle_costs(&ctx, if args.quick { 3 } else { 15 }, if args.quick { &[1_000, 3_000, 10_000][..] } else { &[1_000, 3_000, 10_000, 100_000][..] })?;

    let report = report::FrameReport {
        adapter,
        size: (w, h),
        frames,
        dome_resolution: args.dome_resolution,
        strategies: strategies.iter().map(|(n, _)| *n).collect(),
        adapter_strategy,
        summarised,
        stand_in_ms,
        fill: (worst, med),
        scene: (scene_worst, scene_med),
        physical,
        per_strategy,
        cases: all_cases,
        per_object,
        evaluation: (eval_us, objects),
        particles,
        latency: (latency.0, latency.1, shader_ms),
    };
    skytune::support::safe_write::write_atomic(&args.out, report.markdown().as_bytes())?;
    report.print_summary(&args.out);
    Ok(())
}

/// Time between the frames of the sun-moving measurement, game hours (about 0.3 degrees of sun on
/// a 24-hour day): every frame's sun differs, so every frame updates what follows the sun.
const SUN_STEP_HOURS: f32 = 0.02;

impl Case {
    /// Whether `other` is the same sky, moment and view (the model and strategy aside).
    fn same_view(&self, other: &Case) -> bool {
        (&self.sky, self.hour, self.weather, self.view) == (&other.sky, other.hour, other.weather, other.view)
    }

    /// A physical case's frames against its painted twin's among `cases` (same sky, strategy,
    /// moment and view), frame by frame: the sun still and moving; `None` for a painted case or
    /// one without a twin.
    fn against_twin(&self, cases: &[Case]) -> Option<[f64; 2]> {
        if !self.model.is_physical() {
            return None;
        }
        let twin = cases.iter().find(|o| o.strategy == self.strategy && !o.model.is_physical() && o.same_view(self))?;
        Some([0, 1].map(|k| paired_ratio(&self.samples[k], &twin.samples[k])))
    }
}

/// The views of every case: towards the horizon and the zenith.
type Views = [(&'static str, Camera); 2];

/// Every sky's cases for every twin (the sky and its copies with other models) and strategy:
/// each moment and view, frames of the sky alone, of the sky with the scene stand-in, with the sun
/// moving and of the floor alternating, the twins' frames in turn, and the phases' GPU times from
/// the timing renderer. `measured` holds a set of renderers per twin.
fn measure_cases(ctx: &GpuContext, floor: &Baseline, (skies, views): (&[(String, Vec<Sky>)], &Views), measured: &mut [Vec<Measured>], frames: u32) -> anyhow::Result<Vec<Case>> {
    let mut cases = Vec::new();
    for (name, twins) in skies {
        for (sky, set) in twins.iter().zip(measured.iter_mut()) {
            for m in set.iter_mut() {
                m.plain.set_sky(sky)?;
                m.moving.set_sky(sky)?;
                m.timing.set_sky(sky)?;
                if sky.model.kind == SkyModelKind::Precomputed {
                    // Its tables are built over frames: waited for, untimed, by a still on each renderer.
                    let still = FrameInput::new(12.0, 0.0);
                    for hl in [&mut m.plain, &mut m.moving, &mut m.timing] {
                        hl.render(sky, &still, &views[0].1, &m.options)?;
                    }
                }
            }
        }
        for (hour, weather) in TIMES {
            for (view, camera) in views {
                let input = FrameInput::new(hour, weather);
                // Each twin's still frame, the same for every measured frame.
                let stills: Vec<_> = twins.iter().map(|sky| sky.evaluate(&input)).collect();
                let mut samples: Vec<Vec<Samples>> = twins.iter().map(|_| measured[0].iter().map(|_| Samples::default()).collect()).collect();
                for i in 0..frames + 2 {
                    let moved_input = FrameInput::new(hour + SUN_STEP_HOURS * (i + 1) as f32, weather);
                    for (((sky, frame), set), samples) in twins.iter().zip(&stills).zip(measured.iter_mut()).zip(&mut samples) {
                        let moved = sky.evaluate(&moved_input);
                        for (m, samples) in set.iter_mut().zip(samples) {
                            let target = m.moving.target.target();
                            let moving = timed(ctx, |e| m.moving.renderer.render(ctx, e, &target, &moved, camera, &m.options))?;
                            m.moving.renderer.after_submit();
                            let target = m.plain.target.target();
                            let f = timed(ctx, |e| floor.record(e, target.color))?;
                            let with = timed(ctx, |e| m.plain.renderer.render(ctx, e, &target, frame, camera, &m.with_scene))?;
                            m.plain.renderer.after_submit();
                            let s = timed(ctx, |e| m.plain.renderer.render(ctx, e, &target, frame, camera, &m.options))?;
                            m.plain.renderer.after_submit();
                            let target = m.timing.target.target();
                            timed(ctx, |e| m.timing.renderer.render(ctx, e, &target, frame, camera, &m.options))?;
                            settle(ctx, &mut m.timing)?;
                            if i >= 2 {
                                samples.floor_ms.push(f);
                                samples.sky_ms.push(s);
                                samples.moving_ms.push(moving);
                                samples.scene_ms.push(with);
                                samples.phases.push(m.timing.renderer.gpu_pass_ms().to_vec());
                            }
                        }
                    }
                }
                for ((sky, set), samples) in twins.iter().zip(measured.iter()).zip(samples) {
                    for (m, samples) in set.iter().zip(samples) {
                        let case = Case::of(samples, (name, sky.model.kind, m.name), (hour, weather, view));
                        println!(
                            "{:<10} {:<11} {:<8} {:>5.1} h weather {:.1} {:<7}: frame {:>8.2} ms (sun moving {:>8.2}), floor {:>6.2} ms, ratio {:>5.1} (with the scene {:>6.2} ms, {:.1})",
                            case.sky,
                            case.model.name(),
                            case.strategy,
                            hour,
                            weather,
                            view,
                            case.sky_ms,
                            case.moving_ms,
                            case.floor_ms,
                            case.sky_ms / case.floor_ms,
                            case.with_scene_ms,
                            case.with_scene_ms / case.floor_ms
                        );
                        cases.push(case);
                    }
                }
            }
        }
    }
    Ok(cases)
}

impl Case {
    /// The case of `samples`: the frames of one sky (`name`, its model, the strategy's preset) at
    /// one moment and view.
    fn of(samples: Samples, (name, model, strategy): (&str, SkyModelKind, &'static str), (hour, weather, view): (f32, f32, &'static str)) -> Case {
        let phases = &samples.phases;
        let names: Vec<&'static str> = phases.first().map(|p| p.iter().map(|(n, _)| *n).collect()).unwrap_or_default();
        let phase_medians =
            names.iter().map(|n| (*n, median(&phases.iter().filter_map(|p| p.iter().find(|(m, _)| m == n).map(|(_, ms)| *ms as f64)).collect::<Vec<_>>()))).collect();
        Case {
            sky: name.to_string(),
            model,
            strategy,
            hour,
            weather,
            view,
            sky_ms: median(&samples.sky_ms),
            moving_ms: median(&samples.moving_ms),
            floor_ms: median(&samples.floor_ms),
            with_scene_ms: median(&samples.scene_ms),
            phases: phase_medians,
            samples: [samples.sky_ms, samples.moving_ms],
        }
    }
}

/// Each object's cost (name, ms), the frame with no object and the median frame with every object.
pub type ObjectCosts = (Vec<(String, f64)>, f64, f64);

/// What each object of the built-in sky costs at dusk, looking at the horizon: frames with every
/// object against frames with that one left out, in pairs; returns each object's cost (ms), the
/// frame with no object and the median frame with every object.
fn per_object_costs(
    ctx: &GpuContext,
    builtin: &Sky,
    (plain, mut other): (&mut Headless, Headless),
    (options, camera): (&RenderOptions, &Camera),
    frames: u32,
) -> anyhow::Result<ObjectCosts> {
    plain.set_sky(builtin)?;
    let dusk = FrameInput::new(18.5, 0.3);
    let camera = *camera;
    // Frames with every object and without those left out alternate, and an object's cost is the
    // median of the pairs' differences: a drifting machine moves both frames of a pair alike. The
    // frames without it come from a second renderer: one renderer alternating between two sets of
    // objects made frames slower by about 0.8 ms whatever was left out (an object outside the
    // frame, which draws nothing, showed that much), which is not what either frame costs alone.
    other.set_sky(builtin)?;
    // A still on each first: a physical model's map (and `precomputed`'s tables) ready, untimed.
    for hl in [&mut *plain, &mut other] {
        hl.render(builtin, &dusk, &camera, options)?;
    }
    let every = builtin.evaluate(&dusk);
    let mut paired = |hl: &mut Headless, input: &FrameInput| -> anyhow::Result<(f64, f64, f64)> {
        let frame = builtin.evaluate(input);
        let (mut with, mut without, mut differences) = (Vec::new(), Vec::new(), Vec::new());
        for i in 0..frames + 2 {
            let target = hl.target.target();
            let a = timed(ctx, |e| hl.renderer.render(ctx, e, &target, &every, &camera, options))?;
            hl.renderer.after_submit();
            let target = other.target.target();
            let b = timed(ctx, |e| other.renderer.render(ctx, e, &target, &frame, &camera, options))?;
            other.renderer.after_submit();
            if i >= 2 {
                with.push(a);
                without.push(b);
                differences.push(a - b);
            }
        }
        Ok((median(&with), median(&without), median(&differences)))
    };
    let mut per_object = Vec::new();
    let mut with_all = Vec::new();
    for o in &builtin.objects {
        let (with, _, cost) = paired(plain, &FrameInput { disabled: vec![o.name.clone()], ..dusk.clone() })?;
        with_all.push(with);
        per_object.push((o.name.clone(), cost));
    }
    let (with, nothing, _) = paired(plain, &FrameInput { disabled: builtin.objects.iter().map(|o| o.name.clone()).collect(), ..dusk.clone() })?;
    with_all.push(with);
    let all = median(&with_all);
    Ok((per_object, nothing, all))
}

/// `skies`, each with copies of itself with each of `models` as its skydome's colour source,
/// after it (its own model is not repeated): the twins measured side by side.
fn with_models(skies: Vec<(String, Sky)>, models: &[SkyModelKind]) -> Vec<(String, Vec<Sky>)> {
    skies
        .into_iter()
        .map(|(name, sky)| {
            let copies = models.iter().filter(|k| **k != sky.model.kind).map(|k| {
                let mut copy = sky.clone();
                copy.model.kind = *k;
                if *k == SkyModelKind::Precomputed {
                    // A frame's cost does not depend on the tables' size, their build does: the
                    // default tables take 80 s to build on lavapipe, these a few seconds.
                    copy.model.settings.precomputed = skytune::atmosphere::PrecomputedSettings::SMALL;
                }
                copy
            });
            let twins = std::iter::once(sky.clone()).chain(copies).collect();
            (name, twins)
        })
        .collect()
}

/// Physical-model frames against the same sky's painted (bitmap) frame, case by case: each case's
/// ratio is the median over its frames of each frame against its twin's, measured beside it.
struct PhysicalRatios {
    /// Worst and median, the sun still.
    still: (f64, f64),
    /// Worst and median, the sun moving every frame.
    moving: (f64, f64),
    /// Worst and median of the physical frames against the floor, the sun still.
    floor: (f64, f64),
    /// Physical cases with a painted twin.
    count: usize,
}

impl PhysicalRatios {
    /// A line for the report.
    fn describe(&self, strategy: &str) -> String {
        format!(
            "**physical_ratio worst={:.2} median={:.2}** (`{strategy}` strategy; {} physical cases, each against the same sky, moment and view drawn with its bitmaps, their frames alternating; goal: 1.3) and with the sun moving every frame worst={:.2} median={:.2} (goal: 1.6); against the floor worst={:.1} median={:.1}",
            self.still.0, self.still.1, self.count, self.moving.0, self.moving.1, self.floor.0, self.floor.1,
        )
    }
}

/// Median over the frames of `physical` against `painted`, frame by frame (the twins' frames
/// were measured in turn).
fn paired_ratio(physical: &[f64], painted: &[f64]) -> f64 {
    median(&physical.iter().zip(painted).map(|(p, b)| p / b).collect::<Vec<_>>())
}

/// The physical cases of `strategy` against their painted twins; `None` when there are none.
fn physical_ratios(cases: &[Case], strategy: &str) -> Option<PhysicalRatios> {
    let pairs: Vec<(&Case, [f64; 2])> = cases.iter().filter(|c| c.strategy == strategy).filter_map(|c| c.against_twin(cases).map(|r| (c, r))).collect();
    if pairs.is_empty() {
        return None;
    }
    let worst_median = |v: Vec<f64>| (v.iter().copied().fold(0.0, f64::max), median(&v));
    let [still, moving] = [0, 1].map(|k| worst_median(pairs.iter().map(|(_, r)| r[k]).collect()));
    Some(PhysicalRatios { still, moving, floor: worst_median(pairs.iter().map(|(p, _)| p.sky_ms / p.floor_ms).collect()), count: pairs.len() })
}

/// Median CPU time of `Sky::evaluate` for a sky of 50 objects, microseconds, and the object count.
fn evaluation_cost(runs: u32) -> anyhow::Result<(f64, usize)> {
    let dir = std::env::temp_dir().join(format!("skytune-bench-eval-{}", std::process::id()));
    let palette = skytune::sky::procedural::preset("default").ok_or_else(|| anyhow!("no default preset"))?;
    let file = skytune::sky::builtin::write_sky_folder(&dir, palette, 7)?;
    let base = skytune::sky::load_sky_file(&file).map_err(|e| anyhow!("{e}"))?;
    let mut text = std::fs::read_to_string(&file)?;
    for i in base.objects.len()..50 {
        let path = ["sun", "moon", "small_moon", "planet"][i % 4];
        let _ = write!(
            text,
            "\n[[object]]\nname = \"extra_{i}\"\npriority = 30\npath = \"{path}\"\n[object.standard]\nshape = {{ kind = \"billboard\", size_deg = 2 }}\nblend = \"additive\"\ndiffuse = {{ mode = \"bitmap\", bitmap = \"sun_color.png\" }}\nref_color = \"diffuse\"\n[[object.standard.stage]]\ntexture = \"sun.png\"\n"
        );
    }
    std::fs::write(&file, text)?;
    let mut sky = skytune::sky::load_sky_file(&file).map_err(|e| anyhow!("{e}"))?;
    let _ = std::fs::remove_dir_all(&dir);
    // The objects' evaluation; the particles are measured on their own (`particle_costs`).
    sky.emitters.clear();
    let mut times = Vec::new();
    for i in 0..runs {
        let input = FrameInput::new((i as f32 * 0.37) % 24.0, (i as f32 * 0.13) % 1.0);
        let t = Instant::now();
        let frame = sky.evaluate(&input);
        times.push(t.elapsed().as_secs_f64() * 1e6);
        std::hint::black_box(frame);
    }
    Ok((median(&times), sky.objects.len()))
}

/// One row of the particle comparison.
struct ParticleCost {
    cap: u32,
    runs: u32,
    cpu_alive: usize,
    gpu_alive: u32,
    cpu_ms: f64,
    gpu_ms: f64,
}

/// The built-in rain emitter at each cap, simulated on the CPU (plus upload) and on the GPU.
fn particle_costs(ctx: &GpuContext, runs: u32, caps: &[u32]) -> anyhow::Result<Vec<ParticleCost>> {
    use skytune::sky::particle_sim::simulate;
    use skytune::sky::particles::ParticleClock;
    let mut out = Vec::new();
    for &cap in caps {
        let mut sky = default_sky();
        let mut e = sky.emitters.iter().find(|e| e.name == "rain").cloned().ok_or_else(|| anyhow!("the built-in sky has no rain emitter"))?;
        e.kind = skytune::sky::model::EmitterKind::Particles;
        e.emission = skytune::sky::resolved::Color { mode: skytune::sky::resolved::ColorMode::Unused, bitmap: None, value: [1.0; 4] };
        e.max_particles = cap;
        e.lifetime_spread = 0.0;
        e.rate = cap as f32 / e.lifetime_s;
        sky.emitters = vec![e.clone()];
        let mut gpu = skytune::render::passes::particle_sim::StandaloneSim::new(ctx, &ShaderLibrary::embedded(), cap)?;
        let upload = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("BenchFrame::particle_upload"),
            size: cap as u64 * 64,
            usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let (mut cpu_ms, mut gpu_ms, mut cpu_alive, mut gpu_alive) = (Vec::new(), Vec::new(), 0, 0);
        for i in 0..runs + 1 {
            let time_s = 100.0 + i as f64 * 0.37;
            let input = |gpu_particles: bool| FrameInput { particle_clock: Some(ParticleClock { time_s, hours_per_s: 0.0 }), gpu_particles, ..FrameInput::new(12.0, 0.0) };
            let mut frame = sky.evaluate(&FrameInput { particle_clock: Some(ParticleClock { time_s: -1e6, hours_per_s: 0.0 }), ..input(false) });
            let t = Instant::now();
            frame.particles = simulate(&sky, &input(false), &frame);
            let instances = frame.particles.emitters.first().map_or(&[][..], |f| &f.instances[..]);
            ctx.queue.write_buffer(&upload, 0, bytemuck::cast_slice(instances));
            ctx.queue.submit([]);
            ctx.wait_idle()?;
            let cpu = t.elapsed().as_secs_f64() * 1000.0;
            // The GPU path: the CPU hands over the birth conditions, the compute pass evaluates.
            let t = Instant::now();
            let births = simulate(&sky, &input(true), &frame).emitters.first().and_then(|f| f.gpu.clone()).unwrap_or_default();
            gpu.sim.prepare(&ctx.queue, &e, &births);
            let _ = timed(ctx, |enc| gpu.record(enc))?;
            let g = t.elapsed().as_secs_f64() * 1000.0;
            if i > 0 {
                cpu_ms.push(cpu);
                gpu_ms.push(g);
                cpu_alive = instances.len();
                gpu_alive = gpu.read(ctx)?.iter().filter(|p| p.position[3] > 0.0).count() as u32;
            }
        }
        out.push(ParticleCost { cap, runs, cpu_alive, gpu_alive, cpu_ms: median(&cpu_ms), gpu_ms: median(&gpu_ms) });
    }
    Ok(out)
}

/// Latencies (ms) of sky-file edits and bitmap edits: write, then poll and render a frame per
/// loop as the window does, until the frame shows the change.
fn reload_latency(hl: &mut Headless, edits: u32) -> anyhow::Result<(Vec<f64>, Vec<f64>)> {
    let dir = std::env::temp_dir().join(format!("skytune-bench-reload-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let palette = skytune::sky::procedural::preset("default").ok_or_else(|| anyhow!("no default preset"))?;
    let file = skytune::sky::builtin::write_sky_folder(&dir, palette, 7)?;
    let mut live = LiveSky::new(SkySpec::File(file.clone())).map_err(|e| anyhow!("{e}"))?;
    hl.set_sky(live.sky())?;
    let text = std::fs::read_to_string(&file)?;
    let camera = Camera::default();
    let options = RenderOptions { glare: false, ..Default::default() };
    let frame_until = |live: &mut LiveSky, hl: &mut Headless, started: Instant| -> anyhow::Result<f64> {
        loop {
            anyhow::ensure!(started.elapsed() < Duration::from_secs(30), "no reload within 30 s");
            if let Some(ReloadEvent::Reloaded) = live.poll() {
                hl.set_sky(live.sky())?;
                hl.frame(live.sky(), &FrameInput::new(12.0, 0.0), &camera, &options, 0.0);
                hl.ctx.wait_idle()?;
                return Ok(started.elapsed().as_secs_f64() * 1000.0);
            }
            hl.frame(live.sky(), &FrameInput::new(12.0, 0.0), &camera, &options, 0.0);
            hl.ctx.wait_idle()?;
        }
    };
    let (mut sky_ms, mut bitmap_ms) = (Vec::new(), Vec::new());
    for k in 0..edits {
        // Let the previous edit's events pass.
        std::thread::sleep(Duration::from_millis(400));
        while live.poll().is_some() {}
        std::fs::write(&file, text.replacen("name = \"", &format!("name = \"edit {k} "), 1)).context("writing the sky file")?;
        sky_ms.push(frame_until(&mut live, hl, Instant::now())?);
        std::thread::sleep(Duration::from_millis(400));
        while live.poll().is_some() {}
        let fog = image::RgbaImage::from_pixel(24, 3, image::Rgba([(k * 30 % 255) as u8, 40, 90, 255]));
        fog.save(dir.join("fog.png")).context("writing the bitmap")?;
        bitmap_ms.push(frame_until(&mut live, hl, Instant::now())?);
    }
    let _ = std::fs::remove_dir_all(&dir);
    Ok((sky_ms, bitmap_ms))
}

/// Latencies (ms) of shader edits: a file of a hot-reloaded shader folder written, to the first
/// frame rendered with the rebuilt pipelines (watcher, debounce, every pipeline rebuilt).
fn shader_latency(ctx: &GpuContext, (w, h): (u32, u32), edits: u32) -> anyhow::Result<Vec<f64>> {
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::Arc;
    let dir = std::env::temp_dir().join(format!("skytune-bench-shaders-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    ShaderLibrary::export_embedded(&dir).context("writing the shaders")?;
    let mut hl = Headless::with_library(ctx.clone(), ShaderLibrary { dir: Some(dir.clone()) }, w, h)?;
    let sky = default_sky();
    hl.set_sky(&sky)?;
    let changed = Arc::new(AtomicBool::new(false));
    let flag = changed.clone();
    let mut watcher = skytune::files::watch::FileWatcher::new(move |paths| {
        if paths.iter().any(|p| p.extension().is_some_and(|x| x == "wgsl")) {
            flag.store(true, Ordering::Release);
        }
    })?;
    watcher.set_dirs([dir.clone()].into_iter().collect());
    let file = dir.join("sky_objects.wgsl");
    let original = std::fs::read_to_string(&file)?;
    let camera = Camera::default();
    let options = RenderOptions { glare: false, ..Default::default() };
    let mut out = Vec::new();
    for k in 0..edits {
        std::thread::sleep(Duration::from_millis(400));
        changed.store(false, Ordering::Release);
        std::fs::write(&file, format!("{original}\n// edit {k}\n")).context("writing the shader")?;
        let started = Instant::now();
        loop {
            anyhow::ensure!(started.elapsed() < Duration::from_secs(60), "no shader reload within 60 s");
            if changed.swap(false, Ordering::AcqRel) {
                hl.renderer.reload_shaders(&hl.ctx)?;
                hl.frame(&sky, &FrameInput::new(12.0, 0.0), &camera, &options, 0.0);
                hl.ctx.wait_idle()?;
                out.push(started.elapsed().as_secs_f64() * 1000.0);
                break;
            }
            hl.frame(&sky, &FrameInput::new(12.0, 0.0), &camera, &options, 0.0);
            hl.ctx.wait_idle()?;
        }
    }
    drop(watcher);
    let _ = std::fs::remove_dir_all(&dir);
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn case(model: SkyModelKind, hour: f32, sky_ms: f64, moving_ms: f64) -> Case {
        Case {
            sky: "desert".into(),
            model,
            strategy: "software",
            hour,
            weather: 0.0,
            view: "horizon",
            sky_ms,
            moving_ms,
            samples: [vec![sky_ms; 3], vec![moving_ms; 3]],
            floor_ms: 2.0,
            with_scene_ms: 0.0,
            phases: Vec::new(),
        }
    }

    #[test]
    fn every_sky_gets_each_model_once_after_its_own() {
        let sky = default_sky();
        let own = sky.model.kind;
        let out = with_models(vec![("a".into(), sky)], &[SkyModelKind::Lut, own, SkyModelKind::Hosek]);
        assert_eq!(out.len(), 1, "one sky");
        let kinds: Vec<SkyModelKind> = out[0].1.iter().map(|s| s.model.kind).collect();
        assert_eq!(kinds, vec![own, SkyModelKind::Lut, SkyModelKind::Hosek]);
        assert_eq!(out[0].0, "a");
    }

    #[test]
    fn physical_cases_are_measured_against_their_painted_twin() {
        let cases = vec![
            case(SkyModelKind::Bitmap, 12.0, 4.0, 4.0),
            case(SkyModelKind::Lut, 12.0, 6.0, 20.0),
            case(SkyModelKind::Bitmap, 18.5, 2.0, 2.0),
            case(SkyModelKind::Hosek, 18.5, 5.0, 5.0),
            // No painted twin at this hour: left out.
            case(SkyModelKind::Lut, 23.0, 100.0, 100.0),
        ];
        let p = physical_ratios(&cases, "software").expect("physical cases");
        assert_eq!(p.count, 2);
        assert_eq!(p.still, (2.5, 2.5), "1.5 and 2.5: the worst, and the upper median of two");
        assert_eq!(p.moving.0, 5.0);
        assert!(physical_ratios(&cases[..1], "software").is_none(), "no physical case, no line");
        assert!(physical_ratios(&cases, "plain").is_none(), "another strategy's cases are not paired");
    }

    #[test]
    fn twins_are_compared_frame_by_frame() {
        // The machine runs at half speed over the last three pairs (and one pair is off).
        let physical = [3.0, 3.0, 6.0, 6.0, 6.0];
        let painted = [2.0, 2.0, 2.0, 4.0, 4.0];
        assert_eq!(paired_ratio(&physical, &painted), 1.5, "the median of the pairs' ratios");
        assert_eq!(median(&physical) / median(&painted), 3.0, "the ratio of the medians mixes the speeds");
    }
}
