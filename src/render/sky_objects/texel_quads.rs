//! A sparse texture on a dome's grid drawn texel by texel: each texel that is not black becomes a
//! small polygon covering where bilinear filtering reads it, and the polygon's fragments add the
//! texel times its filter weight. Summed by additive blending, that is the level-0 bilinear sample
//! itself (a sample is the sum over texels of the texel times the product of the two tent weights
//! `max(0, 1 - |distance in texels|)`), but only the few pixels near a bright texel are shaded.
//! The skydome's tiled stars times their mask light under 1% of their texels: sampling them over
//! the whole frame costs a software rasteriser about as much as the fill-rate floor's one sample
//! (docs/architecture.md), their polygons a fraction of that.
//!
//! The polygons lie on the grid's flat triangles, each clipped to its triangle: the rasteriser
//! interpolates a texel's offset over a polygon exactly as it interpolates texture coordinates
//! over the triangle under it, so the mapping is the mesh's.

use bytemuck::{Pod, Zeroable};
use glam::{Vec2, Vec3};
use wgpu::util::DeviceExt;

use crate::render::gpu::mesh::MeshData;

/// The most texels that are not black a texture may have to be drawn texel by texel (about a
/// megabyte of vertices); denser textures are sampled.
pub const MAX_TEXELS: usize = 40_000;
/// The largest share of a texture's texels that may be lit for it to be drawn texel by texel:
/// the built-in stars (0.75% lit) cost about half the sample they replace at dusk looking up
/// (docs/architecture.md), so above about twice that the polygons would cost more.
pub const MAX_LIT_SHARE: f32 = 0.015;

/// Vertex of a texel's polygon. Keep in sync with `vs_texels` in shaders/sky_objects/texels.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct TexelVertex {
    /// Point on the grid triangle under it (a direction, not unit length).
    pub position: [f32; 3],
    /// Where it lies in the texture, in texels from the texel's centre (u, v).
    pub offset: [f32; 2],
    /// The texel (RGBA8), the same at every vertex of its polygon.
    pub texel: [u8; 4],
}

const _: () = assert!(std::mem::size_of::<TexelVertex>() == 24);

impl TexelVertex {
    /// Vertex buffer layout.
    pub const LAYOUT: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
        array_stride: std::mem::size_of::<TexelVertex>() as u64,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x2, 2 => Unorm8x4],
    };
}

/// A repeating RGBA8 texture and how a dome's mesh coordinates map onto it.
pub struct TexelSource<'a> {
    /// Width and height, texels.
    pub size: (u32, u32),
    /// RGBA8 texels, rows top first.
    pub rgba8: &'a [u8],
    /// Repeats across the mesh's coordinates (u, v): texture coordinates = mesh's x this.
    pub scale: [f32; 2],
}

impl TexelSource<'_> {
    /// Texel (i, j), repeating.
    fn at(&self, i: i64, j: i64) -> [u8; 4] {
        let (w, h) = (i64::from(self.size.0), i64::from(self.size.1));
        let k = (j.rem_euclid(h) * w + i.rem_euclid(w)) as usize * 4;
        [self.rgba8[k], self.rgba8[k + 1], self.rgba8[k + 2], self.rgba8[k + 3]]
    }

    /// Texels whose colour is not black (alpha is not drawn by an additive term).
    pub fn lit(&self) -> usize {
        self.rgba8.chunks_exact(4).filter(|t| t[..3] != [0, 0, 0]).count()
    }

    /// Whether few enough texels are lit for the texture to be drawn texel by texel.
    pub fn sparse(&self) -> bool {
        let lit = self.lit();
        let all = self.size.0 as usize * self.size.1 as usize;
        all > 0 && lit <= MAX_TEXELS && lit as f32 <= MAX_LIT_SHARE * all as f32
    }
}

/// CPU geometry: the polygons as triangles, by the grid's cells.
#[derive(Debug, Clone, Default)]
pub struct TexelMesh {
    /// Vertices.
    pub vertices: Vec<TexelVertex>,
    /// Triangle list indices, cell by cell of the grid ([`Self::cell_starts`]).
    pub indices: Vec<u32>,
    /// Index of each grid cell's first triangle (ring by ring, then segment by segment), and
    /// the count at the end (rings x segments + 1 entries).
    pub cell_starts: Vec<u32>,
    /// Segments per ring.
    pub segments: u32,
    /// Each cell's bounding cone: unit centre direction and angular radius, degrees.
    pub cell_cones: Vec<(Vec3, f32)>,
    /// Polygons (lit texels clipped to one grid triangle).
    pub polygons: u32,
}

