//! Sky objects pass: every object of the sky file, drawn by priority with its 4-stage material.

use std::collections::HashMap;
use std::sync::Arc;

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Quat, Vec3, Vec4};

use super::camera::Camera;
use super::error::RenderResult;
use super::mesh::{outline_mesh, shape_key, shape_mesh, GpuMesh, SkyVertex};
use super::pass::{Caps, DrawItem, FrameContext, Pass, PassBuild, Phase, Pipelines, Placement, SkyUpload, Staged, Target};
use super::reduced_layers::Divisor;
use super::renderer::FrameStats;
use super::shaders;
use super::stage_fold;
use super::texel_quads::{self, GpuTexelMesh, TexelSource, TexelVertex};
use super::textures::{self, TextureCache};
use crate::sky::eval::{FrameSky, VersionFrame};
use crate::sky::resolved::{BlendMode, Lighting, Shape, Sky, StageOp, TextureImage, UvSource, Version, MAX_STAGES};

/// One texture stage. Keep in sync with `Stage` in shaders/sky_objects.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable, PartialEq)]
pub struct StageUniform {
    /// UV scale (xy) and offset (zw), repeats.
    pub scale_offset: [f32; 4],
    /// Sun: size in radians; Quake: z_scale, z_offset, t_scale, time_scale.
    pub params: [f32; 4],
    /// op (0 add, 1 modulate), uv mode, constant index (4 = none), live (0: its term is black
    /// this frame and is not sampled).
    pub cfg: [u32; 4],
}

/// One draw. Keep in sync with `Draw` in shaders/sky_objects.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable, PartialEq)]
pub struct DrawUniform {
    /// Columns: right x half size, up x half size, centre direction (quads); identity for domes.
    pub object_from_local: [[f32; 4]; 4],
    /// Diffuse colour.
    pub diffuse: [f32; 4],
    /// Constant colours.
    pub constants: [[f32; 4]; 4],
    /// Stages.
    pub stages: [StageUniform; 4],
    /// Stage count, lighting (0 flat, 1 moon, 2 cloud), stage fed by the sky-view map (4 = none),
    /// lit clouds' density (f32 bits).
    pub misc: [u32; 4],
}
const _: () = assert!(std::mem::size_of::<StageUniform>() == 48);
const _: () = assert!(std::mem::size_of::<DrawUniform>() == 64 + 16 + 64 + 4 * 48 + 16);

/// "No stage" in stage-index fields shared with the shader.
const NO_STAGE: u32 = 4;

/// UV mode of a stage folded into the one before it ([`super::stage_fold`]): reads as white,
/// not sampled. Keep in sync with `UV_WHITE` in shaders/sky_objects.wgsl.
const UV_WHITE: u32 = 4;

/// UV mode of the mesh's texture coordinates. Keep in sync with `UV_MESH` in
/// shaders/sky_objects.wgsl.
const UV_MESH: u32 = 0;

/// UV mode of the celestial mapping.
const UV_CELESTIAL: u32 = 2;

/// UV mode of a celestial stage that no pixel of its draw minifies this frame: sampled from
/// level 0 without the derivatives the celestial mapping otherwise computes per pixel (a variant
/// of the mapping, never in a uniform). Keep in sync with `UV_CELESTIAL_LEVEL0` in
/// shaders/sky_objects.wgsl.
const UV_CELESTIAL_LEVEL0: u32 = 5;

/// UV mode numbers shared with the shader.
fn uv_mode(uv: &UvSource) -> (u32, [f32; 4]) {
    match *uv {
        UvSource::Mesh => (0, [0.0; 4]),
        UvSource::Sun { size_deg } => (1, [size_deg.get().to_radians(), 0.0, 0.0, 0.0]),
        UvSource::Celestial => (UV_CELESTIAL, [0.0; 4]),
        UvSource::Quake { z_scale, z_offset, t_scale, time_scale } => (3, [z_scale.get(), z_offset.get(), t_scale.get(), time_scale.get()]),
    }
}

impl From<&Version> for DrawUniform {
    /// The parts of a draw that do not change from frame to frame.
    fn from(v: &Version) -> Self {
        let mut stages = [StageUniform::zeroed(); 4];
        for (k, s) in v.stages.iter().enumerate() {
            let (mode, params) = uv_mode(&s.uv);
            let op = match s.op {
                StageOp::Add => 0,
                StageOp::Modulate => 1,
            };
            stages[k] = StageUniform { scale_offset: [s.uv_scale[0], s.uv_scale[1], 0.0, 0.0], params, cfg: [op, mode, s.constant.map_or(4, |c| c as u32), 1] };
        }
        DrawUniform {
            object_from_local: Mat4::IDENTITY.to_cols_array_2d(),
            diffuse: [1.0; 4],
            constants: [[1.0; 4]; 4],
            stages,
            misc: [
                v.stages.len() as u32,
                match v.lighting {
                    Lighting::Flat => 0,
                    Lighting::Moon => 1,
                    Lighting::Cloud => 2,
                },
                NO_STAGE,
                v.cloud_density.to_bits(),
            ],
        }
    }
}

impl DrawUniform {
    /// Marks the stages of terms that contribute nothing this frame (a factor's constant is black,
    /// and transparent too when alpha weighs the colour) so the shader does not sample them;
    /// returns how many. The sky-model stage is never skipped.
    pub fn skip_dark_terms(&mut self, alpha_matters: bool) -> u32 {
        let count = (self.misc[0] as usize).min(4);
        let mut skipped = 0;
        let mut start = 0;
        while start < count {
            let mut end = start + 1;
            while end < count && self.stages[end].cfg[0] == 1 {
                end += 1;
            }
            let dark = (start..end).any(|k| {
                let c = self.stages[k].cfg[2] as usize;
                c < 4 && self.constants[c][..3].iter().all(|v| *v <= 0.0) && (!alpha_matters || self.constants[c][3] <= 0.0)
            });
            let holds_view = (start..end).any(|k| k as u32 == self.misc[2]);
            if dark && !holds_view {
                for k in start..end {
                    self.stages[k].cfg[3] = 0;
                    skipped += 1;
                }
            }
            start = end;
        }
        skipped
    }

    /// Applies a frame's colours, UV offsets and placement; `sky_view_stage` is the gradient
    /// stage when a physical sky model colours it.
    pub fn with_frame(mut self, pass: &VersionFrame, shape: &Shape, placement: Option<(Vec3, f32)>, camera_up: Vec3, sky_view_stage: Option<usize>) -> Self {
        self.misc[2] = sky_view_stage.map_or(NO_STAGE, |k| k as u32);
        self.diffuse = pass.diffuse;
        self.constants = pass.constants;
        for (k, off) in pass.uv_offsets.iter().enumerate() {
            self.stages[k].scale_offset[2] = off[0];
            self.stages[k].scale_offset[3] = off[1];
        }
        if let (Some((dir, roll_deg)), Shape::Billboard { size_deg } | Shape::Quad { size_deg }) = (placement, shape) {
            // Billboards keep the screen's up; quads keep the world's up turned by the path's roll.
            let (up_hint, roll) = match shape {
                Shape::Billboard { .. } => (camera_up, 0.0),
                _ => (Vec3::Y, roll_deg.to_radians()),
            };
            let mut right = dir.cross(up_hint).try_normalize().unwrap_or(Vec3::X);
            let mut up = right.cross(dir);
            let q = Quat::from_axis_angle(dir, roll);
            right = q * right;
            up = q * up;
            let half = (size_deg.get().to_radians() * 0.5).tan();
            self.object_from_local = Mat4::from_cols((right * half).extend(0.0), (up * half).extend(0.0), dir.extend(0.0), Vec4::W).to_cols_array_2d();
        }
        self
    }
}

/// The generic pipelines (one per blend mode: every material, read from the uniform) and the
/// shader module the specialised ones are built from.
pub struct SkyObjectPipelines {
    generic: [wgpu::RenderPipeline; 3],
    module: wgpu::ShaderModule,
}

/// What a specialised pipeline is built for: the material's signature in this frame (stage
/// count, and per stage its UV mode, op, constant index and whether its term is live), the stage
/// the sky-view map feeds, the lighting, the blend and what the target holds. Everything the
/// shader would otherwise branch on per draw: lavapipe pays for both sides of such branches.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
struct VariantKey {
    count: u32,
    modes: [u32; 4],
    ops: [u32; 4],
    constants: [u32; 4],
    live: [bool; 4],
    view_stage: u32,
    lighting: u32,
    blend: usize,
    target: Target,
    /// The HDR target's tone mapper (`TONE_KIND` of tone.wgsl): 1 ACES, 2 neutral; 0 on the
    /// display target.
    tone: u32,
    /// Drawn into a reduced-resolution buffer ([`super::reduced_layers`]).
    reduced: bool,
    /// Where on the frame it goes ([`Slot::Plain`] for reduced draws).
    placement: Slot,
}

/// Where a draw on the frame goes, as its pipeline variant sees it (the shader's switches of a
/// [`super::pass::Placement`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
enum Slot {
    /// In its place in the sky phase, depth-tested against the scene.
    Plain,
    /// After a run of reduced layers that lies above it, corrected by that run's colour and
    /// transmittance (`UNDER_RUN` in the shader).
    UnderRun,
    /// Additive, first onto the cleared frame under the background run, not depth-tested
    /// ([`super::strategy::UnderBackground::Additive`]).
    First,
    /// Additive and covering the frame: the background itself, its run's colour plus the
    /// draw's term, neither blended nor depth-tested (`BACKGROUND` in the shader: 1).
    Background,
    /// As `Background` over joined runs, the term weighed by the runs above it (`BACKGROUND`: 2).
    JoinedBackground,
    /// Into a seeded reduced buffer as its first layer, over the lower run's colour itself and
    /// replacing what the buffer holds (`OVER_SEED` in the shader; `Placement::OverSeed`).
    OverSeed,
}

impl Slot {
    /// The background placement over one run or over joined runs.
    fn background(joined: bool) -> Self {
        if joined {
            Slot::JoinedBackground
        } else {
            Slot::Background
        }
    }
}

impl VariantKey {
    /// The signature of a draw with this frame's uniform `u`.
    fn of(u: &DrawUniform, blend: BlendMode, target: Target, neutral_tone: bool) -> Self {
        let tone = match (target, neutral_tone) {
            (Target::Display, _) => 0,
            (Target::Hdr, false) => 1,
            (Target::Hdr, true) => 2,
        };
        Self {
            count: u.misc[0],
            modes: u.stages.map(|s| s.cfg[1]),
            ops: u.stages.map(|s| s.cfg[0]),
            constants: u.stages.map(|s| s.cfg[2]),
            live: u.stages.map(|s| s.cfg[3] != 0),
            view_stage: u.misc[2],
            lighting: u.misc[1],
            blend: blend_index(blend),
            target,
            tone,
            reduced: false,
            placement: Slot::Plain,
        }
    }

    /// The override constants that specialise `shaders/sky_objects.wgsl` for this signature.
    fn constants(&self) -> Vec<(&'static str, f64)> {
        const MODES: [&str; 4] = ["UV_MODE_0", "UV_MODE_1", "UV_MODE_2", "UV_MODE_3"];
        const OPS: [&str; 4] = ["OP_0", "OP_1", "OP_2", "OP_3"];
        const CONSTANTS: [&str; 4] = ["CONSTANT_0", "CONSTANT_1", "CONSTANT_2", "CONSTANT_3"];
        const LIVE: [&str; 4] = ["LIVE_0", "LIVE_1", "LIVE_2", "LIVE_3"];
        let mut c = vec![
            ("SPECIALISED", 1.0),
            ("STAGE_COUNT", f64::from(self.count)),
            ("VIEW_STAGE", f64::from(self.view_stage)),
            ("LIGHTING", f64::from(self.lighting)),
            ("TARGET_KIND", if self.target == Target::Hdr { 2.0 } else { 1.0 }),
            ("TONE_KIND", f64::from(self.tone)),
            ("UNDER_RUN", f64::from(u8::from(self.placement == Slot::UnderRun))),
            ("BLEND_KIND", self.blend as f64),
            ("OVER_SEED", f64::from(u8::from(self.placement == Slot::OverSeed))),
            (
                "BACKGROUND",
                match self.placement {
                    Slot::Background => 1.0,
                    Slot::JoinedBackground => 2.0,
                    _ => 0.0,
                },
            ),
        ];
        for k in 0..4 {
            c.push((MODES[k], f64::from(self.modes[k])));
            c.push((OPS[k], f64::from(self.ops[k])));
            c.push((CONSTANTS[k], f64::from(self.constants[k])));
            c.push((LIVE[k], f64::from(u8::from(self.live[k]))));
        }
        c
    }
}

/// What a pipeline drawing two alpha-blended dome layers at once into a reduced buffer is built
/// for (`vs_pair`, `fs_pair` in shaders/sky_objects.wgsl): the lower layer's signature (its
/// placement: plain or over the seed) and the upper one's.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
struct PairKey {
    lower: VariantKey,
    upper: VariantKey,
}

