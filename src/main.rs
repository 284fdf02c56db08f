//! The `skytune` binary: window (default), `render`, `check`, `watch`, `new-sky`, `bench`, `radiance`.

mod cli;

use std::path::Path;
use std::time::Duration;

use anyhow::{anyhow, bail, Context as _};
use clap::Parser;

use cli::{bench_frame, bench_models, bench_passes, stability_report};
use cli::{Cli, Command, FrameArgs, RenderArgs};
use skytune::files::hot_reload::{LiveSky, ReloadEvent, SkySpec};
use skytune::render::{AdapterChoice, Camera, GpuContext, Headless, RenderOptions};
use skytune::sky::resolved::SkyModelKind;
use skytune::sky::{procedural, FrameInput, Sky, Tier};
use skytune::support::shard::{self, Shard};

fn main() {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("info,wgpu_core=warn,wgpu_hal=warn,naga=warn")).init();
    let cli = Cli::parse();
    if let Err(e) = run(cli) {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}

fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        None => skytune::app::run(skytune::app::AppConfig {
            sky: cli.sky,
            season: cli.app.season,
            tier: cli.app.tier,
            frames: cli.app.frames,
            screenshot_and_exit: cli.app.screenshot_and_exit,
            shots: cli.app.shots,
            cpu: cli.app.cpu,
            shader_dir: cli.app.shader_dir,
            compare: cli.app.compare,
            soak: cli.app.soak,
            hour: cli.app.hour,
            weather: cli.app.weather,
            view: cli.app.view,
            strategy: cli.app.strategy,
            edit: cli.app.edit,
        }),
        Some(Command::Render(args)) => render(&args),
        Some(Command::Check { sky }) => check(&sky),
        Some(Command::Watch { render, max_reloads }) => watch(&render, max_reloads),
        Some(Command::NewSky { dir, preset, seed, force }) => {
            let palette = procedural::preset(&preset).ok_or_else(|| anyhow!("unknown preset \"{preset}\"; expected one of {}", procedural::PRESETS.map(|p| p.name).join(", ")))?;
            let sky = new_sky_folder(&dir, palette, seed, force)?;
            println!("wrote {} and its bitmaps; open it with `skytune {}`", sky.display(), sky.display());
            Ok(())
        }
        Some(Command::Bench(cli::BenchCommand { what: Some(cli::BenchWhat::Frame(args)), .. })) => bench_frame::run(&args),
        Some(Command::Bench(cli::BenchCommand { what: Some(cli::BenchWhat::Models(args)), .. })) => bench_models::run(&args),
        Some(Command::Bench(cli::BenchCommand { what: Some(cli::BenchWhat::Reference(args)), .. })) => cli::bench_reference::run(&args),
        Some(Command::Bench(cli::BenchCommand { what: Some(cli::BenchWhat::Aerial(args)), .. })) => cli::bench_aerial::run(&args),
        Some(Command::Bench(cmd)) => bench_passes::run(&cmd.args),
        Some(Command::Radiance(args)) => radiance(&args),
        Some(Command::ExportEnv(args)) => cli::export_env::run(&args),
        Some(Command::Validate(args)) => cli::validate::run(&args, adapter(args.cpu)),
        Some(Command::ValidateAerial(args)) => cli::validate_aerial::run(&args, adapter(args.cpu)),
        Some(Command::Compare(args)) => compare(&args),
        Some(Command::Soak(args)) => soak(&args),
        Some(Command::Sweep(args)) => stability_report::run(&args),
        Some(Command::Bake(args)) => bake(&args),
        Some(Command::Merge(args)) => merge(&args),
    }
}

/// `skytune new-sky`: a new folder is written under a temporary name and renamed when complete;
/// an existing folder is refused unless `force`.
fn new_sky_folder(dir: &Path, palette: &procedural::Palette, seed: u64, force: bool) -> anyhow::Result<std::path::PathBuf> {
    let occupied = dir.exists() && (dir.is_file() || std::fs::read_dir(dir).map(|mut d| d.next().is_some()).unwrap_or(true));
    if occupied && !force {
        bail!("{} exists already; choose another folder, or pass --force to write the sky into it (files of the same names are replaced)", dir.display());
    }
    if dir.is_dir() {
        return skytune::sky::builtin::write_sky_folder(dir, palette, seed).with_context(|| format!("writing {}", dir.display()));
    }
    let name = dir.file_name().map_or_else(|| "sky".into(), |n| n.to_string_lossy().into_owned());
    let staging = dir.with_file_name(format!(".{name}.partial-{}", std::process::id()));
    let result = skytune::sky::builtin::write_sky_folder(&staging, palette, seed)
        .with_context(|| format!("writing {}", staging.display()))
        .and_then(|_| std::fs::rename(&staging, dir).with_context(|| format!("renaming {} to {}", staging.display(), dir.display())));
    if result.is_err() {
        let _ = std::fs::remove_dir_all(&staging);
    }
    result.map(|_| dir.join("sky.toml"))
}

