//! The model benchmark's charts, drawn with `plotters` as SVG and PNG: error against cost (log
//! axes, Pareto front, labelled points) and error against sun elevation per model.

use std::path::Path;

use anyhow::{anyhow, Context as _};
use plotters::coord::Shift;
use plotters::prelude::*;

use skytune::atmosphere::dome::Regime;
use skytune::measure::model_points::{ChartRow, SunRow};

const SIZE: (u32, u32) = (1100, 700);

/// The cost chart: three panels side by side.
const COST_SIZE: (u32, u32) = (1800, 720);

/// The PNG backend measures and draws text with a font of its own: egui's, already in the binary.
fn register_font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        if plotters::style::register_font("sans-serif", FontStyle::Normal, epaint_default_fonts::UBUNTU_LIGHT).is_err() {
            log::warn!("the chart font did not load; PNG charts will have no text");
        }
    });
}

/// Draws `draw` into `stem`.svg and `stem`.png, `size` pixels.
pub fn both_at(
    stem: &Path,
    size: (u32, u32),
    draw: impl Fn(&DrawingArea<SVGBackend<'_>, Shift>) -> anyhow::Result<()> + Copy,
    draw_png: impl Fn(&DrawingArea<BitMapBackend<'_>, Shift>) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    register_font();
    let svg = stem.with_extension("svg");
    {
        let root = SVGBackend::new(&svg, size).into_drawing_area();
        draw(&root)?;
        root.present().map_err(|e| anyhow!("{e}")).with_context(|| format!("writing {}", svg.display()))?;
    }
    let mut buffer = vec![0u8; (size.0 * size.1 * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buffer, size).into_drawing_area();
        draw_png(&root)?;
        root.present().map_err(|e| anyhow!("{e}"))?;
    }
    let png = stem.with_extension("png");
    let image = image::RgbImage::from_raw(size.0, size.1, buffer).context("chart buffer size")?;
    let mut bytes = Vec::new();
    image.write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png)?;
    skytune::support::safe_write::write_atomic(&png, &bytes)?;
    Ok(())
}

/// The colour of a model in every chart.
pub fn colour(model: &str) -> RGBColor {
    match model {
        "single" => RGBColor(31, 119, 180),
        "lut" => RGBColor(214, 39, 40),
        "cells" => RGBColor(148, 103, 189),
        "preetham" => RGBColor(255, 127, 14),
        "hosek" => RGBColor(44, 160, 44),
        "linear" => RGBColor(140, 86, 75),
        "dome-map" => RGBColor(227, 119, 194),
        "regression" => RGBColor(23, 190, 207),
        "baked" => RGBColor(127, 127, 127),
        "reference" => RGBColor(30, 30, 30),
        _ => RGBColor(0, 0, 0),
    }
}

fn log_range(values: impl Iterator<Item = f64>) -> std::ops::Range<f64> {
    let (lo, hi) = values.filter(|v| v.is_finite() && *v > 0.0).fold((f64::MAX, f64::MIN), |(a, b), v| (a.min(v), b.max(v)));
    if lo > hi {
        return 0.1..10.0;
    }
    (lo / 1.5)..(hi * 1.5)
}

fn draw_cost<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, rows: &[ChartRow]) -> anyhow::Result<()>
where
    DB::ErrorType: 'static,
{
    let e = |x: DrawingAreaErrorKind<DB::ErrorType>| anyhow!("{x:?}");
    root.fill(&WHITE).map_err(e)?;
    let (title, panels) = root.split_vertically(50);
    title
        .titled(
            "Sky models: error against the whole frame's cost, by regime (error bars: the reference's own noise; Pareto front of dE2000 over all regimes in black)",
            ("sans-serif", 20),
        )
        .map_err(e)?;
    let x_range = log_range(rows.iter().map(|r| r.floor_ratio_moving()));
    let y_range = log_range(rows.iter().flat_map(|r| Regime::ALL.map(|g| r.regime(g).0.max(1e-3))));
    let font = ("sans-serif", 12).into_font();
    for (panel, regime) in panels.split_evenly((1, 3)).iter().zip(Regime::ALL) {
        let mut chart = ChartBuilder::on(panel)
            .caption(regime.name(), ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(60)
            .build_cartesian_2d(x_range.clone().log_scale(), y_range.clone().log_scale())
            .map_err(e)?;
        chart
            .configure_mesh()
            .x_desc("whole frame / fill-rate floor, sun moving (log)")
            .y_desc("relative RMSE over the dome (log)")
            .label_style(("sans-serif", 14))
            // A log axis gets a label at every minor tick, which run together above 30.
            .x_labels(6)
            .x_label_formatter(&|v| format!("{v:.0}"))
            .draw()
            .map_err(e)?;
        let at = |r: &ChartRow| (r.floor_ratio_moving(), r.regime(regime).0.max(1e-3));
        let mut front: Vec<(f64, f64)> = rows.iter().filter(|r| r.pareto).map(at).collect();
        front.sort_by(|a, b| a.0.total_cmp(&b.0));
        chart.draw_series(LineSeries::new(front, BLACK.stroke_width(1))).map_err(e)?;
        for r in rows {
            let c = colour(&r.model);
            let (x, y) = at(r);
            let noise = r.regime(regime).1;
            let bar = vec![(x, (y - noise).max(y_range.start)), (x, y + noise)];
            chart.draw_series(std::iter::once(PathElement::new(bar, c.stroke_width(1)))).map_err(e)?;
            chart.draw_series(std::iter::once(Circle::new((x, y), if r.pareto { 5 } else { 3 }, c.filled()))).map_err(e)?;
        }
        // Labels placed in pixels where they overlap no other label and no point.
        let points: Vec<(i32, i32)> = rows.iter().map(|r| chart.backend_coord(&at(r))).collect();
        let sizes: Vec<(i32, i32)> = rows
            .iter()
            .map(|r| root.estimate_text_size(&r.id, &font.clone().into_text_style(root)).map(|(w, h)| (w as i32 + 6, h as i32 + 4)).unwrap_or((7 * r.id.len() as i32 + 6, 16)))
            .collect();
        let (x0, y0) = chart.backend_coord(&(x_range.start, y_range.end));
        let (x1, y1) = chart.backend_coord(&(x_range.end, y_range.start));
        let placed = place_labels(&points, &sizes, (x0, y0, x1, y1));
        for ((r, p), (pos, leader)) in rows.iter().zip(&points).zip(placed) {
            let c = colour(&r.model);
            if leader {
                let (w, h) = sizes[rows.iter().position(|q| q.id == r.id).unwrap_or(0)];
                let end = ((pos.0 + w / 2).clamp(pos.0, pos.0 + w), (pos.1 + h / 2).clamp(pos.1, pos.1 + h));
                root.draw(&PathElement::new(vec![*p, end], c.mix(0.5).stroke_width(1))).map_err(e)?;
            }
            root.draw(&Text::new(r.id.clone(), pos, font.clone().color(&c))).map_err(e)?;
        }
    }
    Ok(())
}

/// Where each label goes: the top-left corner of a `sizes[i]` box near `points[i]` that
/// overlaps no label placed before it and no point, inside `bounds` (x0, y0, x1, y1), and
/// whether it sits far enough from its point to need a leader line. Candidates go round the
/// point in rings of growing radius; a label that finds no free place keeps the first one.
pub fn place_labels(points: &[(i32, i32)], sizes: &[(i32, i32)], bounds: (i32, i32, i32, i32)) -> Vec<((i32, i32), bool)> {
    let mut boxes: Vec<(i32, i32, i32, i32)> = Vec::new();
    let overlaps = |a: (i32, i32, i32, i32), b: (i32, i32, i32, i32)| a.0 < b.2 && b.0 < a.2 && a.1 < b.3 && b.1 < a.3;
    let near_point = |b: (i32, i32, i32, i32)| points.iter().any(|p| overlaps(b, (p.0 - 4, p.1 - 4, p.0 + 4, p.1 + 4)));
    let mut out = Vec::new();
    for (p, &(w, h)) in points.iter().zip(sizes) {
        let mut chosen = None;
        'rings: for ring in 0..12 {
            let r = 6 + ring * 10;
            for step in 0..16 {
                let a = step as f64 / 16.0 * std::f64::consts::TAU;
                let (cx, cy) = (p.0 + (r as f64 * a.cos()) as i32, p.1 - (r as f64 * a.sin()) as i32);
                // The box hangs off the candidate on the side facing away from the point.
                let x = if a.cos() >= 0.0 { cx } else { cx - w };
                let y = if a.sin() >= 0.0 { cy - h } else { cy };
                let b = (x, y, x + w, y + h);
                let inside = b.0 >= bounds.0 && b.1 >= bounds.1 && b.2 <= bounds.2 && b.3 <= bounds.3;
                if inside && !near_point(b) && !boxes.iter().any(|o| overlaps(b, *o)) {
                    chosen = Some(((x, y), ring > 1));
                    break 'rings;
                }
            }
        }
        let (pos, leader) = chosen.unwrap_or(((p.0 + 6, p.1 - 6 - h), false));
        boxes.push((pos.0, pos.1, pos.0 + w, pos.1 + h));
        out.push((pos, leader));
    }
    out
}

