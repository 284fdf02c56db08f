//! `skytune sweep`: runs the stability sweep of every model and writes docs/stability.md; with
//! `--shard K/N`, one shard's counts as TOML, which `skytune merge` turns into the report.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::Context as _;
use serde::{Deserialize, Serialize};

use crate::cli::SweepArgs;
use skytune::measure::model_points::Evaluator;
use skytune::measure::stability::{self, Counters, SweptModel, WORST_KEPT};
use skytune::render::{AdapterChoice, GpuContext};
use skytune::support::shard::Shard;

/// One model's counts in a report: a run's, or the sum of shards'.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
struct ModelCounts {
    name: String,
    evaluated: u64,
    nan: u64,
    infinite: u64,
    negative: u64,
    discontinuous: u64,
    refused: u64,
    seconds: f64,
    /// (batch, report line) of the first failing cases.
    worst: Vec<(usize, String)>,
}

impl ModelCounts {
    fn new(model: SweptModel, c: &Counters, seconds: f64) -> Self {
        Self {
            name: model.name().into(),
            evaluated: c.evaluated,
            nan: c.nan,
            infinite: c.infinite,
            negative: c.negative,
            discontinuous: c.discontinuous,
            refused: c.refused,
            seconds,
            worst: c.worst.iter().map(|w| (w.batch, w.line())).collect(),
        }
    }

    fn failures(&self) -> u64 {
        self.nan + self.infinite + self.negative + self.discontinuous + self.refused
    }
}

/// What one shard writes.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct SweepPart {
    /// Always [`PART_KIND`].
    kind: String,
    shard: String,
    count: usize,
    seed: u64,
    adapter: String,
    seconds: f64,
    models: Vec<ModelCounts>,
}

const PART_KIND: &str = "skytune sweep shard";

/// Whether `text` is a sweep shard's file.
pub fn is_sweep_part(text: &str) -> bool {
    text.lines().next().is_some_and(|l| l.trim() == format!("kind = \"{PART_KIND}\""))
}

pub fn run(args: &SweepArgs) -> anyhow::Result<()> {
    anyhow::ensure!(args.count >= 1, "--count: expected at least 1");
    let shard = args.shard.unwrap_or(Shard::WHOLE);
    if !shard.is_whole() {
        anyhow::ensure!(
            args.out.extension().is_some_and(|e| e == "toml"),
            "--out: a shard writes its counts as TOML (for `skytune merge`), so name a .toml file, found {}",
            args.out.display()
        );
        // A complete part of the same shard, count, seed and models is not computed again.
        let done = std::fs::read_to_string(&args.out).ok().and_then(|t| toml::from_str::<SweepPart>(&t).ok());
        if let Some(part) = done.filter(|p| {
            (p.kind.as_str(), p.shard.as_str(), p.count, p.seed) == (PART_KIND, shard.to_string().as_str(), args.count, args.seed)
                && SweptModel::ALL.iter().all(|m| p.models.iter().any(|c| c.name == m.name()))
        }) {
            println!("{}: shard {shard} is complete already (the same --count and --seed); skipped", args.out.display());
            return fail_on_shipped(&part.models);
        }
    }
    let started = std::time::Instant::now();
    let ctx = GpuContext::headless(if args.cpu { AdapterChoice::Cpu } else { AdapterChoice::from_env() })?;
    let ev = Evaluator::new(&ctx)?;
    let mut results: Vec<ModelCounts> = Vec::new();
    for model in SweptModel::ALL {
        let bar = skytune::support::progress::Reporter::new(args.count as u64, model.name());
        let t = std::time::Instant::now();
        let counters = stability::sweep(&ev, model, args.count, args.seed, shard, &mut |n| bar.inc(n as u64))?;
        bar.finish();
        println!(
            "{:<36} {:>8} sets: NaN {} inf {} negative {} jumps {} refused {}",
            model.name(),
            counters.evaluated,
            counters.nan,
            counters.infinite,
            counters.negative,
            counters.discontinuous,
            counters.refused
        );
        results.push(ModelCounts::new(model, &counters, t.elapsed().as_secs_f64()));
    }
    let text = if shard.is_whole() {
        report(args.count, args.seed, &ctx.adapter_line(), &results, started.elapsed().as_secs_f64(), None)
    } else {
        let part = SweepPart {
            kind: PART_KIND.into(),
            shard: shard.to_string(),
            count: args.count,
            seed: args.seed,
            adapter: ctx.adapter_line(),
            seconds: started.elapsed().as_secs_f64(),
            models: results.clone(),
        };
        toml::to_string(&part).context("writing the shard's counts")?
    };
    skytune::support::safe_write::write_atomic(&args.out, text.as_bytes())?;
    println!("wrote {}", args.out.display());
    fail_on_shipped(&results)
}

