//! Sky objects pass: every object of the sky file, drawn by priority with its 4-stage material.
//!
//! - [`material`]: the draw's uniform, built from a version, changed per frame;
//! - [`variants`]: the generic and the specialised pipelines, by material signature and placement;
//! - [`upload`]: a sky's per-object GPU resources;
//! - [`detail`]: texel density by stage, shape and view (pure; the mip bounds built on it are
//!   [`crate::render::plan::mip_bounds`]);
//! - [`pairs`]: two cloud layers drawn at once;
//! - [`texels`] and [`texel_quads`]: the background's sparse stars texel by texel;
//! - [`stage_fold`]: stages folded into fewer where their product is constant.
//!
//! This file holds the pass itself: which versions are visible this frame, at which resolution,
//! what each can be drawn as (its [`Caps`]), and recording one draw.

mod detail;
pub mod layer_map;
mod material;
mod pairs;
pub mod stage_fold;
pub mod texel_quads;
mod texels;
mod upload;
mod variants;

#[allow(unused_imports)]
use self::{detail::*, layer_map::*, material::*, texels::*, upload::*, variants::*};
pub use detail::{texture_oversampling, DETAIL_TOLERANCE};
pub use material::{DrawUniform, StageUniform};
pub use upload::SkyObjectDraws;
pub use variants::SkyObjectPipelines;

use std::collections::HashMap;
use std::sync::Arc;

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Quat, Vec3, Vec4};

use self::texel_quads::{GpuTexelMesh, TexelSource, TexelVertex};
use crate::render::frame::camera::Camera;
use crate::render::frame::pass::{Caps, DrawItem, FrameContext, OwnBuffer, Pass, PassBuild, Phase, Pipelines, Placement, SkyUpload, Staged, Target};
use crate::render::frame::stats::FrameStats;
use crate::render::gpu::error::RenderResult;
use crate::render::gpu::mesh::{outline_mesh, shape_key, shape_mesh, GpuMesh, MeshData, SkyVertex};
use crate::render::gpu::shaders;
use crate::render::gpu::textures::{self, TextureCache};
use crate::render::plan::mip_bounds::{self, DomeGrid, DrawMesh};
use crate::render::plan::resolution::Divisor;
use crate::render::plan::resolution::{resolution, LayerStages, Resolution, ResolutionFacts};
use crate::render::plan::strategy::DisplayCurves;
use crate::render::plan::visibility::{visibility, CullFacts, Visibility};
use crate::sky::eval::{FrameSky, VersionFrame};
use crate::sky::resolved::{BlendMode, Lighting, Shape, Sky, StageOp, TextureImage, UvSource, Version, MAX_STAGES};

/// The sky objects pass: pipelines (one per blend mode, built once and rebuilt on shader edits,
/// plus one per material signature and placement, built when the frame plan uses it) and the
/// current sky's per-object resources.
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
    /// Pipelines drawing a sparse stage texel by texel ([`crate::render::sky_objects::texel_quads`]), by the
    /// background's signature (`None`: building it failed; the stage is sampled). Emptied when
    /// the shaders change.
    texel_pipelines: HashMap<VariantKey, Option<wgpu::RenderPipeline>>,
    /// The background without its sparse stage as one triangle over the frame
    /// ([`crate::render::plan::strategy::SparseStages::TexelPolygonsOnBands`]), by the signature without the stage.
    fullscreen_pipelines: HashMap<VariantKey, Option<wgpu::RenderPipeline>>,
    /// Dome layers may go to reduced buffers this frame (placements other than their own are
    /// offered only then).
    reduces: bool,
    /// The coarsest buffer this frame that resolves a physical model's map
    /// ([`ResolutionFacts::map_divisor`]): the most a matched layer's own buffer may be.
    map_divisor: Divisor,
    /// Sparse stages are drawn texel by texel this frame ([`crate::render::plan::strategy::SparseStages::TexelPolygons`]).
    texels_on: bool,
    /// Cloud-layer stages of draws on their grid computed per vertex this frame
    /// ([`crate::render::plan::strategy::LayerCoordinates::PerVertex`]).
    layer_per_vertex: bool,
    /// The rest of such a draw goes as bands where the polygons stand for the stage
    /// ([`crate::render::plan::strategy::SparseStages::TexelPolygonsOnBands`]).
    bands_on: bool,
    /// Draws recorded this frame without a pipeline (left out): none while every pipeline the
    /// plan uses was built.
    missing_pipelines: std::cell::Cell<u32>,
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

