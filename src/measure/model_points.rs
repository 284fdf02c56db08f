//! The points of the speed-against-accuracy chart: every sky model at several quality settings,
//! and cheap representations of a model, each evaluated over the measurement dome
//! ([`crate::atmosphere::dome`]). Used by `skytune bench models`, `skytune bake`, the stability
//! sweep and `model = "auto"`.
//!
//! GPU models are evaluated where they ship, through the radiance probe; CPU models and
//! representations on the CPU.

use crate::atmosphere::analytic::{self, AnalyticModel, AnalyticUnits, LinearParams};
use crate::atmosphere::cells::{CellModel, CellSettings};
use crate::atmosphere::dome::{self, DomeDir};
use crate::atmosphere::reference::Case;
use crate::atmosphere::represent::{self, Baked, DomeMapTable, Regression};
use crate::atmosphere::{Atmosphere, LutSettings, OpticalDepth, PrecomputedSettings, Rgb, SingleSettings, TablePrecision};
use crate::render::atmosphere::radiance_probe::RadianceProbe;
use crate::render::{GpuContext, ShaderLibrary};

/// A model and its quality settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Method {
    /// `single` on the GPU.
    Single(SingleSettings),
    /// `lut` on the GPU.
    Lut(LutSettings),
    /// `precomputed` on the GPU.
    Precomputed(PrecomputedSettings),
    /// `cells` on the CPU with this many iterations.
    Cells(usize),
    /// `preetham` (turbidity and scale fitted per atmosphere).
    Preetham,
    /// `hosek` (turbidity and scale fitted per atmosphere).
    Hosek,
    /// `linear`, Braun and Cohen (scale fitted per atmosphere; its colours decoded from sRGB).
    Linear,
    /// The sky-dome map of the default `lut` model, `res` texels a side, 16 sun elevations.
    DomeMap(usize),
    /// The sky-dome regression of the default `lut` model.
    Regression,
    /// NeL bitmaps baked from the default `lut` model, this many gradient rows.
    Baked(usize),
}

impl Method {
    /// The model's name in the sky file.
    pub fn model_name(&self) -> &'static str {
        match self {
            Method::Single(_) => "single",
            Method::Lut(_) => "lut",
            Method::Precomputed(_) => "precomputed",
            Method::Cells(_) => "cells",
            Method::Preetham => "preetham",
            Method::Hosek => "hosek",
            Method::Linear => "linear",
            Method::DomeMap(_) => "dome-map",
            Method::Regression => "regression",
            Method::Baked(_) => "baked",
        }
    }

    /// Whether the sky file can select it (`model = "auto"` picks among these).
    pub fn is_runtime_model(&self) -> bool {
        matches!(self, Method::Single(_) | Method::Lut(_) | Method::Precomputed(_) | Method::Cells(_) | Method::Preetham | Method::Hosek)
    }
}

/// One point of the chart.
#[derive(Debug, Clone, PartialEq)]
pub struct Point {
    /// Label on the chart and key in the CSV (`single-erf-16`).
    pub id: String,
    /// What it evaluates.
    pub method: Method,
    /// Part of the quick benchmark (CI).
    pub quick: bool,
    /// A candidate of `model = "auto"` (where the sky file can select its model). Points that
    /// chart one quality axis at the default tables are not: each costs `auto` a table build per
    /// weather step (over a minute on a software rasteriser) and draws at the default's cost.
    pub auto: bool,
}

