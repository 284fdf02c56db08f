//! The scene's depth belongs to the renderer and can be sampled: a pass of the compute phase reads
//! the last frame's depth and `scene_distance_m` (shaders/globals.wgsl) turns it into metres along
//! the view ray, checked against the stand-in's flat ground near the viewer intersected on the
//! CPU; the globals carry the previous frame's camera.

mod common;

use skytune::render::frame::pass::{DrawItem, FrameContext, Pass, PassBuild, PassConstructor, Phase, Pipelines};
use skytune::render::gpu::error::RenderResult;
use skytune::render::{Camera, GpuContext, Headless, RenderOptions, SkyRenderer, OFFSCREEN_FORMAT};
use skytune::sky::builtin::default_sky;
use skytune::sky::FrameInput;

const W: u32 = 160;
const H: u32 = 90;
/// Entries the probe writes: eight pixels, then the previous camera's last column.
const ENTRIES: u64 = 9;

/// Reads the scene's depth in the compute phase.
struct DepthProbe {
    pipeline: Pipelines<wgpu::ComputePipeline>,
    layout: wgpu::BindGroupLayout,
    bind_group: Option<(u64, wgpu::BindGroup)>,
    storage: wgpu::Buffer,
    readback: wgpu::Buffer,
}

impl DepthProbe {
    fn new(b: &PassBuild<'_>) -> RenderResult<Self> {
        let d = b.device;
        let layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("DepthProbe::layout"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Texture { sample_type: wgpu::TextureSampleType::Depth, view_dimension: wgpu::TextureViewDimension::D2, multisampled: false },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Buffer { ty: wgpu::BufferBindingType::Storage { read_only: false }, has_dynamic_offset: false, min_binding_size: None },
                    count: None,
                },
            ],
        });
        let pipeline_layout = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("DepthProbe::pipeline_layout"),
            bind_group_layouts: &[Some(b.globals_layout), Some(&layout)],
            immediate_size: 0,
        });
        let buffer = |label: &str, usage| d.create_buffer(&wgpu::BufferDescriptor { label: Some(label), size: ENTRIES * 16, usage, mapped_at_creation: false });
        Ok(Self {
            pipeline: Pipelines::new(b, pipeline_layout, Self::build)?,
            layout,
            bind_group: None,
            storage: buffer("DepthProbe::storage", wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC),
            readback: buffer("DepthProbe::readback", wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST),
        })
    }

    fn build(b: &PassBuild<'_>, layout: &wgpu::PipelineLayout) -> RenderResult<wgpu::ComputePipeline> {
        let module = skytune::render::gpu::shaders::module(b.device, b.library, "depth_probe")?;
        skytune::render::gpu::shaders::compute_pipeline(b.device, layout, &module, "cs_main", "DepthProbe::pipeline")
    }

    /// What the last frame's dispatch wrote (blocks).
    fn read(&self, ctx: &GpuContext) -> Vec<[f32; 4]> {
        self.readback.map_async(wgpu::MapMode::Read, .., |r| r.unwrap());
        ctx.wait_idle().unwrap();
        let v: Vec<[f32; 4]> = bytemuck::cast_slice(&self.readback.get_mapped_range(..).unwrap()).to_vec();
        self.readback.unmap();
        v
    }
}

impl Pass for DepthProbe {
    fn name(&self) -> &'static str {
        "depth_probe"
    }
    fn phase(&self) -> Phase {
        Phase::Compute
    }
    fn stage_pipelines(&mut self, b: &PassBuild<'_>) -> RenderResult<()> {
        self.pipeline.stage(b)
    }
    fn commit_pipelines(&mut self, accept: bool) {
        self.pipeline.commit(accept);
    }
    fn prepare(&mut self, cx: &FrameContext<'_>) {
        let (view, generation) = cx.depth;
        if self.bind_group.as_ref().is_none_or(|(g, _)| *g != generation) {
            let group = cx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("DepthProbe::bind_group"),
                layout: &self.layout,
                entries: &[
                    wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(view) },
                    wgpu::BindGroupEntry { binding: 1, resource: self.storage.as_entire_binding() },
                ],
            });
            self.bind_group = Some((generation, group));
        }
    }
    fn items(&self, _cx: &FrameContext<'_>, out: &mut Vec<DrawItem>) {
        out.push(DrawItem::new(0, 0));
    }
    fn dispatch(&self, cpass: &mut wgpu::ComputePass<'_>, _key: usize) {
        let Some((_, group)) = &self.bind_group else { return };
        cpass.set_pipeline(self.pipeline.get());
        cpass.set_bind_group(1, group, &[]);
        cpass.dispatch_workgroups(1, 1, 1);
    }
    fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        encoder.copy_buffer_to_buffer(&self.storage, 0, &self.readback, 0, ENTRIES * 16);
    }
}