impl PairKey {
    /// The lower layer's override constants and the upper layer's as `UPPER_*`.
    fn constants(&self) -> Vec<(&'static str, f64)> {
        const MODES: [&str; 4] = ["UPPER_UV_MODE_0", "UPPER_UV_MODE_1", "UPPER_UV_MODE_2", "UPPER_UV_MODE_3"];
        const OPS: [&str; 4] = ["UPPER_OP_0", "UPPER_OP_1", "UPPER_OP_2", "UPPER_OP_3"];
        const CONSTANTS: [&str; 4] = ["UPPER_CONSTANT_0", "UPPER_CONSTANT_1", "UPPER_CONSTANT_2", "UPPER_CONSTANT_3"];
        const LIVE: [&str; 4] = ["UPPER_LIVE_0", "UPPER_LIVE_1", "UPPER_LIVE_2", "UPPER_LIVE_3"];
        let u = &self.upper;
        let mut c = self.lower.constants();
        c.extend([("UPPER_STAGE_COUNT", f64::from(u.count)), ("UPPER_VIEW_STAGE", f64::from(u.view_stage)), ("UPPER_LIGHTING", f64::from(u.lighting))]);
        for k in 0..4 {
            c.extend([(MODES[k], f64::from(u.modes[k])), (OPS[k], f64::from(u.ops[k])), (CONSTANTS[k], f64::from(u.constants[k])), (LIVE[k], f64::from(u8::from(u.live[k])))]);
        }
        c
    }
}

/// The blend of a pair of alpha layers into a reduced buffer: `fs_pair` writes premultiplied
/// colour and what the pair covers, so the buffer ends as two alpha blends would leave it
/// ([`super::reduced_layers::REDUCED_BLENDS`]): colour + (1 - covered) x buffer, and the
/// transmittance in alpha times what the pair lets through.
const PAIR_BLEND: wgpu::BlendState = wgpu::BlendState {
    color: wgpu::BlendComponent { src_factor: wgpu::BlendFactor::One, dst_factor: wgpu::BlendFactor::OneMinusSrcAlpha, operation: wgpu::BlendOperation::Add },
    alpha: wgpu::BlendComponent { src_factor: wgpu::BlendFactor::Zero, dst_factor: wgpu::BlendFactor::OneMinusSrcAlpha, operation: wgpu::BlendOperation::Add },
};

/// The sky objects pass: pipelines (one per blend mode, built once and rebuilt on shader edits,
/// plus one per material signature, built on first use) and the current sky's per-object resources.
pub struct SkyObjectsPass {
    bind_layout: wgpu::BindGroupLayout,
    pipeline_layout: wgpu::PipelineLayout,
    /// Bound as group 2 (a run's buffer) when a draw is not under a run: every pipeline's
    /// layout has the group, only `UNDER_RUN` variants read it.
    no_run: wgpu::BindGroup,
    display_format: wgpu::TextureFormat,
    pipelines: Pipelines<SkyObjectPipelines>,
    /// Specialised pipelines by material signature (`None`: building it failed; the generic one
    /// draws). Emptied when the shaders change.
    variants: HashMap<VariantKey, Option<wgpu::RenderPipeline>>,
    /// Pipelines drawing two layers at once, by their signatures (`None`: building it failed;
    /// the two are drawn one after the other). Emptied when the shaders change.
    pairs: HashMap<PairKey, Option<wgpu::RenderPipeline>>,
    /// The layout of pair pipelines: the upper layer's draw bind group as group 3.
    pair_layout: wgpu::PipelineLayout,
    /// Pipelines drawing a sparse stage texel by texel ([`super::texel_quads`]), by the
    /// background's signature (`None`: building it failed; the stage is sampled). Emptied when
    /// the shaders change.
    texel_pipelines: HashMap<VariantKey, Option<wgpu::RenderPipeline>>,
    /// The background without its sparse stage as one triangle over the frame
    /// ([`super::strategy::SparseStages::TexelPolygonsOnBands`]), by the signature without the stage.
    fullscreen_pipelines: HashMap<VariantKey, Option<wgpu::RenderPipeline>>,
    /// Sparse stages are drawn texel by texel this frame ([`super::strategy::SparseStages::TexelPolygons`]).
    texels_on: bool,
    /// The rest of such a draw goes as bands where the polygons stand for the stage
    /// ([`super::strategy::SparseStages::TexelPolygonsOnBands`]).
    bands_on: bool,
    /// Triangles of texel polygons recorded this frame (counted as they are recorded).
    texel_triangles: std::cell::Cell<u32>,
    /// Scissor rectangles of the background drawn as one triangle this frame.
    background_rects: std::cell::Cell<u32>,
    draws: Staged<Option<SkyObjectDraws>>,
    /// The shared sky-view map and its sampler, bound to every draw.
    sky_view: (wgpu::TextureView, wgpu::Sampler),
    /// This frame's draws, in order: one per visible version, or two where a version is split.
    visible: Vec<Visible>,
    hidden: u32,
    /// Texture stages not sampled this frame (their term is black).
    stages_skipped: u32,
    /// Draws left out this frame: blended, every term black and transparent.
    draws_dark: u32,
    /// Objects hidden this frame by their ref colour.
    ref_hidden: u32,
    /// Objects below the horizon this frame, behind the main scene.
    below_horizon: u32,
    /// Dome layers outside the frame's elevations this frame.
    off_screen: u32,
    /// Stages sampled from level 0 alone this frame, over every draw (in some of its rows).
    level0_stages: u32,
    /// This frame's draw parts ([`Visible::parts`]): index range, level-0 stages.
    parts: Vec<(std::ops::Range<u32>, u8)>,
    /// This frame's pipeline signature of every drawn version, by (object index, version).
    keys: HashMap<(usize, usize), VariantKey>,
    /// The lowest and highest elevations the frame shows, degrees (with a margin for the
    /// dome's chords).
    frame_elevations_deg: (f32, f32),
    /// This frame's camera and size in pixels.
    frame_camera: Camera,
    frame_size: (u32, u32),
}

/// One draw of this frame: a version of an object, whole or the part of its terms that goes to
/// one resolution.
#[derive(Debug, Clone, Copy)]
struct Visible {
    /// Object index.
    index: usize,
    priority: u8,
    version: usize,
    /// Drawn into a reduced-resolution buffer.
    reduced: bool,
    /// Where reduced: frame pixels per buffer pixel along each side, the coarsest buffer the
    /// options allow that still resolves its textures.
    divisor: Divisor,
    /// The stages this draw samples (the other terms are left out): every stage when whole.
    part: [bool; 4],
    /// The fine terms of a split opaque layer: added on top of its reduced part.
    on_top: bool,
    /// Its parts this frame: `parts[start..start + count]` of the pass, each an index range and
    /// the stages (bit k: stage k) that no pixel of it minifies, sampled from level 0 alone
    /// (`count` 0: the whole mesh, every stage mipmapped).
    parts: (u32, u32),
}

/// Blend index of [`BLENDS`] that adds colour as it is (the fine terms of a split opaque layer).
const BLEND_ADD: usize = 3;

/// Term of each stage: an `add` stage starts one, `modulate` stages join the current one.
fn stage_terms(ops: [u32; 4]) -> [usize; 4] {
    let mut terms = [0; 4];
    let mut term = 0;
    for k in 0..4 {
        if k > 0 && ops[k] == 0 {
            term += 1;
        }
        terms[k] = term;
    }
    terms
}

fn blend_index(b: BlendMode) -> usize {
    match b {
        BlendMode::Opaque => 0,
        BlendMode::Alpha => 1,
        BlendMode::Additive => 2,
    }
}

const BLENDS: [Option<wgpu::BlendState>; 4] = [
    None,
    Some(wgpu::BlendState::ALPHA_BLENDING),
    Some(super::ADDITIVE_ALPHA),
    Some(wgpu::BlendState {
        color: wgpu::BlendComponent { src_factor: wgpu::BlendFactor::One, dst_factor: wgpu::BlendFactor::One, operation: wgpu::BlendOperation::Add },
        alpha: wgpu::BlendComponent { src_factor: wgpu::BlendFactor::Zero, dst_factor: wgpu::BlendFactor::One, operation: wgpu::BlendOperation::Add },
    }),
];

/// Blends of draws under a run (`UNDER_RUN` in shaders/sky_objects.wgsl, which premultiplies what
/// it writes), by blend index of [`BLENDS`]: a draw that would have gone before the run goes
/// after it, so that run and the one below composite at once. With the run's colour C and
/// transmittance T at the pixel, the frame must end as C + T x (the draw over what was there):
/// opaque writes C + T m; alpha writes T a m + a C over (1 - a) of the target; additive ones add
/// T times their term. Alpha channels blend as the plain draws'.
const UNDER_RUN_BLENDS: [Option<wgpu::BlendState>; 4] = {
    const ADD: wgpu::BlendComponent = wgpu::BlendComponent { src_factor: wgpu::BlendFactor::One, dst_factor: wgpu::BlendFactor::One, operation: wgpu::BlendOperation::Add };
    const KEEP: wgpu::BlendComponent = wgpu::BlendComponent { src_factor: wgpu::BlendFactor::Zero, dst_factor: wgpu::BlendFactor::One, operation: wgpu::BlendOperation::Add };
    const OVER: wgpu::BlendComponent =
        wgpu::BlendComponent { src_factor: wgpu::BlendFactor::One, dst_factor: wgpu::BlendFactor::OneMinusSrcAlpha, operation: wgpu::BlendOperation::Add };
    [None, Some(wgpu::BlendState { color: OVER, alpha: OVER }), Some(wgpu::BlendState { color: ADD, alpha: KEEP }), Some(wgpu::BlendState { color: ADD, alpha: KEEP })]
};

