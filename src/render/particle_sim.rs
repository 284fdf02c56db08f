//! The particle evaluation of `crate::sky::particles` as a compute pass (`shaders/particle_sim.wgsl`),
//! kept to be measured against the CPU's by `skytune bench frame` (docs/performance.md): on
//! lavapipe the CPU evaluation plus the instance upload is the faster at the default counts, so
//! the renderer draws the CPU's particles and this pass is not in the frame's list.

use bytemuck::{Pod, Zeroable};
use wgpu::util::DeviceExt;

use super::error::RenderResult;
use super::{shaders, GpuContext, ShaderLibrary};
use crate::sky::particles::ParticleInstance;
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
}
const _: () = assert!(std::mem::size_of::<SimUniform>() == 112);

/// The compute pipeline and its buffers for one camera emitter.
pub struct GpuParticleSim {
    pipeline: wgpu::ComputePipeline,
    params: wgpu::Buffer,
    counter: wgpu::Buffer,
    /// Live particles, written by the pass (vertex-buffer usable).
    pub particles: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    empty: wgpu::BindGroup,
    slots: u32,
}

impl GpuParticleSim {
    /// Builds the pipeline with room for `cap` particles.
    pub fn new(ctx: &GpuContext, library: &ShaderLibrary, cap: u32) -> RenderResult<Self> {
        let device = &ctx.device;
        let storage = |binding: u32| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer { ty: wgpu::BufferBindingType::Storage { read_only: false }, has_dynamic_offset: false, min_binding_size: None },
            count: None,
        };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("ParticleSim::layout"),
            entries: &[super::uniform_entry(0, wgpu::ShaderStages::COMPUTE), storage(1), storage(2)],
        });
        let empty_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some("ParticleSim::empty_layout"), entries: &[] });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("ParticleSim::pipeline_layout"),
            bind_group_layouts: &[Some(&empty_layout), Some(&layout)],
            immediate_size: 0,
        });
        let module = shaders::module(device, library, "particle_sim")?;
        let pipeline = shaders::compute_pipeline(device, &pipeline_layout, &module, "cs_main", "ParticleSim::pipeline")?;
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("ParticleSim::params"),
            size: std::mem::size_of::<SimUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let counter = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("ParticleSim::alive"),
            contents: &[0; 4],
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
        });
        let particles = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("ParticleSim::particles"),
            size: cap.max(1) as u64 * std::mem::size_of::<ParticleInstance>() as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("ParticleSim::bind_group"),
            layout: &layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: params.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: particles.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 2, resource: counter.as_entire_binding() },
            ],
        });
        let empty = device.create_bind_group(&wgpu::BindGroupDescriptor { label: Some("ParticleSim::empty"), layout: &empty_layout, entries: &[] });
        Ok(Self { pipeline, params, counter, particles, bind_group, empty, slots: 0 })
    }

    /// Writes the parameters of `e` at `time_s` (full emission).
    pub fn prepare(&mut self, queue: &wgpu::Queue, e: &Emitter, time_s: f64) {
        let max_life = (e.lifetime_s * (1.0 + e.lifetime_spread)) as f64;
        let slot_rate = (e.rate as f64).min(e.max_particles as f64 / max_life).max(1e-9);
        let first = ((time_s - max_life) * slot_rate).ceil();
        let last = (time_s * slot_rate).floor();
        self.slots = (last - first + 1.0).max(0.0) as u32;
        let axis = e.direction.try_normalize().unwrap_or(glam::Vec3::NEG_Y);
        let u = SimUniform {
            clock: [(time_s - first / slot_rate) as f32, (1.0 / slot_rate) as f32, (e.rate as f64 / slot_rate).min(1.0) as f32, self.slots as f32],
            life: [e.lifetime_s, e.lifetime_spread, e.speed, e.speed_spread],
            direction: [axis.x, axis.y, axis.z, e.spread_deg.to_radians()],
            shape: [e.gravity, e.box_m, e.size[0], e.size[1]],
            color0: e.color[0],
            color1: e.color[1],
            misc: [e.seed as u32, e.max_particles, first as i64 as u32, e.streak_s.to_bits()],
        };
        queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&u));
        queue.write_buffer(&self.counter, 0, &[0; 4]);
    }

    /// Records the evaluation.
    pub fn record(&self, encoder: &mut wgpu::CommandEncoder) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("ParticleSim::pass"), timestamp_writes: None });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.empty, &[]);
        pass.set_bind_group(1, &self.bind_group, &[]);
        pass.dispatch_workgroups(self.slots.div_ceil(64).max(1), 1, 1);
    }

    /// Particles the last evaluation found alive (reads the counter back; blocks).
    pub fn alive(&self, ctx: &GpuContext) -> RenderResult<u32> {
        let bytes = super::headless::read_buffer(ctx, &self.counter, 4)?;
        Ok(u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]))
    }
}
