//! Particles pass (sky phase): the particles of emitters attached to sky objects, on the dome in
//! directions, interleaved with the objects by the owner's priority; and the lightning flash
//! over the sky. The simulation is the CPU's (`crate::sky::particles`, measured faster than a
//! compute pass on lavapipe: docs/performance.md); this pass uploads the instances and draws them.
//! `precipitation.rs` draws the emitters attached to the camera with the same GPU resources.

use crate::render::frame::pass::{Caps, DrawItem, FrameContext, Pass, PassBuild, Phase, Pipelines, Placement, SkyUpload, Staged, Target};
use crate::render::frame::stats::FrameStats;
use crate::render::gpu::error::RenderResult;
use crate::render::gpu::shaders;
use crate::render::gpu::textures::TextureCache;
use crate::render::plan::resolution::Divisor;
use crate::sky::particles::ParticleInstance;
use crate::sky::resolved::{BlendMode, EmitterAttach};
use crate::sky::Sky;

/// One emitter's GPU side: its sprite, blend and instance buffer (grown on demand).
pub struct EmitterGpu {
    /// Emitter name: living particles of an emitter that still exists carry over a reload.
    pub name: String,
    /// Bind group 1: sprite texture and sampler.
    pub bind_group: wgpu::BindGroup,
    /// Additive (else alpha).
    pub additive: bool,
    /// Instances, rewritten every frame.
    pub buffer: Option<wgpu::Buffer>,
    /// Instances written this frame.
    pub count: u32,
    /// Whether it draws around the camera (precipitation) rather than on the dome.
    pub camera: bool,
    /// Priority of the owning object (dome emitters).
    pub priority: u8,
}

/// The GPU side of every emitter of a sky, for one of the two particle passes.
pub struct EmitterSet {
    /// Per emitter of the sky, in its order.
    pub emitters: Vec<EmitterGpu>,
}

impl EmitterSet {
    /// Bind groups for every emitter of `sky` (sprites through the shared texture cache; a white
    /// texel for procedural shapes).
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue, layout: &wgpu::BindGroupLayout, sampler: &wgpu::Sampler, textures: &mut TextureCache, sky: &Sky) -> Self {
        let white = crate::sky::resolved::TextureImage { width: 1, height: 1, rgba8: vec![255; 4], key: "skytune:particle-white".into() };
        let emitters = sky
            .emitters
            .iter()
            .map(|e| {
                let view = textures.get(device, queue, e.texture.as_deref().unwrap_or(&white));
                let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("Particles::bind_group"),
                    layout,
                    entries: &[
                        wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&view) },
                        wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::Sampler(sampler) },
                    ],
                });
                let (camera, priority) = match e.attach {
                    EmitterAttach::Camera => (true, 0),
                    EmitterAttach::Object(i) => (false, sky.objects.get(i).map_or(0, |o| o.priority)),
                };
                EmitterGpu { name: e.name.clone(), bind_group, additive: e.blend != BlendMode::Alpha, buffer: None, count: 0, camera, priority }
            })
            .collect();
        Self { emitters }
    }

    /// Writes this frame's instances of the emitters drawn `camera`-side (or dome-side), growing
    /// buffers as needed; `extra` adds instances to a dome draw (the flash), keyed by emitter.
    pub fn upload(&mut self, cx: &FrameContext<'_>, camera: bool) {
        for g in self.emitters.iter_mut() {
            g.count = 0;
        }
        for f in &cx.frame.particles.emitters {
            let Some(g) = self.emitters.get_mut(f.emitter).filter(|g| g.camera == camera) else { continue };
            write_instances(cx.device, cx.queue, g, &f.instances);
        }
    }
}

/// Writes `instances` into `g`'s buffer, reallocating it (doubling) when it is too small.
pub fn write_instances(device: &wgpu::Device, queue: &wgpu::Queue, g: &mut EmitterGpu, instances: &[ParticleInstance]) {
    g.count = instances.len() as u32;
    if instances.is_empty() {
        return;
    }
    let bytes: &[u8] = bytemuck::cast_slice(instances);
    if g.buffer.as_ref().is_none_or(|b| b.size() < bytes.len() as u64) {
        let size = (bytes.len() as u64).next_power_of_two().max(64 * 64);
        g.buffer = Some(device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("Particles::instances"),
            size,
            usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        }));
    }
    if let Some(b) = &g.buffer {
        queue.write_buffer(b, 0, bytes);
    }
}

/// The bind group layout of both particle passes: sprite texture and sampler.
pub fn bind_layout(device: &wgpu::Device, label: &str) -> wgpu::BindGroupLayout {
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(label),
        entries: &[crate::render::gpu::parts::texture_entry(0), crate::render::gpu::parts::sampler_entry(1)],
    })
}