impl SkyObjectsPass {
    /// Builds the layouts and pipelines.
    pub fn new(b: &PassBuild<'_>) -> RenderResult<Self> {
        let (device, globals) = (b.device, b.globals_layout);
        let mut entries = vec![super::uniform_entry(0, wgpu::ShaderStages::VERTEX_FRAGMENT)];
        entries.extend((0..4).map(|i| super::texture_entry(1 + i)));
        entries.extend((0..4).map(|i| super::sampler_entry(5 + i)));
        entries.extend([super::texture_entry(9), super::sampler_entry(10)]);
        let bind_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some("SkyObjects::draw_layout"), entries: &entries });
        let run_layout = super::reduced_layers::run_layout(device, "SkyObjects::run_layout");
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("SkyObjects::pipeline_layout"),
            bind_group_layouts: &[Some(globals), Some(&bind_layout), Some(&run_layout)],
            immediate_size: 0,
        });
        let pair_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("SkyObjects::pair_layout"),
            bind_group_layouts: &[Some(globals), Some(&bind_layout), Some(&run_layout), Some(&bind_layout)],
            immediate_size: 0,
        });
        let no_run = {
            let uniform = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("SkyObjects::no_run_uniform"),
                size: 16,
                usage: wgpu::BufferUsages::UNIFORM,
                mapped_at_creation: false,
            });
            let view = super::textures::unused_view(device, "SkyObjects::no_run_texture");
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("SkyObjects::no_run"),
                layout: &run_layout,
                entries: &[
                    wgpu::BindGroupEntry { binding: 0, resource: uniform.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(&view) },
                    wgpu::BindGroupEntry { binding: 2, resource: wgpu::BindingResource::Sampler(&b.shared.sky_view_sampler) },
                    wgpu::BindGroupEntry { binding: 3, resource: wgpu::BindingResource::TextureView(&view) },
                ],
            })
        };
        let pipelines = Pipelines::new_render(b, pipeline_layout.clone(), Self::build)?;
        let sky_view = (b.shared.sky_view_view.clone(), b.shared.sky_view_sampler.clone());
        Ok(Self {
            bind_layout,
            pipeline_layout,
            no_run,
            display_format: b.color_format,
            pipelines,
            variants: HashMap::new(),
            pairs: HashMap::new(),
            pair_layout,
            texel_pipelines: HashMap::new(),
            fullscreen_pipelines: HashMap::new(),
            texels_on: false,
            bands_on: false,
            texel_triangles: std::cell::Cell::new(0),
            background_rects: std::cell::Cell::new(0),
            draws: Staged::new(None),
            sky_view,
            visible: Vec::new(),
            hidden: 0,
            stages_skipped: 0,
            draws_dark: 0,
            ref_hidden: 0,
            below_horizon: 0,
            off_screen: 0,
            level0_stages: 0,
            parts: Vec::new(),
            keys: HashMap::new(),
            frame_elevations_deg: (-90.0, 90.0),
            frame_camera: Camera::default(),
            frame_size: (1, 1),
        })
    }

    fn build(b: &PassBuild<'_>, layout: &wgpu::PipelineLayout) -> RenderResult<SkyObjectPipelines> {
        let module = shaders::module(b.device, b.library, "sky_objects")?;
        let names = ["SkyObjects::pipeline_opaque", "SkyObjects::pipeline_alpha", "SkyObjects::pipeline_additive"];
        let one = |i: usize| create_pipeline(b.device, (layout, &module, MAIN), names[i], (BLENDS[i], b.color_format, Some(wgpu::CompareFunction::Less)), &b.target_constants());
        Ok(SkyObjectPipelines { generic: [one(0)?, one(1)?, one(2)?], module })
    }

    /// Specialised pipelines built so far: (succeeded, failed and drawn by the generic pipeline).
    pub fn variants_built(&self) -> (usize, usize) {
        let ok = self.variants.values().filter(|v| v.is_some()).count();
        (ok, self.variants.len() - ok)
    }

    /// The pipeline signature of draw `e` this frame, if its version was prepared for `target`.
    fn entry_key(&self, e: &Visible, target: Target, placement: Slot) -> Option<VariantKey> {
        let k = self.keys.get(&(e.index, e.version)).filter(|k| k.target == target)?;
        let live = std::array::from_fn(|s| k.live[s] && e.part[s]);
        let view_stage = if (k.view_stage as usize) < 4 && !e.part[k.view_stage as usize] { NO_STAGE } else { k.view_stage };
        let blend = if e.on_top { BLEND_ADD } else { k.blend };
        let placement = match (e.reduced, placement) {
            (true, Slot::OverSeed) if !e.on_top => Slot::OverSeed,
            (true, _) => Slot::Plain,
            (false, Slot::OverSeed) => return None,
            (false, p) => p,
        };
        // A celestial stage's level-0 bit is the same in every part of a draw (its bound does not
        // depend on the dome's rings), so one pipeline serves them all.
        let level0 = if e.parts.1 > 0 { self.parts.get(e.parts.0 as usize).map_or(0, |p| p.1) } else { 0 };
        let modes = std::array::from_fn(|s| if k.modes[s] == UV_CELESTIAL && level0 & (1 << s) != 0 { UV_CELESTIAL_LEVEL0 } else { k.modes[s] });
        Some(VariantKey { live, view_stage, blend, reduced: e.reduced, placement, modes, ..*k })
    }

    /// Whether draw `e` adds to the frame (its blend, or the fine terms of a split layer).
    fn additive(&self, e: &Visible) -> bool {
        e.on_top || self.draws.current.as_ref().is_some_and(|d| d.objects[e.index][e.version].blend == BlendMode::Additive)
    }

    /// Whether draw `e`'s shape is a whole dome (down to its lowest row, every row).
    fn dome_of(&self, e: &Visible) -> bool {
        self.draws.current.as_ref().is_some_and(|d| matches!(d.objects[e.index][e.version].shape, Shape::Dome { .. }))
    }

    /// The lowest elevation of draw `key`'s shape when it is a whole dome, degrees.
    fn dome_bottom_deg(&self, key: usize) -> Option<f32> {
        let (Some(draws), Some(e)) = (&self.draws.current, self.visible.get(key)) else { return None };
        match draws.objects[e.index][e.version].shape {
            Shape::Dome { bottom_deg } => Some(bottom_deg.get()),
            _ => None,
        }
    }

    /// What item `key` can be drawn as this frame, `next` the pass's item after it in priority
    /// order.
    fn caps(&self, key: usize, target: Target, next: Option<usize>) -> Caps {
        let dome = self.dome_bottom_deg(key).is_some();
        let spans_frame = match (&self.draws.current, self.visible.get(key)) {
            (Some(draws), Some(e)) => matches!(draws.objects[e.index][e.version].shape, Shape::Dome { .. } | Shape::DomeBand { .. }),
            _ => false,
        };
        Caps {
            under_run: self.can_place(key, target, Slot::UnderRun),
            first: self.can_place(key, target, Slot::First),
            spans_frame,
            // A dome covers its buffer, or the frame, down to its lowest row (`background_gap`),
            // every row in view being drawn; only reduced draws have the seed's placement
            // (`entry_key`).
            over_seed: dome && self.can_place(key, target, Slot::OverSeed),
            background: [false, true].map(|joined| dome && self.can_place(key, target, Slot::background(joined))),
            background_gap: self.background_gap(key),
            pair_next: next.map(|upper| (upper, [false, true].map(|over_seed| self.can_pair(key, upper, target, over_seed)))),
        }
    }

    /// Whether reduced items `lower` and `upper` can be drawn at once ([`Placement::Pair`]).
    fn can_pair(&self, lower: usize, upper: usize, target: Target, over_seed: bool) -> bool {
        let (Some(draws), Some(a), Some(b)) = (&self.draws.current, self.visible.get(lower), self.visible.get(upper)) else { return false };
        let built = self.pair_key(a, b, target, over_seed).is_some_and(|k| self.pairs.get(&k).is_some_and(Option::is_some));
        built && self.pair_parts(a, b, Self::pair_mesh(draws, a, b).mesh.index_count).is_some()
    }

    /// Records reduced items `lower` and `upper` at once, over `seed` when given.
    fn record_pair(&self, rpass: &mut wgpu::RenderPass<'_>, (lower, upper): (usize, usize), target: Target, seed: Option<&wgpu::BindGroup>) -> u32 {
        let (Some(draws), Some(a), Some(b)) = (&self.draws.current, self.visible.get(lower), self.visible.get(upper)) else { return 0 };
        let Some(pipeline) = self.pair_key(a, b, target, seed.is_some()).and_then(|k| self.pairs.get(&k)).and_then(Option::as_ref) else { return 0 };
        let (da, db) = (&draws.objects[a.index][a.version], &draws.objects[b.index][b.version]);
        let mesh = &Self::pair_mesh(draws, a, b).mesh;
        let Some(parts) = self.pair_parts(a, b, mesh.index_count) else { return 0 };
        rpass.set_pipeline(pipeline);
        rpass.set_bind_group(2, seed.unwrap_or(&self.no_run), &[]);
        rpass.set_vertex_buffer(0, mesh.vertices.slice(..));
        rpass.set_index_buffer(mesh.indices.slice(..), wgpu::IndexFormat::Uint32);
        for (indices, level0_lower, level0_upper) in &parts {
            rpass.set_bind_group(1, &da.bind_groups[usize::from(level0_lower & da.level0_able)], &[]);
            rpass.set_bind_group(3, &db.bind_groups[usize::from(level0_upper & db.level0_able)], &[]);
            rpass.draw_indexed(indices.clone(), 0, 0..1);
        }
        parts.len() as u32
    }

    /// Pixels item `key` leaves uncovered as the background or over a seed: below the dome's
    /// lowest row, with the margin of its chords' sag.
    fn background_gap(&self, key: usize) -> Option<[u32; 4]> {
        let covered_from_deg = self.dome_bottom_deg(key)? + 0.5;
        if covered_from_deg <= self.frame_elevations_deg.0 {
            return None;
        }
        self.frame_camera.pixels_below_elevation(self.frame_size, covered_from_deg)
    }

    /// Whether draw `key` has a pipeline for `placement` on the frame this frame.
    fn can_place(&self, key: usize, target: Target, placement: Slot) -> bool {
        self.visible.get(key).and_then(|e| self.entry_key(e, target, placement)).is_some_and(|k| k.placement == placement && self.variants.get(&k).is_some_and(Option::is_some))
    }

    /// Records draw `key` into the frame's target or, `reduced`, into a reduced-resolution
    /// buffer; returns draw calls.
    fn record(&self, rpass: &mut wgpu::RenderPass<'_>, key: usize, target: Target, reduced: bool, (placement, under_run): (Slot, Option<&wgpu::BindGroup>)) -> u32 {
        let (Some(draws), Some(e)) = (&self.draws.current, self.visible.get(key)) else { return 0 };
        let d = &draws.objects[e.index][e.version];
        let specialised = self.entry_key(e, target, placement).and_then(|k| self.variants.get(&k)).and_then(Option::as_ref);
        let pipeline = match specialised {
            Some(p) => p,
            // The generic pipeline draws every term: only right for whole draws in their place.
            None if !reduced && placement == Slot::Plain && e.part == [true; 4] && !e.on_top => &self.pipelines.for_target(target).generic[blend_index(d.blend)],
            // Building it failed and was logged.
            None => return 0,
        };
        rpass.set_pipeline(pipeline);
        rpass.set_bind_group(2, under_run.unwrap_or(&self.no_run), &[]);
        rpass.set_vertex_buffer(0, d.mesh.vertices.slice(..));
        rpass.set_index_buffer(d.mesh.indices.slice(..), wgpu::IndexFormat::Uint32);
        let (start, count) = (e.parts.0 as usize, e.parts.1 as usize);
        if count == 0 {
            rpass.set_bind_group(1, &d.bind_groups[0], &[]);
            rpass.draw_indexed(0..d.mesh.index_count, 0, 0..1);
            return 1;
        }
        // The background's sparse stage texel by texel where it is sampled from level 0: those
        // parts drawn without it, its polygons there added after.
        let texels = self.texel_draw(e, target, placement);
        let parts = &self.parts[start..start + count];
        let mut calls = 0;
        // Without the stage the draw samples nothing mapped by the grid (only the runs, at the
        // pixel: `without_texel_stage`), so where no ring needs the grid it is one triangle over
        // the frame, scissored round the rectangles that do: the box of the rings still sampling
        // the stage and the rows below the dome (`background_gap`). Inside those (or over the
        // whole frame without that triangle), one band over each run of such rings. Every
        // triangle edge costs lavapipe the 4 x 4 blocks it crosses shaded twice.
        let frame = [0, 0, self.frame_size.0, self.frame_size.1];
        let mut band_scissors = vec![frame];
        if let Some(t) = texels.as_ref().filter(|t| t.fullscreen.is_some()) {
            let sampled_rings = parts.iter().filter(|(_, level0)| level0 & (1 << t.stage) == 0).map(|(indices, _)| indices.clone());
            band_scissors = self.rings_box(d, sampled_rings).into_iter().chain(self.background_gap(key)).collect();
        }
        if let Some(fullscreen) = texels.as_ref().and_then(|t| t.fullscreen) {
            let rects = scissor_rects(frame, &band_scissors);
            rpass.set_pipeline(fullscreen);
            rpass.set_bind_group(1, &d.bind_groups[0], &[]);
            for &[x, y, w, h] in &rects {
                rpass.set_scissor_rect(x, y, w, h);
                rpass.draw(0..3, 0..1);
            }
            calls += rects.len() as u32;
            self.background_rects.set(self.background_rects.get() + rects.len() as u32);
            rpass.set_scissor_rect(0, 0, self.frame_size.0, self.frame_size.1);
        }
        let mut texel_rings = Vec::new();
        for (indices, level0) in parts {
            rpass.set_bind_group(1, &d.bind_groups[usize::from(level0 & d.level0_able)], &[]);
            match &texels {
                Some(t) if level0 & (1 << t.stage) != 0 => {
                    rpass.set_pipeline(t.without);
                    // The grid's indices: six per cell, `segments` cells per ring.
                    let per_ring = t.mesh.segments.max(1) * 6;
                    let rings = (indices.start / per_ring) as usize..(indices.end / per_ring) as usize;
                    if self.bands_on {
                        rpass.set_index_buffer(t.mesh.bands.slice(..), wgpu::IndexFormat::Uint32);
                        let band = t.mesh.band(rings.clone());
                        for &[x, y, w, h] in &band_scissors {
                            rpass.set_scissor_rect(x, y, w, h);
                            rpass.draw_indexed(band.clone(), 0, 0..1);
                        }
                        rpass.set_scissor_rect(0, 0, self.frame_size.0, self.frame_size.1);
                        calls += band_scissors.len() as u32;
                        rpass.set_index_buffer(d.mesh.indices.slice(..), wgpu::IndexFormat::Uint32);
                    } else {
                        rpass.draw_indexed(indices.clone(), 0, 0..1);
                        calls += 1;
                    }
                    texel_rings.push(rings);
                }
                _ => {
                    rpass.set_pipeline(pipeline);
                    rpass.draw_indexed(indices.clone(), 0, 0..1);
                    calls += 1;
                }
            }
        }
        if let (Some(t), false) = (&texels, texel_rings.is_empty()) {
            rpass.set_pipeline(t.polygons);
            rpass.set_bind_group(1, &d.bind_groups[0], &[]);
            rpass.set_vertex_buffer(0, t.mesh.vertices.slice(..));
            rpass.set_index_buffer(t.mesh.indices.slice(..), wgpu::IndexFormat::Uint32);
            let shown = self.frame_camera.cone_test(self.frame_size.0 as f32 / self.frame_size.1.max(1) as f32);
            for rings in texel_rings {
                for indices in t.mesh.ring_indices(rings, &shown) {
                    self.texel_triangles.set(self.texel_triangles.get() + (indices.end - indices.start) / 3);
                    rpass.draw_indexed(indices, 0, 0..1);
                    calls += 1;
                }
            }
        }
        calls
    }

    /// The frame's pixels (x, y, width, height) that hold the grid rings of `d` whose triangles
    /// `ring_indices` index (ranges of its grid's indices), with a pixel of margin: the box of
    /// their rows of vertices, projected. The whole frame when one lies behind the eye (the box
    /// would be unbounded), None for no rings.
    fn rings_box(&self, d: &VersionDraw, ring_indices: impl Iterator<Item = std::ops::Range<u32>>) -> Option<[u32; 4]> {
        let (top_deg, bottom_deg, rings, segments) = super::mesh::dome_grid(&d.shape)?;
        let per_ring = segments * 6;
        let (w, h) = (self.frame_size.0.max(1), self.frame_size.1.max(1));
        let (_, clip_from_sky) = self.frame_camera.matrices(w as f32 / h as f32);
        let (mut lo, mut hi) = (glam::Vec2::splat(f32::INFINITY), glam::Vec2::splat(f32::NEG_INFINITY));
        let mut any = false;
        for indices in ring_indices {
            // The rings' region is bounded by its top and bottom rows' chords and the meridians
            // between: its projection lies in the box of those rows' vertices.
            for row in [indices.start / per_ring, indices.end.div_ceil(per_ring)] {
                let elevation = super::mesh::row_elevation_deg(top_deg, bottom_deg, rings, row.min(rings));
                for s in 0..segments {
                    let dir = crate::sky::eval::direction(s as f32 / segments as f32 * 360.0, elevation);
                    let clip = clip_from_sky * dir.extend(1.0);
                    if clip.w < 1e-4 {
                        return Some([0, 0, w, h]);
                    }
                    let p = glam::Vec2::new((clip.x / clip.w * 0.5 + 0.5) * w as f32, (0.5 - clip.y / clip.w * 0.5) * h as f32);
                    (lo, hi) = (lo.min(p), hi.max(p));
                    any = true;
                }
            }
        }
        if !any {
            return None;
        }
        let x0 = (lo.x.floor() - 1.0).clamp(0.0, w as f32) as u32;
        let y0 = (lo.y.floor() - 1.0).clamp(0.0, h as f32) as u32;
        let x1 = (hi.x.ceil() + 1.0).clamp(0.0, w as f32) as u32;
        let y1 = (hi.y.ceil() + 1.0).clamp(0.0, h as f32) as u32;
        (x1 > x0 && y1 > y0).then_some([x0, y0, x1 - x0, y1 - y0])
    }

    /// The background signature `key` with its sparse stage `stage` drawn texel by texel: the
    /// signature without the stage, if the stage makes a term of its own that the polygons can
    /// stand for (mesh-mapped, not the sky model's, the term's other stages folded into it as
    /// white, no lighting) on the display target.
    fn without_texel_stage(key: &VariantKey, stage: usize) -> Option<VariantKey> {
        let background = matches!(key.placement, Slot::Background | Slot::JoinedBackground);
        let own_term = (0..MAX_STAGES).filter(|&j| j != stage && key.live[j]).all(|j| j > stage && key.modes[j] == UV_WHITE && key.ops[j] == 1 && key.constants[j] == NO_STAGE);
        let term = key.live[stage] && key.modes[stage] == UV_MESH && key.ops[stage] != 1 && key.view_stage as usize != stage && key.lighting == 0;
        (background && key.target == Target::Display && !key.reduced && own_term && term).then(|| {
            let mut live = key.live;
            live[stage] = false;
            VariantKey { live, ..*key }
        })
    }

    /// Draw `e` placed as `placement` with its sparse stage texel by texel this frame.
    fn texel_draw(&self, e: &Visible, target: Target, placement: Slot) -> Option<TexelDraw<'_>> {
        let d = &self.draws.current.as_ref()?.objects[e.index][e.version];
        let (stage, mesh) = d.texels.as_ref().filter(|_| self.texels_on)?;
        let key = self.entry_key(e, target, placement)?;
        let without_key = Self::without_texel_stage(&key, *stage)?;
        let without = self.variants.get(&without_key)?.as_ref()?;
        let polygons = self.texel_pipelines.get(&key)?.as_ref()?;
        let fullscreen = self.fullscreen_pipelines.get(&without_key).and_then(Option::as_ref).filter(|_| self.bands_on);
        Some(TexelDraw { stage: *stage, without, fullscreen, polygons, mesh })
    }

    /// Whether draw `e` can be one of a pair: a whole alpha-blended layer in a reduced buffer.
    fn pair_candidate(&self, e: &Visible) -> bool {
        e.reduced && !e.on_top && self.draws.current.as_ref().is_some_and(|d| d.objects[e.index][e.version].blend == BlendMode::Alpha)
    }

    /// Whether draws `lower` and `upper` can be drawn at once: both candidates, on one mesh, or
    /// on one shape's grid and outline (the same directions).
    fn pairable(&self, lower: &Visible, upper: &Visible) -> bool {
        let Some(draws) = &self.draws.current else { return false };
        let (a, b) = (&draws.objects[lower.index][lower.version], &draws.objects[upper.index][upper.version]);
        let one_cover = Arc::ptr_eq(&a.mesh, &b.mesh) || (a.shape == b.shape && (a.outline || b.outline));
        self.pair_candidate(lower) && self.pair_candidate(upper) && one_cover
    }

    /// The mesh a pair is drawn on: the one draw's grid where the other draws an outline.
    fn pair_mesh<'a>(draws: &'a SkyObjectDraws, lower: &Visible, upper: &Visible) -> &'a VersionDraw {
        let (a, b) = (&draws.objects[lower.index][lower.version], &draws.objects[upper.index][upper.version]);
        if a.outline && !b.outline {
            b
        } else {
            a
        }
    }

    /// The signature of draws `lower` and `upper` drawn at once this frame, `lower` over the seed
    /// or not.
    fn pair_key(&self, lower: &Visible, upper: &Visible, target: Target, over_seed: bool) -> Option<PairKey> {
        if !self.pairable(lower, upper) {
            return None;
        }
        let placement = if over_seed { Slot::OverSeed } else { Slot::Plain };
        let lower = self.entry_key(lower, target, placement).filter(|k| k.placement == placement)?;
        Some(PairKey { lower, upper: self.entry_key(upper, target, Slot::Plain)? })
    }

    /// The index ranges draws `lower` and `upper` (on one mesh of `index_count` indices) both
    /// draw, each with both draws' level-0 stages; None where they do not draw the same
    /// triangles.
    fn pair_parts(&self, lower: &Visible, upper: &Visible, index_count: u32) -> Option<Vec<(std::ops::Range<u32>, u8, u8)>> {
        let parts = |e: &Visible| match e.parts {
            (_, 0) => vec![(0..index_count, 0)],
            (start, count) => self.parts[start as usize..(start + count) as usize].to_vec(),
        };
        let (mut a, mut b) = (parts(lower), parts(upper));
        // An outline drawn on the other's grid: that grid's rows, with the outline's level-0
        // stages (those of every row in view).
        let outline = |e: &Visible| self.draws.current.as_ref().is_some_and(|d| d.objects[e.index][e.version].outline);
        match (outline(lower), outline(upper)) {
            (true, false) => a = b.iter().map(|p| (p.0.clone(), a.first().map_or(0, |q| q.1))).collect(),
            (false, true) => b = a.iter().map(|p| (p.0.clone(), b.first().map_or(0, |q| q.1))).collect(),
            _ => {}
        }
        let mut shared = Vec::new();
        let (mut i, mut j) = (0, 0);
        while i < a.len() && j < b.len() {
            let (ra, rb) = (&a[i].0, &b[j].0);
            let range = ra.start.max(rb.start)..ra.end.min(rb.end);
            if !range.is_empty() {
                shared.push((range, a[i].1, b[j].1));
            }
            if ra.end <= rb.end {
                i += 1;
            } else {
                j += 1;
            }
        }
        let indices = |r: &std::ops::Range<u32>| r.end - r.start;
        let both: u32 = shared.iter().map(|p| indices(&p.0)).sum();
        (both == a.iter().map(|p| indices(&p.0)).sum::<u32>() && both == b.iter().map(|p| indices(&p.0)).sum::<u32>()).then_some(shared)
    }

    /// Builds the specialised pipelines this frame's draws need and do not have yet.
    fn build_variants(&mut self, device: &wgpu::Device, target: Target, runs: bool) {
        for e in &self.visible {
            // Drawn as it is, and (on the frame, with runs) possibly after the run above it, or
            // first under the background when additive.
            let placed = |p: Slot, wanted: bool| self.entry_key(e, target, p).filter(|k| wanted && k.placement == p);
            // As the background only when it may cover the frame (an additive dome layer).
            let background = runs && self.additive(e) && self.dome_of(e);
            // As the background with its sparse stage left to the texel polygons.
            let texel_stage = self.draws.current.as_ref().and_then(|d| d.objects[e.index][e.version].texels.as_ref()).map(|t| t.0);
            let without = |p: Slot| placed(p, background).zip(texel_stage).and_then(|(k, stage)| Self::without_texel_stage(&k, stage));
            let wanted = [
                self.entry_key(e, target, Slot::Plain),
                placed(Slot::UnderRun, runs),
                placed(Slot::First, runs && self.additive(e)),
                placed(Slot::Background, background),
                placed(Slot::JoinedBackground, background),
                // The first layer of a seeded buffer: any whole dome layer reduced.
                placed(Slot::OverSeed, runs && self.dome_of(e)),
                without(Slot::Background),
                without(Slot::JoinedBackground),
            ];
            for key in wanted.into_iter().flatten() {
                if self.variants.contains_key(&key) {
                    continue;
                }
                let constants = key.constants();
                let format = match (key.reduced, key.target) {
                    (true, target) => super::reduced_layers::reduced_format(target),
                    (false, Target::Hdr) => super::HDR_FORMAT,
                    (false, Target::Display) => self.display_format,
                };
                let blend = match (key.reduced, key.placement) {
                    (true, Slot::OverSeed) => None,
                    (true, _) => Some(super::reduced_layers::REDUCED_BLENDS[key.blend]),
                    (false, Slot::UnderRun) => UNDER_RUN_BLENDS[key.blend],
                    (false, Slot::Plain | Slot::First) => BLENDS[key.blend],
                    // Not made (`entry_key`): reduced only.
                    (false, Slot::Background | Slot::JoinedBackground | Slot::OverSeed) => None,
                };
                // Reduced buffers have no depth: the composite is depth-tested instead. Draws
                // under the background come before the scene, which covers what they hide.
                let depth = match (key.reduced, key.placement) {
                    (true, _) => None,
                    (false, Slot::First | Slot::Background | Slot::JoinedBackground) => Some(wgpu::CompareFunction::Always),
                    (false, _) => Some(wgpu::CompareFunction::Less),
                };
                let label = format!("SkyObjects::pipeline {key:?}");
                let built = create_pipeline(device, (&self.pipeline_layout, &self.pipelines.get().module, MAIN), &label, (blend, format, depth), &constants);
                if let Err(e) = &built {
                    log::error!("{label}: {e}; the generic pipeline draws this material whole on the frame, reduced or split parts are not drawn");
                }
                self.variants.insert(key, built.ok());
            }
        }
        // The polygons' pipelines of sparse stages of background draws (the draws without the
        // stage are variants, above).
        let mut texel_keys = Vec::new();
        for e in self.visible.iter().filter(|e| runs && self.additive(e) && self.dome_of(e)) {
            let Some(stage) = self.draws.current.as_ref().and_then(|d| d.objects[e.index][e.version].texels.as_ref()).map(|t| t.0) else { continue };
            for placement in [Slot::Background, Slot::JoinedBackground] {
                if let Some(key) = self.entry_key(e, target, placement).filter(|k| Self::without_texel_stage(k, stage).is_some()) {
                    texel_keys.push((key, stage));
                }
            }
        }
        for (key, stage) in texel_keys {
            if let Some(without) = Self::without_texel_stage(&key, stage).filter(|k| !self.fullscreen_pipelines.contains_key(k)) {
                let label = format!("SkyObjects::fullscreen {without:?}");
                let built = create_pipeline(
                    device,
                    (&self.pipeline_layout, &self.pipelines.get().module, FULLSCREEN),
                    &label,
                    (None, self.display_format, Some(wgpu::CompareFunction::Always)),
                    &without.constants(),
                );
                if let Err(e) = &built {
                    log::error!("{label}: {e}; drawn on the dome");
                }
                self.fullscreen_pipelines.insert(without, built.ok());
            }
            if !self.texel_pipelines.contains_key(&key) {
                let label = format!("SkyObjects::texels {key:?}");
                let mut constants = key.constants();
                constants.push(("TEXEL_STAGE", stage as f64));
                let built = create_pipeline(
                    device,
                    (&self.pipeline_layout, &self.pipelines.get().module, TEXELS),
                    &label,
                    (BLENDS[BLEND_ADD], self.display_format, Some(wgpu::CompareFunction::Always)),
                    &constants,
                );
                if let Err(e) = &built {
                    log::error!("{label}: {e}; the stage is sampled");
                }
                self.texel_pipelines.insert(key, built.ok());
            }
        }
        // Pairs: each reduced alpha layer with the next one in the renderer's order (priority,
        // then this list's), over the seed too where the lower is a whole dome.
        let mut alpha: Vec<usize> = (0..self.visible.len()).filter(|&k| self.pair_candidate(&self.visible[k])).collect();
        alpha.sort_by_key(|&k| self.visible[k].priority);
        let mut wanted = Vec::new();
        for w in alpha.windows(2) {
            let (lower, upper) = (&self.visible[w[0]], &self.visible[w[1]]);
            wanted.extend([false, true].into_iter().filter(|&o| !o || self.dome_of(lower)).filter_map(|o| self.pair_key(lower, upper, target, o)));
        }
        for key in wanted {
            if self.pairs.contains_key(&key) {
                continue;
            }
            let label = format!("SkyObjects::pair {key:?}");
            let blend = if key.lower.placement == Slot::OverSeed { None } else { Some(PAIR_BLEND) };
            let format = super::reduced_layers::reduced_format(target);
            let built = create_pipeline(device, (&self.pair_layout, &self.pipelines.get().module, PAIR), &label, (blend, format, None), &key.constants());
            if let Err(e) = &built {
                log::error!("{label}: {e}; the two layers are drawn one after the other");
            }
            self.pairs.insert(key, built.ok());
        }
    }
}

