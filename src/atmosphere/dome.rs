//! The dome the sky models are measured on (`skytune bench models`, `model = "auto"`, the
//! stability sweep): view directions with solid-angle weights, the sun elevations and atmospheres
//! of the benchmark, the fixed-exposure display transform, the error figures (relative RMSE,
//! PSNR, CIE dE2000) and the reference's radiance over that dome, cached on disk because it takes
//! minutes. No GPU types.
//!
//! Radiance is in sr^-1 per unit of solar irradiance, as everywhere in [`crate::atmosphere`].

use std::f64::consts::PI;
use std::path::Path;

use deltae::{DEMethod, DeltaE, LabValue, XyzValue};

use super::reference::{Case, Reference, ReferenceSettings};
use super::{Atmosphere, Rgb};
use crate::support::progress::Cancelled;
use crate::support::shard::Shard;

/// One view direction of the dome and the solid angle it stands for.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DomeDir {
    /// Elevation above the horizon, degrees.
    pub elev_deg: f64,
    /// Azimuth relative to the sun's, degrees (0..180: the sky is symmetric about the sun's
    /// vertical plane, so each direction also stands for its mirror image).
    pub rel_az_deg: f64,
    /// Solid angle this direction stands for, sr (the weights of a dome sum to 2 pi).
    pub weight_sr: f64,
}

/// Directions over the upper hemisphere: `bands` bands of equal solid angle (sin(elevation)
/// uniform, band centres) times `azimuths` azimuths over half a turn.
pub fn dome_directions(bands: usize, azimuths: usize) -> Vec<DomeDir> {
    let weight_sr = 2.0 * PI / (bands * azimuths) as f64;
    (0..bands)
        .flat_map(|i| {
            let elev_deg = (((i as f64 + 0.5) / bands as f64).asin()).to_degrees();
            (0..azimuths).map(move |j| DomeDir { elev_deg, rel_az_deg: (j as f64 + 0.5) * 180.0 / azimuths as f64, weight_sr })
        })
        .collect()
}

/// The benchmark's dome: 8 equal-area bands x 12 azimuths (96 directions).
pub const BENCH_DOME: (usize, usize) = (8, 12);

/// Sun elevations of the full benchmark, degrees: -10 to 90, finer near the horizon.
pub const SUN_ELEVATIONS_DEG: [f64; 18] = [-10.0, -6.0, -4.0, -2.0, -1.0, 0.0, 1.0, 2.0, 3.0, 5.0, 8.0, 12.0, 20.0, 30.0, 45.0, 60.0, 75.0, 90.0];

/// Sun elevations of the quick benchmark (a subset of [`SUN_ELEVATIONS_DEG`]).
pub const QUICK_SUN_ELEVATIONS_DEG: [f64; 5] = [-4.0, 0.0, 2.0, 12.0, 45.0];

/// Camera altitude of the benchmark, km (the sky file's default).
pub const CAMERA_KM: f64 = 0.0;

/// Ground albedo of the benchmark (the sky file's default).
pub const ALBEDO: f64 = 0.3;

/// The benchmark's atmospheres: the default and two aerosol loads.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Haze {
    /// Hillaire 2020's Earth ([`Atmosphere::default`]).
    Default,
    /// Four times the default's aerosols (Mie scattering and extinction).
    Hazy,
    /// A quarter of the default's aerosols.
    Clean,
}

impl Haze {
    /// Every atmosphere of the full benchmark.
    pub const ALL: [Haze; 3] = [Haze::Default, Haze::Hazy, Haze::Clean];

