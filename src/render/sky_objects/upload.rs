//! A sky's per-object GPU resources: meshes, uniforms, bind groups, texel meshes, uploaded
//! once per sky and reused across reloads where nothing changed.

#[allow(unused_imports)]
use super::*;

/// GPU resources of one version (standard or fallback version) of an object.
pub(super) struct VersionDraw {
    pub(super) uniform: wgpu::Buffer,
    /// By the stages sampled from level 0 alone (bit k: stage k, within `level0_able`).
    pub(super) bind_groups: Vec<wgpu::BindGroup>,
    /// Stages that have a level-0 variant: those with a texture of their own.
    pub(super) level0_able: u8,
    /// How each stage's texture lies on the sky (None: no stage or no texture).
    pub(super) maps: [Option<StageMap>; MAX_STAGES],
    pub(super) mesh: Arc<GpuMesh>,
    /// The mesh is the dome's outline ([`outline_mesh`]), one band of triangles, not its grid.
    pub(super) outline: bool,
    pub(super) gradient: Option<(wgpu::Texture, u32)>,
    /// The stage the gradient feeds (and a physical sky model replaces).
    pub(super) gradient_stage: Option<usize>,
    pub(super) blend: BlendMode,
    pub(super) shape: Shape,
    pub(super) base: DrawUniform,
    /// Its pipeline signature's part that the sky's data fixes.
    pub(super) signature: MaterialSignature,
    /// Finest detail of each stage's texture on the sky, texels per degree (0: no stage).
    pub(super) texels_per_deg: [f32; 4],
    /// How much finer each stage's texels are than the detail they carry
    /// ([`texture_oversampling`]; 1 for a folded texture and without a texture).
    pub(super) oversampling: [f32; 4],
    /// A sparse stage's texels as polygons on the grid ([`crate::render::sky_objects::texel_quads`]): the stage and
    /// its polygons.
    pub(super) texels: Option<(usize, Arc<GpuTexelMesh>)>,
    /// The signature's UV modes with its cloud-layer stages computed per vertex, where the draw
    /// is on its grid and the strategy says so ([`vertex_layer_modes`]); None without such stages.
    pub(super) vertex_modes: Option<[u32; MAX_STAGES]>,
}

impl VersionDraw {
    /// [`Self::texels_per_deg`] where a frame shows elevations `shown_deg` (lowest, highest):
    /// [`texels_per_deg_shown`] over its dome's grid, the stage drawn texel by texel kept.
    pub(super) fn texels_per_deg_shown(&self, shown_deg: (f32, f32)) -> [f32; MAX_STAGES] {
        let Some(grid) = crate::render::gpu::mesh::dome_grid(&self.shape).map(DomeGrid::from_tuple) else { return self.texels_per_deg };
        let keep = self.texels.as_ref().map(|(k, _)| *k);
        texels_per_deg_shown(&self.maps, (self.texels_per_deg, self.oversampling), keep, grid, shown_deg)
    }

    /// [`Self::vertex_modes`] where the frame's strategy computes layer coordinates per vertex
    /// (`per_vertex`), else None.
    pub(super) fn vertex_modes_for(&self, per_vertex: bool) -> Option<[u32; MAX_STAGES]> {
        self.vertex_modes.filter(|_| per_vertex)
    }
}

/// The UV modes of `sig` with the stages of `v` under the first cloud layer it maps (the same
/// layer: one distance per vertex moves the grid onto it) computed per vertex: `UV_LAYER_VERTEX`.
/// None on the dome's outline (its triangles span the whole dome: nothing to interpolate from) or
/// without a layer stage.
pub(super) fn vertex_layer_modes(v: &Version, sig: &MaterialSignature, on_outline: bool) -> Option<[u32; MAX_STAGES]> {
    if on_outline || crate::render::gpu::mesh::dome_grid(&v.shape).is_none() {
        return None;
    }
    let first = (0..v.stages.len().min(MAX_STAGES)).find(|&k| sig.modes[k] == UV_LAYER)?;
    let layer = v.stages[first].uv;
    Some(std::array::from_fn(|k| if sig.modes[k] == UV_LAYER && v.stages.get(k).is_some_and(|s| s.uv == layer) { UV_LAYER_VERTEX } else { sig.modes[k] }))
}