/// Entry points (vertex, fragment) of one draw's pipelines and of a pair's.
/// A background draw with its sparse stage texel by texel this frame ([`SkyObjectsPass::texel_draw`]).
struct TexelDraw<'a> {
    /// The stage the polygons stand for.
    stage: usize,
    /// The draw without the stage, on the grid or its bands.
    without: &'a wgpu::RenderPipeline,
    /// The same as one triangle over the frame ([`super::strategy::SparseStages::TexelPolygonsOnBands`]), if built.
    fullscreen: Option<&'a wgpu::RenderPipeline>,
    /// The polygons' pipeline and mesh.
    polygons: &'a wgpu::RenderPipeline,
    mesh: &'a GpuTexelMesh,
}

const MAIN: (&str, &str) = ("vs_main", "fs_main");
const PAIR: (&str, &str) = ("vs_pair", "fs_pair");
const TEXELS: (&str, &str) = ("vs_texels", "fs_texels");
const FULLSCREEN: (&str, &str) = ("vs_fullscreen", "fs_main");

/// `frame` (x, y, width, height) less the rectangles `holes`, as rectangles that do not overlap.
fn scissor_rects(frame: [u32; 4], holes: &[[u32; 4]]) -> Vec<[u32; 4]> {
    let mut rects = vec![frame];
    for &[hx, hy, hw, hh] in holes {
        let (hx1, hy1) = (hx + hw, hy + hh);
        let mut out = Vec::new();
        for [x, y, w, h] in rects {
            let (x1, y1) = (x + w, y + h);
            if hx >= x1 || hx1 <= x || hy >= y1 || hy1 <= y {
                out.push([x, y, w, h]);
                continue;
            }
            // Above and below the hole across the rectangle, then left and right of it beside it.
            let (top, bottom) = (hy.max(y), hy1.min(y1));
            let pieces = [[x, y, w, top - y], [x, bottom, w, y1 - bottom], [x, top, hx.max(x) - x, bottom - top], [hx1.min(x1), top, x1 - hx1.min(x1), bottom - top]];
            out.extend(pieces.into_iter().filter(|r| r[2] > 0 && r[3] > 0));
        }
        rects = out;
    }
    rects
}