/// `skytune bake`: bakes a physical model into NeL bitmaps and writes a sky folder per sky.
fn bake(args: &cli::BakeArgs) -> anyhow::Result<()> {
    use skytune::measure::model_points::Method;
    let shard = args.shard.unwrap_or(Shard::WHOLE);
    // (sky, its output folder): one sky bakes into --out, several into --out/NAME.
    let mut jobs: Vec<(Option<&Path>, std::path::PathBuf)> = Vec::new();
    if args.skies.len() <= 1 {
        jobs.push((args.skies.first().map(|p| p.as_path()), args.out.clone()));
    } else {
        for p in &args.skies {
            let folder = if p.is_dir() { p.as_path() } else { p.parent().unwrap_or(Path::new(".")) };
            let name = folder.file_name().map_or_else(|| "sky".into(), |n| n.to_string_lossy().into_owned());
            let out = args.out.join(&name);
            if let Some((other, _)) = jobs.iter().find(|(_, o)| *o == out) {
                bail!(
                    "{} and {} would both bake into {}: give skies in folders of different names",
                    other.map_or("?".into(), |o| o.display().to_string()),
                    p.display(),
                    out.display()
                );
            }
            jobs.push((Some(p.as_path()), out));
        }
    }
    let jobs = shard.take(&jobs);
    let ctx = GpuContext::headless(adapter(args.cpu))?;
    let ev = skytune::measure::model_points::Evaluator::new(&ctx)?;
    for (path, out) in jobs {
        let sky = spec_for(path, None)?.load().map_err(|e| anyhow!("{e}"))?;
        let m = &sky.model;
        let method = match args.model {
            SkyModelKind::Single => Method::Single(m.settings.single),
            SkyModelKind::Lut => Method::Lut(m.settings.lut),
            SkyModelKind::Precomputed => Method::Precomputed(m.settings.precomputed),
            SkyModelKind::Cells => Method::Cells(m.settings.cell_iterations as usize),
            SkyModelKind::Preetham => Method::Preetham,
            SkyModelKind::Hosek => Method::Hosek,
            other => bail!("--model: cannot bake from {}", other.name()),
        };
        let started = std::time::Instant::now();
        let baked = skytune::measure::bake::bake(&ev, &sky, method, args.rows, args.weathers)?;
        skytune::measure::bake::write_folder(&out, &sky, &baked, method.model_name()).with_context(|| format!("writing {}", out.display()))?;
        println!(
            "baked {} into {} ({} rows x 24 hours x {} weather steps) in {:.1} s; open it with `skytune {}`",
            method.model_name(),
            out.display(),
            args.rows,
            args.weathers,
            started.elapsed().as_secs_f64(),
            out.join("sky.toml").display()
        );
    }
    Ok(())
}

/// `skytune radiance`: evaluates a model on every case of a CSV file.
/// What `radiance` evaluates in: the atmosphere, the camera altitude and ground albedo a sky file
/// sets, and a line saying where they came from.
type RadianceSetting = (skytune::atmosphere::Atmosphere, Option<skytune::atmosphere::dome::Ground>, String);

/// The atmosphere `radiance` evaluates (the sky file's at its weather, or the default, with the
/// `--atmosphere` keys over it), the camera altitude and ground albedo the sky file sets, and a
/// line saying where the atmosphere came from.
fn radiance_atmosphere(args: &cli::RadianceArgs) -> anyhow::Result<RadianceSetting> {
    use skytune::atmosphere::Atmosphere;
    let (mut atm, camera, mut source) = match &args.sky {
        Some(path) => {
            anyhow::ensure!((0.0..=1.0).contains(&args.weather), "--weather: expected 0..=1, found {}", args.weather);
            let sky = skytune::sky::load_sky_file(path).map_err(|e| anyhow!("{e}"))?;
            let atm = Atmosphere::at_weather(&sky.atmosphere_by_weather, args.weather).unwrap_or(sky.atmosphere);
            let ground = sky.model.ground();
            (atm, Some(ground), format!("atmosphere of {} at weather {}, camera at {} km, ground albedo {}", path.display(), args.weather, ground.camera_km, ground.albedo))
        }
        None => (Atmosphere::default(), None, "default atmosphere (Hillaire 2020)".to_string()),
    };
    if !args.atmosphere.is_empty() {
        // The sky file's own parser and checks: a key is spelled, typed and bounded as there.
        let mut text = String::new();
        for kv in &args.atmosphere {
            let (key, value) = kv.split_once('=').ok_or_else(|| anyhow!("--atmosphere: expected KEY=VALUE, found \"{kv}\""))?;
            text.push_str(&format!("{} = {}\n", key.trim(), value.trim()));
        }
        let def: skytune::sky::model::AtmosphereDef = skytune::sky::load::parse_toml("--atmosphere", &text).map_err(|e| anyhow!("{e}"))?;
        anyhow::ensure!(def.weather.is_empty(), "--atmosphere: weather steps come from a sky file (--sky and --weather)");
        atm = def.apply(atm, None).map_err(|errors| anyhow!("--atmosphere: {}", errors.iter().map(|e| format!("{}: {}", e.field, e.message)).collect::<Vec<_>>().join("; ")))?;
        source.push_str(&format!(", with {}", args.atmosphere.join(", ")));
    }
    atm.validate().map_err(|errors| anyhow!("--atmosphere: {}", errors.iter().map(|e| format!("{}: {}", e.field, e.message)).collect::<Vec<_>>().join("; ")))?;
    Ok((atm, camera, format!("{source}: {atm:?}")))
}

