//! Tone-map pass (display phase): reads the frame's HDR target and writes display values through
//! the sky model's tone mapper and sRGB encoding. Only frames of a physical sky model draw into
//! the HDR target; the NeL bitmap path draws display values directly and this pass is idle.

use bytemuck::{Pod, Zeroable};

use crate::render::frame::pass::{DrawItem, FrameContext, Pass, PassBuild, Phase, Pipelines, Placement, Target};
use crate::render::gpu::error::RenderResult;
use crate::render::gpu::shaders;
use crate::sky::resolved::ToneMapper;

/// Keep in sync with `ToneMapParams` in shaders/tone_map.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable, PartialEq)]
pub struct ToneMapUniform {
    /// x: tone mapper (0 ACES fitted, 1 Khronos PBR Neutral); yzw unused.
    pub settings: [u32; 4],
}
const _: () = assert!(std::mem::size_of::<ToneMapUniform>() == 16);

impl From<ToneMapper> for ToneMapUniform {
    fn from(t: ToneMapper) -> Self {
        let index = match t {
            ToneMapper::Aces => 0,
            ToneMapper::Neutral => 1,
        };
        Self { settings: [index, 0, 0, 0] }
    }
}

/// The tone-map pass: its pipeline, uniform and the bind group of the current HDR target.
pub struct ToneMapPass {
    layout: wgpu::BindGroupLayout,
    pipeline: Pipelines<wgpu::RenderPipeline>,
    uniform: wgpu::Buffer,
    /// The bind group and the generation of the HDR target it reads.
    bound: Option<(wgpu::BindGroup, u64)>,
    active: bool,
}

impl ToneMapPass {
    /// Builds the pipeline.
    pub fn new(b: &PassBuild<'_>) -> RenderResult<Self> {
        let device = b.device;
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("ToneMap::layout"),
            entries: &[crate::render::gpu::parts::uniform_entry(0, wgpu::ShaderStages::FRAGMENT), crate::render::gpu::parts::texture_entry(1)],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("ToneMap::pipeline_layout"),
            bind_group_layouts: &[Some(b.globals_layout), Some(&layout)],
            immediate_size: 0,
        });
        let uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("ToneMap::uniform"),
            size: std::mem::size_of::<ToneMapUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        // Only ever drawn into the display target.
        let pipeline = Pipelines::new(b, pipeline_layout, Self::build)?;
        Ok(Self { layout, pipeline, uniform, bound: None, active: false })
    }

    fn build(b: &PassBuild<'_>, layout: &wgpu::PipelineLayout) -> RenderResult<wgpu::RenderPipeline> {
        shaders::fullscreen_pipeline(b.device, b.library, "tone_map", layout, "ToneMap::pipeline", b.color_format)
    }
}

impl Pass for ToneMapPass {
    fn name(&self) -> &'static str {
        "tone_map"
    }

    fn phase(&self) -> Phase {
        Phase::Display
    }

    fn stage_pipelines(&mut self, b: &PassBuild<'_>) -> RenderResult<()> {
        self.pipeline.stage(b)
    }

    fn commit_pipelines(&mut self, accept: bool) {
        self.pipeline.commit(accept);
    }

    fn prepare(&mut self, cx: &FrameContext<'_>) {
        self.active = false;
        let Some((view, generation)) = cx.hdr.filter(|_| cx.target == Target::Hdr) else { return };
        if self.bound.as_ref().is_none_or(|(_, g)| *g != generation) {
            let bind_group = cx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("ToneMap::bind_group"),
                layout: &self.layout,
                entries: &[
                    wgpu::BindGroupEntry { binding: 0, resource: self.uniform.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(view) },
                ],
            });
            self.bound = Some((bind_group, generation));
        }
        cx.queue.write_buffer(&self.uniform, 0, bytemuck::bytes_of(&ToneMapUniform::from(cx.frame.sky_model.camera.tone_mapper)));
        self.active = true;
    }

    fn items(&self, _cx: &FrameContext<'_>, out: &mut Vec<DrawItem>) {
        if self.active {
            out.push(DrawItem::new(0, 0));
        }
    }

    fn draw(&self, rpass: &mut wgpu::RenderPass<'_>, _key: usize, _target: Target, _placement: Placement, _run: Option<&wgpu::BindGroup>) -> u32 {
        let Some((bind_group, _)) = &self.bound else { return 0 };
        rpass.set_pipeline(self.pipeline.get());
        rpass.set_bind_group(1, bind_group, &[]);
        rpass.draw(0..3, 0..1);
        1
    }
}

/// The ACES tone mapper on the CPU, in f64: exposed linear Rec. 709 radiance to linear display
/// values in [0, 1]. Keep in sync with `tone_map_aces` in shaders/sky_model/tone.wgsl.
pub fn tone_map_aces(color: [f64; 3]) -> [f64; 3] {
    const INPUT: [[f64; 3]; 3] = [[0.59719, 0.35458, 0.04823], [0.07600, 0.90834, 0.01566], [0.02840, 0.13383, 0.83777]];
    const OUTPUT: [[f64; 3]; 3] = [[1.60475, -0.53108, -0.07367], [-0.10208, 1.10813, -0.00605], [-0.00327, -0.07276, 1.07602]];
    let times = |m: &[[f64; 3]; 3], v: [f64; 3]| m.map(|row| row[0] * v[0] + row[1] * v[1] + row[2] * v[2]);
    let fitted = times(&INPUT, color).map(|v| (v * (v + 0.0245786) - 0.000090537) / (v * (0.983729 * v + 0.4329510) + 0.238081));
    times(&OUTPUT, fitted).map(|v| v.clamp(0.0, 1.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cpu_aces_curve_runs_from_black_to_white_and_rises() {
        assert_eq!(tone_map_aces([0.0; 3]), [0.0; 3]);
        assert!(tone_map_aces([1e3; 3]).iter().all(|v| (*v - 1.0).abs() < 1e-3));
        let mut last = 0.0;
        for k in 1..200 {
            let grey = tone_map_aces([k as f64 * 0.05; 3])[1];
            assert!(grey >= last, "falls at {}", k as f64 * 0.05);
            last = grey;
        }
        // The fit's toe: 0.18 exposed lands about a third lower (0.12 .. 0.14).
        let mid = tone_map_aces([0.18; 3])[1];
        assert!((0.10..0.16).contains(&mid), "{mid}");
    }
}