/// One sky-object pipeline: `constants` specialise it (none: the generic pipeline).
fn create_pipeline(
    device: &wgpu::Device,
    (layout, module, (vertex, fragment)): (&wgpu::PipelineLayout, &wgpu::ShaderModule, (&str, &str)),
    label: &str,
    (blend, format, depth): (Option<wgpu::BlendState>, wgpu::TextureFormat, Option<wgpu::CompareFunction>),
    constants: &[(&str, f64)],
) -> RenderResult<wgpu::RenderPipeline> {
    let options = wgpu::PipelineCompilationOptions { constants, zero_initialize_workgroup_memory: true };
    shaders::validated(device, label, || {
        device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(label),
            layout: Some(layout),
            vertex: wgpu::VertexState {
                module,
                entry_point: Some(vertex),
                buffers: match vertex {
                    v if v == TEXELS.0 => &[Some(TexelVertex::LAYOUT)],
                    v if v == FULLSCREEN.0 => &[],
                    _ => &[Some(SkyVertex::LAYOUT)],
                },
                compilation_options: options.clone(),
            },
            primitive: wgpu::PrimitiveState { cull_mode: None, ..Default::default() },
            depth_stencil: depth.and_then(|compare| super::depth_state(false, compare)),
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module,
                entry_point: Some(fragment),
                targets: &[Some(wgpu::ColorTargetState { format, blend, write_mask: wgpu::ColorWrites::ALL })],
                compilation_options: options,
            }),
            multiview_mask: None,
            cache: None,
        })
    })
}

impl Pass for SkyObjectsPass {
    fn name(&self) -> &'static str {
        "sky_objects"
    }

    fn phase(&self) -> Phase {
        Phase::Sky
    }

    fn stage_pipelines(&mut self, b: &PassBuild<'_>) -> RenderResult<()> {
        self.pipelines.stage(b)
    }

    fn commit_pipelines(&mut self, accept: bool) {
        self.pipelines.commit(accept);
        if accept {
            // Rebuilt from the new module on their next use.
            self.variants.clear();
            self.pairs.clear();
            self.texel_pipelines.clear();
            self.fullscreen_pipelines.clear();
        }
    }

    fn stage_sky(&mut self, up: &mut SkyUpload<'_>) {
        let draws = SkyObjectDraws::new(up.device, up.queue, (&self.bind_layout, &self.sky_view), up.textures, up.sky, self.draws.current.as_ref());
        self.draws.stage(Some(draws));
    }

    fn commit_sky(&mut self, accept: bool) {
        self.draws.commit(accept);
    }

    fn prepare(&mut self, cx: &FrameContext<'_>) {
        self.visible.clear();
        self.hidden = 0;
        self.draws_dark = 0;
        self.texels_on = cx.options.strategy.texel_polygons() && cx.target == Target::Display;
        self.bands_on = cx.options.strategy.grid_bands();
        self.texel_triangles.set(0);
        self.background_rects.set(0);
        let Some(draws) = &self.draws.current else { return };
        let neutral = super::tone_map::ToneMapUniform::from(cx.frame.sky_model.tone_mapper).settings[0] != 0;
        self.keys.clear();
        self.stages_skipped = draws.prepare(cx.queue, cx.frame, cx.camera, cx.options.skips.dark_stages, (cx.target, neutral), &mut self.keys);
        self.ref_hidden = 0;
        self.below_horizon = 0;
        self.off_screen = 0;
        // The frame's elevations, with a margin for the dome's chords (tests in mesh.rs).
        let (lowest_deg, highest_deg) = cx.camera.elevation_range_deg(cx.size.0 as f32 / cx.size.1.max(1) as f32);
        self.frame_elevations_deg = (lowest_deg, highest_deg);
        (self.frame_camera, self.frame_size) = (*cx.camera, cx.size);
        let in_view = |shape: &Shape| match *shape {
            Shape::Dome { bottom_deg } => bottom_deg.get() - 0.5 <= highest_deg,
            Shape::DomeBand { bottom_deg, top_deg } => {
                let (lo, hi) = (bottom_deg.get().min(top_deg.get()), bottom_deg.get().max(top_deg.get()));
                lo - 0.5 <= highest_deg && hi + 0.5 >= lowest_deg
            }
            Shape::Billboard { .. } | Shape::Quad { .. } => true,
        };
        let cull = cx.options.skips.off_screen;
        let behind_scene = |of: &crate::sky::ObjectFrame, versions: &[crate::sky::VersionFrame]| {
            let Some((dir, _)) = of.placement.filter(|_| cx.options.scene && cx.options.skips.below_horizon) else { return false };
            let elevation_deg = dir.y.clamp(-1.0, 1.0).asin().to_degrees();
            versions.iter().all(|v| match draws.objects[of.index][v.version].shape {
                // Half the diagonal of the square: its highest corner at any roll.
                crate::sky::resolved::Shape::Billboard { size_deg } | crate::sky::resolved::Shape::Quad { size_deg } => {
                    elevation_deg + size_deg.get() * std::f32::consts::FRAC_1_SQRT_2 < -super::renderer::SCENE_COVERS_BELOW_DEG
                }
                _ => false,
            })
        };
        // Billboards and quads wholly outside the frame: a draw that shows nothing still costs
        // its vertices and its state (a small saving: docs/architecture.md).
        let aspect = cx.size.0 as f32 / cx.size.1.max(1) as f32;
        let out_of_frame = |of: &crate::sky::ObjectFrame, versions: &[crate::sky::VersionFrame]| {
            let Some((dir, _)) = of.placement.filter(|_| cull) else { return false };
            versions.iter().all(|v| match draws.objects[of.index][v.version].shape {
                // The square's half diagonal, flat at its distance, and half a degree of margin.
                Shape::Billboard { size_deg } | Shape::Quad { size_deg } => {
                    let half_diagonal_deg = ((size_deg.get() * 0.5).to_radians().tan() * std::f32::consts::SQRT_2).atan().to_degrees();
                    size_deg.get() < 170.0 && !cx.camera.sees_cone(aspect, dir, half_diagonal_deg + 0.5)
                }
                _ => false,
            })
        };
        let (finest, coarsest) = cx.options.strategy.dome_resolution.divisors();
        let finest_whole = cx.options.strategy.dome_resolution.finest_whole();
        let reduce_domes = finest > Divisor::FULL;
        // The frame's pixels per degree of view at its centre.
        let frame_px_per_deg = cx.size.1 as f32 / cx.camera.fov_y_deg.max(1.0);
        let reduced_px_per_deg = frame_px_per_deg / finest.get();
        for of in &cx.frame.objects {
            match &of.versions {
                Ok(versions) if behind_scene(of, versions) => {
                    self.hidden += 1;
                    self.below_horizon += 1;
                }
                Ok(versions) if cull && (versions.iter().all(|v| !in_view(&draws.objects[of.index][v.version].shape)) || out_of_frame(of, versions)) => {
                    self.hidden += 1;
                    self.off_screen += 1;
                }
                Ok(versions) => {
                    for v in versions {
                        let d = &draws.objects[of.index][v.version];
                        let entry = Visible {
                            index: of.index,
                            priority: of.priority,
                            version: v.version,
                            reduced: false,
                            divisor: Divisor::FULL,
                            part: [true; 4],
                            on_top: false,
                            parts: (0, 0),
                        };
                        // Blended by its alpha with every term black and transparent this frame (a
                        // night-only card by day), the draw's material is 0 and leaves every
                        // buffer as it is: not drawn.
                        let key = self.keys.get(&(of.index, v.version));
                        let dark = key.filter(|_| cx.options.skips.dark_stages).is_some_and(|key| {
                            let count = (key.count as usize).min(MAX_STAGES);
                            d.blend != BlendMode::Opaque && !key.live[..count].iter().any(|&live| live)
                        });
                        if dark {
                            self.draws_dark += 1;
                            continue;
                        }
                        let dome = matches!(d.shape, Shape::Dome { .. } | Shape::DomeBand { .. });
                        let Some(key) = key.filter(|_| reduce_domes && dome) else {
                            self.visible.push(entry);
                            continue;
                        };
                        // A term is fine when a texture it samples this frame has finer detail
                        // than the reduced buffer's pixels (the skydome's stars at night).
                        let count = (key.count as usize).min(MAX_STAGES);
                        let terms = stage_terms(key.ops);
                        let fine_stage = |k: usize| key.live[k] && d.texels_per_deg[k] > reduced_px_per_deg;
                        let fine: [bool; 4] = std::array::from_fn(|k| k < count && (0..count).any(|j| terms[j] == terms[k] && fine_stage(j)));
                        let coarse: [bool; 4] = std::array::from_fn(|k| k < count && !fine[k]);
                        let any_fine = (0..count).any(|k| fine[k] && key.live[k]);
                        let any_coarse = (0..count).any(|k| coarse[k] && key.live[k]);
                        // The coarsest buffer allowed that resolves every coarse stage sampled (no
                        // stage sampled: the coarsest). A physical sky model's stage stays at the
                        // finest: its map has no texel size here, and the sun's aureole is sharp.
                        // The most texels per degree among the stages sampled of `stages`.
                        let densest = |stages: [bool; 4]| (0..count).filter(|&k| stages[k] && key.live[k]).map(|k| d.texels_per_deg[k]).fold(0.0, f32::max);
                        let physical = (key.view_stage as usize) < MAX_STAGES;
                        let divisor = if physical { finest } else { Divisor::at_most(frame_px_per_deg / densest(coarse), finest, coarsest) };
                        let reduced = Visible { reduced: true, divisor, ..entry };
                        match (any_fine, any_coarse, d.blend) {
                            (false, _, _) => self.visible.push(reduced),
                            // Terms add up: the coarse ones at reduced resolution, then the fine
                            // ones added on top at full resolution (opaque layers only: under
                            // alpha blending the terms' alphas do not add).
                            (true, true, BlendMode::Opaque) => {
                                self.visible.push(Visible { part: coarse, ..reduced });
                                self.visible.push(Visible { part: fine, on_top: true, ..entry });
                            }
                            // Whole, in a buffer between `finest_whole` and the finest where one
                            // resolves every texture it samples (a cloud layer with a fine texture).
                            (true, _, BlendMode::Alpha) if !physical => {
                                let factor = frame_px_per_deg / densest([true; 4]);
                                if factor >= finest_whole.get() {
                                    self.visible.push(Visible { reduced: true, divisor: Divisor::at_most(factor, finest_whole, finest), ..entry });
                                } else {
                                    self.visible.push(entry);
                                }
                            }
                            _ => self.visible.push(entry),
                        }
                    }
                }
                Err(why) => {
                    self.hidden += 1;
                    self.ref_hidden += u32::from(matches!(why, crate::sky::Hidden::RefAlphaZero(_)));
                }
            }
        }
        // Stages whose level of detail stays at most 1/2 wherever they are drawn, at each draw's
        // resolution: the mipmapped sampler (nearest level, linear within it, the same filter
        // either side of 0) reads level 0 there too (Vulkan: level ceil(lod + 1/2) - 1), so a
        // level-0 sampler gives the same pixels without the level-of-detail work.
        // Domes decide per ring of triangles, since texture coordinates crowd towards the pole (a
        // view of the zenith needs the tiled stars' levels round the zenith, not lower down); the
        // rings the frame does not show are left out.
        self.level0_stages = 0;
        self.parts.clear();
        if cx.options.skips.unneeded_mips {
            let view = FrameView::new(cx.camera, cx.aspect(), (lowest_deg, highest_deg), cx.frame.towards_sun, cx.frame.celestial_from_world);
            // Drawn or not, the scene's pixels there are the scene's (reduced buffers keep their
            // clear colour there, too far below the scene's edge for the upsampling to reach).
            let covered_below_deg = if cx.options.scene && cx.options.skips.below_horizon { -super::renderer::SCENE_COVERS_BELOW_DEG } else { f32::NEG_INFINITY };
            for e in &mut self.visible {
                let d = &draws.objects[e.index][e.version];
                // Frame pixels per degree at the frame's centre (the fewest: a perspective frame
                // has more per degree towards its edges), in this draw's buffer.
                let px_per_deg = view.centre_px_per_deg(cx.size.1) / e.divisor.get();
                let level0 = |ring: Option<usize>| {
                    (0..MAX_STAGES)
                        .filter(|&k| d.maps[k].as_ref().is_some_and(|m| m.peak(&d.shape, ring, &view) * LOD_MARGIN <= px_per_deg * std::f32::consts::SQRT_2))
                        .fold(0u8, |m, k| m | 1 << k)
                };
                let start = self.parts.len();
                let mut used = 0u8;
                match super::mesh::dome_grid(&d.shape) {
                    Some((top_deg, bottom_deg, rings, segments)) => {
                        let per_ring = segments * 6;
                        for r in 0..rings {
                            let (a, b) = (top_deg + (bottom_deg - top_deg) * r as f32 / rings as f32, top_deg + (bottom_deg - top_deg) * (r + 1) as f32 / rings as f32);
                            let (ring_lo, ring_hi) = (a.min(b), a.max(b));
                            // With the margin of the chords' sag (tests in mesh.rs); rings the
                            // scene covers whole are left out too.
                            if ring_lo - 0.5 > highest_deg || ring_hi + 0.5 < lowest_deg.max(covered_below_deg) {
                                continue;
                            }
                            let mask = level0(Some(r as usize));
                            // The outline's one band spans every ring: a stage is sampled from
                            // level 0 there where it can be in every ring in view.
                            if d.outline {
                                let part = self.parts.get_mut(start).map(|(_, m)| m);
                                match part {
                                    Some(m) => *m &= mask,
                                    None => self.parts.push((0..per_ring, mask)),
                                }
                                continue;
                            }
                            used |= mask;
                            let indices = r * per_ring..(r + 1) * per_ring;
                            let ours = self.parts.len() > start;
                            match self.parts.last_mut() {
                                Some((range, m)) if ours && *m == mask && range.end == indices.start => range.end = indices.end,
                                _ => self.parts.push((indices, mask)),
                            }
                        }
                        if d.outline {
                            used |= self.parts.get(start).map_or(0, |p| p.1);
                        }
                        // No ring in view: one empty part, drawn as nothing.
                        if self.parts.len() == start {
                            self.parts.push((0..0, 0));
                        }
                    }
                    None => {
                        used = level0(None);
                        self.parts.push((0..d.mesh.index_count, used));
                    }
                }
                e.parts = (start as u32, (self.parts.len() - start) as u32);
                self.level0_stages += used.count_ones();
            }
        }
        // Draws on the frame may come between two runs that the renderer joins: their
        // corrected variants are built too.
        self.build_variants(cx.device, cx.target, reduce_domes);
    }

    fn items(&self, cx: &FrameContext<'_>, out: &mut Vec<DrawItem>) {
        let target = cx.target;
        // The next item in priority order (the sky phase's order among this pass's items, stable).
        let mut order: Vec<usize> = (0..self.visible.len()).collect();
        order.sort_by_key(|&k| self.visible[k].priority);
        let mut next = vec![None; self.visible.len()];
        for w in order.windows(2) {
            next[w[0]] = Some(w[1]);
        }
        out.extend(self.visible.iter().enumerate().map(|(key, e)| DrawItem {
            reduced: e.reduced,
            additive: self.additive(e),
            divisor: e.divisor,
            caps: self.caps(key, target, next[key]),
            ..DrawItem::new(e.priority, key)
        }));
    }

    fn draw(&self, rpass: &mut wgpu::RenderPass<'_>, key: usize, target: Target, placement: Placement, run: Option<&wgpu::BindGroup>) -> u32 {
        match placement {
            Placement::Plain => self.record(rpass, key, target, false, (Slot::Plain, None)),
            Placement::Reduced => self.record(rpass, key, target, true, (Slot::Plain, None)),
            Placement::UnderRun => self.record(rpass, key, target, false, (Slot::UnderRun, run)),
            Placement::First => self.record(rpass, key, target, false, (Slot::First, None)),
            Placement::OverSeed => self.record(rpass, key, target, true, (Slot::OverSeed, run)),
            Placement::Background { joined } => self.record(rpass, key, target, false, (Slot::background(joined), run)),
            Placement::Pair { upper, over_seed } => self.record_pair(rpass, (key, upper), target, run.filter(|_| over_seed)),
        }
    }

    fn stats_recorded(&self, stats: &mut FrameStats) {
        stats.texel_triangles = self.texel_triangles.get();
        stats.background_rects = self.background_rects.get();
    }

    fn stats(&self, stats: &mut FrameStats) {
        let mut objects: Vec<usize> = self.visible.iter().map(|e| e.index).collect();
        objects.dedup();
        stats.objects_drawn = objects.len() as u32;
        stats.objects_hidden = self.hidden;
        stats.stages_skipped = self.stages_skipped;
        stats.draws_dark = self.draws_dark;
        stats.objects_ref_hidden = self.ref_hidden;
        stats.objects_below_horizon = self.below_horizon;
        stats.objects_off_screen = self.off_screen;
        stats.stages_level0 = self.level0_stages;
        let mut reduced: Vec<usize> = self.visible.iter().filter(|e| e.reduced).map(|e| e.index).collect();
        reduced.dedup();
        stats.objects_reduced = reduced.len() as u32;
    }
}

