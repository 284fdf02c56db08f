//! `kind = "auto"` in `[sky_model]`: the cheapest model and setting whose error against the
//! reference, over the sky's own range of sun elevations and weathers, stays within the budget.
//!
//! - Candidates: the benchmark's points a sky file can select ([`model_points::Point::auto`]),
//!   ranked by the frame cost of the committed benchmark (docs/models.csv, embedded), ties by id:
//!   the same inputs give the same pick on any machine.
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
}

/// What `auto` picked.
#[derive(Debug, Clone, PartialEq)]
pub struct Pick {
    /// The cheapest candidate within the budget (or the most accurate when none is).
    pub chosen: Scored,
    /// The next cheapest candidate within the budget.
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
        match c.method {
            Method::Single(s) => SkyModel { kind: SkyModelKind::Single, single: s, ..*base },
            Method::Lut(s) => SkyModel { kind: SkyModelKind::Lut, lut: s, ..*base },
            Method::Precomputed(s) => SkyModel { kind: SkyModelKind::Precomputed, precomputed: s, ..*base },
            Method::Cells(i) => SkyModel { kind: SkyModelKind::Cells, cell_iterations: i as u32, ..*base },
            Method::Preetham => SkyModel { kind: SkyModelKind::Preetham, turbidity: c.turbidity as f32, turbidity_from_atmosphere: false, ..*base },
            Method::Hosek => SkyModel { kind: SkyModelKind::Hosek, turbidity: c.turbidity as f32, turbidity_from_atmosphere: false, ..*base },
            _ => *base,
        }
    }
}

/// The candidates with their committed costs, cheapest first: by frame cost, then by one-off cost
/// (building tables: `precomputed` points cost the same per frame whatever their size), then by id.
pub fn candidates() -> Vec<(model_points::Point, f64)> {
    let costs: HashMap<String, (f64, f64)> =
        model_points::rows_from_csv(model_points::COMMITTED_CSV).unwrap_or_default().into_iter().map(|r| (r.id.clone(), (r.frame_ms(), r.build_ms))).collect();
    let mut out: Vec<(model_points::Point, (f64, f64))> = model_points::points().into_iter().filter(|p| p.auto).filter_map(|p| costs.get(&p.id).copied().map(|c| (p, c))).collect();
    out.sort_by(|a, b| a.1 .0.total_cmp(&b.1 .0).then_with(|| a.1 .1.total_cmp(&b.1 .1)).then_with(|| a.0.id.cmp(&b.0.id)));
    out.into_iter().map(|(p, (frame_ms, _))| (p, frame_ms)).collect()
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

/// Every candidate's worst error over the sky's conditions, measured on `ev`, cheapest first;
/// progress and cancellation through `job`.
pub fn score(sky: &Sky, ev: &Evaluator<'_>, job: &Job) -> anyhow::Result<Vec<Scored>> {
    let suns = sky_suns(sky);
    let atmospheres = sky_atmospheres(sky);
    let dirs: Vec<DomeDir> = dome::dome_directions(dome::BENCH_DOME.0, dome::BENCH_DOME.1);
    // Read once: the committed dataset is parsed, a cached one read from disk.
    let ground = sky.model.ground();
    let known: Vec<_> = atmospheres.iter().map(|a| known_reference(a, &suns, ground)).collect();
    let to_compute = known.iter().filter(|k| k.is_none()).count();
    let reference_share = if to_compute == 0 { 0.0 } else { REFERENCE_SHARE };
    let share_each = reference_share / to_compute.max(1) as f64;
    let mut computed = 0;
    let mut references: Vec<Vec<Vec<Rgb>>> = Vec::new();
    for (w, (a, k)) in atmospheres.iter().zip(known).enumerate() {
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
    let candidates = candidates();
    let measuring = job.phase(reference_share, 1.0 - reference_share);
    let mut scored = Vec::new();
    for (n, (point, cost_ms)) in candidates.iter().enumerate() {
        job.check()?;
        job.set_stage(format!("measuring {}", point.id));
        measuring.report(n, candidates.len());
        let mut worst = 0.0f64;
        let mut turbidity = 0.0;
        for (w, (atm, refs)) in atmospheres.iter().zip(&references).enumerate() {
            let targets: Vec<FitTarget<'_>> = suns.iter().zip(refs).map(|(s, r)| FitTarget { sun_elev_deg: *s, dirs: &dirs, radiance: r }).collect();
            // Analytic models render in the sky's units: fit the turbidity only (scale 1).
            let units = sky.model.analytic_units;
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
        scored.push(Scored { id: point.id.clone(), method: point.method, turbidity, de2000: worst, cost_ms: *cost_ms });
    }
    measuring.report(1, 1);
    anyhow::ensure!(!scored.is_empty(), "no candidate model has a cost in the committed benchmark (docs/models.csv)");
    Ok(scored)
}

/// The cheapest of `scored` (cheapest first) within `budget`, and the next one; the most accurate
/// when none is within.
pub fn choose(scored: &[Scored], budget: Budget, suns_deg: Vec<f64>) -> Pick {
    let mut within = scored.iter().filter(|s| s.de2000 <= budget.de2000);
    let (chosen, runner_up, within_budget) = match within.next() {
        Some(first) => (first.clone(), within.next().cloned(), true),
        None => {
            let best = scored.iter().min_by(|a, b| a.de2000.total_cmp(&b.de2000).then(a.cost_ms.total_cmp(&b.cost_ms)));
            (best.cloned().unwrap_or_else(|| scored[0].clone()), None, false)
        }
    };
    Pick { chosen, runner_up, within_budget, budget, suns_deg }
}

/// Scores already measured in this process, by everything they depend on.
static SCORES: Mutex<Vec<(u64, Vec<Scored>)>> = Mutex::new(Vec::new());

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
        sky.model.analytic_units,
    ))
}

