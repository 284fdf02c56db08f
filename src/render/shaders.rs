//! WGSL sources: embedded in the binary, or read from a folder for hot reload.
//! Pipelines are rebuilt inside an error scope and swapped in only on success.

use std::path::{Path, PathBuf};

/// Names of the pass shaders (each `shaders/NAME.wgsl`); `globals.wgsl` is prepended to each.
pub const PASSES: [&str; 4] = ["sky_objects", "stars", "scene", "glare"];

const EMBEDDED: [(&str, &str); 5] = [
    ("globals", include_str!("../../shaders/globals.wgsl")),
    ("sky_objects", include_str!("../../shaders/sky_objects.wgsl")),
    ("stars", include_str!("../../shaders/stars.wgsl")),
    ("scene", include_str!("../../shaders/scene.wgsl")),
    ("glare", include_str!("../../shaders/glare.wgsl")),
];

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

    fn raw(&self, name: &str) -> Result<String, String> {
        match &self.dir {
            Some(dir) => {
                let path = dir.join(format!("{name}.wgsl"));
                std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))
            }
            None => EMBEDDED.iter().find(|(n, _)| *n == name).map(|(_, s)| s.to_string()).ok_or_else(|| format!("no shader named {name}")),
        }
    }

    /// Full source of a pass: globals followed by the pass's own file.
    pub fn source(&self, name: &str) -> Result<String, String> {
        Ok(format!("{}\n{}", self.raw("globals")?, self.raw(name)?))
    }
}

/// Runs `build` inside a validation error scope; returns its result only if wgpu reported nothing.
pub fn validated<T>(device: &wgpu::Device, what: &str, build: impl FnOnce() -> T) -> Result<T, String> {
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let out = build();
    match pollster::block_on(scope.pop()) {
        None => Ok(out),
        Some(e) => Err(format!("{what}: {e}")),
    }
}

/// Creates a shader module from a pass's source, validated.
pub fn module(device: &wgpu::Device, library: &ShaderLibrary, name: &str) -> Result<wgpu::ShaderModule, String> {
    let source = library.source(name)?;
    validated(device, &format!("shaders/{name}.wgsl"), || {
        device.create_shader_module(wgpu::ShaderModuleDescriptor { label: Some(name), source: wgpu::ShaderSource::Wgsl(source.into()) })
    })
}
