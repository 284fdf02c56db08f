//! WGSL sources: embedded in the binary (every `shaders/**/*.wgsl`, found by build.rs), or read
//! from a folder for hot reload. Modules are created inside an error scope.

use std::path::{Path, PathBuf};

use super::error::{RenderError, RenderResult};

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

    fn raw(&self, name: &str) -> RenderResult<String> {
        match &self.dir {
            Some(dir) => {
                let path = dir.join(format!("{name}.wgsl"));
                std::fs::read_to_string(&path).map_err(|source| RenderError::ShaderFile { path, source })
            }
            None => EMBEDDED.iter().find(|(n, _)| *n == name).map(|(_, s)| s.to_string()).ok_or_else(|| RenderError::UnknownShader(name.to_string())),
        }
    }

    /// Full source of a module: globals followed by the module's own file.
    pub fn source(&self, name: &str) -> RenderResult<String> {
        Ok(format!("{}\n{}", self.raw(GLOBALS)?, self.raw(name)?))
    }
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
