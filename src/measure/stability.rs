//! Stability where methods fail (`skytune sweep`): random parameter sets across and beyond each
//! model's domain, counting NaN, infinite, negative and discontinuous radiance. The shipped
//! models clamp or fall back outside their domains, so every counter should be zero; the raw
//! published fits are swept too, to show what the clamps prevent.
//!
//! Discontinuity: the same case with the sun [`JUMP_DELTA_DEG`] lower and higher; see [`jump`].

use crate::atmosphere::analytic::{self, Preetham};
use crate::atmosphere::cells::{CellModel, CellSettings};
use crate::atmosphere::reference::Case;
use crate::atmosphere::{Atmosphere, LutSettings, OpticalDepth, PrecomputedSettings, Rgb, SingleSettings};
use crate::measure::model_points::{Evaluator, Method};
use crate::support::shard::Shard;

/// Step of the sun between the two evaluations of a case, degrees.
pub const JUMP_DELTA_DEG: f64 = 0.05;
/// Largest change of a channel over that step, relative to the brightest channel of the two
/// results (a decade every 3 degrees, the steepest twilight in any model, changes by 4%).
pub const JUMP_RELATIVE: f64 = 0.25;
/// A jump's step is also this many times larger than the neighbouring step.
pub const JUMP_STEP_RATIO: f64 = 4.0;
/// A candidate's step is re-evaluated in this many sub-steps (see [`refined_is_jump`]).
pub const JUMP_REFINE: usize = 8;
/// Changes below this are not jumps, sr^-1 (a thousandth of a dark twilight sky).
pub const JUMP_FLOOR_SR: f64 = 1e-7;

/// A swept model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SweptModel {
    /// `single` with the erf optical depth.
    SingleErf,
    /// `single` with numerical optical depth.
    SingleNumerical,
    /// `lut` at its defaults.
    Lut,
    /// `precomputed` with its small tables (`PrecomputedSettings::SMALL`; a few atmospheres and
    /// one ground albedo each, since each builds its tables). The lookup, the parametrisation and
    /// the build are those of the defaults, which cost 30 times the build (70 s per atmosphere
    /// on lavapipe).
    Precomputed,
    /// `cells` (6 iterations; a few atmospheres, since each is solved).
    Cells,
    /// `preetham` as shipped.
    Preetham,
    /// `hosek` as shipped.
    Hosek,
    /// `linear` as shipped.
    Linear,
    /// Preetham's published fit without the clamps (CPU; zenith luminance).
    PreethamRaw,
    /// Hosek-Wilkie's published model without the clamps (CPU, the `hw-skymodel` crate).
    HosekRaw,
}

impl SweptModel {
    /// Shipped models, then the raw fits.
    pub const ALL: [SweptModel; 10] = [
        SweptModel::SingleErf,
        SweptModel::SingleNumerical,
        SweptModel::Lut,
        SweptModel::Precomputed,
        SweptModel::Cells,
        SweptModel::Preetham,
        SweptModel::Hosek,
        SweptModel::Linear,
        SweptModel::PreethamRaw,
        SweptModel::HosekRaw,
    ];

    /// Name in the report.
    pub fn name(self) -> &'static str {
        match self {
            SweptModel::SingleErf => "single (erf)",
            SweptModel::SingleNumerical => "single (numerical)",
            SweptModel::Lut => "lut",
            SweptModel::Precomputed => "precomputed (small tables)",
            SweptModel::Cells => "cells",
            SweptModel::Preetham => "preetham",
            SweptModel::Hosek => "hosek",
            SweptModel::Linear => "linear",
            SweptModel::PreethamRaw => "preetham, published fit unclamped",
            SweptModel::HosekRaw => "hosek, published model unclamped",
        }
    }

    /// Whether skytune ships it (its counters must be zero).
    pub fn shipped(self) -> bool {
        !matches!(self, SweptModel::PreethamRaw | SweptModel::HosekRaw)
    }
}

