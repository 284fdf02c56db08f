//! The background's sparse stage drawn texel by texel: the draw without that stage on one
//! triangle over the frame and bands, and the scissor rectangles round what still samples it.

#[allow(unused_imports)]
use super::*;

/// Entry points (vertex, fragment) of one draw's pipelines and of a pair's.
/// A background draw with its sparse stage texel by texel this frame ([`SkyObjectsPass::texel_draw`]).
pub(super) struct TexelDraw<'a> {
    /// The stage the polygons stand for.
    pub(super) stage: usize,
    /// The draw without the stage, on the grid or its bands.
    pub(super) without: &'a wgpu::RenderPipeline,
    /// The same as one triangle over the frame ([`crate::render::plan::strategy::SparseStages::TexelPolygonsOnBands`]), if built.
    pub(super) fullscreen: Option<&'a wgpu::RenderPipeline>,
    /// The polygons' pipeline and mesh.
    pub(super) polygons: &'a wgpu::RenderPipeline,
    pub(super) mesh: &'a GpuTexelMesh,
}

/// `frame` (x, y, width, height) less the rectangles `holes`, as rectangles that do not overlap.
pub(super) fn scissor_rects(frame: [u32; 4], holes: &[[u32; 4]]) -> Vec<[u32; 4]> {
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

impl SkyObjectsPass {
    /// The frame's pixels (x, y, width, height) that hold the grid rings of `d` whose triangles
    /// `ring_indices` index (ranges of its grid's indices), with a pixel of margin: the box of
    /// their rows of vertices, projected. The whole frame when one lies behind the eye (the box
    /// would be unbounded), None for no rings.
    pub(super) fn rings_box(&self, d: &VersionDraw, ring_indices: impl Iterator<Item = std::ops::Range<u32>>) -> Option<[u32; 4]> {
        let (top_deg, bottom_deg, rings, segments) = crate::render::gpu::mesh::dome_grid(&d.shape)?;
        let per_ring = segments * 6;
        let (w, h) = (self.frame_size.0.max(1), self.frame_size.1.max(1));
        let (_, clip_from_sky) = self.frame_camera.matrices(w as f32 / h as f32);
        let (mut lo, mut hi) = (glam::Vec2::splat(f32::INFINITY), glam::Vec2::splat(f32::NEG_INFINITY));
        let mut any = false;
        for indices in ring_indices {
            // The rings' region is bounded by its top and bottom rows' chords and the meridians
            // between: its projection lies in the box of those rows' vertices.
            for row in [indices.start / per_ring, indices.end.div_ceil(per_ring)] {
                let elevation = crate::render::gpu::mesh::row_elevation_deg(top_deg, bottom_deg, rings, row.min(rings));
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
    /// stand for (mesh-mapped or a cloud layer's per vertex, not the sky model's, the term's other stages folded into it as
    /// white, no lighting) on the display target, in a layer without the sky model's map (whose
    /// terms are summed in radiance and tone-mapped by the layer: the polygons' display values
    /// could not join that sum).
    pub(super) fn without_texel_stage(key: &VariantKey, stage: usize) -> Option<VariantKey> {
        let background = matches!(key.placement, Slot::Background | Slot::JoinedBackground);
        let own_term = (0..MAX_STAGES).filter(|&j| j != stage && key.live[j]).all(|j| j > stage && key.modes[j] == UV_WHITE && key.ops[j] == 1 && key.constants[j] == NO_STAGE);
        // Per vertex, the polygons lie on the same chords of the layer as the grid the sample
        // would be interpolated over.
        let on_grid = key.modes[stage] == UV_MESH || key.modes[stage] == UV_LAYER_VERTEX;
        let term = key.live[stage] && on_grid && key.ops[stage] != 1 && key.view_stage as usize >= MAX_STAGES && key.lighting == 0;
        (background && key.target == Target::Display && !key.reduced && own_term && term).then(|| {
            let mut live = key.live;
            live[stage] = false;
            VariantKey { live, ..*key }
        })
    }

    /// Draw `e` placed as `placement` with its sparse stage texel by texel this frame.
    pub(super) fn texel_draw(&self, e: &Visible, target: Target, placement: Slot) -> Option<TexelDraw<'_>> {
        let d = &self.draws.current.as_ref()?.objects[e.index][e.version];
        let (stage, mesh) = d.texels.as_ref().filter(|_| self.texels_on)?;
        let key = self.entry_key(e, target, placement)?;
        let without_key = Self::without_texel_stage(&key, *stage)?;
        let without = self.variants.get(&without_key)?.as_ref()?;
        let polygons = self.texel_pipelines.get(&key)?.as_ref()?;
        let fullscreen = self.fullscreen_pipelines.get(&without_key).and_then(Option::as_ref).filter(|_| self.bands_on);
        Some(TexelDraw { stage: *stage, without, fullscreen, polygons, mesh })
    }
}
