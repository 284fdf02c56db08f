//! The renderer as a list of phases: a pass added by the recipe of docs/architecture.md (a module,
//! its `.wgsl`, one line in a list) runs in its phase and is timed; sky reloads keep what did not
//! change; the clock steps frames.

mod common;

use skytune::render::frame::pass::{DrawItem, FrameContext, Pass, PassBuild, PassConstructor, Phase, Pipelines, Target};
use skytune::render::gpu::error::RenderResult;
use skytune::render::{Camera, GpuContext, Headless, RenderOptions, ShaderLibrary, SkyRenderer, OFFSCREEN_FORMAT};
use skytune::sky::builtin::default_sky;
use skytune::sky::{load_sky_file, Clock, FrameInput, Stepping};

const W: u32 = 160;
const H: u32 = 90;

fn camera() -> Camera {
    Camera { yaw_deg: 220.0, pitch_deg: 20.0, ..Camera::default() }
}

/// A compute pass: copies globals into a storage buffer and counts its dispatches.
struct HourProbe {
    pipeline: Pipelines<wgpu::ComputePipeline>,
    bind_group: wgpu::BindGroup,
    storage: wgpu::Buffer,
    readback: wgpu::Buffer,
}

impl HourProbe {
    fn new(b: &PassBuild<'_>) -> RenderResult<Self> {
        let d = b.device;
        let bind_layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("HourProbe::layout"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: wgpu::BindingType::Buffer { ty: wgpu::BufferBindingType::Storage { read_only: false }, has_dynamic_offset: false, min_binding_size: None },
                count: None,
            }],
        });
        let layout = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("HourProbe::pipeline_layout"),
            bind_group_layouts: &[Some(b.globals_layout), Some(&bind_layout)],
            immediate_size: 0,
        });
        let storage = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("HourProbe::storage"),
            size: 16,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let readback = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("HourProbe::readback"),
            size: 16,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind_group = d.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("HourProbe::bind_group"),
            layout: &bind_layout,
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: storage.as_entire_binding() }],
        });
        Ok(Self { pipeline: Pipelines::new(b, layout, Self::build)?, bind_group, storage, readback })
    }

    fn build(b: &PassBuild<'_>, layout: &wgpu::PipelineLayout) -> RenderResult<wgpu::ComputePipeline> {
        let module = skytune::render::gpu::shaders::module(b.device, b.library, "hour_probe")?;
        skytune::render::gpu::shaders::compute_pipeline(b.device, layout, &module, "cs_main", "HourProbe::pipeline")
    }

    /// The probe's buffer after the last frame (blocks).
    fn read(&self, ctx: &GpuContext) -> [f32; 4] {
        self.readback.map_async(wgpu::MapMode::Read, .., |r| r.unwrap());
        ctx.wait_idle().unwrap();
        let v: [f32; 4] = bytemuck::pod_read_unaligned(&self.readback.get_mapped_range(..).unwrap()[..16]);
        self.readback.unmap();
        v
    }
}

impl Pass for HourProbe {
    fn name(&self) -> &'static str {
        "hour_probe"
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
    fn items(&self, _cx: &FrameContext<'_>, out: &mut Vec<DrawItem>) {
        out.push(DrawItem::new(0, 0));
    }
    fn dispatch(&self, cpass: &mut wgpu::ComputePass<'_>, _key: usize) {
        cpass.set_pipeline(self.pipeline.get());
        cpass.set_bind_group(1, &self.bind_group, &[]);
        cpass.dispatch_workgroups(1, 1, 1);
    }
    fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        encoder.copy_buffer_to_buffer(&self.storage, 0, &self.readback, 0, 16);
    }
}

/// A pass drawn in the scene's depth range after the sky (where particles go).
struct Tint {
    pipeline: Pipelines<wgpu::RenderPipeline>,
}

impl Tint {
    fn new(b: &PassBuild<'_>) -> RenderResult<Self> {
        let layout = b.device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("Tint::pipeline_layout"),
            bind_group_layouts: &[Some(b.globals_layout)],
            immediate_size: 0,
        });
        Ok(Self { pipeline: Pipelines::new_render(b, layout, Self::build)? })
    }

    fn build(b: &PassBuild<'_>, layout: &wgpu::PipelineLayout) -> RenderResult<wgpu::RenderPipeline> {
        let module = skytune::render::gpu::shaders::module(b.device, b.library, "tint")?;
        skytune::render::gpu::shaders::validated(b.device, "Tint::pipeline", || {
            b.device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("Tint::pipeline"),
                layout: Some(layout),
                vertex: wgpu::VertexState { module: &module, entry_point: Some("vs_main"), buffers: &[], compilation_options: Default::default() },
                primitive: Default::default(),
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: skytune::render::DEPTH_FORMAT,
                    depth_write_enabled: Some(false),
                    depth_compare: Some(wgpu::CompareFunction::Less),
                    stencil: Default::default(),
                    bias: Default::default(),
                }),
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some("fs_main"),
                    targets: &[Some(wgpu::ColorTargetState { format: b.color_format, blend: None, write_mask: wgpu::ColorWrites::ALL })],
                    compilation_options: Default::default(),
                }),
                multiview_mask: None,
                cache: None,
            })
        })
    }
}