/// Error against cost by regime: `stem`.svg and `stem`.png.
pub fn cost_chart(rows: &[ChartRow], stem: &Path) -> anyhow::Result<()> {
    both_at(stem, COST_SIZE, |root| draw_cost(root, rows), |root| draw_cost(root, rows))
}

/// The points drawn per model in the sun chart: each model's default setting.
const SUN_CHART_POINTS: [&str; 9] = ["single-erf-32", "lut-default", "cells-6", "preetham", "hosek", "linear", "dome-map-24", "regression", "baked-32"];

fn draw_sun<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, rows: &[SunRow], noise: &[(f64, f64)]) -> anyhow::Result<()>
where
    DB::ErrorType: 'static,
{
    let e = |x: DrawingAreaErrorKind<DB::ErrorType>| anyhow!("{x:?}");
    root.fill(&WHITE).map_err(e)?;
    let chosen: Vec<&SunRow> = rows.iter().filter(|r| r.haze == "default" && SUN_CHART_POINTS.contains(&r.id.as_str())).collect();
    let y_range = log_range(chosen.iter().map(|r| r.error.rel_rmse_mean().max(1e-4)).chain(noise.iter().map(|n| n.1.max(1e-4))));
    let mut chart = ChartBuilder::on(root)
        .caption("Relative RMSE over the dome by sun elevation (default atmosphere)", ("sans-serif", 24))
        .margin(20)
        .x_label_area_size(50)
        .y_label_area_size(70)
        .build_cartesian_2d(-11.0f64..91.0, y_range.log_scale())
        .map_err(e)?;
    chart.configure_mesh().x_desc("sun elevation, degrees").y_desc("relative RMSE of radiance (mean of r, g, b), log").label_style(("sans-serif", 16)).draw().map_err(e)?;
    for id in SUN_CHART_POINTS {
        let mut line: Vec<(f64, f64)> = chosen.iter().filter(|r| r.id == id).map(|r| (r.sun_elev_deg, r.error.rel_rmse_mean().max(1e-4))).collect();
        if line.is_empty() {
            continue;
        }
        line.sort_by(|a, b| a.0.total_cmp(&b.0));
        let model = id.trim_end_matches(|c: char| c.is_ascii_digit() || c == '-').trim_end_matches("-erf").trim_end_matches("-default");
        let c = colour(model);
        chart
            .draw_series(LineSeries::new(line.clone(), c.stroke_width(2)))
            .map_err(e)?
            .label(id)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2)));
        chart.draw_series(line.into_iter().map(|p| Circle::new(p, 3, c.filled()))).map_err(e)?;
    }
    // Below this line a model's error is the reference's noise, not the model's.
    let mut floor: Vec<(f64, f64)> = noise.iter().map(|(s, n)| (*s, n.max(1e-4))).collect();
    floor.sort_by(|a, b| a.0.total_cmp(&b.0));
    if !floor.is_empty() {
        chart
            .draw_series(LineSeries::new(floor, BLACK.mix(0.6).stroke_width(3)))
            .map_err(e)?
            .label("the reference's own noise")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK.mix(0.6).stroke_width(3)));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .label_font(("sans-serif", 14))
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(e)?;
    Ok(())
}

