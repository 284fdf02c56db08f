//! Main-scene stand-in pass: terrain and a few buildings, fogged with the sky's fog colour.
//! It is drawn first in depth range [0, 0.95] so the sky (in [0.99, 1]) fails the depth test
//! behind it; it can also draw a clip-space test occluder for the glare tests.

use bytemuck::{Pod, Zeroable};
use wgpu::util::DeviceExt;

use crate::render::atmosphere::tables::AerialVolume;
use crate::render::frame::pass::{DrawItem, FrameContext, Pass, PassBuild, Phase, Pipelines, Placement, Target};
use crate::render::gpu::error::RenderResult;
use crate::render::gpu::shaders;

/// Vertex of the stand-in scene. Keep in sync with `vs_main` in shaders/scene.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
struct SceneVertex {
    position: [f32; 3],
    normal: [f32; 3],
    albedo: [f32; 3],
}

fn terrain_height(x: f32, z: f32) -> f32 {
    let r = (x * x + z * z).sqrt();
    // Flat where the viewer stands, rolling hills further out.
    let flat = ((r - 40.0) / 300.0).clamp(0.0, 1.0);
    let hills = (30.0 * (x / 190.0).sin() * (z / 240.0).cos() + 9.0 * (x / 55.0 + z / 80.0).sin()) * flat * flat - 0.5;
    hills + far_ridges(x, z, r)
}

/// Ridges beyond the hills: none within 3 km (the hills near the viewer are what they were),
/// rising to about a kilometre from 9 km out, so that aerial perspective shows on them.
fn far_ridges(x: f32, z: f32, r: f32) -> f32 {
    let t = ((r - 3000.0) / 6000.0).clamp(0.0, 1.0);
    let rise = t * t * (3.0 - 2.0 * t);
    if rise <= 0.0 {
        return 0.0;
    }
    let crest = 1.0 - (x / 2300.0 + 1.3 * (z / 5100.0).sin()).sin().abs();
    let ridge = 650.0 * crest * crest.sqrt() * (0.6 + 0.4 * (z / 3700.0 + x / 6100.0).sin());
    let swell = 260.0 * (0.5 + 0.5 * (x / 1700.0).sin() * (z / 1900.0).cos());
    rise * (ridge + swell)
}

/// Terrain cells along each side, and cells along each side of a chunk (the unit of culling).
const TERRAIN_CELLS: u32 = 144;
const CHUNK_CELLS: u32 = 12;
/// Cells across the fine middle of the terrain (52 m each over +-2.5 km); the rest widen towards
/// the edge at +-20 km.
const FINE_CELLS: u32 = 96;
const FINE_EXTENT_M: f32 = 2500.0;
/// Half the stand-in's width, m: 40 km across.
pub const TERRAIN_EXTENT_M: f32 = 20000.0;

/// Coordinate of grid line `i` of `TERRAIN_CELLS + 1` along either axis, m: uniform over the
/// fine middle, then widening as a power of the distance from it so that the first coarse cell is
/// about as wide as a fine one.
fn grid_line_m(i: u32) -> f32 {
    let coarse = (TERRAIN_CELLS - FINE_CELLS) / 2;
    let fine_cell = 2.0 * FINE_EXTENT_M / FINE_CELLS as f32;
    let k = i as i64 - coarse as i64;
    if (0..=FINE_CELLS as i64).contains(&k) {
        return -FINE_EXTENT_M + fine_cell * k as f32;
    }
    let (outward, sign) = if k < 0 { ((-k) as f32, -1.0) } else { ((k - FINE_CELLS as i64) as f32, 1.0) };
    let span = TERRAIN_EXTENT_M - FINE_EXTENT_M;
    // span (1 / coarse)^p = one fine cell.
    let p = (span / fine_cell).ln() / (coarse as f32).ln();
    sign * (FINE_EXTENT_M + span * (outward / coarse as f32).powf(p))
}

