//! `skytune bench models`: every sky model at several quality settings, error against the
//! reference over the dome against cost; writes docs/models.md, models.csv, models-by-sun.csv and
//! the charts (models-cost.svg/png, models-by-sun.svg/png).

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use anyhow::Context as _;

use crate::cli::{self, ModelBenchArgs};
use skytune::atmosphere::dome::{self, DomeError, Haze, ReferenceDome};
use skytune::atmosphere::reference::Case;
use skytune::atmosphere::LutSettings;
use skytune::measure::model_points::{self, ChartRow, Evaluator, FitTarget, Method, Point, Prepared, SunRow};
use skytune::render::{AdapterChoice, Camera, GpuContext, Headless, RenderOptions};
use skytune::sky::builtin::default_sky;
use skytune::sky::resolved::{SkyModel, SkyModelKind};
use skytune::sky::{FrameInput, Sky};
use skytune::support::progress::Reporter;

/// The reference over the benchmark's dome: read from `path`, or computed (minutes) and written.
pub fn reference_dome(path: &Path, paths: u32) -> anyhow::Result<ReferenceDome> {
    match ReferenceDome::load(path, paths, dome::BENCH_DOME) {
        Ok(r) if r.suns.len() == Haze::ALL.len() * dome::SUN_ELEVATIONS_DEG.len() => return Ok(r),
        Ok(_) => log::warn!("{}: incomplete; recomputing", path.display()),
        Err(e) => match dome::committed_reference() {
            // Run from elsewhere than the checkout: the dataset built into the binary.
            Ok(r) if paths == dome::COMMITTED_PATHS => return Ok(r),
            _ => log::warn!("{e}; computing the reference dome (once, minutes)"),
        },
    }
    let bar = Reporter::new(0, "reference");
    let reference = ReferenceDome::compute(&Haze::ALL, &dome::SUN_ELEVATIONS_DEG, dome::BENCH_DOME, paths, &|done, total| {
        bar.set_length(total as u64);
        bar.set_position(done as u64);
        Ok(())
    })?;
    bar.finish();
    reference.save(path).with_context(|| format!("writing {}", path.display()))?;
    Ok(reference)
}

/// What a point costs.
#[derive(Debug, Clone, Copy, Default)]
struct Cost {
    /// GPU time of a 1280x720 frame of the skydome in which the sun moved (median, ms).
    gpu_frame_ms: f64,
    /// CPU time when the sun moves (filling the sky-view map on the CPU), ms.
    cpu_ms: f64,
    /// One-off: building tables, solving, fitting, ms.
    build_ms: f64,
}