fn radiance(args: &cli::RadianceArgs) -> anyhow::Result<()> {
    use skytune::atmosphere::cases;
    anyhow::ensure!(args.max_order >= 1, "--max-order: expected at least 1, found {}", args.max_order);
    anyhow::ensure!((1..=4096).contains(&args.view_steps) && (1..=4096).contains(&args.sun_steps), "--view-steps and --sun-steps: expected 1..=4096");
    let (atm, ground, atmosphere_line) = radiance_atmosphere(args)?;
    let mut all = cases::read_cases(&args.cases, atm.thickness_km())?;
    if let Some(g) = ground {
        anyhow::ensure!(g.camera_km < atm.thickness_km(), "--sky: the camera ({} km) is above the top of its atmosphere", g.camera_km);
        for c in &mut all {
            (c.camera_km, c.albedo) = (g.camera_km, g.albedo);
        }
    }
    let finite = cases::has_finite_rays(&all);
    // Finite rays: the reference; `lut`'s exact integration on the GPU; every runtime model
    // through the renderer's aerial-perspective volume but Braun and Cohen's, whose colour is not
    // a radiance.
    anyhow::ensure!(
        !finite || args.model != SkyModelKind::Linear,
        "{}: distance_km: --model linear gives one display colour, not a radiance along a ray; finite rays are answered by every other model",
        args.cases.display()
    );
    anyhow::ensure!(
        args.aerial != Some(cli::AerialArg::Exact) || matches!(args.model, SkyModelKind::Lut | SkyModelKind::Reference),
        "--aerial exact: only --model lut marches a finite ray itself (and the reference); --model {} answers through the volume",
        args.model.name()
    );
    let through_volume = finite && args.model != SkyModelKind::Reference && (args.model != SkyModelKind::Lut || args.aerial == Some(cli::AerialArg::Volume));
    let shard = args.shard.unwrap_or(Shard::WHOLE);
    let list = shard.take(&all);
    // Everything a shard's rows depend on: its arguments but where it writes, and its cases.
    let inputs = {
        let mut a = args.clone();
        (a.out, a.shard) = (Default::default(), None);
        shard::inputs_key(&[format!("{a:?}").as_bytes(), &std::fs::read(&args.cases).unwrap_or_default(), atmosphere_line.as_bytes()])
    };
    if !shard.is_whole() && std::fs::read_to_string(&args.out).is_ok_and(|t| shard.is_complete(&t, all.len(), 1, inputs)) {
        println!("{}: shard {shard} is complete already (the same inputs); skipped", args.out.display());
        return Ok(());
    }
    let started = std::time::Instant::now();
    let what = if finite {
        "radiance scattered into each view ray before distance_km (empty: the edge of the atmosphere), in sr^-1 per unit of solar irradiance (1 per channel at the top of the atmosphere), and the ray's transmittance t_r,t_g,t_b; the surface at the distance emits and reflects nothing"
    } else {
        "sky radiance in sr^-1 per unit of solar irradiance (1 per channel at the top of the atmosphere)"
    };
    let units: std::borrow::Cow<str> = format!("{what}; {atmosphere_line}; sun disc and ground surface excluded").into();
    // The reference's standard errors and paths, written beside its radiance, or a model's
    // transmittance along finite rays.
    let mut estimates = None;
    let mut transmittance = None;
    let (out, units, comment) = match args.model {
        _ if through_volume => {
            let (answers, comment) = volume_radiance(args, &atm, &list)?;
            let (out, t) = answers.to_f64();
            transmittance = Some(t);
            (out, units, comment)
        }
        SkyModelKind::Reference => {
            let (e, comment) = reference_radiance(args, atm, &list)?;
            let out = e.iter().map(|e| e.all).collect();
            estimates = Some(e);
            (out, units, comment)
        }
        SkyModelKind::Single => {
            let settings = skytune::atmosphere::SingleSettings {
                view_steps: args.view_steps,
                sun_steps: args.sun_steps,
                optical_depth: match args.optical_depth {
                    cli::OpticalDepthArg::Erf => skytune::atmosphere::OpticalDepth::Erf,
                    cli::OpticalDepthArg::Numerical => skytune::atmosphere::OpticalDepth::Numerical,
                },
            };
            let ctx = GpuContext::headless(adapter(args.cpu))?;
            let probe = skytune::render::atmosphere::radiance_probe::RadianceProbe::new(&ctx, &skytune::render::ShaderLibrary::embedded())?;
            let out = probe.single(&ctx, &atm, &settings, &list)?;
            let out = out.into_iter().map(|c| c.map(f64::from)).collect();
            (out, units, format!("model single on {}: {settings:?}", ctx.adapter_line()))
        }
        SkyModelKind::Lut => {
            let settings = lut_settings(args)?;
            let ctx = GpuContext::headless(adapter(args.cpu))?;
            let probe = skytune::render::atmosphere::radiance_probe::RadianceProbe::new(&ctx, &skytune::render::ShaderLibrary::embedded())?;
            let (out, t) = probe.lut_rays(&ctx, &atm, &settings, &list)?.to_f64();
            transmittance = Some(t);
            (out, units, format!("model lut on {}: {settings:?}", ctx.adapter_line()))
        }
        SkyModelKind::Precomputed => {
            let d = skytune::atmosphere::PrecomputedSettings::default();
            let settings = skytune::atmosphere::PrecomputedSettings {
                orders: args.orders,
                scattering_size: args.scattering_size.unwrap_or(d.scattering_size),
                density_directions: args.density_directions,
                precision: args.precision,
                ..d
            };
            settings.validate().map_err(|e| anyhow!("--{}: {}", e.field.replace('_', "-"), e.message))?;
            let ctx = GpuContext::headless(adapter(args.cpu))?;
            let probe = skytune::render::atmosphere::radiance_probe::RadianceProbe::new(&ctx, &skytune::render::ShaderLibrary::embedded())?;
            let out = probe.precomputed(&ctx, &atm, &settings, &list)?;
            let out = out.into_iter().map(|c| c.map(f64::from)).collect();
            (out, units, format!("model precomputed on {}: {settings:?}", ctx.adapter_line()))
        }
        SkyModelKind::Cells => {
            use skytune::atmosphere::cells::{CellModel, CellSettings};
            anyhow::ensure!(args.iterations <= 32, "--iterations: expected 0..=32, found {}", args.iterations);
            let settings = CellSettings { iterations: args.iterations, ..Default::default() };
            let mut out = vec![[0.0; 3]; list.len()];
            let mut albedos: Vec<f64> = list.iter().map(|c| c.albedo).collect();
            albedos.sort_by(f64::total_cmp);
            albedos.dedup();
            for albedo in albedos {
                let model = CellModel::solve(atm, albedo, settings);
                for (c, o) in list.iter().zip(out.iter_mut()).filter(|(c, _)| c.albedo == albedo) {
                    *o = model.radiance(c);
                }
            }
            (out, units, format!("model cells: {settings:?}"))
        }
        SkyModelKind::Preetham | SkyModelKind::Hosek | SkyModelKind::Linear => {
            use skytune::atmosphere::analytic::{self, AnalyticModel, LinearParams};
            anyhow::ensure!(args.turbidity.is_finite(), "--turbidity: expected a finite number, found {}", args.turbidity);
            let units = if args.published_units { analytic::AnalyticUnits::Published } else { analytic::AnalyticUnits::Calibrated };
            let model = match args.model {
                SkyModelKind::Preetham => AnalyticModel::Preetham { turbidity: args.turbidity, units },
                SkyModelKind::Hosek => AnalyticModel::Hosek { turbidity: args.turbidity, albedo: 0.0, units },
                _ => AnalyticModel::Linear(
                    LinearParams::preset(&args.preset)
                        .ok_or_else(|| anyhow!("--preset: unknown table \"{}\"; expected one of {}", args.preset, analytic::LINEAR_PRESETS.map(|p| p.0).join(", ")))?,
                ),
            };
            let albedo_note = if matches!(model, AnalyticModel::Hosek { .. }) { " (the albedo column is used)" } else { "" };
            let per_case = |c: &skytune::atmosphere::reference::Case| match model {
                AnalyticModel::Hosek { turbidity, units, .. } => AnalyticModel::Hosek { turbidity, albedo: c.albedo, units },
                m => m,
            };
            let out: Vec<[f64; 3]> = if args.on_cpu {
                list.iter()
                    .map(|c| {
                        per_case(c).radiance(
                            analytic::direction(c.view_elev_deg.to_radians(), c.rel_azimuth_deg.to_radians()),
                            analytic::direction(c.sun_elev_deg.to_radians(), 0.0),
                            analytic::equinox_morning_hour(c.sun_elev_deg),
                        )
                    })
                    .collect()
            } else {
                let ctx = GpuContext::headless(adapter(args.cpu))?;
                let probe = skytune::render::atmosphere::radiance_probe::RadianceProbe::new(&ctx, &skytune::render::ShaderLibrary::embedded())?;
                probe.analytic(&ctx, &list, per_case)?.into_iter().map(|c| c.map(f64::from)).collect()
            };
            let place = if args.on_cpu { "CPU" } else { "GPU" };
            (out, model.units().into(), format!("model {} on the {place}: turbidity {}{albedo_note}", model.name(), args.turbidity))
        }
        other => bail!("--model: {} has no radiance to evaluate", other.name()),
    };
    let name = args.model.name();
    let mut comment = format!("skytune radiance --model {name}: {units}\n{comment}");
    if !shard.is_whole() {
        comment = format!("{}\n{comment}", shard.table_line(all.len(), 1, inputs).trim_start_matches("# "));
    }
    match (&estimates, &transmittance) {
        (Some(e), _) => cases::write_reference(&args.out, &comment, &list, e)?,
        (None, Some(t)) => cases::write_rays(&args.out, &comment, &list, &out, t)?,
        (None, None) => cases::write_radiance(&args.out, &comment, &list, &out)?,
    }
    println!("wrote {} ({} cases in {:.1} s)", args.out.display(), list.len(), started.elapsed().as_secs_f64());
    Ok(())
}