/// Error against sun elevation per model, with the reference's own noise (sun elevation,
/// relative RMSE) as a floor line: `stem`.svg and `stem`.png.
pub fn sun_chart(rows: &[SunRow], noise: &[(f64, f64)], stem: &Path) -> anyhow::Result<()> {
    both_at(stem, SIZE, |root| draw_sun(root, rows, noise), |root| draw_sun(root, rows, noise))
}

#[cfg(test)]
mod tests {
    use super::place_labels;

    #[test]
    fn labels_of_crowded_points_do_not_overlap() {
        // Ten points on top of each other and a few apart, as points sharing one frame cost are.
        let mut points: Vec<(i32, i32)> = (0..10).map(|i| (300, 300 + i)).collect();
        points.extend([(320, 300), (500, 100), (50, 50)]);
        let sizes: Vec<(i32, i32)> = points.iter().map(|_| (80, 14)).collect();
        let placed = place_labels(&points, &sizes, (0, 0, 800, 600));
        let boxes: Vec<(i32, i32, i32, i32)> = placed.iter().zip(&sizes).map(|(((x, y), _), (w, h))| (*x, *y, x + w, y + h)).collect();
        for (i, a) in boxes.iter().enumerate() {
            assert!(a.0 >= 0 && a.1 >= 0 && a.2 <= 800 && a.3 <= 600, "label {i} leaves the plot: {a:?}");
            for (j, b) in boxes.iter().enumerate().skip(i + 1) {
                assert!(!(a.0 < b.2 && b.0 < a.2 && a.1 < b.3 && b.1 < a.3), "labels {i} and {j} overlap: {a:?} {b:?}");
            }
            for p in &points {
                assert!(!(a.0 < p.0 + 4 && p.0 - 4 < a.2 && a.1 < p.1 + 4 && p.1 - 4 < a.3), "label {i} covers the point at {p:?}");
            }
        }
        // A lone point's label sits next to it, without a leader.
        assert!(!placed[11].1);
    }
}
