//! Stars pass: the point-star field of the sky file, additive, rotating with the celestial frame.

use bytemuck::{Pod, Zeroable};
use wgpu::util::DeviceExt;

use crate::render::frame::pass::{Caps, DrawItem, FrameContext, Pass, PassBuild, Phase, Pipelines, Placement, SkyUpload, Staged, Target};
use crate::render::frame::stats::FrameStats;
use crate::render::gpu::error::RenderResult;
use crate::render::gpu::shaders;
use crate::sky::starfield;
use crate::sky::{resolved::Stars, Rgba};

/// Per-frame star parameters. Keep in sync with `StarsParams` in shaders/stars.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct StarsUniform {
    /// Tint (rgb) and visibility (a).
    pub color: [f32; 4],
    /// x: size of a magnitude-0 star in pixels.
    pub size: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<StarsUniform>() == 32);

/// Instance data of one star. Keep in sync with `vs_main` in shaders/stars.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
struct StarInstance {
    direction: [f32; 3],
    brightness: f32,
}

/// The stars pass: its pipeline and the current sky's star field.
pub struct StarsPass {
    bind_layout: wgpu::BindGroupLayout,
    pipeline: Pipelines<wgpu::RenderPipeline>,
    /// The same drawn after the run of reduced layers above the stars ([`Placement::UnderRun`](crate::render::frame::pass::Placement::UnderRun)).
    under_run: Pipelines<wgpu::RenderPipeline>,
    /// The same drawn first under the background, not depth-tested ([`Placement::First`](crate::render::frame::pass::Placement::First)).
    first: Pipelines<wgpu::RenderPipeline>,
    field: Staged<Option<StarField>>,
    /// Whether the stars show this frame.
    visible: bool,
    /// Transparent this frame (drawn anyway only when the skip is off).
    skipped: bool,
}

impl StarsPass {
    /// Builds the pipeline.
    pub fn new(b: &PassBuild<'_>) -> RenderResult<Self> {
        let (device, globals) = (b.device, b.globals_layout);
        let bind_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("Stars::layout"),
            entries: &[crate::render::gpu::parts::uniform_entry(0, wgpu::ShaderStages::VERTEX_FRAGMENT)],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("Stars::pipeline_layout"),
            bind_group_layouts: &[Some(globals), Some(&bind_layout)],
            immediate_size: 0,
        });
        let pipeline = Pipelines::new_render(b, pipeline_layout.clone(), |b, l| Self::build(b, l, "fs_main", wgpu::CompareFunction::Less))?;
        let first = Pipelines::new_render(b, pipeline_layout, |b, l| Self::build(b, l, "fs_main", wgpu::CompareFunction::Always))?;
        let run_layout = crate::render::passes::reduced_layers::run_layout(device, "Stars::run_layout");
        let under_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("Stars::under_run_pipeline_layout"),
            bind_group_layouts: &[Some(globals), Some(&bind_layout), Some(&run_layout)],
            immediate_size: 0,
        });
        let under_run = Pipelines::new_render(b, under_layout, |b, l| Self::build(b, l, "fs_under_run", wgpu::CompareFunction::Less))?;
        Ok(Self { bind_layout, pipeline, under_run, first, field: Staged::new(None), visible: false, skipped: false })
    }

    fn build(b: &PassBuild<'_>, layout: &wgpu::PipelineLayout, entry: &str, compare: wgpu::CompareFunction) -> RenderResult<wgpu::RenderPipeline> {
        let (device, format) = (b.device, b.color_format);
        let module = shaders::module(device, b.library, "stars")?;
        let constants = b.target_constants();
        let options = wgpu::PipelineCompilationOptions { constants: &constants, zero_initialize_workgroup_memory: true };
        shaders::validated(device, "Stars::pipeline", || {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("Stars::pipeline"),
                layout: Some(layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("vs_main"),
                    buffers: &[Some(wgpu::VertexBufferLayout {
                        array_stride: std::mem::size_of::<StarInstance>() as u64,
                        step_mode: wgpu::VertexStepMode::Instance,
                        attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32],
                    })],
                    compilation_options: options.clone(),
                },
                primitive: wgpu::PrimitiveState { topology: wgpu::PrimitiveTopology::TriangleStrip, cull_mode: None, ..Default::default() },
                depth_stencil: crate::render::gpu::parts::depth_state(false, compare),
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some(entry),
                    targets: &[Some(wgpu::ColorTargetState { format, blend: Some(crate::render::gpu::parts::ADDITIVE_ALPHA), write_mask: wgpu::ColorWrites::ALL })],
                    compilation_options: options.clone(),
                }),
                multiview_mask: None,
                cache: None,
            })
        })
    }
}

