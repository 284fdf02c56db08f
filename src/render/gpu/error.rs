//! Errors of the render module. Each is handled once: the app shows it in its errors panel and
//! keeps what it had, the CLI adds context with anyhow and exits.

use std::path::PathBuf;

/// What went wrong on the GPU side.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// A shader file could not be read.
    #[error("{path}: {source}")]
    ShaderFile {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// No shader of that name is embedded in this build.
    #[error("no embedded shader named \"{0}\"")]
    UnknownShader(String),
    /// wgpu rejected a shader module, a pipeline or an upload (a validation error).
    #[error("{what}: {message}")]
    Validation {
        /// The object being created (`shaders/glare.wgsl`, `Glare::sprite`, `uploading the sky`).
        what: String,
        /// wgpu's message.
        message: String,
    },
    /// No adapter fits the request.
    #[error("no suitable Vulkan adapter ({wanted}); found: [{found}]. On Debian install mesa-vulkan-drivers (scripts/setup.sh does)")]
    NoAdapter {
        /// What was asked for.
        wanted: String,
        /// Adapters seen.
        found: String,
    },
    /// The device could not be created.
    #[error("requesting the GPU device: {0}")]
    RequestDevice(#[from] wgpu::RequestDeviceError),
    /// Waiting for the GPU failed or timed out.
    #[error("waiting for the GPU: {0}")]
    Poll(#[from] wgpu::PollError),
    /// Reading a render target back failed.
    #[error("reading the image back: {0}")]
    Readback(String),
}

/// Result of the render module.
pub type RenderResult<T> = Result<T, RenderError>;
