//! Reading GPU textures and buffers back to the CPU, waited for: screenshots, tests, and the
//! passes that check their own results.

use crate::render::gpu::context::GpuContext;
use crate::render::gpu::error::{RenderError, RenderResult};

/// Copies a `width` x `height` texture of `texel_bytes` per texel back to the CPU, rows packed
/// (blocks until the GPU is done).
pub fn read_texture(ctx: &GpuContext, texture: &wgpu::Texture, width: u32, height: u32, texel_bytes: u32) -> RenderResult<Vec<u8>> {
    let row = (width * texel_bytes).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let buffer = readback_buffer(ctx, "Offscreen::readback", (row * height) as u64);
    let mut encoder = ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("Offscreen::readback_encoder") });
    encoder.copy_texture_to_buffer(
        texture.as_image_copy(),
        wgpu::TexelCopyBufferInfo { buffer: &buffer, layout: wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(row), rows_per_image: Some(height) } },
        wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
    );
    let bytes = finish_readback(ctx, encoder, &buffer)?;
    let line = (width * texel_bytes) as usize;
    Ok((0..height as usize).flat_map(|y| bytes[y * row as usize..y * row as usize + line].iter().copied()).collect())
}

/// Copies the first `size` bytes of a buffer (with COPY_SRC usage) back to the CPU.
pub fn read_buffer(ctx: &GpuContext, source: &wgpu::Buffer, size: u64) -> RenderResult<Vec<u8>> {
    let buffer = readback_buffer(ctx, "Headless::buffer_readback", size);
    let mut encoder = ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("Headless::buffer_readback_encoder") });
    encoder.copy_buffer_to_buffer(source, 0, &buffer, 0, size);
    finish_readback(ctx, encoder, &buffer)
}

fn readback_buffer(ctx: &GpuContext, label: &str, size: u64) -> wgpu::Buffer {
    ctx.device.create_buffer(&wgpu::BufferDescriptor { label: Some(label), size, usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST, mapped_at_creation: false })
}

fn finish_readback(ctx: &GpuContext, encoder: wgpu::CommandEncoder, buffer: &wgpu::Buffer) -> RenderResult<Vec<u8>> {
    ctx.queue.submit([encoder.finish()]);
    let (tx, rx) = std::sync::mpsc::channel();
    buffer.map_async(wgpu::MapMode::Read, .., move |r| {
        let _ = tx.send(r);
    });
    ctx.wait_idle()?;
    rx.recv().map_err(|_| RenderError::Readback("the readback callback never ran".into()))?.map_err(|e| RenderError::Readback(e.to_string()))?;
    let bytes = buffer.get_mapped_range(..).map_err(|e| RenderError::Readback(e.to_string()))?.to_vec();
    buffer.unmap();
    Ok(bytes)
}
