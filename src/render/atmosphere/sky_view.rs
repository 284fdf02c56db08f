//! Sky-view pass (compute phase): renders the frame's physical sky model into the shared sky-view
//! map as exposed linear radiance, which the skydome's gradient stage then samples into the HDR
//! target (the display phase tone-maps it: `tone_map.rs`) or tone-maps itself on a
//! display-referred frame. Idle with the NeL bitmap model; recomputed only when the sun, the
//! model or the atmosphere changes. While the sun moves by small steps the fill strategy may
//! spread each map over frames ([`crate::render::plan::map_updates`]): `cs_main` computes a slice
//! of the work map, and `sky_view/blend.wgsl` writes the shown map from the two last finished
//! ones. The `cells` model is solved and marched on a CPU worker thread; its radiance reaches the
//! GPU when ready, and until then the previous map stays.

use bytemuck::{Pod, Zeroable};

use std::sync::atomic::Ordering;
use std::sync::Arc;

use crate::atmosphere::cells::CellSettings;
use crate::render::atmosphere::cpu_maps::{CpuJob, CpuModel, CpuWorker};
use crate::render::atmosphere::tables::{PrecomputedHeader, PrecomputedState};
use crate::render::atmosphere::uniforms::{AtmosphereUniform, LutUniform, SingleUniform};
use crate::render::frame::light::{LightSource, MODEL_LIGHT_OFFSET};
use crate::render::frame::pass::{DrawItem, FrameContext, Pass, PassBuild, Phase, Pipelines};
use crate::render::gpu::error::RenderResult;
use crate::render::gpu::shaders;
use crate::render::plan::resolution::SKY_VIEW_SIZE;
use crate::sky::resolved::{SkyModel, SkyModelKind};

/// Maps of CPU models kept (each 96 x 108 texels of 16 bytes: 165 KiB).
const CPU_CACHE_MAPS: usize = 16;

/// Bytes of one sky-view texel ([`crate::render::atmosphere::SKY_VIEW_FORMAT`]).
const TEXEL_BYTES: u32 = 8;

/// Bytes of one texel of the work and finished maps (four f32).
const MAP_TEXEL_BYTES: u32 = 16;

/// Keep in sync with `BlendParams` in shaders/sky_view/blend.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
struct BlendParams {
    /// Weight of the newer finished map (x), texels (y).
    settings: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<BlendParams>() == 16);

/// Keep in sync with `SkyViewParams` in shaders/sky_view.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable, PartialEq)]
pub struct SkyViewParams {
    /// Unit vector towards the sun (xyz), viewer altitude in km (w).
    pub towards_sun: [f32; 4],
    /// Radiance scale 2^EV (x), tone mapper of the scene's light (y: 0 ACES, 1 neutral), map size
    /// in texels (zw).
    pub exposure: [f32; 4],
    /// Model (x: 0 single, 1 lut, 2 radiance from the CPU, 3 analytic, 4 precomputed), automatic
    /// exposure (y: 1).
    pub model: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<SkyViewParams>() == 48);

impl From<(&SkyModel, glam::Vec3)> for SkyViewParams {
    fn from((model, towards_sun): (&SkyModel, glam::Vec3)) -> Self {
        let (w, h) = SKY_VIEW_SIZE;
        let kind = match model.kind {
            SkyModelKind::Lut => 1.0,
            SkyModelKind::Cells | SkyModelKind::Reference => 2.0,
            k if k.is_analytic() => 3.0,
            SkyModelKind::Precomputed => 4.0,
            _ => 0.0,
        };
        // Braun and Cohen's colours are display values: no exposure, the tone mapper's inverse.
        let display_referred = model.kind == SkyModelKind::Linear;
        let exposure = if display_referred { 1.0 } else { model.camera.exposure_ev.exp2() };
        let auto = model.camera.auto_exposure && !display_referred;
        Self {
            towards_sun: towards_sun.extend(model.world.camera_km).to_array(),
            exposure: [exposure, crate::render::passes::tone_map::ToneMapUniform::from(model.camera.tone_mapper).settings[0] as f32, w as f32, h as f32],
            model: [kind, if auto { 1.0 } else { 0.0 }, 0.0, 0.0],
        }
    }
}

