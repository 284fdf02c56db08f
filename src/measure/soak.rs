//! Soak: hours of an artist's use compressed into one run. Every frame changes the hour, weather,
//! GPU tier, view and sky model at random; every 100 frames the sky file is rewritten, alternating
//! a good edit and a broken one; every 500 frames the shaders are rebuilt. Resident memory and the
//! GPU's live objects and memory are sampled every 100 frames; the run fails on growth after
//! warm-up, on any error other than the broken file's own, and when a broken reload does not
//! leave the last good sky rendering exactly as before.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::{anyhow, bail, Context as _};

use crate::files::hot_reload::{LiveSky, SkySpec};
use crate::render::{Camera, GpuContext, Headless, RenderOptions};
use crate::sky::resolved::SkyModelKind;
use crate::sky::{FrameInput, Sky, Tier};

/// Frames between two sky reloads.
pub const RELOAD_EVERY: u64 = 100;
/// Frames between two shader rebuilds.
pub const SHADERS_EVERY: u64 = 500;
/// Frames between two memory samples.
pub const SAMPLE_EVERY: u64 = 100;

/// Settings of a soak run.
#[derive(Debug, Clone)]
pub struct SoakSettings {
    /// Frames to render.
    pub frames: u64,
    /// Target size, pixels.
    pub size: (u32, u32),
    /// Seed of the random changes (same seed, same run).
    pub seed: u64,
    /// Largest accepted growth of GPU memory and live buffers after warm-up (0.05: 5%).
    pub max_growth: f64,
    /// Largest accepted growth of resident memory after warm-up.
    pub max_rss_growth: f64,
    /// Frames of warm-up before growth is measured (caches of the shader compiler and the
    /// allocator fill over the first few shader rebuilds).
    pub warm_up_frames: u64,
    /// Folder holding the sky to soak (`sky.toml` and its bitmaps), copied to a temporary folder
    /// first; `None`: the built-in default sky.
    pub sky_dir: Option<PathBuf>,
}

/// One memory sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Frames rendered when sampled.
    pub frame: u64,
    /// Resident set size of the process, bytes.
    pub rss_bytes: u64,
    /// Live GPU buffers.
    pub gpu_buffers: i64,
    /// wgpu-hal's texture counter (not balanced on Vulkan: reported, not judged).
    pub gpu_textures: i64,
    /// GPU memory of buffers and textures, bytes.
    pub gpu_bytes: i64,
}

/// What a soak run found.
#[derive(Debug, Clone)]
pub struct SoakReport {
    /// The memory samples.
    pub samples: Vec<Sample>,
    /// Samples dropped as warm-up.
    pub warm_up: usize,
    /// Growth of resident memory after warm-up (last samples against the first ones).
    pub rss_growth: f64,
    /// Growth of GPU memory after warm-up.
    pub gpu_growth: f64,
    /// Growth of the count of live GPU buffers after warm-up.
    pub gpu_object_growth: f64,
    /// Good reloads that reached the renderer.
    pub good_reloads: u32,
    /// Broken reloads that were rejected with the broken file's error, the last good sky
    /// rendering the same picture afterwards.
    pub broken_reloads: u32,
    /// Shader rebuilds.
    pub shader_reloads: u32,
    /// Anything else that went wrong (must stay empty).
    pub errors: Vec<String>,
    /// Wall time, seconds.
    pub seconds: f64,
    /// Adapter.
    pub adapter: String,
}

/// Resident set size of this process, bytes (Linux; 0 elsewhere).
pub fn resident_bytes() -> u64 {
    let pages = std::fs::read_to_string("/proc/self/statm").ok().and_then(|s| s.split_whitespace().nth(1).and_then(|v| v.parse::<u64>().ok()));
    pages.unwrap_or(0) * 4096
}

fn gpu_sample(ctx: &GpuContext, frame: u64) -> Sample {
    let c = ctx.device.get_internal_counters().hal;
    Sample {
        frame,
        rss_bytes: resident_bytes(),
        gpu_buffers: c.buffers.read() as i64,
        gpu_textures: c.textures.read() as i64,
        gpu_bytes: c.buffer_memory.read() as i64 + c.texture_memory.read() as i64,
    }
}