/// The stand-in's geometry: vertices, indices, and the chunks the indices are grouped in (index
/// range and world-space bounds), the buildings last.
fn scene_geometry() -> (Vec<SceneVertex>, Vec<u32>, Vec<Chunk>) {
    let (mut v, mut idx, mut chunks) = (Vec::new(), Vec::new(), Vec::new());
    const N: u32 = TERRAIN_CELLS;
    for j in 0..=N {
        for i in 0..=N {
            let (x, z) = (grid_line_m(i), grid_line_m(j));
            let e = 1.0;
            let n = glam::Vec3::new(terrain_height(x - e, z) - terrain_height(x + e, z), 2.0 * e, terrain_height(x, z - e) - terrain_height(x, z + e)).normalize();
            let shade = 0.8 + 0.2 * ((x * 0.013).sin() * (z * 0.011).cos());
            let y = terrain_height(x, z);
            // Grass gives way to bare rock up the ridges.
            let rock = ((y - 250.0) / 400.0).clamp(0.0, 1.0);
            let albedo = glam::Vec3::new(0.25, 0.32, 0.16).lerp(glam::Vec3::new(0.36, 0.33, 0.3), rock) * shade;
            v.push(SceneVertex { position: [x, y, z], normal: n.to_array(), albedo: albedo.to_array() });
        }
    }
    // Indices chunk by chunk, so a chunk is one index range; within a chunk the cells keep
    // their row-major order (and each its two triangles), as the frame draws them.
    for cj in 0..N / CHUNK_CELLS {
        for ci in 0..N / CHUNK_CELLS {
            let start = idx.len() as u32;
            let (mut lo, mut hi) = (glam::Vec3::splat(f32::INFINITY), glam::Vec3::splat(f32::NEG_INFINITY));
            for j in cj * CHUNK_CELLS..(cj + 1) * CHUNK_CELLS {
                for i in ci * CHUNK_CELLS..(ci + 1) * CHUNK_CELLS {
                    let a = j * (N + 1) + i;
                    let b = a + N + 1;
                    for k in [a, b, a + 1, a + 1, b, b + 1] {
                        idx.push(k);
                        let p = glam::Vec3::from(v[k as usize].position);
                        (lo, hi) = (lo.min(p), hi.max(p));
                    }
                }
            }
            chunks.push(Chunk { indices: start..idx.len() as u32, bounds: (lo, hi) });
        }
    }
    let (buildings_start, buildings_first_vertex) = (idx.len() as u32, v.len());
    // Buildings: (azimuth deg, distance m, width m, height m).
    for &(az, dist, w, h) in &[
        (150.0f32, 60.0f32, 14.0f32, 18.0f32),
        (200.0, 90.0, 20.0, 26.0),
        (95.0, 70.0, 12.0, 12.0),
        (265.0, 55.0, 16.0, 9.0),
        (20.0, 80.0, 22.0, 30.0),
        (320.0, 120.0, 18.0, 22.0),
    ] {
        let c = crate::sky::eval::direction(az, 0.0) * dist;
        let (x0, x1, z0, z1, y0, y1) = (c.x - w / 2.0, c.x + w / 2.0, c.z - w / 2.0, c.z + w / 2.0, -1.0, h);
        let albedo = [0.55, 0.5, 0.45];
        let faces: [([f32; 3], [[f32; 3]; 4]); 5] = [
            ([0.0, 0.0, 1.0], [[x0, y0, z1], [x1, y0, z1], [x1, y1, z1], [x0, y1, z1]]),
            ([0.0, 0.0, -1.0], [[x1, y0, z0], [x0, y0, z0], [x0, y1, z0], [x1, y1, z0]]),
            ([1.0, 0.0, 0.0], [[x1, y0, z1], [x1, y0, z0], [x1, y1, z0], [x1, y1, z1]]),
            ([-1.0, 0.0, 0.0], [[x0, y0, z0], [x0, y0, z1], [x0, y1, z1], [x0, y1, z0]]),
            ([0.0, 1.0, 0.0], [[x0, y1, z1], [x1, y1, z1], [x1, y1, z0], [x0, y1, z0]]),
        ];
        for (n, quad) in faces {
            let base = v.len() as u32;
            v.extend(quad.iter().map(|&p| SceneVertex { position: p, normal: n, albedo }));
            idx.extend_from_slice(&[base, base + 1, base + 2, base, base + 2, base + 3]);
        }
    }
    let (lo, hi) = v[buildings_first_vertex..].iter().fold((glam::Vec3::splat(f32::INFINITY), glam::Vec3::splat(f32::NEG_INFINITY)), |(lo, hi), x| {
        let p = glam::Vec3::from(x.position);
        (lo.min(p), hi.max(p))
    });
    chunks.push(Chunk { indices: buildings_start..idx.len() as u32, bounds: (lo, hi) });
    (v, idx, chunks)
}

