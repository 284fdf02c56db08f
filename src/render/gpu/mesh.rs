//! Procedural sky geometry: domes, dome bands and unit quads.

use bytemuck::{Pod, Zeroable};
use wgpu::util::DeviceExt;

use crate::sky::eval::direction;
use crate::sky::resolved::Shape;

/// Vertex of sky shapes. Keep in sync with `vs_main` inputs in shaders/sky_objects.wgsl (`sky_vertex` in shaders/sky_objects/draw.wgsl).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub struct SkyVertex {
    /// Unit direction (domes) or (x, y, 1) quad corner.
    pub position: [f32; 3],
    /// Texture coordinates.
    pub uv: [f32; 2],
}

impl SkyVertex {
    /// Vertex buffer layout.
    pub const LAYOUT: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
        array_stride: std::mem::size_of::<SkyVertex>() as u64,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x2],
    };
}

/// CPU-side geometry.
#[derive(Debug, Clone, Default)]
pub struct MeshData {
    /// Vertices.
    pub vertices: Vec<SkyVertex>,
    /// Triangle list indices.
    pub indices: Vec<u32>,
}

/// Elevation of vertex row `row` of a grid of `rings` from `top_deg` down to `bottom_deg`, degrees.
pub fn row_elevation_deg(top_deg: f32, bottom_deg: f32, rings: u32, row: u32) -> f32 {
    top_deg + (bottom_deg - top_deg) * row as f32 / rings as f32
}

/// Triangle-list indices of the quads between vertex rows `top` and `bottom` of a grid of
/// `segments` (rows of `segments` + 1 vertices): one quad per segment, the chords of both rows.
fn row_quads(top: u32, bottom: u32, segments: u32) -> impl Iterator<Item = u32> {
    let row = segments + 1;
    (0..segments).flat_map(move |s| {
        let (a, b) = (top * row + s, bottom * row + s);
        [a, b, a + 1, a + 1, b, b + 1]
    })
}

/// A grid over (azimuth, elevation) from `top_deg` down to `bottom_deg`; v runs 0 at the top to 1.
fn sphere_band(top_deg: f32, bottom_deg: f32, rings: u32, segments: u32) -> MeshData {
    let mut m = MeshData::default();
    for r in 0..=rings {
        let v = r as f32 / rings as f32;
        let elevation = row_elevation_deg(top_deg, bottom_deg, rings, r);
        for s in 0..=segments {
            let u = s as f32 / segments as f32;
            m.vertices.push(SkyVertex { position: direction(u * 360.0, elevation).to_array(), uv: [u, v] });
        }
    }
    m.indices = (0..rings).flat_map(|r| row_quads(r, r + 1, segments)).collect();
    m
}

/// The (azimuth, elevation) grid of a dome shape: (top_deg, bottom_deg, rings, segments).
pub fn dome_grid(shape: &Shape) -> Option<(f32, f32, u32, u32)> {
    match *shape {
        Shape::Dome { bottom_deg } => Some((90.0, bottom_deg.get(), 16, 32)),
        Shape::DomeBand { bottom_deg, top_deg } => Some((top_deg.get(), bottom_deg.get(), 6, 48)),
        Shape::Billboard { .. } | Shape::Quad { .. } => None,
    }
}

/// Geometry of a shape.
pub fn shape_mesh(shape: &Shape) -> MeshData {
    match dome_grid(shape) {
        Some((top_deg, bottom_deg, rings, segments)) => sphere_band(top_deg, bottom_deg, rings, segments),
        // Billboards and quads: one square.
        None => MeshData {
            vertices: [[-1.0, 1.0, 0.0, 0.0], [1.0, 1.0, 1.0, 0.0], [-1.0, -1.0, 0.0, 1.0], [1.0, -1.0, 1.0, 1.0]]
                .iter()
                .map(|&[x, y, u, v]| SkyVertex { position: [x, y, 1.0], uv: [u, v] })
                .collect(),
            indices: vec![0, 2, 1, 1, 2, 3],
        },
    }
}

/// A dome shape's outline: one band of triangles between its top ring (the pole, for a dome) and
/// its bottom one, with the grid's segments ([`dome_grid`]). Its triangles cover the same
/// directions as the grid's (their edges along the rings are the same chords, those between are
/// on the same meridians), but its texture coordinates follow only the outline: for layers whose
/// stages all map the view direction per pixel (celestial, sun, Quake, layer), which a rasteriser pays
/// per triangle. None for billboards and quads.
pub fn outline_mesh(shape: &Shape) -> Option<MeshData> {
    dome_grid(shape).map(|(top_deg, bottom_deg, _, segments)| sphere_band(top_deg, bottom_deg, 1, segments))
}

