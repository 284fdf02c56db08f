//! Pipelines of the sky objects: the generic ones (every material, read from the uniform) and
//! the specialised variants, one per material signature and placement, built when the frame
//! plan first uses them.

#[allow(unused_imports)]
use super::*;

/// The generic pipelines (one per blend mode: every material, read from the uniform) and the
/// shader module the specialised ones are built from.
pub struct SkyObjectPipelines {
    pub(super) generic: [wgpu::RenderPipeline; 3],
    pub(super) module: wgpu::ShaderModule,
}

/// What a specialised pipeline is built for: the material's signature in this frame (stage
/// count, and per stage its UV mode, op, constant index and whether its term is live), the stage
/// the sky-view map feeds, the lighting, the blend and what the target holds. Everything the
/// shader would otherwise branch on per draw: lavapipe pays for both sides of such branches.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub(super) struct VariantKey {
    pub(super) count: u32,
    pub(super) modes: [u32; 4],
    pub(super) ops: [u32; 4],
    pub(super) constants: [u32; 4],
    pub(super) live: [bool; 4],
    pub(super) view_stage: u32,
    pub(super) lighting: u32,
    pub(super) blend: usize,
    pub(super) target: Target,
    /// The frame's tone mapper where the shader tone-maps (`TONE_KIND` of tone.wgsl): 1 ACES, 2
    /// neutral; 0 where it does not (display colours onto the display target).
    pub(super) tone: u32,
    /// How the sRGB curves are evaluated (`CURVES_KIND` of tone.wgsl).
    pub(super) curves: DisplayCurves,
    /// A blended layer of a display-referred physical frame, whose colour is made what the HDR
    /// path's blend over the model's sky would leave (`OVER_MODEL_SKY` in the shader).
    pub(super) over_model: bool,
    /// Drawn into a reduced-resolution buffer ([`crate::render::passes::reduced_layers`]).
    pub(super) reduced: bool,
    /// Where on the frame it goes ([`Slot::Plain`] for reduced draws).
    pub(super) placement: Slot,
}

/// What a frame's sky-object pipelines are specialised for besides each draw's material.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub(super) struct FrameShading {
    /// The target the frame's layers draw into.
    pub(super) target: Target,
    /// The frame's blended layers match the HDR picture ([`crate::render::plan::matches_hdr_picture`]).
    pub(super) matched: bool,
    /// The frame's tone mapper is Khronos PBR Neutral (else ACES).
    pub(super) neutral_tone: bool,
    /// How the strategy evaluates the sRGB curves.
    pub(super) curves: DisplayCurves,
}

/// Where a draw on the frame goes, as its pipeline variant sees it (the shader's switches of a
/// [`crate::render::frame::pass::Placement`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub(super) enum Slot {
    /// In its place in the sky phase, depth-tested against the scene.
    Plain,
    /// After a run of reduced layers that lies above it, corrected by that run's colour and
    /// transmittance (`UNDER_RUN` in the shader).
    UnderRun,
    /// Additive, first onto the cleared frame under the background run, not depth-tested
    /// ([`crate::render::plan::strategy::UnderBackground::Additive`]).
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
    pub(super) fn background(joined: bool) -> Self {
        if joined {
            Slot::JoinedBackground
        } else {
            Slot::Background
        }
    }
}

impl VariantKey {
    /// The signature of a draw of a version with material `sig`, this frame's `live` stages
    /// (those whose term is not black: [`DrawUniform::skip_dark_terms`]) and the stage the
    /// sky-view map feeds.
    pub(super) fn of(sig: &MaterialSignature, (live, view_stage): ([bool; 4], Option<usize>), blend: BlendMode, shading: FrameShading) -> Self {
        let FrameShading { target, matched, neutral_tone, curves } = shading;
        let over_model = matched && view_stage.is_none() && blend != BlendMode::Opaque;
        // Whether the shader tone-maps: on the HDR target (display colours taken to radiance), a
        // layer holding the map on the display target (`view_on_display`) and a matched layer.
        // Left to the uniform, lavapipe would run both tone mappers and both inverses for every
        // fragment (it evaluates both sides of a uniform branch).
        let tone_maps = target == Target::Hdr || view_stage.is_some() || over_model;
        let tone = match (tone_maps, neutral_tone) {
            (false, _) => 0,
            (true, false) => 1,
            (true, true) => 2,
        };
        Self {
            count: sig.count,
            modes: sig.modes,
            ops: sig.ops,
            constants: sig.constants,
            live,
            view_stage: view_stage.map_or(NO_STAGE, |k| k as u32),
            lighting: sig.lighting,
            blend: blend_index(blend),
            target,
            tone,
            // Only a shader that tone-maps evaluates the curves.
            curves: if tone_maps { curves } else { DisplayCurves::Exact },
            over_model,
            reduced: false,
            placement: Slot::Plain,
        }
    }

