//! Histories: textures a pass keeps from one frame to the next (a temporal accumulation, a
//! reprojected march), owned by the renderer apart from the plan's run buffers, which are remade
//! from each frame's plan. A pass asks for its histories every frame ([`crate::render::frame::pass::Pass::histories`]);
//! each is a pair of textures, one written this frame and the other holding the last frame's,
//! swapped after every frame.

/// A history a pass asks for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct HistoryRequest {
    /// Name, unique within the pass (GPU labels).
    pub name: &'static str,
    /// Texel format (it must allow storage writes and sampling).
    pub format: wgpu::TextureFormat,
    /// Frame pixels per history texel, across and down (1: full resolution).
    pub divisor: u32,
}

impl HistoryRequest {
    /// Texels of the history for a frame of `size` pixels (at least 1 x 1).
    pub fn texels(&self, (width, height): (u32, u32)) -> (u32, u32) {
        let d = self.divisor.max(1);
        (width.div_ceil(d).max(1), height.div_ceil(d).max(1))
    }
}

/// The two textures of a history.
pub struct History {
    request: HistoryRequest,
    textures: [wgpu::Texture; 2],
    views: [wgpu::TextureView; 2],
    /// Texels.
    size: (u32, u32),
    /// Which of the two this frame writes.
    current: usize,
    /// Frames written since the pair was made (0: the previous texture holds nothing).
    frames: u64,
}

impl History {
    fn new(device: &wgpu::Device, pass: &str, request: HistoryRequest, size: (u32, u32)) -> Self {
        let make = |k: usize| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(&format!("History::{pass}::{}::{k}", request.name)),
                size: wgpu::Extent3d { width: size.0, height: size.1, depth_or_array_layers: 1 },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: request.format,
                usage: wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            })
        };
        let textures = [make(0), make(1)];
        let views = [textures[0].create_view(&Default::default()), textures[1].create_view(&Default::default())];
        Self { request, textures, views, size, current: 0, frames: 0 }
    }

    /// The view this frame writes.
    pub fn write_view(&self) -> &wgpu::TextureView {
        &self.views[self.current]
    }

    /// The view holding the last frame's (meaningful once [`Self::frames`] is above 0).
    pub fn read_view(&self) -> &wgpu::TextureView {
        &self.views[1 - self.current]
    }

    /// The texture this frame writes.
    pub fn write_texture(&self) -> &wgpu::Texture {
        &self.textures[self.current]
    }

    /// The texture holding the last frame's (tests read it back after a frame).
    pub fn read_texture(&self) -> &wgpu::Texture {
        &self.textures[1 - self.current]
    }

    /// Texels across and down.
    pub fn size(&self) -> (u32, u32) {
        self.size
    }

    /// Frames written before this one since the history was made: 0 on its first frame, when
    /// the texture to read holds nothing.
    pub fn frames(&self) -> u64 {
        self.frames
    }

    /// Which of the two textures this frame writes (0 or 1): a pass keeps a bind group for each.
    pub fn parity(&self) -> usize {
        self.current
    }
}

/// Every pass's histories, by pass name ([`crate::render::frame::pass::Pass::name`]) and name.
#[derive(Default)]
pub struct Histories {
    entries: Vec<(&'static str, History)>,
}

impl Histories {
    /// Makes the histories `requests` of pass `pass` ask for at a frame of `frame` pixels,
    /// remaking those whose format, divisor or size changed and dropping the pass's others.
    pub fn ensure(&mut self, device: &wgpu::Device, pass: &'static str, requests: &[HistoryRequest], frame: (u32, u32)) {
        self.entries.retain(|(p, h)| *p != pass || requests.iter().any(|r| *r == h.request && r.texels(frame) == h.size));
        for request in requests {
            if !self.entries.iter().any(|(p, h)| *p == pass && h.request == *request) {
                self.entries.push((pass, History::new(device, pass, *request, request.texels(frame))));
            }
        }
    }

    /// Pass `pass`'s history `name`, if it asked for one this frame.
    pub fn get(&self, pass: &str, name: &str) -> Option<&History> {
        self.entries.iter().find(|(p, h)| *p == pass && h.request.name == name).map(|(_, h)| h)
    }

    /// After a frame: what each history wrote becomes the one to read.
    pub fn swap(&mut self) {
        for (_, h) in &mut self.entries {
            h.current = 1 - h.current;
            h.frames += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_history_covers_the_frame_at_its_divisor() {
        let r = HistoryRequest { name: "clouds", format: wgpu::TextureFormat::Rgba16Float, divisor: 4 };
        assert_eq!(r.texels((1280, 720)), (320, 180));
        assert_eq!(r.texels((1281, 3)), (321, 1), "partial texels at the edges are kept");
        assert_eq!(HistoryRequest { divisor: 0, ..r }.texels((10, 10)), (10, 10), "divisor 0 reads as 1");
    }
}
