//! The report of `skytune bench frame`: what a run measured, written as docs/performance.md and as
//! the summary lines on stdout.

use std::fmt::Write as _;
use std::path::Path;

use super::{median, Case, ObjectCosts, ParticleCost, PhysicalRatios};
use skytune::sky::model::SkyModelKind;

/// Everything one run of `skytune bench frame` measured.
pub(super) struct FrameReport<'a> {
    /// The adapter, as `GpuContext::adapter_line` names it.
    pub adapter: String,
    /// Frame size, pixels.
    pub size: (u32, u32),
    /// Measured frames per case.
    pub frames: u32,
    /// `--dome-resolution`, overriding each strategy's.
    pub dome_resolution: Option<skytune::render::DomeResolution>,
    /// The strategies measured, by preset name.
    pub strategies: Vec<&'a str>,
    /// The adapter's own strategy.
    pub adapter_strategy: &'a str,
    /// The strategy the summary lines are about.
    pub summarised: &'a str,
    /// What the main-scene stand-in adds at the horizon, ms (median).
    pub stand_in_ms: f64,
    /// Painted skies against the floor, worst and median, sky alone.
    pub fill: (f64, f64),
    /// The same with the scene stand-in.
    pub scene: (f64, f64),
    /// Physical skies against their painted twins.
    pub physical: Option<PhysicalRatios>,
    /// Per strategy: name, worst and median ratio of the painted cases, and their frame against
    /// the summarised strategy's (median).
    pub per_strategy: Vec<(&'a str, f64, f64, f64)>,
    /// Every case of every strategy.
    pub cases: Vec<Case>,
    /// Each object's cost in the built-in sky at dusk (ms), that frame with every object left out
    /// and with all of them (ms): the sky as it is, then each of its copies with another skydome
    /// colour source.
    pub per_object: Vec<(SkyModelKind, ObjectCosts)>,
    /// `Sky::evaluate`: median microseconds and the object count.
    pub evaluation: (f64, usize),
    /// Particle simulation on the CPU and the GPU.
    pub particles: Vec<ParticleCost>,
    /// Reload latency per edit, ms: sky file, bitmap, shader.
    pub latency: (Vec<f64>, Vec<f64>, Vec<f64>),
}