/// `--model lut`'s tables, from the arguments.
fn lut_settings(args: &cli::RadianceArgs) -> anyhow::Result<skytune::atmosphere::LutSettings> {
    let (tw, th) = cli::parse_size(&args.transmittance_size)?;
    let settings = skytune::atmosphere::LutSettings {
        transmittance_size: [tw, th],
        multiscattering_size: args.multiscattering_size,
        multiscattering_grid: args.multiscattering_grid,
        view_steps: args.view_steps,
        ..Default::default()
    };
    settings.validate().map_err(|e| anyhow!("--{}: {}", e.field.replace('_', "-"), e.message))?;
    Ok(settings)
}

/// Finite rays through the renderer's aerial-perspective volume, as a frame of `args.model`
/// builds it (the shared LUT tables at the `lut` arguments; the multiple-scattering orders
/// unless the model is `single`), and the comment naming it.
fn volume_radiance(
    args: &cli::RadianceArgs,
    atm: &skytune::atmosphere::Atmosphere,
    list: &[skytune::atmosphere::reference::Case],
) -> anyhow::Result<(skytune::render::atmosphere::radiance_probe::ProbeAnswers, String)> {
    let d = skytune::atmosphere::aerial::AerialSettings::default();
    let aerial =
        skytune::atmosphere::aerial::AerialSettings { volume_size: args.volume_size.unwrap_or(d.volume_size), distance_km: args.volume_distance_km.unwrap_or(d.distance_km), ..d };
    aerial.validate().map_err(|e| anyhow!("--volume-{}: {}", e.field.replace('_', "-").trim_start_matches("volume-"), e.message))?;
    let lut = lut_settings(args)?;
    let multiple = args.model != SkyModelKind::Single;
    let ctx = GpuContext::headless(adapter(args.cpu))?;
    let probe = skytune::render::atmosphere::aerial_probe::AerialProbe::new(&ctx, &skytune::render::ShaderLibrary::embedded())?;
    let answers = probe.volume_rays(&ctx, atm, &lut, &aerial, multiple, list)?;
    Ok((
        answers,
        format!("model {} through the aerial-perspective volume on {}: {aerial:?}, multiple scattering {multiple}; tables {lut:?}", args.model.name(), ctx.adapter_line()),
    ))
}