/// Everything the map depends on: it is recomputed when this changes.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Key {
    atmosphere: AtmosphereUniform,
    single: SingleUniform,
    lut: LutUniform,
    precomputed: PrecomputedHeader,
    /// Finished builds of the `precomputed` tables (a new build changes the map).
    precomputed_generation: u64,
    params: SkyViewParams,
    /// `cells` iterations, or `reference` paths and grid.
    cpu: [u32; 3],
    /// The analytic models' coefficients for this sun (and hour).
    analytic: [[f32; 4]; 12],
}

/// The sky-view pass.
pub struct SkyViewPass {
    pipeline: Pipelines<[wgpu::ComputePipeline; 2]>,
    blend_pipeline: Pipelines<wgpu::ComputePipeline>,
    single: wgpu::Buffer,
    params: wgpu::Buffer,
    /// The texels `cs_main` computes this frame (first, count).
    slice: wgpu::Buffer,
    /// The work map (`cs_main` writes it) and the older and newer finished maps.
    work: wgpu::Buffer,
    older: wgpu::Buffer,
    newer: wgpu::Buffer,
    blend_params: wgpu::Buffer,
    /// The shown map's texels (rgba16float), copied into the shared texture after the blend.
    texels: wgpu::Buffer,
    map: wgpu::Texture,
    bind_group: wgpu::BindGroup,
    blend_bind_group: wgpu::BindGroup,
    /// The newest map's key: the work map's while one is under way, else the newer finished one's.
    computed: Option<Key>,
    /// The last frame's key (how far the sun moved since).
    last_key: Option<Key>,
    /// How maps follow a moving sun.
    schedule: crate::render::plan::map_updates::MapSchedule,
    /// What this frame computes and shows.
    step: crate::render::plan::map_updates::MapFrame,
    /// The map was current this frame: its recomputation was skipped.
    skipped: bool,
    /// Maps computed so far (the stats panel and tests).
    pub maps_computed: u64,
    /// Radiance per texel from the CPU (`cells`).
    cpu_radiance: wgpu::Buffer,
    cells: Option<CpuWorker>,
    /// The job in flight: its id and the key it answers.
    cells_pending: Option<(u64, Key)>,
    /// Maps the CPU worker finished, newest last: going back to an hour, weather or atmosphere
    /// seen recently (a compare view toggling, a scrubbed slider) costs no recomputation.
    cpu_cache: Vec<(Key, Arc<Vec<[f32; 4]>>)>,
    next_job: u64,
    /// The analytic models' coefficients (`AnalyticCoefficients::vectors`).
    analytic: wgpu::Buffer,
    /// [`crate::render::atmosphere::AtmosphereGpu::sky_light`]: exposure, then the scene's fog,
    /// ambient and diffuse (16 bytes each).
    sky_light: wgpu::Buffer,
    /// The renderer's scene light, whose `model` this pass fills ([`LightSource`]).
    scene_light: wgpu::Buffer,
    /// Whether the `precomputed` tables are complete.
    precomputed_state: Arc<PrecomputedState>,
    /// What this frame's model lights: nothing until a map, and so its light, exists for it.
    light: LightSource,
}

fn uniform(device: &wgpu::Device, label: &str, size: usize) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size as u64,
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

