//! `skytune bench reference`: how the reference converges. Relative error against the number of
//! paths per regime, both as the reference reports it (its standard error) and as measured
//! against a longer run of itself with another seed; writes a Markdown table and a chart
//! (docs/reference-convergence.md, .svg and .png).

use std::fmt::Write as _;
use std::time::Instant;

use anyhow::{anyhow, Context as _};
use plotters::coord::Shift;
use plotters::prelude::*;

use crate::cli::ReferenceBenchArgs;
use skytune::atmosphere::dome::Regime;
use skytune::atmosphere::reference::{Case, Estimate, Reference, ReferenceSettings};
use skytune::atmosphere::Atmosphere;
use skytune::support::progress::Reporter;

/// Seed of the long run: independent of the shorter runs' seed.
const LONG_SEED: u64 = 0x10_0000_0001;

/// The cases of a regime: three suns, cameras at 0.2 and 5 km, a horizontal view across the sun
/// (albedo 0) and one 10 degrees up facing away (albedo 0.3).
fn cases(regime: Regime) -> Vec<Case> {
    let suns: [f64; 3] = match regime {
        Regime::Day => [20.0, 45.0, 75.0],
        Regime::LowSun => [2.0, 5.0, 8.0],
        Regime::Twilight => [-1.0, -3.0, -6.0],
    };
    let mut out = Vec::new();
    for sun_elev_deg in suns {
        for camera_km in [0.2, 5.0] {
            out.push(Case { camera_km, albedo: 0.0, sun_elev_deg, view_elev_deg: 0.0, rel_azimuth_deg: 90.0, distance_km: None });
            out.push(Case { camera_km, albedo: 0.3, sun_elev_deg, view_elev_deg: 10.0, rel_azimuth_deg: 180.0, distance_km: None });
        }
    }
    out
}

/// A line of the chart: its name, the figure it plots and its style.
type Series = (&'static str, fn(&Row) -> f64, ShapeStyle);

/// Every case estimated on every core.
fn estimate_all(atm: Atmosphere, cases: &[Case], paths: u32, seed: u64, bar: &Reporter) -> Vec<Estimate> {
    let model = Reference::new(atm, ReferenceSettings { paths, seed, ..Default::default() });
    let jobs: Vec<_> = cases.iter().map(|c| (&model, *c)).collect();
    let progress = |_, _| {
        bar.inc(1);
        Ok(())
    };
    skytune::atmosphere::reference::estimate_many(&jobs, &progress).unwrap_or_default()
}

/// The value at quantile `q` (nearest rank) of `v`.
fn quantile(v: &mut [f64], q: f64) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * q).round() as usize]
}

/// One regime at one path count.
#[derive(Debug, Clone, Copy)]
struct Row {
    regime: Regime,
    paths: u32,
    seconds: f64,
    /// Median and 95th percentile over cases and channels of the reported relative standard error.
    se_median: f64,
    se_p95: f64,
    /// Median and 95th percentile of the relative error against the long run.
    err_median: f64,
    err_p95: f64,
    /// Share of values within two combined standard errors of the long run.
    within_2se: f64,
}

