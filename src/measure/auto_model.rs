//! `kind = "auto"` in `[sky_model]`: the cheapest model and setting whose error against the
//! reference, over the sky's own range of sun elevations and weathers, stays within the budget.
//!
//! - Candidates: the benchmark's points a sky file can select ([`model_points::Point::auto`]),
//!   ranked by the frame cost of the committed benchmark (docs/models.csv, embedded), ties by id:
//!   the same inputs give the same pick on any machine. They are measured in that order up to
//!   the first within the budget (the pick), then only those quick to measure up to the next one
//!   within it (the runner-up) ([`Scores`]): the pick is the full measurement's, and the default
//!   `precomputed` tables (minutes on a software adapter) are not built for a runner-up.
//! - Error: for each weather step's atmosphere and each sun elevation of the benchmark that the
//!   sky's sun reaches (plus the one on either side of its range), the mean CIE dE2000 over the
//!   benchmark's dome at its fixed exposure, seen from the sky's camera altitude and ground
//!   albedo; a candidate's error is the worst of these. Analytic models are measured as they
//!   render: in the sky's `analytic_units`, the turbidity fitted to the atmosphere.
//! - Reference: the committed dataset for the benchmark's atmospheres seen from its ground (on
//!   the ground, albedo 0.3), else computed once (to a 4% standard error:
//!   [`custom_reference_settings`]) and cached on disk per atmosphere and ground, as are picks,
//!   so loading stays fast.

use std::collections::HashMap;
use std::hash::{Hash, Hasher};
use std::path::PathBuf;
use std::sync::Mutex;

use crate::atmosphere::dome::{self, DomeDir, Haze};
use crate::atmosphere::reference::ReferenceSettings;
use crate::atmosphere::{Atmosphere, Rgb};
use crate::measure::model_points::{self, Evaluator, FitTarget, Method, Prepared};
use crate::sky::resolved::{Budget, SkyModel, SkyModelKind};
use crate::sky::Sky;
use crate::support::progress::{Job, Phase};

/// A candidate with its measured error and cost.
#[derive(Debug, Clone, PartialEq)]
pub struct Scored {
    /// Point id (`lut-small`).
    pub id: String,
    /// The model and settings.
    pub method: Method,
    /// Turbidity fitted per weather step (analytic models; the first is used).
    pub turbidity: f64,
    /// Worst mean dE2000 over the sky's conditions.
    pub de2000: f64,
    /// Frame cost in the committed benchmark, ms.
    pub cost_ms: f64,
    /// Whether it is quick to measure (tables built within [`RUNNER_UP_MAX_BUILD_MS`]): only
    /// such candidates are runners-up.
    pub quick: bool,
}

/// What `auto` picked.
#[derive(Debug, Clone, PartialEq)]
pub struct Pick {
    /// The cheapest candidate within the budget (or the most accurate when none is).
    pub chosen: Scored,
    /// The next cheapest candidate within the budget among those quick to measure
    /// ([`Scored::quick`]).
    pub runner_up: Option<Scored>,
    /// Whether the chosen one meets the budget.
    pub within_budget: bool,
    /// The budget.
    pub budget: Budget,
    /// Sun elevations measured, degrees.
    pub suns_deg: Vec<f64>,
}

impl Pick {
    /// One line for `skytune check` and the app.
    pub fn describe(&self) -> String {
        let c = &self.chosen;
        let runner = self.runner_up.as_ref().map_or_else(|| "none".to_string(), |r| format!("{} (dE2000 {:.2}, {:.1} ms)", r.id, r.de2000, r.cost_ms));
        format!(
            "auto model: {} (dE2000 {:.2} {} budget {:.2}, {:.1} ms per frame in the committed benchmark); runner-up {runner}",
            c.id,
            c.de2000,
            if self.within_budget { "within" } else { "OVER" },
            self.budget.de2000,
            c.cost_ms
        )
    }

