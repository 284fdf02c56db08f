//! Radiance cases as CSV: the interface of `skytune radiance`, the tests and the benchmarks.
//!
//! Input header: `camera_km,albedo,sun_elev_deg,view_elev_deg,rel_azimuth_deg`, and optionally
//! `distance_km` (where the view ray stops; empty: at the edge of the atmosphere). The output
//! repeats those columns and adds `r,g,b` (sr^-1 per unit of solar irradiance); where a case
//! has a distance, the in-scattered light along the ray, and `t_r,t_g,t_b`, its transmittance.

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::reference::Case;
use super::Rgb;

/// One row of an input file.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
struct CaseRow {
    camera_km: f64,
    albedo: f64,
    sun_elev_deg: f64,
    view_elev_deg: f64,
    rel_azimuth_deg: f64,
    /// Empty or absent: to the edge of the atmosphere.
    #[serde(default)]
    distance_km: Option<f64>,
}

/// One cell of an output row, written as csv writes a struct's field of its type.
#[derive(Serialize)]
#[serde(untagged)]
enum Cell {
    Number(f64),
    /// Empty when `None`.
    Optional(Option<f64>),
    Count(u32),
}

/// Case `c`'s output row as (column, cell): the case's columns, `distance_km` in a file with
/// finite rays, `r,g,b` (radiance `l`), then what `beside` holds for it: in a file with finite
/// rays its transmittance `t_r,t_g,t_b`; for the reference the standard errors `se_r,se_g,se_b`
/// of its radiance (the Monte Carlo noise of orders >= 2, sr^-1) and the `paths` it drew (fewer
/// than the cap where a target was met).
fn output_row(c: &Case, l: Rgb, finite: bool, beside: Beside<'_>, k: usize) -> Vec<(&'static str, Cell)> {
    use Cell::{Count, Number, Optional};
    let mut row = vec![
        ("camera_km", Number(c.camera_km)),
        ("albedo", Number(c.albedo)),
        ("sun_elev_deg", Number(c.sun_elev_deg)),
        ("view_elev_deg", Number(c.view_elev_deg)),
        ("rel_azimuth_deg", Number(c.rel_azimuth_deg)),
    ];
    if finite {
        row.push(("distance_km", Optional(c.distance_km)));
    }
    row.extend([("r", Number(l[0])), ("g", Number(l[1])), ("b", Number(l[2]))]);
    let transmittance = match beside {
        Beside::Nothing => None,
        Beside::Transmittance(t) => Some(t[k]),
        Beside::Estimates(e) => Some(e[k].transmittance),
    };
    if let Some(t) = transmittance.filter(|_| finite) {
        row.extend([("t_r", Number(t[0])), ("t_g", Number(t[1])), ("t_b", Number(t[2]))]);
    }
    if let Beside::Estimates(e) = beside {
        let se = e[k].std_err;
        row.extend([("se_r", Number(se[0])), ("se_g", Number(se[1])), ("se_b", Number(se[2])), ("paths", Count(e[k].paths))]);
    }
    row
}

/// Whether any case stops its ray short of the edge of the atmosphere.
pub fn has_finite_rays(cases: &[Case]) -> bool {
    cases.iter().any(|c| c.distance_km.is_some())
}

/// A bad cases file: where and why.
#[derive(Debug, thiserror::Error)]
pub enum CasesError {
    /// The file could not be read or written.
    #[error("{file}: {source}")]
    Io {
        /// The file.
        file: String,
        /// Why.
        source: std::io::Error,
    },
    /// A row does not parse, or a value is out of its domain.
    #[error("{file}:{line}: {field}: {message}")]
    Row {
        /// The file.
        file: String,
        /// 1-based line.
        line: u64,
        /// The column.
        field: String,
        /// What is wrong.
        message: String,
    },
}