/// GPU resources of one version (standard or fallback pass) of an object.
struct VersionDraw {
    uniform: wgpu::Buffer,
    /// By the stages sampled from level 0 alone (bit k: stage k, within `level0_able`).
    bind_groups: Vec<wgpu::BindGroup>,
    /// Stages that have a level-0 variant: those with a texture of their own.
    level0_able: u8,
    /// How each stage's texture lies on the sky (None: no stage or no texture).
    maps: [Option<StageMap>; MAX_STAGES],
    mesh: Arc<GpuMesh>,
    /// The mesh is the dome's outline ([`outline_mesh`]), one band of triangles, not its grid.
    outline: bool,
    gradient: Option<(wgpu::Texture, u32)>,
    /// The stage the gradient feeds (and a physical sky model replaces).
    gradient_stage: Option<usize>,
    blend: BlendMode,
    shape: Shape,
    base: DrawUniform,
    /// Finest detail of each stage's texture on the sky, texels per degree (0: no stage).
    texels_per_deg: [f32; 4],
    /// A sparse stage's texels as polygons on the grid ([`super::texel_quads`]): the stage and
    /// its polygons.
    texels: Option<(usize, Arc<GpuTexelMesh>)>,
}

/// The finest detail a stage's texture puts on the sky, texels per degree of view direction:
/// what a buffer needs at least to show it. The gradient stage (no texture) varies only slowly,
/// by elevation.
fn stage_texels_per_deg(stage: &crate::sky::resolved::Stage, shape: &Shape) -> f32 {
    let Some(t) = &stage.texture else { return 0.0 };
    let (w, h) = (t.width as f32 * stage.uv_scale[0].abs(), t.height as f32 * stage.uv_scale[1].abs());
    let (bottom_deg, top_deg) = match *shape {
        Shape::Dome { bottom_deg } => (bottom_deg.get(), 90.0),
        Shape::DomeBand { bottom_deg, top_deg } => (bottom_deg.get(), top_deg.get()),
        Shape::Billboard { size_deg } | Shape::Quad { size_deg } => (0.0, size_deg.get()),
    };
    let span_deg = (top_deg - bottom_deg).abs().max(1e-3);
    match stage.uv {
        UvSource::Mesh => (w / 360.0).max(h / span_deg),
        UvSource::Sun { size_deg } => w.max(h) / size_deg.get().abs().max(1e-3),
        UvSource::Celestial => (w / 360.0).max(h / 180.0),
        UvSource::Quake { z_scale, z_offset, t_scale, .. } => {
            w.max(h) * quake_uv_per_rad(z_scale.get(), z_offset.get(), t_scale.get(), bottom_deg.min(top_deg), bottom_deg.max(top_deg)).to_radians()
        }
    }
}

/// How much larger a stage's computed peak texel density may be than the level-of-detail the
/// rasteriser derives (from differences across 2x2 pixels, along triangles' chords rather than
/// arcs) before a level-0 sampler could differ from the mipmapped one.
const LOD_MARGIN: f32 = 1.25;

/// What the frame shows, for bounding how finely a texture lands on its pixels.
struct FrameView {
    /// Lowest and highest elevation in the frame, degrees.
    elevation_deg: (f32, f32),
    /// Largest angle between the sun and a direction in the frame, degrees.
    sun_max_deg: f32,
    /// Half the frame's vertical field of view, radians.
    half_fov_y: f32,
    /// A lower bound of the angle between the frame and the nearer pole of the celestial
    /// mapping's texture (where its columns converge), degrees.
    celestial_pole_deg: f32,
}

impl FrameView {
    fn new(camera: &Camera, aspect: f32, elevation_deg: (f32, f32), towards_sun: Vec3, celestial_from_world: Quat) -> Self {
        let half_fov_y = (camera.fov_y_deg.to_radians() * 0.5).min(1.55);
        let t = half_fov_y.tan();
        let half_diagonal = (t * t * (1.0 + aspect * aspect)).sqrt().atan();
        let to_sun = camera.forward().dot(towards_sun.normalize_or_zero()).clamp(-1.0, 1.0).acos();
        // The mapping's latitude is that of the celestial frame's y axis (shaders/sky_objects.wgsl,
        // `celestial_uv`). The largest cone round each pole that the frame does not show, by
        // bisection: `sees_cone` only errs towards showing.
        let north = celestial_from_world.inverse() * Vec3::Y;
        let unseen = |r: f32| !camera.sees_cone(aspect, north, r) && !camera.sees_cone(aspect, -north, r);
        let mut celestial_pole_deg = 0.0;
        if unseen(0.0) {
            let mut above = 90.0;
            for _ in 0..12 {
                let mid = 0.5 * (celestial_pole_deg + above);
                if unseen(mid) {
                    celestial_pole_deg = mid;
                } else {
                    above = mid;
                }
            }
        }
        Self { elevation_deg, sun_max_deg: (to_sun + half_diagonal).to_degrees().min(180.0), half_fov_y, celestial_pole_deg }
    }

    /// Pixels per degree of view direction at the frame's centre for a frame `height_px` high.
    fn centre_px_per_deg(&self, height_px: u32) -> f32 {
        height_px as f32 * 0.5 / self.half_fov_y.tan() * std::f32::consts::PI / 180.0
    }
}

/// How one stage's texture lies on the sky: its mapping and its size in texels across one
/// repeat of the mapping, times the stage's repeats (u, v).
#[derive(Debug, Clone)]
struct StageMap {
    uv: UvSource,
    texels: (f32, f32),
    /// On a dome, under the mesh or the Quake mapping: the peak density over each ring of
    /// triangles (top first), which does not depend on the view (the Quake mapping's takes a
    /// dense search: computed once, not every frame).
    ring_peaks: Vec<f32>,
}

impl StageMap {
    /// None for a stage without a texture of its own (the gradient: one texel wide, no levels).
    fn of(stage: &crate::sky::resolved::Stage, shape: &Shape) -> Option<Self> {
        let t = stage.texture.as_ref()?;
        Some(Self::with_texels(stage.uv, (t.width as f32 * stage.uv_scale[0].abs(), t.height as f32 * stage.uv_scale[1].abs()), shape))
    }

    /// A texture `texels` across one repeat of mapping `uv` on `shape`.
    fn with_texels(uv: UvSource, texels: (f32, f32), shape: &Shape) -> Self {
        let mut map = Self { uv, texels, ring_peaks: Vec::new() };
        if let (UvSource::Mesh | UvSource::Quake { .. }, Some((top_deg, bottom_deg, rings, _))) = (uv, super::mesh::dome_grid(shape)) {
            map.ring_peaks = (0..rings)
                .map(|r| {
                    let (a, b) = (top_deg + (bottom_deg - top_deg) * r as f32 / rings as f32, top_deg + (bottom_deg - top_deg) * (r + 1) as f32 / rings as f32);
                    // A view of just this ring (neither mapping looks at the sun or the frame).
                    map.peak_texels_per_deg(shape, &FrameView { elevation_deg: (a.min(b), a.max(b)), sun_max_deg: 180.0, half_fov_y: 0.0, celestial_pole_deg: 0.0 })
                })
                .collect();
        }
        map
    }

    /// [`Self::peak_texels_per_deg`] over ring `ring` of a dome's triangles (all of it, where the
    /// frame shows part: as high or higher), or over what `view` shows of the shape.
    fn peak(&self, shape: &Shape, ring: Option<usize>, view: &FrameView) -> f32 {
        match ring.and_then(|r| self.ring_peaks.get(r)) {
            Some(&peak) => peak,
            None => self.peak_texels_per_deg(shape, view),
        }
    }