impl SkyObjectsPass {
    /// Builds the layouts and pipelines.
    pub fn new(b: &PassBuild<'_>) -> RenderResult<Self> {
        let (device, globals) = (b.device, b.globals_layout);
        let mut entries = vec![crate::render::gpu::parts::uniform_entry(0, wgpu::ShaderStages::VERTEX_FRAGMENT)];
        entries.extend((0..4).map(|i| crate::render::gpu::parts::texture_entry(1 + i)));
        entries.extend((0..4).map(|i| crate::render::gpu::parts::sampler_entry(5 + i)));
        entries.extend([crate::render::gpu::parts::texture_entry(9), crate::render::gpu::parts::sampler_entry(10)]);
        let bind_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some("SkyObjects::draw_layout"), entries: &entries });
        let run_layout = crate::render::passes::reduced_layers::run_layout(device, "SkyObjects::run_layout");
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
            let view = crate::render::gpu::textures::unused_view(device, "SkyObjects::no_run_texture");
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("SkyObjects::no_run"),
                layout: &run_layout,
                entries: &[
                    wgpu::BindGroupEntry { binding: 0, resource: uniform.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(&view) },
                    wgpu::BindGroupEntry { binding: 2, resource: wgpu::BindingResource::Sampler(&b.atmosphere.sky_view_sampler) },
                    wgpu::BindGroupEntry { binding: 3, resource: wgpu::BindingResource::TextureView(&view) },
                ],
            })
        };
        let pipelines = Pipelines::new_render(b, pipeline_layout.clone(), Self::build)?;
        let sky_view = (b.atmosphere.sky_view_view.clone(), b.atmosphere.sky_view_sampler.clone());
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
            reduces: false,
            map_divisor: Divisor::FULL,
            texels_on: false,
            layer_per_vertex: false,
            bands_on: false,
            missing_pipelines: std::cell::Cell::new(0),
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

    /// Draws of the last frame left out for want of a pipeline (0 unless one failed to build).
    pub fn draws_without_pipeline(&self) -> u32 {
        self.missing_pipelines.get()
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
            own_buffer: self.own_buffer(key, target),
        }
    }

    /// A buffer of its own for reduced item `key` when its fragments are costly: a layer matched
    /// over the model's sky (`OVER_MODEL_SKY`: a sample of the map and three tone curves each).
    /// Its divisor is the item's own but no coarser than the map needs, since its colour follows
    /// the map; a band covers the rows below its top.
    fn own_buffer(&self, key: usize, target: Target) -> Option<OwnBuffer> {
        let e = self.visible.get(key).filter(|e| e.reduced && !e.on_top)?;
        self.entry_key(e, target, Slot::Plain).filter(|k| k.over_model)?;
        // A band covers the rows below its top (with the margin of its chords' sag).
        let top_deg = match self.draws.current.as_ref()?.objects[e.index][e.version].shape {
            Shape::DomeBand { top_deg, .. } => Some(top_deg.get() + 0.5),
            _ => None,
        };
        let covers = top_deg.filter(|&t| t < self.frame_elevations_deg.1).and_then(|t| self.frame_camera.pixels_below_elevation(self.frame_size, t));
        Some(OwnBuffer { divisor: e.divisor.finer(self.map_divisor), covers })
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
            // Building it failed and was logged, or the plan did not use this placement.
            None => {
                self.missing_pipelines.set(self.missing_pipelines.get() + 1);
                return 0;
            }
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
        self.layer_per_vertex = cx.options.strategy.layer_per_vertex();
        self.bands_on = cx.options.strategy.grid_bands();
        self.texel_triangles.set(0);
        self.missing_pipelines.set(0);
        self.background_rects.set(0);
        let Some(draws) = &self.draws.current else { return };
        let neutral = crate::render::passes::tone_map::ToneMapUniform::from(cx.frame.sky_model.camera.tone_mapper).settings[0] != 0;
        self.keys.clear();
        let shading = FrameShading { target: cx.target, matched: cx.matched, neutral_tone: neutral, curves: cx.options.strategy.display_curves };
        self.stages_skipped = draws.prepare(cx.queue, cx.frame, cx.camera, cx.options.skips.dark_stages, shading, &mut self.keys);
        self.ref_hidden = 0;
        self.below_horizon = 0;
        self.off_screen = 0;
        // The frame's elevations, with a margin for the dome's chords (tests in mesh.rs).
        let aspect = cx.aspect();
        let (lowest_deg, highest_deg) = cx.camera.elevation_range_deg(aspect);
        self.frame_elevations_deg = (lowest_deg, highest_deg);
        (self.frame_camera, self.frame_size) = (*cx.camera, cx.size);
        let scene_covers_below = cx.options.scene && cx.options.skips.below_horizon;
        let cull = CullFacts { camera: *cx.camera, aspect, elevations_deg: (lowest_deg, highest_deg), scene_covers_below, off_screen: cx.options.skips.off_screen };
        let resolution_facts = ResolutionFacts::new(cx.options.strategy.dome_resolution, cx.size.1, cx.camera.fov_y_deg, (lowest_deg, highest_deg));
        let mut shapes = Vec::new();
        for of in &cx.frame.objects {
            let versions = match &of.versions {
                Ok(versions) => versions,
                Err(why) => {
                    self.hidden += 1;
                    self.ref_hidden += u32::from(matches!(why, crate::sky::Hidden::RefAlphaZero(_)));
                    continue;
                }
            };
            shapes.clear();
            shapes.extend(versions.iter().map(|v| draws.objects[of.index][v.version].shape));
            match visibility(of.placement.map(|(dir, _)| dir), &shapes, &cull) {
                Visibility::BelowHorizon => {
                    self.hidden += 1;
                    self.below_horizon += 1;
                    continue;
                }
                Visibility::OffScreen => {
                    self.hidden += 1;
                    self.off_screen += 1;
                    continue;
                }
                Visibility::Drawn => {}
            }
            for v in versions {
                let entry =
                    Visible { index: of.index, priority: of.priority, version: v.version, reduced: false, divisor: Divisor::FULL, part: [true; 4], on_top: false, parts: (0, 0) };
                let version = (&draws.objects[of.index][v.version], self.keys.get(&(of.index, v.version)));
                if !push_version(&mut self.visible, entry, version, cx.options.skips.dark_stages, &resolution_facts) {
                    self.draws_dark += 1;
                }
            }
        }
        self.level0_stages = 0;
        self.parts.clear();
        if cx.options.skips.unneeded_mips {
            let view = FrameView::new(cx.camera, aspect, (lowest_deg, highest_deg), cx.frame.towards_sun, cx.frame.celestial_from_world);
            // Drawn or not, the scene's pixels there are the scene's (reduced buffers keep their
            // clear colour there, too far below the scene's edge for the upsampling to reach).
            let covered_below_deg = if scene_covers_below { -crate::render::plan::visibility::SCENE_COVERS_BELOW_DEG } else { f32::NEG_INFINITY };
            for e in &mut self.visible {
                let d = &draws.objects[e.index][e.version];
                // Frame pixels per degree at the frame's centre (the fewest: a perspective frame
                // has more per degree towards its edges), in this draw's buffer along its coarser
                // side (where its textures minify first).
                let px_per_deg = view.centre_px_per_deg(cx.size.1) / e.divisor.coarser();
                // Layer coordinates interpolated per vertex change faster than the layer's own in
                // places (the chords' sag): their bound takes a margin more.
                let per_vertex = d.vertex_modes_for(self.layer_per_vertex);
                let margin = |k: usize| if per_vertex.is_some_and(|m| m[k] == UV_LAYER_VERTEX) { LOD_MARGIN * PER_VERTEX_LOD_MARGIN } else { LOD_MARGIN };
                let level0 = |ring: Option<usize>| {
                    (0..MAX_STAGES)
                        .filter(|&k| d.maps[k].as_ref().is_some_and(|m| m.peak(&d.shape, ring, &view) * margin(k) <= px_per_deg * std::f32::consts::SQRT_2))
                        .fold(0u8, |m, k| m | 1 << k)
                };
                let mesh = match crate::render::gpu::mesh::dome_grid(&d.shape) {
                    Some(grid) => DrawMesh::Dome { grid: DomeGrid::from_tuple(grid), outline: d.outline },
                    None => DrawMesh::Whole { index_count: d.mesh.index_count },
                };
                let (parts, used) = mip_bounds::parts(mesh, (lowest_deg, highest_deg), covered_below_deg, level0);
                e.parts = (self.parts.len() as u32, parts.len() as u32);
                self.parts.extend(parts);
                self.level0_stages += used.count_ones();
            }
        }
        self.reduces = resolution_facts.reduces();
        self.map_divisor = resolution_facts.map_divisor();
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

    fn build_planned(&mut self, device: &wgpu::Device, target: Target, uses: &[(usize, Placement)]) -> bool {
        self.build_planned_variants(device, target, uses)
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

/// This frame's draws of one visible version `d` into `visible`: none when it is dark (returns
/// false), one in its place, or (a dome layer, with reduced buffers allowed) reduced whole or
/// split by [`resolution`].
fn push_version(visible: &mut Vec<Visible>, entry: Visible, (d, key): (&VersionDraw, Option<&VariantKey>), skip_dark: bool, facts: &ResolutionFacts) -> bool {
    // Blended by its alpha with every term black and transparent this frame (a night-only card
    // by day), the draw's material is 0 and leaves every buffer as it is: not drawn.
    let dark = key.filter(|_| skip_dark).is_some_and(|key| {
        let count = (key.count as usize).min(MAX_STAGES);
        d.blend != BlendMode::Opaque && !key.live[..count].iter().any(|&live| live)
    });
    if dark {
        return false;
    }
    let dome = matches!(d.shape, Shape::Dome { .. } | Shape::DomeBand { .. });
    let Some(key) = key.filter(|_| facts.reduces() && dome) else {
        visible.push(entry);
        return true;
    };
    let stages = LayerStages {
        count: key.count as usize,
        terms: stage_terms(key.ops),
        live: key.live,
        texels_per_deg: d.texels_per_deg_shown(facts.shown_deg),
        physical: (key.view_stage as usize) < MAX_STAGES,
        blend: d.blend,
    };
    let reduced = |divisor| Visible { reduced: true, divisor, ..entry };
    match resolution(&stages, facts) {
        Resolution::Full => visible.push(entry),
        Resolution::Reduced(divisor) => visible.push(reduced(divisor)),
        Resolution::Split { coarse, divisor, fine } => {
            visible.push(Visible { part: coarse, ..reduced(divisor) });
            visible.push(Visible { part: fine, on_top: true, ..entry });
        }
    }
    true
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