impl Pass for Tint {
    fn name(&self) -> &'static str {
        "tint"
    }
    fn phase(&self) -> Phase {
        Phase::SceneAfterSky
    }
    fn stage_pipelines(&mut self, b: &PassBuild<'_>) -> RenderResult<()> {
        self.pipeline.stage(b)
    }
    fn commit_pipelines(&mut self, accept: bool) {
        self.pipeline.commit(accept);
    }
    fn items(&self, _cx: &FrameContext<'_>, out: &mut Vec<DrawItem>) {
        out.push(DrawItem::new(0, 0));
    }
    fn draw(&self, rpass: &mut wgpu::RenderPass<'_>, _key: usize, target: Target, _placement: skytune::render::frame::pass::Placement, _run: Option<&wgpu::BindGroup>) -> u32 {
        rpass.set_pipeline(self.pipeline.for_target(target));
        rpass.draw(0..3, 0..1);
        1
    }
}

/// The recipe's "one line in the phase list", here in a list of the test's own.
const EXTRA: &[(&str, PassConstructor)] =
    &[("hour_probe", |b| skytune::render::frame::pass::boxed(HourProbe::new, b)), ("tint", |b| skytune::render::frame::pass::boxed(Tint::new, b))];

#[test]
fn added_passes_run_in_their_phases_and_are_timed() {
    let sky = default_sky();
    let (_dir, library) = common::library_with_test_passes();
    let ctx = GpuContext::headless(skytune::render::AdapterChoice::Cpu).unwrap();
    let mut plain = Headless::new(ctx.clone(), W, H).unwrap();
    plain.set_sky(&sky).unwrap();
    let mut h = Headless::new(ctx, W, H).unwrap();
    h.renderer = SkyRenderer::with_passes(&h.ctx, OFFSCREEN_FORMAT, library, EXTRA).unwrap();
    h.set_sky(&sky).unwrap();
    let names = h.renderer.pass_names();
    assert!(names.contains(&("hour_probe", Phase::Compute)) && names.contains(&("tint", Phase::SceneAfterSky)), "{names:?}");

    let input = FrameInput::new(13.0, 0.25);
    let options = RenderOptions { glare: false, ..Default::default() };
    for _ in 0..4 {
        h.frame(&sky, &input, &camera(), &options, 1.0 / 60.0);
        h.ctx.wait_idle().unwrap();
    }
    let probe = h.renderer.pass::<HourProbe>().unwrap().read(&h.ctx);
    assert_eq!(probe[..3], [13.0, 0.25, W as f32], "the compute pass saw this frame's globals");
    assert_eq!(probe[3], 4.0, "one dispatch per frame");
    h.frame(&sky, &input, &camera(), &options, 1.0 / 60.0);
    let timed: Vec<&str> = h.renderer.gpu_pass_ms().iter().map(|(n, _)| *n).collect();
    for phase in ["compute", "scene", "sky", "scene_after_sky"] {
        assert!(timed.contains(&phase), "phase {phase} not timed: {timed:?}");
    }

    // The tint covers the sky (drawn after it) but not the near scene (which occludes it).
    let tinted = h.render(&sky, &input, &camera(), &options).unwrap();
    let before = plain.render(&sky, &input, &camera(), &options).unwrap();
    assert_eq!(tinted.get_pixel(W / 2, 2).0, [255, 0, 0, 255], "sky pixel");
    assert_ne!(before.get_pixel(W / 2, 2).0, [255, 0, 0, 255]);
    assert_eq!(tinted.get_pixel(W / 2, H - 2), before.get_pixel(W / 2, H - 2), "near-scene pixel must stay as it was");

    // Shader reload covers the added passes too, all or nothing.
    h.renderer.reload_shaders(&h.ctx).unwrap();
    h.renderer.set_library(ShaderLibrary { dir: Some(std::path::PathBuf::from("/nonexistent")) });
    let err = h.renderer.reload_shaders(&h.ctx).unwrap_err();
    assert!(err.to_string().contains("nonexistent"), "{err}");
    let still = h.render(&sky, &input, &camera(), &options).unwrap();
    assert_eq!(common::diff(&still, &tinted, 0).0.differing, 0.0, "a failed reload keeps every pipeline");
}