    /// Name in tables and files.
    pub fn name(self) -> &'static str {
        match self {
            Haze::Default => "default",
            Haze::Hazy => "hazy",
            Haze::Clean => "clean",
        }
    }

    /// The atmosphere.
    pub fn atmosphere(self) -> Atmosphere {
        let aerosols = |k: f64| {
            let a = Atmosphere::default();
            Atmosphere { mie_scattering_per_km: a.mie_scattering_per_km.map(|b| b * k), mie_extinction_per_km: a.mie_extinction_per_km.map(|b| b * k), ..a }
        };
        match self {
            Haze::Default => Atmosphere::default(),
            Haze::Hazy => aerosols(4.0),
            Haze::Clean => aerosols(0.25),
        }
    }

    /// The benchmark atmosphere equal to `atm`, if any.
    pub fn of(atm: &Atmosphere) -> Option<Haze> {
        Haze::ALL.into_iter().find(|h| h.atmosphere() == *atm)
    }

    /// From its name.
    pub fn from_name(name: &str) -> Option<Haze> {
        Haze::ALL.into_iter().find(|h| h.name() == name)
    }
}

/// Where a dome is seen from: the camera's altitude and the ground's albedo.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ground {
    /// Camera altitude, km.
    pub camera_km: f64,
    /// Ground albedo, 0..1.
    pub albedo: f64,
}

impl Ground {
    /// The benchmark's: on the ground ([`CAMERA_KM`]), albedo [`ALBEDO`].
    pub const BENCH: Ground = Ground { camera_km: CAMERA_KM, albedo: ALBEDO };
}

/// The radiance cases of one sun elevation over `dirs`, seen from the benchmark's ground.
pub fn cases(sun_elev_deg: f64, dirs: &[DomeDir]) -> Vec<Case> {
    cases_from(Ground::BENCH, sun_elev_deg, dirs)
}

/// The radiance cases of one sun elevation over `dirs`, seen from `ground`.
pub fn cases_from(ground: Ground, sun_elev_deg: f64, dirs: &[DomeDir]) -> Vec<Case> {
    dirs.iter()
        .map(|d| Case { camera_km: ground.camera_km, albedo: ground.albedo, sun_elev_deg, view_elev_deg: d.elev_deg, rel_azimuth_deg: d.rel_az_deg, distance_km: None })
        .collect()
}

/// Fixed exposure of the error figures, stops: the sky file's default `exposure_ev`.
pub const EXPOSURE_EV: f64 = 5.0;

/// Linear display value of a radiance at the fixed exposure: 1 - exp(-L 2^EV) per channel (a
/// tone curve with an exact inverse, so baked bitmaps can be turned back into radiance).
pub fn display(l: Rgb) -> Rgb {
    let k = EXPOSURE_EV.exp2();
    l.map(|c| 1.0 - (-(c.max(0.0)) * k).exp())
}

/// Inverse of [`display`] (display values of 1 and above map to a large finite radiance).
pub fn radiance_from_display(d: Rgb) -> Rgb {
    let k = EXPOSURE_EV.exp2();
    d.map(|c| -(1.0 - c.clamp(0.0, 1.0 - 1e-6)).ln() / k)
}

/// sRGB encoding of a linear value in 0..1.
pub fn srgb_encode(x: f64) -> f64 {
    let x = x.clamp(0.0, 1.0);
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// sRGB decoding to a linear value in 0..1.
pub fn srgb_decode(x: f64) -> f64 {
    let x = x.clamp(0.0, 1.0);
    if x <= 0.040_45 {
        x / 12.92
    } else {
        ((x + 0.055) / 1.055).powf(2.4)
    }
}

/// CIE L*a*b* (D50, as `deltae` defines it) of a linear Rec. 709 display colour, through the
/// Bradford-adapted sRGB to XYZ(D50) matrix.
fn lab(linear: Rgb) -> LabValue {
    let [r, g, b] = linear.map(|c| c.clamp(0.0, 1.0));
    let xyz = XyzValue {
        x: (0.436_074_7 * r + 0.385_064_9 * g + 0.143_080_4 * b) as f32,
        y: (0.222_504_5 * r + 0.716_878_6 * g + 0.060_616_9 * b) as f32,
        z: (0.013_932_2 * r + 0.097_104_5 * g + 0.714_173_3 * b) as f32,
    };
    LabValue::from(xyz)
}

/// CIE dE2000 between two linear display colours.
pub fn de2000(a: Rgb, b: Rgb) -> f64 {
    *DeltaE::new(lab(a), lab(b), DEMethod::DE2000).value() as f64
}

/// How far a model is from the reference over one dome.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct DomeError {
    /// Relative RMSE of radiance per channel, solid-angle weighted: sqrt(sum w (m - r)^2 / sum w r^2).
    pub rel_rmse: Rgb,
    /// PSNR of the sRGB-encoded display image (peak 1), dB; 99 for identical images.
    pub psnr_db: f64,
    /// Mean CIE dE2000 of the display colours, solid-angle weighted.
    pub de_mean: f64,
    /// 95th percentile of dE2000 (by solid angle).
    pub de_p95: f64,
}