/// An error naming the shipped models that failed.
fn fail_on_shipped(results: &[ModelCounts]) -> anyhow::Result<()> {
    let failing: Vec<&str> = results.iter().filter(|c| c.failures() > 0 && SweptModel::ALL.iter().any(|m| m.name() == c.name && m.shipped())).map(|c| c.name.as_str()).collect();
    anyhow::ensure!(failing.is_empty(), "shipped models failed the sweep: {}", failing.join(", "));
    Ok(())
}

/// The report of a sweep run in shards: counts summed, the first failing cases of the whole.
pub fn merge(parts: &[(String, String)], out: &Path) -> anyhow::Result<()> {
    let mut read: Vec<SweepPart> = Vec::new();
    for (file, text) in parts {
        let part: SweepPart = toml::from_str(text).map_err(|e| anyhow::anyhow!("{file}: {e}"))?;
        let shard = Shard::parse(&part.shard).with_context(|| format!("{file}: shard"))?;
        if let Some(first) = read.first() {
            anyhow::ensure!(
                (part.count, part.seed, Shard::parse(&first.shard)?.count) == (first.count, first.seed, shard.count),
                "{file}: shard {} of --count {} --seed {} does not fit with {}'s {} of --count {} --seed {}",
                part.shard,
                part.count,
                part.seed,
                parts[0].0,
                first.shard,
                first.count,
                first.seed
            );
        }
        anyhow::ensure!(!read.iter().any(|p| p.shard == part.shard), "{file}: shard {} again", part.shard);
        read.push(part);
    }
    let first = read.first().context("merge: no shards")?;
    let count = Shard::parse(&first.shard)?.count;
    anyhow::ensure!(read.len() == count, "{} of {count} sweep shards given", read.len());
    let mut models: Vec<ModelCounts> = Vec::new();
    for m in &first.models {
        let mut sum = ModelCounts { worst: Vec::new(), seconds: 0.0, evaluated: 0, nan: 0, infinite: 0, negative: 0, discontinuous: 0, refused: 0, ..m.clone() };
        for p in &read {
            let c = p.models.iter().find(|c| c.name == m.name).with_context(|| format!("shard {} has no {}", p.shard, m.name))?;
            sum.evaluated += c.evaluated;
            sum.nan += c.nan;
            sum.infinite += c.infinite;
            sum.negative += c.negative;
            sum.discontinuous += c.discontinuous;
            sum.refused += c.refused;
            sum.seconds += c.seconds;
            sum.worst.extend(c.worst.iter().cloned());
        }
        // Each shard kept its first cases in the order of the sets: the first of the whole are among them.
        sum.worst.sort_by_key(|(batch, _)| *batch);
        sum.worst.truncate(WORST_KEPT);
        models.push(sum);
    }
    let seconds = read.iter().map(|p| p.seconds).sum();
    let md = report(first.count, first.seed, &first.adapter, &models, seconds, Some(count));
    skytune::support::safe_write::write_atomic(out, md.as_bytes())?;
    println!("wrote {} from {count} shards", out.display());
    fail_on_shipped(&models)
}