/// One random parameter set.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SweepCase {
    /// The atmosphere.
    pub atmosphere: Atmosphere,
    /// The view, sun and camera.
    pub case: Case,
    /// Turbidity of the analytic models.
    pub turbidity: f64,
}

/// What a sweep found for one model.
#[derive(Debug, Clone, Default)]
pub struct Counters {
    /// Parameter sets evaluated (each three times: the sun moved by -[`JUMP_DELTA_DEG`], 0, +).
    pub evaluated: u64,
    /// Results with a NaN channel.
    pub nan: u64,
    /// Results with an infinite channel.
    pub infinite: u64,
    /// Results with a negative channel.
    pub negative: u64,
    /// Jumps between the two sun elevations.
    pub discontinuous: u64,
    /// Cases that could not be evaluated at all (the raw Hosek model refuses a sun below the horizon).
    pub refused: u64,
    /// The first cases that went wrong (at most [`WORST_KEPT`], in the order of the sets).
    pub worst: Vec<Worst>,
    /// The batch (one atmosphere) being checked: notes carry it, so that a merge of shards
    /// keeps the same first cases as one run.
    batch: usize,
}

/// How many failing cases a sweep keeps per model.
pub const WORST_KEPT: usize = 3;

/// A failing case.
#[derive(Debug, Clone)]
pub struct Worst {
    /// Index of its batch (one atmosphere) among the sweep's.
    pub batch: usize,
    /// What went wrong.
    pub what: String,
    /// The parameters.
    pub case: SweepCase,
}

impl Worst {
    /// The report's line for this case.
    pub fn line(&self) -> String {
        let (case, a) = (&self.case, &self.case.atmosphere);
        format!(
            "{}: sun {:.3} deg, view {:.3} deg, azimuth {:.1} deg, camera {:.3} km, turbidity {:.2}; ground radius {:.0} km, thickness {:.0} km, Rayleigh {:.3e} km^-1 (blue), Mie {:.3e} km^-1",
            self.what,
            case.case.sun_elev_deg,
            case.case.view_elev_deg,
            case.case.rel_azimuth_deg,
            case.case.camera_km,
            case.turbidity,
            a.ground_radius_km,
            a.thickness_km(),
            a.rayleigh_scattering_per_km[2],
            a.mie_scattering_per_km[1]
        )
    }
}

impl Counters {
    /// Sum of the failure counters.
    pub fn failures(&self) -> u64 {
        self.nan + self.infinite + self.negative + self.discontinuous + self.refused
    }

    fn note(&mut self, what: String, case: &SweepCase) {
        if self.worst.len() < WORST_KEPT {
            self.worst.push(Worst { batch: self.batch, what, case: *case });
        }
    }

    /// Checks the results at the sun elevations s - delta, s and s + delta; returns a jump
    /// candidate (channel, start of its step relative to s) for [`sweep`] to refine.
    fn check(&mut self, v: [Rgb; 3], case: &SweepCase) -> Option<(usize, f64)> {
        self.evaluated += 1;
        for x in v {
            if x.iter().any(|c| c.is_nan()) {
                self.nan += 1;
                self.note(format!("NaN {x:?}"), case);
            } else if x.iter().any(|c| c.is_infinite()) {
                self.infinite += 1;
                self.note(format!("infinite {x:?}"), case);
            } else if x.iter().any(|c| *c < 0.0) {
                self.negative += 1;
                self.note(format!("negative {x:?}"), case);
            }
        }
        jump_candidate(v)
    }
}

