//! The mip bounds: which stages of a draw are sampled from level 0 alone, part by part. A stage
//! whose level of detail stays at most 1/2 wherever a part is drawn reads level 0 through the
//! mipmapped sampler too (nearest level, linear within it; Vulkan: level ceil(lod + 1/2) - 1),
//! so a level-0 sampler gives the same pixels without the level-of-detail work.
//!
//! Domes decide per ring of triangles, since texture coordinates crowd towards the pole (a view
//! of the zenith needs the tiled stars' levels round the zenith, not lower down); the rings the
//! frame does not show are left out. Pure: the stage densities come from
//! `sky_objects::detail`, which this module asks through a closure.

use std::ops::Range;

/// The (azimuth, elevation) grid of a dome shape's mesh (`gpu::mesh::dome_grid`): six indices
/// per cell, `segments` cells per ring, rings from `top_deg` down to `bottom_deg`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DomeGrid {
    /// Elevation of the first ring's upper edge, degrees.
    pub top_deg: f32,
    /// Elevation of the last ring's lower edge, degrees.
    pub bottom_deg: f32,
    /// Rings of cells from top to bottom.
    pub rings: u32,
    /// Cells per ring.
    pub segments: u32,
}

impl DomeGrid {
    /// From `gpu::mesh::dome_grid`'s tuple.
    pub fn from_tuple((top_deg, bottom_deg, rings, segments): (f32, f32, u32, u32)) -> Self {
        Self { top_deg, bottom_deg, rings, segments }
    }

    /// Ring `r`'s lowest and highest elevation, degrees.
    pub fn ring_deg(&self, r: u32) -> (f32, f32) {
        let (top, bottom, n) = (self.top_deg, self.bottom_deg, self.rings as f32);
        let (a, b) = (top + (bottom - top) * r as f32 / n, top + (bottom - top) * (r + 1) as f32 / n);
        (a.min(b), a.max(b))
    }

    /// Whether a frame showing elevations `lowest_deg..highest_deg` may show ring `r`: with the
    /// margin of the chords' sag (tests in gpu/mesh.rs).
    pub fn ring_shown(&self, r: u32, lowest_deg: f32, highest_deg: f32) -> bool {
        let (ring_lo, ring_hi) = self.ring_deg(r);
        ring_lo - 0.5 <= highest_deg && ring_hi + 0.5 >= lowest_deg
    }
}

/// The mesh of one draw, as the mip bounds see it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum DrawMesh {
    /// A dome's grid. `outline`: the wireframe outline, one band of indices spanning every ring.
    Dome { grid: DomeGrid, outline: bool },
    /// Any other mesh (billboards, quads): one part of `index_count` indices.
    Whole { index_count: u32 },
}

/// One part of a draw: its index range and the stages (bit k: stage k) sampled from level 0.
pub type Part = (Range<u32>, u8);

/// The parts of a draw over `mesh` in a frame that shows elevations `shown_deg` (lowest,
/// highest), the scene covering what lies below `covered_below_deg` (negative infinity without
/// the scene), and the stages sampled from level 0 in any of them. `level0(ring)` gives the
/// stages whose texels stay coarse enough there (`None`: the whole shape).
///
/// Consecutive rings with the same stages are one part. A dome with no ring in view is one empty
/// part, drawn as nothing; the outline is one part, each stage from level 0 only where it may be
/// in every ring in view.
pub fn parts(mesh: DrawMesh, shown_deg: (f32, f32), covered_below_deg: f32, level0: impl Fn(Option<usize>) -> u8) -> (Vec<Part>, u8) {
    let (lowest_deg, highest_deg) = shown_deg;
    let (grid, outline) = match mesh {
        DrawMesh::Whole { index_count } => {
            let used = level0(None);
            return (vec![(0..index_count, used)], used);
        }
        DrawMesh::Dome { grid, outline } => (grid, outline),
    };
    let per_ring = grid.segments * 6;
    let mut out: Vec<Part> = Vec::new();
    let mut used = 0u8;
    for r in 0..grid.rings {
        // Rings the scene covers whole are left out too.
        if !grid.ring_shown(r, lowest_deg.max(covered_below_deg), highest_deg) {
            continue;
        }
        let mask = level0(Some(r as usize));
        if outline {
            match out.first_mut() {
                Some((_, m)) => *m &= mask,
                None => out.push((0..per_ring, mask)),
            }
            continue;
        }
        used |= mask;
        let indices = r * per_ring..(r + 1) * per_ring;
        match out.last_mut() {
            Some((range, m)) if *m == mask && range.end == indices.start => range.end = indices.end,
            _ => out.push((indices, mask)),
        }
    }
    if outline {
        used |= out.first().map_or(0, |p| p.1);
    }
    if out.is_empty() {
        out.push((0..0, 0));
    }
    (out, used)
}