/// The reference's estimate for every case, on every core; with a line saying how it was
/// computed.
fn reference_radiance(
    args: &cli::RadianceArgs,
    atm: skytune::atmosphere::Atmosphere,
    list: &[skytune::atmosphere::reference::Case],
) -> anyhow::Result<(Vec<skytune::atmosphere::reference::Estimate>, String)> {
    use skytune::atmosphere::reference::{estimate_many, Reference, ReferenceSettings};
    let settings = ReferenceSettings { max_order: args.max_order, paths: args.paths, seed: args.seed, target_rel_se: args.target_se, ..Default::default() };
    let model = Reference::new(atm, settings);
    let bar = skytune::support::progress::Reporter::new(list.len() as u64, "radiance");
    let jobs: Vec<_> = list.iter().map(|c| (&model, *c)).collect();
    let estimates = estimate_many(&jobs, &|done, _| {
        bar.set_position(done as u64);
        Ok(())
    })?;
    bar.finish();
    let worst = estimates.iter().flat_map(|e| (0..3).map(move |c| e.std_err[c] / e.all[c].max(1e-30))).fold(0.0, f64::max);
    let paths: u64 = estimates.iter().map(|e| u64::from(e.paths)).sum();
    let capped = settings.target_rel_se.map_or(0, |t| estimates.iter().filter(|e| e.paths >= settings.paths && (0..3).any(|c| e.std_err[c] > t * e.all[c])).count());
    // The worst noise is printed, not written: a shard's would differ from the whole run's.
    println!("largest relative standard error of a value: {worst:.2e}; {paths} paths in all");
    if capped > 0 {
        println!("{capped} of {} cases reached the cap of {} paths above the target standard error (their se_ columns say how far)", list.len(), settings.paths);
    }
    Ok((estimates, format!("model reference: max order {}, {}, seed {}", settings.max_order, settings.describe_paths(), settings.seed)))
}

/// `skytune merge`: the shards' outputs combined into what the unsharded run writes: tables,
/// sweep counts, or folders (`bench models --part errors`) whose same-named tables are merged.
fn merge(args: &cli::MergeArgs) -> anyhow::Result<()> {
    if args.parts.iter().all(|p| p.is_dir()) {
        let first = &args.parts[0];
        let mut names: Vec<std::ffi::OsString> = std::fs::read_dir(first).with_context(|| format!("reading {}", first.display()))?.flatten().map(|e| e.file_name()).collect();
        names.sort();
        std::fs::create_dir_all(&args.out).with_context(|| format!("creating {}", args.out.display()))?;
        let mut merged = 0;
        for name in names {
            let parts: Vec<(String, String)> = args.parts.iter().map(|d| read_part(&d.join(&name))).collect::<anyhow::Result<_>>()?;
            if !shard::is_shard_table(&parts[0].1) {
                continue;
            }
            let out = args.out.join(&name);
            skytune::support::safe_write::write_atomic(&out, shard::merge_tables(&parts)?.as_bytes()).with_context(|| format!("writing {}", out.display()))?;
            println!("wrote {} from {} shards", out.display(), parts.len());
            merged += 1;
        }
        anyhow::ensure!(merged > 0, "{}: holds no shard's table", first.display());
        return Ok(());
    }
    let parts: Vec<(String, String)> = args.parts.iter().map(|p| read_part(p)).collect::<anyhow::Result<_>>()?;
    let first = parts.first().context("merge: name the shards' files")?;
    let merged = if shard::is_shard_table(&first.1) {
        shard::merge_tables(&parts)?
    } else if stability_report::is_sweep_part(&first.1) {
        return stability_report::merge(&parts, &args.out);
    } else {
        bail!("{}: neither a shard's table (`radiance --shard`, `bench models --shard`) nor a shard of `sweep --shard`", first.0);
    };
    skytune::support::safe_write::write_atomic(&args.out, merged.as_bytes()).with_context(|| format!("writing {}", args.out.display()))?;
    println!("wrote {} from {} shards", args.out.display(), parts.len());
    Ok(())
}

/// A shard's output file: (its name, its text).
fn read_part(p: &Path) -> anyhow::Result<(String, String)> {
    Ok((p.display().to_string(), std::fs::read_to_string(p).with_context(|| format!("reading {}", p.display()))?))
}

/// The sky a command names (or the built-in one).
pub fn spec_for(path: Option<&Path>, season: Option<&str>) -> anyhow::Result<SkySpec> {
    match path {
        None => Ok(SkySpec::Builtin),
        Some(p) => SkySpec::from_path(p, season).map_err(|e| anyhow!("{e}")),
    }
}

/// Frame input and camera from CLI arguments.
/// The fill strategy `--strategy` names (the adapter's without it), with `--dome-resolution`'s
/// resolution where given.
fn strategy_from_args(f: &FrameArgs, ctx: &GpuContext) -> anyhow::Result<skytune::render::FillStrategy> {
    use skytune::render::FillStrategy;
    let mut strategy = FillStrategy::resolve(f.strategy, ctx.adapter.get_info().device_type);
    if let Some(r) = f.dome_resolution {
        strategy.dome_resolution = r;
    }
    Ok(strategy)
}