/// Bands of a dome's grid ([`sphere_band`]'s `rings` x `segments`): for every pair of vertex rows
/// a < b, one quad per segment between row a's chord and row b's, as triangle-list indices into
/// the grid's vertices, in the order [`band_start`] gives. A band covers the same directions as
/// the grid's rings a..b (its quads are flat trapezoids on the same chords, their sides on the
/// same meridians), with far fewer triangles: for draws that map nothing from the grid.
pub fn band_indices(rings: u32, segments: u32) -> Vec<u32> {
    (0..rings).flat_map(|a| (a + 1..=rings).flat_map(move |b| row_quads(a, b, segments))).collect()
}

/// Where the band from vertex row `a` to row `b` (a < b <= rings) starts in [`band_indices`].
pub fn band_start(rings: u32, segments: u32, a: u32, b: u32) -> u32 {
    // Pairs before (a, a + 1): rings + (rings - 1) + ... for the rows above a.
    let before = a * rings - a * a.saturating_sub(1) / 2 + (b - a - 1);
    before * segments * 6
}

/// Cache key of a shape's geometry (quads share one mesh).
pub fn shape_key(shape: &Shape) -> String {
    match *shape {
        Shape::Dome { bottom_deg } => format!("dome {}", bottom_deg.get()),
        Shape::DomeBand { bottom_deg, top_deg } => format!("band {} {}", bottom_deg.get(), top_deg.get()),
        Shape::Billboard { .. } | Shape::Quad { .. } => "quad".into(),
    }
}

/// Geometry on the GPU.
pub struct GpuMesh {
    /// Vertex buffer.
    pub vertices: wgpu::Buffer,
    /// Index buffer (u32).
    pub indices: wgpu::Buffer,
    /// Index count.
    pub index_count: u32,
}