pub fn run(args: &ReferenceBenchArgs) -> anyhow::Result<()> {
    let paths: Vec<u32> = args.paths.split(',').map(|p| p.trim().parse::<u32>().map_err(|e| anyhow!("--paths: \"{p}\": {e}"))).collect::<anyhow::Result<_>>()?;
    anyhow::ensure!(!paths.is_empty() && paths.iter().all(|p| *p >= 1 && *p < args.long), "--paths: path counts from 1 to below --long ({}), comma-separated", args.long);
    let started = Instant::now();
    let atm = Atmosphere::default();
    let mut rows = Vec::new();
    let mut long_seconds = Vec::new();
    for regime in Regime::ALL {
        let list = cases(regime);
        let bar = Reporter::new((list.len() * (paths.len() + 1)) as u64, "reference");
        bar.set_message(format!("{} ({} paths, long run)", regime.name(), args.long));
        let t = Instant::now();
        let long = estimate_all(atm, &list, args.long, LONG_SEED, &bar);
        long_seconds.push((regime, t.elapsed().as_secs_f64()));
        for &n in &paths {
            bar.set_message(format!("{} ({n} paths)", regime.name()));
            let t = Instant::now();
            let short = estimate_all(atm, &list, n, args.seed, &bar);
            let seconds = t.elapsed().as_secs_f64();
            let (mut se, mut err, mut within) = (Vec::new(), Vec::new(), 0usize);
            for (s, l) in short.iter().zip(&long) {
                for c in 0..3 {
                    let v = l.all[c].max(1e-30);
                    se.push(s.std_err[c] / s.all[c].max(1e-30));
                    err.push((s.all[c] - l.all[c]).abs() / v);
                    within += usize::from((s.all[c] - l.all[c]).abs() <= 2.0 * s.std_err[c].hypot(l.std_err[c]));
                }
            }
            let count = se.len().max(1) as f64;
            rows.push(Row {
                regime,
                paths: n,
                seconds,
                se_median: quantile(&mut se.clone(), 0.5),
                se_p95: quantile(&mut se, 0.95),
                err_median: quantile(&mut err.clone(), 0.5),
                err_p95: quantile(&mut err, 0.95),
                within_2se: within as f64 / count,
            });
        }
        bar.finish();
    }
    std::fs::create_dir_all(&args.out).with_context(|| format!("creating {}", args.out.display()))?;
    let stem = args.out.join("reference-convergence");
    crate::cli::charts::both_at(&stem, (1500, 560), |root| draw(root, &rows), |root| draw(root, &rows))?;
    let md = report(args, &rows, &long_seconds, started.elapsed().as_secs_f64());
    skytune::support::safe_write::write_atomic(&stem.with_extension("md"), md.as_bytes())?;
    print!("{md}");
    println!("\nwrote {}.md, .svg and .png", stem.display());
    Ok(())
}

fn report(args: &ReferenceBenchArgs, rows: &[Row], long_seconds: &[(Regime, f64)], seconds: f64) -> String {
    let mut md = String::new();
    let _ = writeln!(md, "# How the reference converges\n");
    let _ = writeln!(
        md,
        "Written by `skytune bench reference --paths {} --long {}` in {seconds:.0} s ({} logical CPUs, {}); re-run it to refresh this file and the chart.\n",
        args.paths,
        args.long,
        std::thread::available_parallelism().map_or(0, |n| n.get()),
        skytune::build_line()
    );
    let _ = writeln!(
        md,
        "Per regime, 12 cases of the default atmosphere: three suns (day 20, 45, 75 degrees; low sun 2, 5, 8; twilight -1, -3, -6), cameras at 0.2 and 5 km, a horizontal view 90 degrees from the sun (albedo 0) and one 10 degrees up facing away (albedo 0.3). \
         Every order (up to 24). Each path count runs with seed {} and is compared with a run of {} paths with another seed: *reported* is the reference's own relative standard error per channel, *measured* the relative difference from the long run (which includes the long run's own noise). \
         *within 2 se*: the share of values within two combined standard errors of the long run (about 95% when the error bars are honest).\n",
        args.seed, args.long
    );
    let _ = writeln!(md, "![relative error against paths per regime](reference-convergence.svg)\n");
    let _ = writeln!(md, "| regime | paths | seconds | reported se median | p95 | measured error median | p95 | within 2 se |");
    let _ = writeln!(md, "|---|---:|---:|---:|---:|---:|---:|---:|");
    for r in rows {
        let _ = writeln!(
            md,
            "| {} | {} | {:.1} | {:.2}% | {:.2}% | {:.2}% | {:.2}% | {:.0}% |",
            r.regime.name(),
            r.paths,
            r.seconds,
            r.se_median * 100.0,
            r.se_p95 * 100.0,
            r.err_median * 100.0,
            r.err_p95 * 100.0,
            r.within_2se * 100.0
        );
    }
    let _ = writeln!(md, "\nThe long runs took {}.", long_seconds.iter().map(|(g, s)| format!("{s:.0} s ({})", g.name())).collect::<Vec<_>>().join(", "));
    md
}

