//! Camera emitters' particles evaluated on the GPU (`shaders/particle_sim.wgsl`), used by the
//! precipitation pass: the CPU hands over the birth conditions (`GpuBirths`), the compute phase
//! writes one instance per birth slot in slot order. Measured against the CPU's evaluation in
//! `skytune bench frame` (docs/performance.md).

use bytemuck::{Pod, Zeroable};

use crate::render::gpu::error::RenderResult;
use crate::render::gpu::shaders;
use crate::render::gpu::shaders::ShaderLibrary;
use crate::sky::particles::{GpuBirths, ParticleInstance, MAX_GPU_BUCKETS};
use crate::sky::resolved::Emitter;

/// Keep in sync with `SimParams` in shaders/particle_sim.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct SimUniform {
    clock: [f32; 4],
    life: [f32; 4],
    direction: [f32; 4],
    shape: [f32; 4],
    color0: [f32; 4],
    color1: [f32; 4],
    misc: [u32; 4],
    buckets: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<SimUniform>() == 128);

/// The layout of the simulation's bind group 1.
pub fn layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    let storage = |binding: u32, read_only: bool| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer { ty: wgpu::BufferBindingType::Storage { read_only }, has_dynamic_offset: false, min_binding_size: None },
        count: None,
    };
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("ParticleSim::layout"),
        entries: &[crate::render::gpu::parts::uniform_entry(0, wgpu::ShaderStages::COMPUTE), storage(1, false), storage(2, true)],
    })
}

/// The pipeline layout, with `group0` as bind group 0 (the frame's globals, or an empty layout).
pub fn pipeline_layout(device: &wgpu::Device, group0: &wgpu::BindGroupLayout, layout: &wgpu::BindGroupLayout) -> wgpu::PipelineLayout {
    device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("ParticleSim::pipeline_layout"),
        bind_group_layouts: &[Some(group0), Some(layout)],
        immediate_size: 0,
    })
}

/// The pipeline.
pub fn pipeline(device: &wgpu::Device, library: &ShaderLibrary, pipeline_layout: &wgpu::PipelineLayout) -> RenderResult<wgpu::ComputePipeline> {
    let module = shaders::module(device, library, "particle_sim")?;
    shaders::compute_pipeline(device, pipeline_layout, &module, "cs_main", "ParticleSim::pipeline")
}

/// One camera emitter's buffers.
pub struct GpuParticleSim {
    params: wgpu::Buffer,
    conditions: wgpu::Buffer,
    /// Instances, one per slot (vertex-buffer usable).
    pub particles: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    /// Slots of the last `prepare` (instances to draw).
    pub slots: u32,
}

impl GpuParticleSim {
    /// Buffers for `cap` particles, bound with `layout` (from [`layout`]).
    pub fn new(device: &wgpu::Device, layout: &wgpu::BindGroupLayout, cap: u32) -> Self {
        let buffer = |label: &str, size: u64, usage| device.create_buffer(&wgpu::BufferDescriptor { label: Some(label), size, usage, mapped_at_creation: false });
        let params = buffer("ParticleSim::params", std::mem::size_of::<SimUniform>() as u64, wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST);
        let conditions = buffer("ParticleSim::conditions", (MAX_GPU_BUCKETS as u64 + 1) * 3 * 16, wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST);
        let particles = buffer(
            "ParticleSim::particles",
            cap.max(1) as u64 * std::mem::size_of::<ParticleInstance>() as u64,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_SRC,
        );
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("ParticleSim::bind_group"),
            layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: params.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: particles.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 2, resource: conditions.as_entire_binding() },
            ],
        });
        Self { params, conditions, particles, bind_group, slots: 0 }
    }

    /// Writes the parameters of `e` and this frame's births.
    pub fn prepare(&mut self, queue: &wgpu::Queue, e: &Emitter, births: &GpuBirths) {
        let cap = (self.particles.size() / std::mem::size_of::<ParticleInstance>() as u64) as u32;
        self.slots = births.slots.min(cap);
        let axis = e.direction.try_normalize().unwrap_or(glam::Vec3::NEG_Y);
        let shape = if e.texture.is_some() { 4 } else { e.shape as u32 };
        let u = SimUniform {
            clock: [births.first_age_s, births.slot_interval_s, births.acceptance, self.slots as f32],
            life: [e.lifetime_s, e.lifetime_spread, e.speed, e.speed_spread],
            direction: [axis.x, axis.y, axis.z, e.spread_deg.to_radians()],
            shape: [e.gravity, e.box_m, e.size[0], e.size[1]],
            color0: e.color[0],
            color1: e.color[1],
            misc: [e.seed as u32, (e.kind == crate::sky::model::EmitterKind::Precipitation) as u32, births.first_slot, e.streak_s.to_bits()],
            buckets: [births.bucket_offset_s, births.bucket_s, (births.conditions.len() / 3).max(1) as f32, shape as f32],
        };
        queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&u));
        if !births.conditions.is_empty() {
            queue.write_buffer(&self.conditions, 0, bytemuck::cast_slice(&births.conditions));
        }
    }

    /// Records the evaluation into `cpass`, whose bind group 0 is set.
    pub fn dispatch(&self, cpass: &mut wgpu::ComputePass<'_>, pipeline: &wgpu::ComputePipeline) {
        if self.slots == 0 {
            return;
        }
        cpass.set_pipeline(pipeline);
        cpass.set_bind_group(1, &self.bind_group, &[]);
        cpass.dispatch_workgroups(self.slots.div_ceil(64), 1, 1);
    }
}

/// The evaluation outside a frame (benchmarks, tests): its own pipeline with an empty group 0.
pub struct StandaloneSim {
    pipeline: wgpu::ComputePipeline,
    empty: wgpu::BindGroup,
    /// The emitter's buffers.
    pub sim: GpuParticleSim,
}

impl StandaloneSim {
    /// A pipeline and buffers for `cap` particles.
    pub fn new(ctx: &crate::render::gpu::context::GpuContext, library: &ShaderLibrary, cap: u32) -> RenderResult<Self> {
        let device = &ctx.device;
        let layout = layout(device);
        let empty_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some("ParticleSim::empty_layout"), entries: &[] });
        let pipeline = pipeline(device, library, &pipeline_layout(device, &empty_layout, &layout))?;
        let empty = device.create_bind_group(&wgpu::BindGroupDescriptor { label: Some("ParticleSim::empty"), layout: &empty_layout, entries: &[] });
        Ok(Self { pipeline, empty, sim: GpuParticleSim::new(device, &layout, cap) })
    }

    /// Records the evaluation of the last `prepare`.
    pub fn record(&self, encoder: &mut wgpu::CommandEncoder) {
        let mut cpass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("ParticleSim::pass"), timestamp_writes: None });
        cpass.set_bind_group(0, &self.empty, &[]);
        self.sim.dispatch(&mut cpass, &self.pipeline);
    }

    /// The instances written (blocks), dead slots included.
    pub fn read(&self, ctx: &crate::render::gpu::context::GpuContext) -> RenderResult<Vec<ParticleInstance>> {
        let size = self.sim.slots as u64 * std::mem::size_of::<ParticleInstance>() as u64;
        if size == 0 {
            return Ok(Vec::new());
        }
        let bytes = crate::render::gpu::readback::read_buffer(ctx, &self.sim.particles, size)?;
        Ok(bytemuck::pod_collect_to_vec(&bytes))
    }
}
