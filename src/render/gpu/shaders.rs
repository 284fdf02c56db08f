//! WGSL sources: embedded in the binary (every `shaders/**/*.wgsl`, found by build.rs), or read
//! from a folder for hot reload. Modules are created inside an error scope.

use std::path::{Path, PathBuf};

use crate::render::gpu::error::{RenderError, RenderResult};

include!(concat!(env!("OUT_DIR"), "/embedded_shaders.rs"));

/// The file prepended to every module: bind group 0.
pub const GLOBALS: &str = "globals";

/// Where shader sources come from.
#[derive(Debug, Clone, Default)]
pub struct ShaderLibrary {
    /// Folder to read `NAME.wgsl` from; `None` uses the embedded copies.
    pub dir: Option<PathBuf>,
}

impl ShaderLibrary {
    /// Embedded sources (release builds, tests).
    pub fn embedded() -> Self {
        Self { dir: None }
    }

    /// The source folder of this checkout, if it is still there (development builds hot-reload it).
    pub fn source_dir() -> Option<PathBuf> {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders");
        dir.join("globals.wgsl").is_file().then_some(dir)
    }

    /// Names of the embedded modules other than the globals (`sky_objects`, `folder/file`, ...).
    pub fn embedded_modules() -> impl Iterator<Item = &'static str> {
        EMBEDDED.iter().map(|(n, _)| *n).filter(|n| *n != GLOBALS)
    }

    /// Writes the embedded sources as files under `dir` (the layout of `shaders/`), e.g. to
    /// hot-reload and measure edits away from the checkout.
    pub fn export_embedded(dir: &Path) -> std::io::Result<()> {
        for (name, source) in EMBEDDED {
            let path = dir.join(format!("{name}.wgsl"));
            if let Some(parent) = path.parent() {
                std::fs::create_dir_all(parent)?;
            }
            std::fs::write(path, source)?;
        }
        Ok(())
    }

    fn raw(&self, name: &str) -> RenderResult<String> {
        match &self.dir {
            Some(dir) => {
                let path = dir.join(format!("{name}.wgsl"));
                std::fs::read_to_string(&path).map_err(|source| RenderError::ShaderFile { path, source })
            }
            None => EMBEDDED.iter().find(|(n, _)| *n == name).map(|(_, s)| s.to_string()).ok_or_else(|| RenderError::UnknownShader(name.to_string())),
        }
    }

    /// Full source of a module: globals, then the modules it requires (`//! requires: a, b` lines,
    /// resolved depth first, each once), then the module's own file.
    pub fn source(&self, name: &str) -> RenderResult<String> {
        let mut order = Vec::new();
        self.resolve(name, &mut Vec::new(), &mut order)?;
        let mut out = self.raw(GLOBALS)?;
        for (_, text) in order {
            out.push('\n');
            out.push_str(&text);
        }
        Ok(out)
    }

    /// Appends `name` after everything it requires; `stack` catches cycles.
    fn resolve(&self, name: &str, stack: &mut Vec<String>, order: &mut Vec<(String, String)>) -> RenderResult<()> {
        if order.iter().any(|(n, _)| n == name) {
            return Ok(());
        }
        if stack.iter().any(|n| n == name) {
            return Err(RenderError::Validation { what: format!("shaders/{name}.wgsl"), message: format!("requires itself through {}", stack.join(" -> ")) });
        }
        let text = self.raw(name)?;
        stack.push(name.to_string());
        for dep in requires(&text) {
            self.resolve(&dep, stack, order)?;
        }
        stack.pop();
        order.push((name.to_string(), text));
        Ok(())
    }
}

/// Modules a shader file requires, from its `//! requires: a, b` lines.
pub fn requires(text: &str) -> Vec<String> {
    text.lines()
        .filter_map(|l| l.trim().strip_prefix("//! requires:"))
        .flat_map(|list| list.split(',').map(|n| n.trim().to_string()).filter(|n| !n.is_empty()).collect::<Vec<_>>())
        .collect()
}

/// Runs `build` inside a validation error scope; returns its result only if wgpu reported nothing.
pub fn validated<T>(device: &wgpu::Device, what: &str, build: impl FnOnce() -> T) -> RenderResult<T> {
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let out = build();
    match pollster::block_on(scope.pop()) {
        None => Ok(out),
        Some(e) => Err(RenderError::Validation { what: what.to_string(), message: e.to_string() }),
    }
}

/// Creates a shader module from `shaders/NAME.wgsl` (with the globals prepended), validated.
pub fn module(device: &wgpu::Device, library: &ShaderLibrary, name: &str) -> RenderResult<wgpu::ShaderModule> {
    let source = library.source(name)?;
    validated(device, &format!("shaders/{name}.wgsl"), || {
        device.create_shader_module(wgpu::ShaderModuleDescriptor { label: Some(name), source: wgpu::ShaderSource::Wgsl(source.into()) })
    })
}

/// A pipeline that draws one full-screen triangle from `shaders/NAME.wgsl` (`vs_main` without
/// vertex buffers, `fs_main`) into a `format` target, no depth, no blending.
pub fn fullscreen_pipeline(
    device: &wgpu::Device,
    library: &ShaderLibrary,
    name: &str,
    layout: &wgpu::PipelineLayout,
    label: &str,
    format: wgpu::TextureFormat,
) -> RenderResult<wgpu::RenderPipeline> {
    let module = module(device, library, name)?;
    fullscreen_pipeline_of(device, &module, "fs_main", layout, label, format, None)
}

/// As [`fullscreen_pipeline`], from a module already made, with fragment entry `entry` and `blend`.
pub fn fullscreen_pipeline_of(
    device: &wgpu::Device,
    module: &wgpu::ShaderModule,
    entry: &str,
    layout: &wgpu::PipelineLayout,
    label: &str,
    format: wgpu::TextureFormat,
    blend: Option<wgpu::BlendState>,
) -> RenderResult<wgpu::RenderPipeline> {
    validated(device, label, || {
        device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(label),
            layout: Some(layout),
            vertex: wgpu::VertexState { module, entry_point: Some("vs_main"), buffers: &[], compilation_options: Default::default() },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: None,
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module,
                entry_point: Some(entry),
                targets: &[Some(wgpu::ColorTargetState { format, blend, write_mask: wgpu::ColorWrites::ALL })],
                compilation_options: Default::default(),
            }),
            multiview_mask: None,
            cache: None,
        })
    })
}

/// Creates a compute pipeline from `module`'s `entry`, validated.
pub fn compute_pipeline(device: &wgpu::Device, layout: &wgpu::PipelineLayout, module: &wgpu::ShaderModule, entry: &str, label: &str) -> RenderResult<wgpu::ComputePipeline> {
    validated(device, label, || {
        device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(label),
            layout: Some(layout),
            module,
            entry_point: Some(entry),
            compilation_options: Default::default(),
            cache: None,
        })
    })
}
