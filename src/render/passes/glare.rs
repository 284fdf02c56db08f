//! Sun glare pass: sun visibility from two occlusion queries, then an additive halo and lens
//! flare. Queries are read back asynchronously: a frame never waits for a result.
//!
//! V draws the solar disc with the depth test on, T draws it with depth compare Always; both
//! write neither colour nor depth. Visibility = V / T.

use std::sync::atomic::{AtomicU8, Ordering};
use std::sync::Arc;

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3, Vec4};

use crate::render::frame::camera::Camera;
use crate::render::frame::options::RenderOptions;
use crate::render::frame::pass::{DrawItem, FrameContext, Pass, PassBuild, Phase, Pipelines, Placement, SkyUpload, Staged, Target};
use crate::render::gpu::error::RenderResult;
use crate::render::gpu::shaders;
use crate::render::gpu::textures::TextureCache;
use crate::sky::resolved::{Glare, MAX_FLARES};
use crate::sky::Rgba;

/// The glare's measured visibility and its perceived intensity (GPU-free, so it can be tested).
#[derive(Debug, Clone, PartialEq)]
pub struct GlareState {
    /// Samples of the disc passing the depth test (V).
    pub visible_samples: u64,
    /// Samples of the disc with the depth test off (T).
    pub total_samples: u64,
    /// Latest V / T, clamped to [0, 1].
    pub ratio: f32,
    /// Intensity drawn: follows `ratio` with retinal persistence.
    pub intensity: f32,
    /// Frames the latest result took to arrive.
    pub frames_waited: u32,
    /// Frames that found no result ready (cumulative, for the stats panel).
    pub frames_without_result: u64,
    /// Keep `ratio` as it is (UI toggle).
    pub frozen: bool,
    /// Whether the glare was drawn in the previous frame.
    pub drawn_last_frame: bool,
}

impl Default for GlareState {
    fn default() -> Self {
        Self { visible_samples: 0, total_samples: 0, ratio: 0.0, intensity: 0.0, frames_waited: 0, frames_without_result: 0, frozen: false, drawn_last_frame: false }
    }
}

impl GlareState {
    /// Advances one frame of `dt_s` seconds. `result` is (V, T, frames waited) when a query result
    /// arrived this frame. Intensity moves toward the ratio by at most dt / persistence x frames
    /// waited (persistence 0: instantly), and restarts from 0 if the glare was not drawn last frame.
    pub fn step(&mut self, dt_s: f32, persistence_s: f32, result: Option<(u64, u64, u32)>) {
        if !self.drawn_last_frame {
            self.intensity = 0.0;
        }
        let Some((v, t, waited)) = result else {
            self.frames_without_result += 1;
            return;
        };
        self.frames_waited = waited;
        if !self.frozen {
            self.visible_samples = v;
            self.total_samples = t;
            self.ratio = if t == 0 { 0.0 } else { (v as f64 / t as f64).clamp(0.0, 1.0) as f32 };
        }
        let max_step = if persistence_s <= 0.0 { f32::INFINITY } else { dt_s / persistence_s * waited as f32 };
        let delta = (self.ratio - self.intensity).clamp(-max_step, max_step);
        self.intensity = (self.intensity + delta).clamp(0.0, 1.0);
    }
}

/// Where the pair of occlusion queries is in its life.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum QueryPhase {
    /// No query in flight: the next frame may issue one.
    Idle,
    /// Recorded in the frame `issued_frame`, not yet submitted for readback.
    Issued {
        /// Frame number the queries were recorded in.
        issued_frame: u64,
    },
    /// Submitted; the readback buffer is being mapped.
    Mapping {
        /// Frame number the queries were recorded in.
        issued_frame: u64,
    },
}

const MAP_PENDING: u8 = 0;
const MAP_DONE: u8 = 1;
const MAP_FAILED: u8 = 2;

/// The occlusion query set and its readback, driven without ever blocking.
struct OcclusionQueries {
    set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    readback: wgpu::Buffer,
    phase: QueryPhase,
    map_state: Arc<AtomicU8>,
}