/// Every point of the benchmark.
pub fn points() -> Vec<Point> {
    let p = |id: &str, method: Method, quick: bool| Point { id: id.into(), method, quick, auto: method.is_runtime_model() };
    let chart_only = |p: Point| Point { auto: false, ..p };
    let single = |view_steps: u32, sun_steps: u32, optical_depth| Method::Single(SingleSettings { view_steps, sun_steps, optical_depth });
    let lut = LutSettings::default();
    vec![
        p("single-erf-8", single(8, 16, OpticalDepth::Erf), false),
        p("single-erf-16", single(16, 16, OpticalDepth::Erf), true),
        p("single-erf-32", single(32, 16, OpticalDepth::Erf), true),
        p("single-erf-64", single(64, 16, OpticalDepth::Erf), false),
        p("single-numerical-32x16", single(32, 16, OpticalDepth::Numerical), false),
        p("single-numerical-128x128", single(128, 128, OpticalDepth::Numerical), false),
        p(
            "lut-small",
            Method::Lut(LutSettings {
                transmittance_size: [64, 16],
                transmittance_steps: 20,
                multiscattering_size: 16,
                multiscattering_grid: 4,
                multiscattering_steps: 10,
                view_steps: 16,
            }),
            true,
        ),
        p("lut-default", Method::Lut(lut), true),
        p(
            "lut-large",
            Method::Lut(LutSettings {
                transmittance_size: [512, 128],
                transmittance_steps: 80,
                multiscattering_size: 64,
                multiscattering_grid: 16,
                multiscattering_steps: 40,
                view_steps: 64,
            }),
            false,
        ),
        p("precomputed-small", Method::Precomputed(PrecomputedSettings::SMALL), true),
        p("precomputed-default", Method::Precomputed(PrecomputedSettings::default()), false),
        // The quality axes other than table size, each at the default tables.
        chart_only(p("precomputed-half", Method::Precomputed(PrecomputedSettings { precision: TablePrecision::Half, ..Default::default() }), false)),
        chart_only(p("precomputed-1-order", Method::Precomputed(PrecomputedSettings { orders: 1, ..Default::default() }), false)),
        chart_only(p("precomputed-2-orders", Method::Precomputed(PrecomputedSettings { orders: 2, ..Default::default() }), false)),
        p("cells-0", Method::Cells(0), false),
        p("cells-2", Method::Cells(2), false),
        p("cells-6", Method::Cells(6), false),
        p("preetham", Method::Preetham, true),
        p("hosek", Method::Hosek, true),
        p("linear", Method::Linear, true),
        p("dome-map-8", Method::DomeMap(8), false),
        p("dome-map-24", Method::DomeMap(24), true),
        p("dome-map-48", Method::DomeMap(48), false),
        p("regression", Method::Regression, true),
        p("baked-8", Method::Baked(8), false),
        p("baked-32", Method::Baked(32), true),
        p("baked-128", Method::Baked(128), false),
    ]
}

/// Turbidity and radiance scale of an analytic model fitted to the reference.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fit {
    /// Turbidity (none for `linear`).
    pub turbidity: f64,
    /// Factor applied to the model's radiance.
    pub scale: f64,
    /// The unit the model is evaluated in before the factor (`preetham`, `hosek`): the published
    /// one where the benchmark fits its own scale, the calibrated one (scale 1) as a sky renders.
    pub units: AnalyticUnits,
}

/// Turbidities the fit tries (Preetham's clamp is 1.7; Hosek's data starts at 1).
const TURBIDITIES: [f64; 12] = [1.0, 1.3, 1.7, 2.0, 2.5, 3.0, 3.5, 4.0, 5.0, 6.0, 8.0, 10.0];

/// A point made ready for one atmosphere: tables built, fits done.
pub enum Prepared {
    /// Evaluated on the GPU per case.
    Gpu(Method),
    /// An analytic model with its fit.
    Analytic(Method, Fit),
    /// The cell model, solved.
    Cells(Box<CellModel>),
    /// A sky-dome map table.
    DomeMap(DomeMapTable),
    /// A regression.
    Regression(Regression),
    /// Baked bitmaps (one weather step).
    Baked(Baked),
}

/// The reference over a dome at one sun elevation: what analytic fits are fitted against.
pub struct FitTarget<'a> {
    /// Sun elevation, degrees.
    pub sun_elev_deg: f64,
    /// Directions.
    pub dirs: &'a [DomeDir],
    /// The reference's radiance per direction.
    pub radiance: &'a [Rgb],
}

/// Evaluates points on one GPU.
pub struct Evaluator<'a> {
    ctx: &'a GpuContext,
    probe: RadianceProbe,
}