    /// The sky model the pick stands for, from `base` (exposure, tone mapper, ...).
    pub fn model(&self, base: &SkyModel) -> SkyModel {
        let c = &self.chosen;
        let mut m = *base;
        let s = &mut m.settings;
        m.kind = match c.method {
            Method::Single(single) => {
                s.single = single;
                SkyModelKind::Single
            }
            Method::Lut(lut) => {
                s.lut = lut;
                SkyModelKind::Lut
            }
            Method::Precomputed(precomputed) => {
                s.precomputed = precomputed;
                SkyModelKind::Precomputed
            }
            Method::Cells(i) => {
                s.cell_iterations = i as u32;
                SkyModelKind::Cells
            }
            Method::Preetham | Method::Hosek => {
                s.analytic.turbidity = c.turbidity as f32;
                s.analytic.turbidity_from_atmosphere = false;
                if c.method == Method::Preetham {
                    SkyModelKind::Preetham
                } else {
                    SkyModelKind::Hosek
                }
            }
            _ => return *base,
        };
        m
    }
}

/// A candidate of `auto`: a point of the chart with its committed costs.
#[derive(Debug, Clone, PartialEq)]
pub struct Candidate {
    /// The point.
    pub point: model_points::Point,
    /// Frame cost in the committed benchmark, ms.
    pub cost_ms: f64,
    /// One-off cost (building its tables) in the committed benchmark, ms.
    pub build_ms: f64,
}

/// Longest table build, in the committed benchmark, of a candidate measured only to name a
/// runner-up: the default `precomputed` tables (139 s on lavapipe) would more than double the
/// time of a first pick for a line of information, while every other candidate builds in under
/// 6 s.
pub const RUNNER_UP_MAX_BUILD_MS: f64 = 10_000.0;

impl Candidate {
    /// Whether it may be measured to name a runner-up ([`RUNNER_UP_MAX_BUILD_MS`]).
    pub fn quick(&self) -> bool {
        self.build_ms <= RUNNER_UP_MAX_BUILD_MS
    }
}

/// The candidates with their committed costs, cheapest first: by frame cost, then by one-off cost
/// (building tables: `precomputed` points cost the same per frame whatever their size), then by id.
pub fn candidates() -> Vec<Candidate> {
    let costs: HashMap<String, (f64, f64)> =
        model_points::rows_from_csv(model_points::COMMITTED_CSV).unwrap_or_default().into_iter().map(|r| (r.id.clone(), (r.frame_ms(), r.build_ms))).collect();
    let mut out: Vec<Candidate> = model_points::points()
        .into_iter()
        .filter(|p| p.auto)
        .filter_map(|p| costs.get(&p.id).copied().map(|(cost_ms, build_ms)| Candidate { point: p, cost_ms, build_ms }))
        .collect();
    out.sort_by(|a, b| a.cost_ms.total_cmp(&b.cost_ms).then_with(|| a.build_ms.total_cmp(&b.build_ms)).then_with(|| a.point.id.cmp(&b.point.id)));
    out
}

/// The benchmark's sun elevations the sky needs: those within the range its sun reaches over a
/// day, and one on either side.
pub fn sky_suns(sky: &Sky) -> Vec<f64> {
    let steps = 96;
    let elevations: Vec<f64> = (0..steps).map(|k| sky.path_at(sky.sun_path, k as f32 / steps as f32 * sky.hours_per_day).0.y.clamp(-1.0, 1.0).asin().to_degrees() as f64).collect();
    let lo = elevations.iter().cloned().fold(f64::MAX, f64::min);
    let hi = elevations.iter().cloned().fold(f64::MIN, f64::max);
    let table = &dome::SUN_ELEVATIONS_DEG;
    let first = table.iter().rposition(|s| *s <= lo).unwrap_or(0);
    let last = table.iter().position(|s| *s >= hi).unwrap_or(table.len() - 1);
    table[first..=last].to_vec()
}

/// The atmospheres of the sky's weather steps (one when it has no weather table).
pub fn sky_atmospheres(sky: &Sky) -> Vec<Atmosphere> {
    if sky.atmosphere_by_weather.is_empty() {
        vec![sky.atmosphere]
    } else {
        sky.atmosphere_by_weather.clone()
    }
}

/// Where computed references and picks are cached ($XDG_CACHE_HOME/skytune, ~/.cache/skytune).
fn cache_dir() -> Option<PathBuf> {
    std::env::var_os("XDG_CACHE_HOME").map(PathBuf::from).or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache"))).map(|d| d.join("skytune"))
}

fn hash_of(x: &impl std::fmt::Debug) -> u64 {
    let mut h = std::collections::hash_map::DefaultHasher::new();
    format!("{x:?}").hash(&mut h);
    h.finish()
}

