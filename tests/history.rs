//! Histories live apart from the plan: a pass that asks for one finds last frame's texels in it
//! frame after frame, through changes of the plan's run buffers, and a new one after a resize.

mod common;

use skytune::render::frame::history::HistoryRequest;
use skytune::render::frame::pass::{DrawItem, FrameContext, Pass, PassBuild, PassConstructor, Phase, Pipelines};
use skytune::render::gpu::error::RenderResult;
use skytune::render::{Camera, FillStrategy, Headless, RenderOptions, SkyRenderer, OFFSCREEN_FORMAT};
use skytune::sky::builtin::default_sky;
use skytune::sky::FrameInput;

const W: u32 = 160;
const H: u32 = 90;
const REQUEST: HistoryRequest = HistoryRequest { name: "count", format: wgpu::TextureFormat::Rgba16Float, divisor: 2 };

/// Counts frames in its history.
struct HistoryProbe {
    pipeline: Pipelines<wgpu::ComputePipeline>,
    layout: wgpu::BindGroupLayout,
    first: wgpu::Buffer,
    /// One bind group per parity of the history, and the size they were made for.
    groups: Option<((u32, u32), [wgpu::BindGroup; 2])>,
    parity: usize,
}

impl HistoryProbe {
    fn new(b: &PassBuild<'_>) -> RenderResult<Self> {
        let d = b.device;
        let layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("HistoryProbe::layout"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: false },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::StorageTexture { access: wgpu::StorageTextureAccess::WriteOnly, format: REQUEST.format, view_dimension: wgpu::TextureViewDimension::D2 },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 2,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Buffer { ty: wgpu::BufferBindingType::Uniform, has_dynamic_offset: false, min_binding_size: None },
                    count: None,
                },
            ],
        });
        let pipeline_layout = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("HistoryProbe::pipeline_layout"),
            bind_group_layouts: &[Some(b.globals_layout), Some(&layout)],
            immediate_size: 0,
        });
        let first = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("HistoryProbe::first"),
            size: 16,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Ok(Self { pipeline: Pipelines::new(b, pipeline_layout, Self::build)?, layout, first, groups: None, parity: 0 })
    }

    fn build(b: &PassBuild<'_>, layout: &wgpu::PipelineLayout) -> RenderResult<wgpu::ComputePipeline> {
        let module = skytune::render::gpu::shaders::module(b.device, b.library, "history_probe")?;
        skytune::render::gpu::shaders::compute_pipeline(b.device, layout, &module, "cs_main", "HistoryProbe::pipeline")
    }
}

impl Pass for HistoryProbe {
    fn name(&self) -> &'static str {
        "history_probe"
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
    fn histories(&self, _options: &RenderOptions, out: &mut Vec<HistoryRequest>) {
        out.push(REQUEST);
    }
    fn prepare(&mut self, cx: &FrameContext<'_>) {
        let Some(history) = cx.histories.get(self.name(), REQUEST.name) else { return };
        if history.frames() == 0 || self.groups.as_ref().is_none_or(|(size, _)| *size != history.size()) {
            // Bind groups for both parities: this frame's and the next one's.
            let group = |read: &wgpu::TextureView, write: &wgpu::TextureView| {
                cx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("HistoryProbe::bind_group"),
                    layout: &self.layout,
                    entries: &[
                        wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(read) },
                        wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(write) },
                        wgpu::BindGroupEntry { binding: 2, resource: self.first.as_entire_binding() },
                    ],
                })
            };
            let now = group(history.read_view(), history.write_view());
            let next = group(history.write_view(), history.read_view());
            let p = history.parity();
            let groups = if p == 0 { [now, next] } else { [next, now] };
            self.groups = Some((history.size(), groups));
        }
        self.parity = history.parity();
        cx.queue.write_buffer(&self.first, 0, bytemuck::cast_slice(&[if history.frames() == 0 { 1.0f32 } else { 0.0 }, 0.0, 0.0, 0.0]));
    }
    fn items(&self, _cx: &FrameContext<'_>, out: &mut Vec<DrawItem>) {
        out.push(DrawItem::new(0, 0));
    }
    fn dispatch(&self, cpass: &mut wgpu::ComputePass<'_>, _key: usize) {
        let Some(((w, h), groups)) = &self.groups else { return };
        cpass.set_pipeline(self.pipeline.get());
        cpass.set_bind_group(1, &groups[self.parity], &[]);
        cpass.dispatch_workgroups(w.div_ceil(8), h.div_ceil(8), 1);
    }
}

const EXTRA: &[(&str, PassConstructor)] = &[("history_probe", |b| skytune::render::frame::pass::boxed(HistoryProbe::new, b))];

/// The last frame's history texels (x, y of each), blocking.
fn counts(h: &Headless) -> ((u32, u32), Vec<[f32; 2]>) {
    let history = h.renderer.histories().get("history_probe", REQUEST.name).expect("asked for");
    let (w, hh) = history.size();
    let bytes = skytune::render::headless::read_texture(&h.ctx, history.read_texture(), w, hh, 8).unwrap();
    let texels = bytes.chunks(8).map(|t| [0, 2].map(|c| half::f16::from_le_bytes([t[c], t[c + 1]]).to_f32())).collect();
    ((w, hh), texels)
}

#[test]
fn a_history_carries_frames_over_plan_changes_and_restarts_on_a_resize() {
    let sky = default_sky();
    let (_dir, library) = common::library_with_test_passes();
    let mut h = common::headless(W, H);
    h.renderer = SkyRenderer::with_passes(&h.ctx, OFFSCREEN_FORMAT, library, EXTRA).unwrap();
    h.set_sky(&sky).unwrap();
    let input = FrameInput::new(13.0, 0.0);
    let camera = Camera::default();
    let software = RenderOptions { glare: false, ..Default::default() };
    let plain = RenderOptions { strategy: FillStrategy::plain(), ..software };
    let frames = |h: &mut Headless, n: usize, options: &RenderOptions| {
        for _ in 0..n {
            h.frame(&sky, &input, &camera, options, 0.0);
        }
    };
    frames(&mut h, 3, &software);
    // The plan's reduced buffers go with the plain strategy; the history stays.
    frames(&mut h, 2, &plain);
    let ((w, hh), texels) = counts(&h);
    assert_eq!((w, hh), (W / 2, H / 2), "at its divisor");
    assert!(texels.iter().all(|t| t[0] == 5.0), "five frames counted: {:?}", &texels[..4]);
    assert!(texels.iter().enumerate().all(|(k, t)| t[1] == (k as u32 % w) as f32), "each texel in its place");
    h.resize(W + 20, H);
    frames(&mut h, 2, &software);
    let ((w, _), texels) = counts(&h);
    assert_eq!(w, (W + 20) / 2);
    assert!(texels.iter().all(|t| t[0] == 2.0), "a resize starts the history again: {:?}", &texels[..4]);
}