impl<'a> Evaluator<'a> {
    /// The probe's pipelines on `ctx`.
    pub fn new(ctx: &'a GpuContext) -> anyhow::Result<Self> {
        Ok(Self { ctx, probe: RadianceProbe::new(ctx, &ShaderLibrary::embedded())? })
    }

    /// The GPU context.
    pub fn ctx(&self) -> &GpuContext {
        self.ctx
    }

    /// Drops tables kept between evaluations, so that the next one builds them (timing a build).
    pub fn forget_tables(&self) {
        self.probe.forget_precomputed();
    }

    /// Radiance of a GPU or analytic method (unfitted: the model's own units) for `cases`.
    pub fn gpu(&self, method: &Method, atm: &Atmosphere, turbidity: f64, cases: &[Case]) -> anyhow::Result<Vec<Rgb>> {
        let widen = |v: Vec<[f32; 3]>| v.into_iter().map(|c| c.map(f64::from)).collect();
        Ok(match *method {
            Method::Single(s) => widen(self.probe.single(self.ctx, atm, &s, cases)?),
            Method::Lut(s) => widen(self.probe.lut(self.ctx, atm, &s, cases)?),
            Method::Precomputed(s) => widen(self.probe.precomputed(self.ctx, atm, &s, cases)?),
            // In the published units: the fitted scale is then the factor from those.
            Method::Preetham | Method::Hosek => self.analytic(method, turbidity, AnalyticUnits::Published, cases)?,
            Method::Linear => {
                let v: Vec<Rgb> = widen(self.probe.analytic(self.ctx, cases, |_| AnalyticModel::Linear(LinearParams::default()))?);
                v.into_iter().map(|c| c.map(dome::srgb_decode)).collect()
            }
            other => anyhow::bail!("{} is not evaluated on the GPU", other.model_name()),
        })
    }

    /// Radiance of `preetham` or `hosek` at `turbidity` in `units` for `cases`, on the GPU.
    fn analytic(&self, method: &Method, turbidity: f64, units: AnalyticUnits, cases: &[Case]) -> anyhow::Result<Vec<Rgb>> {
        let v = match method {
            Method::Preetham => self.probe.analytic(self.ctx, cases, |_| AnalyticModel::Preetham { turbidity, units })?,
            Method::Hosek => self.probe.analytic(self.ctx, cases, |c| AnalyticModel::Hosek { turbidity, albedo: c.albedo, units })?,
            other => anyhow::bail!("{} is not an analytic model with units", other.model_name()),
        };
        Ok(v.into_iter().map(|c| c.map(f64::from)).collect())
    }

    /// Radiance of `models[i]` for `cases[i]` on the GPU (the models' own units).
    pub fn analytic_each(&self, cases: &[Case], models: &[AnalyticModel]) -> anyhow::Result<Vec<Rgb>> {
        Ok(self.probe.analytic_each(self.ctx, cases, models)?.into_iter().map(|c| c.map(f64::from)).collect())
    }

