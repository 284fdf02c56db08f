//! The scene's depth, owned by the renderer: the main scene writes it, and later passes (and the
//! next frame's compute phase) can sample it (`scene_distance_m` in shaders/globals.wgsl turns a
//! stored depth into metres along the view ray).

/// The depth target, sized like the frame's colour target.
pub struct SceneDepth {
    /// The texture ([`crate::render::gpu::parts::DEPTH_FORMAT`]): a render attachment that
    /// shaders can sample (`texture_depth_2d`) and tests can read back.
    pub texture: wgpu::Texture,
    /// Its view.
    pub view: wgpu::TextureView,
    /// Its size, pixels.
    pub size: (u32, u32),
    /// Changes whenever the target is recreated (passes that bind it rebuild their bind groups).
    pub generation: u64,
    /// It holds the clear value (1) everywhere: cleared by the renderer, and no scene drawn into
    /// it since ([`crate::render::frame::options::Skips::covered_clears`]). A new one holds
    /// nothing defined.
    pub untouched: bool,
}

impl SceneDepth {
    /// A depth target of `size` (at least 1 x 1).
    pub fn new(device: &wgpu::Device, (width, height): (u32, u32), generation: u64) -> Self {
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("SkyRenderer::depth"),
            size: wgpu::Extent3d { width: width.max(1), height: height.max(1), depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: crate::render::gpu::parts::DEPTH_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let view = texture.create_view(&wgpu::TextureViewDescriptor { label: Some("SkyRenderer::depth_view"), ..Default::default() });
        Self { texture, view, size: (width, height), generation, untouched: false }
    }
}
