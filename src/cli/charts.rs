//! The model benchmark's charts, drawn with `plotters` as SVG and PNG: error against cost (log
//! axes, Pareto front, labelled points) and error against sun elevation per model.

use std::path::Path;

use anyhow::{anyhow, Context as _};
use plotters::coord::Shift;
use plotters::prelude::*;

use skytune::measure::model_points::{ChartRow, SunRow};

const SIZE: (u32, u32) = (1100, 700);

/// The PNG backend measures and draws text with a font of its own: egui's, already in the binary.
fn register_font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        if plotters::style::register_font("sans-serif", FontStyle::Normal, epaint_default_fonts::UBUNTU_LIGHT).is_err() {
            log::warn!("the chart font did not load; PNG charts will have no text");
        }
    });
}

/// Draws `draw` into `stem`.svg and `stem`.png.
fn both(
    stem: &Path,
    draw: impl Fn(&DrawingArea<SVGBackend<'_>, Shift>) -> anyhow::Result<()> + Copy,
    draw_png: impl Fn(&DrawingArea<BitMapBackend<'_>, Shift>) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    register_font();
    let svg = stem.with_extension("svg");
    {
        let root = SVGBackend::new(&svg, SIZE).into_drawing_area();
        draw(&root)?;
        root.present().map_err(|e| anyhow!("{e}")).with_context(|| format!("writing {}", svg.display()))?;
    }
    let mut buffer = vec![0u8; (SIZE.0 * SIZE.1 * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buffer, SIZE).into_drawing_area();
        draw_png(&root)?;
        root.present().map_err(|e| anyhow!("{e}"))?;
    }
    let png = stem.with_extension("png");
    let image = image::RgbImage::from_raw(SIZE.0, SIZE.1, buffer).context("chart buffer size")?;
    let mut bytes = Vec::new();
    image.write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png)?;
    skytune::support::safe_write::write_atomic(&png, &bytes)?;
    Ok(())
}

fn colour(model: &str) -> RGBColor {
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
    let x_range = log_range(rows.iter().map(|r| r.frame_ms()));
    let y_range = log_range(rows.iter().map(|r| r.error().max(1e-3)));
    let mut chart = ChartBuilder::on(root)
        .caption("Sky models: error against cost (Pareto front in black)", ("sans-serif", 24))
        .margin(20)
        .x_label_area_size(50)
        .y_label_area_size(70)
        .build_cartesian_2d(x_range.log_scale(), y_range.log_scale())
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc("frame ms in which the sun moved (GPU + CPU), log")
        .y_desc("mean CIE dE2000 over the dome, log")
        .label_style(("sans-serif", 16))
        .draw()
        .map_err(e)?;
    let mut front: Vec<(f64, f64)> = rows.iter().filter(|r| r.pareto).map(|r| (r.frame_ms(), r.error().max(1e-3))).collect();
    front.sort_by(|a, b| a.0.total_cmp(&b.0));
    chart.draw_series(LineSeries::new(front, BLACK.stroke_width(2))).map_err(e)?;
    for r in rows {
        let c = colour(&r.model);
        let p = (r.frame_ms(), r.error().max(1e-3));
        chart
            .draw_series(std::iter::once(
                EmptyElement::at(p) + Circle::new((0, 0), if r.pareto { 6 } else { 4 }, c.filled()) + Text::new(r.id.clone(), (7, -7), ("sans-serif", 13).into_font().color(&c)),
            ))
            .map_err(e)?;
    }
    Ok(())
}

/// Error against cost: `stem`.svg and `stem`.png.
pub fn cost_chart(rows: &[ChartRow], stem: &Path) -> anyhow::Result<()> {
    both(stem, |root| draw_cost(root, rows), |root| draw_cost(root, rows))
}

/// The points drawn per model in the sun chart: each model's default setting.
const SUN_CHART_POINTS: [&str; 9] = ["single-erf-32", "lut-default", "cells-6", "preetham", "hosek", "linear", "dome-map-24", "regression", "baked-32"];

fn draw_sun<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, rows: &[SunRow]) -> anyhow::Result<()>
where
    DB::ErrorType: 'static,
{
    let e = |x: DrawingAreaErrorKind<DB::ErrorType>| anyhow!("{x:?}");
    root.fill(&WHITE).map_err(e)?;
    let chosen: Vec<&SunRow> = rows.iter().filter(|r| r.haze == "default" && SUN_CHART_POINTS.contains(&r.id.as_str())).collect();
    let y_range = log_range(chosen.iter().map(|r| r.error.rel_rmse_mean().max(1e-4)));
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

/// Error against sun elevation per model: `stem`.svg and `stem`.png.
pub fn sun_chart(rows: &[SunRow], stem: &Path) -> anyhow::Result<()> {
    both(stem, |root| draw_sun(root, rows), |root| draw_sun(root, rows))
}
