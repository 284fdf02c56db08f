//! Offscreen rendering: a colour + depth target and readback to an image.

use anyhow::{anyhow, Context as _};

use super::renderer::{RenderOptions, SkyRenderer};
use super::{Camera, GpuContext, DEPTH_FORMAT, OFFSCREEN_FORMAT};
use crate::sky::{FrameInput, Sky};

/// An offscreen colour and depth target.
pub struct Offscreen {
    /// Colour texture (RGBA8).
    pub color: wgpu::Texture,
    /// Its view.
    pub color_view: wgpu::TextureView,
    /// Depth view.
    pub depth_view: wgpu::TextureView,
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
}

/// Creates a depth texture view for a target size.
pub fn depth_view(device: &wgpu::Device, width: u32, height: u32) -> wgpu::TextureView {
    device
        .create_texture(&wgpu::TextureDescriptor {
            label: Some("SkyRenderer::depth"),
            size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: DEPTH_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            view_formats: &[],
        })
        .create_view(&Default::default())
}

impl Offscreen {
    /// Creates a target.
    pub fn new(device: &wgpu::Device, width: u32, height: u32) -> Self {
        let color = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("Offscreen::color"),
            size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: OFFSCREEN_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let color_view = color.create_view(&Default::default());
        Self { color, color_view, depth_view: depth_view(device, width, height), width, height }
    }

    /// Copies the colour target back to the CPU (blocks until the GPU is done).
    pub fn read(&self, ctx: &GpuContext) -> anyhow::Result<image::RgbaImage> {
        let row = (self.width * 4).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        let buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("Offscreen::readback"),
            size: (row * self.height) as u64,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder = ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("Offscreen::readback_encoder") });
        encoder.copy_texture_to_buffer(
            self.color.as_image_copy(),
            wgpu::TexelCopyBufferInfo { buffer: &buffer, layout: wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(row), rows_per_image: Some(self.height) } },
            wgpu::Extent3d { width: self.width, height: self.height, depth_or_array_layers: 1 },
        );
        ctx.queue.submit([encoder.finish()]);
        let (tx, rx) = std::sync::mpsc::channel();
        buffer.map_async(wgpu::MapMode::Read, .., move |r| {
            let _ = tx.send(r);
        });
        ctx.wait_idle()?;
        rx.recv().context("readback callback never ran")?.map_err(|e| anyhow!("mapping the readback buffer: {e}"))?;
        let mut pixels = Vec::with_capacity((self.width * self.height * 4) as usize);
        {
            let view = buffer.get_mapped_range(..).map_err(|e| anyhow!("{e}"))?;
            for y in 0..self.height as usize {
                let start = y * row as usize;
                pixels.extend_from_slice(&view[start..start + self.width as usize * 4]);
            }
        }
        buffer.unmap();
        image::RgbaImage::from_raw(self.width, self.height, pixels).ok_or_else(|| anyhow!("readback size mismatch"))
    }
}

/// Most extra frames a still waits for the glare's first occlusion result.
const STILL_WARMUP_FRAMES: usize = 6;

/// A headless renderer with its target: renders frames of a sky to images.
pub struct Headless {
    /// GPU context.
    pub ctx: GpuContext,
    /// Renderer (offscreen format).
    pub renderer: SkyRenderer,
    /// Target.
    pub target: Offscreen,
}

impl Headless {
    /// Creates a context, a renderer with embedded shaders and a target of the given size.
    pub fn new(ctx: GpuContext, width: u32, height: u32) -> anyhow::Result<Self> {
        let renderer = SkyRenderer::new(&ctx, OFFSCREEN_FORMAT, super::ShaderLibrary::embedded()).map_err(|e| anyhow!(e))?;
        let target = Offscreen::new(&ctx.device, width, height);
        Ok(Self { ctx, renderer, target })
    }

    /// Uploads a sky.
    pub fn set_sky(&mut self, sky: &Sky) -> anyhow::Result<()> {
        self.renderer.set_sky(&self.ctx, sky).map_err(|e| anyhow!(e))
    }

    /// Renders one frame without reading it back; returns once it is submitted.
    pub fn frame(&mut self, sky: &Sky, input: &FrameInput, camera: &Camera, options: &RenderOptions, dt_s: f32) {
        let frame = sky.evaluate(input);
        let mut encoder = self.ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("Headless::frame") });
        let size = (self.target.width, self.target.height);
        self.renderer.render(&self.ctx, &mut encoder, &self.target.color_view, &self.target.depth_view, size, sky, &frame, camera, options, dt_s, input.game_hours);
        self.ctx.queue.submit([encoder.finish()]);
        self.renderer.after_submit();
    }

    /// Renders a still and reads it back. With glare, frames are rendered until an occlusion
    /// result has arrived, each counting as one persistence period, so the glare shows at its
    /// settled intensity as it would after the viewer looked for a while.
    pub fn render(&mut self, sky: &Sky, input: &FrameInput, camera: &Camera, options: &RenderOptions) -> anyhow::Result<image::RgbaImage> {
        let settle = sky.glare.as_ref().filter(|_| options.glare).map_or(0.0, |g| g.persistence_s.max(1e-3));
        self.frame(sky, input, camera, options, settle);
        if settle > 0.0 {
            for _ in 0..STILL_WARMUP_FRAMES {
                let before = self.renderer.glare_state().map(|g| g.frames_without_result);
                self.ctx.wait_idle()?;
                self.frame(sky, input, camera, options, settle);
                let after = self.renderer.glare_state().map(|g| g.frames_without_result);
                if before.is_some() && before == after {
                    break;
                }
            }
        }
        self.target.read(&self.ctx)
    }
}
