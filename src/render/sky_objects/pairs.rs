//! Two neighbouring alpha-blended layers on the same mesh (the clouds) drawn at once.

#[allow(unused_imports)]
use super::*;

impl SkyObjectsPass {
    /// Whether reduced items `lower` and `upper` can be drawn at once ([`Placement::Pair`]).
    pub(super) fn can_pair(&self, lower: usize, upper: usize, target: Target, over_seed: bool) -> bool {
        let (Some(draws), Some(a), Some(b)) = (&self.draws.current, self.visible.get(lower), self.visible.get(upper)) else { return false };
        // Over the seed only as a whole dome; not where building its pipeline failed.
        let buildable = (!over_seed || self.dome_of(a)) && self.pair_key(a, b, target, over_seed).is_some_and(|k| !matches!(self.pairs.get(&k), Some(None)));
        buildable && self.pair_parts(a, b, Self::pair_mesh(draws, a, b).mesh.index_count).is_some()
    }

    /// Records reduced items `lower` and `upper` at once, over `seed` when given.
    pub(super) fn record_pair(&self, rpass: &mut wgpu::RenderPass<'_>, (lower, upper): (usize, usize), target: Target, seed: Option<&wgpu::BindGroup>) -> u32 {
        let (Some(draws), Some(a), Some(b)) = (&self.draws.current, self.visible.get(lower), self.visible.get(upper)) else { return 0 };
        let Some(pipeline) = self.pair_key(a, b, target, seed.is_some()).and_then(|k| self.pairs.get(&k)).and_then(Option::as_ref) else {
            self.missing_pipelines.set(self.missing_pipelines.get() + 1);
            return 0;
        };
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

    /// Whether draw `e` can be one of a pair: a whole alpha-blended layer in a reduced buffer.
    pub(super) fn pair_candidate(&self, e: &Visible) -> bool {
        e.reduced && !e.on_top && self.draws.current.as_ref().is_some_and(|d| d.objects[e.index][e.version].blend == BlendMode::Alpha)
    }

    /// Whether draws `lower` and `upper` can be drawn at once: both candidates, on one mesh, or
    /// on one shape's grid and outline (the same directions).
    pub(super) fn pairable(&self, lower: &Visible, upper: &Visible) -> bool {
        let Some(draws) = &self.draws.current else { return false };
        let (a, b) = (&draws.objects[lower.index][lower.version], &draws.objects[upper.index][upper.version]);
        let one_cover = Arc::ptr_eq(&a.mesh, &b.mesh) || (a.shape == b.shape && (a.outline || b.outline));
        // Coordinates per vertex move the grid onto one layer: the other draw's would be
        // interpolated over the wrong chords.
        let per_vertex = a.vertex_modes_for(self.layer_per_vertex).is_some() || b.vertex_modes_for(self.layer_per_vertex).is_some();
        self.pair_candidate(lower) && self.pair_candidate(upper) && one_cover && !per_vertex
    }

    /// The mesh a pair is drawn on: the one draw's grid where the other draws an outline.
    pub(super) fn pair_mesh<'a>(draws: &'a SkyObjectDraws, lower: &Visible, upper: &Visible) -> &'a VersionDraw {
        let (a, b) = (&draws.objects[lower.index][lower.version], &draws.objects[upper.index][upper.version]);
        if a.outline && !b.outline {
            b
        } else {
            a
        }
    }

    /// The signature of draws `lower` and `upper` drawn at once this frame, `lower` over the seed
    /// or not.
    pub(super) fn pair_key(&self, lower: &Visible, upper: &Visible, target: Target, over_seed: bool) -> Option<PairKey> {
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
    pub(super) fn pair_parts(&self, lower: &Visible, upper: &Visible, index_count: u32) -> Option<Vec<(std::ops::Range<u32>, u8, u8)>> {
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
}
