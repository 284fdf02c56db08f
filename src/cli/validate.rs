//! `skytune validate`: each sky model against measured whole-sky scans. Per scan and model it
//! fits the one parameter a user would set (the aerosol optical depth of the physical models, the
//! turbidity of the analytic ones), then writes the luminance-shape and blue/red errors as rows
//! of a CSV that later runs extend, and from all its rows a Markdown report and a chart.

use std::path::{Path, PathBuf};

use anyhow::{anyhow, Context as _};
use plotters::coord::Shift;
use plotters::prelude::*;
use serde::{Deserialize, Serialize};

use super::{ValidateArgs, VALIDATE_MODELS};
use skytune::atmosphere::aerosol::Aerosol;
use skytune::atmosphere::analytic::PREETHAM_MIN_TURBIDITY;
use skytune::atmosphere::reference::{estimate_many, Case, Reference, ReferenceSettings};
use skytune::atmosphere::{Atmosphere, LutSettings, Rgb, SingleSettings};
use skytune::measure::model_points::{Evaluator, Method};
use skytune::measure::validation::{agreement, median, minimise_log, Agreement, Scan, Split};
use skytune::render::{AdapterChoice, GpuContext};
use skytune::sky::resolved::SkyModelKind;

/// The search range of the aerosol optical depth at 550 nm.
const OPTICAL_DEPTHS: (f64, f64) = (0.003, 2.0);

/// Golden-section steps of a fit (the bracket shrinks by 0.618 each).
const FIT_STEPS: usize = 16;

/// `reference`: steps of its fit, within a factor of [`REFERENCE_BRACKET`] of `lut`'s optical
/// depth (each step is a Monte Carlo evaluation of every sample).
const REFERENCE_STEPS: usize = 6;
const REFERENCE_BRACKET: f64 = 2.0;

/// Angstrom exponents tried with `--fit-angstrom`.
const ANGSTROMS: [f64; 6] = [0.0, 0.5, 1.0, 1.5, 2.0, 2.5];

/// One scan and model: a row of the results CSV (docs/validation.csv).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Row {
    /// Scan name (file stem).
    pub scan: String,
    /// `tuning` or `held_out`.
    pub split: String,
    /// Sun elevation at the scan's start, degrees.
    pub sun_elev_deg: f64,
    /// Sun compass azimuth, degrees.
    pub sun_azimuth_deg: f64,
    /// Samples compared.
    pub samples: usize,
    /// Model name.
    pub model: String,
    /// `aerosol_optical_depth` or `turbidity`.
    pub parameter: String,
    /// Its fitted value.
    pub value: f64,
    /// The Angstrom exponent used (physical models; empty for analytic ones).
    pub angstrom_exponent: Option<f64>,
    /// Scale from the model's radiance to the measured (1: the absolute level is right).
    pub scale: f64,
    /// Median relative luminance error after the scale.
    pub luminance_median: f64,
    /// Median relative error of the blue/red ratio.
    pub blue_red_median: f64,
}

/// The goal for the physical models on held-out scans (issue 35): 10% in both figures.
const GOAL: f64 = 0.10;

/// Runs `skytune validate`.
pub fn run(args: &ValidateArgs, adapter: AdapterChoice) -> anyhow::Result<()> {
    anyhow::ensure!((0.0..=1.0).contains(&args.albedo), "--albedo: expected 0..=1, found {}", args.albedo);
    anyhow::ensure!((0.0..90.0).contains(&args.sun_exclusion_deg), "--sun-exclusion-deg: expected 0..90, found {}", args.sun_exclusion_deg);
    let scans = read_scans(&args.scans)?;
    let ctx = GpuContext::headless(adapter)?;
    let ev = Evaluator::new(&ctx)?;
    println!("validating {} scan(s) with {:?} on {}", scans.len(), args.models, ctx.adapter_line());
    let mut rows = read_rows(&args.out)?;
    for scan in &scans {
        let started = std::time::Instant::now();
        let new = fit_scan(&ev, scan, args)?;
        for r in &new {
            println!(
                "{} (sun {:.1} deg, {}): {:<9} {} {:.3}{} scale {:.3}, luminance {:.1}%, blue/red {:.1}%",
                r.scan,
                r.sun_elev_deg,
                r.split,
                r.model,
                r.parameter,
                r.value,
                r.angstrom_exponent.map_or(String::new(), |a| format!(" (Angstrom {a})")),
                r.scale,
                100.0 * r.luminance_median,
                100.0 * r.blue_red_median
            );
        }
        println!("  {:.1} s", started.elapsed().as_secs_f64());
        rows.retain(|r| !new.iter().any(|n| n.scan == r.scan && n.model == r.model));
        rows.extend(new);
        rows.sort_by(|a, b| (&a.scan, model_order(&a.model)).cmp(&(&b.scan, model_order(&b.model))));
        // Written after every scan: a long run keeps what it has done.
        write_rows(&args.out, &rows)?;
    }
    if let Some(report) = &args.report {
        write_report(report, &rows, args, &ctx.adapter_line())?;
        println!("wrote {}", report.display());
    }
    if let Some(stem) = &args.chart {
        chart(&rows, stem)?;
        println!("wrote {}.png and .svg", stem.display());
    }
    Ok(())
}