    /// The override constants that specialise `shaders/sky_objects/signature.wgsl` for this signature.
    pub(super) fn constants(&self) -> Vec<(&'static str, f64)> {
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
            ("CURVES_KIND", f64::from(self.curves.shader_kind())),
            ("UNDER_RUN", f64::from(u8::from(self.placement == Slot::UnderRun))),
            ("BLEND_KIND", self.blend as f64),
            ("OVER_SEED", f64::from(u8::from(self.placement == Slot::OverSeed))),
            ("OVER_MODEL_SKY", f64::from(u8::from(self.over_model))),
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
/// for (`vs_pair`, `fs_pair` in shaders/sky_objects/pairs.wgsl): the lower layer's signature (its
/// placement: plain or over the seed) and the upper one's.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub(super) struct PairKey {
    pub(super) lower: VariantKey,
    pub(super) upper: VariantKey,
}

impl PairKey {
    /// The lower layer's override constants and the upper layer's as `UPPER_*`.
    pub(super) fn constants(&self) -> Vec<(&'static str, f64)> {
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
/// ([`crate::render::passes::reduced_layers::REDUCED_BLENDS`]): colour + (1 - covered) x buffer, and the
/// transmittance in alpha times what the pair lets through.
pub(super) const PAIR_BLEND: wgpu::BlendState = wgpu::BlendState {
    color: wgpu::BlendComponent { src_factor: wgpu::BlendFactor::One, dst_factor: wgpu::BlendFactor::OneMinusSrcAlpha, operation: wgpu::BlendOperation::Add },
    alpha: wgpu::BlendComponent { src_factor: wgpu::BlendFactor::Zero, dst_factor: wgpu::BlendFactor::OneMinusSrcAlpha, operation: wgpu::BlendOperation::Add },
};

/// Blend index of [`BLENDS`] that adds colour as it is (the fine terms of a split opaque layer).
pub(super) const BLEND_ADD: usize = 3;

/// Term of each stage: an `add` stage starts one, `modulate` stages join the current one.
pub(super) fn stage_terms(ops: [u32; 4]) -> [usize; 4] {
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

pub(super) fn blend_index(b: BlendMode) -> usize {
    match b {
        BlendMode::Opaque => 0,
        BlendMode::Alpha => 1,
        BlendMode::Additive => 2,
    }
}

pub(super) const BLENDS: [Option<wgpu::BlendState>; 4] = [
    None,
    Some(wgpu::BlendState::ALPHA_BLENDING),
    Some(crate::render::gpu::parts::ADDITIVE_ALPHA),
    Some(wgpu::BlendState {
        color: wgpu::BlendComponent { src_factor: wgpu::BlendFactor::One, dst_factor: wgpu::BlendFactor::One, operation: wgpu::BlendOperation::Add },
        alpha: wgpu::BlendComponent { src_factor: wgpu::BlendFactor::Zero, dst_factor: wgpu::BlendFactor::One, operation: wgpu::BlendOperation::Add },
    }),
];

/// Blends of draws under a run (`UNDER_RUN` in shaders/sky_objects/placement.wgsl, which premultiplies what
/// it writes), by blend index of [`BLENDS`]: a draw that would have gone before the run goes
/// after it, so that run and the one below composite at once. With the run's colour C and
/// transmittance T at the pixel, the frame must end as C + T x (the draw over what was there):
/// opaque writes C + T m; alpha writes T a m + a C over (1 - a) of the target; additive ones add
/// T times their term. Alpha channels blend as the plain draws'.
pub(super) const UNDER_RUN_BLENDS: [Option<wgpu::BlendState>; 4] = {
    pub(super) const ADD: wgpu::BlendComponent =
        wgpu::BlendComponent { src_factor: wgpu::BlendFactor::One, dst_factor: wgpu::BlendFactor::One, operation: wgpu::BlendOperation::Add };
    pub(super) const KEEP: wgpu::BlendComponent =
        wgpu::BlendComponent { src_factor: wgpu::BlendFactor::Zero, dst_factor: wgpu::BlendFactor::One, operation: wgpu::BlendOperation::Add };
    pub(super) const OVER: wgpu::BlendComponent =
        wgpu::BlendComponent { src_factor: wgpu::BlendFactor::One, dst_factor: wgpu::BlendFactor::OneMinusSrcAlpha, operation: wgpu::BlendOperation::Add };
    [None, Some(wgpu::BlendState { color: OVER, alpha: OVER }), Some(wgpu::BlendState { color: ADD, alpha: KEEP }), Some(wgpu::BlendState { color: ADD, alpha: KEEP })]
};

pub(super) const MAIN: (&str, &str) = ("vs_main", "fs_main");

pub(super) const PAIR: (&str, &str) = ("vs_pair", "fs_pair");

pub(super) const TEXELS: (&str, &str) = ("vs_texels", "fs_texels");

pub(super) const FULLSCREEN: (&str, &str) = ("vs_fullscreen", "fs_main");

/// One sky-object pipeline: `constants` specialise it (none: the generic pipeline).
pub(super) fn create_pipeline(
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
            depth_stencil: depth.and_then(|compare| crate::render::gpu::parts::depth_state(false, compare)),
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

impl SkyObjectsPass {
    pub(super) fn build(b: &PassBuild<'_>, layout: &wgpu::PipelineLayout) -> RenderResult<SkyObjectPipelines> {
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
    pub(super) fn entry_key(&self, e: &Visible, target: Target, placement: Slot) -> Option<VariantKey> {
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
        // Cloud-layer stages of a draw on its grid per vertex where the strategy says so (one
        // pipeline for every part too: it does not depend on the rings).
        let vertex_modes = self.draws.current.as_ref().and_then(|d| d.objects[e.index][e.version].vertex_modes_for(self.layer_per_vertex));
        let modes = std::array::from_fn(|s| match (k.modes[s], vertex_modes) {
            (UV_CELESTIAL, _) if level0 & (1 << s) != 0 => UV_CELESTIAL_LEVEL0,
            (UV_LAYER, Some(m)) => m[s],
            (mode, _) => mode,
        });
        Some(VariantKey { live, view_stage, blend, reduced: e.reduced, placement, modes, ..*k })
    }

    /// Whether draw `key` can be drawn at `placement` on the frame this frame: the placement
    /// suits it (placements other than its own only with reduced buffers this frame; first and
    /// as the background only when additive, over a seed and as the background only as a whole
    /// dome), it has a signature there, and building that pipeline has not failed.
    pub(super) fn can_place(&self, key: usize, target: Target, placement: Slot) -> bool {
        let Some(e) = self.visible.get(key) else { return false };
        let suits = match placement {
            Slot::Plain => true,
            Slot::UnderRun => self.reduces,
            Slot::First => self.reduces && self.additive(e),
            Slot::Background | Slot::JoinedBackground => self.reduces && self.additive(e) && self.dome_of(e),
            Slot::OverSeed => self.reduces && self.dome_of(e),
        };
        suits && self.entry_key(e, target, placement).is_some_and(|k| k.placement == placement && !matches!(self.variants.get(&k), Some(None)))
    }

    /// Builds the pipelines of the plan's draws of this pass (see [`Pass::build_planned`]).
    pub(super) fn build_planned_variants(&mut self, device: &wgpu::Device, target: Target, uses: &[(usize, Placement)]) -> bool {
        let mut failed = false;
        for &(key, placement) in uses {
            let Some(e) = self.visible.get(key).copied() else { continue };
            // Every draw used also gets its pipeline in its own place: what the recorder falls
            // back to where a run buffer is missing (`SkyRenderer::record_step`).
            if let Some(k) = self.entry_key(&e, target, Slot::Plain) {
                self.build_variant(device, k);
            }
            let slot = match placement {
                // Reduced draws' signatures say so (`entry_key`); a failure leaves the generic
                // pipeline drawing whole draws in their place, and nothing to plan differently.
                Placement::Plain | Placement::Reduced => continue,
                Placement::Pair { upper, over_seed } => {
                    let upper = self.visible.get(upper).copied();
                    if let Some(k) = upper.and_then(|u| self.entry_key(&u, target, Slot::Plain)) {
                        self.build_variant(device, k);
                    }
                    let pair = upper.and_then(|u| self.pair_key(&e, &u, target, over_seed));
                    failed |= pair.is_some_and(|k| !self.build_pair(device, k));
                    continue;
                }
                Placement::UnderRun => Slot::UnderRun,
                Placement::First => Slot::First,
                Placement::OverSeed => Slot::OverSeed,
                Placement::Background { joined } => Slot::background(joined),
            };
            let Some(k) = self.entry_key(&e, target, slot).filter(|k| k.placement == slot) else { continue };
            failed |= !self.build_variant(device, k);
            // As the background, its sparse stage texel by texel: the draw without the stage,
            // the polygons and the triangle over the frame (each failure logged and drawn
            // otherwise: `texel_draw`).
            let texel_stage = self.draws.current.as_ref().and_then(|d| d.objects[e.index][e.version].texels.as_ref()).map(|t| t.0);
            if let Some((without, stage)) = texel_stage.and_then(|stage| Self::without_texel_stage(&k, stage).map(|w| (w, stage))) {
                self.build_variant(device, without);
                self.build_texels(device, (k, without), stage);
            }
        }
        failed
    }

    /// Builds the specialised pipeline `key` unless it was; returns whether it exists.
    fn build_variant(&mut self, device: &wgpu::Device, key: VariantKey) -> bool {
        if let Some(built) = self.variants.get(&key) {
            return built.is_some();
        }
        let constants = key.constants();
        let format = match (key.reduced, key.target) {
            (true, target) => crate::render::passes::reduced_layers::reduced_format(target),
            (false, Target::Hdr) => crate::render::gpu::parts::HDR_FORMAT,
            (false, Target::Display) => self.display_format,
        };
        let blend = match (key.reduced, key.placement) {
            (true, Slot::OverSeed) => None,
            (true, _) => Some(crate::render::passes::reduced_layers::REDUCED_BLENDS[key.blend]),
            (false, Slot::UnderRun) => UNDER_RUN_BLENDS[key.blend],
            (false, Slot::Plain | Slot::First) => BLENDS[key.blend],
            // Not made (`entry_key`): reduced only.
            (false, Slot::Background | Slot::JoinedBackground | Slot::OverSeed) => None,
        };
        // Reduced buffers have no depth: the composite is depth-tested instead. Draws under the
        // background come before the scene, which covers what they hide.
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
        let ok = built.is_ok();
        self.variants.insert(key, built.ok());
        ok
    }

    /// Builds the pipelines of background `key`'s sparse stage `stage` drawn texel by texel: the
    /// polygons, and the draw `without` the stage as one triangle over the frame.
    fn build_texels(&mut self, device: &wgpu::Device, (key, without): (VariantKey, VariantKey), stage: usize) {
        if !self.fullscreen_pipelines.contains_key(&without) {
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

    /// Builds the pair pipeline `key` unless it was; returns whether it exists.
    fn build_pair(&mut self, device: &wgpu::Device, key: PairKey) -> bool {
        if let Some(built) = self.pairs.get(&key) {
            return built.is_some();
        }
        let label = format!("SkyObjects::pair {key:?}");
        let blend = if key.lower.placement == Slot::OverSeed { None } else { Some(PAIR_BLEND) };
        let format = crate::render::passes::reduced_layers::reduced_format(key.lower.target);
        let built = create_pipeline(device, (&self.pair_layout, &self.pipelines.get().module, PAIR), &label, (blend, format, None), &key.constants());
        if let Err(e) = &built {
            log::error!("{label}: {e}; the two layers are drawn one after the other");
        }
        let ok = built.is_ok();
        self.pairs.insert(key, built.ok());
        ok
    }
}