/// The part of convex polygon `p` on the left of the line from `a` to `b` (Sutherland-Hodgman).
fn clip(p: &[Vec2], a: Vec2, b: Vec2) -> Vec<Vec2> {
    let side = |q: Vec2| (b - a).perp_dot(q - a);
    let mut out = Vec::with_capacity(p.len() + 1);
    for (k, &q) in p.iter().enumerate() {
        let r = p[(k + 1) % p.len()];
        let (sq, sr) = (side(q), side(r));
        if sq >= 0.0 {
            out.push(q);
        }
        if (sq >= 0.0) != (sr >= 0.0) {
            out.push(q + (r - q) * (sq / (sq - sr)));
        }
    }
    out
}

/// The polygons of `source`'s lit texels on `grid`'s triangles (a dome's grid: `rings` rings of
/// `segments` quads, each ring `segments` x 6 indices, as `mesh::shape_mesh` makes it).
pub fn build(grid: &MeshData, rings: u32, source: &TexelSource<'_>) -> TexelMesh {
    let mut m = TexelMesh::default();
    let per_ring = grid.indices.len() / rings.max(1) as usize;
    // A grid cell is two triangles, six indices.
    m.segments = (per_ring / 6) as u32;
    let texels = Vec2::new(source.size.0 as f32 * source.scale[0], source.size.1 as f32 * source.scale[1]);
    for cell in grid.indices.chunks(6) {
        m.cell_starts.push(m.indices.len() as u32);
        let corners: Vec<Vec3> = cell.iter().map(|&i| Vec3::from(grid.vertices[i as usize].position)).collect();
        let centre = corners.iter().copied().sum::<Vec3>().normalize_or_zero();
        let radius = corners.iter().map(|c| centre.dot(c.normalize_or_zero()).clamp(-1.0, 1.0).acos().to_degrees()).fold(0.0, f32::max);
        m.cell_cones.push((centre, radius));
        for t in cell.chunks_exact(3) {
            let v = [t[0], t[1], t[2]].map(|i| grid.vertices[i as usize]);
            let p = v.map(|v| Vec3::from(v.position));
            // The pole's triangles with two corners at the pole cover nothing.
            if (p[1] - p[0]).cross(p[2] - p[0]).length_squared() < 1e-12 {
                continue;
            }
            // In texel units: texel (i, j) has its centre at (i + 1/2, j + 1/2).
            let q = v.map(|v| Vec2::from(v.uv) * texels);
            let area = (q[1] - q[0]).perp_dot(q[2] - q[0]);
            if area.abs() < 1e-9 {
                continue;
            }
            // Counter-clockwise, for `clip`.
            let tri = if area > 0.0 { [q[0], q[1], q[2]] } else { [q[0], q[2], q[1]] };
            let pos = if area > 0.0 { p } else { [p[0], p[2], p[1]] };
            let (lo, hi) = (tri[0].min(tri[1]).min(tri[2]), tri[0].max(tri[1]).max(tri[2]));
            // A texel's tent spans a texel either side of its centre.
            let (i0, i1) = ((lo.x - 1.5).floor() as i64, (hi.x + 0.5).ceil() as i64);
            let (j0, j1) = ((lo.y - 1.5).floor() as i64, (hi.y + 0.5).ceil() as i64);
            let area = area.abs();
            for j in j0..=j1 {
                for i in i0..=i1 {
                    let texel = source.at(i, j);
                    if texel[..3] == [0, 0, 0] {
                        continue;
                    }
                    let centre = Vec2::new(i as f32 + 0.5, j as f32 + 0.5);
                    let square = [centre + Vec2::new(-1.0, -1.0), centre + Vec2::new(1.0, -1.0), centre + Vec2::new(1.0, 1.0), centre + Vec2::new(-1.0, 1.0)];
                    let mut poly = square.to_vec();
                    for k in 0..3 {
                        if poly.len() < 3 {
                            break;
                        }
                        poly = clip(&poly, tri[k], tri[(k + 1) % 3]);
                    }
                    if poly.len() < 3 {
                        continue;
                    }
                    // Barycentric coordinates on the texel-space triangle carry each corner onto
                    // the flat grid triangle.
                    let first = m.vertices.len() as u32;
                    for &c in &poly {
                        let b1 = (c - tri[0]).perp_dot(tri[2] - tri[0]) / area;
                        let b2 = (tri[1] - tri[0]).perp_dot(c - tri[0]) / area;
                        let b0 = 1.0 - b1 - b2;
                        let position = pos[0] * b0 + pos[1] * b1 + pos[2] * b2;
                        m.vertices.push(TexelVertex { position: position.to_array(), offset: (c - centre).to_array(), texel });
                    }
                    for k in 1..poly.len() as u32 - 1 {
                        m.indices.extend_from_slice(&[first, first + k, first + k + 1]);
                    }
                    m.polygons += 1;
                }
            }
        }
    }
    m.cell_starts.push(m.indices.len() as u32);
    m
}