/// A group of the stand-in's triangles drawn or culled together.
#[derive(Debug, Clone)]
struct Chunk {
    /// Its range in the index buffer.
    indices: std::ops::Range<u32>,
    /// World-space bounding box (min, max), metres.
    bounds: (glam::Vec3, glam::Vec3),
}

/// Whether a world-space box lies wholly outside one plane of the clip volume (wgpu's: depth 0
/// to w): then none of it can reach a pixel, so culling it changes nothing drawn.
fn outside_frustum(clip_from_world: &glam::Mat4, (lo, hi): (glam::Vec3, glam::Vec3)) -> bool {
    let corners: [glam::Vec4; 8] = std::array::from_fn(|k| {
        clip_from_world.mul_vec4(glam::Vec4::new(if k & 1 == 0 { lo.x } else { hi.x }, if k & 2 == 0 { lo.y } else { hi.y }, if k & 4 == 0 { lo.z } else { hi.z }, 1.0))
    });
    let planes: [fn(&glam::Vec4) -> bool; 6] = [|c| c.x < -c.w, |c| c.x > c.w, |c| c.y < -c.w, |c| c.y > c.w, |c| c.z < 0.0, |c| c.z > c.w];
    planes.iter().any(|outside| corners.iter().all(outside))
}

/// The scene's pipelines: terrain and buildings, and the test occluder.
struct ScenePipelines {
    scene: wgpu::RenderPipeline,
    occluder: wgpu::RenderPipeline,
}

/// Draw keys of the scene pass.
const TERRAIN: usize = 0;
const OCCLUDER: usize = 1;
const WALL: usize = 2;

/// Pipelines and geometry of the stand-in scene.
pub struct ScenePass {
    pipelines: Pipelines<ScenePipelines>,
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    chunks: Vec<Chunk>,
    /// This frame's index ranges: the chunks in view, neighbours merged.
    ranges: Vec<std::ops::Range<u32>>,
    occluder: wgpu::Buffer,
    /// The test wall's two triangles ([`crate::render::frame::options::TestWall`]).
    wall: wgpu::Buffer,
    /// Group 1: the aerial-perspective volume, and the atmosphere and LUT tables of the exact march.
    aerial: wgpu::BindGroup,
}

impl ScenePass {
    /// Builds pipelines and uploads the geometry.
    pub fn new(b: &PassBuild<'_>) -> RenderResult<Self> {
        let device = b.device;
        let atmosphere = &b.atmosphere;
        let vertex = wgpu::ShaderStages::VERTEX;
        let storage = |binding| wgpu::BindGroupLayoutEntry { visibility: vertex, ..crate::render::gpu::parts::storage_entry(binding, true) };
        let [a0, a1, a2, a3] = AerialVolume::layout_entries(0, vertex | wgpu::ShaderStages::FRAGMENT);
        let aerial_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("Scene::aerial_layout"),
            entries: &[a0, a1, a2, a3, crate::render::gpu::parts::uniform_entry(4, vertex), storage(5), storage(6), storage(7)],
        });
        let [v0, v1, v2, v3] = atmosphere.aerial.entries(0);
        let [l0, l1, l2] = atmosphere.luts.entries(5);
        let aerial = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("Scene::aerial"),
            layout: &aerial_layout,
            entries: &[v0, v1, v2, v3, wgpu::BindGroupEntry { binding: 4, resource: atmosphere.uniform.as_entire_binding() }, l0, l1, l2],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("Scene::pipeline_layout"),
            bind_group_layouts: &[Some(b.globals_layout), Some(&aerial_layout)],
            immediate_size: 0,
        });
        let pipelines = Pipelines::new_render(b, pipeline_layout, Self::build)?;
        let (v, i, chunks) = scene_geometry();
        let vertices =
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some("Scene::vertices"), contents: bytemuck::cast_slice(&v), usage: wgpu::BufferUsages::VERTEX });
        let indices =
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some("Scene::indices"), contents: bytemuck::cast_slice(&i), usage: wgpu::BufferUsages::INDEX });
        let occluder = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("Scene::occluder"),
            size: 6 * 8,
            usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let wall = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("Scene::wall"),
            size: 6 * std::mem::size_of::<SceneVertex>() as u64,
            usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Ok(Self { pipelines, vertices, indices, chunks, ranges: Vec::new(), occluder, wall, aerial })
    }

    fn build(b: &PassBuild<'_>, layout: &wgpu::PipelineLayout) -> RenderResult<ScenePipelines> {
        let (device, format) = (b.device, b.color_format);
        let module = shaders::module(device, b.library, "scene")?;
        let constants = b.target_constants();
        let options = wgpu::PipelineCompilationOptions { constants: &constants, zero_initialize_workgroup_memory: true };
        let depth = crate::render::gpu::parts::depth_state(true, wgpu::CompareFunction::Less);
        let make = |label: &'static str, vs: &'static str, fs: &'static str, buffer: wgpu::VertexBufferLayout<'_>| {
            shaders::validated(device, label, || {
                device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some(label),
                    layout: Some(layout),
                    vertex: wgpu::VertexState { module: &module, entry_point: Some(vs), buffers: &[Some(buffer)], compilation_options: options.clone() },
                    primitive: wgpu::PrimitiveState { cull_mode: None, ..Default::default() },
                    depth_stencil: depth.clone(),
                    multisample: Default::default(),
                    fragment: Some(wgpu::FragmentState {
                        module: &module,
                        entry_point: Some(fs),
                        targets: &[Some(wgpu::ColorTargetState { format, blend: None, write_mask: wgpu::ColorWrites::ALL })],
                        compilation_options: options.clone(),
                    }),
                    multiview_mask: None,
                    cache: None,
                })
            })
        };
        let scene = make(
            "Scene::pipeline",
            "vs_main",
            "fs_main",
            wgpu::VertexBufferLayout {
                array_stride: std::mem::size_of::<SceneVertex>() as u64,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x3],
            },
        )?;
        let occluder = make(
            "Scene::occluder_pipeline",
            "vs_occluder",
            "fs_occluder",
            wgpu::VertexBufferLayout { array_stride: 8, step_mode: wgpu::VertexStepMode::Vertex, attributes: &wgpu::vertex_attr_array![0 => Float32x2] },
        )?;
        Ok(ScenePipelines { scene, occluder })
    }
}