/// The reference's settings for atmospheres outside the benchmark: paths until a relative
/// standard error of 4% per channel, from 128 paths (two batches) to 512. A pick compares mean
/// dE2000 over the dome against a budget of about 2, which noise of a few percent per direction
/// barely moves; most day directions meet it at the first look, twilight ones draw up to 512.
/// Single scattering takes its sunlight from the table too: with so few paths, its quadrature
/// was most of the time, and the table's 4e-4 is far below the paths' noise.
pub fn custom_reference_settings() -> ReferenceSettings {
    ReferenceSettings {
        paths: 512,
        target_rel_se: Some(0.04),
        min_paths: 128,
        single_sunlight: crate::atmosphere::reference::SunlightBy::Table,
        seed: dome::REFERENCE_SEED,
        ..Default::default()
    }
}

/// The committed or cached reference for `atm` at `suns` seen from `ground`, if there is one (no
/// computing). The committed dataset is seen from the benchmark's ground only.
fn known_reference(atm: &Atmosphere, suns: &[f64], ground: dome::Ground) -> Option<anyhow::Result<Vec<Vec<Rgb>>>> {
    if let Some(haze) = Haze::of(atm).filter(|_| ground == dome::Ground::BENCH) {
        let committed = match dome::committed_reference() {
            Ok(c) => c,
            Err(e) => return Some(Err(e.into())),
        };
        return Some(suns.iter().map(|s| committed.sun(haze, *s).map(|r| r.radiance.clone()).ok_or_else(|| anyhow::anyhow!("the committed reference lacks sun {s}"))).collect());
    }
    let text = reference_file(atm, suns, ground).and_then(|f| std::fs::read_to_string(f).ok())?;
    let rows: Vec<Vec<Rgb>> = text.lines().map(|l| l.split(';').map(|v| parse_rgb(v).unwrap_or([f64::NAN; 3])).collect()).collect();
    (rows.len() == suns.len() && rows.iter().flatten().flatten().all(|v| v.is_finite())).then_some(Ok(rows))
}

/// Where the reference computed for `atm` at `suns` seen from `ground` is cached.
fn reference_file(atm: &Atmosphere, suns: &[f64], ground: dome::Ground) -> Option<PathBuf> {
    // The benchmark's ground keeps the key files cached before the ground was part of it had.
    let seen_from = (ground != dome::Ground::BENCH).then_some(ground);
    let key = match seen_from {
        None => hash_of(&(atm, suns, dome::ReferenceDome::header(custom_reference_settings(), dome::BENCH_DOME))),
        Some(g) => hash_of(&(atm, suns, dome::ReferenceDome::header(custom_reference_settings(), dome::BENCH_DOME), g)),
    };
    cache_dir().map(|d| d.join(format!("reference-{key:016x}.csv")))
}

/// Computes the reference over the benchmark's dome for an atmosphere no dataset holds (a minute
/// or more on two cores; reported through `phase`, stopped when its job is cancelled), and caches
/// it on disk.
fn compute_reference(atm: &Atmosphere, suns: &[f64], ground: dome::Ground, phase: Phase<'_>) -> anyhow::Result<Vec<Vec<Rgb>>> {
    let file = reference_file(atm, suns, ground);
    log::info!("auto model: computing the reference for this atmosphere at {} sun elevations, camera at {} km (once; cached)", suns.len(), ground.camera_km);
    let domes = dome::compute_domes_from(ground, &[*atm], suns, dome::BENCH_DOME, custom_reference_settings(), &|done, total| {
        phase.report(done, total);
        phase.job.check()
    })?;
    let rows: Vec<Vec<Rgb>> = domes.into_iter().map(|d| d.2).collect();
    if let Some(f) = file {
        let text: String = rows.iter().map(|r| r.iter().map(|c| format!("{:e},{:e},{:e}", c[0], c[1], c[2])).collect::<Vec<_>>().join(";") + "\n").collect();
        if let Some(dir) = f.parent() {
            let _ = std::fs::create_dir_all(dir);
        }
        if let Err(e) = crate::support::safe_write::write_atomic(&f, text.as_bytes()) {
            log::warn!("auto model: cannot cache the reference: {e}");
        }
    }
    Ok(rows)
}

fn parse_rgb(s: &str) -> Option<Rgb> {
    let v: Vec<f64> = s.split(',').filter_map(|x| x.trim().parse().ok()).collect();
    (v.len() == 3).then(|| [v[0], v[1], v[2]])
}