impl SkyViewPass {
    /// Builds the pipeline and binds the shared sky-view map.
    pub fn new(b: &PassBuild<'_>) -> RenderResult<Self> {
        let device = b.device;
        let mut entries: Vec<wgpu::BindGroupLayoutEntry> = (0..2).map(|i| crate::render::gpu::parts::uniform_entry(i, wgpu::ShaderStages::COMPUTE)).collect();
        entries.push(wgpu::BindGroupLayoutEntry {
            binding: 2,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer { ty: wgpu::BufferBindingType::Storage { read_only: true }, has_dynamic_offset: false, min_binding_size: None },
            count: None,
        });
        entries.push(wgpu::BindGroupLayoutEntry {
            binding: 3,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer { ty: wgpu::BufferBindingType::Storage { read_only: false }, has_dynamic_offset: false, min_binding_size: None },
            count: None,
        });
        entries.extend([
            // The slice: a uniform, as the stage's storage buffers are all taken.
            crate::render::gpu::parts::uniform_entry(11, wgpu::ShaderStages::COMPUTE),
            crate::render::gpu::parts::storage_entry(4, true),
            crate::render::gpu::parts::storage_entry(5, true),
            crate::render::gpu::parts::storage_entry(6, true),
            crate::render::gpu::parts::storage_entry(7, true),
            crate::render::gpu::parts::storage_entry(8, false),
            // A uniform: the stage's eight storage buffers are taken.
            crate::render::gpu::parts::uniform_entry(9, wgpu::ShaderStages::COMPUTE),
            crate::render::gpu::parts::storage_entry(10, true),
        ]);
        let analytic = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("SkyView::analytic"),
            size: 12 * 16,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let sky_light = b.atmosphere.sky_light.clone();
        let (w, h) = SKY_VIEW_SIZE;
        let cpu_radiance = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("SkyView::cpu_radiance"),
            size: (w * h * 16) as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let texels = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("SkyView::texels"),
            size: (w * h * TEXEL_BYTES) as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let map_buffer = |label: &str| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: (w * h * MAP_TEXEL_BYTES) as u64,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let (work, older, newer) = (map_buffer("SkyView::work"), map_buffer("SkyView::older"), map_buffer("SkyView::newer"));
        let slice = uniform(device, "SkyView::slice", 16);
        let blend_params = uniform(device, "SkyView::blend_params", std::mem::size_of::<BlendParams>());
        let blend_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("SkyView::blend_layout"),
            entries: &[
                crate::render::gpu::parts::storage_entry(0, true),
                crate::render::gpu::parts::storage_entry(1, true),
                crate::render::gpu::parts::storage_entry(2, false),
                crate::render::gpu::parts::uniform_entry(3, wgpu::ShaderStages::COMPUTE),
            ],
        });
        let blend_bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("SkyView::blend_bind_group"),
            layout: &blend_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: older.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: newer.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 2, resource: texels.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 3, resource: blend_params.as_entire_binding() },
            ],
        });
        let blend_pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("SkyView::blend_pipeline_layout"),
            bind_group_layouts: &[Some(b.globals_layout), Some(&blend_layout)],
            immediate_size: 0,
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some("SkyView::layout"), entries: &entries });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("SkyView::pipeline_layout"),
            bind_group_layouts: &[Some(b.globals_layout), Some(&layout)],
            immediate_size: 0,
        });
        let single = uniform(device, "SkyView::single", std::mem::size_of::<SingleUniform>());
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("SkyView::params"),
            size: std::mem::size_of::<SkyViewParams>() as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("SkyView::bind_group"),
            layout: &layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: b.atmosphere.uniform.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: single.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 2, resource: params.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 3, resource: work.as_entire_binding() },
                b.atmosphere.luts.entries(4)[0].clone(),
                b.atmosphere.luts.entries(4)[1].clone(),
                b.atmosphere.luts.entries(4)[2].clone(),
                wgpu::BindGroupEntry { binding: 7, resource: cpu_radiance.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 8, resource: sky_light.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 9, resource: analytic.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 10, resource: b.atmosphere.precomputed.buffer.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 11, resource: slice.as_entire_binding() },
            ],
        });
        let map = b.atmosphere.sky_view.clone();
        Ok(Self {
            pipeline: Pipelines::new(b, pipeline_layout, Self::build)?,
            blend_pipeline: Pipelines::new(b, blend_pipeline_layout, Self::build_blend)?,
            single,
            params,
            slice,
            work,
            older,
            newer,
            blend_params,
            texels,
            map,
            bind_group,
            blend_bind_group,
            computed: None,
            last_key: None,
            schedule: Default::default(),
            step: Default::default(),
            skipped: false,
            maps_computed: 0,
            cpu_radiance,
            cells: None,
            cells_pending: None,
            cpu_cache: Vec::new(),
            next_job: 0,
            sky_light,
            analytic,
            scene_light: b.scene_light.clone(),
            precomputed_state: b.atmosphere.precomputed_state.clone(),
            light: LightSource::Bitmaps,
        })
    }

    /// The exposure pipeline, then the map pipeline.
    fn build(b: &PassBuild<'_>, layout: &wgpu::PipelineLayout) -> RenderResult<[wgpu::ComputePipeline; 2]> {
        let module = shaders::module(b.device, b.library, "sky_view")?;
        Ok([
            shaders::compute_pipeline(b.device, layout, &module, "cs_exposure", "SkyView::exposure_pipeline")?,
            shaders::compute_pipeline(b.device, layout, &module, "cs_main", "SkyView::pipeline")?,
        ])
    }

    /// The pipeline that writes the shown map from the finished ones.
    fn build_blend(b: &PassBuild<'_>, layout: &wgpu::PipelineLayout) -> RenderResult<wgpu::ComputePipeline> {
        let module = shaders::module(b.device, b.library, "sky_view/blend")?;
        shaders::compute_pipeline(b.device, layout, &module, "cs_blend", "SkyView::blend_pipeline")
    }
}

