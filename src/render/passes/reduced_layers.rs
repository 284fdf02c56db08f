//! Dome layers at reduced resolution (trueSKY's mixed-resolution rendering, see
//! ../shared/references/truesky-rendering-techniques.txt): a run of consecutive dome draws of the
//! sky phase is drawn into a buffer [`Divisor`] times smaller on each side, holding premultiplied
//! colour and the run's transmittance, and composited over the frame in the run's place with one
//! full-screen triangle (`shaders/reduced_layers.wgsl`). Billboards, stars and particles stay at
//! full resolution. Dome layers are smooth gradients and soft clouds: on a software rasteriser
//! their fill is most of a frame's cost, and a quarter of the pixels costs about a quarter.

use bytemuck::{Pod, Zeroable};

use crate::render::frame::pass::{FrameContext, Pass, PassBuild, Phase, Pipelines, Placement, Target};
use crate::render::gpu::error::RenderResult;
use crate::render::gpu::shaders;
use crate::render::plan::resolution::Divisor;

/// Format of the reduced buffers for a target: premultiplied colour and transmittance. Display
/// values fit in 8 bits like the display target itself (which clamps every blend the same way);
/// exposed radiance goes above 1 and needs half floats. On lavapipe an 8-bit buffer is cheaper to
/// blend into and to sample: a run's composite costs about a millisecond less at 1280x720.
pub fn reduced_format(target: Target) -> wgpu::TextureFormat {
    match target {
        Target::Display => wgpu::TextureFormat::Rgba8Unorm,
        Target::Hdr => wgpu::TextureFormat::Rgba16Float,
    }
}

/// How each blend mode of a dome layer accumulates into a reduced buffer (cleared to colour 0,
/// transmittance 1): colour as on the frame, transmittance multiplied by what the layer lets
/// through. Indexed like the sky objects' blend modes (opaque, alpha, additive).
pub const REDUCED_BLENDS: [wgpu::BlendState; 3] = [
    wgpu::BlendState {
        color: wgpu::BlendComponent { src_factor: wgpu::BlendFactor::One, dst_factor: wgpu::BlendFactor::Zero, operation: wgpu::BlendOperation::Add },
        alpha: wgpu::BlendComponent { src_factor: wgpu::BlendFactor::Zero, dst_factor: wgpu::BlendFactor::Zero, operation: wgpu::BlendOperation::Add },
    },
    wgpu::BlendState {
        color: wgpu::BlendComponent { src_factor: wgpu::BlendFactor::SrcAlpha, dst_factor: wgpu::BlendFactor::OneMinusSrcAlpha, operation: wgpu::BlendOperation::Add },
        alpha: wgpu::BlendComponent { src_factor: wgpu::BlendFactor::Zero, dst_factor: wgpu::BlendFactor::OneMinusSrcAlpha, operation: wgpu::BlendOperation::Add },
    },
    wgpu::BlendState {
        color: wgpu::BlendComponent { src_factor: wgpu::BlendFactor::SrcAlpha, dst_factor: wgpu::BlendFactor::One, operation: wgpu::BlendOperation::Add },
        alpha: wgpu::BlendComponent { src_factor: wgpu::BlendFactor::Zero, dst_factor: wgpu::BlendFactor::One, operation: wgpu::BlendOperation::Add },
    },
];

/// The composite's blend: target = colour + transmittance x target; the target's alpha is kept.
const COMPOSITE_BLEND: wgpu::BlendState = wgpu::BlendState {
    color: wgpu::BlendComponent { src_factor: wgpu::BlendFactor::One, dst_factor: wgpu::BlendFactor::SrcAlpha, operation: wgpu::BlendOperation::Add },
    alpha: wgpu::BlendComponent { src_factor: wgpu::BlendFactor::Zero, dst_factor: wgpu::BlendFactor::One, operation: wgpu::BlendOperation::Add },
};

/// The blend of a buffer composited into a run's buffer ([`ReducedLayersPass::composite_own`]):
/// colour + transmittance x the run's colour, and the transmittances multiplied, as the layers
/// in that buffer would have left the run's buffer drawn there.
const INTO_RUN_BLEND: wgpu::BlendState = wgpu::BlendState {
    color: wgpu::BlendComponent { src_factor: wgpu::BlendFactor::One, dst_factor: wgpu::BlendFactor::SrcAlpha, operation: wgpu::BlendOperation::Add },
    alpha: wgpu::BlendComponent { src_factor: wgpu::BlendFactor::Zero, dst_factor: wgpu::BlendFactor::SrcAlpha, operation: wgpu::BlendOperation::Add },
};