/// Share of a pick's progress that computing one reference takes (measuring the candidates
/// against it is the rest): about what the two cost on a software adapter.
const REFERENCE_SHARE: f64 = 0.85;

/// What is known of a sky's candidates: each one's score where it is measured, in the order of
/// [`candidates`] (cheapest first).
///
/// A pick needs only some of them: the cheapest candidate within the budget is the pick, whatever
/// comes after it, and the runner-up is the next one within it that is quick to measure. So the
/// candidates are measured in order up to the pick, then only the quick ones up to a runner-up;
/// the rest (the default `precomputed` tables, minutes on a software adapter) are not built for
/// nothing. Only a budget that nothing meets needs every candidate (the most accurate).
#[derive(Debug, Clone, PartialEq)]
pub struct Scores {
    /// Per candidate, in order: its score, if measured.
    pub slots: Vec<Option<Scored>>,
    /// Per candidate, in order: whether it is quick to measure ([`Candidate::quick`]).
    pub quick: Vec<bool>,
}

impl Scores {
    /// Nothing measured of candidates whose quickness is `quick`.
    pub fn empty(quick: Vec<bool>) -> Self {
        Self { slots: vec![None; quick.len()], quick }
    }

    /// The candidates measured, cheapest first.
    pub fn measured(&self) -> Vec<Scored> {
        self.slots.iter().flatten().cloned().collect()
    }

    /// The next candidate to measure before the pick for `budget` is decided (every candidate
    /// for `None`), or `None` when it is.
    pub fn next_needed(&self, budget: Option<Budget>) -> Option<usize> {
        let Some(budget) = budget else { return self.slots.iter().position(Option::is_none) };
        let mut chosen = false;
        for (n, slot) in self.slots.iter().enumerate() {
            if chosen && !self.quick[n] {
                continue;
            }
            let Some(score) = slot else { return Some(n) };
            let within = score.de2000 <= budget.de2000;
            if within && chosen {
                return None;
            }
            chosen |= within;
        }
        // Nothing within (every candidate is measured) or no runner-up after the pick.
        None
    }

    /// Whether what is measured decides the pick for `budget`.
    pub fn decides(&self, budget: Budget) -> bool {
        self.next_needed(Some(budget)).is_none()
    }

    /// The pick for `budget`, if what is measured decides it ([`Scores::decides`]).
    pub fn pick(&self, budget: Budget, suns_deg: Vec<f64>) -> Option<Pick> {
        self.decides(budget).then(|| choose(&self.measured(), budget, suns_deg))
    }
}

/// Measures candidates in the order of `scores` with `measure` until what is measured decides the
/// pick for `until` ([`Scores::next_needed`]), or all of them when `until` is `None` (the full
/// measurement). Kept apart from the GPU so that tests can check the rule on any scores.
pub fn measure_in_order<E>(mut scores: Scores, until: Option<Budget>, mut measure: impl FnMut(usize) -> Result<Scored, E>) -> Result<Scores, E> {
    while let Some(n) = scores.next_needed(until) {
        scores.slots[n] = Some(measure(n)?);
    }
    Ok(scores)
}

/// Every candidate's worst error over the sky's conditions, measured on `ev`, cheapest first
/// (the full measurement); progress and cancellation through `job`.
pub fn score(sky: &Sky, ev: &Evaluator<'_>, job: &Job) -> anyhow::Result<Vec<Scored>> {
    Ok(score_from(sky, ev, job, None, None)?.measured())
}