    /// The most texels of this stage that one degree of view direction crosses anywhere `view`
    /// shows of `shape`, along any screen direction (infinite where unbounded: the celestial
    /// mapping's poles, the antisolar point of a repeating sun mapping).
    fn peak_texels_per_deg(&self, shape: &Shape, view: &FrameView) -> f32 {
        let (w, h) = self.texels;
        let (lo, hi) = view.elevation_deg;
        match self.uv {
            UvSource::Mesh => match super::mesh::dome_grid(shape) {
                // u runs once round the azimuth, v once from the top ring to the bottom one. Along
                // a ring a degree of view crosses 1 / cos(elevation) degrees of azimuth. Each band
                // of triangles between two rings spans a chord of both; the triangles round a pole
                // are spanned by the ring next to it.
                Some((top_deg, bottom_deg, rings, _)) => {
                    let (shape_lo, shape_hi) = (bottom_deg.min(top_deg), bottom_deg.max(top_deg));
                    let (a, b) = (lo.max(shape_lo), hi.min(shape_hi));
                    if a > b {
                        return 0.0;
                    }
                    let step = ((shape_hi - shape_lo) / rings as f32).max(1e-3);
                    let ring_lo = shape_lo + ((a - shape_lo) / step).floor() * step;
                    let ring_hi = (shape_lo + ((b - shape_lo) / step).ceil() * step).min(shape_hi);
                    let inward = |e: f32| if e.abs() >= 90.0 - 1e-3 { e - step * e.signum() } else { e };
                    let steepest = inward(ring_lo).abs().max(inward(ring_hi).abs()).min(89.9);
                    let along = w / 360.0 / steepest.to_radians().cos();
                    let across = h / (shape_hi - shape_lo).max(1e-3);
                    along.max(across)
                }
                // A square size_deg across, flat at its distance: a texel is smaller in angle
                // away from its centre (by cos^2 at the corners, half a diagonal out).
                None => {
                    let size_deg = match *shape {
                        Shape::Billboard { size_deg } | Shape::Quad { size_deg } => size_deg.get(),
                        _ => return f32::INFINITY,
                    };
                    let half_diagonal = (size_deg * 0.5 * std::f32::consts::SQRT_2).to_radians();
                    if half_diagonal >= 1.5 {
                        return f32::INFINITY;
                    }
                    w.max(h) / size_deg / half_diagonal.cos().powi(2)
                }
            },
            // Distance from the sun maps linearly to radius, size_deg across; round the sun a
            // degree of view crosses angle / sin(angle) degrees of that map.
            UvSource::Sun { size_deg } => {
                let angle = view.sun_max_deg.to_radians();
                if angle >= std::f32::consts::PI - 0.02 {
                    return f32::INFINITY;
                }
                let stretch = if angle > 1e-3 { (angle / angle.sin()).max(1.0) } else { 1.0 };
                w.max(h) / size_deg.get().abs().max(1e-3) * stretch
            }
            // Plate carree: along a circle of latitude a degree of view crosses 1 / cos(latitude)
            // degrees of longitude, most near a pole.
            UvSource::Celestial => {
                let from_pole = view.celestial_pole_deg.to_radians().sin();
                if from_pole < 1e-3 {
                    return f32::INFINITY;
                }
                (w / 360.0 / from_pole).max(h / 180.0)
            }
            UvSource::Quake { z_scale, z_offset, t_scale, .. } => {
                let (shape_lo, shape_hi) = match *shape {
                    Shape::Dome { bottom_deg } => (bottom_deg.get(), 90.0),
                    Shape::DomeBand { bottom_deg, top_deg } => (bottom_deg.get().min(top_deg.get()), bottom_deg.get().max(top_deg.get())),
                    Shape::Billboard { .. } | Shape::Quad { .. } => return f32::INFINITY,
                };
                let (a, b) = (lo.max(shape_lo), hi.min(shape_hi));
                if a > b {
                    return 0.0;
                }
                w.max(h) * quake_uv_per_rad(z_scale.get(), z_offset.get(), t_scale.get(), a, b).to_radians()
            }
        }
    }
}

/// The Quake sky's mapping (`stage_uv` in shaders/sky_objects.wgsl: the direction's y scaled by
/// `z_scale` and moved by `z_offset`, then uv = t_scale x xz / length) at its steepest over the
/// elevations `bottom_deg..top_deg`: texture-coordinate units per radian of view direction. At
/// elevation e the ring of directions lands on a circle of radius t cos(e) / L(e), with
/// L(e) = sqrt(cos^2 e + (z sin e + o)^2): along the ring that is t / L(e) per radian, across it
/// t |d/de (cos e / L(e))|. Sampled densely (the derivative by central differences); the shader's
/// floor on L bounds it where L vanishes.
fn quake_uv_per_rad(z_scale: f32, z_offset: f32, t_scale: f32, bottom_deg: f32, top_deg: f32) -> f32 {
    let (z, o, t) = (z_scale as f64, z_offset as f64, t_scale.abs() as f64);
    let radius = |e: f64| e.cos() / (e.cos().powi(2) + (z * e.sin() + o).powi(2)).sqrt().max(1e-4);
    const SAMPLES: u32 = 512;
    let (lo, hi) = ((bottom_deg as f64).to_radians(), (top_deg as f64).to_radians());
    let step = (hi - lo) / SAMPLES as f64;
    let h = 1e-4;
    let mut steepest: f64 = 0.0;
    for i in 0..=SAMPLES {
        let e = lo + step * i as f64;
        let l = (e.cos().powi(2) + (z * e.sin() + o).powi(2)).sqrt().max(1e-4);
        let across = ((radius(e + h) - radius(e - h)) / (2.0 * h)).abs();
        steepest = steepest.max(1.0 / l).max(across);
    }
    (t * steepest) as f32
}

/// How much finer a texture's texels are than the detail it carries: 2^k for the largest k (at
/// most 4) such that halving it k times and scaling it back up (box down, bilinear up, as a
/// reduced buffer would show it) changes 99% of its channel values by at most
/// [`DETAIL_TOLERANCE`] levels of 255. Soft cloud noise drops levels; a star field does not.
pub fn texture_oversampling(img: &TextureImage) -> f32 {
    use image::imageops::{resize, FilterType};
    let Some(full) = image::RgbaImage::from_raw(img.width, img.height, img.rgba8.clone()) else { return 1.0 };
    let mut factor = 1.0;
    for k in 1..=4u32 {
        let (w, h) = (img.width >> k, img.height >> k);
        if w < 2 || h < 2 {
            break;
        }
        let back = resize(&resize(&full, w, h, FilterType::Triangle), img.width, img.height, FilterType::Triangle);
        let mut diffs: Vec<u8> = full.as_raw().iter().zip(back.as_raw()).map(|(a, b)| a.abs_diff(*b)).collect();
        let at = diffs.len() * 99 / 100;
        let (_, p99, _) = diffs.select_nth_unstable(at);
        if *p99 > DETAIL_TOLERANCE {
            break;
        }
        factor = (1u32 << k) as f32;
    }
    factor
}

/// Levels of 255 a texture may lose in 99% of its values and still count as carried by a
/// coarser sampling ([`texture_oversampling`]).
pub const DETAIL_TOLERANCE: u8 = 4;

/// Per-sky GPU resources: one [`VersionDraw`] per version of every object.
pub struct SkyObjectDraws {
    /// objects[i][v]: object i (in draw order), version v (0 standard, 1.. fallback).
    objects: Vec<Vec<VersionDraw>>,
    /// Geometry by shape; a reload takes over the meshes of shapes that are still used.
    meshes: HashMap<String, Arc<GpuMesh>>,
    /// Texel polygons by (texture key, content, shape); taken over like the meshes. `None`: the
    /// texture is not sparse.
    texel_meshes: HashMap<(String, u64, String), Option<Arc<GpuTexelMesh>>>,
}