/// Indices of [`ReducedLayersPass`]'s composite pipelines.
const COMPOSITE: usize = 0;
const BACKGROUND: usize = 1;
const BACKGROUND_OVER: usize = 2;
const JOINED_BACKGROUND_OVER: usize = 3;

/// The composite's uniform. Keep in sync with `Composite` in shaders/reduced/run.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
struct CompositeUniform {
    /// Pixel to texture coordinates (every buffer holds the whole frame): xy, of a frame pixel
    /// (1 / frame size); zw, of a pixel of the seeded buffer (1 / its size), for its first layer
    /// drawn over the seed (`Placement::OverSeed`).
    uv_from_pixel: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<CompositeUniform>() == 16);

/// How a frame's joined runs come together in the background's buffer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Joining<'a> {
    /// Combination j of the joined runs at divisor `[j]`, each in a pass of its own (none: the
    /// runs are not joined).
    Combined(&'a [Divisor]),
    /// The first two runs, the second's buffer seeded with the first ([`ReducedLayersPass::seed`]);
    /// the runs above them, if any, combined over the seeded buffer: combination j at divisor
    /// `[j]` holds runs j + 1 and above (the first of them over the seeded buffer).
    Seeded(&'a [Divisor]),
}

/// One run's buffer, its divisor and the bind group that reads it.
struct RunBuffer {
    view: wgpu::TextureView,
    bind_group: wgpu::BindGroup,
    divisor: Divisor,
    /// Whether `bind_group` reads the buffer of the run below as `run_lower` (the buffer was seeded
    /// with it: [`ReducedLayersPass::seed`]); else that binding is black.
    reads_lower: bool,
}

/// The lower run of a seeded frame as exposed radiance ([`ReducedLayersPass::convert_seed`]).
struct SeedRadiance {
    view: wgpu::TextureView,
    /// Reads the lower run (`run_layers`) and its radiance (`run_lower`).
    bind_group: wgpu::BindGroup,
    /// The lower run's divisor it was made at.
    divisor: Divisor,
}

/// Format of the lower run's radiance ([`ReducedLayersPass::convert_seed`]): exposed radiance
/// goes above 1.
const SEED_RADIANCE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// The reduced buffers of a frame size and the composite pipelines.
pub struct ReducedLayersPass {
    layout: wgpu::BindGroupLayout,
    /// The composite (blended over the frame, depth-tested); the background (the first run of
    /// a frame, drawn before the scene: replacing the clear, neither blended nor tested); and the
    /// background over additive draws already on the frame (blended, not tested), of one run and
    /// of the joined runs (whose combination holds the transmittance of those above the first).
    pipelines: Pipelines<[wgpu::RenderPipeline; 4]>,
    /// Combines two runs into one buffer, the upper over the lower (runs joined across the
    /// billboards between them: [`ReducedLayersPass::record_combined`]): the background's
    /// combination (keeping the upper's transmittance) and one above it (the product); and the
    /// seed of an upper run's buffer with the lower run ([`ReducedLayersPass::seed`]); and the
    /// composite of a layer's own buffer into its run's ([`ReducedLayersPass::composite_own`]).
    combine: Pipelines<[wgpu::RenderPipeline; 4]>,
    /// Bound as `run_lower` where a buffer was not seeded: black, so nothing is taken off.
    black: wgpu::TextureView,
    /// The composite's uniform (frame pixel to texture coordinates, any divisor).
    uniform: wgpu::Buffer,
    sampler: wgpu::Sampler,
    /// Frame size and target the buffers are made for.
    made_for: ((u32, u32), Target),
    /// Per run of a frame; reused while the size, target and run's divisor stay.
    buffers: Vec<RunBuffer>,
    /// When the frame joins its first runs: combination j holds runs j and above (up to the
    /// last joined, which needs none), at the finest divisor among them; when seeded, runs
    /// j + 1 and above, run 1's buffer holding run 0 too.
    combined: Vec<RunBuffer>,
    /// This frame joins its first two runs by seeding the upper's buffer with the lower: the
    /// upper's buffer ends as their combination (the background's, with no runs above them).
    seeded: bool,
    /// The buffers of layers drawn apart from their runs (`RunInput::Own` in the frame plan).
    own: Vec<RunBuffer>,
    /// Takes the lower run of a seeded frame back to exposed radiance ([`Self::convert_seed`]).
    seed_radiance_pipeline: Pipelines<wgpu::RenderPipeline>,
    /// The lower run's radiance, when this frame converts it, and the bind group that reads the
    /// lower run with it as `run_lower` (the seed source then).
    seed_radiance: Option<SeedRadiance>,
    /// What the composite uniform holds.
    uniform_written: CompositeUniform,
}

impl ReducedLayersPass {
    /// Builds the layouts and pipelines; buffers come with the first frame that needs them.
    pub fn new(b: &PassBuild<'_>) -> RenderResult<Self> {
        let device = b.device;
        let layout = run_layout(device, "ReducedLayers::layout");
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("ReducedLayers::pipeline_layout"),
            bind_group_layouts: &[Some(b.globals_layout), Some(&layout)],
            immediate_size: 0,
        });
        let pipelines = Pipelines::new_render(b, pipeline_layout.clone(), Self::build)?;
        // Only display-referred frames convert their seed.
        let seed_radiance_pipeline = Pipelines::new(b, pipeline_layout, |b, layout| {
            let module = shaders::module(b.device, b.library, "reduced_layers")?;
            shaders::fullscreen_pipeline_of(b.device, &module, "fs_seed_radiance", layout, "ReducedLayers::seed_radiance_pipeline", SEED_RADIANCE_FORMAT, None)
        })?;
        // Two runs read at once (group 1 the lower, group 2 the upper).
        let pair_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("ReducedLayers::pair_pipeline_layout"),
            bind_group_layouts: &[Some(b.globals_layout), Some(&layout), Some(&layout)],
            immediate_size: 0,
        });
        let combine = Pipelines::new_render(b, pair_layout, Self::build_combine)?;
        let uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("ReducedLayers::uniform"),
            size: std::mem::size_of::<CompositeUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("ReducedLayers::sampler"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        // Never written: wgpu clears it to zero.
        let black = crate::render::gpu::textures::unused_view(device, "ReducedLayers::black");
        Ok(Self {
            layout,
            pipelines,
            combine,
            black,
            uniform,
            sampler,
            made_for: ((0, 0), Target::Display),
            buffers: Vec::new(),
            combined: Vec::new(),
            seeded: false,
            own: Vec::new(),
            seed_radiance_pipeline,
            seed_radiance: None,
            uniform_written: CompositeUniform { uv_from_pixel: [0.0; 4] },
        })
    }

    fn build(b: &PassBuild<'_>, layout: &wgpu::PipelineLayout) -> RenderResult<[wgpu::RenderPipeline; 4]> {
        let module = shaders::module(b.device, b.library, "reduced_layers")?;
        let always = wgpu::CompareFunction::Always;
        // In the order of COMPOSITE, BACKGROUND, BACKGROUND_OVER and JOINED_BACKGROUND_OVER.
        Ok([
            full_screen_pipeline(b, layout, &module, "ReducedLayers::pipeline", "fs_main", Some(COMPOSITE_BLEND), wgpu::CompareFunction::Less)?,
            full_screen_pipeline(b, layout, &module, "ReducedLayers::background_pipeline", "fs_background", None, always)?,
            // Over what the frame holds: a run's own transmittance is not what lies under it.
            full_screen_pipeline(b, layout, &module, "ReducedLayers::background_over_pipeline", "fs_background", Some(COMPOSITE_BLEND), always)?,
            full_screen_pipeline(b, layout, &module, "ReducedLayers::joined_background_over_pipeline", "fs_main", Some(COMPOSITE_BLEND), always)?,
        ])
    }

    fn build_combine(b: &PassBuild<'_>, layout: &wgpu::PipelineLayout) -> RenderResult<[wgpu::RenderPipeline; 4]> {
        let module = shaders::module(b.device, b.library, "reduced_layers")?;
        let format = reduced_format(b.target);
        Ok([
            shaders::fullscreen_pipeline_of(b.device, &module, "fs_combine", layout, "ReducedLayers::combine_pipeline", format, None)?,
            shaders::fullscreen_pipeline_of(b.device, &module, "fs_combine_above", layout, "ReducedLayers::combine_above_pipeline", format, None)?,
            // The lower run's colour, transmittance 1: what the upper run's layers then go over.
            shaders::fullscreen_pipeline_of(b.device, &module, "fs_background", layout, "ReducedLayers::seed_pipeline", format, None)?,
            shaders::fullscreen_pipeline_of(b.device, &module, "fs_main", layout, "ReducedLayers::into_run_pipeline", format, Some(INTO_RUN_BLEND))?,
        ])
    }

    /// Makes sure the frame's runs have buffers: run `r` at `divisors[r]`, how the joined runs
    /// are combined (`joining`), the buffers of layers drawn apart from their runs (`own`), and
    /// whether a seeded frame's lower run is taken back to radiance (`seed_radiance`), for the
    /// frame size and target.
    pub fn ensure(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        (size, target): ((u32, u32), Target),
        divisors: &[Divisor],
        (joining, seed_radiance): (Joining<'_>, bool),
        own: &[Divisor],
    ) {
        let (combined, seeded) = match joining {
            Joining::Combined(divisors) => (divisors, false),
            Joining::Seeded(divisors) => (divisors, true),
        };
        if self.made_for != (size, target) {
            self.buffers.clear();
            self.combined.clear();
            self.own.clear();
            self.seed_radiance = None;
            self.made_for = (size, target);
        }
        // Each buffer holds the whole frame (its viewport is the whole buffer, even where the
        // frame's size is not a multiple of the divisor): texture coordinates are the frame's.
        let seeded_size = divisors.get(1).filter(|_| seeded).map_or((1, 1), |&d| d.buffer_size(size));
        let u = CompositeUniform { uv_from_pixel: [1.0 / size.0.max(1) as f32, 1.0 / size.1.max(1) as f32, 1.0 / seeded_size.0 as f32, 1.0 / seeded_size.1 as f32] };
        if u.uv_from_pixel != self.uniform_written.uv_from_pixel {
            queue.write_buffer(&self.uniform, 0, bytemuck::bytes_of(&u));
            self.uniform_written = u;
        }
        let mut buffers = std::mem::take(&mut self.buffers);
        let first_changed = self.fit(device, &mut buffers, "ReducedLayers::buffer", divisors);
        // The second buffer reads the first as `run_lower` when seeded with it (its bind group
        // made again when either changes), else black.
        if let [lower, upper, ..] = buffers.as_mut_slice() {
            if upper.reads_lower != seeded || (seeded && first_changed) {
                upper.bind_group = self.bind_group(device, "ReducedLayers::buffer 1", &upper.view, seeded.then_some(&lower.view));
                upper.reads_lower = seeded;
            }
        }
        self.buffers = buffers;
        self.seeded = seeded && self.buffers.len() >= 2;
        let lower = self.buffers.first().filter(|_| self.seeded && seed_radiance);
        self.seed_radiance = match (lower, self.seed_radiance.take()) {
            (Some(lower), Some(kept)) if kept.divisor == lower.divisor && !first_changed => Some(kept),
            (Some(lower), _) => Some(self.seed_radiance_of(device, lower)),
            (None, _) => None,
        };
        // Only the frame's combinations: their count is the chain's length.
        let mut combinations = std::mem::take(&mut self.combined);
        combinations.truncate(combined.len());
        self.fit(device, &mut combinations, "ReducedLayers::combined", combined);
        self.combined = combinations;
        let mut apart = std::mem::take(&mut self.own);
        apart.truncate(own.len());
        self.fit(device, &mut apart, "ReducedLayers::own", own);
        self.own = apart;
    }

    /// Makes `list[k]` a buffer at `divisors[k]` for every k, keeping those already at theirs;
    /// returns whether the first was made anew.
    fn fit(&self, device: &wgpu::Device, list: &mut Vec<RunBuffer>, label: &str, divisors: &[Divisor]) -> bool {
        let mut first_changed = false;
        for (k, &divisor) in divisors.iter().enumerate() {
            if list.get(k).is_some_and(|b| b.divisor == divisor) {
                continue;
            }
            first_changed |= k == 0;
            let buffer = self.buffer(device, &format!("{label} {k}"), divisor);
            if k < list.len() {
                list[k] = buffer;
            } else {
                list.push(buffer);
            }
        }
        first_changed
    }

    /// A buffer of the whole frame at `divisor`, with the bind group that reads it.
    fn buffer(&self, device: &wgpu::Device, label: &str, divisor: Divisor) -> RunBuffer {
        let view = self.texture(device, label, divisor, reduced_format(self.made_for.1));
        let bind_group = self.bind_group(device, label, &view, None);
        RunBuffer { view, bind_group, divisor, reads_lower: false }
    }

    /// A texture of the whole frame at `divisor` in `format`, drawn into and sampled.
    fn texture(&self, device: &wgpu::Device, label: &str, divisor: Divisor, format: wgpu::TextureFormat) -> wgpu::TextureView {
        let (width, height) = divisor.buffer_size(self.made_for.0);
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        texture.create_view(&Default::default())
    }

    /// The bind group that reads buffer `view` ([`run_layout`]), with the buffer of the run
    /// below it as `run_lower` where seeded with it (else black).
    fn bind_group(&self, device: &wgpu::Device, label: &str, view: &wgpu::TextureView, lower: Option<&wgpu::TextureView>) -> wgpu::BindGroup {
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(&format!("{label}::bind_group")),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: self.uniform.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(view) },
                wgpu::BindGroupEntry { binding: 2, resource: wgpu::BindingResource::Sampler(&self.sampler) },
                wgpu::BindGroupEntry { binding: 3, resource: wgpu::BindingResource::TextureView(lower.unwrap_or(&self.black)) },
            ],
        })
    }

    /// Starts run 1's pass of a seeded frame ([`Self::ensure`]): its buffer takes run 0's colour
    /// (upsampled where finer), transmittance 1, in place of nothing in front, so that the run's
    /// layers going over it leave C1 + T1 C0 and T1, the two runs' combination, in one pass less
    /// than combining them afterwards (which reads both buffers). Draws between the runs, which
    /// need run 1's own colour, take C0 off again (`run_alone_at` in shaders/reduced/run.wgsl).
    pub fn seed(&self, rpass: &mut wgpu::RenderPass<'_>, globals: &wgpu::BindGroup, target: Target) -> u32 {
        let Some(lower) = self.buffers.first().filter(|_| self.seeded) else { return 0 };
        let [_, _, seed, _] = self.combine.for_target(target);
        rpass.set_pipeline(seed);
        rpass.set_bind_group(0, globals, &[]);
        rpass.set_bind_group(1, &lower.bind_group, &[]);
        // Not read; the layout has the group.
        rpass.set_bind_group(2, &lower.bind_group, &[]);
        rpass.draw(0..3, 0..1);
        1
    }

    /// The lower run's bind group, which a seeded buffer's first layer reads as group 2 when it
    /// is drawn over the seed itself ([`crate::render::frame::pass::Placement::OverSeed`]), with
    /// its radiance as `run_lower` where this frame converts it; None unless seeded.
    pub fn seed_source(&self) -> Option<&wgpu::BindGroup> {
        let lower = self.buffers.first().filter(|_| self.seeded)?;
        Some(self.seed_radiance.as_ref().map_or(&lower.bind_group, |r| &r.bind_group))
    }

    /// The radiance texture for the lower run's buffer `lower`, and the bind group that reads both.
    fn seed_radiance_of(&self, device: &wgpu::Device, lower: &RunBuffer) -> SeedRadiance {
        let view = self.texture(device, "ReducedLayers::seed_radiance", lower.divisor, SEED_RADIANCE_FORMAT);
        let bind_group = self.bind_group(device, "ReducedLayers::seed_radiance", &lower.view, Some(&view));
        SeedRadiance { view, bind_group, divisor: lower.divisor }
    }

    /// Between a seeded frame's two runs, where [`Self::ensure`] was asked to: the lower run's
    /// colour taken back to exposed radiance at its own resolution, which the seeded buffer's
    /// first layer then blends over (`run_radiance_at_seeded` in shaders/reduced/run.wgsl)
    /// instead of taking each of its finer pixels back itself. Returns the draws.
    pub fn convert_seed(&self, encoder: &mut wgpu::CommandEncoder, globals: &wgpu::BindGroup) -> u32 {
        let (Some(radiance), Some(lower)) = (&self.seed_radiance, self.buffers.first()) else { return 0 };
        // Every texel is written: the clear colour does not matter.
        let mut rpass = self.begin_into(encoder, (&radiance.view, lower.divisor), "ReducedLayers::seed_radiance", None);
        rpass.set_pipeline(self.seed_radiance_pipeline.get());
        rpass.set_bind_group(0, globals, &[]);
        rpass.set_bind_group(1, &lower.bind_group, &[]);
        rpass.draw(0..3, 0..1);
        1
    }

    /// [`Self::seed`] confined to the buffer pixels under frame pixels `[x, y, width, height]`
    /// (rounded outwards): where the first layer drawn over the seed does not reach.
    pub fn seed_within(&self, rpass: &mut wgpu::RenderPass<'_>, globals: &wgpu::BindGroup, target: Target, gap: [u32; 4]) -> u32 {
        let Some(upper) = self.buffers.get(1) else { return 0 };
        let (bw, bh) = upper.divisor.buffer_size(self.made_for.0);
        let Some([x0, y0, w, h]) = self.buffer_rect(upper.divisor, gap) else { return 0 };
        rpass.set_scissor_rect(x0, y0, w, h);
        let n = self.seed(rpass, globals, target);
        rpass.set_scissor_rect(0, 0, bw, bh);
        n
    }

    /// Records the combinations of the joined runs into their buffers ([`Self::ensure`]), from
    /// the top down: combination j is run j under combination j + 1 (or under the last joined
    /// run); seeded, run j + 1 (the first: the seeded buffer, run 0 in it). One full-screen pass
    /// at reduced resolution each, where the background would sample every buffer at every frame
    /// pixel; the last one recorded gets `timestamp_writes`.
    pub fn record_combined(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        globals: &wgpu::BindGroup,
        target: Target,
        mut timestamp_writes: Option<wgpu::RenderPassTimestampWrites<'_>>,
    ) -> u32 {
        let [background, above, _, _] = self.combine.for_target(target);
        let below = usize::from(self.seeded);
        let mut draws = 0;
        for (j, out) in self.combined.iter().enumerate().rev() {
            let (Some(lower), Some(upper)) = (self.buffers.get(j + below), self.upper_bind_group(j + below + 1)) else { return draws };
            // Every pixel is written: the clear colour does not matter.
            let mut rpass = self.begin_into(encoder, (&out.view, out.divisor), "ReducedLayers::combine", if j == 0 { timestamp_writes.take() } else { None });
            // The background's combination keeps the transmittance of the runs above the first
            // (what the draws under the background go under): the upper's alone, or seeded, the
            // seeded buffer's (run 1's) times the upper's.
            rpass.set_pipeline(if j == 0 && !self.seeded { background } else { above });
            rpass.set_bind_group(0, globals, &[]);
            rpass.set_bind_group(1, &lower.bind_group, &[]);
            rpass.set_bind_group(2, upper, &[]);
            rpass.draw(0..3, 0..1);
            draws += 1;
        }
        draws
    }

    /// What lies above the draws between joined runs j - 1 and j: combination j, or run j's
    /// buffer when it is the last joined ([`run_layout`]). Draws there go under it.
    pub fn upper_bind_group(&self, j: usize) -> Option<&wgpu::BindGroup> {
        // Seeded, run 1's buffer holds the combination (for the background) and reads run 0 to
        // take it off (for the draws between them).
        if self.seeded && self.combined.is_empty() {
            return self.buffers.get(1).filter(|_| j <= 1).map(|b| &b.bind_group);
        }
        // Seeded under combinations: the background reads combination 0; nothing lies between
        // runs 0 and 1 (the plan seeds such a chain only where they touch); above, combination
        // j - 1 holds runs j and above.
        let j = match (self.seeded, j) {
            (false, j) | (true, j @ 0) => j,
            (true, 1) => return None,
            (true, j) => j - 1,
        };
        let top = self.combined.len() + usize::from(self.seeded);
        match self.combined.get(j) {
            Some(c) => Some(&c.bind_group),
            None if j == self.combined.len() => self.buffers.get(top).map(|b| &b.bind_group),
            None => None,
        }
    }

    /// Begins the render pass that draws a layer into own buffer `p` (cleared to nothing in
    /// front), before the pass of the run it belongs to.
    pub fn begin_own<'e>(&self, encoder: &'e mut wgpu::CommandEncoder, p: usize, timestamp_writes: Option<wgpu::RenderPassTimestampWrites<'_>>) -> Option<wgpu::RenderPass<'e>> {
        Some(self.begin_into(encoder, self.own.get(p).map(|b| (&b.view, b.divisor))?, "ReducedLayers::own", timestamp_writes))
    }

    /// Composites own buffer `p` into the run's buffer whose pass `rpass` is, in the place of the
    /// layer drawn into it: one full-screen triangle, upsampled bilinearly, blended as the
    /// layer's own blend would have left the run's buffer ([`INTO_RUN_BLEND`]), confined to the
    /// buffer pixels under frame pixels `covers` where given. The caller sets the bind groups of
    /// the run's next draw again.
    pub fn composite_own(&self, rpass: &mut wgpu::RenderPass<'_>, globals: &wgpu::BindGroup, target: Target, (p, covers): (usize, Option<[u32; 4]>), run: Divisor) -> u32 {
        let Some(own) = self.own.get(p) else { return 0 };
        let (bw, bh) = run.buffer_size(self.made_for.0);
        let Some([x, y, w, h]) = covers.map_or(Some([0, 0, bw, bh]), |c| self.buffer_rect(run, c)) else { return 0 };
        let [_, _, _, into_run] = self.combine.for_target(target);
        rpass.set_pipeline(into_run);
        rpass.set_bind_group(0, globals, &[]);
        rpass.set_bind_group(1, &own.bind_group, &[]);
        // Not read; the layout has the group.
        rpass.set_bind_group(2, &own.bind_group, &[]);
        rpass.set_scissor_rect(x, y, w, h);
        rpass.draw(0..3, 0..1);
        rpass.set_scissor_rect(0, 0, bw, bh);
        1
    }

    /// The pixels of a buffer at `divisor` under frame pixels `[x, y, width, height]` (rounded
    /// outwards), as a scissor rectangle; None when empty.
    fn buffer_rect(&self, divisor: Divisor, [x, y, w, h]: [u32; 4]) -> Option<[u32; 4]> {
        let (bw, bh) = divisor.buffer_size(self.made_for.0);
        let (fw, fh) = self.made_for.0;
        // Buffer pixel b covers frame pixels [b fw / bw, (b + 1) fw / bw).
        let lo = |p: u32, frame: u32, buffer: u32| (u64::from(p) * u64::from(buffer) / u64::from(frame.max(1))) as u32;
        let hi = |p: u32, frame: u32, buffer: u32| (u64::from(p) * u64::from(buffer)).div_ceil(u64::from(frame.max(1))) as u32;
        let (x0, y0) = (lo(x, fw, bw).min(bw), lo(y, fh, bh).min(bh));
        let (x1, y1) = (hi(x + w, fw, bw).min(bw), hi(y + h, fh, bh).min(bh));
        (x1 > x0 && y1 > y0).then_some([x0, y0, x1 - x0, y1 - y0])
    }

    /// Begins the render pass that draws run `run` into its buffer (cleared to nothing in front:
    /// colour 0, transmittance 1), its viewport the whole buffer.
    pub fn begin<'e>(&self, encoder: &'e mut wgpu::CommandEncoder, run: usize, timestamp_writes: Option<wgpu::RenderPassTimestampWrites<'_>>) -> Option<wgpu::RenderPass<'e>> {
        Some(self.begin_into(encoder, self.buffers.get(run).map(|b| (&b.view, b.divisor))?, "ReducedLayers::run", timestamp_writes))
    }

    /// A render pass into the buffer `view` made at `divisor`, cleared to nothing in front, its
    /// viewport the whole buffer.
    fn begin_into<'e>(
        &self,
        encoder: &'e mut wgpu::CommandEncoder,
        (view, divisor): (&wgpu::TextureView, Divisor),
        label: &str,
        timestamp_writes: Option<wgpu::RenderPassTimestampWrites<'_>>,
    ) -> wgpu::RenderPass<'e> {
        let mut rpass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(label),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations { load: wgpu::LoadOp::Clear(wgpu::Color { r: 0.0, g: 0.0, b: 0.0, a: 1.0 }), store: wgpu::StoreOp::Store },
            })],
            depth_stencil_attachment: None,
            timestamp_writes,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        let (w, h) = divisor.buffer_size(self.made_for.0);
        rpass.set_viewport(0.0, 0.0, w as f32, h as f32, 0.0, 1.0);
        rpass
    }
}