/// The candidates measured on `ev` besides those `known`, until they decide the pick for `until`
/// (all of them for `None`). References are read or computed only when a candidate is left to
/// measure.
fn score_from(sky: &Sky, ev: &Evaluator<'_>, job: &Job, known: Option<Scores>, until: Option<Budget>) -> anyhow::Result<Scores> {
    let candidates = candidates();
    anyhow::ensure!(!candidates.is_empty(), "no candidate model has a cost in the committed benchmark (docs/models.csv)");
    let done = known.unwrap_or_else(|| Scores::empty(candidates.iter().map(Candidate::quick).collect()));
    if done.next_needed(until).is_none() {
        return Ok(done);
    }
    let suns = sky_suns(sky);
    let atmospheres = sky_atmospheres(sky);
    let dirs: Vec<DomeDir> = dome::dome_directions(dome::BENCH_DOME.0, dome::BENCH_DOME.1);
    // Read once: the committed dataset is parsed, a cached one read from disk.
    let ground = sky.model.ground();
    let known_refs: Vec<_> = atmospheres.iter().map(|a| known_reference(a, &suns, ground)).collect();
    let to_compute = known_refs.iter().filter(|k| k.is_none()).count();
    let reference_share = if to_compute == 0 { 0.0 } else { REFERENCE_SHARE };
    let share_each = reference_share / to_compute.max(1) as f64;
    let mut computed = 0;
    let mut references: Vec<Vec<Vec<Rgb>>> = Vec::new();
    for (w, (a, k)) in atmospheres.iter().zip(known_refs).enumerate() {
        let reference = match k {
            Some(r) => r?,
            None => {
                job.set_stage(format!("computing the reference for weather step {} of {}", w + 1, atmospheres.len()));
                computed += 1;
                compute_reference(a, &suns, ground, job.phase(share_each * (computed - 1) as f64, share_each))?
            }
        };
        references.push(reference);
    }
    let measuring = job.phase(reference_share, 1.0 - reference_share);
    let scores = measure_in_order(done, until, |n| -> anyhow::Result<Scored> {
        let Candidate { point, cost_ms, .. } = &candidates[n];
        job.check()?;
        job.set_stage(format!("measuring {}", point.id));
        measuring.report(n, candidates.len());
        let mut worst = 0.0f64;
        let mut turbidity = 0.0;
        for (w, (atm, refs)) in atmospheres.iter().zip(&references).enumerate() {
            let targets: Vec<FitTarget<'_>> = suns.iter().zip(refs).map(|(s, r)| FitTarget { sun_elev_deg: *s, dirs: &dirs, radiance: r }).collect();
            // Analytic models render in the sky's units: fit the turbidity only (scale 1).
            let units = sky.model.settings.analytic.units;
            let prepared = match point.method {
                Method::Preetham | Method::Hosek => {
                    let t = ev.fit_turbidity_unscaled(&point.method, units, &targets)?;
                    if w == 0 {
                        turbidity = t;
                    }
                    Prepared::Analytic(point.method, model_points::Fit { turbidity: t, scale: 1.0, units })
                }
                m => ev.prepare(&m, atm, &targets)?,
            };
            for (s, r) in suns.iter().zip(refs) {
                let model = ev.radiance(&prepared, atm, *s, &dome::cases_from(ground, *s, &dirs))?;
                worst = worst.max(dome::dome_error(&dirs, r, &model).de_mean);
            }
        }
        log::debug!("auto model: {} reads dE2000 {worst:.3} (worst over {} sun(s) and {} weather step(s))", point.id, suns.len(), atmospheres.len());
        Ok(Scored { id: point.id.clone(), method: point.method, turbidity, de2000: worst, cost_ms: *cost_ms, quick: candidates[n].quick() })
    })?;
    measuring.report(1, 1);
    Ok(scores)
}

/// The cheapest of `scored` (cheapest first) within `budget`, and the next one quick to measure;
/// the most accurate when none is within.
pub fn choose(scored: &[Scored], budget: Budget, suns_deg: Vec<f64>) -> Pick {
    let mut within = scored.iter().filter(|s| s.de2000 <= budget.de2000);
    let (chosen, runner_up, within_budget) = match within.next() {
        Some(first) => (first.clone(), within.find(|s| s.quick).cloned(), true),
        None => {
            let best = scored.iter().min_by(|a, b| a.de2000.total_cmp(&b.de2000).then(a.cost_ms.total_cmp(&b.cost_ms)));
            (best.cloned().unwrap_or_else(|| scored[0].clone()), None, false)
        }
    };
    Pick { chosen, runner_up, within_budget, budget, suns_deg }
}

/// Scores already measured in this process, by everything they depend on.
static SCORES: Mutex<Vec<(u64, Scores)>> = Mutex::new(Vec::new());

/// The key of `sky`'s scores: everything they depend on (its atmospheres, sun range, camera,
/// ground and analytic units, the committed benchmark), not its budget or anything else in the
/// file.
pub fn scores_key(sky: &Sky) -> u64 {
    hash_of(&(
        sky_atmospheres(sky),
        sky_suns(sky),
        hash_of(&model_points::COMMITTED_CSV),
        dome::ReferenceDome::header(dome::committed_settings(), dome::BENCH_DOME),
        sky.model.ground(),
        sky.model.settings.analytic.units,
    ))
}

