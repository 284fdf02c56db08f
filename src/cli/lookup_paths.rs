//! `skytune bench models`: the two ways a frame can draw a table model (`precomputed`): through
//! the sky-view map (the model evaluated at the map's texels, which the skydome samples; how
//! frames draw it) or looked up per pixel (Bruneton's demo). Accuracy of both against the
//! reference over the benchmark's dome, and the cost of the lookups each takes per frame, side by
//! side in one run.

use std::fmt::Write as _;
use std::time::Instant;

use anyhow::Context as _;

use skytune::atmosphere::dome::{self, Haze, ReferenceDome, Regime};
use skytune::atmosphere::reference::Case;
use skytune::atmosphere::Rgb;
use skytune::measure::model_points::{Evaluator, Method, Point, SunRow};
use skytune::measure::sky_view_map::SkyViewMap;
use skytune::measure::validation::median;
use skytune::render::plan::resolution::SKY_VIEW_SIZE;

/// Accuracy and cost of one way of drawing a point.
#[derive(Debug, Clone)]
pub struct PathRow {
    /// Point id.
    pub id: String,
    /// How it is drawn.
    pub path: &'static str,
    /// Model lookups per frame.
    pub lookups: usize,
    /// Wall ms of those lookups (median of 3 on the radiance probe, with moving the cases and
    /// results, which grow with them).
    pub lookup_ms: f64,
    /// Mean PSNR over the dome, dB.
    pub psnr_db: f64,
    /// Mean relative RMSE (r, g, b averaged) per regime, in `Regime::ALL` order.
    pub rel_rmse: [f64; 3],
}

/// Per-pixel and through-the-map rows of each `auto` candidate among `points` that is a
/// `precomputed` setting, over the default atmosphere at `suns`; `by_sun` holds the per-pixel
/// errors already measured (the probe looks the model up per direction).
pub fn measure(ev: &Evaluator<'_>, reference: &ReferenceDome, suns: &[f64], points: &[Point], by_sun: &[SunRow], frame: (u32, u32)) -> anyhow::Result<Vec<PathRow>> {
    let atm = Haze::Default.atmosphere();
    let dirs = dome::dome_directions(dome::BENCH_DOME.0, dome::BENCH_DOME.1);
    let size = (SKY_VIEW_SIZE.0 as usize, SKY_VIEW_SIZE.1 as usize);
    let texels = SkyViewMap::texel_directions(size);
    let case = |sun_elev_deg: f64, view_elev_deg: f64, rel_azimuth_deg: f64| Case {
        camera_km: dome::CAMERA_KM,
        albedo: dome::ALBEDO,
        sun_elev_deg,
        view_elev_deg,
        rel_azimuth_deg,
        distance_km: None,
    };
    let mut rows = Vec::new();
    for p in points.iter().filter(|p| p.auto && matches!(p.method, Method::Precomputed(_))) {
        // Accuracy through the map.
        let mut errors = Vec::new();
        for &s in suns {
            let r = reference.sun(Haze::Default, s).with_context(|| format!("the reference has no default sun {s}"))?;
            let cases: Vec<Case> = texels.iter().map(|(e, a)| case(s, *e, *a)).collect();
            let map = SkyViewMap::new(size, &ev.gpu(&p.method, &atm, 0.0, &cases)?);
            let model: Vec<Rgb> = dirs.iter().map(|d| map.sample(d.elev_deg, d.rel_az_deg)).collect();
            errors.push((s, dome::dome_error(&dirs, &r.radiance, &model)));
        }
        let per_pixel: Vec<(f64, dome::DomeError)> =
            by_sun.iter().filter(|r| r.id == p.id && r.haze == Haze::Default.name() && suns.contains(&r.sun_elev_deg)).map(|r| (r.sun_elev_deg, r.error)).collect();
        // Cost: the map's texels against the frame's pixels, interleaved, the tables built.
        let sun = 30.0;
        let map_cases: Vec<Case> = texels.iter().map(|(e, a)| case(sun, *e, *a)).collect();
        let (w, h) = (frame.0 as usize, frame.1 as usize);
        let pixel_cases: Vec<Case> = SkyViewMap::texel_directions((w, h)).into_iter().map(|(e, a)| case(sun, e, a)).collect();
        ev.gpu(&p.method, &atm, 0.0, &map_cases[..1])?;
        let (mut map_ms, mut pixel_ms) = (Vec::new(), Vec::new());
        for _ in 0..3 {
            for (cases, out) in [(&map_cases, &mut map_ms), (&pixel_cases, &mut pixel_ms)] {
                let t = Instant::now();
                ev.gpu(&p.method, &atm, 0.0, cases)?;
                out.push(t.elapsed().as_secs_f64() * 1000.0);
            }
        }
        let summarise = |path: &'static str, lookups: usize, lookup_ms: f64, e: &[(f64, dome::DomeError)]| {
            let mean = |v: Vec<f64>| v.iter().sum::<f64>() / v.len().max(1) as f64;
            PathRow {
                id: p.id.clone(),
                path,
                lookups,
                lookup_ms,
                psnr_db: mean(e.iter().map(|(_, x)| x.psnr_db).collect()),
                rel_rmse: Regime::ALL.map(|g| mean(e.iter().filter(|(s, _)| Regime::of(*s) == g).map(|(_, x)| x.rel_rmse_mean()).collect())),
            }
        };
        rows.push(summarise("per pixel", w * h, median(pixel_ms), &per_pixel));
        rows.push(summarise("sky-view map", size.0 * size.1, median(map_ms), &errors));
    }
    Ok(rows)
}

/// The section of models.md.
pub fn markdown(rows: &[PathRow], frame: (u32, u32)) -> String {
    let mut md = String::new();
    if rows.is_empty() {
        return md;
    }
    let (mw, mh) = SKY_VIEW_SIZE;
    let _ = writeln!(md, "\n## Per-pixel lookup against the sky-view map (`precomputed`)\n");
    let _ = writeln!(
        md,
        "Frames draw `precomputed` through the {mw}x{mh} sky-view map: the model is looked up at the map's texels and the skydome samples the map (rgba16float, bilinear). The alternative is a lookup per pixel. Accuracy: the default atmosphere over the dome at every sun elevation of this run; through the map, the map is filled on the radiance probe, stored as half floats and sampled bilinearly on the CPU (`skytune::measure::sky_view_map`, a twin of the shader's layout: azimuth from the sun's over half the circle). Cost: wall ms of the lookups on the radiance probe for the map's texels and for a {}x{} frame's pixels, the sun at 30 degrees, median of 3 interleaved (including moving the cases and the results, which grow alike).\n",
        frame.0, frame.1
    );
    let _ = write!(md, "| point | drawn | lookups per frame | lookup wall ms | PSNR dB |");
    for g in Regime::ALL {
        let _ = write!(md, " {} rel. RMSE |", g.name());
    }
    let _ = writeln!(md, "\n|---|---|---:|---:|---:|---:|---:|---:|");
    for r in rows {
        let _ =
            writeln!(md, "| {} | {} | {} | {:.1} | {:.1} | {:.4} | {:.4} | {:.4} |", r.id, r.path, r.lookups, r.lookup_ms, r.psnr_db, r.rel_rmse[0], r.rel_rmse[1], r.rel_rmse[2]);
    }
    md
}
