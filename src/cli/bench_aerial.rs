//! `skytune bench aerial`: what aerial perspective costs a frame. The built-in sky under `lut`
//! lighting the scene, at each view and time, drawn with the scene's old fog (`[aerial_perspective]
//! method = "fog"`), the default volume and the exact march, the three frames alternating with the
//! fill-rate floor in every strategy; and the volume's build alone at each size, against the same
//! floor. A Markdown report (docs/performance-notes.md takes its figures).

use std::fmt::Write as _;

use crate::cli::{self, AerialBenchArgs};
use skytune::atmosphere::aerial::{AerialMethod, AerialSettings};
use skytune::atmosphere::{Atmosphere, LutSettings};
use skytune::render::atmosphere::aerial_probe::AerialProbe;
use skytune::render::passes::baseline::Baseline;
use skytune::render::plan::strategy::PRESETS;
use skytune::render::{AdapterChoice, Camera, GpuContext, Headless, RenderOptions, ShaderLibrary, OFFSCREEN_FORMAT};
use skytune::sky::builtin::default_sky;
use skytune::sky::resolved::{SkyModel, SkyModelKind};
use skytune::sky::{FrameInput, Sky};

use super::bench_frame::{median, timed};

const METHODS: [AerialMethod; 3] = [AerialMethod::Fog, AerialMethod::Volume, AerialMethod::Exact];

fn sky_with(method: AerialMethod) -> Sky {
    let mut sky = default_sky();
    sky.model = SkyModel { kind: SkyModelKind::Lut, drive_scene: true, aerial: AerialSettings { method, ..Default::default() }, ..sky.model };
    sky
}

/// Runs the benchmark.
pub fn run(args: &AerialBenchArgs) -> anyhow::Result<()> {
    let (w, h) = cli::parse_size(&args.size)?;
    let ctx = GpuContext::headless(if args.cpu { AdapterChoice::Cpu } else { AdapterChoice::from_env() })?;
    let untimed = ctx.without_timestamps();
    let library = ShaderLibrary::embedded();
    let floor = Baseline::new(&ctx.device, &ctx.queue, &library, OFFSCREEN_FORMAT)?;
    let skies: Vec<Sky> = METHODS.iter().map(|&m| sky_with(m)).collect();
    let views = [("horizon", Camera { yaw_deg: 180.0, pitch_deg: 10.0, ..Camera::default() }), ("level", Camera { yaw_deg: 70.0, pitch_deg: 2.0, ..Camera::default() })];
    let times = [(12.0, 0.0), (17.0, 0.0)];
    let mut md = format!(
        "Measured by `skytune bench aerial` ({}, {}) on {}, {w}x{h}, {} frames a case after 2 of warm-up; the built-in sky under `lut` lighting the scene.\n\n",
        env!("CARGO_PKG_VERSION"),
        skytune::build_line(),
        ctx.adapter_line(),
        args.frames
    );
    let _ = writeln!(md, "| strategy | hour | view | floor ms | fog ms | volume ms | exact ms | volume / fog | exact / fog |");
    let _ = writeln!(md, "|---|---|---|---:|---:|---:|---:|---:|---:|");
    let mut ratios: Vec<(&str, f64, f64)> = Vec::new();
    for &(name, strategy) in PRESETS.iter().filter(|(n, _)| ["software", "plain"].contains(n)) {
        let options = RenderOptions { glare: false, strategy, ..Default::default() };
        let mut renderers: Vec<Headless> = skies.iter().map(|_| Headless::new(untimed.clone(), w, h)).collect::<Result<_, _>>()?;
        for (hl, sky) in renderers.iter_mut().zip(&skies) {
            hl.set_sky(sky)?;
        }
        for (hour, weather) in times {
            for (view, camera) in &views {
                let input = FrameInput::new(hour, weather);
                let frames: Vec<_> = skies.iter().map(|s| s.evaluate(&input)).collect();
                let mut samples = vec![Vec::new(); 1 + METHODS.len()];
                for i in 0..args.frames + 2 {
                    let target = renderers[0].target.target();
                    let f = timed(&ctx, |e| floor.record(e, target.color))?;
                    let mut row = vec![f];
                    for (hl, frame) in renderers.iter_mut().zip(&frames) {
                        let target = hl.target.target();
                        row.push(timed(&ctx, |e| hl.renderer.render(&ctx, e, &target, frame, camera, &options))?);
                        hl.renderer.after_submit();
                    }
                    if i >= 2 {
                        for (s, v) in samples.iter_mut().zip(row) {
                            s.push(v);
                        }
                    }
                }
                let pair = |k: usize| median(&samples[k].iter().zip(&samples[1]).map(|(a, b)| a / b).collect::<Vec<_>>());
                let m: Vec<f64> = samples.iter().map(|s| median(s)).collect();
                let (volume, exact) = (pair(2), pair(3));
                ratios.push((name, volume, exact));
                let _ = writeln!(md, "| {name} | {hour} | {view} | {:.2} | {:.2} | {:.2} | {:.2} | {volume:.3} | {exact:.3} |", m[0], m[1], m[2], m[3]);
            }
        }
    }
    let _ = writeln!(
        md,
        "\nRatios are medians of frame-by-frame ratios (each method's frame against the fog frame rendered just before it). Goal: the volume's frame at most 1.25x the fog's.\n"
    );
    for name in ["software", "plain"] {
        let r: Vec<&(&str, f64, f64)> = ratios.iter().filter(|r| r.0 == name).collect();
        let worst = r.iter().map(|r| r.1).fold(0.0, f64::max);
        let _ = writeln!(
            md,
            "- `{name}`: volume / fog worst {worst:.3}, median {:.3}; exact / fog median {:.3}",
            median(&r.iter().map(|r| r.1).collect::<Vec<_>>()),
            median(&r.iter().map(|r| r.2).collect::<Vec<_>>())
        );
    }

    // The volume's build alone, against the floor measured beside it.
    let probe = AerialProbe::new(&ctx, &library)?;
    let target = Headless::new(untimed.clone(), w, h)?;
    let _ = writeln!(md, "\n| volume | build ms | floor ms | build / floor |\n|---|---:|---:|---:|");
    let d = AerialSettings::default();
    for &size in &args.sizes {
        let settings = AerialSettings { volume_size: size, steps_per_slice: args.steps_per_slice.unwrap_or(d.steps_per_slice), ..d };
        settings.validate().map_err(|e| anyhow::anyhow!("--sizes: {}", e.message))?;
        let builds = probe.time_builds(&ctx, &Atmosphere::default(), &LutSettings::default(), &settings, args.frames + 2)?;
        let floors: Vec<f64> = (0..args.frames + 2).map(|_| timed(&ctx, |e| floor.record(e, target.target.target().color))).collect::<Result<_, _>>()?;
        let (b, f) = (median(&builds[2..]), median(&floors[2..]));
        let default = if settings == AerialSettings::default() { " (default)" } else { "" };
        let _ = writeln!(md, "| {}x{}x{}, {} samples a slice{default} | {b:.2} | {f:.2} | {:.3} |", size[0], size[1], size[2], settings.steps_per_slice, b / f);
    }
    let _ = writeln!(md, "\nGoal: the default volume's build at most 0.2x the floor (the build runs only when the camera, the sun or the atmosphere moves).");
    skytune::support::safe_write::write_atomic(&args.out, md.as_bytes())?;
    print!("{md}");
    Ok(())
}