/// The sprites' sampler.
pub fn sampler(device: &wgpu::Device, label: &str) -> wgpu::Sampler {
    device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some(label),
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        address_mode_u: wgpu::AddressMode::ClampToEdge,
        address_mode_v: wgpu::AddressMode::ClampToEdge,
        ..Default::default()
    })
}

/// Alpha and additive pipelines of a particle shader (`name`), depth-tested, never writing depth.
pub fn build_pipelines(b: &PassBuild<'_>, layout: &wgpu::PipelineLayout, name: &str, label: &str) -> RenderResult<[wgpu::RenderPipeline; 2]> {
    let [alpha, additive] = build_entries(
        b,
        layout,
        name,
        label,
        [("fs_alpha", wgpu::BlendState::ALPHA_BLENDING, "alpha"), ("fs_main", crate::render::gpu::parts::ADDITIVE_ALPHA, "additive")],
        Some(wgpu::CompareFunction::Less),
    )?;
    Ok([alpha, additive])
}

/// One pipeline per (fragment entry point, blend, label suffix) of a particle shader (`name`),
/// depth-tested with `compare`; None: for a reduced buffer of dome layers (its format, no depth).
fn build_entries<const N: usize>(
    b: &PassBuild<'_>,
    layout: &wgpu::PipelineLayout,
    name: &str,
    label: &str,
    entries: [(&str, wgpu::BlendState, &str); N],
    compare: Option<wgpu::CompareFunction>,
) -> RenderResult<[wgpu::RenderPipeline; N]> {
    let device = b.device;
    let format = if compare.is_some() { b.color_format } else { crate::render::passes::reduced_layers::reduced_format(b.target) };
    let module = shaders::module(device, b.library, name)?;
    let constants = b.target_constants();
    let options = wgpu::PipelineCompilationOptions { constants: &constants, zero_initialize_workgroup_memory: true };
    let make = |entry: &str, blend: wgpu::BlendState, suffix: &str| {
        let label = format!("{label}::{suffix}");
        shaders::validated(device, &label, || {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(&label),
                layout: Some(layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("vs_main"),
                    buffers: &[Some(wgpu::VertexBufferLayout {
                        array_stride: std::mem::size_of::<ParticleInstance>() as u64,
                        step_mode: wgpu::VertexStepMode::Instance,
                        attributes: &wgpu::vertex_attr_array![0 => Float32x4, 1 => Float32x4, 2 => Float32x4, 3 => Uint32x4],
                    })],
                    compilation_options: options.clone(),
                },
                primitive: wgpu::PrimitiveState { topology: wgpu::PrimitiveTopology::TriangleStrip, cull_mode: None, ..Default::default() },
                depth_stencil: compare.and_then(|c| crate::render::gpu::parts::depth_state(false, c)),
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some(entry),
                    targets: &[Some(wgpu::ColorTargetState { format, blend: Some(blend), write_mask: wgpu::ColorWrites::ALL })],
                    compilation_options: options.clone(),
                }),
                multiview_mask: None,
                cache: None,
            })
        })
    };
    let built = entries.iter().map(|(entry, blend, suffix)| make(entry, *blend, suffix)).collect::<RenderResult<Vec<_>>>()?;
    Ok(built.try_into().unwrap_or_else(|_: Vec<_>| unreachable!("one pipeline per entry")))
}

/// Records one emitter's draw.
pub fn draw_emitter(rpass: &mut wgpu::RenderPass<'_>, pipelines: [&wgpu::RenderPipeline; 2], g: &EmitterGpu) -> u32 {
    let Some(buffer) = g.buffer.as_ref().filter(|_| g.count > 0) else { return 0 };
    rpass.set_pipeline(pipelines[g.additive as usize]);
    rpass.set_bind_group(1, &g.bind_group, &[]);
    rpass.set_vertex_buffer(0, buffer.slice(..));
    rpass.draw(0..4, 0..g.count);
    1
}

/// The flash's blend over the frame (`fs_flash` in shaders/particles.wgsl): its premultiplied
/// colour plus the target times one less its alpha (0 where the flash is only added; on a
/// display-referred physical frame one less the slope of the HDR sum it matches); the frame's
/// alpha kept.
const FLASH_BLEND: wgpu::BlendState = wgpu::BlendState {
    color: wgpu::BlendComponent { src_factor: wgpu::BlendFactor::One, dst_factor: wgpu::BlendFactor::OneMinusSrcAlpha, operation: wgpu::BlendOperation::Add },
    alpha: wgpu::BlendComponent { src_factor: wgpu::BlendFactor::Zero, dst_factor: wgpu::BlendFactor::One, operation: wgpu::BlendOperation::Add },
};