/// A jump candidate: one of the two steps changes a channel by more than [`JUMP_RELATIVE`] of the
/// brightest channel plus [`JUMP_FLOOR_SR`], and by more than [`JUMP_STEP_RATIO`] times the other
/// step (a steep but smooth change, as a twilight on a small planet, changes alike over both).
/// Returns the channel and where its step starts relative to the middle sun elevation.
pub fn jump_candidate(v: [Rgb; 3]) -> Option<(usize, f64)> {
    if v.iter().flatten().any(|c| !c.is_finite()) {
        return None;
    }
    let brightest = v.iter().flatten().fold(0.0f64, |m, c| m.max(c.abs()));
    (0..3).find_map(|c| {
        let (d1, d2) = ((v[1][c] - v[0][c]).abs(), (v[2][c] - v[1][c]).abs());
        let (big, small) = (d1.max(d2), d1.min(d2));
        (big > JUMP_RELATIVE * brightest + JUMP_FLOOR_SR && big > JUMP_STEP_RATIO * small + JUMP_FLOOR_SR).then_some((c, if d1 >= d2 { -JUMP_DELTA_DEG } else { 0.0 }))
    })
}

/// Whether a candidate's step is a jump, from one channel re-evaluated at [`JUMP_REFINE`] + 3 evenly
/// spaced sun elevations: one sub-step before the step, the step in [`JUMP_REFINE`] sub-steps, one
/// after. A jump: one inner sub-step holds more than half of the step's change and is more than
/// [`JUMP_STEP_RATIO`] times each of its neighbours (a kink, even at the step's end, continues into
/// the neighbouring sub-step; a discontinuity does not).
pub fn refined_is_jump(v: &[f64]) -> bool {
    let n = v.len();
    if n < 4 {
        return false;
    }
    let step = |k: usize| (v[k + 1] - v[k]).abs();
    let whole = (v[n - 2] - v[1]).abs();
    let Some(k) = (1..n - 2).max_by(|a, b| step(*a).total_cmp(&step(*b))) else { return false };
    step(k) > 0.5 * whole && step(k) > JUMP_STEP_RATIO * step(k - 1).max(step(k + 1))
}

/// A small deterministic generator (splitmix64), so a sweep is reproducible from its seed.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }

    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
}

/// A random valid atmosphere from very thin to very thick, on planets from 100 km to 100,000 km.
fn random_atmosphere(rng: &mut Rng) -> Atmosphere {
    let base = Atmosphere::default();
    let k = 10f64.powf(rng.range(-3.0, 1.5));
    let aerosols = 10f64.powf(rng.range(-2.0, 1.5));
    let ground_radius_km = if rng.next() < 0.7 { base.ground_radius_km } else { 10f64.powf(rng.range(2.0, 5.0)) };
    let thickness = if rng.next() < 0.7 { base.thickness_km() } else { rng.range(10.0, 400.0) };
    Atmosphere {
        ground_radius_km,
        top_radius_km: ground_radius_km + thickness,
        mie_scattering_per_km: base.mie_scattering_per_km.map(|b| b * aerosols),
        mie_extinction_per_km: base.mie_extinction_per_km.map(|b| b * aerosols),
        mie_g: rng.range(-0.95, 0.95),
        ..base.scaled(k)
    }
}

/// `count` random cases with `per_atmosphere` cases per atmosphere: suns from -18 degrees
/// (half of them within 3 degrees of the horizon), views all round (half near the horizon), the
/// camera on the ground, in the air, or above the top of the atmosphere, turbidity 0.5..15.
pub fn random_cases(count: usize, per_atmosphere: usize, seed: u64) -> Vec<SweepCase> {
    let mut rng = Rng(seed);
    let mut out = Vec::with_capacity(count);
    // The ground albedo goes with the atmosphere: the `lut` tables and the cell model are built
    // per (atmosphere, albedo).
    let mut atmosphere = random_atmosphere(&mut rng);
    let mut albedo = rng.next();
    for i in 0..count {
        if i % per_atmosphere.max(1) == 0 && i > 0 {
            atmosphere = random_atmosphere(&mut rng);
            albedo = rng.next();
        }
        let top = atmosphere.thickness_km();
        let camera_km = match rng.next() {
            x if x < 0.4 => 0.0,
            x if x < 0.8 => rng.range(0.0, top),
            _ => rng.range(top, 3.0 * top),
        };
        let sun_elev_deg = if rng.next() < 0.5 { rng.range(-18.0, 90.0) } else { rng.range(-3.0, 3.0) };
        let view_elev_deg = if rng.next() < 0.5 { rng.range(-90.0, 90.0) } else { rng.range(-5.0, 5.0) };
        let case = Case { camera_km, albedo, sun_elev_deg, view_elev_deg, rel_azimuth_deg: rng.range(0.0, 360.0), distance_km: None };
        out.push(SweepCase { atmosphere, case, turbidity: rng.range(0.5, 15.0) });
    }
    out
}

