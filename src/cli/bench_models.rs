//! `skytune bench models`: every sky model at several quality settings, error against the
//! reference over the dome against cost; writes docs/models.md, models.csv, models-by-sun.csv and
//! the charts (models-cost.svg/png, models-by-sun.svg/png).

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use anyhow::Context as _;

use crate::cli::{self, ModelBenchArgs};
use skytune::atmosphere::dome::{self, DomeError, Haze, ReferenceDome, Regime};
use skytune::atmosphere::reference::Case;
use skytune::atmosphere::reference::ReferenceSettings;
use skytune::measure::model_points::{self, ChartRow, Evaluator, FitTarget, Method, Point, Prepared, SunRow};
use skytune::render::passes::baseline::Baseline;
use skytune::render::{AdapterChoice, Camera, GpuContext, Headless, RenderOptions, ShaderLibrary, OFFSCREEN_FORMAT};
use skytune::sky::builtin::default_sky;
use skytune::sky::resolved::{ModelSettings, SkyModel, SkyModelKind};
use skytune::sky::{FrameInput, Sky};
use skytune::support::progress::Reporter;
use skytune::support::shard::Shard;

/// The reference over the benchmark's dome: read from `path`, or computed (minutes) and written.
pub fn reference_dome(path: &Path, settings: ReferenceSettings) -> anyhow::Result<ReferenceDome> {
    match ReferenceDome::load(path, settings, dome::BENCH_DOME) {
        Ok(r) if r.suns.len() == Haze::ALL.len() * dome::SUN_ELEVATIONS_DEG.len() => return Ok(r),
        Ok(_) => log::warn!("{}: incomplete; recomputing", path.display()),
        Err(e) => match dome::committed_reference() {
            // Run from elsewhere than the checkout: the dataset built into the binary.
            Ok(r) if settings == dome::committed_settings() => return Ok(r),
            _ => log::warn!("{e}; computing the reference dome (once, minutes)"),
        },
    }
    let bar = Reporter::new(0, "reference");
    let reference = ReferenceDome::compute(&Haze::ALL, &dome::SUN_ELEVATIONS_DEG, dome::BENCH_DOME, settings, &|done, total| {
        bar.set_length(total as u64);
        bar.set_position(done as u64);
        Ok(())
    })?;
    bar.finish();
    reference.save(path).with_context(|| format!("writing {}", path.display()))?;
    Ok(reference)
}

/// What a kind of draw costs, measured side by side with every other and the fill-rate floor.
#[derive(Debug, Clone, Copy, Default)]
struct DrawCost {
    /// GPU ms of the model's own work (the compute phase) per frame, the sun moving.
    model_moving_ms: f64,
    /// The same with the sun still.
    model_still_ms: f64,
    /// Wall ms of a whole frame of the built-in sky, the sun moving.
    frame_moving_ms: f64,
    /// The same with the sun still.
    frame_still_ms: f64,
    /// Wall ms of the fill-rate floor, alternating with the frames.
    floor_ms: f64,
}

/// How a point's frame is drawn (points drawn alike share one measurement).
#[derive(Debug, Clone, Copy, PartialEq)]
#[allow(clippy::large_enum_variant)] // a handful of values, compared and copied, never stored in bulk
enum Draw {
    /// The model's own sky-view map every frame (the sun moves).
    Model(SkyModel),
    /// A map filled elsewhere (CPU), drawn as it is: a sun-still frame of `single`.
    MapReused,
    /// The NeL gradient bitmaps.
    Bitmap,
}

fn draw_of(method: &Method) -> Draw {
    let with = |kind| SkyModel { kind, ..SkyModel::default() };
    let with_settings = |kind, settings| SkyModel { kind, settings, ..SkyModel::default() };
    let defaults = ModelSettings::default();
    match *method {
        Method::Single(single) => Draw::Model(with_settings(SkyModelKind::Single, ModelSettings { single, ..defaults })),
        Method::Lut(lut) => Draw::Model(with_settings(SkyModelKind::Lut, ModelSettings { lut, ..defaults })),
        // Every table size and order count is looked up alike (16 texels per table and pixel): one
        // measurement per storage precision, with the small tables (quick to build), so that the
        // frames do not rebuild tables between the points; the build itself is the point's
        // `build_ms`.
        Method::Precomputed(s) => Draw::Model(with_settings(
            SkyModelKind::Precomputed,
            ModelSettings { precomputed: skytune::atmosphere::PrecomputedSettings { precision: s.precision, ..skytune::atmosphere::PrecomputedSettings::SMALL }, ..defaults },
        )),
        Method::Preetham => Draw::Model(with(SkyModelKind::Preetham)),
        Method::Hosek => Draw::Model(with(SkyModelKind::Hosek)),
        Method::Linear => Draw::Model(with(SkyModelKind::Linear)),
        Method::Cells(_) | Method::DomeMap(_) | Method::Regression => Draw::MapReused,
        Method::Baked(_) => Draw::Bitmap,
    }
}

fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Each distinct draw's costs, measured side by side in interleaved rounds: the model alone
/// (GPU timestamps of a frame drawing only the skydome: the compute phase is the model's map or
/// tables) and the whole built-in sky (wall time, as `skytune bench frame` measures it, with
/// the floor alternating), each with the sun moving every frame and with it still.
fn measure_draws(ctx: &GpuContext, (w, h): (u32, u32), sky: &Sky, draws: &[Draw], frames: u32) -> anyhow::Result<Vec<DrawCost>> {
    use crate::cli::bench_frame::{settle, timed};
    let camera = Camera { yaw_deg: 180.0, pitch_deg: 40.0, ..Camera::default() };
    // The model alone: the skydome, the object whose gradient stage the models replace.
    let dome = sky.objects.iter().position(|o| o.name == "skydome").context("the built-in sky has no skydome")?;
    let disabled: Vec<String> = sky.objects.iter().enumerate().filter(|(i, _)| *i != dome).map(|(_, o)| o.name.clone()).collect();
    let mut timing = Headless::new(ctx.clone(), w, h)?;
    let mut plain = Headless::new(ctx.without_timestamps(), w, h)?;
    timing.set_sky(sky)?;
    plain.set_sky(sky)?;
    let floor = Baseline::new(&ctx.device, &ctx.queue, &ShaderLibrary::embedded(), OFFSCREEN_FORMAT)?;
    let alone = RenderOptions { glare: false, scene: false, ..Default::default() };
    let whole = RenderOptions { scene: false, ..Default::default() };
    let rounds = 3;
    let per_round = frames.div_ceil(rounds).max(1);
    // Per draw: (model moving, model still, frame moving, frame still, floor) samples.
    let mut samples = vec![[(); 5].map(|_| Vec::new()); draws.len()];
    let mut step = 0u32;
    for _ in 0..rounds {
        for (d, out) in draws.iter().zip(samples.iter_mut()) {
            let model = match d {
                Draw::Model(m) => *m,
                Draw::MapReused => SkyModel { kind: SkyModelKind::Single, ..SkyModel::default() },
                Draw::Bitmap => SkyModel::default(),
            };
            // Tables built over frames (`precomputed` on a software rasteriser) are built before the
            // draw's frames are measured: the renderers share one set of tables, so two
            // `precomputed` draws (single and half precision) rebuild them whenever they alternate.
            let mut input = FrameInput::new(10.0, 0.0);
            input.sky_model = Some(model);
            let frame = sky.evaluate(&input);
            for hl in [&mut plain, &mut timing] {
                loop {
                    {
                        let target = hl.target.target();
                        timed(ctx, |e| hl.renderer.render(ctx, e, &target, &frame, &camera, &whole))?;
                    }
                    settle(ctx, hl)?;
                    if !hl.renderer.busy() {
                        break;
                    }
                }
            }
            for moving in [true, false] {
                for i in 0..per_round + 2 {
                    // A map filled on the CPU is drawn as it is: its sun moves on the CPU.
                    step += 1;
                    let hour = if moving && !matches!(d, Draw::MapReused) { 10.0 + 0.01 * (step % 100) as f32 } else { 10.0 };
                    let mut input = FrameInput::new(hour, 0.0);
                    input.sky_model = Some(model);
                    let frame = sky.evaluate(&input);
                    input.disabled = disabled.clone();
                    let frame_alone = sky.evaluate(&input);
                    let target = plain.target.target();
                    let f = timed(ctx, |e| floor.record(e, target.color))?;
                    let s = timed(ctx, |e| plain.renderer.render(ctx, e, &target, &frame, &camera, &whole))?;
                    plain.renderer.after_submit();
                    let target = timing.target.target();
                    timed(ctx, |e| timing.renderer.render(ctx, e, &target, &frame_alone, &camera, &alone))?;
                    settle(ctx, &mut timing)?;
                    if i >= 2 {
                        let compute = timing.renderer.gpu_pass_ms().iter().filter(|(n, _)| *n == "compute").map(|(_, ms)| *ms as f64).sum::<f64>();
                        let k = usize::from(!moving);
                        out[k].push(compute);
                        out[2 + k].push(s);
                        out[4].push(f);
                    }
                }
            }
        }
    }
    Ok(samples
        .iter_mut()
        .map(|s| DrawCost {
            model_moving_ms: median(&mut s[0]),
            model_still_ms: median(&mut s[1]),
            frame_moving_ms: median(&mut s[2]),
            frame_still_ms: median(&mut s[3]),
            floor_ms: median(&mut s[4]),
        })
        .collect())
}