impl Pass for ReducedLayersPass {
    fn name(&self) -> &'static str {
        "reduced_layers"
    }

    fn phase(&self) -> Phase {
        Phase::Sky
    }

    fn stage_pipelines(&mut self, b: &PassBuild<'_>) -> RenderResult<()> {
        self.pipelines.stage(b)?;
        self.combine.stage(b)?;
        self.seed_radiance_pipeline.stage(b)
    }

    fn commit_pipelines(&mut self, accept: bool) {
        self.pipelines.commit(accept);
        self.combine.commit(accept);
        self.seed_radiance_pipeline.commit(accept);
    }

    fn prepare(&mut self, cx: &FrameContext<'_>) {
        self.seeded = false;
        // Buffers of another size are of no further use.
        if self.made_for.0 != cx.size {
            self.buffers.clear();
            self.combined.clear();
            self.own.clear();
            self.seed_radiance = None;
            self.made_for = ((0, 0), Target::Display);
        }
    }

    /// None of its own: the renderer places a composite where each run's first layer would draw.
    fn items(&self, _cx: &FrameContext<'_>, _out: &mut Vec<crate::render::frame::pass::DrawItem>) {}

    /// Composites run `key` (the renderer places it where the run's first layer would draw).
    fn draw(&self, rpass: &mut wgpu::RenderPass<'_>, key: usize, target: Target, _placement: Placement, _run: Option<&wgpu::BindGroup>) -> u32 {
        let Some(buffer) = self.buffers.get(key) else { return 0 };
        rpass.set_pipeline(&self.pipelines.for_target(target)[COMPOSITE]);
        rpass.set_bind_group(1, &buffer.bind_group, &[]);
        rpass.draw(0..3, 0..1);
        1
    }
}