fn colour(regime: Regime) -> RGBColor {
    match regime {
        Regime::Day => RGBColor(31, 119, 180),
        Regime::LowSun => RGBColor(255, 127, 14),
        Regime::Twilight => RGBColor(148, 103, 189),
    }
}

fn draw<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, rows: &[Row]) -> anyhow::Result<()>
where
    DB::ErrorType: 'static,
{
    let e = |x: DrawingAreaErrorKind<DB::ErrorType>| anyhow!("{x:?}");
    root.fill(&WHITE).map_err(e)?;
    let (lo, hi) = rows.iter().flat_map(|r| [r.se_median, r.se_p95, r.err_median, r.err_p95]).filter(|v| *v > 0.0).fold((f64::MAX, f64::MIN), |(a, b), v| (a.min(v), b.max(v)));
    let (lo, hi) = if lo > hi { (1e-3, 1.0) } else { (lo / 2.0, hi * 2.0) };
    let (p0, p1) = rows.iter().fold((u32::MAX, 0), |(a, b), r| (a.min(r.paths), b.max(r.paths)));
    let x_range = (p0 as f64 / 1.5)..(p1 as f64 * 1.5);
    for (panel, regime) in root.split_evenly((1, 3)).iter().zip(Regime::ALL) {
        let mut chart = ChartBuilder::on(panel)
            .caption(regime.name(), ("sans-serif", 20))
            .margin(14)
            .x_label_area_size(45)
            .y_label_area_size(65)
            .build_cartesian_2d(x_range.clone().log_scale(), (lo..hi).log_scale())
            .map_err(e)?;
        chart
            .configure_mesh()
            .x_labels(8)
            .x_label_formatter(&|x| format!("{x:.0}"))
            .x_desc("paths per case (log)")
            .y_desc("relative error per channel (log)")
            .label_style(("sans-serif", 14))
            .draw()
            .map_err(e)?;
        let mine: Vec<&Row> = rows.iter().filter(|r| r.regime == regime).collect();
        let c = colour(regime);
        let series: [Series; 4] = [
            ("reported se, median", |r| r.se_median, c.stroke_width(2)),
            ("reported se, p95", |r| r.se_p95, c.mix(0.5).stroke_width(1)),
            ("measured error, median", |r| r.err_median, BLACK.stroke_width(2)),
            ("measured error, p95", |r| r.err_p95, BLACK.mix(0.4).stroke_width(1)),
        ];
        for (name, f, style) in series {
            let line: Vec<(f64, f64)> = mine.iter().map(|r| (r.paths as f64, f(r).max(lo))).collect();
            chart.draw_series(LineSeries::new(line.clone(), style)).map_err(e)?.label(name).legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], style));
            chart.draw_series(line.into_iter().map(|p| Circle::new(p, 3, style.filled()))).map_err(e)?;
        }
        // 1/sqrt(paths) through the first median: what an honest Monte Carlo estimate follows.
        if let Some(first) = mine.first() {
            let guide: Vec<(f64, f64)> = mine.iter().map(|r| (r.paths as f64, (first.se_median * (first.paths as f64 / r.paths as f64).sqrt()).max(lo))).collect();
            let grey = RGBColor(44, 160, 44);
            chart
                .draw_series(LineSeries::new(guide, grey.stroke_width(1)))
                .map_err(e)?
                .label("1 / sqrt(paths)")
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], grey.stroke_width(1)));
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 13))
            .position(SeriesLabelPosition::LowerLeft)
            .draw()
            .map_err(e)?;
    }
    Ok(())
}