impl DomeError {
    /// The mean of the three channels' relative RMSE.
    pub fn rel_rmse_mean(&self) -> f64 {
        self.rel_rmse.iter().sum::<f64>() / 3.0
    }
}

/// Errors of `model` against `reference` over `dirs` (same order).
pub fn dome_error(dirs: &[DomeDir], reference: &[Rgb], model: &[Rgb]) -> DomeError {
    let mut num = [0.0; 3];
    let mut den = [0.0; 3];
    let (mut sq, mut w_sum) = (0.0, 0.0);
    let mut des = Vec::with_capacity(dirs.len());
    for ((d, r), m) in dirs.iter().zip(reference).zip(model) {
        for c in 0..3 {
            num[c] += d.weight_sr * (m[c] - r[c]).powi(2);
            den[c] += d.weight_sr * r[c] * r[c];
        }
        let (dr, dm) = (display(*r), display(sanitize(*m)));
        for c in 0..3 {
            sq += d.weight_sr * (srgb_encode(dm[c]) - srgb_encode(dr[c])).powi(2) / 3.0;
        }
        w_sum += d.weight_sr;
        des.push((de2000(dr, dm), d.weight_sr));
    }
    let rel_rmse = std::array::from_fn(|c| {
        if den[c] > 0.0 {
            (num[c] / den[c]).sqrt()
        } else if num[c] > 0.0 {
            f64::INFINITY
        } else {
            0.0
        }
    });
    let mse = sq / w_sum.max(f64::MIN_POSITIVE);
    let psnr_db = if mse > 1e-10 { (-10.0 * mse.log10()).min(99.0) } else { 99.0 };
    let de_mean = des.iter().map(|(e, w)| e * w).sum::<f64>() / w_sum.max(f64::MIN_POSITIVE);
    des.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut acc = 0.0;
    let mut de_p95 = des.last().map_or(0.0, |d| d.0);
    for (e, w) in &des {
        acc += w;
        if acc >= 0.95 * w_sum {
            de_p95 = *e;
            break;
        }
    }
    DomeError { rel_rmse, psnr_db, de_mean, de_p95 }
}

/// NaN and negative radiance count as black for the display figures (the stability sweep counts them).
fn sanitize(l: Rgb) -> Rgb {
    l.map(|c| {
        if c.is_finite() {
            c.max(0.0)
        } else if c == f64::INFINITY {
            1e30
        } else {
            0.0
        }
    })
}

/// The reference's radiance over a dome for a set of atmospheres and sun elevations.
#[derive(Debug, Clone, PartialEq)]
pub struct ReferenceDome {
    /// The reference's settings (paths, target standard error, seed).
    pub settings: ReferenceSettings,
    /// Dome layout (bands, azimuths) of [`dome_directions`].
    pub dome: (usize, usize),
    /// One entry per (atmosphere, sun elevation): radiance and its standard error per direction.
    pub suns: Vec<ReferenceSun>,
}

/// The reference's dome for one atmosphere and sun elevation.
#[derive(Debug, Clone, PartialEq)]
pub struct ReferenceSun {
    /// The atmosphere.
    pub haze: Haze,
    /// Sun elevation, degrees.
    pub sun_elev_deg: f64,
    /// Radiance per direction (all orders), sr^-1 per unit of solar irradiance.
    pub radiance: Vec<Rgb>,
    /// Monte Carlo standard error per direction.
    pub std_err: Vec<Rgb>,
}