/// Reads cases; every value must be finite, the camera inside the atmosphere of `top_km`
/// thickness, the albedo in [0, 1] and elevations in [-90, 90].
pub fn read_cases(path: &Path, top_km: f64) -> Result<Vec<Case>, CasesError> {
    let file = path.display().to_string();
    let mut reader = csv::ReaderBuilder::new().trim(csv::Trim::All).comment(Some(b'#')).from_path(path).map_err(|e| csv_error(&file, e))?;
    let mut out = Vec::new();
    for row in reader.deserialize::<CaseRow>() {
        let row = row.map_err(|e| csv_error(&file, e))?;
        let line = out.len() as u64 + 2;
        let bad = |field: &str, message: String| CasesError::Row { file: file.clone(), line, field: field.into(), message };
        for (field, v) in [
            ("camera_km", row.camera_km),
            ("albedo", row.albedo),
            ("sun_elev_deg", row.sun_elev_deg),
            ("view_elev_deg", row.view_elev_deg),
            ("rel_azimuth_deg", row.rel_azimuth_deg),
        ] {
            if !v.is_finite() {
                return Err(bad(field, format!("expected a finite number, found {v}")));
            }
        }
        if !(0.0..top_km).contains(&row.camera_km) {
            return Err(bad("camera_km", format!("expected 0 <= altitude < {top_km} km (inside the atmosphere), found {}", row.camera_km)));
        }
        if !(0.0..=1.0).contains(&row.albedo) {
            return Err(bad("albedo", format!("expected 0..1, found {}", row.albedo)));
        }
        for (field, v) in [("sun_elev_deg", row.sun_elev_deg), ("view_elev_deg", row.view_elev_deg)] {
            if !(-90.0..=90.0).contains(&v) {
                return Err(bad(field, format!("expected -90..90 degrees, found {v}")));
            }
        }
        if let Some(d) = row.distance_km.filter(|d| !(d.is_finite() && *d > 0.0)) {
            return Err(bad("distance_km", format!("expected a distance > 0 km, or empty for the edge of the atmosphere, found {d}")));
        }
        out.push(Case {
            camera_km: row.camera_km,
            albedo: row.albedo,
            sun_elev_deg: row.sun_elev_deg,
            view_elev_deg: row.view_elev_deg,
            rel_azimuth_deg: row.rel_azimuth_deg,
            distance_km: row.distance_km,
        });
    }
    Ok(out)
}

fn csv_error(file: &str, e: csv::Error) -> CasesError {
    let line = e.position().map_or(0, |p| p.line());
    match e.into_kind() {
        csv::ErrorKind::Io(source) => CasesError::Io { file: file.into(), source },
        csv::ErrorKind::Deserialize { err, .. } => {
            CasesError::Row { file: file.into(), line, field: err.field().map_or_else(|| "row".into(), |f| format!("column {}", f + 1)), message: err.to_string() }
        }
        other => CasesError::Row { file: file.into(), line, field: "row".into(), message: format!("{other:?}") },
    }
}

/// Writes radiance per case as CSV (the cases' columns, then r, g, b), `comment` as `#` lines first.
pub fn write_radiance(path: &Path, comment: &str, cases: &[Case], radiance: &[Rgb]) -> Result<(), CasesError> {
    write_radiance_rows(path, comment, cases, radiance, Beside::Nothing)
}

/// As [`write_radiance`] for a model that answers finite rays: where any case has a distance,
/// every row also gives `distance_km` (after the case's columns) and the ray's transmittance
/// `t_r, t_g, t_b` (after `r, g, b`).
pub fn write_rays(path: &Path, comment: &str, cases: &[Case], radiance: &[Rgb], transmittance: &[Rgb]) -> Result<(), CasesError> {
    write_radiance_rows(path, comment, cases, radiance, Beside::Transmittance(transmittance))
}

/// What a file's rows carry beside radiance.
#[derive(Clone, Copy)]
enum Beside<'a> {
    Nothing,
    /// Transmittance (written where the cases have distances).
    Transmittance(&'a [Rgb]),
    /// The reference's estimates: standard errors, paths and transmittance.
    Estimates(&'a [crate::atmosphere::reference::Estimate]),
}

/// As [`write_radiance`], with the standard error of each value in `se_r, se_g, se_b` columns
/// and the paths each case drew in a `paths` column: the reference's estimates. Where any case
/// has a distance, every row also gives `distance_km` (after the case's columns) and the ray's
/// transmittance `t_r, t_g, t_b` (after `r, g, b`).
pub fn write_reference(path: &Path, comment: &str, cases: &[Case], estimates: &[crate::atmosphere::reference::Estimate]) -> Result<(), CasesError> {
    let radiance: Vec<Rgb> = estimates.iter().map(|e| e.all).collect();
    write_radiance_rows(path, comment, cases, &radiance, Beside::Estimates(estimates))
}

fn write_radiance_rows(path: &Path, comment: &str, cases: &[Case], radiance: &[Rgb], beside: Beside<'_>) -> Result<(), CasesError> {
    let file = path.display().to_string();
    let io = |source| CasesError::Io { file: file.clone(), source };
    let mut text = String::new();
    for line in comment.lines() {
        text.push_str(&format!("# {line}\n"));
    }
    let mut writer = csv::Writer::from_writer(Vec::new());
    let finite = has_finite_rays(cases);
    for (k, (c, l)) in cases.iter().zip(radiance).enumerate() {
        let (names, cells): (Vec<&str>, Vec<Cell>) = output_row(c, *l, finite, beside, k).into_iter().unzip();
        let written = if k == 0 { writer.write_record(&names).map_err(|e| e.to_string()) } else { Ok(()) };
        written.and_then(|()| writer.serialize(cells).map_err(|e| e.to_string())).map_err(|e| io(std::io::Error::other(e)))?;
    }
    let body = writer.into_inner().map_err(|e| io(std::io::Error::other(e.to_string())))?;
    text.push_str(&String::from_utf8_lossy(&body));
    crate::support::safe_write::write_atomic(path, text.as_bytes()).map_err(|e| io(e.source))
}