/// A dome's grid moved onto cloud layer `p` for coordinates computed per vertex: each vertex
/// along its ray to the layer, its texture coordinates the layer's there (the stage's scale not
/// applied). The shader moves the grid the same way (`sky_vertex` in shaders/sky_objects/draw.wgsl).
fn grid_on_layer(grid: &MeshData, p: &LayerParams) -> MeshData {
    let vertices = grid
        .vertices
        .iter()
        .map(|v| {
            let d = glam::DVec3::from(v.position.map(f64::from)).normalize_or_zero();
            let t = p.distance(d.to_array());
            let at = d * t;
            SkyVertex { position: at.as_vec3().to_array(), uv: [at.x as f32, at.z as f32] }
        })
        .collect();
    MeshData { vertices, indices: grid.indices.clone() }
}

/// Per-sky GPU resources: one [`VersionDraw`] per version of every object.
pub struct SkyObjectDraws {
    /// objects[i][v]: object i (in draw order), version v (0 standard, 1.. fallback).
    pub(super) objects: Vec<Vec<VersionDraw>>,
    /// Geometry by shape; a reload takes over the meshes of shapes that are still used.
    pub(super) meshes: HashMap<String, Arc<GpuMesh>>,
    /// Texel polygons by (texture key, content, shape); taken over like the meshes. `None`: the
    /// texture is not sparse.
    pub(super) texel_meshes: HashMap<(String, u64, String), Option<Arc<GpuTexelMesh>>>,
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
        let mut up = Uploader {
            device,
            queue,
            layout,
            sky_view,
            cache,
            previous,
            meshes: HashMap::new(),
            baked: HashMap::new(),
            texel_meshes: HashMap::new(),
            oversampling: HashMap::new(),
        };
        let mut objects = Vec::with_capacity(sky.objects.len());
        for o in &sky.objects {
            let versions = std::iter::once(&o.standard).chain(&o.fallback).enumerate();
            objects.push(versions.map(|(vi, v)| up.version(&format!("SkyObjects::{}[{vi}]", o.name), v)).collect());
        }
        Self { objects, meshes: up.meshes, texel_meshes: up.texel_meshes }
    }

    /// Writes this frame's uniforms and gradients and records each drawn version's pipeline
    /// signature in `keys` (by object index and version) for `(target, neutral tone mapper)`;
    /// returns the texture stages skipped because their term is black this frame.
    pub(super) fn prepare(
        &self,
        queue: &wgpu::Queue,
        frame: &FrameSky,
        camera: &Camera,
        skip_dark: bool,
        shading: FrameShading,
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
                let live = if skip_dark {
                    let (n, live) = u.skip_dark_stages(d.blend != BlendMode::Opaque);
                    skipped += n;
                    live
                } else {
                    std::array::from_fn(|k| k < d.signature.count as usize)
                };
                queue.write_buffer(&d.uniform, 0, bytemuck::bytes_of(&u));
                let key = VariantKey::of(&d.signature, (live, sky_view_stage), d.blend, shading);
                // The signature from the sky's data is what the shader's generic path reads.
                debug_assert_eq!(
                    (key.count, key.modes, key.ops, key.constants, key.live, key.view_stage, key.lighting),
                    (u.misc[0], u.stages.map(|s| s.cfg[1]), u.stages.map(|s| s.cfg[0]), u.stages.map(|s| s.cfg[2]), u.stages.map(|s| s.cfg[3] != 0), u.misc[2], u.misc[1])
                );
                keys.insert((of.index, p.version), key);
                if let (Some((tex, h)), Some(g)) = (&d.gradient, &p.gradient) {
                    let bytes: Vec<u8> = g.iter().flat_map(|c| c.map(|x| (x.clamp(0.0, 1.0) * 255.0).round() as u8)).collect();
                    textures::write(queue, tex, 1, *h, &bytes);
                }
            }
        }
        skipped
    }
}

/// One sky's upload: what its versions share (meshes, baked folds, texel polygons, texture
/// oversampling), each taken over from the previous sky's resources where unchanged.
struct Uploader<'a> {
    device: &'a wgpu::Device,
    queue: &'a wgpu::Queue,
    layout: &'a wgpu::BindGroupLayout,
    sky_view: &'a (wgpu::TextureView, wgpu::Sampler),
    cache: &'a mut TextureCache,
    previous: Option<&'a SkyObjectDraws>,
    meshes: HashMap<String, Arc<GpuMesh>>,
    /// Folded textures baked in this load, by key: the texture and its texel polygons share one.
    baked: HashMap<String, Arc<TextureImage>>,
    texel_meshes: HashMap<(String, u64, String), Option<Arc<GpuTexelMesh>>>,
    oversampling: HashMap<String, f32>,
}

