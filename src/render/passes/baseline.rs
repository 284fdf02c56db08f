//! The fill-rate floor `skytune bench frame` compares the sky with: a render pass that clears the
//! target and draws one full-screen triangle sampling one 128 x 128 texture (`shaders/baseline.wgsl`).
//! Not part of the sky renderer's phases: it stands beside it, in the same target format.

use crate::render::gpu::error::RenderResult;
use crate::render::gpu::shaders::{self, ShaderLibrary};

/// Side of the floor's texture, texels.
pub const FLOOR_TEXTURE_SIDE: u32 = 128;

/// The floor pass: pipeline and bind group, built once.
pub struct Baseline {
    pipeline: wgpu::RenderPipeline,
    bind_group: wgpu::BindGroup,
}

impl Baseline {
    /// Builds the pipeline for `format` and uploads a noise texture.
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue, library: &ShaderLibrary, format: wgpu::TextureFormat) -> RenderResult<Self> {
        let side = FLOOR_TEXTURE_SIDE;
        let mut rng = fastrand::Rng::with_seed(3);
        let texels: Vec<u8> = (0..side * side * 4).map(|_| rng.u8(..)).collect();
        let texture = crate::render::gpu::textures::upload(device, queue, "Baseline::texture", side, side, &texels);
        let view = texture.create_view(&Default::default());
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("Baseline::sampler"),
            address_mode_u: wgpu::AddressMode::Repeat,
            address_mode_v: wgpu::AddressMode::Repeat,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("Baseline::layout"),
            entries: &[crate::render::gpu::parts::texture_entry(0), crate::render::gpu::parts::sampler_entry(1)],
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("Baseline::bind_group"),
            layout: &layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&view) },
                wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::Sampler(&sampler) },
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("Baseline::pipeline_layout"),
            bind_group_layouts: &[None, Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = shaders::fullscreen_pipeline(device, library, "baseline", &pipeline_layout, "Baseline::pipeline", format)?;
        Ok(Self { pipeline, bind_group })
    }

    /// Records the floor frame into `target`: clear, one full-screen triangle.
    pub fn record(&self, encoder: &mut wgpu::CommandEncoder, target: &wgpu::TextureView) {
        let mut rpass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("Baseline::pass"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: target,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations { load: wgpu::LoadOp::Clear(wgpu::Color::BLACK), store: wgpu::StoreOp::Store },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        rpass.set_pipeline(&self.pipeline);
        rpass.set_bind_group(1, &self.bind_group, &[]);
        rpass.draw(0..3, 0..1);
    }
}