/// Where the scores of `key` are cached.
fn scores_file(key: u64) -> Option<PathBuf> {
    cache_dir().map(|d| d.join(format!("auto-{key:016x}.csv")))
}

/// What this process or the disk cache holds of `sky`'s scores (no measuring); nothing measured
/// when neither holds any.
fn known_scores(sky: &Sky) -> Scores {
    let key = scores_key(sky);
    if let Some((_, s)) = SCORES.lock().unwrap_or_else(|p| p.into_inner()).iter().find(|(k, _)| *k == key) {
        return s.clone();
    }
    let candidates = candidates();
    let mut scores = Scores::empty(candidates.iter().map(Candidate::quick).collect());
    let text = scores_file(key).and_then(|f| std::fs::read_to_string(f).ok()).unwrap_or_default();
    for line in text.lines() {
        // id, turbidity, dE2000, cost; a line of another form or candidate is left out.
        let f: Vec<&str> = line.split(',').collect();
        let Some(n) = candidates.iter().position(|c| Some(&c.point.id.as_str()) == f.first()) else { continue };
        let c = &candidates[n];
        let number = |k: usize| f.get(k).and_then(|v| v.parse::<f64>().ok());
        if let (4, Some(turbidity), Some(de2000), Some(cost_ms)) = (f.len(), number(1), number(2), number(3)) {
            scores.slots[n] = Some(Scored { id: c.point.id.clone(), method: c.point.method, turbidity, de2000, cost_ms, quick: c.quick() });
        }
    }
    if scores.slots.iter().any(Option::is_some) {
        remember(key, &scores);
    }
    scores
}

/// Keeps `scores` for `key` in this process, replacing what was kept.
fn remember(key: u64, scores: &Scores) {
    let mut kept = SCORES.lock().unwrap_or_else(|p| p.into_inner());
    kept.retain(|(k, _)| *k != key);
    kept.push((key, scores.clone()));
}

/// `sky`'s scores, enough to decide its pick for `budget` (every candidate for `None`): from this
/// process's cache or the disk cache, the rest measured on `ctx` and cached (seconds to minutes
/// for a new atmosphere; progress and cancellation through `job`).
pub fn score_cached(sky: &Sky, budget: Option<Budget>, ctx: &crate::render::GpuContext, job: &Job) -> anyhow::Result<Scores> {
    let known = known_scores(sky);
    if known.next_needed(budget).is_none() {
        job.set_fraction(1.0);
        return Ok(known);
    }
    let key = scores_key(sky);
    let s = score_from(sky, &Evaluator::new(ctx)?, job, Some(known), budget)?;
    if let Some(f) = scores_file(key) {
        let text: String = s.measured().iter().map(|x| format!("{},{},{},{}\n", x.id, x.turbidity, x.de2000, x.cost_ms)).collect();
        if let Some(dir) = f.parent() {
            let _ = std::fs::create_dir_all(dir);
        }
        if let Err(e) = crate::support::safe_write::write_atomic(&f, text.as_bytes()) {
            log::warn!("auto model: cannot cache the scores: {e}");
        }
    }
    remember(key, &s);
    Ok(s)
}

/// The pick for `sky` if it is known without measuring (cached in this process or on disk).
pub fn known_pick(sky: &Sky, budget: Budget) -> Option<Pick> {
    known_scores(sky).pick(budget, sky_suns(sky))
}

/// The pick for `sky` within `budget` (scores cached per atmospheres and sun range; only as many
/// candidates measured as decide it).
pub fn pick_cached(sky: &Sky, budget: Budget, ctx: &crate::render::GpuContext, job: &Job) -> anyhow::Result<Pick> {
    let scores = score_cached(sky, Some(budget), ctx, job)?;
    Ok(choose(&scores.measured(), budget, sky_suns(sky)))
}

/// The pick for `sky` within `budget` measured on `ev`, as [`pick_cached`] measures it but with
/// no cache: only the candidates that decide it.
pub fn pick(sky: &Sky, budget: Budget, ev: &Evaluator<'_>, job: &Job) -> anyhow::Result<(Pick, Scores)> {
    let scores = score_from(sky, ev, job, None, Some(budget))?;
    Ok((choose(&scores.measured(), budget, sky_suns(sky)), scores))
}