/// A full-screen triangle of `module` (shaders/reduced_layers.wgsl) with fragment entry `entry`,
/// into the frame's target, depth-tested with `compare` and never writing depth.
fn full_screen_pipeline(
    b: &PassBuild<'_>,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    label: &str,
    entry: &str,
    blend: Option<wgpu::BlendState>,
    compare: wgpu::CompareFunction,
) -> RenderResult<wgpu::RenderPipeline> {
    shaders::validated(b.device, label, || {
        b.device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(label),
            layout: Some(layout),
            vertex: wgpu::VertexState { module, entry_point: Some("vs_main"), buffers: &[], compilation_options: Default::default() },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: crate::render::gpu::parts::depth_state(false, compare),
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module,
                entry_point: Some(entry),
                targets: &[Some(wgpu::ColorTargetState { format: b.color_format, blend, write_mask: wgpu::ColorWrites::ALL })],
                compilation_options: Default::default(),
            }),
            multiview_mask: None,
            cache: None,
        })
    })
}

/// The bind group layout of one run's buffer (composite uniform, buffer, sampler, and the buffer
/// of the run below where it was seeded with it, else black): the composite
/// reads it, and so do sky objects drawn under a run ([`crate::render::sky_objects`]).
pub fn run_layout(device: &wgpu::Device, label: &str) -> wgpu::BindGroupLayout {
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(label),
        entries: &[
            crate::render::gpu::parts::uniform_entry(0, wgpu::ShaderStages::FRAGMENT),
            crate::render::gpu::parts::texture_entry(1),
            crate::render::gpu::parts::sampler_entry(2),
            crate::render::gpu::parts::texture_entry(3),
        ],
    })
}