/// Polygons on the GPU.
pub struct GpuTexelMesh {
    /// Vertex buffer.
    pub vertices: wgpu::Buffer,
    /// Index buffer (u32).
    pub indices: wgpu::Buffer,
    /// Index of each grid cell's first triangle, and the count at the end ([`TexelMesh`]).
    pub cell_starts: Vec<u32>,
    /// Segments per ring.
    pub segments: u32,
    /// Each cell's bounding cone ([`TexelMesh::cell_cones`]).
    pub cell_cones: Vec<(Vec3, f32)>,
    /// The grid's bands ([`crate::render::gpu::mesh::band_indices`], indices into the grid's own vertices):
    /// where the polygons stand for the sparse stage, the rest of the draw maps nothing from the
    /// grid, and one band over those rings covers the same pixels with fewer triangles, whose
    /// edges a rasteriser shades twice.
    pub bands: wgpu::Buffer,
    /// Rings of the grid.
    pub rings: u32,
}

impl GpuTexelMesh {
    /// Uploads the polygons; None when there are none.
    pub fn new(device: &wgpu::Device, label: &str, m: &TexelMesh) -> Option<Self> {
        if m.indices.is_empty() {
            return None;
        }
        let vertices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(&format!("{label}::texel_vertices")),
            contents: bytemuck::cast_slice(&m.vertices),
            usage: wgpu::BufferUsages::VERTEX,
        });
        let indices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(&format!("{label}::texel_indices")),
            contents: bytemuck::cast_slice(&m.indices),
            usage: wgpu::BufferUsages::INDEX,
        });
        let segments = m.segments.max(1);
        let rings = (m.cell_starts.len().saturating_sub(1) as u32) / segments;
        let bands = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(&format!("{label}::grid_bands")),
            contents: bytemuck::cast_slice(&crate::render::gpu::mesh::band_indices(rings, segments)),
            usage: wgpu::BufferUsages::INDEX,
        });
        Some(Self { vertices, indices, cell_starts: m.cell_starts.clone(), segments: m.segments, cell_cones: m.cell_cones.clone(), bands, rings })
    }

    /// The indices in [`Self::bands`] of the band over grid rings `rings` (top first).
    pub fn band(&self, rings: std::ops::Range<usize>) -> std::ops::Range<u32> {
        let (a, b) = ((rings.start as u32).min(self.rings), (rings.end as u32).min(self.rings));
        if a >= b {
            return 0..0;
        }
        let start = crate::render::gpu::mesh::band_start(self.rings, self.segments.max(1), a, b);
        start..start + self.segments.max(1) * 6
    }

    /// The index ranges of rings `rings` (grid rings, top first) in cells that `shown` says may
    /// be in view (given a cell's bounding cone), consecutive cells in one range: polygons out of
    /// view still cost the rasteriser their vertices and setup.
    pub fn ring_indices(&self, rings: std::ops::Range<usize>, shown: impl Fn(Vec3, f32) -> bool) -> Vec<std::ops::Range<u32>> {
        let cells = self.cell_cones.len();
        let segments = self.segments.max(1) as usize;
        let mut out: Vec<std::ops::Range<u32>> = Vec::new();
        for c in (rings.start * segments).min(cells)..(rings.end * segments).min(cells) {
            let (start, end) = (self.cell_starts[c], self.cell_starts[c + 1]);
            if start == end || !shown(self.cell_cones[c].0, self.cell_cones[c].1) {
                continue;
            }
            match out.last_mut() {
                Some(r) if r.end == start => r.end = end,
                _ => out.push(start..end),
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::gpu::mesh::{dome_grid, shape_mesh};
    use crate::sky::model::Elevation;
    use crate::sky::resolved::Shape;

    /// Bilinear sample at texture coordinates `uv` (repeating, texel centres at half-integers).
    fn bilinear(s: &TexelSource<'_>, uv: Vec2) -> [f32; 3] {
        let x = uv.x * s.size.0 as f32 - 0.5;
        let y = uv.y * s.size.1 as f32 - 0.5;
        let (i, j) = (x.floor() as i64, y.floor() as i64);
        let (fx, fy) = (x - x.floor(), y - y.floor());
        let mut out = [0.0; 3];
        for (di, dj, w) in [(0, 0, (1.0 - fx) * (1.0 - fy)), (1, 0, fx * (1.0 - fy)), (0, 1, (1.0 - fx) * fy), (1, 1, fx * fy)] {
            let t = s.at(i + di, j + dj);
            for (o, &t) in out.iter_mut().zip(&t) {
                *o += w * f32::from(t);
            }
        }
        out
    }

    #[test]
    fn the_polygons_add_up_to_the_bilinear_sample_everywhere_on_the_grid() {
        let shape = Shape::Dome { bottom_deg: Elevation(-20.0) };
        let (_, _, rings, _) = dome_grid(&shape).expect("a dome has a grid");
        let grid = shape_mesh(&shape);
        // A sparse texture: a few lit texels, two of them side by side (their tents overlap),
        // one on the seam of the repeat.
        let (w, h) = (40u32, 24u32);
        let mut rgba8 = vec![0u8; (w * h * 4) as usize];
        for (i, j, c) in [(3, 4, [200, 100, 50]), (4, 4, [10, 255, 30]), (39, 10, [255, 255, 255]), (20, 0, [90, 90, 200]), (17, 19, [1, 0, 0])] {
            let k = ((j * w + i) * 4) as usize;
            rgba8[k..k + 3].copy_from_slice(&c);
            rgba8[k + 3] = 255;
        }
        let source = TexelSource { size: (w, h), rgba8: &rgba8, scale: [3.0, 2.0] };
        assert!(source.sparse());
        let m = build(&grid, rings, &source);
        let (_, _, _, segments) = dome_grid(&shape).expect("a dome has a grid");
        assert_eq!(m.cell_starts.len(), (rings * segments) as usize + 1);
        assert!(m.polygons >= 5 * 6, "{} polygons", m.polygons);
        // Each cell's cone holds its polygons.
        for (c, &(centre, radius_deg)) in m.cell_cones.iter().enumerate() {
            for &i in &m.indices[m.cell_starts[c] as usize..m.cell_starts[c + 1] as usize] {
                let p = Vec3::from(m.vertices[i as usize].position).normalize();
                assert!(centre.dot(p).clamp(-1.0, 1.0).acos().to_degrees() <= radius_deg + 1e-3, "cell {c}");
            }
        }
        // Points on each grid triangle: the mesh's texture coordinates there, and the sum of the
        // polygons that hold the same point (on the same flat triangle).
        let mut checked = 0;
        let mut rng = fastrand::Rng::with_seed(5);
        for (t_index, t) in grid.indices.chunks_exact(3).enumerate() {
            let v = [t[0], t[1], t[2]].map(|i| grid.vertices[i as usize]);
            let p = v.map(|v| Vec3::from(v.position));
            if (p[1] - p[0]).cross(p[2] - p[0]).length_squared() < 1e-12 {
                continue;
            }
            let normal = (p[1] - p[0]).cross(p[2] - p[0]).normalize();
            for _ in 0..12 {
                let (a, b) = (rng.f32(), rng.f32());
                let (a, b) = if a + b > 1.0 { (1.0 - a, 1.0 - b) } else { (a, b) };
                let point = p[0] * (1.0 - a - b) + p[1] * a + p[2] * b;
                let uv = (Vec2::from(v[0].uv) * (1.0 - a - b) + Vec2::from(v[1].uv) * a + Vec2::from(v[2].uv) * b) * Vec2::from(source.scale);
                let expected = bilinear(&source, uv);
                let mut sum = [0.0f32; 3];
                let mut counted = std::collections::HashSet::new();
                let cell = t_index / 2;
                let range = m.cell_starts[cell] as usize..m.cell_starts[cell + 1] as usize;
                for tri in m.indices[range].chunks_exact(3) {
                    let q = [tri[0], tri[1], tri[2]].map(|i| m.vertices[i as usize]);
                    let qp = q.map(|q| Vec3::from(q.position));
                    // Only polygons on this grid triangle's plane.
                    if qp.iter().any(|x| (*x - p[0]).dot(normal).abs() > 1e-5) {
                        continue;
                    }
                    // Barycentric coordinates of the point in this polygon triangle.
                    let n = (qp[1] - qp[0]).cross(qp[2] - qp[0]);
                    let area = n.length_squared();
                    if area < 1e-14 {
                        continue;
                    }
                    let b1 = (point - qp[0]).cross(qp[2] - qp[0]).dot(n) / area;
                    let b2 = (qp[1] - qp[0]).cross(point - qp[0]).dot(n) / area;
                    let b0 = 1.0 - b1 - b2;
                    // A point on an edge two triangles of one polygon (one fan) share counts once.
                    if b0 < -1e-6 || b1 < -1e-6 || b2 < -1e-6 || !counted.insert(tri[0]) {
                        continue;
                    }
                    let off = Vec2::from(q[0].offset) * b0 + Vec2::from(q[1].offset) * b1 + Vec2::from(q[2].offset) * b2;
                    let weight = (1.0 - off.x.abs()).max(0.0) * (1.0 - off.y.abs()).max(0.0);
                    for (s, &t) in sum.iter_mut().zip(&q[0].texel) {
                        *s += weight * f32::from(t);
                    }
                }
                assert!(sum.iter().zip(&expected).all(|(s, e)| (s - e).abs() < 0.05), "triangle {t_index} at {uv}: polygons {sum:?}, bilinear {expected:?}");
                checked += 1;
            }
        }
        assert!(checked > 5000);
    }
}