/// CPU ms to fill the sky-view map from a prepared CPU point (one thread).
fn cpu_fill_ms(ev: &Evaluator<'_>, prepared: &Prepared) -> anyhow::Result<f64> {
    if matches!(prepared, Prepared::Gpu(_) | Prepared::Analytic(..) | Prepared::Baked(_)) {
        return Ok(0.0);
    }
    let (w, h) = skytune::render::plan::resolution::SKY_VIEW_SIZE;
    let cases: Vec<Case> = (0..w * h)
        .map(|k| Case {
            camera_km: dome::CAMERA_KM,
            albedo: dome::ALBEDO,
            sun_elev_deg: 30.0,
            view_elev_deg: 90.0 - ((k / w) as f64 + 0.5) / h as f64 * 180.0,
            rel_azimuth_deg: ((k % w) as f64 + 0.5) / w as f64 * 360.0,
            distance_km: None,
        })
        .collect();
    let t = Instant::now();
    ev.radiance(prepared, &dome::Haze::Default.atmosphere(), 30.0, &cases)?;
    Ok(t.elapsed().as_secs_f64() * 1000.0)
}

/// `--shard K/N`: this shard's part of the reference dome, written to `--out` for `skytune merge`.
fn reference_shard(args: &ModelBenchArgs, shard: Shard) -> anyhow::Result<()> {
    anyhow::ensure!(
        args.out.extension().is_some_and(|e| e == "csv"),
        "--out: with --shard, the shard's part of the reference dome is written there: name a .csv file, found {}",
        args.out.display()
    );
    let settings = reference_settings(args);
    if std::fs::read_to_string(&args.out).is_ok_and(|t| ReferenceDome::is_complete_shard(&t, &Haze::ALL, &dome::SUN_ELEVATIONS_DEG, dome::BENCH_DOME, settings, shard)) {
        println!("{}: shard {shard} of the reference dome is complete already (the same settings); skipped", args.out.display());
        return Ok(());
    }
    let bar = Reporter::new(0, "reference");
    let text = ReferenceDome::shard_table(&Haze::ALL, &dome::SUN_ELEVATIONS_DEG, dome::BENCH_DOME, settings, shard, &|done, total| {
        bar.set_length(total as u64);
        bar.set_position(done as u64);
        Ok(())
    })?;
    bar.finish();
    skytune::support::safe_write::write_atomic(&args.out, text.as_bytes()).with_context(|| format!("writing {}", args.out.display()))?;
    println!("wrote shard {shard} of the reference dome to {}; `skytune merge --out {} SHARDS...` combines them", args.out.display(), args.reference.display());
    Ok(())
}

/// The points' errors against the reference: rows per (atmosphere, point, sun), the analytic
/// fits, build times and each point prepared for the default atmosphere.
struct Accuracy {
    by_sun: Vec<SunRow>,
    fits: Vec<(String, Haze, model_points::Fit)>,
    build_ms: Vec<Vec<f64>>,
    prepared_default: Vec<Option<Prepared>>,
}

