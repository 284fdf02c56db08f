//! `skytune validate-aerial`: aerial perspective against the double-precision reference on a
//! freshly drawn accuracy set (`skytune::measure::aerial`): the `lut` model's exact march and the
//! aerial-perspective volume at each size asked, read as the scene reads it, per sun band and per
//! distance band, written as CSV rows and a Markdown table between markers.

use std::fmt::Write as _;
use std::path::Path;

use super::ValidateAerialArgs;
use skytune::atmosphere::aerial::AerialSettings;
use skytune::atmosphere::reference::{estimate_many, Case, Estimate, Reference, ReferenceSettings};
use skytune::atmosphere::{Atmosphere, LutSettings};
use skytune::measure::aerial::{self, GroupErrors, DISTANCE_BANDS, SUN_BANDS};
use skytune::render::atmosphere::aerial_probe::AerialProbe;
use skytune::render::atmosphere::radiance_probe::{ProbeAnswers, RadianceProbe};
use skytune::render::{AdapterChoice, GpuContext, ShaderLibrary};

const BEGIN: &str = "<!-- skytune validate-aerial: begin (generated; edits between the markers are replaced) -->";
const END: &str = "<!-- skytune validate-aerial: end -->";

/// One method's errors over one group of cases.
struct Row {
    method: String,
    group: &'static str,
    errors: GroupErrors,
}

/// Runs the validation.
pub fn run(args: &ValidateAerialArgs, adapter: AdapterChoice) -> anyhow::Result<()> {
    let d = AerialSettings::default();
    let volumes: Vec<AerialSettings> =
        args.sizes.iter().map(|&volume_size| AerialSettings { volume_size, steps_per_slice: args.steps_per_slice.unwrap_or(d.steps_per_slice), ..d }).collect();
    for v in &volumes {
        v.validate().map_err(|e| anyhow::anyhow!("--sizes: {}", e.message))?;
    }
    let atm = Atmosphere::default();
    let cases = aerial::draw_cases(args.seed, args.cases, &atm);
    let reporter = skytune::support::progress::Reporter::new(2 * cases.len() as u64, "reference rays");
    let reference = Reference::new(atm, ReferenceSettings { paths: args.paths, ..Default::default() });
    let rays_and_sky: Vec<(&Reference, Case)> = cases.iter().map(|c| (&reference, *c)).chain(cases.iter().map(|c| (&reference, Case { distance_km: None, ..*c }))).collect();
    let estimates: Vec<Estimate> = estimate_many(&rays_and_sky, &|done, _| {
        reporter.set_position(done as u64);
        Ok(())
    })?;
    reporter.finish();
    let (rays, sky) = estimates.split_at(cases.len());

    let ctx = GpuContext::headless(adapter)?;
    let library = ShaderLibrary::embedded();
    let lut = LutSettings::default();
    let mut methods: Vec<(String, ProbeAnswers)> = vec![("exact (lut_aerial)".into(), RadianceProbe::new(&ctx, &library)?.lut_rays(&ctx, &atm, &lut, &cases)?)];
    let probe = AerialProbe::new(&ctx, &library)?;
    for settings in &volumes {
        let [x, y, z] = settings.volume_size;
        let default = if *settings == AerialSettings::default() { " (default)" } else { "" };
        let steps = if settings.steps_per_slice == d.steps_per_slice { String::new() } else { format!(", {} samples a slice", settings.steps_per_slice) };
        methods.push((format!("volume {x}x{y}x{z}{steps}{default}"), probe.volume_rays(&ctx, &atm, &lut, settings, true, &cases)?));
    }

    let mut rows = Vec::new();
    for (method, answers) in &methods {
        let errors = aerial::ray_errors(&cases, &answers.radiance, &answers.transmittance, rays, sky);
        let sun = aerial::by_group(&cases, &errors, SUN_BANDS.len(), aerial::sun_band);
        let distance = aerial::by_group(&cases, &errors, DISTANCE_BANDS.len(), aerial::distance_band);
        for (group, errors) in SUN_BANDS.iter().zip(sun).chain(DISTANCE_BANDS.iter().zip(distance)) {
            rows.push(Row { method: method.clone(), group, errors });
        }
    }
    let mut csv = String::from("method,group,cases,in_scatter_median,in_scatter_p95,in_scatter_worst,transmittance_median,transmittance_p95,transmittance_worst\n");
    for r in &rows {
        let [a, b, c] = r.errors.in_scatter;
        let [d, e, f] = r.errors.transmittance;
        let _ = writeln!(csv, "{},{},{},{a:.5},{b:.5},{c:.5},{d:.5},{e:.5},{f:.5}", r.method, r.group, r.errors.cases);
    }
    skytune::support::safe_write::write_atomic(&args.out, csv.as_bytes())?;
    println!("wrote {} ({} methods, {} cases, seed {})", args.out.display(), methods.len(), cases.len(), args.seed);
    if let Some(report) = &args.report {
        write_report(report, &rows, args, &ctx.adapter_line())?;
        println!("wrote {}", report.display());
    }
    Ok(())
}

fn write_report(path: &Path, rows: &[Row], args: &ValidateAerialArgs, adapter: &str) -> anyhow::Result<()> {
    let mut md = format!("{BEGIN}\n\n");
    let _ = writeln!(
        md,
        "Measured by `skytune validate-aerial --seed {} --cases {} --paths {}` ({}, {}) on {adapter}: {} finite rays drawn afresh with seed {} (viewers 0 to 5 km, views -10 to +30 degrees, 0.1 to 100 km in log distance, suns in turn by day, low and in twilight to -6 degrees; scene points in the air), the default atmosphere, ground albedo 0.3, against the reference ({} paths a ray). In-scatter: the error beyond twice the reference's standard error as a fraction of the sky's radiance in the same direction; transmittance: absolute. Every channel a sample; median / p95 / worst.\n",
        args.seed,
        args.cases,
        args.paths,
        env!("CARGO_PKG_VERSION"),
        skytune::build_line(),
        args.cases,
        args.seed,
        args.paths
    );
    let _ = writeln!(md, "| method | cases | in-scatter / sky | transmittance |");
    let _ = writeln!(md, "|---|---|---|---|");
    for r in rows {
        let [a, b, c] = r.errors.in_scatter;
        let [d, e, f] = r.errors.transmittance;
        let _ = writeln!(md, "| {}, {} | {} | {:.2}% / {:.2}% / {:.2}% | {d:.4} / {e:.4} / {f:.4} |", r.method, r.group, r.errors.cases, 100.0 * a, 100.0 * b, 100.0 * c);
    }
    let _ = writeln!(md, "\n{END}");
    super::validate::replace_between_markers(path, (BEGIN, END), &md)
}