/// The sun's regimes, where models fail differently.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Regime {
    /// Sun above 10 degrees.
    Day,
    /// Sun above 0 and up to 10 degrees.
    LowSun,
    /// Sun at 0 degrees and below: the planet's shadow in the sky.
    Twilight,
}

impl Regime {
    /// Every regime, sun highest first.
    pub const ALL: [Regime; 3] = [Regime::Day, Regime::LowSun, Regime::Twilight];

    /// The regime of a sun elevation.
    pub fn of(sun_elev_deg: f64) -> Self {
        if sun_elev_deg > 10.0 {
            Regime::Day
        } else if sun_elev_deg > 0.0 {
            Regime::LowSun
        } else {
            Regime::Twilight
        }
    }

    /// Name in tables and charts.
    pub fn name(self) -> &'static str {
        match self {
            Regime::Day => "day (sun above 10 deg)",
            Regime::LowSun => "low sun (0 to 10 deg)",
            Regime::Twilight => "twilight (sun 0 deg and below)",
        }
    }
}

impl ReferenceSun {
    /// The reference's own noise as a relative RMSE over the dome (solid-angle weighted, every
    /// channel): how far its radiance may be from the truth, one standard error. A model's
    /// relative RMSE against it is within about this of its RMSE against the truth.
    pub fn relative_noise(&self, dirs: &[DomeDir]) -> f64 {
        let (mut num, mut den) = (0.0, 0.0);
        for ((d, l), e) in dirs.iter().zip(&self.radiance).zip(&self.std_err) {
            for c in 0..3 {
                num += d.weight_sr * e[c] * e[c];
                den += d.weight_sr * l[c] * l[c];
            }
        }
        (num / den.max(1e-300)).sqrt()
    }
}

/// Why a cached reference dome could not be used.
#[derive(Debug, thiserror::Error)]
pub enum ReferenceDomeError {
    /// Reading or writing failed.
    #[error("{file}: {source}")]
    Io {
        /// The file.
        file: String,
        /// Why.
        source: std::io::Error,
    },
    /// The file is not what [`ReferenceDome::save`] writes, or was written for other settings.
    #[error("{file}:{line}: {message}")]
    Format {
        /// The file.
        file: String,
        /// 1-based line.
        line: usize,
        /// What is wrong.
        message: String,
    },
}

/// One dome of [`compute_domes`]: (atmosphere index, sun elevation in degrees, radiance and
/// standard error per direction).
pub type DomeEstimate = (usize, f64, Vec<Rgb>, Vec<Rgb>);

/// The reference's radiance and standard error over a dome for every (atmosphere, sun) pair, on
/// every core: (atmosphere index, sun elevation, radiance, standard error) in the order of the
/// pairs. Jobs are handed out one direction at a time: low suns cost ten times more than high ones.
/// `progress` hears (done, total) after each direction; an `Err` from it stops every worker at its
/// next direction and is returned (nothing partial is).
pub fn compute_domes(
    atmospheres: &[Atmosphere],
    suns_deg: &[f64],
    dome: (usize, usize),
    settings: ReferenceSettings,
    progress: &(dyn Fn(usize, usize) -> Result<(), Cancelled> + Sync),
) -> Result<Vec<DomeEstimate>, Cancelled> {
    compute_domes_from(Ground::BENCH, atmospheres, suns_deg, dome, settings, progress)
}

/// [`compute_domes`] seen from `ground`.
pub fn compute_domes_from(
    ground: Ground,
    atmospheres: &[Atmosphere],
    suns_deg: &[f64],
    dome: (usize, usize),
    settings: ReferenceSettings,
    progress: &(dyn Fn(usize, usize) -> Result<(), Cancelled> + Sync),
) -> Result<Vec<DomeEstimate>, Cancelled> {
    let dirs = dome_directions(dome.0, dome.1);
    let jobs = dome_jobs(ground, atmospheres.len(), suns_deg, &dirs);
    let results = estimate_jobs(atmospheres, &jobs, settings, progress)?;
    Ok(jobs
        .chunks(dirs.len().max(1))
        .zip(results.chunks(dirs.len().max(1)))
        .map(|(chunk, estimates)| (chunk[0].0, chunk[0].1, estimates.iter().map(|e| e.all).collect(), estimates.iter().map(|e| e.std_err).collect()))
        .collect())
}