/// Where the scores of `key` are cached.
fn scores_file(key: u64) -> Option<PathBuf> {
    cache_dir().map(|d| d.join(format!("auto-{key:016x}.csv")))
}

/// `sky`'s scores if this process or the disk cache already holds them (no measuring).
fn known_scores(sky: &Sky) -> Option<Vec<Scored>> {
    let key = scores_key(sky);
    if let Some((_, s)) = SCORES.lock().unwrap_or_else(|p| p.into_inner()).iter().find(|(k, _)| *k == key) {
        return Some(s.clone());
    }
    let file = scores_file(key)?;
    let points = model_points::points();
    let from_disk: Option<Vec<Scored>> = std::fs::read_to_string(&file).ok().and_then(|text| {
        text.lines()
            .map(|line| {
                let f: Vec<&str> = line.split(',').collect();
                let id = *f.first()?;
                let point = points.iter().find(|p| p.id == id)?;
                Some(Scored { id: point.id.clone(), method: point.method, turbidity: f.get(1)?.parse().ok()?, de2000: f.get(2)?.parse().ok()?, cost_ms: f.get(3)?.parse().ok()? })
            })
            .collect()
    });
    let scored = from_disk.filter(|s| !s.is_empty())?;
    SCORES.lock().unwrap_or_else(|p| p.into_inner()).push((key, scored.clone()));
    Some(scored)
}

/// Every candidate's score for `sky`: from this process's cache, the disk cache, or measured on
/// `ctx` (seconds to minutes for a new atmosphere; progress and cancellation through `job`).
pub fn score_cached(sky: &Sky, ctx: &crate::render::GpuContext, job: &Job) -> anyhow::Result<Vec<Scored>> {
    if let Some(s) = known_scores(sky) {
        job.set_fraction(1.0);
        return Ok(s);
    }
    let key = scores_key(sky);
    let s = score(sky, &Evaluator::new(ctx)?, job)?;
    if let Some(f) = scores_file(key) {
        let text: String = s.iter().map(|x| format!("{},{},{},{}\n", x.id, x.turbidity, x.de2000, x.cost_ms)).collect();
        if let Some(dir) = f.parent() {
            let _ = std::fs::create_dir_all(dir);
        }
        if let Err(e) = crate::support::safe_write::write_atomic(&f, text.as_bytes()) {
            log::warn!("auto model: cannot cache the scores: {e}");
        }
    }
    SCORES.lock().unwrap_or_else(|p| p.into_inner()).push((key, s.clone()));
    Ok(s)
}

/// The pick for `sky` if it is known without measuring (cached in this process or on disk).
pub fn known_pick(sky: &Sky, budget: Budget) -> Option<Pick> {
    known_scores(sky).map(|s| choose(&s, budget, sky_suns(sky)))
}

/// The pick for `sky` within `budget` (scores cached per atmospheres and sun range).
pub fn pick_cached(sky: &Sky, budget: Budget, ctx: &crate::render::GpuContext, job: &Job) -> anyhow::Result<Pick> {
    Ok(choose(&score_cached(sky, ctx, job)?, budget, sky_suns(sky)))
}

/// Resolves `kind = "auto"`: replaces the sky's model with the pick. Returns the pick, or `None`
/// for skies that name their model.
pub fn resolve(sky: &mut Sky, ctx: &crate::render::GpuContext, job: &Job) -> anyhow::Result<Option<Pick>> {
    let Some(budget) = sky.auto_model else { return Ok(None) };
    let p = pick_cached(sky, budget, ctx, job)?;
    sky.model = p.model(&sky.model);
    Ok(Some(p))
}