fn model_order(name: &str) -> usize {
    ["preetham", "hosek", "single", "lut", "reference"].iter().position(|m| *m == name).unwrap_or(9)
}

fn read_scans(paths: &[PathBuf]) -> anyhow::Result<Vec<Scan>> {
    let mut files = Vec::new();
    for p in paths {
        if p.is_dir() {
            let mut inside: Vec<PathBuf> = std::fs::read_dir(p)
                .with_context(|| format!("reading {}", p.display()))?
                .flatten()
                .map(|e| e.path())
                .filter(|f| f.extension().is_some_and(|e| e == "csv"))
                .collect();
            inside.sort();
            files.extend(inside);
        } else {
            files.push(p.clone());
        }
    }
    anyhow::ensure!(!files.is_empty(), "no scan files (*.csv) in {paths:?}");
    files.iter().map(|f| Scan::read(f).map_err(|e| anyhow!("{e}"))).collect()
}

fn read_rows(path: &Path) -> anyhow::Result<Vec<Row>> {
    match std::fs::read_to_string(path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(Vec::new()),
        Err(e) => Err(e).with_context(|| format!("reading {}", path.display())),
        Ok(text) => csv::Reader::from_reader(text.as_bytes()).deserialize().collect::<Result<Vec<Row>, _>>().with_context(|| format!("reading {}", path.display())),
    }
}

fn write_rows(path: &Path, rows: &[Row]) -> anyhow::Result<()> {
    let mut w = csv::Writer::from_writer(Vec::new());
    for r in rows {
        w.serialize(r)?;
    }
    skytune::support::safe_write::write_atomic(path, &w.into_inner().map_err(|e| anyhow!("{e}"))?)?;
    Ok(())
}

/// The physical atmosphere of `args.aerosol` with this optical depth (and exponent).
fn atmosphere(args: &ValidateArgs, optical_depth: f64, angstrom: f64) -> Atmosphere {
    Aerosol { optical_depth_550: optical_depth, angstrom_exponent: angstrom, ..args.aerosol.aerosol() }.apply(Atmosphere::default())
}

fn fit_scan(ev: &Evaluator<'_>, scan: &Scan, args: &ValidateArgs) -> anyhow::Result<Vec<Row>> {
    let mut fitted: Vec<(String, Vec<Rgb>, f64)> = Vec::new();
    let rows = fit_scan_with(ev, scan, args, &mut fitted)?;
    if let Some(dir) = &args.samples {
        write_samples(dir, scan, args, &fitted)?;
    }
    Ok(rows)
}

/// Every used sample of `scan`: where, measured, and each model's fitted radiance times its scale
/// (sr^-1 per unit of solar irradiance).
fn write_samples(dir: &Path, scan: &Scan, args: &ValidateArgs, fitted: &[(String, Vec<Rgb>, f64)]) -> anyhow::Result<()> {
    use std::fmt::Write as _;
    let (cases, measured) = scan.cases(args.albedo, args.sun_exclusion_deg);
    let mut text = "view_elev_deg,rel_azimuth_deg,measured_r,measured_g,measured_b".to_string();
    for (m, _, _) in fitted {
        let _ = write!(text, ",{m}_r,{m}_g,{m}_b");
    }
    text.push('\n');
    for (i, (c, y)) in cases.iter().zip(&measured).enumerate() {
        let _ = write!(text, "{},{},{:.6e},{:.6e},{:.6e}", c.view_elev_deg, c.rel_azimuth_deg, y[0], y[1], y[2]);
        for (_, v, k) in fitted {
            let _ = write!(text, ",{:.6e},{:.6e},{:.6e}", v[i][0] * k, v[i][1] * k, v[i][2] * k);
        }
        text.push('\n');
    }
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    skytune::support::safe_write::write_atomic(&dir.join(format!("{}.csv", scan.name)), text.as_bytes())?;
    Ok(())
}