impl SkyObjectDraws {
    /// Uploads every object of a sky, taking over the meshes of `previous` where shapes match.
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        (layout, sky_view): (&wgpu::BindGroupLayout, &(wgpu::TextureView, wgpu::Sampler)),
        cache: &mut TextureCache,
        sky: &Sky,
        previous: Option<&SkyObjectDraws>,
    ) -> Self {
        let old_meshes = previous.map(|p| &p.meshes);
        let mut meshes: HashMap<String, Arc<GpuMesh>> = HashMap::new();
        let old_texels = previous.map(|p| &p.texel_meshes);
        // Folded textures baked in this load, by key: the texture and its texel polygons share one.
        let mut baked: HashMap<String, Arc<TextureImage>> = HashMap::new();
        let mut texel_meshes: HashMap<(String, u64, String), Option<Arc<GpuTexelMesh>>> = HashMap::new();
        let mut oversampling: HashMap<String, f32> = HashMap::new();
        let objects = sky
            .objects
            .iter()
            .map(|o| {
                std::iter::once(&o.standard)
                    .chain(&o.fallback)
                    .enumerate()
                    .map(|(vi, v)| {
                        let label = format!("SkyObjects::{}[{vi}]", o.name);
                        // Where no stage takes its coordinates from the mesh, a dome's triangles
                        // only bound it: its outline does that with one band of them.
                        let outline = v.stages.iter().all(|s| !matches!(s.uv, UvSource::Mesh)).then(|| outline_mesh(&v.shape)).flatten();
                        let key = if outline.is_some() { format!("outline of {}", shape_key(&v.shape)) } else { shape_key(&v.shape) };
                        let is_outline = outline.is_some();
                        let mesh = meshes
                            .entry(key.clone())
                            .or_insert_with(|| match old_meshes.and_then(|m| m.get(&key)) {
                                Some(m) => m.clone(),
                                None => Arc::new(GpuMesh::new(device, &format!("SkyObjects::mesh {key}"), &outline.unwrap_or_else(|| shape_mesh(&v.shape)))),
                            })
                            .clone();
                        let gradient = v.gradients.as_ref().map(|g| {
                            let h = g.bitmaps[0].height;
                            (textures::upload(device, queue, &format!("{label}::gradient"), 1, h, &vec![255; (h * 4) as usize]), h)
                        });
                        let gradient_view = gradient.as_ref().map(|(t, _)| t.create_view(&Default::default()));
                        // Static products of two stages sample one folded texture.
                        let folds = stage_fold::folds(v);
                        let fold_at = |k: usize| folds.iter().find(|f| f.stage == k);
                        let folded_away = |k: usize| k > 0 && fold_at(k - 1).is_some();
                        let mut views = Vec::new();
                        let mut samplers = Vec::new();
                        let mut level0_samplers = Vec::new();
                        for k in 0..MAX_STAGES {
                            let stage = v.stages.get(k);
                            let view = match (fold_at(k), stage.and_then(|s| s.texture.as_ref()), &gradient_view) {
                                _ if folded_away(k) => cache.white.clone(),
                                (Some(f), _, _) => {
                                    let (key, content) = stage_fold::identity(v, f);
                                    cache.derived(device, queue, &key, content, || {
                                        baked.entry(key.clone()).or_insert_with(|| Arc::new(stage_fold::bake(v, f, &key))).as_ref().clone()
                                    })
                                }
                                (None, Some(img), _) => cache.get(device, queue, img),
                                (None, None, Some(gv)) if v.gradients.as_ref().is_some_and(|g| g.stage == k) => gv.clone(),
                                _ => cache.white.clone(),
                            };
                            views.push(view);
                            let clamp = fold_at(k).map_or(stage.is_some_and(|s| s.clamp), |f| f.clamp);
                            samplers.push(if clamp { cache.clamp.clone() } else { cache.repeat.clone() });
                            level0_samplers.push(if clamp { cache.clamp_level0.clone() } else { cache.repeat_level0.clone() });
                        }
                        let uniform = device.create_buffer(&wgpu::BufferDescriptor {
                            label: Some(&format!("{label}::uniform")),
                            size: std::mem::size_of::<DrawUniform>() as u64,
                            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                            mapped_at_creation: false,
                        });
                        let maps: [Option<StageMap>; MAX_STAGES] = std::array::from_fn(|k| match fold_at(k) {
                            _ if folded_away(k) => None,
                            Some(f) => Some(StageMap::with_texels(UvSource::Mesh, (f.size.0 as f32, f.size.1 as f32), &v.shape)),
                            None => v.stages.get(k).and_then(|s| StageMap::of(s, &v.shape)),
                        });
                        let level0_able = (0..MAX_STAGES).filter(|&k| maps[k].is_some()).fold(0u8, |m, k| m | 1 << k);
                        // One bind group per subset of those stages, indexed by the subset's mask (a
                        // mask that is no subset is never indexed, and gets its subset's), so that
                        // a frame only picks one.
                        let bind_groups = (0..=level0_able)
                            .map(|mask| {
                                let mask = mask & level0_able;
                                let mut entries = vec![wgpu::BindGroupEntry { binding: 0, resource: uniform.as_entire_binding() }];
                                for (k, view) in views.iter().enumerate() {
                                    entries.push(wgpu::BindGroupEntry { binding: 1 + k as u32, resource: wgpu::BindingResource::TextureView(view) });
                                }
                                for k in 0..MAX_STAGES {
                                    let s = if mask & (1 << k) != 0 { &level0_samplers[k] } else { &samplers[k] };
                                    entries.push(wgpu::BindGroupEntry { binding: 5 + k as u32, resource: wgpu::BindingResource::Sampler(s) });
                                }
                                entries.push(wgpu::BindGroupEntry { binding: 9, resource: wgpu::BindingResource::TextureView(&sky_view.0) });
                                entries.push(wgpu::BindGroupEntry { binding: 10, resource: wgpu::BindingResource::Sampler(&sky_view.1) });
                                device.create_bind_group(&wgpu::BindGroupDescriptor { label: Some(&format!("{label}::bind_group[{mask:04b}]")), layout, entries: &entries })
                            })
                            .collect();
                        let gradient_stage = v.gradients.as_ref().map(|g| g.stage);
                        let mut texels_per_deg = [0.0; 4];
                        for (k, s) in v.stages.iter().enumerate() {
                            let oversampling = s.texture.as_ref().map_or(1.0, |t| *oversampling.entry(t.key.clone()).or_insert_with(|| texture_oversampling(t)));
                            texels_per_deg[k] = stage_texels_per_deg(s, &v.shape) / oversampling;
                        }
                        let mut base = DrawUniform::from(v);
                        for f in &folds {
                            let (first, second) = (f.stage, f.stage + 1);
                            // A folded texture carries the finer detail of its two stages.
                            texels_per_deg[first] = texels_per_deg[first].max(texels_per_deg[second]);
                            texels_per_deg[second] = 0.0;
                            base.stages[first].scale_offset = [1.0, 1.0, 0.0, 0.0];
                            if base.stages[first].cfg[2] == NO_STAGE {
                                base.stages[first].cfg[2] = base.stages[second].cfg[2];
                            }
                            base.stages[second].cfg[1] = UV_WHITE;
                            base.stages[second].cfg[2] = NO_STAGE;
                        }
                        // A sparse stage under the dome's mesh mapping, static: the folded one, or
                        // one of its own that repeats.
                        let texels = match (super::mesh::dome_grid(&v.shape), is_outline) {
                            (Some((_, _, rings, _)), false) => (0..v.stages.len()).find_map(|k| {
                                let s = &v.stages[k];
                                let fixed = matches!(s.uv, UvSource::Mesh) && s.panner == [0.0, 0.0] && s.uv_offset.is_none() && !folded_away(k) && gradient_stage != Some(k);
                                if !fixed {
                                    return None;
                                }
                                let (key, content, scale): (String, u64, [f32; 2]) = match (fold_at(k), s.texture.as_deref()) {
                                    (Some(f), _) if !f.clamp => {
                                        let (key, content) = stage_fold::identity(v, f);
                                        (key, content, [1.0, 1.0])
                                    }
                                    (None, Some(t)) if !s.clamp => (t.key.clone(), textures::content_hash(t), s.uv_scale),
                                    _ => return None,
                                };
                                let id = (key, content, format!("{} x {scale:?}", shape_key(&v.shape)));
                                let mesh = texel_meshes
                                    .entry(id.clone())
                                    .or_insert_with(|| match old_texels.and_then(|m| m.get(&id)) {
                                        Some(m) => m.clone(),
                                        None => {
                                            let image = match (fold_at(k), &s.texture) {
                                                (Some(f), _) => baked.entry(id.0.clone()).or_insert_with(|| Arc::new(stage_fold::bake(v, f, &id.0))).clone(),
                                                (None, Some(t)) => t.clone(),
                                                (None, None) => return None,
                                            };
                                            let source = TexelSource { size: (image.width, image.height), rgba8: &image.rgba8, scale };
                                            source
                                                .sparse()
                                                .then(|| GpuTexelMesh::new(device, &label, &texel_quads::build(&shape_mesh(&v.shape), rings, &source)))
                                                .flatten()
                                                .map(Arc::new)
                                        }
                                    })
                                    .clone();
                                mesh.map(|m| (k, m))
                            }),
                            _ => None,
                        };
                        VersionDraw {
                            uniform,
                            bind_groups,
                            level0_able,
                            maps,
                            mesh,
                            outline: is_outline,
                            gradient,
                            gradient_stage,
                            blend: v.blend,
                            shape: v.shape,
                            base,
                            texels_per_deg,
                            texels,
                        }
                    })
                    .collect()
            })
            .collect();
        Self { objects, meshes, texel_meshes }
    }

    /// Writes this frame's uniforms and gradients and records each drawn version's pipeline
    /// signature in `keys` (by object index and version) for `(target, neutral tone mapper)`;
    /// returns the texture stages skipped because their term is black this frame.
    fn prepare(
        &self,
        queue: &wgpu::Queue,
        frame: &FrameSky,
        camera: &Camera,
        skip_dark: bool,
        (target, neutral): (Target, bool),
        keys: &mut HashMap<(usize, usize), VariantKey>,
    ) -> u32 {
        let mut skipped = 0;
        for of in &frame.objects {
            let Ok(versions) = &of.versions else { continue };
            for p in versions {
                let d = &self.objects[of.index][p.version];
                let sky_view_stage = d.gradient_stage.filter(|_| frame.sky_model.kind.is_physical());
                let mut u = d.base.with_frame(p, &d.shape, of.placement, camera.screen_up(), sky_view_stage);
                // Alpha weighs the colour under alpha and additive blending: a term only counts as
                // nothing there when it is transparent too.
                if skip_dark {
                    skipped += u.skip_dark_terms(d.blend != BlendMode::Opaque);
                }
                queue.write_buffer(&d.uniform, 0, bytemuck::bytes_of(&u));
                keys.insert((of.index, p.version), VariantKey::of(&u, d.blend, target, neutral));
                if let (Some((tex, h)), Some(g)) = (&d.gradient, &p.gradient) {
                    let bytes: Vec<u8> = g.iter().flat_map(|c| c.map(|x| (x.clamp(0.0, 1.0) * 255.0).round() as u8)).collect();
                    textures::write(queue, tex, 1, *h, &bytes);
                }
            }
        }
        skipped
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scissor_rects_cover_the_frame_outside_the_holes_once() {
        let mut rng = fastrand::Rng::with_seed(11);
        let (w, h) = (37u32, 23u32);
        for _ in 0..300 {
            let holes: Vec<[u32; 4]> = (0..rng.u32(0..4))
                .map(|_| {
                    let (x, y) = (rng.u32(0..w), rng.u32(0..h));
                    [x, y, rng.u32(1..=w - x), rng.u32(1..=h - y)]
                })
                .collect();
            let rects = scissor_rects([0, 0, w, h], &holes);
            let inside = |r: &[u32; 4], px: u32, py: u32| px >= r[0] && px < r[0] + r[2] && py >= r[1] && py < r[1] + r[3];
            for py in 0..h {
                for px in 0..w {
                    let covered = rects.iter().filter(|r| inside(r, px, py)).count();
                    let in_hole = holes.iter().any(|r| inside(r, px, py));
                    assert_eq!(covered, usize::from(!in_hole), "pixel ({px}, {py}) of {rects:?} with holes {holes:?}");
                }
            }
        }
    }

    #[test]
    fn the_celestial_poles_lie_at_least_the_bound_away_from_every_pixel() {
        // Every pixel's direction (a grid over the frame, corners included) lies at least
        // `celestial_pole_deg` from both poles of the mapping, and the bound is not idle: a frame
        // facing away from both poles gets one, a frame holding a pole gets 0.
        let mut away = 0;
        for (camera, aspect) in [
            (Camera::default(), 16.0 / 9.0),
            (Camera { yaw_deg: 180.0, pitch_deg: 10.0, ..Camera::default() }, 16.0 / 9.0),
            (Camera { yaw_deg: 60.0, pitch_deg: 75.0, ..Camera::default() }, 1.0),
            (Camera { pitch_deg: -30.0, fov_y_deg: 100.0, ..Camera::default() }, 2.0),
        ] {
            for hour in [0.0f32, 5.5, 12.0, 18.5] {
                let celestial_from_world = Quat::from_axis_angle(crate::sky::eval::direction(0.0, 45.0), std::f32::consts::TAU * hour / 24.0);
                let view = FrameView::new(&camera, aspect, (-90.0, 90.0), Vec3::Y, celestial_from_world);
                let north = celestial_from_world.inverse() * Vec3::Y;
                let sky_from_clip = camera.matrices(aspect).1.inverse();
                let mut nearest_deg = f32::INFINITY;
                for (i, j) in (0..=32).flat_map(|i| (0..=32).map(move |j| (i, j))) {
                    let ndc = glam::Vec4::new(i as f32 / 16.0 - 1.0, j as f32 / 16.0 - 1.0, 0.5, 1.0);
                    let p = sky_from_clip * ndc;
                    let dir = (p.truncate() / p.w).normalize();
                    let deg = north.dot(dir).abs().min(1.0).acos().to_degrees();
                    nearest_deg = nearest_deg.min(deg);
                }
                assert!(view.celestial_pole_deg <= nearest_deg + 1e-3, "{camera:?} at {hour} h: bound {} past the nearest pixel {nearest_deg}", view.celestial_pole_deg);
                if nearest_deg > 20.0 {
                    assert!(view.celestial_pole_deg > 0.25 * nearest_deg, "{camera:?} at {hour} h: bound {} for a pole {nearest_deg} degrees away", view.celestial_pole_deg);
                    away += 1;
                }
                if nearest_deg < 0.5 {
                    assert_eq!(view.celestial_pole_deg, 0.0);
                }
                // Round the poles the texture's columns crowd: the density bound grows without limit.
                let map = StageMap { uv: UvSource::Celestial, texels: (256.0, 128.0), ring_peaks: Vec::new() };
                let peak = map.peak_texels_per_deg(&Shape::Dome { bottom_deg: crate::sky::model::Elevation(-20.0) }, &view);
                let expected = 256.0 / 360.0 / view.celestial_pole_deg.to_radians().sin();
                assert!(peak >= expected.max(128.0 / 180.0) * 0.999 || peak.is_infinite(), "{peak} {expected}");
            }
        }
        assert!(away >= 4, "frames away from the poles ({away})");
    }

    fn uniform(ops: &[(u32, u32)]) -> DrawUniform {
        let mut u = DrawUniform::zeroed();
        for (k, (op, constant)) in ops.iter().enumerate() {
            u.stages[k].cfg = [*op, 0, *constant, 1];
        }
        u.misc = [ops.len() as u32, 0, NO_STAGE, 0];
        u.constants = [[1.0; 4]; 4];
        u
    }

    #[test]
    fn black_terms_are_skipped_and_nothing_else() {
        // Gradient; stars x mask with constant 0; halo with constant 1 (the default skydome).
        let mut u = uniform(&[(0, 4), (0, 0), (1, 4), (0, 1)]);
        u.constants[0] = [0.0, 0.0, 0.0, 1.0];
        assert_eq!(u.skip_dark_terms(false), 2);
        assert_eq!(u.stages.map(|s| s.cfg[3]), [1, 0, 0, 1]);
        // Under alpha (or additive) blending an opaque black constant still weighs: kept.
        let mut v = uniform(&[(0, 4), (0, 0), (1, 4), (0, 1)]);
        v.constants[0] = [0.0, 0.0, 0.0, 1.0];
        assert_eq!(v.skip_dark_terms(true), 0);
        v.constants[0] = [0.0; 4];
        assert_eq!(v.skip_dark_terms(true), 2);
        // The stage a physical sky model feeds is never skipped.
        let mut w = uniform(&[(0, 0)]);
        w.constants[0] = [0.0; 4];
        w.misc[2] = 0;
        assert_eq!(w.skip_dark_terms(false), 0);
    }

    /// The Quake mapping as the shader evaluates it (without the scroll), in f64.
    fn quake_uv(dir: [f64; 3], z: f64, o: f64, t: f64) -> [f64; 2] {
        let y = dir[1] * z + o;
        let l = (dir[0] * dir[0] + y * y + dir[2] * dir[2]).sqrt().max(1e-4);
        [dir[0] * t / l, dir[2] * t / l]
    }

    #[test]
    fn quake_density_bounds_the_mapping_and_is_reached() {
        // Random pairs of nearby directions over the dome: the texture-coordinate distance per
        // radian between them never exceeds the bound, and comes close to it somewhere.
        let mut rng = fastrand::Rng::with_seed(11);
        for &(z, o, t, bottom) in &[(3.0, 0.0, 0.7, -5.0), (3.0, 0.0, 1.3, -5.0), (1.0, 0.0, 1.0, -20.0), (2.0, 0.4, 0.5, 0.0), (5.0, -0.3, 2.0, -10.0)] {
            let bound = quake_uv_per_rad(z as f32, o as f32, t as f32, bottom as f32, 90.0) as f64;
            let mut seen: f64 = 0.0;
            for _ in 0..20_000 {
                let e = (bottom + (90.0 - bottom) * rng.f64()).to_radians();
                let a = rng.f64() * std::f64::consts::TAU;
                let dir = |e: f64, a: f64| [e.cos() * a.sin(), e.sin(), e.cos() * a.cos()];
                let (de, da) = ((rng.f64() - 0.5) * 1e-4, (rng.f64() - 0.5) * 1e-4);
                let (p, q) = (dir(e, a), dir((e + de).min(std::f64::consts::FRAC_PI_2), a + da));
                let angle = (p[0] * q[0] + p[1] * q[1] + p[2] * q[2]).clamp(-1.0, 1.0).acos();
                if angle < 1e-7 {
                    continue;
                }
                let (u, v) = (quake_uv(p, z, o, t), quake_uv(q, z, o, t));
                let rate = ((u[0] - v[0]).powi(2) + (u[1] - v[1]).powi(2)).sqrt() / angle;
                assert!(rate <= bound * 1.01, "z {z} o {o} t {t}: {rate} per rad above the bound {bound}");
                seen = seen.max(rate);
            }
            assert!(seen > bound * 0.8, "z {z} o {o} t {t}: bound {bound} per rad far above the steepest seen, {seen}");
        }
    }
}