impl ReducedLayersPass {
    /// Draws the frame's background, into the scene's pass before the scene: the first run or,
    /// `joined`, the combination of the joined runs ([`Self::record_combined`]). The target holds
    /// only its clear colour (black) then, so compositing over it is writing the run's colour,
    /// and the scene drawn next covers what it hides. A full-screen pass without blending or depth
    /// test costs a software rasteriser about half a blended, tested one. What lies between two
    /// joined runs in the sky phase (billboards) is drawn afterwards under what lies above it
    /// ([`Self::upper_bind_group`]). `over`: added to additive draws already on the frame, which
    /// lie on top of the first run or, joined, under the runs above the first.
    pub fn draw_background(&self, rpass: &mut wgpu::RenderPass<'_>, target: Target, joined: bool, over: bool) -> u32 {
        let combination = if self.seeded && self.combined.is_empty() { self.buffers.get(1) } else { self.combined.first() };
        let (buffer, pipeline) = match (joined, over) {
            (true, true) => (combination, JOINED_BACKGROUND_OVER),
            (true, false) => (combination, BACKGROUND),
            (false, true) => (self.buffers.first(), BACKGROUND_OVER),
            (false, false) => (self.buffers.first(), BACKGROUND),
        };
        self.draw_as_background(rpass, buffer, target, pipeline)
    }