/// Measures the points of `shard` (an item is an (atmosphere, point) pair, atmosphere after
/// atmosphere) against the reference.
fn accuracy(ev: &Evaluator<'_>, reference: &ReferenceDome, hazes: &[Haze], suns: &[f64], points: &[Point], shard: Shard) -> anyhow::Result<Accuracy> {
    let dirs = dome::dome_directions(dome::BENCH_DOME.0, dome::BENCH_DOME.1);
    let bar = Reporter::new((points.len() * hazes.len()).div_ceil(shard.count) as u64, "accuracy");
    let mut by_sun: Vec<SunRow> = Vec::new();
    let mut fits: Vec<(String, Haze, model_points::Fit)> = Vec::new();
    let mut build_ms = vec![Vec::new(); points.len()];
    let mut prepared_default: Vec<Option<Prepared>> = (0..points.len()).map(|_| None).collect();
    for (h, &haze) in hazes.iter().enumerate() {
        let atm = haze.atmosphere();
        let refs: Vec<&dome::ReferenceSun> =
            suns.iter().map(|s| reference.sun(haze, *s).with_context(|| format!("the reference has no {} sun {s}", haze.name()))).collect::<anyhow::Result<_>>()?;
        let targets: Vec<FitTarget<'_>> = refs.iter().map(|r| FitTarget { sun_elev_deg: r.sun_elev_deg, dirs: &dirs, radiance: &r.radiance }).collect();
        for (k, p) in points.iter().enumerate() {
            if !shard.owns(h * points.len() + k) {
                continue;
            }
            bar.set_message(format!("{} {}", p.id, haze.name()));
            let t = Instant::now();
            let prepared = ev.prepare(&p.method, &atm, &targets)?;
            build_ms[k].push(t.elapsed().as_secs_f64() * 1000.0);
            if let Prepared::Analytic(_, fit) = &prepared {
                fits.push((p.id.clone(), haze, *fit));
            }
            for r in &refs {
                let model = ev.radiance(&prepared, &atm, r.sun_elev_deg, &dome::cases(r.sun_elev_deg, &dirs))?;
                let e = dome::dome_error(&dirs, &r.radiance, &model);
                by_sun.push(SunRow { id: p.id.clone(), haze: haze.name().into(), sun_elev_deg: r.sun_elev_deg, error: e });
            }
            if haze == Haze::Default {
                prepared_default[k] = Some(prepared);
            }
            bar.inc(1);
        }
    }
    bar.finish();
    Ok(Accuracy { by_sun, fits, build_ms, prepared_default })
}

/// `--shard K/N --part errors`: this shard's rows of models-by-sun.csv, as a shard's table in
/// `--out` (a folder), for `skytune merge` to put together folder by folder.
fn errors_shard(args: &ModelBenchArgs, shard: Shard) -> anyhow::Result<()> {
    let reference = reference_dome(&args.reference, reference_settings(args))?;
    let (hazes, suns, points) = selection(args);
    let rows = hazes.len() * points.len() * suns.len();
    let ids: Vec<&str> = points.iter().map(|p| p.id.as_str()).collect();
    let inputs = skytune::support::shard::inputs_key(&[ReferenceDome::header(reference.settings, reference.dome).as_bytes(), format!("{hazes:?} {suns:?} {ids:?}").as_bytes()]);
    let file = args.out.join("models-by-sun.csv");
    if std::fs::read_to_string(&file).is_ok_and(|t| shard.is_complete(&t, rows, suns.len(), inputs)) {
        println!("{}: shard {shard} of the errors is complete already (the same inputs); skipped", file.display());
        return Ok(());
    }
    let ctx = GpuContext::headless(if args.cpu { AdapterChoice::Cpu } else { AdapterChoice::from_env() })?;
    let ev = Evaluator::new(&ctx)?;
    let acc = accuracy(&ev, &reference, &hazes, &suns, &points, shard)?;
    let text = format!("{}\n{}", shard.table_line(rows, suns.len(), inputs), model_points::sun_rows_to_csv(&acc.by_sun));
    std::fs::create_dir_all(&args.out).with_context(|| format!("creating {}", args.out.display()))?;
    skytune::support::safe_write::write_atomic(&file, text.as_bytes()).with_context(|| format!("writing {}", file.display()))?;
    println!("wrote shard {shard} of the errors to {}; `skytune merge --out DIR FOLDERS...` combines them", file.display());
    Ok(())
}

/// The atmospheres, sun elevations and points a run measures (`--quick`: fewer).
fn selection(args: &ModelBenchArgs) -> (Vec<Haze>, Vec<f64>, Vec<Point>) {
    let hazes: Vec<Haze> = if args.quick { vec![Haze::Default] } else { Haze::ALL.to_vec() };
    let suns: Vec<f64> = if args.quick { dome::QUICK_SUN_ELEVATIONS_DEG.to_vec() } else { dome::SUN_ELEVATIONS_DEG.to_vec() };
    let points: Vec<Point> = model_points::points().into_iter().filter(|p| !args.quick || p.quick).collect();
    (hazes, suns, points)
}

/// The reference's settings `bench models` asks for.
fn reference_settings(args: &ModelBenchArgs) -> ReferenceSettings {
    ReferenceSettings { paths: args.paths, target_rel_se: Some(args.target_se), ..dome::committed_settings() }
}

