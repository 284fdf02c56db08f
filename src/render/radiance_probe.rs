//! Evaluates a GPU sky model for a list of radiance cases and reads the answers back: the
//! interface `skytune radiance`, the model tests and the benchmarks use. A compute pipeline of
//! its own (`shaders/radiance_probe.wgsl`), outside the frame's phases.

use wgpu::util::DeviceExt;

use super::error::{RenderError, RenderResult};
use super::sky_model::{AtmosphereUniform, SingleUniform};
use super::{shaders, GpuContext, ShaderLibrary};
use crate::atmosphere::reference::Case;
use crate::atmosphere::{Atmosphere, SingleSettings};

/// The probe's pipeline.
pub struct RadianceProbe {
    layout: wgpu::BindGroupLayout,
    single: wgpu::ComputePipeline,
}

fn buffer_entry(binding: u32, ty: wgpu::BufferBindingType) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer { ty, has_dynamic_offset: false, min_binding_size: None },
        count: None,
    }
}

impl RadianceProbe {
    /// Builds the pipeline from `library`.
    pub fn new(ctx: &GpuContext, library: &ShaderLibrary) -> RenderResult<Self> {
        let device = &ctx.device;
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("RadianceProbe::layout"),
            entries: &[
                buffer_entry(0, wgpu::BufferBindingType::Uniform),
                buffer_entry(1, wgpu::BufferBindingType::Uniform),
                buffer_entry(2, wgpu::BufferBindingType::Storage { read_only: true }),
                buffer_entry(3, wgpu::BufferBindingType::Storage { read_only: false }),
            ],
        });
        // Group 0 (the frame's globals) is declared by every module but unused here.
        let empty = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some("RadianceProbe::empty_layout"), entries: &[] });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("RadianceProbe::pipeline_layout"),
            bind_group_layouts: &[Some(&empty), Some(&layout)],
            immediate_size: 0,
        });
        let module = shaders::module(device, library, "radiance_probe")?;
        let single = shaders::validated(device, "RadianceProbe::single", || {
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some("RadianceProbe::single"),
                layout: Some(&pipeline_layout),
                module: &module,
                entry_point: Some("cs_single"),
                compilation_options: Default::default(),
                cache: None,
            })
        })?;
        Ok(Self { layout, single })
    }

    /// Radiance of the `single` model for every case, sr^-1 per unit of solar irradiance
    /// (blocks until the GPU is done).
    pub fn single(&self, ctx: &GpuContext, atmosphere: &Atmosphere, settings: &SingleSettings, cases: &[Case]) -> RenderResult<Vec<[f32; 3]>> {
        if cases.is_empty() {
            return Ok(Vec::new());
        }
        let device = &ctx.device;
        let init = |label: &str, contents: &[u8], usage| device.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some(label), contents, usage });
        let atm = init("RadianceProbe::atmosphere", bytemuck::bytes_of(&AtmosphereUniform::from(atmosphere)), wgpu::BufferUsages::UNIFORM);
        let set = init("RadianceProbe::settings", bytemuck::bytes_of(&SingleUniform::from(settings)), wgpu::BufferUsages::UNIFORM);
        let data: Vec<[f32; 4]> = cases.iter().map(|c| [c.camera_km as f32, c.sun_elev_deg as f32, c.view_elev_deg as f32, c.rel_azimuth_deg as f32]).collect();
        let input = init("RadianceProbe::cases", bytemuck::cast_slice(&data), wgpu::BufferUsages::STORAGE);
        let size = (cases.len() * 16) as u64;
        let output = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("RadianceProbe::radiance"),
            size,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let readback = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("RadianceProbe::readback"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("RadianceProbe::bind_group"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: atm.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: set.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 2, resource: input.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 3, resource: output.as_entire_binding() },
            ],
        });
        let empty = device.create_bind_group(&wgpu::BindGroupDescriptor { label: Some("RadianceProbe::empty"), layout: &self.single.get_bind_group_layout(0), entries: &[] });
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("RadianceProbe::encoder") });
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("RadianceProbe::pass"), timestamp_writes: None });
            pass.set_pipeline(&self.single);
            pass.set_bind_group(0, &empty, &[]);
            pass.set_bind_group(1, &bind_group, &[]);
            pass.dispatch_workgroups((cases.len() as u32).div_ceil(64), 1, 1);
        }
        encoder.copy_buffer_to_buffer(&output, 0, &readback, 0, size);
        ctx.queue.submit([encoder.finish()]);
        let (tx, rx) = std::sync::mpsc::channel();
        readback.map_async(wgpu::MapMode::Read, .., move |r| {
            let _ = tx.send(r);
        });
        ctx.wait_idle()?;
        rx.recv().map_err(|_| RenderError::Readback("the readback callback never ran".into()))?.map_err(|e| RenderError::Readback(e.to_string()))?;
        let out = {
            let view = readback.get_mapped_range(..).map_err(|e| RenderError::Readback(e.to_string()))?;
            bytemuck::cast_slice::<u8, [f32; 4]>(&view).iter().map(|v| [v[0], v[1], v[2]]).collect()
        };
        readback.unmap();
        Ok(out)
    }
}