impl SkyViewPass {
    /// Progress (0..1) of a CPU model's map being computed, if one is.
    pub fn progress(&self) -> Option<f32> {
        let worker = self.cells.as_ref().filter(|_| self.cells_pending.is_some())?;
        let total = worker.progress.total.load(Ordering::Relaxed).max(1);
        Some(worker.progress.done.load(Ordering::Relaxed) as f32 / total as f32)
    }

    /// Asks the CPU worker for the map of `key` if it is not on it yet, and uploads a finished
    /// one. Returns whether this frame has the radiance of `key` to show.
    fn cells_ready(&mut self, cx: &FrameContext<'_>, model: &SkyModel, key: Key) -> bool {
        if self.cells.is_none() {
            self.cells = CpuWorker::spawn();
        }
        if let Some(map) = self.cpu_cache.iter().find(|(k, _)| *k == key).map(|(_, m)| m.clone()) {
            cx.queue.write_buffer(&self.cpu_radiance, 0, bytemuck::cast_slice(&map));
            self.cells_pending = None;
            return true;
        }
        let Some(worker) = &self.cells else { return false };
        if self.cells_pending.is_none_or(|(_, k)| k != key) {
            self.next_job += 1;
            let job = CpuJob {
                id: self.next_job,
                atmosphere: cx.frame.atmosphere,
                albedo: model.world.ground_albedo as f64,
                model: match model.kind {
                    SkyModelKind::Reference => CpuModel::Reference { paths: model.settings.reference.paths, grid: model.settings.reference.grid },
                    _ => CpuModel::Cells(CellSettings { iterations: model.settings.cell_iterations as usize, ..Default::default() }),
                },
                camera_km: model.world.camera_km as f64,
                towards_sun: cx.frame.towards_sun.as_dvec3(),
            };
            if worker.jobs.send(job).is_err() {
                self.cells = None;
                return false;
            }
            self.cells_pending = Some((self.next_job, key));
        }
        let Some((id, _)) = self.cells_pending else { return false };
        let mut ready = None;
        while let Ok((done, map)) = worker.results.try_recv() {
            if done == id {
                ready = Some(map);
            }
        }
        let Some(map) = ready else { return false };
        cx.queue.write_buffer(&self.cpu_radiance, 0, bytemuck::cast_slice(&map));
        self.cells_pending = None;
        if self.cpu_cache.len() >= CPU_CACHE_MAPS {
            self.cpu_cache.remove(0);
        }
        self.cpu_cache.push((key, Arc::new(map)));
        true
    }
}