impl GpuMesh {
    /// Uploads a mesh.
    pub fn new(device: &wgpu::Device, label: &str, data: &MeshData) -> Self {
        let vertices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(&format!("{label}::vertices")),
            contents: bytemuck::cast_slice(&data.vertices),
            usage: wgpu::BufferUsages::VERTEX,
        });
        let indices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(&format!("{label}::indices")),
            contents: bytemuck::cast_slice(&data.indices),
            usage: wgpu::BufferUsages::INDEX,
        });
        Self { vertices, indices, index_count: data.indices.len() as u32 }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sky::eval::azimuth_elevation;
    use crate::sky::model::Elevation;

    /// Largest displacement of a mesh-mapped texture on the sky, degrees of arc (u along the
    /// circle of latitude, v along the span): the rasteriser interpolates texture coordinates
    /// linearly over each flat triangle, the mapping is azimuth / 360 and elevation down the
    /// span. The pole's fan is left out (azimuth has no meaning there).
    fn uv_arc_error_deg(m: &MeshData, top_deg: f32, bottom_deg: f32) -> (f32, f32) {
        let (mut du, mut dv): (f32, f32) = (0.0, 0.0);
        for t in m.indices.chunks_exact(3) {
            let v: Vec<&SkyVertex> = t.iter().map(|&i| &m.vertices[i as usize]).collect();
            if v.iter().any(|v| v.position[1] > 0.999) {
                continue;
            }
            for (a, b) in [(0.2, 0.2), (0.6, 0.2), (0.2, 0.6), (1.0 / 3.0, 1.0 / 3.0), (0.5, 0.0), (0.0, 0.5), (0.5, 0.5)] {
                let w = [1.0 - a - b, a, b];
                let p: glam::Vec3 = (0..3).map(|k| glam::Vec3::from(v[k].position) * w[k]).sum();
                let uv: [f32; 2] = [(0..3).map(|k| v[k].uv[0] * w[k]).sum(), (0..3).map(|k| v[k].uv[1] * w[k]).sum()];
                let (az, el) = azimuth_elevation(p.normalize());
                let off_u = (uv[0] - (az / 360.0).rem_euclid(1.0)).abs();
                du = du.max(off_u.min(1.0 - off_u) * 360.0 * el.to_radians().cos());
                dv = dv.max((uv[1] - (top_deg - el) / (top_deg - bottom_deg)).abs() * (top_deg - bottom_deg));
            }
        }
        (du, dv)
    }

    /// Whether direction `d`, seen from the centre, lies in one of the triangles `indices` of
    /// `m`'s vertices: in the cone over a triangle, a sum of its corners with no negative weight.
    fn covered(m: &MeshData, indices: &[u32], d: glam::Vec3) -> bool {
        indices.chunks_exact(3).any(|t| {
            let corners = glam::Mat3::from_cols_array_2d(&[0, 1, 2].map(|k| m.vertices[t[k] as usize].position));
            corners.determinant().abs() > 1e-7 && (corners.inverse() * d).to_array().iter().all(|&w| w >= -1e-5)
        })
    }

    /// `n` directions on a spiral over the sphere, avoiding the grids' own vertices.
    fn spiral(n: usize) -> impl Iterator<Item = glam::Vec3> {
        (0..n).map(move |i| {
            let y = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
            let az = i as f32 * 2.399_963;
            let r = (1.0 - y * y).sqrt();
            glam::Vec3::new(r * az.sin(), y, -r * az.cos())
        })
    }

    #[test]
    fn a_band_covers_the_directions_its_rings_of_the_grid_cover() {
        for shape in [Shape::Dome { bottom_deg: Elevation(-20.0) }, Shape::DomeBand { bottom_deg: Elevation(-10.0), top_deg: Elevation(20.0) }] {
            let (_, _, rings, segments) = dome_grid(&shape).expect("a dome shape");
            let grid = shape_mesh(&shape);
            let bands = band_indices(rings, segments);
            let per_band = (segments * 6) as usize;
            assert_eq!(bands.len(), (rings * (rings + 1) / 2) as usize * per_band);
            let per_ring = (segments * 6) as usize;
            for (a, b) in [(0, 1), (0, rings), (1, rings), (3, 7.min(rings)), (rings - 1, rings), (2, 3)] {
                let start = band_start(rings, segments, a, b) as usize;
                let band = &bands[start..start + per_band];
                // The band's rows are a and b.
                let row = segments + 1;
                assert!(band.iter().all(|&i| i / row == a || i / row == b), "{shape:?} band {a}..{b}: rows");
                let rings_of_grid = &grid.indices[a as usize * per_ring..b as usize * per_ring];
                let (mut inside, mut differ) = (0, 0);
                for d in spiral(3000) {
                    let (g, o) = (covered(&grid, rings_of_grid, d), covered(&grid, band, d));
                    inside += usize::from(g);
                    differ += usize::from(g != o);
                }
                assert!(inside > 0, "{shape:?} band {a}..{b}: no direction inside");
                assert_eq!(differ, 0, "{shape:?} band {a}..{b}: directions covered by the band or the rings alone");
                assert!(band.len() * 2 <= rings_of_grid.len() || b - a == 1, "{shape:?} band {a}..{b}: no fewer triangles");
            }
        }
    }

    #[test]
    fn a_domes_outline_covers_the_directions_its_grid_covers() {
        // Directions inside the outline's triangles (seen from the centre) are inside the grid's,
        // and the other way round: sampled over the sphere, each direction is covered by both or
        // by neither.
        for shape in
            [Shape::Dome { bottom_deg: Elevation(-20.0) }, Shape::Dome { bottom_deg: Elevation(-5.0) }, Shape::DomeBand { bottom_deg: Elevation(-10.0), top_deg: Elevation(20.0) }]
        {
            let (grid, outline) = (shape_mesh(&shape), outline_mesh(&shape).expect("a dome shape"));
            assert!(outline.indices.len() * 4 <= grid.indices.len(), "{shape:?}: the outline has fewer triangles");
            let (mut inside, mut differ) = (0, 0);
            for d in spiral(4000) {
                let (g, o) = (covered(&grid, &grid.indices, d), covered(&outline, &outline.indices, d));
                inside += usize::from(g);
                differ += usize::from(g != o);
            }
            assert!(inside > 1000, "{shape:?}: {inside}");
            assert_eq!(differ, 0, "{shape:?}: directions covered by one mesh and not the other");
        }
        assert!(outline_mesh(&Shape::Quad { size_deg: crate::sky::model::Positive(5.0) }).is_none());
    }

    #[test]
    fn dome_tessellation_bends_textures_by_a_third_of_a_degree_at_most() {
        // Lavapipe pays per triangle (about 0.7 us each at 1280x720), so domes are coarse; the
        // price is this bend of mesh-mapped textures, largest near the zenith (4 pixels at
        // 1280x720 with a 70 degree field of view).
        for (shape, top, bottom) in
            [(Shape::Dome { bottom_deg: Elevation(-20.0) }, 90.0, -20.0), (Shape::DomeBand { bottom_deg: Elevation(-20.0), top_deg: Elevation(20.0) }, 20.0, -20.0)]
        {
            let (du, dv) = uv_arc_error_deg(&shape_mesh(&shape), top, bottom);
            assert!(du < 0.35 && dv < 0.35, "{shape:?}: textures bend by {du:.3} deg along u, {dv:.3} deg along v");
        }
        // The measure itself: a finer mesh bends less.
        let (fine, coarse) = (uv_arc_error_deg(&sphere_band(90.0, -20.0, 32, 64), 90.0, -20.0), uv_arc_error_deg(&sphere_band(90.0, -20.0, 8, 16), 90.0, -20.0));
        assert!(fine.0 < 0.1 && coarse.0 > 1.0, "{fine:?} {coarse:?}");
    }
}