#[test]
fn reloading_a_sky_keeps_unchanged_textures_and_the_glare_state() {
    let (dir, path) = common::default_sky_folder();
    let sky = load_sky_file(&path).unwrap();
    let mut h = common::headless(W, H);
    h.set_sky(&sky).unwrap();
    let first = h.renderer.upload_stats;
    assert!(first.textures_uploaded > 5 && first.textures_reused == 0, "{first:?}");

    // Let the glare build up, looking at the noon sun.
    let sun = Camera { yaw_deg: 180.0, pitch_deg: 60.0, fov_y_deg: 30.0, ..Camera::default() };
    let input = FrameInput::new(12.0, 0.0);
    for _ in 0..8 {
        h.frame(&sky, &input, &sun, &RenderOptions::default(), 0.1);
        h.ctx.wait_idle().unwrap();
    }
    let glare = h.renderer.glare_state().unwrap().clone();
    assert!(glare.intensity > 0.0, "{glare:?}");

    // The same files again: nothing is uploaded, and the glare goes on where it was.
    let again = load_sky_file(&path).unwrap();
    h.set_sky(&again).unwrap();
    assert_eq!(h.renderer.upload_stats, skytune::render::UploadStats { textures_uploaded: 0, textures_reused: first.textures_uploaded });
    assert_eq!(h.renderer.glare_state().unwrap(), &glare);

    // One bitmap edited: exactly that texture is uploaded again, and it shows.
    let galaxy = dir.path().join("galaxy.png");
    let mut img = image::open(&galaxy).unwrap().to_rgba8();
    for p in img.pixels_mut() {
        p.0 = [255, 0, 255, 255];
    }
    img.save(&galaxy).unwrap();
    let edited = load_sky_file(&path).unwrap();
    h.set_sky(&edited).unwrap();
    assert_eq!(h.renderer.upload_stats, skytune::render::UploadStats { textures_uploaded: 1, textures_reused: first.textures_uploaded - 1 });
    let night = FrameInput::new(23.0, 0.0);
    let a = {
        h.set_sky(&again).unwrap();
        h.render(&again, &night, &camera(), &RenderOptions::default()).unwrap()
    };
    h.set_sky(&edited).unwrap();
    let b = h.render(&edited, &night, &camera(), &RenderOptions::default()).unwrap();
    assert!(common::diff(&a, &b, 10).0.differing > 0.01, "the edited galaxy must show at night");
}

#[test]
fn clock_steps_real_or_fixed_time() {
    let mut fixed = Clock::new(Stepping::Fixed { dt_s: 0.05 });
    let mut input = FrameInput::new(6.0, 0.0);
    fixed.advance(&mut input);
    assert_eq!((input.dt_s, input.frame), (0.05, 1));
    fixed.advance(&mut input);
    assert_eq!((input.dt_s, input.frame), (0.05, 2));
    let frame = default_sky().evaluate(&input);
    assert_eq!((frame.dt_s, frame.frame, frame.hours_per_day), (0.05, 2, 24.0));

    let mut real = Clock::new(Stepping::RealTime);
    assert_eq!(real.tick(), (0.0, 1), "the first frame has no previous one");
    std::thread::sleep(std::time::Duration::from_millis(20));
    let (dt, n) = real.tick();
    assert!(n == 2 && (0.015..=Clock::MAX_DT_S).contains(&dt), "{dt}");
}

#[test]
fn stills_are_deterministic_with_glare() {
    let sky = default_sky();
    let sun = Camera { yaw_deg: 180.0, pitch_deg: 40.0, ..Camera::default() };
    let input = FrameInput::new(12.0, 0.0);
    let render = || {
        let mut h = common::headless(W, H);
        h.set_sky(&sky).unwrap();
        h.render(&sky, &input, &sun, &RenderOptions::default()).unwrap()
    };
    let (a, b) = (render(), render());
    assert_eq!(common::diff(&a, &b, 0).0.differing, 0.0);
    // The glare settled into the still: it differs from the same still without glare.
    let mut h = common::headless(W, H);
    h.set_sky(&sky).unwrap();
    let no_glare = h.render(&sky, &input, &sun, &RenderOptions { glare: false, ..Default::default() }).unwrap();
    assert!(common::diff(&a, &no_glare, 10).0.differing > 0.005, "the settled glare shows in the still");
}