fn fit_scan_with(ev: &Evaluator<'_>, scan: &Scan, args: &ValidateArgs, fitted: &mut Vec<(String, Vec<Rgb>, f64)>) -> anyhow::Result<Vec<Row>> {
    let (cases, measured) = scan.cases(args.albedo, args.sun_exclusion_deg);
    anyhow::ensure!(cases.len() >= 10, "{}: only {} usable samples", scan.name, cases.len());
    let (sun_elev, sun_az) = scan.sun();
    let row = |model: &str, parameter: &str, value: f64, angstrom: Option<f64>, a: Agreement| Row {
        scan: scan.name.clone(),
        split: scan.split.name().to_string(),
        sun_elev_deg: (sun_elev * 100.0).round() / 100.0,
        sun_azimuth_deg: (sun_az * 100.0).round() / 100.0,
        samples: cases.len(),
        model: model.to_string(),
        parameter: parameter.to_string(),
        value,
        angstrom_exponent: angstrom,
        scale: a.scale,
        luminance_median: a.luminance_median,
        blue_red_median: a.blue_red_median,
    };
    // In the fitting order: `reference` is searched near `lut`'s fit.
    let models: Vec<SkyModelKind> = VALIDATE_MODELS.iter().copied().filter(|m| args.models.contains(m)).collect();
    let angstroms: Vec<f64> = if args.fit_angstrom { ANGSTROMS.to_vec() } else { vec![args.aerosol.aerosol().angstrom_exponent] };
    let mut rows = Vec::new();
    let mut lut_fit = None;
    for model in models {
        match model {
            SkyModelKind::Preetham | SkyModelKind::Hosek => {
                let (method, lo) = if model == SkyModelKind::Preetham { (Method::Preetham, PREETHAM_MIN_TURBIDITY) } else { (Method::Hosek, 1.0) };
                let values = |t: f64| ev.gpu(&method, &Atmosphere::default(), t, &cases);
                let (t, _) = minimise_log(lo, 10.0, FIT_STEPS, |t| Ok(agreement(&values(t)?, &measured).objective))?;
                let v = values(round3(t))?;
                let a = agreement(&v, &measured);
                fitted.push((method.model_name().to_string(), v, a.scale));
                rows.push(row(method.model_name(), "turbidity", round3(t), None, a));
            }
            SkyModelKind::Single | SkyModelKind::Lut => {
                let method = if model == SkyModelKind::Single { Method::Single(SingleSettings::default()) } else { Method::Lut(LutSettings::default()) };
                let values = |tau: f64, a: f64| ev.gpu(&method, &atmosphere(args, tau, a), 0.0, &cases);
                let mut best: Option<(f64, f64, f64)> = None;
                for &a in &angstroms {
                    let (tau, objective) = minimise_log(OPTICAL_DEPTHS.0, OPTICAL_DEPTHS.1, FIT_STEPS, |tau| Ok(agreement(&values(tau, a)?, &measured).objective))?;
                    if best.is_none_or(|b| objective < b.2) {
                        best = Some((tau, a, objective));
                    }
                }
                let (tau, a, _) = best.context("no fit")?;
                if model == SkyModelKind::Lut {
                    lut_fit = Some((tau, a));
                }
                let v = values(round3(tau), a)?;
                let agreed = agreement(&v, &measured);
                fitted.push((method.model_name().to_string(), v, agreed.scale));
                rows.push(row(method.model_name(), "aerosol_optical_depth", round3(tau), Some(a), agreed));
            }
            SkyModelKind::Reference => {
                // Dear: searched near lut's fit (or the preset's amount), with lut's exponent.
                let (centre, a) = lut_fit.unwrap_or((args.aerosol.aerosol().optical_depth_550, angstroms[0]));
                let settings = ReferenceSettings { paths: args.reference_paths, target_rel_se: Some(0.02), ..Default::default() };
                let values = |tau: f64| reference(atmosphere(args, tau, a), settings, &cases);
                let (tau, _) = minimise_log(centre / REFERENCE_BRACKET, centre * REFERENCE_BRACKET, REFERENCE_STEPS, |tau| Ok(agreement(&values(tau)?, &measured).objective))?;
                let v = values(round3(tau))?;
                let agreed = agreement(&v, &measured);
                fitted.push(("reference".to_string(), v, agreed.scale));
                rows.push(row("reference", "aerosol_optical_depth", round3(tau), Some(a), agreed));
            }
            other => anyhow::bail!("--models: {} is not compared with measured skies", other.name()),
        }
    }
    Ok(rows)
}