/// Cases per atmosphere of each model (the cell model is solved per atmosphere, the LUTs built).
fn per_atmosphere(model: SweptModel) -> usize {
    match model {
        SweptModel::Cells | SweptModel::Precomputed => 5000,
        _ => 1000,
    }
}

/// Batches (one atmosphere each) of a sweep of `count` sets of `model`.
pub fn batches(model: SweptModel, count: usize) -> usize {
    count.div_ceil(per_atmosphere(model))
}

/// Sweeps one model over `count` parameter sets, or over the batches (atmospheres) of them that
/// `shard` owns; `progress(done)` after each atmosphere.
pub fn sweep(ev: &Evaluator<'_>, model: SweptModel, count: usize, seed: u64, shard: Shard, progress: &mut dyn FnMut(usize)) -> anyhow::Result<Counters> {
    let cases = random_cases(count, per_atmosphere(model), seed);
    let mut counters = Counters::default();
    for (b, batch) in cases.chunks(per_atmosphere(model)).enumerate() {
        if !shard.owns(b) {
            continue;
        }
        counters.batch = b;
        let atm = batch[0].atmosphere;
        // The cell model is solved once per atmosphere (and ground albedo of its first case).
        let cells = (model == SweptModel::Cells).then(|| CellModel::solve(atm, batch[0].case.albedo, CellSettings::default()));
        let evaluate = |cases: &[SweepCase]| evaluate(ev, model, cells.as_ref(), &atm, cases);
        let at = |d: f64| -> Vec<SweepCase> { batch.iter().map(|c| SweepCase { case: Case { sun_elev_deg: c.case.sun_elev_deg + d, ..c.case }, ..*c }).collect() };
        let (a, b, c) = (evaluate(&at(-JUMP_DELTA_DEG))?, evaluate(batch)?, evaluate(&at(JUMP_DELTA_DEG))?);
        let mut candidates = Vec::new();
        for (i, case) in batch.iter().enumerate() {
            match (a[i], b[i], c[i]) {
                (Some(x), Some(y), Some(z)) => {
                    if let Some((channel, from_deg)) = counters.check([x, y, z], case) {
                        candidates.push((i, channel, from_deg));
                    }
                }
                _ => {
                    counters.evaluated += 1;
                    counters.refused += 1;
                    counters.note("refused".into(), case);
                }
            }
        }
        // A candidate is a jump only if the change does not spread when the step is refined.
        let mut refined = Vec::new();
        for &(i, _, from_deg) in &candidates {
            for k in 0..JUMP_REFINE + 3 {
                let sun = batch[i].case.sun_elev_deg + from_deg + JUMP_DELTA_DEG * (k as f64 - 1.0) / JUMP_REFINE as f64;
                refined.push(SweepCase { case: Case { sun_elev_deg: sun, ..batch[i].case }, ..batch[i] });
            }
        }
        let values = if refined.is_empty() { Vec::new() } else { evaluate(&refined)? };
        for (n, &(i, channel, _)) in candidates.iter().enumerate() {
            let v: Vec<f64> = values[n * (JUMP_REFINE + 3)..(n + 1) * (JUMP_REFINE + 3)].iter().map(|x| x.map_or(f64::NAN, |x| x[channel])).collect();
            if refined_is_jump(&v) {
                counters.discontinuous += 1;
                counters
                    .note(format!("jump in channel {channel}: {:.4e} to {:.4e} within {:.4} degrees of sun", v[0], v[JUMP_REFINE], JUMP_DELTA_DEG / JUMP_REFINE as f64), &batch[i]);
            }
        }
        progress(batch.len());
    }
    Ok(counters)
}

