//! Offscreen rendering: a colour target (the renderer owns the depth), readback to an image, and [`Headless`], the one
//! path of headless renders, stills and the app's screenshots and contact sheets.

use crate::render::frame::camera::Camera;
use crate::render::frame::options::RenderOptions;
use crate::render::frame::renderer::{RenderTarget, SkyRenderer};
use crate::render::gpu::context::GpuContext;
use crate::render::gpu::error::{RenderError, RenderResult};
use crate::render::gpu::parts::OFFSCREEN_FORMAT;
use crate::render::gpu::shaders::ShaderLibrary;
use crate::sky::{FrameInput, Sky};

pub use crate::render::gpu::readback::{read_buffer, read_texture};

/// An offscreen colour target.
pub struct Offscreen {
    /// Colour texture (RGBA8).
    pub color: wgpu::Texture,
    /// Its view.
    pub color_view: wgpu::TextureView,
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
}

impl Offscreen {
    /// Creates a target.
    pub fn new(device: &wgpu::Device, width: u32, height: u32) -> Self {
        Self::with_format(device, width, height, OFFSCREEN_FORMAT, "Offscreen::color")
    }

    /// Creates a target of another colour format (the window's sky view, in the surface's).
    pub fn with_format(device: &wgpu::Device, width: u32, height: u32, format: wgpu::TextureFormat, label: &str) -> Self {
        let color = device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let color_view = color.create_view(&Default::default());
        Self { color, color_view, width, height }
    }

    /// Copies the colour target back to the CPU (blocks until the GPU is done).
    pub fn read(&self, ctx: &GpuContext) -> RenderResult<image::RgbaImage> {
        let pixels = read_texture(ctx, &self.color, self.width, self.height, 4)?;
        image::RgbaImage::from_raw(self.width, self.height, pixels).ok_or_else(|| RenderError::Readback("size mismatch".into()))
    }

    /// The target as the renderer draws into it.
    pub fn target(&self) -> RenderTarget<'_> {
        RenderTarget { color: &self.color_view, size: (self.width, self.height) }
    }
}

/// Longest a still waits for a pass's background work (the `cells` model's solve).
const STILL_BUSY_TIMEOUT: std::time::Duration = std::time::Duration::from_secs(300);

/// A renderer with its own offscreen target: renders frames of a sky to images. The context may
/// be shared with a window (it is a set of shared handles).
pub struct Headless {
    /// GPU context.
    pub ctx: GpuContext,
    /// Renderer (offscreen format).
    pub renderer: SkyRenderer,
    /// Target.
    pub target: Offscreen,
    /// Frames rendered so far.
    frames: u64,
}

impl Headless {
    /// Creates a renderer with embedded shaders and a target of the given size.
    pub fn new(ctx: GpuContext, width: u32, height: u32) -> RenderResult<Self> {
        Self::with_library(ctx, ShaderLibrary::embedded(), width, height)
    }

    /// Creates a renderer with shaders from `library` and a target of the given size.
    pub fn with_library(ctx: GpuContext, library: ShaderLibrary, width: u32, height: u32) -> RenderResult<Self> {
        let renderer = SkyRenderer::new(&ctx, OFFSCREEN_FORMAT, library)?;
        let target = Offscreen::new(&ctx.device, width, height);
        Ok(Self { ctx, renderer, target, frames: 0 })
    }

    /// Makes the target `width` x `height` (no-op when it already is).
    pub fn resize(&mut self, width: u32, height: u32) {
        if (self.target.width, self.target.height) != (width, height) {
            self.target = Offscreen::new(&self.ctx.device, width, height);
        }
    }

    /// Uploads a sky.
    pub fn set_sky(&mut self, sky: &Sky) -> RenderResult<()> {
        self.renderer.set_sky(&self.ctx, sky)
    }

    /// Renders one frame `dt_s` seconds after the previous one, without reading it back; returns
    /// once it is submitted.
    pub fn frame(&mut self, sky: &Sky, input: &FrameInput, camera: &Camera, options: &RenderOptions, dt_s: f32) {
        self.frames += 1;
        let input = FrameInput { dt_s, frame: self.frames, ..input.clone() };
        let frame = sky.evaluate(&input);
        let mut encoder = self.ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("Headless::frame") });
        self.renderer.render(&self.ctx, &mut encoder, &self.target.target(), &frame, camera, options);
        self.ctx.queue.submit([encoder.finish()]);
        self.renderer.after_submit();
    }

    /// Renders a still and reads it back. Passes that need history (the glare) settle first:
    /// frames are rendered with a fixed step, each waiting for the GPU, until every pass says its
    /// steady state shows, so the same input always gives the same picture.
    pub fn render(&mut self, sky: &Sky, input: &FrameInput, camera: &Camera, options: &RenderOptions) -> RenderResult<image::RgbaImage> {
        let dt = self.renderer.settle_dt_s(options).unwrap_or(0.0);
        let settle_frames = self.renderer.settle_frames(options);
        self.frame(sky, input, camera, options, dt);
        let started = std::time::Instant::now();
        let mut extra = 0;
        while !self.renderer.settled() {
            let busy = self.renderer.busy();
            if (!busy && extra >= settle_frames) || started.elapsed() > STILL_BUSY_TIMEOUT {
                break;
            }
            self.ctx.wait_idle()?;
            if busy {
                std::thread::sleep(std::time::Duration::from_millis(10));
            } else {
                extra += 1;
            }
            self.frame(sky, input, camera, options, dt);
        }
        self.target.read(&self.ctx)
    }

    /// Like [`Self::render`], for an interactive caller that must not block: while a pass has
    /// background work in flight (a CPU sky model), renders one frame and returns `None` (call
    /// again later); otherwise settles and reads the still back.
    pub fn try_render(&mut self, sky: &Sky, input: &FrameInput, camera: &Camera, options: &RenderOptions) -> RenderResult<Option<image::RgbaImage>> {
        let dt = self.renderer.settle_dt_s(options).unwrap_or(0.0);
        self.frame(sky, input, camera, options, dt);
        for _ in 0..self.renderer.settle_frames(options) {
            if self.renderer.busy() {
                return Ok(None);
            }
            if self.renderer.settled() {
                break;
            }
            self.ctx.wait_idle()?;
            self.frame(sky, input, camera, options, dt);
        }
        if self.renderer.busy() {
            return Ok(None);
        }
        self.target.read(&self.ctx).map(Some)
    }
}
