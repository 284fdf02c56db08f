//! What an atmosphere out of its domain reports: the field, as the sky file names it, and why.

/// A parameter out of its domain.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{field}: {message}")]
pub struct AtmosphereError {
    /// The field, as named in the sky file.
    pub field: &'static str,
    /// What is wrong.
    pub message: String,
}