/// Every (atmosphere index, sun elevation, case) of a set of domes, dome after dome.
fn dome_jobs(ground: Ground, atmospheres: usize, suns_deg: &[f64], dirs: &[DomeDir]) -> Vec<(usize, f64, Case)> {
    let mut jobs = Vec::new();
    for k in 0..atmospheres {
        for &s in suns_deg {
            jobs.extend(cases_from(ground, s, dirs).into_iter().map(|c| (k, s, c)));
        }
    }
    jobs
}

/// The reference's estimate of every job, on every core.
fn estimate_jobs(
    atmospheres: &[Atmosphere],
    jobs: &[(usize, f64, Case)],
    settings: ReferenceSettings,
    progress: &(dyn Fn(usize, usize) -> Result<(), Cancelled> + Sync),
) -> Result<Vec<crate::atmosphere::reference::Estimate>, Cancelled> {
    let references: Vec<Reference> = atmospheres.iter().map(|a| Reference::new(*a, settings)).collect();
    let jobs: Vec<(&Reference, Case)> = jobs.iter().map(|(k, _, c)| (&references[*k], *c)).collect();
    crate::atmosphere::reference::estimate_many(&jobs, progress)
}

/// One row of the dataset's CSV.
fn dome_row(haze: Haze, sun_elev_deg: f64, d: &DomeDir, l: Rgb, e: Rgb) -> String {
    format!("{},{},{:.4},{:.4},{:.6e},{:.6e},{:.6e},{:.3e},{:.3e},{:.3e}\n", haze.name(), sun_elev_deg, d.elev_deg, d.rel_az_deg, l[0], l[1], l[2], e[0], e[1], e[2])
}

/// The benchmark's reference dataset as committed (assets/reference_dome.csv, embedded).
pub fn committed_reference() -> Result<ReferenceDome, ReferenceDomeError> {
    ReferenceDome::parse(include_str!("../../assets/reference_dome.csv"), "assets/reference_dome.csv", committed_settings(), BENCH_DOME)
}

/// Most Monte Carlo paths per direction of the committed reference dataset.
pub const COMMITTED_PATHS: u32 = 16384;

/// Relative standard error per channel the committed reference dataset draws paths until.
pub const COMMITTED_TARGET_SE: f64 = 0.01;

/// The reference's settings of the committed dataset: every direction to 1% per channel, or
/// 16,384 paths (twilight, where the goal is 3%: docs/models.md states what was reached).
pub fn committed_settings() -> ReferenceSettings {
    ReferenceSettings { paths: COMMITTED_PATHS, seed: REFERENCE_SEED, target_rel_se: Some(COMMITTED_TARGET_SE), ..Default::default() }
}

/// Seed of the benchmark's reference (fixed: the dataset is reproducible).
pub const REFERENCE_SEED: u64 = 0x5eed;

impl ReferenceDome {
    /// Header line naming everything the values depend on; a cache with another header is stale.
    pub fn header(settings: ReferenceSettings, dome: (usize, usize)) -> String {
        let atmospheres: Vec<String> = Haze::ALL.iter().map(|h| format!("{}={:?}", h.name(), h.atmosphere())).collect();
        format!(
            "skytune reference dome v4 (orders 2 and up: sunlit strata per segment, spectral MIS per path, phase-function directions, tabulated sunlight; paths to a target standard error): dome={}x{} camera_km={CAMERA_KM} albedo={ALBEDO} settings={settings:?} atmospheres=[{}]",
            dome.0,
            dome.1,
            atmospheres.join("; ")
        )
    }