pub fn run(args: &ModelBenchArgs) -> anyhow::Result<()> {
    if let Some(shard) = args.shard {
        return match args.part {
            cli::BenchPart::Reference => reference_shard(args, shard),
            cli::BenchPart::Errors => errors_shard(args, shard),
        };
    }
    let started = Instant::now();
    let reference = reference_dome(&args.reference, reference_settings(args))?;
    let (w, h) = cli::parse_size(&args.size)?;
    let ctx = GpuContext::headless(if args.cpu { AdapterChoice::Cpu } else { AdapterChoice::from_env() })?;
    let adapter = ctx.adapter_line();
    println!("adapter: {adapter}");
    let ev = Evaluator::new(&ctx)?;
    let (hazes, suns, points) = selection(args);
    let dirs = dome::dome_directions(dome::BENCH_DOME.0, dome::BENCH_DOME.1);

    // Accuracy.
    let acc = accuracy(&ev, &reference, &hazes, &suns, &points, Shard::WHOLE)?;
    let (by_sun, fits, mut build_ms, prepared_default) = (acc.by_sun, acc.fits, acc.build_ms, acc.prepared_default);

    // Cost: one frame measurement per distinct draw, side by side.
    let mut draws: Vec<Draw> = Vec::new();
    for p in &points {
        let d = draw_of(&p.method);
        if !draws.contains(&d) {
            draws.push(d);
        }
    }
    println!("measuring {} frame kinds at {w}x{h}, {} frames each, the sun moving and still", draws.len(), args.frames);
    let sky = default_sky();
    let costs = measure_draws(&ctx, (w, h), &sky, &draws, args.frames)?;
    let noise: Vec<(Regime, f64)> =
        reference.suns.iter().filter(|s| hazes.contains(&s.haze) && suns.contains(&s.sun_elev_deg)).map(|s| (Regime::of(s.sun_elev_deg), s.relative_noise(&dirs))).collect();
    let noise_in = |regime: Regime| {
        let v: Vec<f64> = noise.iter().filter(|(r, _)| *r == regime).map(|(_, n)| *n).collect();
        v.iter().sum::<f64>() / v.len().max(1) as f64
    };
    let mut rows: Vec<ChartRow> = Vec::new();
    for (k, p) in points.iter().enumerate() {
        let prepared = prepared_default[k].as_ref().context("every point was prepared for the default atmosphere")?;
        let cost = costs[draws.iter().position(|d| *d == draw_of(&p.method)).unwrap_or(0)];
        let build_ms = match p.method {
            Method::Lut(_) | Method::Precomputed(_) => table_build_ms(&ev, &p.method)?,
            _ => median(&mut build_ms[k]),
        };
        let mine: Vec<&SunRow> = by_sun.iter().filter(|r| r.id == p.id).collect();
        let mean_where = |keep: &dyn Fn(&SunRow) -> bool, f: &dyn Fn(&DomeError) -> f64| {
            let v: Vec<f64> = mine.iter().filter(|r| keep(r)).map(|r| f(&r.error)).collect();
            v.iter().sum::<f64>() / v.len().max(1) as f64
        };
        let mean = |f: &dyn Fn(&DomeError) -> f64| mean_where(&|_| true, f);
        let in_regime = |regime: Regime, f: &dyn Fn(&DomeError) -> f64| mean_where(&|r| Regime::of(r.sun_elev_deg) == regime, f);
        let fit = fits.iter().find(|(id, h, _)| *id == p.id && *h == Haze::Default).map(|f| f.2);
        rows.push(ChartRow {
            id: p.id.clone(),
            model: p.method.model_name().into(),
            rel_rmse_r: mean(&|e| e.rel_rmse[0]),
            rel_rmse_g: mean(&|e| e.rel_rmse[1]),
            rel_rmse_b: mean(&|e| e.rel_rmse[2]),
            psnr_db: mean(&|e| e.psnr_db),
            de_mean: mean(&|e| e.de_mean),
            de_p95: mean(&|e| e.de_p95),
            rmse_day: in_regime(Regime::Day, &|e| e.rel_rmse_mean()),
            rmse_low_sun: in_regime(Regime::LowSun, &|e| e.rel_rmse_mean()),
            rmse_twilight: in_regime(Regime::Twilight, &|e| e.rel_rmse_mean()),
            noise_day: noise_in(Regime::Day),
            noise_low_sun: noise_in(Regime::LowSun),
            noise_twilight: noise_in(Regime::Twilight),
            de_day: in_regime(Regime::Day, &|e| e.de_mean),
            de_low_sun: in_regime(Regime::LowSun, &|e| e.de_mean),
            de_twilight: in_regime(Regime::Twilight, &|e| e.de_mean),
            model_gpu_ms_moving: cost.model_moving_ms.max(0.0) + 0.0, // "+ 0.0": no "-0.00" where the model has no GPU phase
            model_gpu_ms_still: cost.model_still_ms.max(0.0) + 0.0,
            cpu_ms: cpu_fill_ms(&ev, prepared)?,
            frame_ms_moving: cost.frame_moving_ms,
            frame_ms_still: cost.frame_still_ms,
            floor_ms: cost.floor_ms,
            build_ms,
            fit_turbidity: fit.map(|f| f.turbidity),
            fit_scale: fit.map(|f| f.scale),
            pareto: false,
        });
    }
    model_points::mark_pareto(&mut rows);
    let lookup = crate::cli::lookup_paths::measure(&ev, &reference, &suns, &points, &by_sun, (w, h))?;

    std::fs::create_dir_all(&args.out).with_context(|| format!("creating {}", args.out.display()))?;
    let csv_path = args.out.join("models.csv");
    skytune::support::safe_write::write_atomic(&csv_path, model_points::rows_to_csv(&rows).as_bytes())?;
    skytune::support::safe_write::write_atomic(&args.out.join("models-by-sun.csv"), model_points::sun_rows_to_csv(&by_sun).as_bytes())?;
    crate::cli::charts::cost_chart(&rows, &args.out.join("models-cost"))?;
    let default_noise: Vec<(f64, f64)> =
        reference.suns.iter().filter(|s| s.haze == Haze::Default && suns.contains(&s.sun_elev_deg)).map(|s| (s.sun_elev_deg, s.relative_noise(&dirs))).collect();
    crate::cli::charts::sun_chart(&by_sun, &default_noise, &args.out.join("models-by-sun"))?;
    let mut md = report(args, &adapter, &rows, &by_sun, &fits, &reference, &hazes, &suns, (w, h), started.elapsed().as_secs_f64());
    md.push_str(&crate::cli::lookup_paths::markdown(&lookup, (w, h)));
    skytune::support::safe_write::write_atomic(&args.out.join("models.md"), md.as_bytes())?;
    print!("{md}");
    println!("\nwrote {}/models.md, models.csv, models-by-sun.csv, models-cost.svg/png, models-by-sun.svg/png", args.out.display());
    Ok(())
}