impl Pass for SkyViewPass {
    fn name(&self) -> &'static str {
        "sky_view"
    }

    fn phase(&self) -> Phase {
        Phase::Compute
    }

    fn stage_pipelines(&mut self, b: &PassBuild<'_>) -> RenderResult<()> {
        self.pipeline.stage(b)?;
        self.blend_pipeline.stage(b)
    }

    fn commit_pipelines(&mut self, accept: bool) {
        self.pipeline.commit(accept);
        self.blend_pipeline.commit(accept);
        // New shaders may compute a different map.
        self.computed = None;
    }

    fn prepare(&mut self, cx: &FrameContext<'_>) {
        self.prepare_map(cx);
        let model = &cx.frame.sky_model;
        // Only once a map, and so its light, exists for the model in use.
        let kind = SkyViewParams::from((model, cx.frame.towards_sun)).model;
        self.light = match model.kind.is_physical() && self.computed.is_some_and(|k| k.params.model == kind) {
            false => LightSource::Bitmaps,
            true if model.drive_scene => LightSource::Model,
            true => LightSource::ModelClouds,
        };
    }

    fn items(&self, _cx: &FrameContext<'_>, out: &mut Vec<DrawItem>) {
        if self.step.exposure || self.step.texels.is_some() {
            out.push(DrawItem::new(0, 0));
        }
    }

    fn stats(&self, stats: &mut crate::render::frame::stats::FrameStats) {
        stats.map_skipped = self.skipped;
        stats.map_texels = self.step.texels.as_ref().map_or(0, |t| t.len() as u32);
    }

    fn dispatch(&self, cpass: &mut wgpu::ComputePass<'_>, _key: usize) {
        self.dispatch_map(cpass);
    }

    fn after_phase(&self, encoder: &mut wgpu::CommandEncoder, globals: &wgpu::BindGroup) {
        self.copy_map(encoder, globals);
        // Every frame the model's light is used: the renderer writes the scene light each frame.
        if self.light != LightSource::Bitmaps {
            encoder.copy_buffer_to_buffer(&self.sky_light, 0, &self.scene_light, MODEL_LIGHT_OFFSET, std::mem::size_of::<[[f32; 4]; 4]>() as u64);
        }
    }

    fn light_source(&self) -> Option<LightSource> {
        (self.light != LightSource::Bitmaps).then_some(self.light)
    }

    fn busy(&self) -> bool {
        self.cells_pending.is_some()
    }

    fn settled(&self) -> bool {
        self.cells_pending.is_none() && self.schedule.settled()
    }
}