/// How a point's frame is drawn (points drawn alike share one measurement).
#[derive(Debug, Clone, Copy, PartialEq)]
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
    match *method {
        Method::Single(s) => Draw::Model(SkyModel { single: s, ..with(SkyModelKind::Single) }),
        Method::Lut(s) => Draw::Model(SkyModel { lut: s, ..with(SkyModelKind::Lut) }),
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

/// GPU ms per frame of each distinct draw, measured side by side in interleaved rounds.
fn measure_draws(hl: &mut Headless, sky: &Sky, draws: &[Draw], frames: u32) -> anyhow::Result<Vec<f64>> {
    let camera = Camera { yaw_deg: 180.0, pitch_deg: 40.0, ..Camera::default() };
    // Only the skydome: the object whose gradient stage the models replace.
    let dome = sky.objects.iter().position(|o| o.name == "skydome").context("the built-in sky has no skydome")?;
    let disabled: Vec<String> = sky.objects.iter().enumerate().filter(|(i, _)| *i != dome).map(|(_, o)| o.name.clone()).collect();
    let options = RenderOptions { glare: false, ..Default::default() };
    let rounds = 3;
    let per_round = frames.div_ceil(rounds).max(1);
    let mut samples = vec![Vec::new(); draws.len()];
    for _ in 0..rounds {
        for (d, out) in draws.iter().zip(samples.iter_mut()) {
            let mut input = FrameInput::new(10.0, 0.0);
            input.disabled = disabled.clone();
            input.sky_model = Some(match d {
                Draw::Model(m) => *m,
                Draw::MapReused => SkyModel { kind: SkyModelKind::Single, ..SkyModel::default() },
                Draw::Bitmap => SkyModel::default(),
            });
            for i in 0..per_round + 2 {
                if matches!(d, Draw::Model(_)) {
                    input.hour = 10.0 + 0.01 * i as f32;
                }
                hl.frame(sky, &input, &camera, &options, 0.0);
                hl.ctx.wait_idle()?;
                if i >= 2 {
                    // Timestamps of the previous frame of this same draw.
                    out.push(hl.renderer.gpu_pass_ms().iter().map(|(_, ms)| *ms as f64).sum::<f64>());
                }
            }
        }
    }
    Ok(samples.iter_mut().map(|s| median(s)).collect())
}

/// CPU ms to fill the 192 x 108 sky-view map from a prepared CPU point (one thread).
fn cpu_fill_ms(ev: &Evaluator<'_>, prepared: &Prepared) -> anyhow::Result<f64> {
    if matches!(prepared, Prepared::Gpu(_) | Prepared::Analytic(..) | Prepared::Baked(_)) {
        return Ok(0.0);
    }
    let (w, h) = skytune::render::frame::pass::SharedResources::SKY_VIEW_SIZE;
    let cases: Vec<Case> = (0..w * h)
        .map(|k| Case {
            camera_km: dome::CAMERA_KM,
            albedo: dome::ALBEDO,
            sun_elev_deg: 30.0,
            view_elev_deg: 90.0 - ((k / w) as f64 + 0.5) / h as f64 * 180.0,
            rel_azimuth_deg: ((k % w) as f64 + 0.5) / w as f64 * 360.0,
        })
        .collect();
    let t = Instant::now();
    ev.radiance(prepared, &dome::Haze::Default.atmosphere(), 30.0, &cases)?;
    Ok(t.elapsed().as_secs_f64() * 1000.0)
}

pub fn run(args: &ModelBenchArgs) -> anyhow::Result<()> {
    let started = Instant::now();
    let reference = reference_dome(&args.reference, args.paths)?;
    let (w, h) = cli::parse_size(&args.size)?;
    let ctx = GpuContext::headless(if args.cpu { AdapterChoice::Cpu } else { AdapterChoice::from_env() })?;
    let adapter = ctx.adapter_line();
    println!("adapter: {adapter}");
    let ev = Evaluator::new(&ctx)?;
    let hazes: Vec<Haze> = if args.quick { vec![Haze::Default] } else { Haze::ALL.to_vec() };
    let suns: Vec<f64> = if args.quick { dome::QUICK_SUN_ELEVATIONS_DEG.to_vec() } else { dome::SUN_ELEVATIONS_DEG.to_vec() };
    let points: Vec<Point> = model_points::points().into_iter().filter(|p| !args.quick || p.quick).collect();
    let dirs = dome::dome_directions(dome::BENCH_DOME.0, dome::BENCH_DOME.1);

    // Accuracy.
    let bar = Reporter::new((points.len() * hazes.len()) as u64, "accuracy");
    let mut by_sun: Vec<SunRow> = Vec::new();
    let mut fits: Vec<(String, Haze, model_points::Fit)> = Vec::new();
    let mut build_ms = vec![Vec::new(); points.len()];
    let mut prepared_default: Vec<Option<Prepared>> = (0..points.len()).map(|_| None).collect();
    for &haze in &hazes {
        let atm = haze.atmosphere();
        let refs: Vec<&dome::ReferenceSun> =
            suns.iter().map(|s| reference.sun(haze, *s).with_context(|| format!("the reference has no {} sun {s}", haze.name()))).collect::<anyhow::Result<_>>()?;
        let targets: Vec<FitTarget<'_>> = refs.iter().map(|r| FitTarget { sun_elev_deg: r.sun_elev_deg, dirs: &dirs, radiance: &r.radiance }).collect();
        for (k, p) in points.iter().enumerate() {
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

    // Cost: one frame measurement per distinct draw, side by side.
    let mut draws: Vec<Draw> = Vec::new();
    for p in &points {
        let d = draw_of(&p.method);
        if !draws.contains(&d) {
            draws.push(d);
        }
    }
    println!("measuring {} frame kinds at {w}x{h}, {} frames each", draws.len(), args.frames);
    let mut hl = Headless::new(GpuContext::headless(if args.cpu { AdapterChoice::Cpu } else { AdapterChoice::from_env() })?, w, h)?;
    let sky = default_sky();
    hl.set_sky(&sky)?;
    let frame_ms = measure_draws(&mut hl, &sky, &draws, args.frames)?;
    let mut rows: Vec<ChartRow> = Vec::new();
    for (k, p) in points.iter().enumerate() {
        let prepared = prepared_default[k].as_ref().context("every point was prepared for the default atmosphere")?;
        let mut cost = Cost {
            gpu_frame_ms: frame_ms[draws.iter().position(|d| *d == draw_of(&p.method)).unwrap_or(0)],
            cpu_ms: cpu_fill_ms(&ev, prepared)?,
            build_ms: median(&mut build_ms[k]),
        };
        if let Method::Lut(s) = p.method {
            cost.build_ms = lut_build_ms(&ev, &s)?;
        }
        let mine: Vec<&SunRow> = by_sun.iter().filter(|r| r.id == p.id).collect();
        let n = mine.len().max(1) as f64;
        let mean = |f: &dyn Fn(&DomeError) -> f64| mine.iter().map(|r| f(&r.error)).sum::<f64>() / n;
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
            gpu_frame_ms: cost.gpu_frame_ms,
            cpu_ms: cost.cpu_ms,
            build_ms: cost.build_ms,
            fit_turbidity: fit.map(|f| f.turbidity),
            fit_scale: fit.map(|f| f.scale),
            pareto: false,
        });
    }
    model_points::mark_pareto(&mut rows);

    std::fs::create_dir_all(&args.out).with_context(|| format!("creating {}", args.out.display()))?;
    let csv_path = args.out.join("models.csv");
    skytune::support::safe_write::write_atomic(&csv_path, model_points::rows_to_csv(&rows).as_bytes())?;
    skytune::support::safe_write::write_atomic(&args.out.join("models-by-sun.csv"), model_points::sun_rows_to_csv(&by_sun).as_bytes())?;
    crate::cli::charts::cost_chart(&rows, &args.out.join("models-cost"))?;
    crate::cli::charts::sun_chart(&by_sun, &args.out.join("models-by-sun"))?;
    let md = report(args, &adapter, &rows, &by_sun, &fits, &reference, &hazes, &suns, (w, h), started.elapsed().as_secs_f64());
    skytune::support::safe_write::write_atomic(&args.out.join("models.md"), md.as_bytes())?;
    print!("{md}");
    println!("\nwrote {}/models.md, models.csv, models-by-sun.csv, models-cost.svg/png, models-by-sun.svg/png", args.out.display());
    Ok(())
}

/// One-off cost of the `lut` model's tables: build them and evaluate one case, wall ms (median of 3).
fn lut_build_ms(ev: &Evaluator<'_>, settings: &LutSettings) -> anyhow::Result<f64> {
    let case = dome::cases(30.0, &dome::dome_directions(1, 1));
    let mut times = Vec::new();
    for _ in 0..3 {
        let t = Instant::now();
        ev.gpu(&Method::Lut(*settings), &dome::Haze::Default.atmosphere(), 0.0, &case)?;
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
    let mut md = String::new();
    let _ = writeln!(md, "# Sky models: speed against accuracy\n");
    let _ = writeln!(
        md,
        "Written by `skytune bench models{}` in {seconds:.0} s; re-run it to refresh this file, models.csv, models-by-sun.csv and the charts.\n",
        if args.quick { " --quick" } else { "" }
    );
    let _ = writeln!(md, "- adapter: {adapter}");
    let _ = writeln!(
        md,
        "- machine: {} logical CPUs; {} build of skytune",
        std::thread::available_parallelism().map_or(0, |n| n.get()),
        if cfg!(debug_assertions) { "debug" } else { "release" }
    );
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
    let _ = writeln!(md, "- reference: `src/atmosphere/reference.rs`, every order, {} Monte Carlo paths per direction, cached in {}", reference.paths, args.reference.display());
    // The reference's own noise: a floor under every relative RMSE.
    let noise: Vec<f64> = reference
        .suns
        .iter()
        .filter(|s| hazes.contains(&s.haze) && suns.contains(&s.sun_elev_deg))
        .map(|s| {
            let dirs = dome::dome_directions(dome::BENCH_DOME.0, dome::BENCH_DOME.1);
            let (mut num, mut den) = (0.0, 0.0);
            for ((d, l), e) in dirs.iter().zip(&s.radiance).zip(&s.std_err) {
                for c in 0..3 {
                    num += d.weight_sr * e[c] * e[c];
                    den += d.weight_sr * l[c] * l[c];
                }
            }
            (num / den.max(1e-300)).sqrt()
        })
        .collect();
    let noise_mean = noise.iter().sum::<f64>() / noise.len().max(1) as f64;
    let _ = writeln!(
        md,
        "- the reference's own Monte Carlo noise, as a relative RMSE over the dome: mean {:.2}%, worst {:.2}% (errors below this are not resolved)",
        noise_mean * 100.0,
        noise.iter().cloned().fold(0.0, f64::max) * 100.0
    );
    let _ = writeln!(
        md,
        "- cost: GPU time (timestamp queries, all passes) of a {w}x{h} frame that draws only the skydome with the model, the sun moving every frame (the sky-view map recomputed), median of {} frames in 3 interleaved rounds, every model in the same run; \
         plus the CPU time of CPU paths when the sun moves (filling the 192x108 sky-view map on one thread); `frame` = GPU + CPU. One-off: building tables (`lut`: tables + one case, wall), solving (`cells`), fitting (analytic models), baking.\n",
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
    let _ = writeln!(md, "![error against cost](models-cost.svg)\n\n![error against sun elevation](models-by-sun.svg)\n");
    let _ = writeln!(md, "| point | rel. RMSE r / g / b | PSNR dB | dE2000 mean | dE2000 p95 | frame ms (GPU + CPU) | one-off ms | Pareto |");
    let _ = writeln!(md, "|---|---|---:|---:|---:|---:|---:|:---:|");
    for r in rows {
        let _ = writeln!(
            md,
            "| {} | {:.3} / {:.3} / {:.3} | {:.1} | {:.2} | {:.2} | {:.2} ({:.2} + {:.2}) | {:.0} | {} |",
            r.id,
            r.rel_rmse_r,
            r.rel_rmse_g,
            r.rel_rmse_b,
            r.psnr_db,
            r.de_mean,
            r.de_p95,
            r.frame_ms(),
            r.gpu_frame_ms,
            r.cpu_ms,
            r.build_ms,
            if r.pareto { "yes" } else { "" }
        );
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