impl OcclusionQueries {
    fn new(device: &wgpu::Device) -> Self {
        Self {
            set: device.create_query_set(&wgpu::QuerySetDescriptor { label: Some("Glare::occlusion_queries"), ty: wgpu::QueryType::Occlusion, count: 2 }),
            resolve: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("Glare::query_resolve"),
                size: 16,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
            readback: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("Glare::query_readback"),
                size: 16,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            phase: QueryPhase::Idle,
            map_state: Arc::new(AtomicU8::new(MAP_PENDING)),
        }
    }

    /// A finished result, if one has arrived: (V, T, issued frame). Never blocks.
    fn try_take(&mut self, device: &wgpu::Device) -> Option<(u64, u64, u64)> {
        let QueryPhase::Mapping { issued_frame } = self.phase else { return None };
        // Lets wgpu run map callbacks of work that already finished; does not wait.
        let _ = device.poll(wgpu::PollType::Poll);
        match self.map_state.load(Ordering::Acquire) {
            MAP_DONE => {
                let values = self.readback.get_mapped_range(..).ok().map(|view| {
                    let v: [u64; 2] = bytemuck::pod_read_unaligned(&view[..16]);
                    v
                });
                self.readback.unmap();
                self.phase = QueryPhase::Idle;
                values.map(|[v, t]| (v, t, issued_frame))
            }
            MAP_FAILED => {
                self.phase = QueryPhase::Idle;
                None
            }
            _ => None,
        }
    }
}

/// Pipelines of the glare pass.
struct GlarePipelines {
    disc_visible: wgpu::RenderPipeline,
    disc_total: wgpu::RenderPipeline,
    sprite: wgpu::RenderPipeline,
}

/// The glare pass: pipelines, and the current sky's glare with its queries and state.
pub struct GlarePass {
    bind_layout: wgpu::BindGroupLayout,
    pipelines: Pipelines<GlarePipelines>,
    resources: Staged<Option<GlareResources>>,
    /// Whether the glare takes part in this frame (the sky has glare, it is switched on).
    active: bool,
    /// Whether this frame shows the steady state: the sun is hidden, or a query result arrived.
    settled: bool,
}

/// Disc placement. Keep in sync with `Disc` in shaders/glare.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
struct DiscUniform {
    sky_from_disc: [[f32; 4]; 4],
}

/// One sprite. Keep in sync with `vs_sprite` in shaders/glare.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable, PartialEq)]
pub struct SpriteInstance {
    /// Centre, NDC.
    pub centre_ndc: [f32; 2],
    /// Half size, NDC.
    pub half_size_ndc: [f32; 2],
    /// Rotation, radians.
    pub rotation: f32,
    /// Colour (premultiplied by intensity).
    pub color: [f32; 4],
}

const DISC_SEGMENTS: usize = 48;
/// Margin of the disc's cone against the frame's sides, degrees (rounding only: a pixel centre
/// always lies inside the sides).
const DISC_MARGIN_DEG: f32 = 0.5;

fn disc_vertices() -> Vec<[f32; 2]> {
    (0..DISC_SEGMENTS)
        .flat_map(|i| {
            let a0 = i as f32 / DISC_SEGMENTS as f32 * std::f32::consts::TAU;
            let a1 = (i + 1) as f32 / DISC_SEGMENTS as f32 * std::f32::consts::TAU;
            [[0.0, 0.0], [a0.cos(), a0.sin()], [a1.cos(), a1.sin()]]
        })
        .collect()
}