    /// Writes `buffer`'s colour over the frame with background pipeline `pipeline`; 0 draws
    /// without it.
    fn draw_as_background(&self, rpass: &mut wgpu::RenderPass<'_>, buffer: Option<&RunBuffer>, target: Target, pipeline: usize) -> u32 {
        let Some(buffer) = buffer else { return 0 };
        rpass.set_pipeline(&self.pipelines.for_target(target)[pipeline]);
        rpass.set_bind_group(1, &buffer.bind_group, &[]);
        rpass.draw(0..3, 0..1);
        1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn divisors_step_by_quarters_within_their_bounds() {
        let (half, quarter) = (Divisor::HALF, Divisor::QUARTER);
        // The built-in clouds: 10.3 frame pixels per degree, 4.04 texels per degree.
        assert_eq!(Divisor::at_most(10.29 / 4.04, half, quarter).x(), 2.5);
        assert_eq!(Divisor::at_most(3.99, half, quarter).y(), 3.75);
        assert_eq!(Divisor::at_most(1.2, half, quarter), half);
        assert_eq!(Divisor::at_most(f32::INFINITY, half, quarter), quarter);
        assert_eq!(Divisor::at_most(f32::NAN, half, quarter), half);
        assert_eq!(Divisor::whole(3).to_string(), "3");
        assert_eq!(Divisor::at_most(2.5, half, quarter).to_string(), "2.5");
        // Buffers cover the whole frame, rounding up.
        assert_eq!(Divisor::at_most(2.5, half, quarter).buffer_size((1280, 720)), (512, 288));
        assert_eq!(Divisor::whole(4).buffer_size((322, 181)), (81, 46));
        assert_eq!(quarter.buffer_size((1, 1)), (1, 1));
        // Coarser across than down (a physical map's buffer): each side by its own.
        let map = Divisor::at_most_each((9.0, 5.1), half, Divisor::EIGHTH);
        assert_eq!((map.x(), map.y(), map.to_string()), (8.0, 5.0, "8x5".to_string()));
        assert_eq!(map.buffer_size((1280, 720)), (160, 144));
    }
}
