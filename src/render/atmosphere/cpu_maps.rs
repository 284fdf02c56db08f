//! The `cells` and `reference` models' sky-view maps, computed on a CPU worker thread: the
//! sky-view pass asks for a map and uploads the radiance when it arrives.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;

use crate::atmosphere::cells::{CellModel, CellSettings};
use crate::atmosphere::reference::{Case, Reference, ReferenceSettings};
use crate::atmosphere::Atmosphere;
use crate::render::plan::resolution::SKY_VIEW_SIZE;

/// A model computed on the CPU worker.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum CpuModel {
    /// The cell model with its settings.
    Cells(CellSettings),
    /// The double-precision reference: Monte Carlo paths per direction, and the coarse grid of
    /// directions it is evaluated on (then interpolated over the map).
    Reference { paths: u32, grid: [u32; 2] },
}

/// A sky-view map for the CPU worker to compute.
pub(super) struct CpuJob {
    pub(super) id: u64,
    pub(super) atmosphere: Atmosphere,
    pub(super) albedo: f64,
    pub(super) model: CpuModel,
    pub(super) camera_km: f64,
    pub(super) towards_sun: glam::DVec3,
}

/// Directions done and directions in all, of the job in progress.
#[derive(Default)]
pub(super) struct Progress {
    pub(super) done: AtomicUsize,
    pub(super) total: AtomicUsize,
}

/// The CPU worker of the `cells` and `reference` models: keeps the last cell solution and
/// answers with radiance per texel of the sky-view map. Bursts of jobs (a moving sun) are
/// coalesced to the latest.
pub(super) struct CpuWorker {
    pub(super) jobs: std::sync::mpsc::Sender<CpuJob>,
    pub(super) results: std::sync::mpsc::Receiver<(u64, Vec<[f32; 4]>)>,
    pub(super) progress: Arc<Progress>,
}

impl CpuWorker {
    pub(super) fn spawn() -> Option<Self> {
        let (jobs, job_rx) = std::sync::mpsc::channel::<CpuJob>();
        let (result_tx, results) = std::sync::mpsc::channel();
        let progress = Arc::new(Progress::default());
        let shared = progress.clone();
        let spawned = std::thread::Builder::new().name("skytune-sky-model".into()).spawn(move || {
            let mut cells: Option<CellModel> = None;
            while let Ok(mut job) = job_rx.recv() {
                while let Ok(next) = job_rx.try_recv() {
                    job = next;
                }
                let map = match job.model {
                    CpuModel::Cells(settings) => {
                        if !cells.as_ref().is_some_and(|m| m.solved_for(&job.atmosphere, job.albedo, &settings)) {
                            cells = Some(CellModel::solve(job.atmosphere, job.albedo, settings));
                        }
                        let Some(m) = cells.as_ref() else { continue };
                        sky_view_radiance([SKY_VIEW_SIZE.0, SKY_VIEW_SIZE.1], job.towards_sun, &shared, |dir| m.radiance_towards(job.camera_km, dir, job.towards_sun))
                    }
                    CpuModel::Reference { paths, grid } => {
                        let reference = Reference::new(job.atmosphere, ReferenceSettings { paths, ..Default::default() });
                        let sun = job.towards_sun;
                        let coarse = sky_view_radiance(grid, sun, &shared, |dir| {
                            let az = |d: glam::DVec3| d.x.atan2(-d.z);
                            let case = Case {
                                camera_km: job.camera_km,
                                albedo: job.albedo,
                                sun_elev_deg: sun.y.clamp(-1.0, 1.0).asin().to_degrees(),
                                view_elev_deg: dir.y.clamp(-1.0, 1.0).asin().to_degrees(),
                                rel_azimuth_deg: (az(dir) - az(sun)).to_degrees(),
                                distance_km: None,
                            };
                            reference.radiance(&case)
                        });
                        upsample(&coarse, grid)
                    }
                };
                if result_tx.send((job.id, map)).is_err() {
                    break;
                }
            }
        });
        match spawned {
            Ok(_) => Some(Self { jobs, results, progress }),
            Err(e) => {
                log::error!("cannot start the sky-model worker: {e}");
                None
            }
        }
    }
}

/// Bilinear interpolation of a coarse map (texel centres, both axes clamped at their ends, as the
/// map's sampler does) onto the sky-view map.
fn upsample(coarse: &[[f32; 4]], [gw, gh]: [u32; 2]) -> Vec<[f32; 4]> {
    let (w, h) = SKY_VIEW_SIZE;
    let at = |x: i64, y: i64| coarse[(y.clamp(0, gh as i64 - 1) as u32 * gw + x.clamp(0, gw as i64 - 1) as u32) as usize];
    (0..w * h)
        .map(|k| {
            let (u, v) = ((k % w) as f32 + 0.5, (k / w) as f32 + 0.5);
            let (x, y) = (u / w as f32 * gw as f32 - 0.5, v / h as f32 * gh as f32 - 0.5);
            let (x0, y0) = (x.floor(), y.floor());
            let (fx, fy) = (x - x0, y - y0);
            let (x0, y0) = (x0 as i64, y0 as i64);
            let (a, b, c, d) = (at(x0, y0), at(x0 + 1, y0), at(x0, y0 + 1), at(x0 + 1, y0 + 1));
            std::array::from_fn(|i| (a[i] * (1.0 - fx) + b[i] * fx) * (1.0 - fy) + (c[i] * (1.0 - fx) + d[i] * fx) * fy)
        })
        .collect()
}

/// Radiance of every texel of a `w` x `h` sky-view map with the sun towards `towards_sun` (the
/// direction of a texel as `sky_view_direction` in shaders/sky_model/sky_view_map.wgsl), rows
/// split over the machine's cores; counts progress.
fn sky_view_radiance([w, h]: [u32; 2], towards_sun: glam::DVec3, progress: &Progress, radiance: impl Fn(glam::DVec3) -> [f64; 3] + Sync) -> Vec<[f32; 4]> {
    let sun_azimuth = towards_sun.x.atan2(-towards_sun.z);
    let mut out = vec![[0.0f32; 4]; (w * h) as usize];
    progress.done.store(0, Ordering::Relaxed);
    progress.total.store(out.len(), Ordering::Relaxed);
    let workers = std::thread::available_parallelism().map_or(1, |n| n.get());
    let rows_per = (h as usize).div_ceil(workers).max(1);
    std::thread::scope(|scope| {
        for (chunk_index, chunk) in out.chunks_mut(rows_per * w as usize).enumerate() {
            let radiance = &radiance;
            scope.spawn(move || {
                for (k, texel) in chunk.iter_mut().enumerate() {
                    let index = chunk_index * rows_per * w as usize + k;
                    let (x, y) = ((index % w as usize) as f64, (index / w as usize) as f64);
                    let (u, v) = ((x + 0.5) / w as f64, (y + 0.5) / h as f64);
                    let azimuth = sun_azimuth + u * std::f64::consts::PI;
                    let e = (0.5 - v) * 2.0;
                    let elevation = e.signum() * e * e * std::f64::consts::FRAC_PI_2;
                    let dir = glam::DVec3::new(azimuth.sin() * elevation.cos(), elevation.sin(), -azimuth.cos() * elevation.cos());
                    let l = radiance(dir);
                    *texel = [l[0] as f32, l[1] as f32, l[2] as f32, 1.0];
                    progress.done.fetch_add(1, Ordering::Relaxed);
                }
            });
        }
    });
    out
}