impl FrameReport<'_> {
    /// docs/performance.md.
    pub fn markdown(&self) -> String {
        let mut md = self.header();
        self.case_table(&mut md);
        self.other_costs(&mut md);
        md
    }

    /// The title, the setup, the method and the summary lines with the table per strategy.
    fn header(&self) -> String {
        let (w, h) = self.size;
        let (summarised, stand_in_ms) = (self.summarised, self.stand_in_ms);
        let mut md = String::new();
        let _ = writeln!(md, "# Performance\n\nWritten by `skytune bench frame` (`cargo run --release -- bench frame`); re-run it to refresh this file.\n");
        let _ = writeln!(md, "- adapter: {}", self.adapter);
        let _ = writeln!(
            md,
            "- machine: {} logical CPUs; {}; {w}x{h}; {} measured frames per case after 2 warm-up frames; dome layers at {} resolution (`--dome-resolution`); fill strategies {} (`--strategy`), the adapter's own `{}`",
            std::thread::available_parallelism().map_or(1, |n| n.get()),
            skytune::build_line(),
            self.frames,
            self.dome_resolution.map_or("the strategy's", |r| r.name()),
            self.strategies.iter().map(|n| format!("`{n}`")).collect::<Vec<_>>().join(" and "),
            self.adapter_strategy
        );
        let _ = writeln!(
            md,
            "- method: each frame is recorded, submitted and waited for (wall time: on lavapipe the rasterisation itself). The floor is one render pass that clears the same target (rgba8) and draws one full-screen triangle sampling one 128 x 128 texture (`shaders/baseline.wgsl`); floor and sky frames alternate within each case, and the ratio is sky over floor of the same case. A sky's copies with physical models (`--sky-models`) are measured with it, their frames in turn, so that each physical frame is measured beside its painted twin; `physical_ratio` is, per case, the median of those pairs' ratios. The sky is drawn alone, filling the frame (`scene` off: the goal is the sky's cost); the frame with the main-scene stand-in in front of it (terrain and buildings at the horizon: {stand_in_ms:.1} ms more there, median over the horizon cases) is measured in the same alternation, for reference. The timed frames come from a renderer that records no GPU timestamps (the floor records none, and lavapipe charges a sky frame's timestamps about 3% of its time); the phase columns are timestamp medians of the same sky-alone frame drawn by a second renderer that records them, in the same alternation."
        );
        let ((worst, med), (scene_worst, scene_med)) = (self.fill, self.scene);
        let _ = writeln!(
            md,
            "\n**fill_limit_ratio worst={worst:.1} median={med:.1}** (`{summarised}` strategy; goal: 3; with the scene stand-in: worst {scene_worst:.1}, median {scene_med:.1})\n"
        );
        if let Some(p) = &self.physical {
            let _ = writeln!(md, "{}\n", p.describe(summarised));
        }
        let _ = writeln!(md, "| strategy | worst ratio | median ratio | frame against `{summarised}`, median of the cases |\n|---|---:|---:|---:|");
        for (name, worst, med, against) in &self.per_strategy {
            let _ = writeln!(md, "| {name} | {worst:.2} | {med:.2} | {against:.2} |");
        }
        let _ = writeln!(md);
        md
    }

    /// One row per case (a physical one also against its painted twin, frame by frame), with a
    /// column for every phase any case drew (rain's and the compute phase's only in some), in the
    /// order met.
    fn case_table(&self, md: &mut String) {
        let mut phase_names: Vec<&str> = Vec::new();
        for (n, _) in self.cases.iter().flat_map(|c| &c.phases) {
            if !phase_names.contains(n) {
                phase_names.push(n);
            }
        }
        let _ = write!(
            md,
            "| sky | model | strategy | hour | weather | view | frame ms | sun moving ms | floor ms | ratio | with scene ms | ratio with scene | against painted, still / moving |"
        );
        for n in &phase_names {
            let _ = write!(md, " {n} ms |");
        }
        let _ = write!(md, "\n|---|---|---|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|");
        for _ in &phase_names {
            let _ = write!(md, "---:|");
        }
        let _ = writeln!(md);
        for c in &self.cases {
            let _ = write!(
                md,
                "| {} | {} | {} | {} | {} | {} | {:.2} | {:.2} | {:.2} | {:.1} | {:.2} | {:.1} | {} |",
                c.sky,
                c.model.name(),
                c.strategy,
                c.hour,
                c.weather,
                c.view,
                c.sky_ms,
                c.moving_ms,
                c.floor_ms,
                c.sky_ms / c.floor_ms,
                c.with_scene_ms,
                c.with_scene_ms / c.floor_ms,
                c.against_twin(&self.cases).map_or_else(|| "-".to_string(), |[s, m]| format!("{s:.2} / {m:.2}"))
            );
            for n in &phase_names {
                let _ = match c.phases.iter().find(|(m, _)| m == n) {
                    Some((_, ms)) => write!(md, " {ms:.2} |"),
                    None => write!(md, " - |"),
                };
            }
            let _ = writeln!(md);
        }
    }

    /// Per object, the CPU's evaluation, particles and hot-reload latency.
    fn other_costs(&self, md: &mut String) {
        let frames: Vec<String> = self
            .per_object
            .iter()
            .map(|(kind, (_, nothing, all))| format!("{all:.2} ms a frame with the skydome's {} colours, {nothing:.2} ms with every object left out", kind.name()))
            .collect();
        let _ = writeln!(md, "\n## Where the time goes\n\nThe built-in sky alone at 18.5 h, weather 0.3, horizon view: {}. Each object's cost is the median difference between a frame with every object and one without it, the two alternating, each drawn by a renderer of its own (leaving one out can also change how the others are drawn: which layers join, which draw is the background):\n", frames.join("; "));
        let header: String = self.per_object.iter().map(|(kind, _)| format!(" {} ms | share |", kind.name())).collect();
        let _ = writeln!(md, "| object |{header}\n|---|{}", "---:|---:|".repeat(self.per_object.len()));
        let names: Vec<&String> = self.per_object.first().map(|(_, (objects, _, _))| objects.iter().map(|(n, _)| n).collect()).unwrap_or_default();
        for name in names {
            let cells: String = self
                .per_object
                .iter()
                .map(|(_, (objects, _, all))| objects.iter().find(|(n, _)| n == name).map_or(" - | - |".to_string(), |(_, ms)| format!(" {ms:.2} | {:.0}% |", 100.0 * ms / all)))
                .collect();
            let _ = writeln!(md, "| {name} |{cells}");
        }
        let (eval_us, objects) = self.evaluation;
        let _ = writeln!(md, "\n## CPU: evaluating the sky\n\n`Sky::evaluate` for a sky of {objects} objects (the built-in sky plus billboards on its paths): median {eval_us:.1} us per frame (target: 50 us).\n");
        let _ = writeln!(
            md,
            "## Particles: CPU or GPU simulation\n\nOne camera emitter (the built-in rain, always on, rate = cap / lifetime so the cap fills) at N particles, medians of {} frames at different times, side by side in one run. CPU: `sky::particle_sim::simulate` (the closed-form evaluation of every birth slot of the last lifetime) plus the upload of its instances; GPU: the CPU's table of birth conditions per sixteenth of a second, then the same evaluation as a compute pass (`shaders/particle_sim.wgsl`, one invocation per slot writing its instance in slot order), submitted and waited for. The renderer evaluates camera emitters (rain, snow: thousands of particles) on the GPU and dome emitters (shooting stars, eruptions, lightning: tens) on the CPU.\n",
            self.particles.first().map_or(0, |p| p.runs)
        );
        let _ = writeln!(md, "| particles | alive (CPU) | alive (GPU) | CPU + upload ms | GPU ms | GPU / CPU |\n|---:|---:|---:|---:|---:|---:|");
        for p in &self.particles {
            let _ = writeln!(md, "| {} | {} | {} | {:.3} | {:.3} | {:.2} |", p.cap, p.cpu_alive, p.gpu_alive, p.cpu_ms, p.gpu_ms, p.gpu_ms / p.cpu_ms);
        }
        let _ = writeln!(md);
        let (w, h) = self.size;
        let (files, bitmaps, shaders) = &self.latency;
        let _ = writeln!(md, "## Hot-reload latency\n\nFrom the end of a file write to the end of the first frame rendered with the change (file watcher with its debounce of {} ms, off-thread load, upload, one frame at {w}x{h}), medians of {} edits (target: 100 ms plus the debounce):\n", skytune::files::watch::DEBOUNCE.as_millis(), files.len().min(bitmaps.len()));
        let _ = writeln!(
            md,
            "| edit | median ms |\n|---|---:|\n| sky file | {:.0} |\n| bitmap | {:.0} |\n| shader (`sky_objects.wgsl`: every pipeline of the renderer rebuilt) | {:.0} |",
            median(files),
            median(bitmaps),
            median(shaders)
        );
    }

    /// The summary lines on stdout, after the report was written to `out`.
    pub fn print_summary(&self, out: &Path) {
        for p in &self.particles {
            println!("particles {}: CPU + upload {:.3} ms ({} alive), GPU {:.3} ms ({} alive)", p.cap, p.cpu_ms, p.cpu_alive, p.gpu_ms, p.gpu_alive);
        }
        for (kind, (objects, _, _)) in &self.per_object {
            println!("per object (built-in sky, {}, dusk, horizon): {}", kind.name(), objects.iter().map(|(n, ms)| format!("{n} {ms:.2} ms")).collect::<Vec<_>>().join(", "));
        }
        let (eval_us, objects) = self.evaluation;
        let (files, bitmaps, shaders) = &self.latency;
        println!(
            "evaluate: {eval_us:.1} us for {objects} objects; reload latency: sky file {:.0} ms, bitmap {:.0} ms, shader {:.0} ms",
            median(files),
            median(bitmaps),
            median(shaders)
        );
        println!("wrote {}", out.display());
        let ((worst, med), (scene_worst, scene_med)) = (self.fill, self.scene);
        println!("with the scene stand-in: worst={scene_worst:.2} median={scene_med:.2}");
        for (name, worst, med, against) in &self.per_strategy {
            println!("strategy {name}: worst={worst:.2} median={med:.2}, frame against {} median {against:.2}", self.summarised);
        }
        if let Some(p) = &self.physical {
            println!("physical_ratio worst={:.2} median={:.2}", p.still.0, p.still.1);
            println!("physical_ratio_sun_moving worst={:.2} median={:.2}", p.moving.0, p.moving.1);
        }
        println!("fill_limit_ratio worst={worst:.2} median={med:.2}");
    }
}