    /// Makes `method` ready for `atm`: fits analytic models against `targets`, builds tables
    /// from the default `lut` model.
    pub fn prepare(&self, method: &Method, atm: &Atmosphere, targets: &[FitTarget<'_>]) -> anyhow::Result<Prepared> {
        let lut = Method::Lut(LutSettings::default());
        // The cases carry the sun elevation; the source needs nothing else.
        let mut source = |_sun_elev_deg: f64, cases: &[Case]| -> anyhow::Result<Vec<Rgb>> { self.gpu(&lut, atm, 0.0, cases) };
        Ok(match *method {
            Method::Single(_) | Method::Lut(_) | Method::Precomputed(_) => Prepared::Gpu(*method),
            Method::Preetham | Method::Hosek | Method::Linear => Prepared::Analytic(*method, self.fit(method, targets)?),
            Method::Cells(iterations) => Prepared::Cells(Box::new(CellModel::solve(*atm, dome::ALBEDO, CellSettings { iterations, ..Default::default() }))),
            Method::DomeMap(res) => Prepared::DomeMap(DomeMapTable::build(res, &mut source)?),
            Method::Regression => Prepared::Regression(Regression::build(&mut source)?),
            Method::Baked(rows) => {
                let hours: [f64; represent::BAKED_HOURS] = std::array::from_fn(|h| represent::equinox_elevation_deg(h as f64));
                Prepared::Baked(Baked::build(rows, &hours, &mut [&mut source])?)
            }
        })
    }

    /// The turbidity and scale that bring an analytic model closest to the reference (least
    /// squares of the relative error, every sun elevation of `targets` counting alike).
    pub fn fit(&self, method: &Method, targets: &[FitTarget<'_>]) -> anyhow::Result<Fit> {
        self.fit_with(method, targets, None)
    }

    /// The turbidity that brings an analytic model closest to the reference in mean dE2000 as it
    /// renders in `units` (no scale).
    pub fn fit_turbidity_unscaled(&self, method: &Method, units: AnalyticUnits, targets: &[FitTarget<'_>]) -> anyhow::Result<f64> {
        Ok(self.fit_with(method, targets, Some(units))?.turbidity)
    }

    /// The least-squares fit of turbidity and scale from the published unit, or with `unscaled`
    /// the turbidity alone in those units by mean dE2000.
    fn fit_with(&self, method: &Method, targets: &[FitTarget<'_>], unscaled: Option<AnalyticUnits>) -> anyhow::Result<Fit> {
        let scaled = unscaled.is_none();
        let units = unscaled.unwrap_or(AnalyticUnits::Published);
        let turbidities: Vec<f64> = match method {
            Method::Linear => vec![0.0],
            // Below its clamp Preetham's fit is the clamp's: the same point under another name.
            Method::Preetham => TURBIDITIES.into_iter().filter(|t| *t >= analytic::PREETHAM_MIN_TURBIDITY).collect(),
            _ => TURBIDITIES.to_vec(),
        };
        let mut best: Option<(f64, Fit)> = None;
        for turbidity in turbidities {
            let mut values = Vec::new();
            for t in targets {
                let cases = dome::cases(t.sun_elev_deg, t.dirs);
                values.push(match method {
                    Method::Preetham | Method::Hosek => self.analytic(method, turbidity, units, &cases)?,
                    _ => self.gpu(method, &Atmosphere::default(), turbidity, &cases)?,
                });
            }
            let (mut num, mut den) = (0.0, 0.0);
            for (t, m) in targets.iter().zip(&values) {
                let norm: f64 = t.dirs.iter().zip(t.radiance).map(|(d, r)| d.weight_sr * r.iter().map(|x| x * x).sum::<f64>()).sum::<f64>().max(1e-300);
                for ((d, r), m) in t.dirs.iter().zip(t.radiance).zip(m) {
                    for c in 0..3 {
                        num += d.weight_sr * m[c] * r[c] / norm;
                        den += d.weight_sr * m[c] * m[c] / norm;
                    }
                }
            }
            let scale = if !scaled {
                1.0
            } else if den > 0.0 {
                num / den
            } else {
                1.0
            };
            let error: f64 = targets
                .iter()
                .zip(&values)
                .map(|(t, m)| {
                    let with_scale: Vec<Rgb> = m.iter().map(|x| x.map(|c| c * scale)).collect();
                    let e = dome::dome_error(t.dirs, t.radiance, &with_scale);
                    if scaled {
                        e.rel_rmse_mean()
                    } else {
                        e.de_mean
                    }
                })
                .sum();
            if best.as_ref().is_none_or(|(e, _)| error < *e) {
                best = Some((error, Fit { turbidity, scale, units }));
            }
        }
        best.map(|b| b.1).ok_or_else(|| anyhow::anyhow!("no turbidity to fit"))
    }

    /// Radiance of a prepared point at one sun elevation (morning of the equinox day for the
    /// baked bitmaps) over `cases`.
    pub fn radiance(&self, prepared: &Prepared, atm: &Atmosphere, sun_elev_deg: f64, cases: &[Case]) -> anyhow::Result<Vec<Rgb>> {
        let each = |f: &dyn Fn(&Case) -> Rgb| cases.iter().map(f).collect::<Vec<Rgb>>();
        Ok(match prepared {
            Prepared::Gpu(m) => self.gpu(m, atm, 0.0, cases)?,
            Prepared::Analytic(m @ (Method::Preetham | Method::Hosek), fit) => {
                self.analytic(m, fit.turbidity, fit.units, cases)?.into_iter().map(|c| c.map(|x| x * fit.scale)).collect()
            }
            Prepared::Analytic(m, fit) => self.gpu(m, atm, fit.turbidity, cases)?.into_iter().map(|c| c.map(|x| x * fit.scale)).collect(),
            Prepared::Cells(model) => each(&|c| model.radiance(c)),
            Prepared::DomeMap(t) => each(&|c| t.radiance(sun_elev_deg, c.view_elev_deg, c.rel_azimuth_deg)),
            Prepared::Regression(r) => each(&|c| r.radiance(sun_elev_deg, c.view_elev_deg, c.rel_azimuth_deg)),
            Prepared::Baked(b) => {
                let hour = analytic::equinox_morning_hour(sun_elev_deg);
                each(&|c| b.radiance(0, hour, sun_elev_deg, c.view_elev_deg, c.rel_azimuth_deg))
            }
        })
    }
}

/// One point's figures: a row of docs/models.csv.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ChartRow {
    /// Point id.
    pub id: String,
    /// Model name.
    pub model: String,
    /// Mean relative RMSE of red.
    pub rel_rmse_r: f64,
    /// Mean relative RMSE of green.
    pub rel_rmse_g: f64,
    /// Mean relative RMSE of blue.
    pub rel_rmse_b: f64,
    /// Mean PSNR of the display image, dB.
    pub psnr_db: f64,
    /// Mean dE2000.
    pub de_mean: f64,
    /// Mean of the 95th percentiles of dE2000.
    pub de_p95: f64,
    /// Mean relative RMSE (over r, g, b) by day: sun above 10 degrees.
    pub rmse_day: f64,
    /// Mean relative RMSE at low sun: 0 to 10 degrees.
    pub rmse_low_sun: f64,
    /// Mean relative RMSE at twilight: sun at 0 degrees and below.
    pub rmse_twilight: f64,
    /// The reference's own relative noise over the dome by day (one standard error): the
    /// error bar of `rmse_day`.
    pub noise_day: f64,
    /// The reference's relative noise at low sun.
    pub noise_low_sun: f64,
    /// The reference's relative noise at twilight.
    pub noise_twilight: f64,
    /// Mean dE2000 by day.
    pub de_day: f64,
    /// Mean dE2000 at low sun.
    pub de_low_sun: f64,
    /// Mean dE2000 at twilight.
    pub de_twilight: f64,
    /// GPU ms of the model itself per frame with the sun moving: its sky-view map or tables
    /// recomputed (the compute phase of a frame drawing only the skydome).
    pub model_gpu_ms_moving: f64,
    /// GPU ms of the model itself per frame with the sun still.
    pub model_gpu_ms_still: f64,
    /// CPU ms per frame when the sun moves (CPU paths fill the sky-view map).
    pub cpu_ms: f64,
    /// Whole frame of the built-in sky drawn with the model, the sun moving, wall ms.
    pub frame_ms_moving: f64,
    /// Whole frame with the sun still, wall ms.
    pub frame_ms_still: f64,
    /// The adapter's fill-rate floor in the same run, wall ms (`skytune bench frame`'s).
    pub floor_ms: f64,
    /// One-off ms (tables, solving, fitting, baking).
    pub build_ms: f64,
    /// Fitted turbidity in the default atmosphere (analytic models).
    pub fit_turbidity: Option<f64>,
    /// Fitted radiance scale in the default atmosphere (analytic models).
    pub fit_scale: Option<f64>,
    /// On the Pareto front of (frame ms, mean dE2000).
    pub pareto: bool,
}

impl ChartRow {
    /// Mean relative RMSE per channel.
    pub fn rel_rmse(&self) -> Rgb {
        [self.rel_rmse_r, self.rel_rmse_g, self.rel_rmse_b]
    }

    /// Cost of a whole frame in which the sun moved, ms: the frame plus the CPU's share.
    pub fn frame_ms(&self) -> f64 {
        self.frame_ms_moving + self.cpu_ms
    }

    /// A whole frame with the sun moving as a multiple of the fill-rate floor.
    pub fn floor_ratio_moving(&self) -> f64 {
        self.frame_ms() / self.floor_ms
    }

    /// A whole frame with the sun still as a multiple of the fill-rate floor.
    pub fn floor_ratio_still(&self) -> f64 {
        self.frame_ms_still / self.floor_ms
    }

    /// Mean relative RMSE and the reference's noise in a regime.
    pub fn regime(&self, regime: dome::Regime) -> (f64, f64) {
        match regime {
            dome::Regime::Day => (self.rmse_day, self.noise_day),
            dome::Regime::LowSun => (self.rmse_low_sun, self.noise_low_sun),
            dome::Regime::Twilight => (self.rmse_twilight, self.noise_twilight),
        }
    }

    /// The chart's error axis: mean dE2000.
    pub fn error(&self) -> f64 {
        self.de_mean
    }
}

/// Marks the rows no other row beats in both frame cost and error.
pub fn mark_pareto(rows: &mut [ChartRow]) {
    let figures: Vec<(f64, f64)> = rows.iter().map(|r| (r.frame_ms(), r.error())).collect();
    for (i, r) in rows.iter_mut().enumerate() {
        let (c, e) = figures[i];
        r.pareto = !figures.iter().enumerate().any(|(j, &(c2, e2))| j != i && c2 <= c && e2 <= e && (c2 < c || e2 < e));
    }
}

/// docs/models.csv.
pub fn rows_to_csv(rows: &[ChartRow]) -> String {
    let mut w = csv::Writer::from_writer(Vec::new());
    for r in rows {
        let _ = w.serialize(r);
    }
    String::from_utf8_lossy(&w.into_inner().unwrap_or_default()).into_owned()
}

/// Reads docs/models.csv (as [`rows_to_csv`] writes it).
pub fn rows_from_csv(text: &str) -> Result<Vec<ChartRow>, csv::Error> {
    csv::Reader::from_reader(text.as_bytes()).deserialize().collect()
}

/// The last committed benchmark (docs/models.csv at build time): what the app charts and what
/// `model = "auto"` ranks costs by.
pub const COMMITTED_CSV: &str = include_str!("../../docs/models.csv");

/// One point's errors at one atmosphere and sun elevation: a row of docs/models-by-sun.csv.
#[derive(Debug, Clone, PartialEq)]
pub struct SunRow {
    /// Point id.
    pub id: String,
    /// Atmosphere name.
    pub haze: String,
    /// Sun elevation, degrees.
    pub sun_elev_deg: f64,
    /// Errors over the dome.
    pub error: dome::DomeError,
}

/// docs/models-by-sun.csv.
pub fn sun_rows_to_csv(rows: &[SunRow]) -> String {
    let mut s = String::from("id,haze,sun_elev_deg,rel_rmse_r,rel_rmse_g,rel_rmse_b,psnr_db,de_mean,de_p95\n");
    for r in rows {
        let e = &r.error;
        s.push_str(&format!(
            "{},{},{},{:.5},{:.5},{:.5},{:.2},{:.4},{:.4}\n",
            r.id, r.haze, r.sun_elev_deg, e.rel_rmse[0], e.rel_rmse[1], e.rel_rmse[2], e.psnr_db, e.de_mean, e.de_p95
        ));
    }
    s
}

/// The benchmark point a sky model is, if it is one (settings equal), else the point of its model
/// at default settings: where the app marks the current model on the chart.
pub fn point_for(model: &crate::sky::resolved::SkyModel) -> Option<String> {
    use crate::sky::resolved::SkyModelKind;
    let all = points();
    let exact = all.iter().find(|p| match p.method {
        Method::Single(s) => model.kind == SkyModelKind::Single && model.settings.single == s,
        Method::Lut(s) => model.kind == SkyModelKind::Lut && model.settings.lut == s,
        Method::Precomputed(s) => model.kind == SkyModelKind::Precomputed && model.settings.precomputed == s,
        Method::Cells(i) => model.kind == SkyModelKind::Cells && model.settings.cell_iterations as usize == i,
        Method::Preetham => model.kind == SkyModelKind::Preetham,
        Method::Hosek => model.kind == SkyModelKind::Hosek,
        Method::Linear => model.kind == SkyModelKind::Linear,
        _ => false,
    });
    let default = match model.kind {
        SkyModelKind::Single => Some("single-erf-32"),
        SkyModelKind::Lut => Some("lut-default"),
        SkyModelKind::Precomputed => Some("precomputed-default"),
        SkyModelKind::Cells => Some("cells-6"),
        _ => None,
    };
    exact.map(|p| p.id.clone()).or(default.map(String::from))
}

/// The calibration of an analytic model's published unit ([`AnalyticUnits::Calibrated`]): for
/// each sun of the committed reference dome at or above the horizon, in the default atmosphere,
/// the factor that gives the model at [`analytic::DEFAULT_TURBIDITY`] the reference's mean
/// displayed luminance over the sky above the horizon (solid-angle weighted; the default
/// exposure and tone mapper, [`dome::EXPOSURE_EV`] and ACES), by bisection (CPU, double
/// precision). On screen rather than in radiance: Preetham's sky is brighter overhead and darker
/// at the horizon than the reference's, so at equal mean radiance it looked 15 to 20% brighter;
/// the benchmark's least-squares fit of radiance follows the bright sky round the sun and left it
/// brighter still.
pub fn calibration(method: &Method) -> anyhow::Result<Vec<(f64, f64)>> {
    let model = match method {
        Method::Preetham => AnalyticModel::Preetham { turbidity: analytic::DEFAULT_TURBIDITY, units: AnalyticUnits::Published },
        Method::Hosek => AnalyticModel::Hosek { turbidity: analytic::DEFAULT_TURBIDITY, albedo: dome::ALBEDO, units: AnalyticUnits::Published },
        other => anyhow::bail!("only preetham and hosek are calibrated, not {}", other.model_name()),
    };
    let reference = dome::committed_reference()?;
    let dirs = dome::dome_directions(reference.dome.0, reference.dome.1);
    let shown = |radiance: &mut dyn Iterator<Item = Rgb>| -> f64 {
        dirs.iter()
            .zip(radiance)
            .map(|(d, r)| {
                let c = crate::render::passes::tone_map::tone_map_aces(r.map(|x| x * dome::EXPOSURE_EV.exp2()));
                d.weight_sr * (0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2])
            })
            .sum()
    };
    let mut table = Vec::new();
    for s in reference.suns.iter().filter(|s| s.haze == dome::Haze::Default && s.sun_elev_deg >= 0.0) {
        let sun = analytic::direction(s.sun_elev_deg.to_radians(), 0.0);
        let published: Vec<Rgb> = dirs.iter().map(|d| model.radiance(analytic::direction(d.elev_deg.to_radians(), d.rel_az_deg.to_radians()), sun, 12.0)).collect();
        let target = shown(&mut s.radiance.iter().copied());
        // The mean display grows with the factor: bisect its logarithm.
        let (mut lo, mut hi) = (-12.0f64, 4.0f64);
        anyhow::ensure!(
            shown(&mut published.iter().map(|c| c.map(|x| x * hi.exp()))) > target,
            "{} cannot reach the reference's brightness at sun {} degrees",
            model.name(),
            s.sun_elev_deg
        );
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if shown(&mut published.iter().map(|c| c.map(|x| x * mid.exp()))) < target {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        table.push((s.sun_elev_deg, (0.5 * (lo + hi)).exp()));
    }
    table.sort_by(|a, b| a.0.total_cmp(&b.0));
    Ok(table)
}