/// Three significant digits (the analytic models' scales from their published units are small).
fn significant(x: f64) -> String {
    format!("{}", round3(x))
}

fn round3(x: f64) -> f64 {
    let digits = 3 - x.abs().log10().floor() as i32 - 1;
    let k = 10f64.powi(digits.max(0));
    (x * k).round() / k
}

/// The reference's radiance of `cases` (the same seed for every atmosphere: the fit compares
/// optical depths with the same paths).
fn reference(atm: Atmosphere, settings: ReferenceSettings, cases: &[Case]) -> anyhow::Result<Vec<Rgb>> {
    let model = Reference::new(atm, settings);
    let jobs: Vec<_> = cases.iter().map(|c| (&model, *c)).collect();
    Ok(estimate_many(&jobs, &|_, _| Ok(()))?.into_iter().map(|e| e.all).collect())
}

const BEGIN: &str = "<!-- skytune validate: begin (generated; edits between the markers are replaced) -->";
const END: &str = "<!-- skytune validate: end -->";

fn write_report(path: &Path, rows: &[Row], args: &ValidateArgs, adapter: &str) -> anyhow::Result<()> {
    use std::fmt::Write as _;
    let mut md = String::new();
    let _ = writeln!(md, "{BEGIN}\n");
    let _ = writeln!(
        md,
        "Measured by `skytune validate` ({}, {}) on {adapter}: physical models with the `{}` aerosol{}, ground albedo {}, samples within {} degrees of the sun left out.\n",
        env!("CARGO_PKG_VERSION"),
        skytune::build_line(),
        args.aerosol.name(),
        if args.fit_angstrom { " (Angstrom exponent fitted)" } else { "" },
        args.albedo,
        args.sun_exclusion_deg
    );
    let _ = writeln!(md, "**Summary: medians over scans** (each scan's figure is itself a median over its samples)\n");
    let _ = writeln!(md, "| model | split | scans | fitted parameter (range) | luminance error | blue/red error | scale |");
    let _ = writeln!(md, "|---|---|---|---|---|---|---|");
    let mut models: Vec<&str> = rows.iter().map(|r| r.model.as_str()).collect();
    models.sort_by_key(|m| model_order(m));
    models.dedup();
    for m in &models {
        for split in [Split::Tuning, Split::HeldOut] {
            let sel: Vec<&Row> = rows.iter().filter(|r| r.model == *m && r.split == split.name()).collect();
            if sel.is_empty() {
                continue;
            }
            let values: Vec<f64> = sel.iter().map(|r| r.value).collect();
            let (lo, hi) = values.iter().fold((f64::MAX, f64::MIN), |(a, b), v| (a.min(*v), b.max(*v)));
            let _ = writeln!(
                md,
                "| {m} | {} | {} | {} {:.3} ({lo:.3} to {hi:.3}) | {:.1}% | {:.1}% | {} |",
                split.name(),
                sel.len(),
                sel[0].parameter,
                median(values.clone()),
                100.0 * median(sel.iter().map(|r| r.luminance_median).collect()),
                100.0 * median(sel.iter().map(|r| r.blue_red_median).collect()),
                significant(median(sel.iter().map(|r| r.scale).collect()))
            );
        }
    }
    let _ = writeln!(md, "\n**Goal** (held-out scans, `lut` and `reference`: median luminance and blue/red errors within {:.0}%):\n", 100.0 * GOAL);
    for m in ["lut", "reference"] {
        let sel: Vec<&Row> = rows.iter().filter(|r| r.model == m && r.split == Split::HeldOut.name()).collect();
        if sel.is_empty() {
            let _ = writeln!(md, "- `{m}`: not measured");
            continue;
        }
        let (l, b) = (median(sel.iter().map(|r| r.luminance_median).collect()), median(sel.iter().map(|r| r.blue_red_median).collect()));
        let verdict = |x: f64| if x <= GOAL { "met" } else { "not met" };
        let _ = writeln!(md, "- `{m}`: luminance {:.1}% ({}), blue/red {:.1}% ({})", 100.0 * l, verdict(l), 100.0 * b, verdict(b));
    }
    let _ = writeln!(md, "\n**Every scan**\n");
    let _ = writeln!(md, "| scan | split | sun elevation | samples | model | fitted | Angstrom | scale | luminance error | blue/red error |");
    let _ = writeln!(md, "|---|---|---|---|---|---|---|---|---|---|");
    for r in rows {
        let _ = writeln!(
            md,
            "| {} | {} | {:.1} | {} | {} | {} {} | {} | {} | {:.1}% | {:.1}% |",
            r.scan,
            r.split,
            r.sun_elev_deg,
            r.samples,
            r.model,
            r.parameter,
            r.value,
            r.angstrom_exponent.map_or("-".to_string(), |a| a.to_string()),
            significant(r.scale),
            100.0 * r.luminance_median,
            100.0 * r.blue_red_median
        );
    }
    let _ = writeln!(md, "\n{END}");
    replace_between_markers(path, (BEGIN, END), &md)
}