pub fn frame_from_args(f: &FrameArgs) -> anyhow::Result<(FrameInput, Camera)> {
    let tier = Tier::new(f.tier).ok_or_else(|| anyhow!("--tier: expected 4, 2 or 1, found {}", f.tier))?;
    anyhow::ensure!(f.hour.is_finite() && f.weather.is_finite(), "--hour and --weather must be finite numbers");
    let mut camera = Camera::preset_arg(&f.view).map_err(|e| anyhow!(e))?;
    if let Some(y) = f.yaw {
        camera.yaw_deg = y;
    }
    if let Some(p) = f.pitch {
        camera.pitch_deg = p;
    }
    anyhow::ensure!((1.0..=170.0).contains(&f.fov), "--fov: expected 1..170 degrees, found {}", f.fov);
    camera.fov_y_deg = f.fov;
    let mut input = FrameInput::new(f.hour, f.weather);
    input.tier = tier;
    input.env_map = f.env_map;
    Ok((input, camera))
}

fn adapter(cpu: bool) -> AdapterChoice {
    if cpu {
        AdapterChoice::Cpu
    } else {
        AdapterChoice::from_env()
    }
}

/// Renders `sky` as `args` says into `args.out`.
fn render_to_file(headless: &mut Headless, sky: &Sky, args: &RenderArgs) -> anyhow::Result<()> {
    let (input, camera) = frame_from_args(&args.frame)?;
    anyhow::ensure!(!args.frame.with_scene || args.frame.env_map, "--with-scene: only with --env-map (a view shows the scene unless --no-scene)");
    let mut options = RenderOptions { scene: !args.frame.no_scene, strategy: strategy_from_args(&args.frame, &headless.ctx)?, ..Default::default() };
    if args.frame.env_map {
        options = options.for_environment_map(args.frame.with_scene && !args.frame.no_scene);
    }
    let mut input = input;
    input.sky_model = model_override(sky, &args.frame)?;
    let frame = sky.evaluate(&input);
    for o in &frame.objects {
        if let Err(why) = &o.versions {
            log::info!("hidden: {} ({why})", sky.objects[o.index].name);
        }
    }
    use skytune::files::export::{self, Format};
    let ext = args.out.extension().map(|e| e.to_string_lossy().to_ascii_lowercase());
    let format = match (args.format, ext.as_deref()) {
        (Some(cli::ExportFormat::Png), _) | (None, Some("png")) | (None, None) => Format::Png,
        (Some(cli::ExportFormat::Exr), _) | (None, Some("exr")) => Format::Exr,
        (Some(cli::ExportFormat::Hdr), _) | (None, Some("hdr")) => Format::Hdr,
        (None, Some(other)) => bail!("--out: unknown image extension \".{other}\"; use .png, .exr or .hdr, or give --format"),
    };
    let about = format!("sky \"{}\", hour {}, weather {}, tier {}", sky.name, input.hour, input.weather, input.tier.stages());
    if let Some(projection) = args.projection {
        anyhow::ensure!(args.frame.env_map, "--projection: only with --env-map (an environment map shows the objects marked visible_in_env_map)");
        let (w, h) = cli::parse_size(&args.size)?;
        match projection {
            cli::Projection::Cube => {
                let faces = export::cube_faces(headless, sky, &input, &options, h, format.linear())?;
                for ((suffix, _, _), face) in export::CUBE_FACES.iter().zip(&faces) {
                    let path = export::face_path(&args.out, suffix, format);
                    export::save(face, format, &path)?;
                    println!("wrote {} ({h}x{h} cube face, {about})", path.display());
                }
            }
            cli::Projection::Equirect => {
                // Faces a little sharper than the map's texels at the equator.
                let face = (w / 4).clamp(16, 2048);
                let faces = export::cube_faces(headless, sky, &input, &options, face, format.linear())?;
                let map = export::equirect_from_cube(&faces, w, h);
                export::save(&map, format, &args.out)?;
                println!("wrote {} ({w}x{h} equirectangular, {about})", args.out.display());
            }
        }
        return Ok(());
    }
    // PNG: the display image as rendered; EXR and HDR: linear light read back from the frame.
    let (w, h) = if format.linear() {
        let image = export::render_linear(headless, sky, &input, &camera, &options)?;
        export::save(&image, format, &args.out)?;
        image.dimensions()
    } else {
        let image = headless.render(sky, &input, &camera, &options)?;
        skytune::support::safe_write::save_png(&image, &args.out)?;
        image.dimensions()
    };
    println!("wrote {} ({w}x{h}, {about})", args.out.display());
    Ok(())
}

/// `skytune soak`: runs, prints progress and the verdict, writes the report and the plot.
fn soak(args: &cli::SoakArgs) -> anyhow::Result<()> {
    let settings = skytune::measure::soak::SoakSettings {
        frames: args.frames,
        size: cli::parse_size(&args.size)?,
        seed: args.seed,
        max_growth: args.max_growth_percent / 100.0,
        max_rss_growth: args.max_rss_growth_percent.unwrap_or(args.max_growth_percent) / 100.0,
        warm_up_frames: args.warm_up_frames.unwrap_or(args.frames / 4),
        sky_dir: args.sky_dir.clone(),
    };
    let ctx = GpuContext::headless(adapter(args.cpu))?;
    println!("adapter: {}", ctx.adapter_line());
    let report = skytune::measure::soak::run(ctx, &settings, |s| {
        println!(
            "frame {:>6}: resident {:>7.1} MiB, GPU {} buffers {} textures {:.1} MiB",
            s.frame,
            s.rss_bytes as f64 / 1048576.0,
            s.gpu_buffers,
            s.gpu_textures,
            s.gpu_bytes as f64 / 1048576.0
        )
    })?;
    skytune::measure::soak::require_samples(&report)?;
    if let Some(plot) = &args.plot {
        report.plot_svg(plot)?;
        println!("wrote {}", plot.display());
    }
    let plot_link = match (&args.plot, &args.report) {
        (Some(p), Some(r)) => Some(p.strip_prefix(r.parent().unwrap_or(Path::new(""))).unwrap_or(p).display().to_string()),
        _ => None,
    };
    let md = report.markdown(&settings, plot_link.as_deref());
    if let Some(path) = &args.report {
        // The report may hold other, hand-written sections: only the soak's is replaced.
        let existing = std::fs::read_to_string(path).unwrap_or_default();
        skytune::support::safe_write::write_atomic(path, skytune::measure::soak::splice_section(&existing, &md).as_bytes())?;
        println!("wrote {}", path.display());
    }
    println!(
        "soak: {} frames in {:.0} s; growth after warm-up: resident {:+.2}%, GPU memory {:+.2}%, GPU objects {:+.2}%; reloads {} good, {} broken, {} shader",
        settings.frames,
        report.seconds,
        report.rss_growth * 100.0,
        report.gpu_growth * 100.0,
        report.gpu_object_growth * 100.0,
        report.good_reloads,
        report.broken_reloads,
        report.shader_reloads
    );
    report.verdict(&settings).map_err(|e| anyhow!("soak failed:\n{e}"))
}