impl GlarePass {
    /// Builds the pipelines.
    pub fn new(b: &PassBuild<'_>) -> RenderResult<Self> {
        let (device, globals) = (b.device, b.globals_layout);
        let bind_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("Glare::layout"),
            entries: &[
                crate::render::gpu::parts::uniform_entry(0, wgpu::ShaderStages::VERTEX),
                crate::render::gpu::parts::texture_entry(1),
                crate::render::gpu::parts::sampler_entry(2),
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("Glare::pipeline_layout"),
            bind_group_layouts: &[Some(globals), Some(&bind_layout)],
            immediate_size: 0,
        });
        let pipelines = Pipelines::new_render(b, pipeline_layout, Self::build)?;
        Ok(Self { bind_layout, pipelines, resources: Staged::new(None), active: false, settled: true })
    }

    fn build(b: &PassBuild<'_>, layout: &wgpu::PipelineLayout) -> RenderResult<GlarePipelines> {
        let (device, format) = (b.device, b.color_format);
        let module = shaders::module(device, b.library, "glare")?;
        let constants = b.target_constants();
        let options = wgpu::PipelineCompilationOptions { constants: &constants, zero_initialize_workgroup_memory: true };
        let disc = |label: &'static str, compare: wgpu::CompareFunction| {
            shaders::validated(device, label, || {
                device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some(label),
                    layout: Some(layout),
                    vertex: wgpu::VertexState {
                        module: &module,
                        entry_point: Some("vs_disc"),
                        buffers: &[Some(wgpu::VertexBufferLayout {
                            array_stride: 8,
                            step_mode: wgpu::VertexStepMode::Vertex,
                            attributes: &wgpu::vertex_attr_array![0 => Float32x2],
                        })],
                        compilation_options: options.clone(),
                    },
                    primitive: wgpu::PrimitiveState { cull_mode: None, ..Default::default() },
                    depth_stencil: crate::render::gpu::parts::depth_state(false, compare),
                    multisample: Default::default(),
                    fragment: Some(wgpu::FragmentState {
                        module: &module,
                        entry_point: Some("fs_disc"),
                        targets: &[Some(wgpu::ColorTargetState { format, blend: None, write_mask: wgpu::ColorWrites::empty() })],
                        compilation_options: options.clone(),
                    }),
                    multiview_mask: None,
                    cache: None,
                })
            })
        };
        let visible = disc("Glare::disc_visible", wgpu::CompareFunction::Less)?;
        let total = disc("Glare::disc_total", wgpu::CompareFunction::Always)?;
        let sprite = shaders::validated(device, "Glare::sprite", || {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("Glare::sprite"),
                layout: Some(layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("vs_sprite"),
                    buffers: &[Some(wgpu::VertexBufferLayout {
                        array_stride: std::mem::size_of::<SpriteInstance>() as u64,
                        step_mode: wgpu::VertexStepMode::Instance,
                        attributes: &wgpu::vertex_attr_array![0 => Float32x2, 1 => Float32x2, 2 => Float32, 3 => Float32x4],
                    })],
                    compilation_options: options.clone(),
                },
                primitive: wgpu::PrimitiveState { topology: wgpu::PrimitiveTopology::TriangleStrip, cull_mode: None, ..Default::default() },
                depth_stencil: crate::render::gpu::parts::depth_state(false, wgpu::CompareFunction::Always),
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some("fs_sprite"),
                    targets: &[Some(wgpu::ColorTargetState {
                        format,
                        blend: Some(wgpu::BlendState {
                            color: wgpu::BlendComponent { src_factor: wgpu::BlendFactor::One, dst_factor: wgpu::BlendFactor::One, operation: wgpu::BlendOperation::Add },
                            alpha: wgpu::BlendComponent { src_factor: wgpu::BlendFactor::Zero, dst_factor: wgpu::BlendFactor::One, operation: wgpu::BlendOperation::Add },
                        }),
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                    compilation_options: options.clone(),
                }),
                multiview_mask: None,
                cache: None,
            })
        })?;
        Ok(GlarePipelines { disc_visible: visible, disc_total: total, sprite })
    }

    /// The current sky's glare, if it has one.
    pub fn resources(&self) -> Option<&GlareResources> {
        self.resources.current.as_ref()
    }

    /// The current sky's glare, mutable (freeze toggle).
    pub fn resources_mut(&mut self) -> Option<&mut GlareResources> {
        self.resources.current.as_mut()
    }
}