impl Pass for ScenePass {
    fn name(&self) -> &'static str {
        "scene"
    }

    fn phase(&self) -> Phase {
        Phase::Scene
    }

    fn stage_pipelines(&mut self, b: &PassBuild<'_>) -> RenderResult<()> {
        self.pipelines.stage(b)
    }

    fn commit_pipelines(&mut self, accept: bool) {
        self.pipelines.commit(accept);
    }

    fn prepare(&mut self, cx: &FrameContext<'_>) {
        // Chunks wholly out of view are not submitted: on a software rasteriser every triangle
        // costs its vertex shading, clipping and setup even when it reaches no pixel.
        let (clip_from_world, _) = cx.camera.matrices(cx.aspect());
        self.ranges.clear();
        let cull = cx.options.skips.off_screen;
        for c in self.chunks.iter().filter(|c| !(cull && outside_frustum(&clip_from_world, c.bounds))) {
            match self.ranges.last_mut() {
                Some(r) if r.end == c.indices.start => r.end = c.indices.end,
                _ => self.ranges.push(c.indices.clone()),
            }
        }
        if let Some(o) = &cx.options.occluder {
            let ([x0, y0], [x1, y1]) = (o.min, o.max);
            let quad: [[f32; 2]; 6] = [[x0, y0], [x1, y0], [x1, y1], [x0, y0], [x1, y1], [x0, y1]];
            cx.queue.write_buffer(&self.occluder, 0, bytemuck::cast_slice(&quad));
        }
        if let Some(w) = &cx.options.wall {
            let centre = glam::Vec3::from(w.centre_m);
            let normal = (cx.camera.position() - centre).normalize_or(glam::Vec3::Z);
            let right = normal.cross(glam::Vec3::Y).normalize_or(glam::Vec3::X) * w.half_size_m;
            let up = right.cross(normal).normalize() * w.half_size_m;
            let corner = |a: f32, b: f32| SceneVertex { position: (centre + right * a + up * b).to_array(), normal: normal.to_array(), albedo: w.albedo };
            let quad = [corner(-1.0, -1.0), corner(1.0, -1.0), corner(1.0, 1.0), corner(-1.0, -1.0), corner(1.0, 1.0), corner(-1.0, 1.0)];
            cx.queue.write_buffer(&self.wall, 0, bytemuck::cast_slice(&quad));
        }
    }

    fn items(&self, cx: &FrameContext<'_>, out: &mut Vec<DrawItem>) {
        if cx.options.scene {
            out.push(DrawItem::new(0, TERRAIN));
        }
        if cx.options.occluder.is_some() {
            out.push(DrawItem::new(0, OCCLUDER));
        }
        if cx.options.wall.is_some() {
            out.push(DrawItem::new(0, WALL));
        }
    }

    fn draw(&self, rpass: &mut wgpu::RenderPass<'_>, key: usize, target: Target, _placement: Placement, _run: Option<&wgpu::BindGroup>) -> u32 {
        let p = self.pipelines.for_target(target);
        rpass.set_bind_group(1, &self.aerial, &[]);
        if key == TERRAIN {
            rpass.set_pipeline(&p.scene);
            rpass.set_vertex_buffer(0, self.vertices.slice(..));
            rpass.set_index_buffer(self.indices.slice(..), wgpu::IndexFormat::Uint32);
            for r in &self.ranges {
                rpass.draw_indexed(r.clone(), 0, 0..1);
            }
            return self.ranges.len() as u32;
        } else if key == WALL {
            rpass.set_pipeline(&p.scene);
            rpass.set_vertex_buffer(0, self.wall.slice(..));
            rpass.draw(0..6, 0..1);
        } else {
            rpass.set_pipeline(&p.occluder);
            rpass.set_vertex_buffer(0, self.occluder.slice(..));
            rpass.draw(0..6, 0..1);
        }
        1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_grid_is_fine_in_the_middle_and_widens_to_the_edge() {
        let lines: Vec<f32> = (0..=TERRAIN_CELLS).map(grid_line_m).collect();
        assert_eq!((lines[0], lines[TERRAIN_CELLS as usize]), (-TERRAIN_EXTENT_M, TERRAIN_EXTENT_M));
        let widths: Vec<f32> = lines.windows(2).map(|w| w[1] - w[0]).collect();
        let fine = 2.0 * FINE_EXTENT_M / FINE_CELLS as f32;
        let coarse = ((TERRAIN_CELLS - FINE_CELLS) / 2) as usize;
        for (k, w) in widths.iter().enumerate() {
            if (coarse..coarse + FINE_CELLS as usize).contains(&k) {
                assert!((w - fine).abs() < 1e-2, "fine cell {k}: {w} m");
            } else {
                // Widening away from the middle, the first coarse cell about a fine one.
                let outward = if k < coarse { coarse - 1 - k } else { k - coarse - FINE_CELLS as usize };
                assert!(*w >= fine * 0.99 && (outward == 0 || *w > widths[if k < coarse { k + 1 } else { k - 1 }]), "cell {k}: {w} m");
                assert!(outward > 0 || (w - fine).abs() < 0.01 * fine, "first coarse cell {k}: {w} m");
            }
        }
        // Ridges far out, none near the viewer.
        assert_eq!(far_ridges(1000.0, 1500.0, 1802.8), 0.0);
        let peak = (0..200).map(|k| terrain_height(15000.0 * (k as f32 * 0.1).cos(), 15000.0 * (k as f32 * 0.1).sin())).fold(0.0, f32::max);
        assert!(peak > 500.0, "ridges at 15 km reach {peak} m");
    }

    #[test]
    fn chunks_cover_the_stand_in_and_bound_their_triangles() {
        let (v, idx, chunks) = scene_geometry();
        let mut next = 0;
        for c in &chunks {
            assert_eq!(c.indices.start, next, "chunks follow each other");
            next = c.indices.end;
            for &k in &idx[c.indices.start as usize..c.indices.end as usize] {
                let p = glam::Vec3::from(v[k as usize].position);
                assert!(p.cmpge(c.bounds.0).all() && p.cmple(c.bounds.1).all(), "{p} outside {:?}", c.bounds);
            }
        }
        assert_eq!(next as usize, idx.len(), "every triangle is in a chunk");
        // At the horizon, the terrain behind the viewer is left out; the buildings (all round the
        // viewer, some in view) are kept.
        let (clip_from_world, _) = crate::render::frame::camera::Camera::default().matrices(16.0 / 9.0);
        let culled = chunks.iter().filter(|c| outside_frustum(&clip_from_world, c.bounds)).count();
        assert!(culled > chunks.len() / 3, "{culled} of {} chunks left out", chunks.len());
        assert!(!outside_frustum(&clip_from_world, chunks[chunks.len() - 1].bounds));
    }
}