/// The sky model the frame arguments ask for instead of the sky file's, if they ask.
fn model_override(sky: &Sky, f: &cli::FrameArgs) -> anyhow::Result<Option<skytune::sky::resolved::SkyModel>> {
    if f.sky_model.is_none() && f.exposure_ev.is_none() && !f.auto_exposure && !f.drive_scene {
        return Ok(None);
    }
    let mut model = sky.model;
    if let Some(kind) = f.sky_model {
        model.kind = kind;
    }
    model.drive_scene |= f.drive_scene;
    if f.auto_exposure {
        model.camera.auto_exposure = true;
        model.camera.exposure_ev = 0.0;
    }
    if let Some(ev) = f.exposure_ev {
        anyhow::ensure!(ev.is_finite(), "--exposure-ev: expected a finite number of stops");
        model.camera.exposure_ev = ev;
    }
    Ok(Some(model))
}

/// `skytune compare`: renders both sides, prints the figures, writes the picture.
fn compare(args: &cli::CompareArgs) -> anyhow::Result<()> {
    use skytune::measure::image_diff::{self, Layout, SideSpec};
    let sides: [SideSpec; 2] = [args.a.parse()?, args.b.parse()?];
    let layout = Layout::ALL.into_iter().find(|l| l.name() == args.layout).ok_or_else(|| anyhow!("--layout: expected side, split or diff, found \"{}\"", args.layout))?;
    anyhow::ensure!(args.split.is_finite(), "--split: expected a number in 0..1");
    let (w, h) = cli::parse_size(&args.size)?;
    let ctx = GpuContext::headless(adapter(args.frame.cpu))?;
    println!("adapter: {}", ctx.adapter_line());
    let options = RenderOptions { scene: !args.frame.no_scene, glare: !args.no_glare, strategy: strategy_from_args(&args.frame, &ctx)?, ..Default::default() };
    let mut images = Vec::new();
    for (label, side) in ["A", "B"].iter().zip(&sides) {
        let path = side.sky.as_deref().or(args.sky.as_deref());
        let sky = spec_for(path, side.season.as_deref().or(args.frame.season.as_deref()))?.load().map_err(|e| anyhow!("side {label}: {e}"))?;
        let (mut input, camera) = frame_from_args(&args.frame)?;
        input.sky_model = model_override(&sky, &args.frame)?;
        if let Some(hour) = side.hour {
            // As `skytune render --hour`: the panners' game time is the hour.
            input.hour = hour;
            input.game_hours = hour as f64;
        }
        input.weather = side.weather.unwrap_or(input.weather);
        if let Some(t) = side.tier {
            input.tier = Tier::new(t).ok_or_else(|| anyhow!("side {label}: tier {t}"))?;
        }
        if side.model.is_some() || side.exposure_ev.is_some() {
            let mut model = input.sky_model.unwrap_or(sky.model);
            model.kind = side.model.unwrap_or(model.kind);
            model.camera.exposure_ev = side.exposure_ev.unwrap_or(model.camera.exposure_ev);
            input.sky_model = Some(model);
        }
        let mut headless = Headless::new(ctx.clone(), w, h)?;
        headless.set_sky(&sky)?;
        let model = input.sky_model.unwrap_or(sky.model).kind;
        images.push(headless.render(&sky, &input, &camera, &options)?);
        println!("{label}: sky \"{}\" ({}), hour {}, weather {}, tier {}, model {}", sky.name, sky.source_name, input.hour, input.weather, input.tier.stages(), model.name());
    }
    let diff = image_diff::difference(&images[0], &images[1], args.tolerance);
    let picture = image_diff::compose(&images[0], &images[1], &diff, layout, args.split);
    skytune::support::safe_write::save_png(&picture, &args.out)?;
    println!("{}", diff.summary());
    println!("wrote {} ({})", args.out.display(), layout.name());
    if let Some(limit) = args.max_flip_mean {
        anyhow::ensure!(diff.flip.mean <= limit, "FLIP mean {:.4} is above --max-flip-mean {limit}", diff.flip.mean);
    }
    if let Some(limit) = args.max_differing {
        anyhow::ensure!(diff.pixels.differing <= limit, "{:.4} of pixels differ, above --max-differing {limit}", diff.pixels.differing);
    }
    Ok(())
}