/// Writes `md` (which starts with `begin` and ends with `end`) into the file at `path` in place
/// of what lies between those markers there, keeping the rest of the file; appends it when the
/// file has no such markers (or does not exist).
pub(crate) fn replace_between_markers(path: &Path, (begin, end): (&str, &str), md: &str) -> anyhow::Result<()> {
    let old = std::fs::read_to_string(path).unwrap_or_default();
    let text = match (old.find(begin), old.find(end)) {
        (Some(b), Some(e)) if e > b => format!("{}{}{}", &old[..b], md.trim_end(), &old[e + end.len()..]),
        _ => format!("{old}{}{md}", if old.is_empty() { "" } else { "\n" }),
    };
    skytune::support::safe_write::write_atomic(path, text.as_bytes())?;
    Ok(())
}

fn chart(rows: &[Row], stem: &Path) -> anyhow::Result<()> {
    super::charts::both_at(stem, (1400, 620), |root| draw(root, rows), |root| draw(root, rows))
}

fn draw<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, rows: &[Row]) -> anyhow::Result<()>
where
    DB::ErrorType: 'static,
{
    let e = |x: DrawingAreaErrorKind<DB::ErrorType>| anyhow!("{x:?}");
    root.fill(&WHITE).map_err(e)?;
    let (title, panels) = root.split_vertically(50);
    title.titled("Sky models against measured skies (Kider et al. 2014): filled = held-out scans, hollow = tuning scans", ("sans-serif", 20)).map_err(e)?;
    let top = rows.iter().flat_map(|r| [r.luminance_median, r.blue_red_median]).fold(0.12f64, f64::max).min(2.0) * 100.0 * 1.1;
    let x_range = rows.iter().map(|r| r.sun_elev_deg).fold((90.0f64, 0.0f64), |(a, b), x| (a.min(x), b.max(x)));
    let x_range = (x_range.0 - 3.0).max(0.0)..(x_range.1 + 3.0).min(90.0);
    let mut models: Vec<&str> = rows.iter().map(|r| r.model.as_str()).collect();
    models.sort_by_key(|m| model_order(m));
    models.dedup();
    for (panel, (name, pick)) in panels.split_evenly((1, 2)).iter().zip([("median luminance-shape error, %", 0), ("median blue/red ratio error, %", 1)]) {
        let mut chart = ChartBuilder::on(panel)
            .caption(name, ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(55)
            .build_cartesian_2d(x_range.clone(), 0.0..top)
            .map_err(e)?;
        chart.configure_mesh().x_desc("sun elevation, degrees").y_desc("%").label_style(("sans-serif", 14)).draw().map_err(e)?;
        chart.draw_series(LineSeries::new(vec![(x_range.start, 100.0 * GOAL), (x_range.end, 100.0 * GOAL)], BLACK.mix(0.4).stroke_width(1))).map_err(e)?;
        for (k, m) in models.iter().enumerate() {
            let c = super::charts::colour(m);
            // Models side by side around each scan's elevation, so that they do not hide each other.
            let dx = (k as f64 - (models.len() as f64 - 1.0) / 2.0) * 0.35;
            for r in rows.iter().filter(|r| r.model == *m) {
                let y = 100.0 * if pick == 0 { r.luminance_median } else { r.blue_red_median };
                let style = if r.split == Split::HeldOut.name() { c.filled() } else { c.stroke_width(2) };
                chart.draw_series(std::iter::once(Circle::new((r.sun_elev_deg + dx, y.min(top)), 5, style))).map_err(e)?;
            }
            chart.draw_series(std::iter::empty::<Circle<(f64, f64), i32>>()).map_err(e)?.label(m.to_string()).legend(move |(x, y)| Circle::new((x, y), 5, c.filled()));
        }
        chart.configure_series_labels().background_style(WHITE.mix(0.9)).border_style(BLACK).label_font(("sans-serif", 14)).draw().map_err(e)?;
    }
    Ok(())
}
