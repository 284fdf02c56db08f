//! Texture uploads shared by passes, keyed by source file, plus the common samplers.

use std::collections::HashMap;

use crate::sky::resolved::TextureImage;

/// Uploaded textures and samplers.
pub struct TextureCache {
    views: HashMap<String, wgpu::TextureView>,
    /// 1x1 opaque white, bound to unused stages.
    pub white: wgpu::TextureView,
    /// Linear, repeating.
    pub repeat: wgpu::Sampler,
    /// Linear, clamped to edge.
    pub clamp: wgpu::Sampler,
}

/// Texture format of every sky texture: colours stay display-encoded, like the 2005 pipeline.
pub const TEXTURE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

/// Creates a texture from RGBA8 data.
pub fn upload(device: &wgpu::Device, queue: &wgpu::Queue, label: &str, width: u32, height: u32, rgba8: &[u8]) -> wgpu::Texture {
    let texture = device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: TEXTURE_FORMAT,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    write(queue, &texture, width, height, rgba8);
    texture
}

/// Overwrites a whole texture with RGBA8 data.
pub fn write(queue: &wgpu::Queue, texture: &wgpu::Texture, width: u32, height: u32, rgba8: &[u8]) {
    queue.write_texture(
        wgpu::TexelCopyTextureInfo { texture, mip_level: 0, origin: wgpu::Origin3d::ZERO, aspect: wgpu::TextureAspect::All },
        rgba8,
        wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(width * 4), rows_per_image: Some(height) },
        wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
    );
}

fn sampler(device: &wgpu::Device, label: &str, mode: wgpu::AddressMode) -> wgpu::Sampler {
    device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some(label),
        address_mode_u: mode,
        address_mode_v: mode,
        address_mode_w: mode,
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        ..Default::default()
    })
}

impl TextureCache {
    /// Creates the cache with its white texture and samplers.
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue) -> Self {
        let white = upload(device, queue, "TextureCache::white", 1, 1, &[255; 4]).create_view(&Default::default());
        Self {
            views: HashMap::new(),
            white,
            repeat: sampler(device, "TextureCache::repeat", wgpu::AddressMode::Repeat),
            clamp: sampler(device, "TextureCache::clamp", wgpu::AddressMode::ClampToEdge),
        }
    }

    /// The view of an image, uploading it on first use.
    pub fn get(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, image: &TextureImage) -> wgpu::TextureView {
        self.views
            .entry(image.key.clone())
            .or_insert_with(|| {
                upload(device, queue, &format!("texture {}", image.key), image.width, image.height, &image.rgba8).create_view(&Default::default())
            })
            .clone()
    }
}