impl Pass for GlarePass {
    fn name(&self) -> &'static str {
        "glare"
    }

    fn phase(&self) -> Phase {
        Phase::Overlay
    }

    fn stage_pipelines(&mut self, b: &PassBuild<'_>) -> RenderResult<()> {
        self.pipelines.stage(b)
    }

    fn commit_pipelines(&mut self, accept: bool) {
        self.pipelines.commit(accept);
    }

    fn stage_sky(&mut self, up: &mut SkyUpload<'_>) {
        let next = up.sky.glare.as_ref().map(|g| GlareResources::new(up.device, up.queue, &self.bind_layout, up.textures, g));
        self.resources.stage(next);
    }

    fn commit_sky(&mut self, accept: bool) {
        let Some(Some(mut old)) = self.resources.commit(accept) else { return };
        // The glare survives a reload: the eye keeps its adaptation and in-flight queries still land.
        if let Some(new) = self.resources.current.as_mut() {
            std::mem::swap(&mut new.state, &mut old.state);
            std::mem::swap(&mut new.queries, &mut old.queries);
        }
    }

    fn prepare(&mut self, cx: &FrameContext<'_>) {
        self.settled = true;
        // Glare and flares belong to the camera that looks, not to the light an environment map
        // holds.
        let color = cx.frame.glare.filter(|_| cx.options.glare && !cx.frame.env_map);
        self.active = false;
        let Some(g) = self.resources.current.as_mut() else { return };
        match color {
            Some(color) => {
                let f = GlareFrame { towards_sun: cx.frame.towards_sun, color, dt_s: cx.frame.dt_s, frame: cx.frame.frame };
                let arrived = g.prepare(cx.device, cx.queue, &f, cx.camera, cx.aspect(), cx.options.skips.off_screen);
                self.active = true;
                self.settled = !g.draw_this_frame || arrived;
            }
            None => {
                g.state.drawn_last_frame = false;
                g.issue_this_frame = false;
                g.draw_this_frame = false;
            }
        }
    }

    fn items(&self, _cx: &FrameContext<'_>, out: &mut Vec<DrawItem>) {
        // Nothing to query nor draw (the disc out of the frame, the glare faded): no pass.
        if self.active && self.resources.current.as_ref().is_some_and(GlareResources::has_work) {
            out.push(DrawItem::new(0, 0));
        }
    }

    fn draw(&self, rpass: &mut wgpu::RenderPass<'_>, _key: usize, target: Target, _placement: Placement, _run: Option<&wgpu::BindGroup>) -> u32 {
        self.resources.current.as_ref().map_or(0, |g| g.draw(rpass, self.pipelines.for_target(target)))
    }

    fn occlusion_query_set(&self) -> Option<&wgpu::QuerySet> {
        self.resources.current.as_ref().filter(|_| self.active).map(|g| &g.queries.set)
    }

    fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        if let (true, Some(g)) = (self.active, &self.resources.current) {
            g.resolve(encoder);
        }
    }

    fn after_submit(&mut self) {
        if let Some(g) = self.resources.current.as_mut() {
            g.after_submit();
        }
    }

    fn settle_dt_s(&self, options: &RenderOptions) -> Option<f32> {
        self.resources.current.as_ref().filter(|_| options.glare).map(|g| g.settings.persistence_s.max(1e-3))
    }

    fn settled(&self) -> bool {
        self.settled
    }
}

/// Per-sky glare resources, the query pair and the glare state.
pub struct GlareResources {
    settings: Glare,
    disc_uniform: wgpu::Buffer,
    disc_vertices: wgpu::Buffer,
    /// Bind group per sprite texture: [halo, flare 0, ...].
    bind_groups: Vec<wgpu::BindGroup>,
    sprites: wgpu::Buffer,
    sprite_count: u32,
    queries: OcclusionQueries,
    issue_this_frame: bool,
    draw_this_frame: bool,
    /// Visibility and intensity (shown in the UI).
    pub state: GlareState,
}

/// What the glare pass needs to know about a frame.
#[derive(Debug, Clone, Copy)]
pub struct GlareFrame {
    /// Unit vector towards the sun.
    pub towards_sun: Vec3,
    /// Glare colour (alpha scales it).
    pub color: Rgba,
    /// Seconds since the previous frame.
    pub dt_s: f32,
    /// Frame number.
    pub frame: u64,
}