const EXTRA: &[(&str, PassConstructor)] = &[("depth_probe", |b| skytune::render::frame::pass::boxed(DepthProbe::new, b))];

fn probed_renderer() -> (tempfile::TempDir, Headless) {
    let (dir, library) = common::library_with_test_passes();
    let mut h = common::headless(W, H);
    h.renderer = SkyRenderer::with_passes(&h.ctx, OFFSCREEN_FORMAT, library, EXTRA).unwrap();
    h.set_sky(&default_sky()).unwrap();
    (dir, h)
}

/// Distance along the ray through `pixel` (framebuffer coordinates) to the stand-in's flat ground
/// near the viewer (height -0.5 m within 40 m of the origin: src/render/passes/scene.rs), m.
fn ground_distance_m(camera: &Camera, pixel: [f32; 2]) -> f32 {
    let (clip_from_world, _) = camera.matrices(W as f32 / H as f32);
    let ndc = glam::Vec2::new(pixel[0] / W as f32 * 2.0 - 1.0, 1.0 - pixel[1] / H as f32 * 2.0);
    let far = clip_from_world.inverse().project_point3(ndc.extend(1.0));
    let ray = (far - camera.position()).normalize();
    (camera.position().y + 0.5) / -ray.y
}

#[test]
fn the_scene_depth_is_sampled_as_distance_with_and_without_the_depth_split() {
    let sky = default_sky();
    let (_dir, mut h) = probed_renderer();
    let camera = Camera { yaw_deg: 220.0, pitch_deg: -30.0, ..Camera::default() };
    let input = FrameInput::new(13.0, 0.0);
    let mut seen: Vec<Vec<f32>> = Vec::new();
    for depth_split in [true, false] {
        let options = RenderOptions { glare: false, depth_split, ..Default::default() };
        // The compute phase sees the last frame's depth: two frames of the same view.
        for _ in 0..2 {
            h.frame(&sky, &input, &camera, &options, 0.0);
            h.ctx.wait_idle().unwrap();
        }
        let probe = h.renderer.pass::<DepthProbe>().unwrap().read(&h.ctx);
        for p in &probe[..8] {
            let (distance, stored, pixel) = (p[0], p[1], [p[2], p[3]]);
            let expected = ground_distance_m(&camera, pixel);
            assert!(expected > 1.0 && expected < 40.0, "{pixel:?}: the ground near the viewer ({expected} m)");
            if depth_split {
                assert!(stored <= skytune::render::SCENE_DEPTH.1, "{pixel:?}: stored {stored} in the scene's range");
            }
            // Measured: at most 0.21% apart (the terrain's triangles about the viewer tilt by a
            // few millimetres). Forgetting the depth range reads 0.80 m for 3.70 m; forgetting
            // the ray's slant, 0.9% short already at the probed pixel nearest the centre.
            assert!((distance - expected).abs() <= 5e-3 * expected, "{pixel:?} split {depth_split}: {distance} m, the ground at {expected} m");
        }
        seen.push(probe[..8].iter().map(|p| p[0]).collect());
    }
    for (a, b) in seen[0].iter().zip(&seen[1]) {
        // Measured: at most 6e-6 apart (the split stores the same depths in 0.95 of the range).
        assert!((a - b).abs() <= 1e-4 * a, "with the depth split {a} m, without it {b} m");
    }
}

#[test]
fn the_globals_carry_the_previous_frames_camera() {
    let sky = default_sky();
    let (_dir, mut h) = probed_renderer();
    let options = RenderOptions { glare: false, ..Default::default() };
    let input = FrameInput::new(13.0, 0.0);
    let (a, b) = (Camera { yaw_deg: 200.0, pitch_deg: -10.0, ..Camera::default() }, Camera { yaw_deg: 250.0, pitch_deg: 5.0, ..Camera::default() });
    let column = |c: &Camera| c.matrices(W as f32 / H as f32).0.col(3).to_array();
    h.frame(&sky, &input, &a, &options, 0.0);
    h.frame(&sky, &input, &b, &options, 0.0);
    let probe = h.renderer.pass::<DepthProbe>().unwrap().read(&h.ctx);
    assert_ne!(column(&a), column(&b));
    assert_eq!(probe[8], column(&a), "frame 2 sees frame 1's camera as the previous one");
    h.frame(&sky, &input, &b, &options, 0.0);
    assert_eq!(h.renderer.pass::<DepthProbe>().unwrap().read(&h.ctx)[8], column(&b));
}