    /// The lines before the rows: the header and the column names.
    fn head(settings: ReferenceSettings, dome: (usize, usize)) -> String {
        format!("# {}\nhaze,sun_elev_deg,view_elev_deg,rel_azimuth_deg,r,g,b,r_err,g_err,b_err\n", Self::header(settings, dome))
    }

    /// The key of a shard's inputs ([`Shard::table_line`]): the header names them all.
    fn shard_inputs(hazes: &[Haze], suns_deg: &[f64], dome: (usize, usize), settings: ReferenceSettings) -> u64 {
        let names: Vec<&str> = hazes.iter().map(|h| h.name()).collect();
        crate::support::shard::inputs_key(&[Self::header(settings, dome).as_bytes(), names.join(",").as_bytes(), format!("{suns_deg:?}").as_bytes()])
    }

    /// Whether `text` is the complete output of [`Self::shard_table`] with these arguments.
    pub fn is_complete_shard(text: &str, hazes: &[Haze], suns_deg: &[f64], dome: (usize, usize), settings: ReferenceSettings, shard: Shard) -> bool {
        let total = hazes.len() * suns_deg.len() * dome.0 * dome.1;
        shard.is_complete(text, total, 1, Self::shard_inputs(hazes, suns_deg, dome, settings))
    }

    /// One shard's rows of what [`Self::compute`] and [`Self::save`] write, as a shard's table
    /// (`skytune merge` combines the shards into the dataset, byte for byte).
    pub fn shard_table(
        hazes: &[Haze],
        suns_deg: &[f64],
        dome: (usize, usize),
        settings: ReferenceSettings,
        shard: Shard,
        progress: &(dyn Fn(usize, usize) -> Result<(), Cancelled> + Sync),
    ) -> Result<String, Cancelled> {
        let atmospheres: Vec<Atmosphere> = hazes.iter().map(|h| h.atmosphere()).collect();
        let dirs = dome_directions(dome.0, dome.1);
        let all = dome_jobs(Ground::BENCH, atmospheres.len(), suns_deg, &dirs);
        let index: Vec<usize> = (0..all.len()).collect();
        let mine = shard.take(&index);
        let jobs: Vec<(usize, f64, Case)> = mine.iter().map(|i| all[*i]).collect();
        let estimates = estimate_jobs(&atmospheres, &jobs, settings, progress)?;
        let mut text = format!("{}\n{}", shard.table_line(all.len(), 1, Self::shard_inputs(hazes, suns_deg, dome, settings)), Self::head(settings, dome));
        for ((i, (k, sun, _)), e) in mine.iter().zip(&jobs).zip(&estimates) {
            text.push_str(&dome_row(hazes[*k], *sun, &dirs[i % dirs.len()], e.all, e.std_err));
        }
        Ok(text)
    }

    /// Computes the reference for every (haze, sun) pair on every core; `progress(done, total)`
    /// is called from the workers after each direction.
    pub fn compute(
        hazes: &[Haze],
        suns_deg: &[f64],
        dome: (usize, usize),
        settings: ReferenceSettings,
        progress: &(dyn Fn(usize, usize) -> Result<(), Cancelled> + Sync),
    ) -> Result<Self, Cancelled> {
        let atmospheres: Vec<Atmosphere> = hazes.iter().map(|h| h.atmosphere()).collect();
        let domes = compute_domes(&atmospheres, suns_deg, dome, settings, progress)?;
        let suns = domes.into_iter().map(|(k, sun_elev_deg, radiance, std_err)| ReferenceSun { haze: hazes[k], sun_elev_deg, radiance, std_err }).collect();
        Ok(Self { settings, dome, suns })
    }

    /// The dome for an atmosphere and sun elevation, if computed.
    pub fn sun(&self, haze: Haze, sun_elev_deg: f64) -> Option<&ReferenceSun> {
        self.suns.iter().find(|s| s.haze == haze && s.sun_elev_deg == sun_elev_deg)
    }