/// Median of the values.
fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    if v.is_empty() {
        0.0
    } else {
        v[v.len() / 2]
    }
}

/// Growth of `value` from the first samples after warm-up to the last ones (medians of up to 5).
fn growth(samples: &[Sample], value: impl Fn(&Sample) -> f64) -> f64 {
    // The first and last third of the samples (at most 5 each): short runs compare something.
    let n = (samples.len() / 3).clamp(1, 5);
    if samples.len() < 2 {
        return 0.0;
    }
    let first = median(samples[..n].iter().map(&value).collect());
    let last = median(samples[samples.len() - n..].iter().map(&value).collect());
    if first <= 0.0 {
        return if last > 0.0 { f64::INFINITY } else { 0.0 };
    }
    (last - first) / first
}

/// A fresh temporary folder `skytune-NAME-PID` holding a copy of a sky to rewrite: the files of
/// `sky_file`'s folder (not its sub-folders), or the built-in sky when `None`. Returns the folder
/// and the copied sky file. The artist's files are only read.
pub fn sky_copy(name: &str, sky_file: Option<&Path>) -> anyhow::Result<(PathBuf, PathBuf)> {
    let dir = std::env::temp_dir().join(format!("skytune-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    let copied = match sky_file {
        Some(file) => {
            let from = file.parent().unwrap_or(Path::new("."));
            for entry in std::fs::read_dir(from).with_context(|| format!("reading {}", from.display()))? {
                let path = entry?.path();
                if path.is_file() {
                    std::fs::copy(&path, dir.join(path.file_name().unwrap_or_default())).with_context(|| format!("copying {}", path.display()))?;
                }
            }
            dir.join(file.file_name().unwrap_or_default())
        }
        None => crate::sky::builtin::write_sky_folder(&dir, crate::sky::procedural::preset("default").ok_or_else(|| anyhow!("no default preset"))?, 7)?,
    };
    Ok((dir, copied))
}

/// The same random changes for a given seed: hour, weather, tier, view, model (shared by
/// `skytune soak` and the window's `--soak`).
pub struct Driver {
    rng: fastrand::Rng,
}

impl Driver {
    /// A driver with its seed.
    pub fn new(seed: u64) -> Self {
        Self { rng: fastrand::Rng::with_seed(seed) }
    }

    /// The next frame's random input and camera.
    pub fn frame(&mut self, sky: &Sky) -> (FrameInput, Camera) {
        let r = &mut self.rng;
        let hour = r.f32() * sky.hours_per_day;
        let mut input = FrameInput::new(hour, r.f32());
        input.tier = Tier::ALL[r.usize(..Tier::ALL.len())];
        // Mostly the bitmaps; the GPU physical models now and then (the CPU ones would measure
        // their worker, not the tool).
        let kind = [SkyModelKind::Bitmap, SkyModelKind::Bitmap, SkyModelKind::Single, SkyModelKind::Lut][r.usize(..4)];
        input.sky_model = Some(crate::sky::resolved::SkyModel { kind, ..sky.model });
        let camera = Camera { yaw_deg: r.f32() * 360.0, pitch_deg: r.f32() * 100.0 - 10.0, ..Camera::default() };
        (input, camera)
    }
}

/// Runs a soak; `progress` is called every [`SAMPLE_EVERY`] frames.
pub fn run(ctx: GpuContext, settings: &SoakSettings, mut progress: impl FnMut(&Sample)) -> anyhow::Result<SoakReport> {
    let started = Instant::now();
    let (dir, sky_file) = sky_copy("soak", settings.sky_dir.as_ref().map(|d| d.join("sky.toml")).as_deref())?;
    let good_text = std::fs::read_to_string(&sky_file).with_context(|| format!("reading {}", sky_file.display()))?;
    // Broken the same way for any sky: an object whose name is a number.
    let broken_text = broken_version(&good_text);
    let mut live = LiveSky::new(SkySpec::File(sky_file.clone())).map_err(|e| anyhow!("{e}"))?;
    let adapter = ctx.adapter_line();
    let mut headless = Headless::new(ctx.clone(), settings.size.0, settings.size.1)?;
    headless.set_sky(live.sky())?;
    let mut driver = Driver::new(settings.seed);
    let mut report = SoakReport {
        samples: Vec::new(),
        warm_up: 0,
        rss_growth: 0.0,
        gpu_growth: 0.0,
        gpu_object_growth: 0.0,
        good_reloads: 0,
        broken_reloads: 0,
        shader_reloads: 0,
        errors: Vec::new(),
        seconds: 0.0,
        adapter,
    };
    let still_input = FrameInput::new(10.0, 0.2);
    let options = RenderOptions::default();
    // Stills compared across a broken reload: without the glare, whose visibility has history.
    let still_options = RenderOptions { glare: false, ..options };
    let mut reloads = 0u64;
    for frame in 1..=settings.frames {
        let sky = live.sky().clone();
        let (input, camera) = driver.frame(&sky);
        headless.frame(&sky, &input, &camera, &options, 1.0 / 60.0);
        headless.ctx.wait_idle()?;

        if frame % RELOAD_EVERY == 0 {
            reloads += 1;
            let broken = reloads.is_multiple_of(2);
            if broken {
                let before = headless.render(&sky, &still_input, &Camera::default(), &still_options)?;
                crate::support::safe_write::write_atomic(&sky_file, broken_text.as_bytes())?;
                // A save may reach the watcher as several events: wait for the state, not a count.
                let rejected = wait_until(&mut live, |l| l.error.as_ref().is_some_and(|e| e.to_string().contains("sky.toml:")));
                if !rejected {
                    report.errors.push(format!("frame {frame}: the broken file was not rejected with its error"));
                }
                let after = headless.render(live.sky(), &still_input, &Camera::default(), &still_options)?;
                if after != before {
                    report.errors.push(format!("frame {frame}: after the broken reload the last good sky renders differently"));
                } else {
                    report.broken_reloads += 1;
                }
            } else {
                // A real change each time: the name carries the frame.
                let text = good_version(&good_text, frame);
                crate::support::safe_write::write_atomic(&sky_file, text.as_bytes())?;
                let prefix = format!("soak {frame} ");
                if wait_until(&mut live, |l| l.error.is_none() && l.sky().name.starts_with(&prefix)) {
                    match headless.set_sky(live.sky()) {
                        Ok(()) => report.good_reloads += 1,
                        Err(e) => report.errors.push(format!("frame {frame}: uploading the reloaded sky: {e}")),
                    }
                } else {
                    report.errors.push(format!("frame {frame}: the good edit did not load: {:?}", live.error.as_ref().map(|e| e.to_string())));
                }
            }
        }
        // Sampled before this frame's shader rebuild: the old pipelines' memory is freed over the
        // next frames, and a sample right after a rebuild would measure that transient.
        if frame % SAMPLE_EVERY == 0 {
            headless.ctx.wait_idle()?;
            // What the allocator holds but nobody uses is not growth.
            crate::render::release_freed_memory();
            let sample = gpu_sample(&headless.ctx, frame);
            progress(&sample);
            report.samples.push(sample);
        }
        if frame % SHADERS_EVERY == 0 {
            match headless.renderer.reload_shaders(&headless.ctx) {
                Ok(()) => report.shader_reloads += 1,
                Err(e) => report.errors.push(format!("frame {frame}: shader rebuild: {e}")),
            }
        }
    }
    let uncaptured = headless.ctx.uncaptured_errors();
    if uncaptured > 0 {
        report.errors.push(format!("{uncaptured} wgpu error(s) outside any error scope (see the log)"));
    }
    if let Some(reason) = headless.ctx.lost_reason() {
        report.errors.push(format!("the device was lost: {reason}"));
    }
    report.warm_up = report.samples.iter().take_while(|s| s.frame <= settings.warm_up_frames).count().min(report.samples.len().saturating_sub(2));
    let steady = &report.samples[report.warm_up..];
    report.rss_growth = growth(steady, |s| s.rss_bytes as f64);
    report.gpu_growth = growth(steady, |s| s.gpu_bytes as f64);
    // Buffers only: wgpu-hal's Vulkan texture counter is not balanced (it goes negative), so
    // textures are watched through their memory.
    report.gpu_object_growth = growth(steady, |s| s.gpu_buffers as f64);
    report.seconds = started.elapsed().as_secs_f64();
    let _ = std::fs::remove_dir_all(&dir);
    Ok(report)
}

/// A broken version of any sky file: an object whose name is a number.
pub fn broken_version(good: &str) -> String {
    format!("{good}\n[[object]]\nname = 3\n")
}

/// A good version of a sky file that differs from the last one: the name carries `tag`.
pub fn good_version(good: &str, tag: u64) -> String {
    good.replacen("name = \"", &format!("name = \"soak {tag} "), 1)
}

/// Waits until the reloads the watcher starts bring `live` into the state `done` describes (asks
/// for a reload itself after 10 s without one); false after 30 s.
fn wait_until(live: &mut LiveSky, done: impl Fn(&LiveSky) -> bool) -> bool {
    let started = Instant::now();
    let mut asked = false;
    while started.elapsed() < Duration::from_secs(30) {
        let _ = live.wait(Duration::from_millis(200));
        if done(live) {
            // Let the rest of the save's events settle, so they do not land in the next reload.
            while live.wait(Duration::from_millis(150)).is_some() {}
            return done(live);
        }
        if !asked && started.elapsed() > Duration::from_secs(10) {
            live.request_reload();
            asked = true;
        }
    }
    false
}

impl SoakReport {
    /// Why the run failed, if it did.
    pub fn verdict(&self, settings: &SoakSettings) -> Result<(), String> {
        let mut problems = self.errors.clone();
        for (what, g, max_growth) in [
            ("resident memory", self.rss_growth, settings.max_rss_growth),
            ("GPU memory", self.gpu_growth, settings.max_growth),
            ("live GPU buffers", self.gpu_object_growth, settings.max_growth),
        ] {
            if g > max_growth {
                problems.push(format!("{what} grew {:.1}% after warm-up (at most {:.1}%)", g * 100.0, max_growth * 100.0));
            }
        }
        if problems.is_empty() {
            Ok(())
        } else {
            Err(problems.join("\n"))
        }
    }

    /// The Markdown report.
    pub fn markdown(&self, settings: &SoakSettings, plot: Option<&str>) -> String {
        use std::fmt::Write;
        let mib = |b: f64| b / (1u64 << 20) as f64;
        let mut md = String::new();
        let _ = writeln!(md, "### Measured run\n");
        let _ = writeln!(
            md,
            "Written by `skytune soak --frames {} --size {}x{} --seed {} --warm-up-frames {}` ({}); re-run it to refresh this section.\n",
            settings.frames,
            settings.size.0,
            settings.size.1,
            settings.seed,
            settings.warm_up_frames,
            if settings.sky_dir.is_some() { "a sky folder" } else { "the built-in sky" }
        );
        let _ = writeln!(md, "- adapter: {}; {} frames in {:.0} s", self.adapter, settings.frames, self.seconds);
        let _ = writeln!(
            md,
            "- every frame: random hour, weather, GPU tier, view and sky model (bitmap, single, lut); every {RELOAD_EVERY} frames the sky file is rewritten, alternating a good edit and a broken one; every {SHADERS_EVERY} frames the shaders are rebuilt"
        );
        let _ = writeln!(
            md,
            "- reloads: {} good (uploaded), {} broken (rejected with the file's error; the last good sky rendered the same picture after each), {} shader rebuilds",
            self.good_reloads, self.broken_reloads, self.shader_reloads
        );
        let _ = writeln!(md, "- errors other than the broken file's: {}", if self.errors.is_empty() { "none".to_string() } else { self.errors.join("; ") });
        let _ = writeln!(
            md,
            "- growth after warm-up ({} of {} samples dropped; medians of the first and last third of the samples, at most 5 each; resident memory sampled after handing freed heap back): resident memory {:+.2}% (limit {:.0}%), GPU memory {:+.2}%, live GPU buffers {:+.2}% (limit {:.0}%); GPU memory is wgpu-hal's count of buffer and texture memory (its texture object counter is not balanced on Vulkan and is listed for information only)\n",
            self.warm_up,
            self.samples.len(),
            self.rss_growth * 100.0,
            settings.max_rss_growth * 100.0,
            self.gpu_growth * 100.0,
            self.gpu_object_growth * 100.0,
            settings.max_growth * 100.0
        );
        if let Some(p) = plot {
            let _ = writeln!(md, "![Memory over frames]({p})\n");
        }
        let _ = writeln!(md, "| frame | resident MiB | GPU buffers | GPU texture counter | GPU MiB |\n|---:|---:|---:|---:|---:|");
        let step = (self.samples.len() / 20).max(1);
        for (i, s) in self.samples.iter().enumerate() {
            if i % step == 0 || i + 1 == self.samples.len() {
                let _ = writeln!(md, "| {} | {:.1} | {} | {} | {:.1} |", s.frame, mib(s.rss_bytes as f64), s.gpu_buffers, s.gpu_textures, mib(s.gpu_bytes as f64));
            }
        }
        md
    }

    /// Draws resident and GPU memory over frames as SVG.
    pub fn plot_svg(&self, path: &Path) -> anyhow::Result<()> {
        use plotters::prelude::*;
        let mut svg = String::new();
        {
            let root = SVGBackend::with_string(&mut svg, (800, 400)).into_drawing_area();
            root.fill(&WHITE).map_err(|e| anyhow!("{e}"))?;
            let mib = |b: f64| b / (1u64 << 20) as f64;
            let last = self.samples.last().map_or(1, |s| s.frame).max(1);
            let top = self.samples.iter().map(|s| mib(s.rss_bytes as f64).max(mib(s.gpu_bytes as f64))).fold(1.0, f64::max) * 1.15;
            let mut chart = ChartBuilder::on(&root)
                .caption("Memory over a soak run", ("sans-serif", 20))
                .margin(10)
                .x_label_area_size(40)
                .y_label_area_size(60)
                .build_cartesian_2d(0u64..last, 0.0..top)
                .map_err(|e| anyhow!("{e}"))?;
            chart.configure_mesh().x_desc("frame").y_desc("MiB").draw().map_err(|e| anyhow!("{e}"))?;
            chart
                .draw_series(LineSeries::new(self.samples.iter().map(|s| (s.frame, mib(s.rss_bytes as f64))), &BLUE))
                .map_err(|e| anyhow!("{e}"))?
                .label("resident memory")
                .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLUE));
            chart
                .draw_series(LineSeries::new(self.samples.iter().map(|s| (s.frame, mib(s.gpu_bytes as f64))), &RED))
                .map_err(|e| anyhow!("{e}"))?
                .label("GPU memory (buffers + textures)")
                .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RED));
            chart.configure_series_labels().background_style(WHITE.mix(0.8)).border_style(BLACK).position(SeriesLabelPosition::LowerRight).draw().map_err(|e| anyhow!("{e}"))?;
            root.present().map_err(|e| anyhow!("{e}"))?;
        }
        crate::support::safe_write::write_atomic(path, svg.as_bytes())?;
        Ok(())
    }
}

/// Markers of the generated soak section in a hand-written report.
pub const SECTION_BEGIN: &str = "<!-- soak:begin (written by skytune soak) -->";
/// End marker of the generated section.
pub const SECTION_END: &str = "<!-- soak:end -->";

/// `existing` with its soak section replaced by `section` (appended when it has none).
pub fn splice_section(existing: &str, section: &str) -> String {
    let block = format!("{SECTION_BEGIN}\n{section}\n{SECTION_END}\n\n");
    match (existing.find(SECTION_BEGIN), existing.find(SECTION_END)) {
        (Some(a), Some(b)) if b > a => format!("{}{block}{}", &existing[..a], existing[b + SECTION_END.len()..].trim_start_matches('\n')),
        _ if existing.trim().is_empty() => format!("# Reliability\n\n{block}"),
        _ => format!("{}\n{block}", existing.trim_end()),
    }
}

/// Fails unless `samples` has a value.
pub fn require_samples(report: &SoakReport) -> anyhow::Result<()> {
    if report.samples.len() < 3 {
        bail!("a soak needs at least {} frames to measure growth", 3 * SAMPLE_EVERY);
    }
    Ok(())
}