#[cfg(test)]
mod tests {
    use super::*;

    const GRID: DomeGrid = DomeGrid { top_deg: 90.0, bottom_deg: -20.0, rings: 11, segments: 4 };

    /// Stage 0 coarse enough from ring 3 down (10 degrees a ring: below 60 degrees), stage 1 everywhere.
    fn level0(ring: Option<usize>) -> u8 {
        0b10 | u8::from(ring.is_none_or(|r| r >= 3))
    }

    #[test]
    fn rings_in_view_merge_into_parts_by_their_stages() {
        let dome = DrawMesh::Dome { grid: GRID, outline: false };
        let per_ring = 24;
        // Every ring shown: the three polar rings, then the rest.
        let (all, used) = parts(dome, (-90.0, 90.0), f32::NEG_INFINITY, level0);
        assert_eq!(all, vec![(0..3 * per_ring, 0b10), (3 * per_ring..11 * per_ring, 0b11)]);
        assert_eq!(used, 0b11);
        // The parts never overlap and cover exactly the rings in view: a frame from 5 to 35
        // degrees shows rings 5 to 8 (40..30 down to 10..0), with half a degree of margin.
        let (low, used) = parts(dome, (5.0, 35.0), f32::NEG_INFINITY, level0);
        assert_eq!(low, vec![(5 * per_ring..9 * per_ring, 0b11)]);
        assert_eq!(used, 0b11);
        // What the scene covers is left out: from -2 degrees, the rings down to -10 only.
        let (covered, _) = parts(dome, (-30.0, 5.0), -2.0, level0);
        assert_eq!(covered, vec![(8 * per_ring..10 * per_ring, 0b11)]);
        // No ring in view: one empty part.
        let band = DomeGrid { top_deg: 80.0, bottom_deg: 60.0, rings: 2, segments: 4 };
        assert_eq!(parts(DrawMesh::Dome { grid: band, outline: false }, (-10.0, 40.0), f32::NEG_INFINITY, level0), (vec![(0..0, 0)], 0));
        // Near the pole only: stage 1 alone from level 0.
        let (polar, used) = parts(dome, (75.0, 90.0), f32::NEG_INFINITY, level0);
        assert_eq!((polar, used), (vec![(0..2 * per_ring, 0b10)], 0b10));
    }

    #[test]
    fn the_outline_keeps_only_stages_coarse_in_every_ring_in_view() {
        let outline = DrawMesh::Dome { grid: GRID, outline: true };
        assert_eq!(parts(outline, (-90.0, 90.0), f32::NEG_INFINITY, level0), (vec![(0..24, 0b10)], 0b10));
        assert_eq!(parts(outline, (5.0, 35.0), f32::NEG_INFINITY, level0), (vec![(0..24, 0b11)], 0b11));
        // Billboards and quads: one part, the whole shape's bound.
        assert_eq!(parts(DrawMesh::Whole { index_count: 6 }, (0.0, 10.0), 0.0, level0), (vec![(0..6, 0b11)], 0b11));
    }
}
