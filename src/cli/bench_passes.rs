//! `skytune bench`: measures the sky passes side by side in one run and writes a Markdown report.
//!
//! Configurations run in interleaved rounds (A B C ... A B C ...) so slow drifts of a noisy
//! machine hit all of them alike; medians are reported, with ratios taken within the same run.

use std::fmt::Write as _;
use std::time::Instant;

use anyhow::anyhow;

use crate::cli::{self, BenchArgs};
use skytune::render::plan::strategy::{RunJoining, UnderBackground};
use skytune::render::{AdapterChoice, Camera, FillStrategy, GpuContext, Headless, RenderOptions, Skips};
use skytune::sky::builtin::default_sky;
use skytune::sky::resolved::{SkyModel, SkyModelKind};
use skytune::sky::{FrameInput, Sky, Tier};

struct Config {
    name: String,
    camera: Camera,
    depth_split: bool,
    tier: Tier,
    /// Skydome colour source; with `sun_moves`, the sun moves every frame (the map is recomputed).
    model: SkyModelKind,
    sun_moves: bool,
    /// The renderer's skips (all on except where a configuration measures one).
    skips: Skips,
    /// Hour of the day ([`HOUR`] unless a configuration needs the night's stars).
    hour: f32,
    /// The fill strategy: `software` (the default) unless a configuration measures one of its
    /// choices.
    strategy: FillStrategy,
    wall_ms: Vec<f32>,
    scene_ms: Vec<f32>,
    sky_ms: Vec<f32>,
    compute_ms: Vec<f32>,
    display_ms: Vec<f32>,
}

fn median(v: &[f32]) -> f32 {
    if v.is_empty() {
        return f32::NAN;
    }
    let mut s = v.to_vec();
    s.sort_by(f32::total_cmp);
    s[s.len() / 2]
}

const HOUR: f32 = 16.0;
/// The configurations that need the night's stars.
const NIGHT: f32 = 23.0;
const WEATHER: f32 = 0.3;
const ROUNDS: u32 = 3;

/// Fraction of the screen covered by the main-scene stand-in from a camera.
fn scene_coverage(h: &mut Headless, sky: &Sky, camera: &Camera) -> anyhow::Result<f32> {
    let mut input = FrameInput::new(HOUR, WEATHER);
    input.disabled = sky.objects.iter().map(|o| o.name.clone()).collect();
    let img = h.render(sky, &input, camera, &RenderOptions { glare: false, ..Default::default() })?;
    let covered = img.pixels().filter(|p| p[0] as u32 + p[1] as u32 + p[2] as u32 > 0).count();
    Ok(covered as f32 / (img.width() * img.height()) as f32)
}