/// [`FLASH_BLEND`] into a run's reduced buffer: the run's transmittance scaled as its colour is,
/// so what is drawn under the run later (`Placement::UnderRun`) is flattened by the flash too.
const FLASH_RUN_BLEND: wgpu::BlendState = wgpu::BlendState {
    color: FLASH_BLEND.color,
    alpha: wgpu::BlendComponent { src_factor: wgpu::BlendFactor::Zero, dst_factor: wgpu::BlendFactor::OneMinusSrcAlpha, operation: wgpu::BlendOperation::Add },
};

/// Draw key of the lightning flash.
const FLASH_KEY: usize = usize::MAX;

/// The particles pass.
pub struct ParticlesPass {
    bind_layout: wgpu::BindGroupLayout,
    sampler: wgpu::Sampler,
    /// Alpha, additive, and the flash's (additive, `fs_flash`).
    pipeline: Pipelines<[wgpu::RenderPipeline; 3]>,
    /// Alpha and additive, drawn after the run of reduced layers above them
    /// ([`Placement::UnderRun`](crate::render::frame::pass::Placement::UnderRun)).
    under_run: Pipelines<[wgpu::RenderPipeline; 2]>,
    /// Additive, drawn first under the background, not depth-tested ([`Placement::First`](crate::render::frame::pass::Placement::First)).
    first: Pipelines<[wgpu::RenderPipeline; 1]>,
    /// The flash into a reduced buffer ([`Placement::Reduced`](crate::render::frame::pass::Placement::Reduced)).
    reduced: Pipelines<[wgpu::RenderPipeline; 1]>,
    set: Staged<Option<EmitterSet>>,
    /// The flash's one instance.
    flash: EmitterGpu,
    /// Particles alive and caps, for the stats.
    alive: u32,
}

impl ParticlesPass {
    /// Builds the pipelines.
    pub fn new(b: &PassBuild<'_>) -> RenderResult<Self> {
        let bind_layout = bind_layout(b.device, "Particles::layout");
        let pipeline_layout = b.device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("Particles::pipeline_layout"),
            bind_group_layouts: &[Some(b.globals_layout), Some(&bind_layout)],
            immediate_size: 0,
        });
        // The flash covers the screen: its own entry point keeps the shapes' branches, which a
        // SIMD rasteriser would run for every pixel, out of it.
        let pipeline = Pipelines::new_render(b, pipeline_layout.clone(), |b, l| {
            build_entries(
                b,
                l,
                "particles",
                "Particles::pipeline",
                [("fs_alpha", wgpu::BlendState::ALPHA_BLENDING, "alpha"), ("fs_main", crate::render::gpu::parts::ADDITIVE_ALPHA, "additive"), ("fs_flash", FLASH_BLEND, "flash")],
                Some(wgpu::CompareFunction::Less),
            )
        })?;
        // The flash added to a run of reduced dome layers ([`FlashPlacement::InRun`](crate::render::plan::strategy::FlashPlacement::InRun)).
        let reduced = Pipelines::new_render(b, pipeline_layout.clone(), |b, l| {
            build_entries(b, l, "particles", "Particles::reduced_pipeline", [("fs_flash", FLASH_RUN_BLEND, "flash")], None)
        })?;
        let first = Pipelines::new_render(b, pipeline_layout.clone(), |b, l| {
            build_entries(b, l, "particles", "Particles::first_pipeline", [("fs_main", crate::render::gpu::parts::ADDITIVE_ALPHA, "additive")], Some(wgpu::CompareFunction::Always))
        })?;
        let run_layout = crate::render::passes::reduced_layers::run_layout(b.device, "Particles::run_layout");
        let under_layout = b.device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("Particles::under_run_pipeline_layout"),
            bind_group_layouts: &[Some(b.globals_layout), Some(&bind_layout), Some(&run_layout)],
            immediate_size: 0,
        });
        let under_run = Pipelines::new_render(b, under_layout, |b, l| {
            // Premultiplied by the shader (fs_alpha_under_run).
            let over = wgpu::BlendState { color: wgpu::BlendComponent::OVER, alpha: wgpu::BlendComponent::OVER };
            let entries = [("fs_alpha_under_run", over, "alpha"), ("fs_main_under_run", crate::render::gpu::parts::ADDITIVE_ALPHA, "additive")];
            build_entries(b, l, "particles", "Particles::under_run_pipeline", entries, Some(wgpu::CompareFunction::Less))
        })?;
        let sampler = sampler(b.device, "Particles::sampler");
        // The flash's bind group: its texture is never sampled (fs_flash).
        let view = crate::render::gpu::textures::unused_view(b.device, "Particles::flash_texture");
        let bind_group = b.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("Particles::flash_bind_group"),
            layout: &bind_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&view) },
                wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::Sampler(&sampler) },
            ],
        });
        let flash = EmitterGpu { name: "flash".into(), bind_group, additive: true, buffer: None, count: 0, camera: false, priority: 63 };
        Ok(Self { bind_layout, sampler, pipeline, under_run, first, reduced, set: Staged::new(None), flash, alive: 0 })
    }
}