/// Resolves `kind = "auto"`: replaces the sky's model with the pick. Returns the pick, or `None`
/// for skies that name their model.
pub fn resolve(sky: &mut Sky, ctx: &crate::render::GpuContext, job: &Job) -> anyhow::Result<Option<Pick>> {
    let Some(budget) = sky.auto_model else { return Ok(None) };
    let p = pick_cached(sky, budget, ctx, job)?;
    sky.model = p.model(&sky.model);
    Ok(Some(p))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scored(n: usize, de2000: f64, quick: bool) -> Scored {
        Scored { id: format!("c{n}"), method: Method::Cells(n), turbidity: 0.0, de2000, cost_ms: n as f64, quick }
    }

    fn measure_from(all: &[Scored], known: Scores, budget: Budget) -> (Scores, Vec<usize>) {
        let mut asked = Vec::new();
        let scores = measure_in_order(known, Some(budget), |n| {
            asked.push(n);
            Ok::<_, ()>(all[n].clone())
        })
        .expect("measured");
        (scores, asked)
    }

    /// On every list of errors (random, with ties at the budget and candidates slow to measure),
    /// what the rule measures picks what every candidate picks, and it measures nothing past the
    /// pick but the quick candidates up to the runner-up.
    #[test]
    fn what_the_rule_measures_picks_what_every_candidate_picks() {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let mut stopped_early = 0;
        for _ in 0..2000 {
            let len = 1 + (next() % 12) as usize;
            let all: Vec<Scored> = (0..len).map(|n| scored(n, [0.5, 1.0, 2.0, 3.0, 8.0][(next() % 5) as usize], next() % 4 != 0)).collect();
            let empty = Scores::empty(all.iter().map(|s| s.quick).collect());
            for de2000 in [0.4, 1.0, 2.0, 5.0] {
                let budget = Budget { de2000 };
                let (scores, asked) = measure_from(&all, empty.clone(), budget);
                let full = choose(&all, budget, Vec::new());
                assert_eq!(scores.pick(budget, Vec::new()), Some(full.clone()), "{all:?} at {de2000}");
                let chosen = all.iter().position(|s| s.de2000 <= de2000);
                let expected: Vec<usize> = match chosen {
                    None => (0..len).collect(),
                    Some(c) => {
                        let runner = (c + 1..len).find(|&n| all[n].quick && all[n].de2000 <= de2000).unwrap_or(len);
                        (0..=c).chain((c + 1..runner.min(len - 1) + 1).filter(|&n| all[n].quick)).collect()
                    }
                };
                assert_eq!(asked, expected, "{all:?} at {de2000}");
                stopped_early += usize::from(asked.len() < len);
                // Resumed from part of what it measured, it measures the rest and ends the same.
                let mut part = empty.clone();
                for &n in &asked[..asked.len() / 2] {
                    part.slots[n] = Some(all[n].clone());
                }
                assert_eq!(measure_from(&all, part, budget).0, scores);
            }
        }
        assert!(stopped_early > 1000, "the rule stopped early {stopped_early} times");
    }

    /// What decides a loose budget may not decide a tighter one: it says so rather than pick, and
    /// measuring on from it gives the tighter budget's pick.
    #[test]
    fn an_undecided_measurement_gives_no_pick() {
        let all = vec![scored(0, 3.0, true), scored(1, 1.5, true), scored(2, 1.8, false), scored(3, 1.9, true), scored(4, 0.5, true)];
        let (loose, asked) = measure_from(&all, Scores::empty(all.iter().map(|s| s.quick).collect()), Budget { de2000: 2.0 });
        assert_eq!(asked, [0, 1, 3], "c2 is slow to measure and past the pick");
        assert_eq!(loose.pick(Budget { de2000: 2.0 }, Vec::new()).and_then(|p| p.runner_up).map(|r| r.id), Some("c3".to_string()));
        assert!(loose.pick(Budget { de2000: 1.0 }, Vec::new()).is_none(), "only c4 meets 1.0, and it is not measured");
        let (tight, asked) = measure_from(&all, loose, Budget { de2000: 1.0 });
        assert_eq!(asked, [2, 4]);
        assert_eq!(tight.pick(Budget { de2000: 1.0 }, Vec::new()).map(|p| p.chosen.id), Some("c4".to_string()));
    }
}