fn render(args: &RenderArgs) -> anyhow::Result<()> {
    let spec = spec_for(args.sky.as_deref(), args.frame.season.as_deref())?;
    let mut sky = spec.load().map_err(|e| anyhow!("{e}"))?;
    let (w, h) = cli::parse_size(&args.size)?;
    let ctx = GpuContext::headless(adapter(args.frame.cpu))?;
    println!("adapter: {}", ctx.adapter_line());
    if let Some(pick) = skytune::support::progress::run_reported("auto model", |job| skytune::measure::auto_model::resolve(&mut sky, &ctx, job))? {
        println!("{}", pick.describe());
    }
    let mut headless = Headless::new(ctx, w, h)?;
    headless.set_sky(&sky)?;
    render_to_file(&mut headless, &sky, args)
}

fn check(path: &Path) -> anyhow::Result<()> {
    if skytune::sky::load::is_continent_file(path) {
        let c = skytune::sky::load::load_continent(path).map_err(|e| anyhow!("{e}"))?;
        println!("continent \"{}\"", c.name);
        let mut failed = false;
        for (season, sky) in skytune::sky::load::SEASONS.iter().zip(&c.skies) {
            match skytune::sky::load_sky_file(sky) {
                Ok(s) => {
                    println!("  {season}: {} -> \"{}\" ok", sky.display(), s.name);
                    for w in &s.warnings {
                        println!("  warning: {w}");
                    }
                }
                Err(e) => {
                    println!("  {season}: {} has errors:\n{e}", sky.display());
                    failed = true;
                }
            }
        }
        if failed {
            bail!("{} has invalid skies", path.display());
        }
        return Ok(());
    }
    let sky = skytune::sky::load_sky_file(path).map_err(|e| anyhow!("{e}"))?;
    print!("{}", summary(&sky));
    for w in &sky.warnings {
        println!("warning: {w}");
    }
    if let Some(budget) = sky.auto_model {
        let ctx = GpuContext::headless(AdapterChoice::from_env())?;
        let pick = skytune::support::progress::run_reported("auto model", |job| skytune::measure::auto_model::pick_cached(&sky, budget, &ctx, job))?;
        println!("  {}", pick.describe());
        println!("  measured at sun elevations {:?} degrees, over {} weather step(s)", pick.suns_deg, skytune::measure::auto_model::sky_atmospheres(&sky).len());
    }
    Ok(())
}

/// A human-readable summary of a sky.
pub fn summary(sky: &Sky) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let _ = writeln!(s, "sky \"{}\" ({}): ok", sky.name, sky.source_name);
    let _ = writeln!(s, "  {} hours per day, weather steps: {}", sky.hours_per_day, if sky.weather_names.is_empty() { "-".into() } else { sky.weather_names.join(", ") });
    let _ = writeln!(s, "  {} paths, {} objects, {} bitmaps/textures", sky.paths.len(), sky.objects.len(), sky.watched_files.len());
    for o in &sky.objects {
        let stages = o.standard.stages.len();
        let fb: Vec<String> = o.fallback.iter().map(|v| v.stages.len().to_string()).collect();
        let _ = writeln!(
            s,
            "  [{:>2}] {:<16} {:?}, {} stage(s){}",
            o.priority,
            o.name,
            o.standard.shape,
            stages,
            if fb.is_empty() { String::new() } else { format!(", fallback versions with {} stage(s)", fb.join(" + ")) }
        );
    }
    for e in &sky.emitters {
        let on = match e.attach {
            skytune::sky::resolved::EmitterAttach::Camera => "the camera".to_string(),
            skytune::sky::resolved::EmitterAttach::Object(i) => format!("\"{}\"", sky.objects[i].name),
        };
        let _ = writeln!(s, "  emitter {}: on {on}, {:?}, {} per s for {} s, at most {} particles", e.name, e.kind, e.rate, e.lifetime_s, e.max_particles);
    }
    if let Some(st) = &sky.stars {
        let source = match st.source {
            skytune::sky::model::StarSource::Catalogue => "the Bright Star Catalogue".to_string(),
            skytune::sky::model::StarSource::Procedural => format!("{} generated", st.count),
        };
        let _ = writeln!(s, "  stars: {source}, magnitude cutoff {}", st.magnitude_cutoff);
    }
    if let Some(g) = &sky.glare {
        let _ = writeln!(s, "  glare: halo {} deg, {} flare sprites, persistence {} s", g.halo_size_deg, g.flares.len(), g.persistence_s);
    }
    s
}

fn watch(args: &RenderArgs, max_reloads: Option<u32>) -> anyhow::Result<()> {
    let spec = spec_for(args.sky.as_deref(), args.frame.season.as_deref())?;
    let mut live = LiveSky::new(spec.clone()).map_err(|e| anyhow!("{e}"))?;
    let (w, h) = cli::parse_size(&args.size)?;
    let ctx = GpuContext::headless(adapter(args.frame.cpu))?;
    println!("adapter: {}", ctx.adapter_line());
    let mut headless = Headless::new(ctx, w, h)?;
    headless.set_sky(live.sky())?;
    render_to_file(&mut headless, live.sky(), args)?;
    println!("watching {} (Ctrl-C to stop)", spec.display());
    let mut reloads = 0;
    while max_reloads.is_none_or(|m| reloads < m) {
        match live.wait(Duration::from_millis(500)) {
            Some(ReloadEvent::Reloaded) => {
                reloads += 1;
                let sky = live.sky().clone();
                match headless.set_sky(&sky) {
                    Ok(()) => render_to_file(&mut headless, &sky, args)?,
                    Err(e) => eprintln!("GPU upload failed, keeping the previous image: {e:#}"),
                }
            }
            Some(ReloadEvent::Failed(e)) => {
                reloads += 1;
                eprintln!("reload failed; {} still shows the last good sky:\n{e}", args.out.display());
            }
            Some(ReloadEvent::Superseded) | None => {}
        }
    }
    Ok(())
}
