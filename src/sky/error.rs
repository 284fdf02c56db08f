//! What a sky load reports: one located problem of a sky file (file, line, column, field), and
//! all of them. Loading ([`super::load`]) makes them; a loaded sky ([`super::resolved`]) keeps its
//! warnings.

use std::fmt;

/// One problem in a sky file, located precisely.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{file}:{line}:{column}: {field}: {message}")]
pub struct SkyError {
    /// File the problem is in (the sky file, or the bitmap that failed).
    pub file: String,
    /// 1-based line in `file` (1 for whole-file problems).
    pub line: usize,
    /// 1-based column.
    pub column: usize,
    /// Dotted path of the field, e.g. `object[1].standard.stage[0].texture`.
    pub field: String,
    /// What was wrong and what was expected.
    pub message: String,
}

/// All the problems found in one load.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub struct SkyErrors(pub Vec<SkyError>);

impl fmt::Display for SkyErrors {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, e) in self.0.iter().enumerate() {
            if i > 0 {
                writeln!(f)?;
            }
            write!(f, "{e}")?;
        }
        Ok(())
    }
}