impl StarsPass {
    /// Draws the star field with `pipeline` (its other groups already bound); 0 draws without one.
    fn draw_with(&self, rpass: &mut wgpu::RenderPass<'_>, pipeline: &wgpu::RenderPipeline) -> u32 {
        let Some(field) = &self.field.current else { return 0 };
        rpass.set_pipeline(pipeline);
        rpass.set_bind_group(1, &field.bind_group, &[]);
        rpass.set_vertex_buffer(0, field.instances.slice(..));
        rpass.draw(0..4, 0..field.drawn);
        1
    }
}

impl Pass for StarsPass {
    fn name(&self) -> &'static str {
        "stars"
    }

    fn phase(&self) -> Phase {
        Phase::Sky
    }

    fn stage_pipelines(&mut self, b: &PassBuild<'_>) -> RenderResult<()> {
        self.pipeline.stage(b)?;
        self.under_run.stage(b)?;
        self.first.stage(b)
    }

    fn commit_pipelines(&mut self, accept: bool) {
        self.pipeline.commit(accept);
        self.under_run.commit(accept);
        self.first.commit(accept);
    }

    fn stage_sky(&mut self, up: &mut SkyUpload<'_>) {
        let field = up.sky.stars.as_ref().map(|s| StarField::new(up.device, &self.bind_layout, s));
        self.field.stage(field);
    }

    fn commit_sky(&mut self, accept: bool) {
        self.field.commit(accept);
    }

    fn prepare(&mut self, cx: &FrameContext<'_>) {
        (self.visible, self.skipped) = match (&mut self.field.current, cx.frame.stars) {
            (Some(field), Some(s)) => {
                // On the HDR target the tone map's toe can lift half a level by more: every star.
                let faint_skipped = cx.options.skips.invisible_stars && cx.target == Target::Display;
                let visible = field.prepare(cx.queue, s.color, faint_skipped);
                (visible || (!cx.options.skips.invisible_stars && field.count > 0), !visible)
            }
            _ => (false, false),
        };
    }

    fn items(&self, cx: &FrameContext<'_>, out: &mut Vec<DrawItem>) {
        if let (true, Some(s)) = (self.visible, cx.frame.stars) {
            let drawable = self.field.current.is_some();
            out.push(DrawItem { additive: true, caps: Caps { under_run: drawable, first: drawable, ..Caps::default() }, ..DrawItem::new(s.priority, 0) });
        }
    }

    fn draw(&self, rpass: &mut wgpu::RenderPass<'_>, _key: usize, target: Target, placement: Placement, run: Option<&wgpu::BindGroup>) -> u32 {
        match (placement, run) {
            (Placement::Plain, _) => self.draw_with(rpass, self.pipeline.for_target(target)),
            (Placement::First, _) => self.draw_with(rpass, self.first.for_target(target)),
            (Placement::UnderRun, Some(run)) => {
                rpass.set_bind_group(2, run, &[]);
                self.draw_with(rpass, self.under_run.for_target(target))
            }
            _ => 0,
        }
    }

    fn stats(&self, stats: &mut FrameStats) {
        stats.stars = self.field.current.as_ref().map_or(0, |f| f.count);
        stats.stars_drawn = self.field.current.as_ref().filter(|_| self.visible).map_or(0, |f| f.drawn);
        stats.stars_skipped = self.skipped && !self.visible;
    }
}

/// GPU resources of a sky's star field.
pub struct StarField {
    /// Brightest first, so that the stars bright enough to show this frame are a prefix.
    instances: wgpu::Buffer,
    count: u32,
    /// Each instance's brightness as the shader caps it (`min(brightness, 1.5)`), descending.
    capped_brightness: Vec<f32>,
    /// Instances drawn this frame: those whose brightest pixel adds at least half a level.
    drawn: u32,
    uniform: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    size_px: f32,
}