/// One-off cost of a table model's tables (`lut`, `precomputed`): build them and evaluate one
/// case, wall ms (median of 3; one where a build takes over 10 s, against noise of a few percent).
fn table_build_ms(ev: &Evaluator<'_>, method: &Method) -> anyhow::Result<f64> {
    let case = dome::cases(30.0, &dome::dome_directions(1, 1));
    let mut times: Vec<f64> = Vec::new();
    while times.len() < 3 && times.iter().sum::<f64>() < 10_000.0 {
        ev.forget_tables();
        let t = Instant::now();
        ev.gpu(method, &dome::Haze::Default.atmosphere(), 0.0, &case)?;
        times.push(t.elapsed().as_secs_f64() * 1000.0);
    }
    Ok(median(&mut times))
}

#[allow(clippy::too_many_arguments)]
fn report(
    args: &ModelBenchArgs,
    adapter: &str,
    rows: &[ChartRow],
    by_sun: &[SunRow],
    fits: &[(String, Haze, model_points::Fit)],
    reference: &ReferenceDome,
    hazes: &[Haze],
    suns: &[f64],
    (w, h): (u32, u32),
    seconds: f64,
) -> String {
    let (mw, mh) = skytune::render::plan::resolution::SKY_VIEW_SIZE;
    let mut md = String::new();
    let _ = writeln!(md, "# Sky models: speed against accuracy\n");
    let _ = writeln!(
        md,
        "Written by `skytune bench models{}` in {seconds:.0} s; re-run it to refresh this file, models.csv, models-by-sun.csv and the charts.\n",
        if args.quick { " --quick" } else { "" }
    );
    let _ = writeln!(md, "- adapter: {adapter}");
    let _ = writeln!(md, "- machine: {} logical CPUs; {}", std::thread::available_parallelism().map_or(0, |n| n.get()), skytune::build_line());
    let _ = writeln!(
        md,
        "- dome: {} directions ({} equal-area elevation bands x {} azimuths over half a turn, solid-angle weights), camera at {} km, ground albedo {}",
        dome::BENCH_DOME.0 * dome::BENCH_DOME.1,
        dome::BENCH_DOME.0,
        dome::BENCH_DOME.1,
        dome::CAMERA_KM,
        dome::ALBEDO
    );
    let _ = writeln!(md, "- sun elevations (degrees): {}", suns.iter().map(|s| s.to_string()).collect::<Vec<_>>().join(", "));
    let _ = writeln!(md, "- atmospheres: {}", hazes.iter().map(|h| h.name()).collect::<Vec<_>>().join(", "));
    let _ = writeln!(md, "- reference: `src/atmosphere/reference/`, every order, {}, cached in {}", reference.settings.describe_paths(), args.reference.display());
    // The reference's own noise: a floor under every relative RMSE.
    let dirs = dome::dome_directions(dome::BENCH_DOME.0, dome::BENCH_DOME.1);
    let noise: Vec<f64> = reference.suns.iter().filter(|s| hazes.contains(&s.haze) && suns.contains(&s.sun_elev_deg)).map(|s| s.relative_noise(&dirs)).collect();
    let noise_mean = noise.iter().sum::<f64>() / noise.len().max(1) as f64;
    let _ = writeln!(
        md,
        "- the reference's own Monte Carlo noise, as a relative RMSE over the dome: mean {:.2}%, worst {:.2}% (errors below this are not resolved; by regime in the table below)",
        noise_mean * 100.0,
        noise.iter().cloned().fold(0.0, f64::max) * 100.0
    );
    let per_regime: Vec<String> = Regime::ALL
        .iter()
        .filter_map(|regime| {
            let mut v: Vec<f64> = reference
                .suns
                .iter()
                .filter(|s| hazes.contains(&s.haze) && suns.contains(&s.sun_elev_deg) && Regime::of(s.sun_elev_deg) == *regime)
                .flat_map(|s| s.radiance.iter().zip(&s.std_err).flat_map(|(l, e)| (0..3).filter(|c| l[*c] > 0.0).map(move |c| e[c] / l[c])))
                .collect();
            v.sort_by(f64::total_cmp);
            let median = *v.get(v.len() / 2)?;
            Some(format!("{} median {:.2}%, worst {:.2}%", regime.name(), median * 100.0, v.last().copied().unwrap_or(0.0) * 100.0))
        })
        .collect();
    let _ = writeln!(
        md,
        "- the reference's relative standard error per value (direction and channel), by regime (the goal: median at most 1% by day and at low sun and 3% at twilight, worst at most 5% and 10%): {}",
        per_regime.join("; ")
    );
    let _ = writeln!(
        md,
        "- cost, every point in the same run, in {} interleaved rounds ({} measured frames per point and case, medians):\n  \
         - **model**: what the model itself costs per frame, the GPU time (timestamp queries) of the compute phase of a {w}x{h} frame that draws only the skydome: its sky-view map, and for `lut` its tables, recomputed when the sun moves, reused when it is still; plus the CPU time of CPU paths when the sun moves (filling the {mw}x{mh} sky-view map on one thread);\n  \
         - **frame**: a whole {w}x{h} frame of the built-in sky drawn with the model (every layer, no scene stand-in, as `skytune bench frame`), wall time (lavapipe rasterises on the CPU), as a multiple of the fill-rate floor measured alternately in the same run (`shaders/baseline.wgsl`: one full-screen triangle sampling one texture); the CPU time above is added when the sun moves;\n  \
         - one-off: building tables (`lut`, `precomputed`: tables + one case, wall; `precomputed` frames are measured once, with the small tables, since every size is looked up alike), solving (`cells`), fitting (analytic models), baking. `kind = \"auto\"` ranks candidates by the whole frame with the sun moving.\n",
        3,
        args.frames
    );
    let _ = writeln!(md, "## Method\n");
    let _ = writeln!(md, "Per point, atmosphere and sun elevation, over the dome (means over every atmosphere and sun elevation in the table):\n");
    let _ = writeln!(md, "- relative RMSE per channel: sqrt(sum w (model - reference)^2 / sum w reference^2), w the solid angle;");
    let _ = writeln!(
        md,
        "- display image: radiance times 2^{} (the sky file's default exposure), tone curve 1 - exp(-x), sRGB-encoded; PSNR of that image (peak 1, as Bruneton reports his); mean and 95th-percentile CIE dE2000 of its colours (solid-angle weighted; sRGB to XYZ(D50) by the Bradford matrix, `deltae` for dE2000).",
        dome::EXPOSURE_EV
    );
    let _ = writeln!(
        md,
        "- `preetham`, `hosek`: the turbidity (from {{1, 1.3, 1.7, 2, 2.5, 3, 3.5, 4, 5, 6, 8, 10}}, Preetham from 1.7) and one radiance scale fitted per atmosphere by least squares of the relative error over every sun elevation; `linear` (display values, decoded from sRGB): one scale."
    );
    let _ = writeln!(
        md,
        "- representations built from the default `lut` model: the procedural-sky text's sky-dome map (../shared/references/procedural-sky-scattering-blog.txt; its non-uniform (sin pitch, sqrt((1 - cos yaw) / 2)) sampling, tabulated at 16 sun elevations and interpolated), its regression (5 coefficients per channel: constant, (1 - sin pitch)^3, cos^2 of the angle to the sun, a g = 0.8 forward lobe, and the horizon term times (1 + cos) / 2; weighted least squares, interpolated between the 16 sun elevations), and baked NeL bitmaps (`skytune bake`: 24 hours of an equinox day at the equator, 8-bit gradients of N rows plus a halo; error includes the interpolation between baked hours).\n"
    );
    let _ = writeln!(md, "## Results\n");
    let _ = writeln!(md, "![error against sun elevation](models-by-sun.svg)\n");
    let _ = writeln!(
        md,
        "| point | rel. RMSE r / g / b | PSNR dB | dE2000 mean | dE2000 p95 | model GPU ms, sun moving / still | model CPU ms, sun moving | frame / floor, sun moving / still | one-off ms | Pareto |"
    );
    let _ = writeln!(md, "|---|---|---:|---:|---:|---:|---:|---:|---:|:---:|");
    for r in rows {
        let _ = writeln!(
            md,
            "| {} | {:.3} / {:.3} / {:.3} | {:.1} | {:.2} | {:.2} | {:.2} / {:.2} | {:.2} | {:.2} / {:.2} | {:.0} | {} |",
            r.id,
            r.rel_rmse_r,
            r.rel_rmse_g,
            r.rel_rmse_b,
            r.psnr_db,
            r.de_mean,
            r.de_p95,
            r.model_gpu_ms_moving,
            r.model_gpu_ms_still,
            r.cpu_ms,
            r.floor_ratio_moving(),
            r.floor_ratio_still(),
            r.build_ms,
            if r.pareto { "yes" } else { "" }
        );
    }
    let floor: Vec<f64> = rows.iter().map(|r| r.floor_ms).collect();
    let _ = writeln!(md, "\nThe fill-rate floor: {:.2} ms (median over the points' cases).\n", median(&mut floor.clone()));
    let _ = writeln!(md, "## Accuracy by regime\n");
    let _ = writeln!(
        md,
        "Mean relative RMSE over the dome (r, g, b averaged; every atmosphere and sun elevation of the regime) +- the reference's own relative noise there (one standard error: the RMSE against the truth lies within about this of the figure), and mean dE2000.\n"
    );
    let _ = writeln!(md, "![error against cost by regime](models-cost.svg)\n");
    let _ = write!(md, "| point |");
    for g in Regime::ALL {
        let _ = write!(md, " {} rel. RMSE | dE2000 |", g.name());
    }
    let _ = writeln!(md, "\n|---|---:|---:|---:|---:|---:|---:|");
    for r in rows {
        let _ = write!(md, "| {} |", r.id);
        for (g, de) in Regime::ALL.into_iter().zip([r.de_day, r.de_low_sun, r.de_twilight]) {
            let (e, n) = r.regime(g);
            let _ = write!(md, " {e:.3} +- {n:.3} | {de:.2} |");
        }
        let _ = writeln!(md);
    }
    let _ = writeln!(md, "\n## Fits of the analytic models\n");
    let _ = writeln!(md, "| model | atmosphere | turbidity | scale |");
    let _ = writeln!(md, "|---|---|---:|---:|");
    for (id, haze, fit) in fits {
        let t = if id == "linear" { "-".to_string() } else { format!("{}", fit.turbidity) };
        let _ = writeln!(md, "| {id} | {} | {t} | {:.3e} |", haze.name(), fit.scale);
    }
    let _ = writeln!(md, "\n## Where each model fails\n");
    let _ = writeln!(md, "Worst sun elevation per point (largest mean relative RMSE over its atmospheres):\n");
    let _ = writeln!(md, "| point | worst sun (deg) | rel. RMSE there | best sun (deg) | rel. RMSE there |");
    let _ = writeln!(md, "|---|---:|---:|---:|---:|");
    for r in rows {
        let mut per_sun: Vec<(f64, f64)> = suns
            .iter()
            .map(|s| {
                let v: Vec<f64> = by_sun.iter().filter(|x| x.id == r.id && x.sun_elev_deg == *s).map(|x| x.error.rel_rmse_mean()).collect();
                (*s, v.iter().sum::<f64>() / v.len().max(1) as f64)
            })
            .collect();
        per_sun.sort_by(|a, b| a.1.total_cmp(&b.1));
        if let (Some(best), Some(worst)) = (per_sun.first(), per_sun.last()) {
            let _ = writeln!(md, "| {} | {} | {:.3} | {} | {:.3} |", r.id, worst.0, worst.1, best.0, best.1);
        }
    }
    md
}