impl SkyViewPass {
    /// Decides what this frame computes and shows of the map, and writes its inputs.
    fn prepare_map(&mut self, cx: &FrameContext<'_>) {
        use crate::render::plan::map_updates::{lead_frames, sun_ahead, sun_change, MapChange, MapFrame, MapUpdates, SPREAD_MAX_STEP_DEG};
        let model = &cx.frame.sky_model;
        self.step = MapFrame::default();
        self.skipped = false;
        if !model.kind.on_cpu() {
            // A switch away from a CPU model drops its request (a late answer is ignored).
            self.cells_pending = None;
        }
        if !model.kind.is_physical() {
            return;
        }
        let key = Key {
            atmosphere: (&cx.frame.atmosphere).into(),
            single: (&model.settings.single).into(),
            lut: LutUniform::new(&model.settings.lut, model.world.ground_albedo, cx.frame.atmosphere.mie_g),
            precomputed: PrecomputedHeader::new(&model.settings.precomputed, model.world.ground_albedo),
            precomputed_generation: self.precomputed_state.generation.load(Ordering::Relaxed),
            params: (model, cx.frame.towards_sun).into(),
            cpu: match model.kind {
                SkyModelKind::Reference => [model.settings.reference.paths, model.settings.reference.grid[0], model.settings.reference.grid[1]],
                _ => [model.settings.cell_iterations, 0, 0],
            },
            analytic: model.analytic().map_or([[0.0; 4]; 12], |m| m.coefficients(cx.frame.towards_sun.as_dvec3().to_array(), cx.frame.hour as f64).vectors),
        };
        let last_key = self.last_key.replace(key);
        // Until the tables are complete the last map stays (the tables pass builds them over
        // frames on a software rasteriser).
        if model.kind == SkyModelKind::Precomputed && !self.precomputed_state.complete.load(Ordering::Relaxed) {
            return;
        }
        // CPU models answer asynchronously: only GPU maps are recomputed when the skip is off.
        let unchanged = self.computed == Some(key) && (cx.options.skips.unchanged_tables || model.kind.on_cpu());
        if unchanged {
            self.cells_pending = None;
        } else if model.kind.on_cpu() && !self.cells_ready(cx, model, key) {
            return;
        }
        let (w, h) = SKY_VIEW_SIZE;
        let updates = if model.kind.on_cpu() { MapUpdates::Whole } else { cx.options.strategy.map_updates };
        // The sun a map begun this frame is computed for: a spread map, for the frame that will
        // show it alone.
        let sun = |k: &Key| glam::Vec3::from_slice(&k.params.towards_sun[..3]);
        let ahead = last_key.map_or(sun(&key), |last| sun_ahead(sun(&last), sun(&key), lead_frames(updates)));
        let change = match self.computed {
            _ if unchanged => MapChange::Same,
            // The sun still moving by a small step, nothing else changed: the spread goes on, or
            // the map stays while the sun is within what it resolves.
            Some(newest)
                if last_key != Some(key)
                    && !model.kind.on_cpu()
                    && sun_moved(&newest, &key).is_some()
                    && last_key.and_then(|l| sun_moved(&l, &key)).is_some_and(|deg| deg <= SPREAD_MAX_STEP_DEG) =>
            {
                sun_change(sun(&newest).angle_between(ahead).to_degrees())
            }
            // Anything else, the sun stopped away from the newest map included: whole, exactly.
            _ => MapChange::Other,
        };
        self.step = self.schedule.step(change, updates, w * h);
        self.skipped = self.step.is_idle();
        let mut key = key;
        if self.step.exposure && change == MapChange::SunStep {
            key.params.towards_sun = ahead.extend(key.params.towards_sun[3]).to_array();
        }
        if self.step.exposure {
            cx.queue.write_buffer(&self.single, 0, bytemuck::bytes_of(&key.single));
            cx.queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&key.params));
            cx.queue.write_buffer(&self.analytic, 0, bytemuck::cast_slice(&key.analytic));
            self.computed = Some(key);
        }
        if let Some(texels) = &self.step.texels {
            cx.queue.write_buffer(&self.slice, 0, bytemuck::cast_slice(&[texels.start, texels.len() as u32, 0, 0]));
        }
        if let Some(weight) = self.step.show {
            cx.queue.write_buffer(&self.blend_params, 0, bytemuck::bytes_of(&BlendParams { settings: [weight, (w * h) as f32, 0.0, 0.0] }));
        }
        if self.step.finish {
            self.maps_computed += 1;
        }
    }

    fn dispatch_map(&self, cpass: &mut wgpu::ComputePass<'_>) {
        let [exposure, map] = self.pipeline.get();
        cpass.set_bind_group(1, &self.bind_group, &[]);
        if self.step.exposure {
            cpass.set_pipeline(exposure);
            cpass.dispatch_workgroups(1, 1, 1);
        }
        if let Some(texels) = &self.step.texels {
            cpass.set_pipeline(map);
            cpass.dispatch_workgroups((texels.len() as u32).div_ceil(64), 1, 1);
        }
    }

    /// Between the compute phase and the sky phase, so this frame samples this frame's map: a
    /// finished work map takes its place among the finished ones, and the shown map is written.
    fn copy_map(&self, encoder: &mut wgpu::CommandEncoder, globals: &wgpu::BindGroup) {
        let (w, h) = SKY_VIEW_SIZE;
        if self.step.finish {
            let older_from = if self.step.whole { &self.work } else { &self.newer };
            encoder.copy_buffer_to_buffer(older_from, 0, &self.older, 0, None);
            encoder.copy_buffer_to_buffer(&self.work, 0, &self.newer, 0, None);
        }
        if self.step.show.is_some() {
            {
                let mut cpass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("SkyView::blend"), timestamp_writes: None });
                cpass.set_pipeline(self.blend_pipeline.get());
                cpass.set_bind_group(0, globals, &[]);
                cpass.set_bind_group(1, &self.blend_bind_group, &[]);
                cpass.dispatch_workgroups((w * h).div_ceil(64), 1, 1);
            }
            encoder.copy_buffer_to_texture(
                wgpu::TexelCopyBufferInfo {
                    buffer: &self.texels,
                    layout: wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(w * TEXEL_BYTES), rows_per_image: Some(h) },
                },
                self.map.as_image_copy(),
                wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
            );
        }
    }
}

/// How far the sun moved from `a` to `b`, degrees, if nothing else the map depends on did (the
/// analytic models' coefficients follow the sun: they count as something else).
fn sun_moved(a: &Key, b: &Key) -> Option<f32> {
    let sun = |k: &Key| glam::Vec3::from_slice(&k.params.towards_sun[..3]);
    // (towards_sun.w is the camera's altitude: not the sun.)
    let towards_sun = [a.params.towards_sun[0], a.params.towards_sun[1], a.params.towards_sun[2], b.params.towards_sun[3]];
    let same_but_sun = Key { params: SkyViewParams { towards_sun, ..b.params }, ..*b } == *a;
    same_but_sun.then(|| sun(a).angle_between(sun(b)).to_degrees())
}