impl StarField {
    /// Generates and uploads the stars of a sky.
    pub fn new(device: &wgpu::Device, layout: &wgpu::BindGroupLayout, stars: &Stars) -> Self {
        let generated = starfield::generate(stars);
        let mut data: Vec<StarInstance> = generated.iter().map(|s| StarInstance { direction: s.direction.to_array(), brightness: s.brightness() }).collect();
        // Additive draws commute (clamped sums of non-negative terms), so the order is free.
        data.sort_by(|a, b| b.brightness.total_cmp(&a.brightness));
        let capped_brightness = data.iter().map(|s| s.brightness.min(MAX_BRIGHTNESS)).collect();
        let placeholder = [StarInstance::zeroed()];
        let instances = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("Stars::instances"),
            // A zero-sized vertex buffer is invalid; one invisible star keeps the path uniform.
            contents: bytemuck::cast_slice(if data.is_empty() { &placeholder[..] } else { &data[..] }),
            usage: wgpu::BufferUsages::VERTEX,
        });
        let uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("Stars::uniform"),
            size: std::mem::size_of::<StarsUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("Stars::bind_group"),
            layout,
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: uniform.as_entire_binding() }],
        });
        let count = data.len() as u32;
        Self { instances, count, capped_brightness, drawn: count, uniform, bind_group, size_px: stars.size_px }
    }

    /// Number of stars kept after the magnitude cutoff.
    pub fn count(&self) -> u32 {
        self.count
    }

    /// Writes this frame's colour and picks the stars to draw: with `faint_skipped`, those whose
    /// brightest pixel adds at least half a level of 255 in some channel (fainter ones round to
    /// nothing on an 8-bit display target: at dusk all but 2 of the lakes sky's 1068), else all.
    /// Returns whether any star is visible at all.
    pub fn prepare(&mut self, queue: &wgpu::Queue, color: Rgba, faint_skipped: bool) -> bool {
        queue.write_buffer(&self.uniform, 0, bytemuck::bytes_of(&StarsUniform { color, size: [self.size_px, 0.0, 0.0, 0.0] }));
        self.drawn = if faint_skipped { visible_stars(&self.capped_brightness, color) } else { self.count };
        color[3] > 0.5 / 255.0 && self.count > 0
    }
}

/// Brightness past which shaders/stars.wgsl draws a star no brighter. Keep in sync with `vs_main` there.
const MAX_BRIGHTNESS: f32 = 1.5;

/// How many of the stars (capped brightness, descending) add at least half a level of 255 at
/// their brightest pixel under tint and visibility `color`: shaders/stars.wgsl writes
/// tint x min(falloff x brightness x extinction x visibility, 1) in display values, falloff and
/// extinction at most 1.
fn visible_stars(capped_brightness: &[f32], color: Rgba) -> u32 {
    let peak_tint = color[0].max(color[1]).max(color[2]);
    let half_level = 0.5 / 255.0;
    capped_brightness.partition_point(|&b| peak_tint * (b * color[3]).min(1.0) >= half_level) as u32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stars_adding_less_than_half_a_level_are_left_out() {
        let capped = [1.5, 1.0, 0.01, 0.001];
        // 0.001 x 1 is under half a level of 255 (0.00196), 0.01 is not.
        assert_eq!(visible_stars(&capped, [1.0, 1.0, 1.0, 1.0]), 3);
        // The tint's brightest channel counts; visibility scales every star.
        assert_eq!(visible_stars(&capped, [0.0, 0.0, 0.1, 1.0]), 2);
        assert_eq!(visible_stars(&capped, [1.0, 1.0, 1.0, 0.01]), 2);
        // The shader clamps a star's weight to 1 before the tint.
        assert_eq!(visible_stars(&capped, [0.0015, 0.0, 0.0, 100.0]), 0);
        assert_eq!(visible_stars(&capped, [1.0, 1.0, 1.0, 0.0]), 0);
        assert_eq!(visible_stars(&[], [1.0; 4]), 0);
    }
}