/// One model over cases that share an atmosphere; `None` where the model refuses.
fn evaluate(ev: &Evaluator<'_>, model: SweptModel, cells: Option<&CellModel>, atm: &Atmosphere, cases: &[SweepCase]) -> anyhow::Result<Vec<Option<Rgb>>> {
    let plain: Vec<Case> = cases.iter().map(|c| c.case).collect();
    let some = |v: Vec<Rgb>| v.into_iter().map(Some).collect();
    let single = |optical_depth| Method::Single(SingleSettings { optical_depth, ..Default::default() });
    let view = |c: &Case| analytic::direction(c.view_elev_deg.to_radians(), c.rel_azimuth_deg.to_radians());
    let sun = |c: &Case| analytic::direction(c.sun_elev_deg.to_radians(), 0.0);
    Ok(match model {
        SweptModel::SingleErf => some(ev.gpu(&single(OpticalDepth::Erf), atm, 0.0, &plain)?),
        SweptModel::SingleNumerical => some(ev.gpu(&single(OpticalDepth::Numerical), atm, 0.0, &plain)?),
        SweptModel::Lut => some(ev.gpu(&Method::Lut(LutSettings::default()), atm, 0.0, &plain)?),
        SweptModel::Precomputed => {
            // One ground albedo per atmosphere (the first case's), as for `cells`: one table build.
            let one: Vec<Case> = plain.iter().map(|c| Case { albedo: plain[0].albedo, ..*c }).collect();
            some(ev.gpu(&Method::Precomputed(PrecomputedSettings::SMALL), atm, 0.0, &one)?)
        }
        SweptModel::Cells => {
            let m = cells.ok_or_else(|| anyhow::anyhow!("the cell model was not solved"))?;
            plain.iter().map(|c| Some(m.radiance(c))).collect()
        }
        SweptModel::Preetham | SweptModel::Hosek | SweptModel::Linear => {
            let models: Vec<analytic::AnalyticModel> = cases
                .iter()
                .map(|c| match model {
                    SweptModel::Preetham => analytic::AnalyticModel::Preetham { turbidity: c.turbidity, units: Default::default() },
                    SweptModel::Hosek => analytic::AnalyticModel::Hosek { turbidity: c.turbidity, albedo: c.case.albedo, units: Default::default() },
                    _ => analytic::AnalyticModel::Linear(analytic::LinearParams::default()),
                })
                .collect();
            some(ev.analytic_each(&plain, &models)?)
        }
        SweptModel::PreethamRaw => cases
            .iter()
            .map(|c| {
                let p = Preetham::unclamped(c.turbidity, c.case.sun_elev_deg.to_radians(), sun(&c.case));
                let [y, x, yy] = p.xy_y(view(&c.case));
                Some([y * x / yy.max(1e-9), y, y * (1.0 - x - yy) / yy.max(1e-9)])
            })
            .collect(),
        SweptModel::HosekRaw => cases
            .iter()
            .map(|c| {
                let params = hw_skymodel::rgb::SkyParams { elevation: c.case.sun_elev_deg.to_radians() as f32, turbidity: c.turbidity as f32, albedo: [c.case.albedo as f32; 3] };
                let state = hw_skymodel::rgb::SkyState::new(&params).ok()?;
                let v = view(&c.case);
                let theta = v[1].clamp(-1.0, 1.0).acos() as f32;
                let s = sun(&c.case);
                let gamma = (v[0] * s[0] + v[1] * s[1] + v[2] * s[2]).clamp(-1.0, 1.0).acos() as f32;
                use hw_skymodel::rgb::Channel;
                Some(
                    [Channel::R, Channel::G, Channel::B]
                        .map(|ch| state.radiance(theta, gamma, ch) as f64 * analytic::calibration_at(&analytic::HOSEK_CALIBRATION, c.case.sun_elev_deg)),
                )
            })
            .collect(),
    })
}
