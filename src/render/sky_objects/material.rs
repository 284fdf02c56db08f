//! A sky object's material as the shader reads it: the draw's uniform (stages, UV modes,
//! constants), built from a version and changed per frame (black terms skipped, placement).

#[allow(unused_imports)]
use super::*;

/// One texture stage. Keep in sync with `Stage` in shaders/sky_objects/draw.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable, PartialEq)]
pub struct StageUniform {
    /// UV scale (xy) and offset (zw), repeats.
    pub scale_offset: [f32; 4],
    /// Sun: size in radians; Quake: z_scale, z_offset, t_scale, time_scale; layer: height and
    /// radius in repeats, sine of the fade's elevation.
    pub params: [f32; 4],
    /// op (0 add, 1 modulate), uv mode, constant index (4 = none), live (0: its term is black
    /// this frame and is not sampled).
    pub cfg: [u32; 4],
}

/// One draw. Keep in sync with `Draw` in shaders/sky_objects/draw.wgsl.
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
pub(super) const NO_STAGE: u32 = 4;

/// UV mode of a stage folded into the one before it ([`crate::render::sky_objects::stage_fold`]): reads as white,
/// not sampled. Keep in sync with `UV_WHITE` in shaders/sky_objects/draw.wgsl.
pub(super) const UV_WHITE: u32 = 4;

/// UV mode of the mesh's texture coordinates. Keep in sync with `UV_MESH` in
/// shaders/sky_objects/draw.wgsl.
pub(super) const UV_MESH: u32 = 0;

/// UV mode of the celestial mapping.
pub(super) const UV_CELESTIAL: u32 = 2;

/// UV mode of a celestial stage that no pixel of its draw minifies this frame: sampled from
/// level 0 without the derivatives the celestial mapping otherwise computes per pixel (a variant
/// of the mapping, never in a uniform). Keep in sync with `UV_CELESTIAL_LEVEL0` in
/// shaders/sky_objects/draw.wgsl.
pub(super) const UV_CELESTIAL_LEVEL0: u32 = 5;

/// UV mode of the cloud-layer mapping. Keep in sync with `UV_LAYER` in
/// shaders/sky_objects/draw.wgsl.
pub(super) const UV_LAYER: u32 = 6;

/// UV mode of the cloud-layer mapping computed per vertex of the dome's grid, the grid moved onto
/// the layer (`LayerCoordinates::PerVertex`; a variant of the mapping, never in a uniform). Keep
/// in sync with `UV_LAYER_VERTEX` in shaders/sky_objects/draw.wgsl.
pub(super) const UV_LAYER_VERTEX: u32 = 7;

/// UV mode numbers shared with the shader.
pub(super) fn uv_mode(uv: &UvSource) -> (u32, [f32; 4]) {
    match *uv {
        UvSource::Mesh => (0, [0.0; 4]),
        UvSource::Sun { size_deg } => (1, [size_deg.get().to_radians(), 0.0, 0.0, 0.0]),
        UvSource::Celestial => (UV_CELESTIAL, [0.0; 4]),
        UvSource::Quake { z_scale, z_offset, t_scale, time_scale } => (3, [z_scale.get(), z_offset.get(), t_scale.get(), time_scale.get()]),
        UvSource::Layer { .. } => (UV_LAYER, layer_params(*uv).map_or([0.0; 4], |p| [p.height as f32, p.radius as f32, p.fade_sin as f32, 0.0])),
    }
}

/// The shader's index of a lighting (`misc[1]` of the uniform, `LIGHTING` of a variant).
pub(super) fn lighting_index(l: Lighting) -> u32 {
    match l {
        Lighting::Flat => 0,
        Lighting::Moon => 1,
        Lighting::Cloud => 2,
    }
}

/// The part of a pipeline signature that a version's data fixes: its stages after folding (count,
/// UV mode, op and constant of each) and its lighting. Computed once per upload from the sky, not
/// read back from the uniform the GPU gets.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct MaterialSignature {
    pub(super) count: u32,
    pub(super) modes: [u32; 4],
    pub(super) ops: [u32; 4],
    pub(super) constants: [u32; 4],
    pub(super) lighting: u32,
}

impl MaterialSignature {
    /// The signature of version `v` with the stages `folded_into` (the first of each folded pair)
    /// each sampling the folded texture, the stage after it left white.
    pub(super) fn of(v: &Version, folded_into: &[usize]) -> Self {
        let mut sig = Self { count: v.stages.len() as u32, modes: [0; 4], ops: [0; 4], constants: [0; 4], lighting: lighting_index(v.lighting) };
        for (k, s) in v.stages.iter().enumerate().take(4) {
            sig.modes[k] = uv_mode(&s.uv).0;
            sig.ops[k] = u32::from(s.op == StageOp::Modulate);
            sig.constants[k] = s.constant.map_or(NO_STAGE, |c| c as u32);
        }
        for &first in folded_into {
            let second = first + 1;
            if second < 4 {
                if sig.constants[first] == NO_STAGE {
                    sig.constants[first] = sig.constants[second];
                }
                sig.modes[second] = UV_WHITE;
                sig.constants[second] = NO_STAGE;
            }
        }
        sig
    }
}

impl From<&Version> for DrawUniform {
    /// The parts of a draw that do not change from frame to frame, no stage folded.
    fn from(v: &Version) -> Self {
        let mut stages = [StageUniform::zeroed(); 4];
        for (k, s) in v.stages.iter().enumerate() {
            stages[k] = StageUniform { scale_offset: [s.uv_scale[0], s.uv_scale[1], 0.0, 0.0], params: uv_mode(&s.uv).1, cfg: [0; 4] };
        }
        let u = DrawUniform {
            object_from_local: Mat4::IDENTITY.to_cols_array_2d(),
            diffuse: [1.0; 4],
            constants: [[1.0; 4]; 4],
            stages,
            misc: [0, 0, NO_STAGE, v.cloud_density.to_bits()],
        };
        u.with_signature(&MaterialSignature::of(v, &[]))
    }
}

impl DrawUniform {
    /// The uniform with the configuration words of `sig` (stage count, lighting, and each
    /// stage's op, UV mode and constant, every stage sampled): the one place they are written.
    pub(super) fn with_signature(mut self, sig: &MaterialSignature) -> Self {
        (self.misc[0], self.misc[1]) = (sig.count, sig.lighting);
        for k in 0..(sig.count as usize).min(4) {
            self.stages[k].cfg = [sig.ops[k], sig.modes[k], sig.constants[k], 1];
        }
        self
    }

    /// Marks the stages of terms that contribute nothing this frame (a factor's constant is black,
    /// and transparent too when alpha weighs the colour) so the shader does not sample them;
    /// returns how many. The sky-model stage is never skipped.
    pub fn skip_dark_terms(&mut self, alpha_matters: bool) -> u32 {
        self.skip_dark_stages(alpha_matters).0
    }

    /// [`Self::skip_dark_terms`], also returning the stages still sampled.
    pub(super) fn skip_dark_stages(&mut self, alpha_matters: bool) -> (u32, [bool; 4]) {
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
        (skipped, std::array::from_fn(|k| k < count && self.stages[k].cfg[3] != 0))
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