impl Uploader<'_> {
    /// The resources of version `v`, labelled `label`.
    fn version(&mut self, label: &str, v: &Version) -> VersionDraw {
        // Where no stage takes its coordinates from the mesh, a dome's triangles
        // only bound it: its outline does that with one band of them.
        let outline = v.stages.iter().all(|s| !matches!(s.uv, UvSource::Mesh)).then(|| outline_mesh(&v.shape)).flatten();
        let key = if outline.is_some() { format!("outline of {}", shape_key(&v.shape)) } else { shape_key(&v.shape) };
        let is_outline = outline.is_some();
        let mesh = self
            .meshes
            .entry(key.clone())
            .or_insert_with(|| match self.previous.and_then(|p| p.meshes.get(&key)) {
                Some(m) => m.clone(),
                None => Arc::new(GpuMesh::new(self.device, &format!("SkyObjects::mesh {key}"), &outline.unwrap_or_else(|| shape_mesh(&v.shape)))),
            })
            .clone();
        let gradient = v.gradients.as_ref().map(|g| {
            let h = g.bitmaps[0].height;
            (textures::upload(self.device, self.queue, &format!("{label}::gradient"), 1, h, &vec![255; (h * 4) as usize]), h)
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
                _ if folded_away(k) => self.cache.white.clone(),
                (Some(f), _, _) => {
                    let (key, content) = stage_fold::identity(v, f);
                    self.cache.derived(self.device, self.queue, &key, content, || {
                        self.baked.entry(key.clone()).or_insert_with(|| Arc::new(stage_fold::bake(v, f, &key))).as_ref().clone()
                    })
                }
                (None, Some(img), _) => self.cache.get(self.device, self.queue, img),
                (None, None, Some(gv)) if v.gradients.as_ref().is_some_and(|g| g.stage == k) => gv.clone(),
                _ => self.cache.white.clone(),
            };
            views.push(view);
            let clamp = fold_at(k).map_or(stage.is_some_and(|s| s.clamp), |f| f.clamp);
            samplers.push(if clamp { self.cache.clamp.clone() } else { self.cache.repeat.clone() });
            level0_samplers.push(if clamp { self.cache.clamp_level0.clone() } else { self.cache.repeat_level0.clone() });
        }
        let uniform = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(&format!("{label}::uniform")),
            size: std::mem::size_of::<DrawUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let maps: [Option<StageMap>; MAX_STAGES] = std::array::from_fn(|k| match fold_at(k) {
            _ if folded_away(k) => None,
            Some(f) => {
                let scale = f.uv_scale();
                Some(StageMap::with_texels(v.stages[f.stage].uv, (f.size.0 as f32 * scale[0], f.size.1 as f32 * scale[1]), &v.shape))
            }
            None => v.stages.get(k).and_then(|s| StageMap::of(s, &v.shape)),
        });
        let level0_able = (0..MAX_STAGES).filter(|&k| maps[k].is_some()).fold(0u8, |m, k| m | 1 << k);
        // One bind group per subset of those stages, indexed by the subset's mask (a
        // mask that is no subset is never indexed, and gets its subset's), so that
        // a frame only picks one.
        let bind_groups = self.bind_groups(label, &uniform, (&views, &samplers, &level0_samplers), level0_able);
        let gradient_stage = v.gradients.as_ref().map(|g| g.stage);
        let mut texels_per_deg = [0.0; 4];
        let mut oversampling = [1.0; 4];
        for (k, s) in v.stages.iter().enumerate().take(MAX_STAGES) {
            oversampling[k] = s.texture.as_ref().map_or(1.0, |t| *self.oversampling.entry(t.key.clone()).or_insert_with(|| texture_oversampling(t)));
            texels_per_deg[k] = stage_texels_per_deg(s, &v.shape) / oversampling[k];
        }
        let signature = MaterialSignature::of(v, &folds.iter().map(|f| f.stage).collect::<Vec<_>>());
        let mut base = DrawUniform::from(v).with_signature(&signature);
        for f in &folds {
            let (first, second) = (f.stage, f.stage + 1);
            // A folded texture carries the finer detail of its two stages.
            texels_per_deg[first] = texels_per_deg[first].max(texels_per_deg[second]);
            texels_per_deg[second] = 0.0;
            (oversampling[first], oversampling[second]) = (1.0, 1.0);
            let scale = f.uv_scale();
            base.stages[first].scale_offset = [scale[0], scale[1], 0.0, 0.0];
        }
        let vertex_modes = vertex_layer_modes(v, &signature, is_outline);
        let texels = self.sparse_stage(label, v, (&folds, gradient_stage), vertex_modes);
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
            signature,
            texels_per_deg,
            oversampling,
            texels,
            vertex_modes,
        }
    }

    /// The bind groups of a version with `level0_able` stages: one per subset of those stages,
    /// by the subset's mask, with the stages' views and samplers (level-0 or mipmapped).
    fn bind_groups(
        &self,
        label: &str,
        uniform: &wgpu::Buffer,
        (views, samplers, level0_samplers): (&[wgpu::TextureView], &[wgpu::Sampler], &[wgpu::Sampler]),
        level0_able: u8,
    ) -> Vec<wgpu::BindGroup> {
        (0..=level0_able)
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
                entries.push(wgpu::BindGroupEntry { binding: 9, resource: wgpu::BindingResource::TextureView(&self.sky_view.0) });
                entries.push(wgpu::BindGroupEntry { binding: 10, resource: wgpu::BindingResource::Sampler(&self.sky_view.1) });
                self.device.create_bind_group(&wgpu::BindGroupDescriptor { label: Some(&format!("{label}::bind_group[{mask:04b}]")), layout: self.layout, entries: &entries })
            })
            .collect()
    }

    /// A sparse stage under the dome's mesh mapping or a cloud layer's computed per vertex
    /// (`vertex_modes`), static (the folded one, or one of its own that repeats), and its texel
    /// polygons: on the grid's triangles, or on the grid moved onto the layer.
    fn sparse_stage(
        &mut self,
        label: &str,
        v: &Version,
        (folds, gradient_stage): (&[stage_fold::Fold], Option<usize>),
        vertex_modes: Option<[u32; MAX_STAGES]>,
    ) -> Option<(usize, Arc<GpuTexelMesh>)> {
        let fold_at = |k: usize| folds.iter().find(|f| f.stage == k);
        let folded_away = |k: usize| k > 0 && fold_at(k - 1).is_some();
        let on_layer = |k: usize| vertex_modes.is_some_and(|m| m[k] == UV_LAYER_VERTEX);
        // On the dome's outline no stage is mesh-mapped and none per vertex: nothing matches.
        match crate::render::gpu::mesh::dome_grid(&v.shape) {
            Some((_, _, rings, _)) => (0..v.stages.len().min(MAX_STAGES)).find_map(|k| {
                let s = &v.stages[k];
                let mapped = matches!(s.uv, UvSource::Mesh) || on_layer(k);
                let fixed = mapped && s.panner == [0.0, 0.0] && s.uv_offset.is_none() && !folded_away(k) && gradient_stage != Some(k);
                if !fixed {
                    return None;
                }
                let (key, content, scale): (String, u64, [f32; 2]) = match (fold_at(k), s.texture.as_deref()) {
                    (Some(f), _) if !f.clamp => {
                        let (key, content) = stage_fold::identity(v, f);
                        (key, content, f.uv_scale())
                    }
                    (None, Some(t)) if !s.clamp => (t.key.clone(), textures::content_hash(t), s.uv_scale),
                    _ => return None,
                };
                let layer = on_layer(k).then(|| layer_params(s.uv)).flatten();
                let id = (key, content, format!("{} x {scale:?} on {:?}", shape_key(&v.shape), layer.is_some().then_some(s.uv)));
                let mesh = self
                    .texel_meshes
                    .entry(id.clone())
                    .or_insert_with(|| match self.previous.and_then(|p| p.texel_meshes.get(&id)) {
                        Some(m) => m.clone(),
                        None => {
                            let image = match (fold_at(k), &s.texture) {
                                (Some(f), _) => self.baked.entry(id.0.clone()).or_insert_with(|| Arc::new(stage_fold::bake(v, f, &id.0))).clone(),
                                (None, Some(t)) => t.clone(),
                                (None, None) => return None,
                            };
                            let source = TexelSource { size: (image.width, image.height), rgba8: &image.rgba8, scale };
                            let grid = match &layer {
                                Some(p) => grid_on_layer(&shape_mesh(&v.shape), p),
                                None => shape_mesh(&v.shape),
                            };
                            source.sparse().then(|| GpuTexelMesh::new(self.device, label, &texel_quads::build(&grid, rings, &source))).flatten().map(Arc::new)
                        }
                    })
                    .clone();
                mesh.map(|m| (k, m))
            }),
            None => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::gpu::mesh::dome_grid;
    use crate::sky::builtin::default_sky;
    use crate::sky::model::Elevation;

    /// The layer coordinates the rasteriser interpolates over the grid moved onto the layer, at a
    /// direction inside a grid triangle: the point of the chord triangle on the view ray.
    fn on_chord(p: [glam::DVec3; 3], dir: glam::DVec3) -> glam::DVec2 {
        let n = (p[1] - p[0]).cross(p[2] - p[0]);
        let q = dir * (n.dot(p[0]) / n.dot(dir));
        glam::DVec2::new(q.x, q.z)
    }

    /// The largest distance per ring of `shape`'s grid, in texels (`texels` a repeat), between the
    /// coordinates interpolated over the grid moved onto layer `p` and the layer's own.
    fn worst_per_ring(p: &LayerParams, shape: &Shape, texels: f64) -> Vec<f64> {
        let grid = grid_on_layer(&shape_mesh(shape), p);
        let (_, _, rings, segments) = dome_grid(shape).expect("a dome");
        let mut worst = vec![0.0f64; rings as usize];
        let mut rng = fastrand::Rng::with_seed(9);
        for (k, t) in grid.indices.chunks_exact(3).enumerate() {
            let q = [t[0], t[1], t[2]].map(|i| glam::DVec3::from(grid.vertices[i as usize].position.map(f64::from)));
            if (q[1] - q[0]).cross(q[2] - q[0]).length_squared() < 1e-12 {
                continue;
            }
            let ring = k / 2 / segments as usize;
            for _ in 0..40 {
                let (a, b) = (rng.f64(), rng.f64());
                let (a, b) = if a + b > 1.0 { (1.0 - a, 1.0 - b) } else { (a, b) };
                let dir = (q[0] * (1.0 - a - b) + q[1] * a + q[2] * b).normalize();
                let exact = glam::DVec2::from(p.uv(dir.to_array()));
                worst[ring] = worst[ring].max((on_chord(q, dir) - exact).length() * texels);
            }
        }
        worst
    }

    #[test]
    fn coordinates_per_vertex_stay_within_a_few_texels_of_the_layer() {
        // The built-in stars' layer (1 km up round a 1 km planet: nearly a sphere round the eye)
        // on the skydome's grid, in the stars' texels (128 a repeat): the chords sag most near the
        // horizon, across the grid's 11.25-degree segments. Measured: 0.01 texels in the top
        // ring, 0.2 by 56 degrees, 0.9 by 28, 3.1 in the bottom ring (-13 to -20 degrees).
        let sky = default_sky();
        let v = &sky.objects.iter().find(|o| o.name == "skydome").expect("a skydome").standard;
        let p = layer_params(v.stages[1].uv).expect("the stars on a layer");
        let worst = worst_per_ring(&p, &v.shape, 128.0 * f64::from(v.stages[1].uv_scale[0]));
        assert!(worst[0] < 0.05 && worst[4] < 0.3, "near the zenith: {worst:?}");
        assert!(worst.iter().all(|&w| w < 3.3), "{worst:?}");
        assert!(worst[worst.len() - 1] > 2.5, "the bound is reached at the bottom: {worst:?}");
        // A flat cloud layer (2 km up round the Earth, 10 km repeats of 256 texels) down to 5
        // degrees: the chords lie almost on it. Measured: 0.61 texels in the bottom ring, where
        // the layer's coordinates interpolated over the unit dome's chords instead are 52 off.
        let clouds = LayerParams { height: 0.2, radius: 636.0, fade_sin: 0.0 };
        let worst = worst_per_ring(&clouds, &Shape::Dome { bottom_deg: Elevation(5.0) }, 256.0);
        assert!(worst.iter().all(|&w| w < 0.8), "{worst:?}");
    }
}