impl GlareResources {
    /// Uploads the glare of a sky.
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue, layout: &wgpu::BindGroupLayout, cache: &mut TextureCache, glare: &Glare) -> Self {
        use wgpu::util::DeviceExt;
        let disc_uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("Glare::disc_uniform"),
            size: std::mem::size_of::<DiscUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let disc_vertices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("Glare::disc_vertices"),
            contents: bytemuck::cast_slice(&disc_vertices()),
            usage: wgpu::BufferUsages::VERTEX,
        });
        let bind_groups = std::iter::once(&glare.halo)
            .chain(glare.flares.iter().map(|f| &f.texture))
            .map(|img| {
                let view = cache.get(device, queue, img);
                device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("Glare::bind_group"),
                    layout,
                    entries: &[
                        wgpu::BindGroupEntry { binding: 0, resource: disc_uniform.as_entire_binding() },
                        wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(&view) },
                        wgpu::BindGroupEntry { binding: 2, resource: wgpu::BindingResource::Sampler(&cache.clamp) },
                    ],
                })
            })
            .collect();
        let sprites = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("Glare::sprites"),
            size: (std::mem::size_of::<SpriteInstance>() * (MAX_FLARES + 1)) as u64,
            usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Self {
            settings: glare.clone(),
            disc_uniform,
            disc_vertices,
            bind_groups,
            sprites,
            sprite_count: 0,
            queries: OcclusionQueries::new(device),
            issue_this_frame: false,
            draw_this_frame: false,
            state: GlareState::default(),
        }
    }

    /// Phase of the query pair.
    pub fn query_phase(&self) -> &QueryPhase {
        &self.queries.phase
    }

    /// Collects any finished result, updates the intensity and prepares this frame's draws.
    /// `skip_off_screen`: while the sun's disc lies wholly outside the frame and no query is in
    /// flight, the result both queries would give (no sample either way) stands for them.
    /// Returns whether a query result arrived.
    pub fn prepare(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, f: &GlareFrame, camera: &Camera, aspect: f32, skip_off_screen: bool) -> bool {
        let (_, clip_from_sky) = camera.matrices(aspect);
        let clip = clip_from_sky * f.towards_sun.extend(1.0);
        let in_front = clip.w > 1e-4;
        let visible = in_front && f.color[3] > 0.5 / 255.0;
        // The disc (inscribed in a circle disc_size / 2 from the sun) covers no pixel centre when
        // its circle lies wholly outside the frame's sides, which pass outside every centre.
        let disc_off_screen = skip_off_screen && !camera.sees_cone(aspect, f.towards_sun, self.settings.disc_size_deg * 0.5 + DISC_MARGIN_DEG);

        let mut result = self.queries.try_take(device).map(|(v, t, issued)| (v, t, (f.frame.saturating_sub(issued)).max(1) as u32));
        let known = visible && disc_off_screen && result.is_none() && self.queries.phase == QueryPhase::Idle;
        if known {
            result = Some((0, 0, 1));
        }
        let arrived = result.is_some();
        self.state.step(f.dt_s, self.settings.persistence_s, result);
        // A new query only when none is in flight: NeL's rule, and the reason frames are counted.
        self.issue_this_frame = visible && !disc_off_screen && self.queries.phase == QueryPhase::Idle;
        if self.issue_this_frame {
            self.queries.phase = QueryPhase::Issued { issued_frame: f.frame };
        }
        self.draw_this_frame = visible;
        self.state.drawn_last_frame = visible;

        let sun = f.towards_sun;
        let right = sun.cross(Vec3::Y).try_normalize().unwrap_or(Vec3::X);
        let up = right.cross(sun);
        let half = (self.settings.disc_size_deg.to_radians() * 0.5).tan();
        let m = Mat4::from_cols((right * half).extend(0.0), (up * half).extend(0.0), sun.extend(0.0), Vec4::W);
        queue.write_buffer(&self.disc_uniform, 0, bytemuck::bytes_of(&DiscUniform { sky_from_disc: m.to_cols_array_2d() }));

        if !visible {
            self.sprite_count = 0;
            return arrived;
        }
        let sprites = self.sprites(Vec3::new(clip.x / clip.w, clip.y / clip.w, 0.0), f.color, camera, aspect);
        self.sprite_count = sprites.len() as u32;
        queue.write_buffer(&self.sprites, 0, bytemuck::cast_slice(&sprites));
        arrived
    }

    /// Whether this frame has queries to issue or sprites to draw.
    fn has_work(&self) -> bool {
        self.issue_this_frame || (self.draw_this_frame && self.state.intensity > 0.0 && self.sprite_count > 0)
    }

    fn sprites(&self, sun_ndc: Vec3, color: Rgba, camera: &Camera, aspect: f32) -> Vec<SpriteInstance> {
        let g = &self.settings;
        let i = self.state.intensity;
        let lost = 1.0 - i;
        let scale = if g.shrink { i } else { 1.0 };
        let tint = |t: Rgba| [color[0] * t[0] * color[3] * t[3] * i, color[1] * t[1] * color[3] * t[3] * i, color[2] * t[2] * color[3] * t[3] * i, 1.0];
        let fov_half_tan = (camera.fov_y_deg.to_radians() * 0.5).tan();
        let halo_half = (g.halo_size_deg.to_radians() * 0.5).tan() / fov_half_tan * scale;
        let mut out = vec![SpriteInstance { centre_ndc: [sun_ndc.x, sun_ndc.y], half_size_ndc: [halo_half / aspect, halo_half], rotation: 0.0, color: tint([1.0; 4]) }];
        for f in &g.flares {
            let p = sun_ndc * (1.0 - f.position);
            let half = f.size * scale;
            out.push(SpriteInstance { centre_ndc: [p.x, p.y], half_size_ndc: [half / aspect, half], rotation: g.rotate * lost, color: tint(f.tint) });
        }
        out
    }

    /// Records the occlusion queries (if one is due) and the sprites. Needs a pass created with
    /// this resource's query set. Returns draw calls.
    fn draw(&self, rpass: &mut wgpu::RenderPass<'_>, pass: &GlarePipelines) -> u32 {
        let mut calls = 0;
        if self.issue_this_frame {
            rpass.set_bind_group(1, &self.bind_groups[0], &[]);
            rpass.set_vertex_buffer(0, self.disc_vertices.slice(..));
            for (index, pipeline) in [(0, &pass.disc_visible), (1, &pass.disc_total)] {
                rpass.set_pipeline(pipeline);
                rpass.begin_occlusion_query(index);
                rpass.draw(0..(DISC_SEGMENTS * 3) as u32, 0..1);
                rpass.end_occlusion_query();
                calls += 1;
            }
        }
        if self.draw_this_frame && self.state.intensity > 0.0 {
            rpass.set_pipeline(&pass.sprite);
            rpass.set_vertex_buffer(0, self.sprites.slice(..));
            for k in 0..self.sprite_count {
                rpass.set_bind_group(1, &self.bind_groups[k as usize], &[]);
                rpass.draw(0..4, k..k + 1);
                calls += 1;
            }
        }
        calls
    }

    /// After the glare pass: resolve the queries into the readback buffer.
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        if self.issue_this_frame {
            encoder.resolve_query_set(&self.queries.set, 0..2, &self.queries.resolve, 0);
            encoder.copy_buffer_to_buffer(&self.queries.resolve, 0, &self.queries.readback, 0, 16);
        }
    }

    /// After submitting the frame: start mapping the readback buffer (completes asynchronously).
    pub fn after_submit(&mut self) {
        if let QueryPhase::Issued { issued_frame } = self.queries.phase {
            let state = self.queries.map_state.clone();
            state.store(MAP_PENDING, Ordering::Release);
            self.queries.readback.map_async(wgpu::MapMode::Read, .., move |r| {
                state.store(if r.is_ok() { MAP_DONE } else { MAP_FAILED }, Ordering::Release);
            });
            self.queries.phase = QueryPhase::Mapping { issued_frame };
        }
    }
}