impl Pass for ParticlesPass {
    fn name(&self) -> &'static str {
        "particles"
    }

    fn phase(&self) -> Phase {
        Phase::Sky
    }

    fn stage_pipelines(&mut self, b: &PassBuild<'_>) -> RenderResult<()> {
        self.pipeline.stage(b)?;
        self.under_run.stage(b)?;
        self.first.stage(b)?;
        self.reduced.stage(b)
    }

    fn commit_pipelines(&mut self, accept: bool) {
        self.pipeline.commit(accept);
        self.under_run.commit(accept);
        self.first.commit(accept);
        self.reduced.commit(accept);
    }

    fn stage_sky(&mut self, up: &mut SkyUpload<'_>) {
        let set = (!up.sky.emitters.is_empty()).then(|| EmitterSet::new(up.device, up.queue, &self.bind_layout, &self.sampler, up.textures, up.sky));
        self.set.stage(set);
    }

    fn commit_sky(&mut self, accept: bool) {
        self.set.commit(accept);
    }

    fn prepare(&mut self, cx: &FrameContext<'_>) {
        self.alive = cx.frame.particles.alive() as u32;
        if let Some(set) = self.set.current.as_mut() {
            set.upload(cx, false);
        }
        let f = cx.frame.particles.flash.min(1.0);
        let flash = if f > 0.0 {
            // A cold white over the sky, additive; the scene's light is lifted by the evaluation.
            vec![ParticleInstance { position: [0.0, 1.0, 0.0, 1.0], velocity: [0.0; 4], color: [0.55 * f, 0.6 * f, 0.7 * f, 1.0], misc: [5, 0, 0, 0] }]
        } else {
            Vec::new()
        };
        write_instances(cx.device, cx.queue, &mut self.flash, &flash);
    }

    fn items(&self, cx: &FrameContext<'_>, out: &mut Vec<DrawItem>) {
        if let Some(set) = &self.set.current {
            for (key, g) in set.emitters.iter().enumerate().filter(|(_, g)| !g.camera && g.count > 0) {
                out.push(DrawItem { additive: g.additive, caps: Caps { under_run: true, first: g.additive, ..Caps::default() }, ..DrawItem::new(g.priority, key) });
            }
        }
        if self.flash.count > 0 {
            // One constant colour: it needs no resolution, so it joins the run of dome layers
            // before it, if there is one, at whatever resolution that run has.
            let (finest, coarsest) = cx.options.strategy.dome_resolution.divisors();
            let reduced = cx.options.strategy.flash_in_run() && finest.reduces();
            out.push(DrawItem { additive: true, reduced, joins_only: true, divisor: if reduced { coarsest } else { Divisor::FULL }, ..DrawItem::new(63, FLASH_KEY) });
        }
    }

    fn draw(&self, rpass: &mut wgpu::RenderPass<'_>, key: usize, target: Target, placement: Placement, run: Option<&wgpu::BindGroup>) -> u32 {
        let emitter = || self.set.current.as_ref().and_then(|s| s.emitters.get(key));
        match placement {
            Placement::Reduced if key == FLASH_KEY => {
                let [flash] = self.reduced.for_target(target);
                draw_emitter(rpass, [flash, flash], &self.flash)
            }
            Placement::UnderRun => {
                let [alpha, additive] = self.under_run.for_target(target);
                let (Some(g), Some(run)) = (emitter(), run) else { return 0 };
                rpass.set_bind_group(2, run, &[]);
                draw_emitter(rpass, [alpha, additive], g)
            }
            Placement::First => {
                let [additive] = self.first.for_target(target);
                emitter().filter(|g| g.additive).map_or(0, |g| draw_emitter(rpass, [additive, additive], g))
            }
            Placement::Plain => {
                let [alpha, additive, flash] = self.pipeline.for_target(target);
                if key == FLASH_KEY {
                    return draw_emitter(rpass, [flash, flash], &self.flash);
                }
                emitter().map_or(0, |g| draw_emitter(rpass, [alpha, additive], g))
            }
            _ => 0,
        }
    }

    fn stats(&self, stats: &mut FrameStats) {
        stats.particles = self.alive;
    }
}