pub fn run(args: &BenchArgs) -> anyhow::Result<()> {
    let (w, h) = cli::parse_size(&args.size)?;
    let ctx = GpuContext::headless(if args.cpu { AdapterChoice::Cpu } else { AdapterChoice::from_env() })?;
    let adapter = ctx.adapter_line();
    let timestamps = ctx.timestamps;
    println!("adapter: {adapter}");
    let mut hl = Headless::new(ctx, w, h)?;
    let sky = default_sky();
    hl.set_sky(&sky)?;

    let down = Camera { yaw_deg: 180.0, pitch_deg: -38.0, ..Camera::default() };
    let up = Camera { yaw_deg: 180.0, pitch_deg: 40.0, ..Camera::default() };
    let horizon = Camera { yaw_deg: 180.0, pitch_deg: 10.0, ..Camera::default() };
    let cover_down = scene_coverage(&mut hl, &sky, &down)?;
    let cover_up = scene_coverage(&mut hl, &sky, &up)?;

    let mk = |name: &str, camera: Camera, depth_split: bool, tier: u8| Config {
        name: name.to_string(),
        camera,
        depth_split,
        tier: Tier::new(tier).expect("valid tier"),
        model: SkyModelKind::Bitmap,
        sun_moves: false,
        skips: Skips::default(),
        hour: HOUR,
        strategy: FillStrategy::software(),
        wall_ms: Vec::new(),
        scene_ms: Vec::new(),
        sky_ms: Vec::new(),
        compute_ms: Vec::new(),
        display_ms: Vec::new(),
    };
    let with_model = |c: Config, model: SkyModelKind, sun_moves: bool| Config { model, sun_moves, ..c };
    let mut configs = vec![
        mk("scene covers the screen, depth split", down, true, 4),
        mk("scene covers the screen, no split", down, false, 4),
        mk("sky fills the screen, depth split", up, true, 4),
        mk("sky fills the screen, no split", up, false, 4),
        mk("sky fills the screen, tier 2 (fallbacks)", up, true, 2),
        mk("sky fills the screen, tier 1", up, true, 1),
        with_model(mk("sky fills the screen, single model, sun still (map reused)", up, true, 4), SkyModelKind::Single, false),
        with_model(mk("sky fills the screen, single model, sun moving (map every frame)", up, true, 4), SkyModelKind::Single, true),
        with_model(mk("sky fills the screen, lut model, sun still (map reused)", up, true, 4), SkyModelKind::Lut, false),
        with_model(mk("sky fills the screen, lut model, sun moving (map every frame)", up, true, 4), SkyModelKind::Lut, true),
        with_model(mk("sky fills the screen, preetham model, sun moving (map every frame)", up, true, 4), SkyModelKind::Preetham, true),
        with_model(mk("sky fills the screen, hosek model, sun moving (map every frame)", up, true, 4), SkyModelKind::Hosek, true),
        with_model(mk("sky fills the screen, linear model, sun moving (map every frame)", up, true, 4), SkyModelKind::Linear, true),
        // Each skip switched off alone, against the same frame with every skip (configurations 2 and 8).
        Config { skips: Skips { dark_stages: false, ..Skips::default() }, ..mk("sky fills the screen, black stages sampled (skip off)", up, true, 4) },
        Config { skips: Skips { invisible_stars: false, ..Skips::default() }, ..mk("sky fills the screen, transparent stars drawn (skip off)", up, true, 4) },
        Config {
            skips: Skips { unchanged_tables: false, ..Skips::default() },
            ..with_model(mk("sky fills the screen, lut model, sun still, tables and map rebuilt (skip off)", up, true, 4), SkyModelKind::Lut, false)
        },
        Config { skips: Skips { off_screen: false, ..Skips::default() }, ..mk("sky fills the screen, dome layers and rows out of view drawn (skip off)", up, true, 4) },
        Config { skips: Skips { unneeded_mips: false, ..Skips::default() }, ..mk("sky fills the screen, every stage mipmapped (skip off)", up, true, 4) },
        // The scene in view: what lies behind it.
        mk("horizon", horizon, true, 4),
        Config { skips: Skips { below_horizon: false, ..Skips::default() }, ..mk("horizon, billboards and dome rows behind the scene drawn (skip off)", horizon, true, 4) },
        // The night's additive draws (the skydome's fine stars, the star field) under the background.
        Config { hour: NIGHT, ..mk("night, sky fills the screen", up, true, 4) },
        Config {
            hour: NIGHT,
            strategy: FillStrategy { under_background: UnderBackground::Nothing, ..FillStrategy::software() },
            ..mk("night, sky fills the screen, additive draws in the sky phase (nothing under the background)", up, true, 4)
        },
        Config {
            hour: NIGHT,
            strategy: FillStrategy { under_background: UnderBackground::Additive, ..FillStrategy::software() },
            ..mk("night, sky fills the screen, background composited over the additive draws (additive draws under it, none fused)", up, true, 4)
        },
        // The joined runs' combination: the second run's buffer seeded with the first, or a pass of its own.
        Config {
            strategy: FillStrategy { runs: RunJoining::Combined, ..FillStrategy::software() },
            ..mk("sky fills the screen, joined runs combined in a pass of their own (runs joined, not seeded)", up, true, 4)
        },
        Config { skips: Skips { covered_clears: false, ..Skips::default() }, ..mk("sky fills the screen, frame cleared under the background (skip off)", up, true, 4) },
    ];
    let per_round = args.frames.div_ceil(ROUNDS).max(1);
    for round in 0..ROUNDS {
        for c in configs.iter_mut() {
            let mut input = FrameInput::new(c.hour, WEATHER);
            input.tier = c.tier;
            input.sky_model = Some(SkyModel { kind: c.model, ..sky.model });
            let options = RenderOptions { depth_split: c.depth_split, glare: false, skips: c.skips, strategy: c.strategy, ..Default::default() };
            // Two warm-up frames: pipelines, caches and the timestamp readback of this configuration.
            for i in 0..per_round + 2 {
                if c.sun_moves {
                    input.hour = c.hour + 0.01 * i as f32;
                }
                let t = Instant::now();
                hl.frame(&sky, &input, &c.camera, &options, 0.0);
                hl.ctx.wait_idle()?;
                let wall = t.elapsed().as_secs_f32() * 1000.0;
                if i >= 2 {
                    c.wall_ms.push(wall);
                    // Times of the previous frame of this same configuration.
                    for (pass, ms) in hl.renderer.gpu_pass_ms() {
                        match *pass {
                            "scene" => c.scene_ms.push(*ms),
                            "sky" => c.sky_ms.push(*ms),
                            "compute" => c.compute_ms.push(*ms),
                            "display" => c.display_ms.push(*ms),
                            _ => {}
                        }
                    }
                }
            }
        }
        println!("round {}/{ROUNDS} done", round + 1);
    }

    let mut md = String::new();
    let _ = writeln!(md, "# Benchmarks\n");
    let _ = writeln!(md, "Written by `skytune bench` (`cargo run --release -- bench`); re-run it to refresh this file.\n");
    let _ = writeln!(md, "- adapter: {adapter}");
    let _ = writeln!(
        md,
        "- machine: {} logical CPUs; {} build of skytune; image {w}x{h}; built-in sky at hour {HOUR}, weather {WEATHER}; glare off",
        std::thread::available_parallelism().map_or(0, |n| n.get()),
        if cfg!(debug_assertions) { "debug" } else { "release" }
    );
    let _ =
        writeln!(md, "- method: {ROUNDS} interleaved rounds x {per_round} frames per configuration (2 warm-up frames dropped each round); each frame is submitted and waited for.");
    let _ = writeln!(
        md,
        "  Wall = submit to GPU idle (on lavapipe this is the rasterisation itself). GPU = timestamp queries around each pass{}.",
        if timestamps { "" } else { " (not supported by this adapter: columns empty)" }
    );
    let _ =
        writeln!(md, "- scene coverage (fraction of pixels covered by the main-scene stand-in): looking down {:.1}%, looking up {:.1}%\n", cover_down * 100.0, cover_up * 100.0);
    let _ = writeln!(md, "| configuration | frame wall ms (median) | compute phase GPU ms | scene phase GPU ms | sky phase GPU ms | display phase GPU ms | frames |");
    let _ = writeln!(md, "|---|---:|---:|---:|---:|---:|---:|");
    let optional = |v: &[f32]| if v.is_empty() { "-".to_string() } else { format!("{:.2}", median(v)) };
    for c in &configs {
        let (compute, display) = (optional(&c.compute_ms), optional(&c.display_ms));
        let _ = writeln!(md, "| {} | {:.2} | {compute} | {:.2} | {:.2} | {display} | {} |", c.name, median(&c.wall_ms), median(&c.scene_ms), median(&c.sky_ms), c.wall_ms.len());
    }
    let ratio = |a: usize, b: usize| median(&configs[a].wall_ms) / median(&configs[b].wall_ms);
    let sky_ratio = |a: usize, b: usize| median(&configs[a].sky_ms) / median(&configs[b].sky_ms);
    let _ = writeln!(md, "\n## What it shows\n");
    let _ = writeln!(
        md,
        "- Depth-range split with the scene covering {:.0}% of the screen: the whole frame takes {:.2}x the time of the same frame without the split \
         (sky pass alone: {:.2} ms with the split; without it the sky pass also draws the scene, so compare whole frames).",
        cover_down * 100.0,
        ratio(0, 1),
        median(&configs[0].sky_ms)
    );
    let _ = writeln!(md, "- Sky pass with the split, scene covering {:.0}% vs {:.0}% of the screen: {:.2}x.", cover_down * 100.0, cover_up * 100.0, sky_ratio(0, 2));
    let _ = writeln!(md, "- With the sky filling the screen (almost nothing for the split to reject): split / no split = {:.2}x.", ratio(2, 3));
    // Most of a sky frame is drawn before the sky phase (the reduced buffers, the background in
    // the scene's pass), so tiers compare whole frames.
    let _ = writeln!(md, "- Tier 2 fallbacks vs tier 4, whole frame: {:.2}x; tier 1 vs tier 4: {:.2}x.", ratio(4, 2), ratio(5, 2));
    let _ = writeln!(
        md,
        "- Physical sky models with the sky filling the screen, frame time relative to the bitmap sky: `single` {:.2}x with the sun still (the sky-view map is reused) and {:.2}x with the sun moving every frame; `lut` {:.2}x and {:.2}x (its tables are built once; only the map follows the sun). \
         These frames draw into the HDR target and add the display phase (tone mapping into the display target).",
        ratio(6, 2),
        ratio(7, 2),
        ratio(8, 2),
        ratio(9, 2)
    );
    let compute = |i: usize| optional(&configs[i].compute_ms);
    let _ = writeln!(
        md,
        "- The sky-view map of each model with the sun moving (compute phase, GPU ms, same run): `single` {}, `lut` {}, `preetham` {}, `hosek` {}, `linear` {}; \
         frame time relative to the bitmap sky: `preetham` {:.2}x, `hosek` {:.2}x, `linear` {:.2}x.",
        compute(7),
        compute(9),
        compute(10),
        compute(11),
        compute(12),
        ratio(10, 2),
        ratio(11, 2),
        ratio(12, 2)
    );
    let saving = |off: usize, on: usize| median(&configs[off].wall_ms) - median(&configs[on].wall_ms);
    let _ = writeln!(
        md,
        "- What each skip saves (frame wall ms with the skip off minus with it on, same run): black texture stages not sampled {:.2} ms; transparent stars not drawn {:.2} ms; \
         unchanged lut tables and sky-view map not rebuilt {:.2} ms (the skip off rebuilds both every frame; compute phase {} ms). Objects hidden by their ref colour this frame: {} (not drawn at all; the app's stats panel counts every skip per frame and measures them live).",
        saving(13, 2),
        saving(14, 2),
        saving(15, 8),
        optional(&configs[15].compute_ms),
        {
            let mut input = FrameInput::new(HOUR, WEATHER);
            input.tier = Tier::FOUR;
            sky.evaluate(&input).objects.iter().filter(|o| matches!(o.versions, Err(skytune::sky::Hidden::RefAlphaZero(_)))).count()
        }
    );
    let _ = writeln!(
        md,
        "- More skips and options, the same way: dome layers and rows of dome triangles out of view not drawn {:.2} ms; stages that no pixel minifies sampled from level 0 {:.2} ms \
         (sky filling the screen); billboards and dome rows behind the scene not drawn {:.2} ms (horizon); the night's additive draws put under the background (`UnderBackground::Additive`) {:.2} ms (night, sky filling the screen, hour {NIGHT}); \
         the skydome's fine stars drawn as the background (`UnderBackground::AdditiveFused`) {:.2} ms (the same night frame); \
         the second joined run's buffer seeded with the first instead of a combining pass (`RunJoining::Seeded`) {:.2} ms (sky filling the screen); \
         the frame's colour not cleared under the background (`covered_clears`; the scene is drawn, so its depth is cleared) {:.2} ms (sky filling the screen).",
        saving(16, 2),
        saving(17, 2),
        saving(19, 18),
        saving(21, 20),
        saving(22, 20),
        saving(23, 2),
        saving(24, 2)
    );
    skytune::support::safe_write::write_atomic(&args.out, md.as_bytes())?;
    print!("{md}");
    println!("\nwrote {}", args.out.display());
    if configs.iter().any(|c| c.wall_ms.is_empty()) {
        return Err(anyhow!("a configuration recorded no frames"));
    }
    Ok(())
}