    /// Writes the dataset as CSV with its header.
    pub fn save(&self, path: &Path) -> Result<(), ReferenceDomeError> {
        let mut text = Self::head(self.settings, self.dome);
        let dirs = dome_directions(self.dome.0, self.dome.1);
        for s in &self.suns {
            for ((d, l), e) in dirs.iter().zip(&s.radiance).zip(&s.std_err) {
                text.push_str(&dome_row(s.haze, s.sun_elev_deg, d, *l, *e));
            }
        }
        crate::support::safe_write::write_atomic(path, text.as_bytes()).map_err(|e| ReferenceDomeError::Io { file: path.display().to_string(), source: e.source })
    }

    /// Reads a dataset written by [`Self::save`] for these settings.
    pub fn load(path: &Path, settings: ReferenceSettings, dome: (usize, usize)) -> Result<Self, ReferenceDomeError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|source| ReferenceDomeError::Io { file: file.clone(), source })?;
        Self::parse(&text, &file, settings, dome)
    }

    /// Parses [`Self::save`]'s format.
    pub fn parse(text: &str, file: &str, settings: ReferenceSettings, dome: (usize, usize)) -> Result<Self, ReferenceDomeError> {
        let bad = |line: usize, message: String| ReferenceDomeError::Format { file: file.into(), line, message };
        let mut lines = text.lines().enumerate();
        let expected = format!("# {}", Self::header(settings, dome));
        match lines.next() {
            Some((_, h)) if h == expected => {}
            _ => return Err(bad(1, "written for other settings or atmospheres (header differs); recompute it".into())),
        }
        lines.next();
        let n = dome.0 * dome.1;
        let mut suns: Vec<ReferenceSun> = Vec::new();
        for (i, line) in lines {
            let f: Vec<&str> = line.split(',').collect();
            if f.len() != 10 {
                return Err(bad(i + 1, format!("expected 10 columns, found {}", f.len())));
            }
            let haze = Haze::from_name(f[0]).ok_or_else(|| bad(i + 1, format!("haze: unknown atmosphere \"{}\"", f[0])))?;
            let num = |k: usize| f[k].trim().parse::<f64>().map_err(|e| bad(i + 1, format!("column {}: {e}", k + 1)));
            let sun = num(1)?;
            let l = [num(4)?, num(5)?, num(6)?];
            let e = [num(7)?, num(8)?, num(9)?];
            match suns.last_mut() {
                Some(s) if s.haze == haze && s.sun_elev_deg == sun && s.radiance.len() < n => {
                    s.radiance.push(l);
                    s.std_err.push(e);
                }
                _ => suns.push(ReferenceSun { haze, sun_elev_deg: sun, radiance: vec![l], std_err: vec![e] }),
            }
        }
        if let Some(s) = suns.iter().find(|s| s.radiance.len() != n) {
            return Err(bad(0, format!("{} at sun {} has {} directions, expected {n}", s.haze.name(), s.sun_elev_deg, s.radiance.len())));
        }
        Ok(Self { settings, dome, suns })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cancelled_dome_stops_early_and_returns_nothing_partial() {
        let atm = [Atmosphere::default()];
        let calls = std::sync::atomic::AtomicUsize::new(0);
        let out = compute_domes(&atm, &[-6.0, 30.0], BENCH_DOME, ReferenceSettings { paths: 8, ..Default::default() }, &|done, _| {
            calls.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            if done >= 3 {
                Err(Cancelled)
            } else {
                Ok(())
            }
        });
        assert_eq!(out, Err(Cancelled));
        let directions = 2 * dome_directions(BENCH_DOME.0, BENCH_DOME.1).len();
        // Each worker finishes the direction it holds, then stops.
        let workers = std::thread::available_parallelism().map_or(1, |n| n.get());
        assert!(calls.into_inner() <= 3 + workers, "stopped early, of {directions}");
        let whole = compute_domes(&atm, &[30.0], (2, 3), ReferenceSettings { paths: 8, ..Default::default() }, &|_, _| Ok(())).expect("not cancelled");
        assert_eq!(whole.len(), 1);
        assert_eq!(whole[0].2.len(), dome_directions(2, 3).len());
    }
}
