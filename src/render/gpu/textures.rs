//! Texture uploads shared by passes, keyed by source file and content, plus the common samplers.
//! A sky reload builds a successor cache that takes over every texture whose file did not change.

use std::collections::HashMap;
use std::hash::{Hash, Hasher};

use crate::sky::resolved::TextureImage;

#[derive(Clone)]
struct Entry {
    content: u64,
    view: wgpu::TextureView,
}

/// Uploaded textures and samplers.
pub struct TextureCache {
    views: HashMap<String, Entry>,
    /// The cache this one succeeds: textures with unchanged content are taken from it.
    previous: HashMap<String, Entry>,
    /// Textures uploaded since this cache was made.
    pub uploaded: u32,
    /// Textures taken over from the previous cache unchanged.
    pub reused: u32,
    /// 1x1 opaque white, bound to unused stages.
    pub white: wgpu::TextureView,
    /// Linear, repeating.
    pub repeat: wgpu::Sampler,
    /// Linear, clamped to edge.
    pub clamp: wgpu::Sampler,
    /// As `repeat`, level 0 only: for stages no pixel minifies (same texels; on lavapipe a
    /// sampler whose level of detail is pinned skips computing it).
    pub repeat_level0: wgpu::Sampler,
    /// As `clamp`, level 0 only.
    pub clamp_level0: wgpu::Sampler,
}

/// Texture format of every sky texture: colours stay display-encoded, like the 2005 pipeline.
pub const TEXTURE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

/// A 1 x 1 texture (zero-filled by wgpu) for a binding the shader never samples in that draw.
pub fn unused_view(device: &wgpu::Device, label: &str) -> wgpu::TextureView {
    device
        .create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d { width: 1, height: 1, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: TEXTURE_FORMAT,
            usage: wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        })
        .create_view(&Default::default())
}

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

/// Creates a texture with its full mip chain from RGBA8 data (each level a filtered half of the one
/// above, computed on the CPU at load): tiled and minified textures (the skydome's stars, ten times
/// over the dome) stop shimmering. Samplers take the nearest level, bilinearly: trilinear cost 5%
/// more on lavapipe for no visible gain here (docs/architecture.md).
pub fn upload_mipmapped(device: &wgpu::Device, queue: &wgpu::Queue, label: &str, width: u32, height: u32, rgba8: &[u8]) -> wgpu::Texture {
    let levels = 32 - width.max(height).max(1).leading_zeros();
    let texture = device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
        mip_level_count: levels,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: TEXTURE_FORMAT,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    let Some(mut level) = image::RgbaImage::from_raw(width, height, rgba8.to_vec()) else { return texture };
    for mip in 0..levels {
        let (w, h) = level.dimensions();
        queue.write_texture(
            wgpu::TexelCopyTextureInfo { texture: &texture, mip_level: mip, origin: wgpu::Origin3d::ZERO, aspect: wgpu::TextureAspect::All },
            level.as_raw(),
            wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(w * 4), rows_per_image: Some(h) },
            wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
        );
        if mip + 1 < levels {
            level = image::imageops::resize(&level, (w / 2).max(1), (h / 2).max(1), image::imageops::FilterType::Triangle);
        }
    }
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

fn sampler(device: &wgpu::Device, label: &str, mode: wgpu::AddressMode, lod_max_clamp: f32) -> wgpu::Sampler {
    device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some(label),
        address_mode_u: mode,
        address_mode_v: mode,
        address_mode_w: mode,
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        mipmap_filter: wgpu::MipmapFilterMode::Nearest,
        lod_max_clamp,
        ..Default::default()
    })
}

impl TextureCache {
    /// Creates the cache with its white texture and samplers.
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue) -> Self {
        let white = upload(device, queue, "TextureCache::white", 1, 1, &[255; 4]).create_view(&Default::default());
        Self {
            views: HashMap::new(),
            previous: HashMap::new(),
            uploaded: 0,
            reused: 0,
            white,
            repeat: sampler(device, "TextureCache::repeat", wgpu::AddressMode::Repeat, 32.0),
            clamp: sampler(device, "TextureCache::clamp", wgpu::AddressMode::ClampToEdge, 32.0),
            repeat_level0: sampler(device, "TextureCache::repeat_level0", wgpu::AddressMode::Repeat, 0.0),
            clamp_level0: sampler(device, "TextureCache::clamp_level0", wgpu::AddressMode::ClampToEdge, 0.0),
        }
    }

    /// An empty cache for the next sky that can take over this one's textures; this one stays
    /// valid until the next sky is committed.
    pub fn successor(&self) -> Self {
        Self {
            views: HashMap::new(),
            previous: self.views.clone(),
            uploaded: 0,
            reused: 0,
            white: self.white.clone(),
            repeat: self.repeat.clone(),
            clamp: self.clamp.clone(),
            repeat_level0: self.repeat_level0.clone(),
            clamp_level0: self.clamp_level0.clone(),
        }
    }

    /// Textures held.
    pub fn len(&self) -> usize {
        self.views.len()
    }

    /// Whether no texture is held.
    pub fn is_empty(&self) -> bool {
        self.views.is_empty()
    }

    /// The view of an image: the one already uploaded for the same file and content, else a new upload.
    pub fn get(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, image: &TextureImage) -> wgpu::TextureView {
        self.view_of(&image.key, content_hash(image), |label| upload_mipmapped(device, queue, label, image.width, image.height, &image.rgba8))
    }

    /// The view of a texture derived from others (`content` identifies what it is made of): the
    /// one already uploaded for the same key and content, else `make`'s, uploaded with its mips.
    /// Deriving costs CPU time at load; a reload that keeps the sources keeps the result.
    pub fn derived(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, key: &str, content: u64, make: impl FnOnce() -> TextureImage) -> wgpu::TextureView {
        self.view_of(key, content, |label| {
            let image = make();
            upload_mipmapped(device, queue, label, image.width, image.height, &image.rgba8)
        })
    }

    /// The view held for `key` with `content`, this sky's or taken over from the previous one;
    /// else `upload`'s texture (given its label).
    fn view_of(&mut self, key: &str, content: u64, upload: impl FnOnce(&str) -> wgpu::Texture) -> wgpu::TextureView {
        if let Some(e) = self.views.get(key).filter(|e| e.content == content) {
            return e.view.clone();
        }
        let entry = match self.previous.remove(key).filter(|e| e.content == content) {
            Some(e) => {
                self.reused += 1;
                e
            }
            None => {
                self.uploaded += 1;
                Entry { content, view: upload(&format!("texture {key}")).create_view(&Default::default()) }
            }
        };
        self.views.insert(key.to_string(), entry.clone());
        entry.view
    }

    /// Drops the textures of the previous sky that the new one did not take over.
    pub fn forget_previous(&mut self) {
        self.previous.clear();
    }
}

/// What identifies an image's content in the cache.
pub fn content_hash(image: &TextureImage) -> u64 {
    let mut h = std::collections::hash_map::DefaultHasher::new();
    (image.width, image.height).hash(&mut h);
    image.rgba8.hash(&mut h);
    h.finish()
}