/// The Markdown report; `shards`: how many shards the counts were summed from.
fn report(count: usize, seed: u64, adapter: &str, results: &[ModelCounts], seconds: f64, shards: Option<usize>) -> String {
    let mut md = String::new();
    let _ = writeln!(md, "# Stability of the sky models\n");
    let how = shards.map_or_else(String::new, |n| format!(" in {n} shards (`--shard K/{n}`, combined by `skytune merge`; seconds summed over the shards)"));
    let _ =
        writeln!(md, "Written by `skytune sweep --count {count} --seed {seed}`{how} in {seconds:.0} s on {adapter}, {}; re-run it to refresh this file.\n", skytune::build_line());
    let _ = writeln!(md, "## Method\n");
    let _ = writeln!(
        md,
        "Each model gets {} random parameter sets (`src/measure/stability.rs`), across and beyond its domain:\n\n\
         - atmospheres from a thousandth to 30 times the default's coefficients, aerosols from 1% to 30 times, Mie g from -0.95 to 0.95, thickness 10 to 400 km, planets of 100 to 100,000 km radius (30% of atmospheres; f32 cancellation in ray-sphere intersection), one atmosphere per 1,000 sets (5,000 for `cells`, solved per atmosphere);\n\
         - the camera on the ground (40%), inside the atmosphere (40%) or up to twice its thickness above its top (20%);\n\
         - the sun from -18 degrees (astronomical night) to 90, half of the sets within 3 degrees of the horizon (where the erf optical depth crosses its regime boundary b = 7 sqrt(a) and b turns negative, and where the LUT parameterisation is tightest);\n\
         - views all round, half within 5 degrees of the horizon, rays into the ground included; ground albedo 0..1; turbidity 0.5..15 for `preetham` and `hosek` (beyond 1.3..10).\n\n\
         Each set is evaluated three times, with the sun moved by -{d}, 0 and +{d} degrees. Counted: results with a NaN, an infinite or a negative channel, and jumps: a step that changes a channel by more than {} of the brightest channel of the three results plus {:e} sr^-1, and by more than {} times the other step, and whose change, re-evaluated in {} sub-steps plus one on either side, happens within one sub-step for more than half and is more than that ratio times each neighbouring sub-step (a discontinuity stays in one sub-step; a kink, even a clamp at 0, or a steep smooth change, as a twilight on a small planet, continues into its neighbours). GPU models run on the GPU through the radiance probe, as they ship.\n",
        count,
        stability::JUMP_RELATIVE,
        stability::JUMP_FLOOR_SR,
        stability::JUMP_STEP_RATIO,
        stability::JUMP_REFINE,
        d = stability::JUMP_DELTA_DEG
    );
    let _ = writeln!(md, "## Counts\n");
    let _ = writeln!(md, "| model | sets | NaN | infinite | negative | jumps | refused | seconds |");
    let _ = writeln!(md, "|---|---:|---:|---:|---:|---:|---:|---:|");
    for c in results {
        let _ = writeln!(md, "| {} | {} | {} | {} | {} | {} | {} | {:.1} |", c.name, c.evaluated, c.nan, c.infinite, c.negative, c.discontinuous, c.refused, c.seconds);
    }
    let _ = writeln!(md, "\n## Where the published models fail, and what skytune ships\n");
    let _ = writeln!(
        md,
        "- **Preetham** (row `preetham, published fit unclamped`: the paper's fit at the swept turbidity and the real sun elevation, luminance and chromaticity to XYZ without any clamp). Below a turbidity of about 1.3 the zenith luminance fit goes negative, and with the sun below the horizon the (4/9 - T/120)(pi - 2 theta_s) term leaves the range of its tangent: negative and exploding luminance. \
         Shipped: turbidity clamped to [1.7, 10] (the lowest value that is positive at every sun elevation, `tests/analytic.rs`), the sun below the horizon evaluated on it and darkened by a decade every 3 degrees, views below the horizon given the horizon's value, out-of-gamut colours clamped at 0."
    );
    let _ = writeln!(
        md,
        "- **Hosek-Wilkie** (row `hosek, published model unclamped`: the `hw-skymodel` crate at the swept parameters). Its dataset covers solar elevations from 0 to 90 degrees and turbidity 1 to 10: outside, the model cannot be evaluated at all (`refused`). Inside, its coefficients are interpolated in the cube root of the elevation, whose slope is infinite at the horizon: an early sweep found the sky jumping by up to 75% over 0.05 degrees of sun there. \
         Shipped: turbidity and albedo clamped, the sun below the horizon as for Preetham, and the coefficients evaluated no lower than 2 degrees of sun (`HOSEK_MIN_ELEVATION_DEG`)."
    );
    let _ = writeln!(
        md,
        "- **single** and **lut** treated the sun as a point: each ray-march sample was lit or in the planet's shadow, so as the sun set, samples switched off one by one and the sky jumped (64% over 0.05 degrees on a small planet). Shipped: a sample's sunlight fades smoothly to nothing while the sun sinks 0.1 degrees below its horizon, lit along the horizon meanwhile (`sun_visible_fraction` in shaders/sky_model/atmosphere.wgsl); the reference does the same (`Reference::sunlight`), so the models still converge to it (`single` at 128 x 128 steps: 0.09% at low sun). A fade as wide as the sun's disc (0.53 degrees) moved low-sun skies 1.7% away from a point-sun reference."
    );
    let _ = writeln!(md, "\n## Worst cases found\n");
    for c in results {
        if c.worst.is_empty() {
            continue;
        }
        let _ = writeln!(md, "**{}**\n", c.name);
        for (_, line) in &c.worst {
            let _ = writeln!(md, "- {line}");
        }
        let _ = writeln!(md);
    }
    md
}
