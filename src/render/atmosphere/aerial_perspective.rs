//! Aerial-perspective pass (compute phase): builds the froxel volume of the frame's camera (screen
//! cells across and down, depth slices out to a distance; Hillaire 2020) from the frame's
//! atmosphere and the shared LUT tables, into [`crate::render::atmosphere::AtmosphereGpu::aerial`],
//! which the scene reads with each vertex's distance. Rebuilt only when the camera, the sun, the
//! atmosphere or the settings move; idle when the scene keeps its fog (the NeL bitmaps, a model
//! that does not light the scene, Braun and Cohen's display-referred colour).

use crate::atmosphere::aerial::AerialMethod;
use crate::render::atmosphere::tables::{AerialVolume, LutTables, AERIAL_FORMAT};
use crate::render::atmosphere::uniforms::{AerialUniform, AerialUse, AtmosphereUniform, LutUniform};
use crate::render::frame::pass::{DrawItem, FrameContext, Pass, PassBuild, Phase, Staged};
use crate::render::gpu::error::RenderResult;
use crate::render::gpu::parts::{storage_entry, uniform_entry};
use crate::sky::resolved::{SkyModel, SkyModelKind};

/// What a frame under `model` gives the scene of the atmosphere in front of it: the model's
/// aerial perspective when the model lights the scene, with the multiple-scattering orders
/// unless the model leaves them out (`single`); none for the bitmaps, for Braun and Cohen, whose
/// one colour is not a radiance, and where the sky file asks for fog.
pub fn aerial_use(model: &SkyModel) -> AerialUse {
    if !model.kind.is_physical() || !model.drive_scene || model.kind == SkyModelKind::Linear || model.aerial.method == AerialMethod::Fog {
        return AerialUse::None;
    }
    AerialUse::Model { multiple: model.kind != SkyModelKind::Single }
}

/// The volume's builder (shaders/aerial_perspective.wgsl), for the pass and the radiance probe.
pub struct AerialBuilder {
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
}

impl AerialBuilder {
    /// Builds the pipeline with `group0` as bind group 0 (the frame's globals, or an empty layout).
    pub fn new(device: &wgpu::Device, library: &crate::render::gpu::shaders::ShaderLibrary, group0: &wgpu::BindGroupLayout) -> RenderResult<Self> {
        let storage_texture = |binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::StorageTexture { access: wgpu::StorageTextureAccess::WriteOnly, format: AERIAL_FORMAT, view_dimension: wgpu::TextureViewDimension::D3 },
            count: None,
        };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("AerialPerspective::layout"),
            entries: &[
                uniform_entry(0, wgpu::ShaderStages::COMPUTE),
                uniform_entry(1, wgpu::ShaderStages::COMPUTE),
                storage_entry(2, true),
                storage_entry(3, true),
                storage_entry(4, true),
                storage_texture(5),
                storage_texture(6),
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("AerialPerspective::pipeline_layout"),
            bind_group_layouts: &[Some(group0), Some(&layout)],
            immediate_size: 0,
        });
        let module = crate::render::gpu::shaders::module(device, library, "aerial_perspective")?;
        let pipeline = crate::render::gpu::shaders::compute_pipeline(device, &pipeline_layout, &module, "cs_main", "AerialPerspective::pipeline")?;
        Ok(Self { layout, pipeline })
    }

    /// A bind group over the atmosphere uniform, the LUT tables and the volume (whose params
    /// buffer says which volume to build).
    pub fn bind_group(&self, device: &wgpu::Device, atmosphere: &wgpu::Buffer, luts: &LutTables, volume: &AerialVolume) -> wgpu::BindGroup {
        let [p, t, m] = luts.entries(2);
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("AerialPerspective::bind_group"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: atmosphere.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: volume.params.as_entire_binding() },
                p,
                t,
                m,
                wgpu::BindGroupEntry { binding: 5, resource: wgpu::BindingResource::TextureView(&volume.in_scatter_view) },
                wgpu::BindGroupEntry { binding: 6, resource: wgpu::BindingResource::TextureView(&volume.transmittance_view) },
            ],
        })
    }

    /// Records the build of a volume of `size` cells across and down into `cpass`, whose bind
    /// group 0 is set.
    pub fn dispatch(&self, cpass: &mut wgpu::ComputePass<'_>, bind_group: &wgpu::BindGroup, size: [u32; 3]) {
        cpass.set_bind_group(1, bind_group, &[]);
        cpass.set_pipeline(&self.pipeline);
        cpass.dispatch_workgroups(size[0].div_ceil(8), size[1].div_ceil(8), 1);
    }
}

/// The aerial-perspective pass.
pub struct AerialPerspectivePass {
    builder: Staged<AerialBuilder>,
    bind_group: wgpu::BindGroup,
    params: wgpu::Buffer,
    /// What the params buffer holds, and what the volume was built from.
    written: Option<AerialUniform>,
    built: Option<(AerialUniform, AtmosphereUniform, LutUniform)>,
    size: [u32; 3],
    dirty: bool,
    /// Volume builds so far (stats and tests).
    pub builds: u64,
}

impl AerialPerspectivePass {
    /// Builds the pipeline and binds the shared tables and volume.
    pub fn new(b: &PassBuild<'_>) -> RenderResult<Self> {
        let builder = AerialBuilder::new(b.device, b.library, b.globals_layout)?;
        let bind_group = builder.bind_group(b.device, &b.atmosphere.uniform, &b.atmosphere.luts, &b.atmosphere.aerial);
        let params = b.atmosphere.aerial.params.clone();
        Ok(Self { builder: Staged::new(builder), bind_group, params, written: None, built: None, size: [0; 3], dirty: false, builds: 0 })
    }
}

impl Pass for AerialPerspectivePass {
    fn name(&self) -> &'static str {
        "aerial_perspective"
    }

    fn phase(&self) -> Phase {
        Phase::Compute
    }

    fn stage_pipelines(&mut self, b: &PassBuild<'_>) -> RenderResult<()> {
        let next = AerialBuilder::new(b.device, b.library, b.globals_layout)?;
        self.builder.stage(next);
        Ok(())
    }

    fn commit_pipelines(&mut self, accept: bool) {
        if self.builder.pending().is_some() && accept {
            self.built = None;
        }
        self.builder.commit(accept);
    }

    fn prepare(&mut self, cx: &FrameContext<'_>) {
        self.dirty = false;
        let model = &cx.frame.sky_model;
        let using = aerial_use(model);
        let (clip_from_world, _) = cx.camera.matrices(cx.aspect());
        let params = AerialUniform::new(&model.aerial, using, clip_from_world.inverse(), cx.camera.position(), model.world.camera_km, cx.frame.towards_sun);
        if self.written != Some(params) {
            cx.queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
            self.written = Some(params);
        }
        if using == AerialUse::None || model.aerial.method != AerialMethod::Volume {
            return;
        }
        let key = (params, AtmosphereUniform::from(&cx.frame.atmosphere), LutUniform::new(&model.settings.lut, model.world.ground_albedo, cx.frame.atmosphere.mie_g));
        if self.built == Some(key) && cx.options.skips.unchanged_tables {
            return;
        }
        self.built = Some(key);
        self.size = model.aerial.volume_size;
        self.dirty = true;
        self.builds += 1;
    }

    fn items(&self, _cx: &FrameContext<'_>, out: &mut Vec<DrawItem>) {
        if self.dirty {
            out.push(DrawItem::new(0, 0));
        }
    }

    fn dispatch(&self, cpass: &mut wgpu::ComputePass<'_>, _key: usize) {
        self.builder.current.dispatch(cpass, &self.bind_group, self.size);
    }
}
