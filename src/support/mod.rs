//! What every layer may use and that uses nothing of skytune: safe file writes, and progress and
//! cancellation of long work.

pub mod progress;
pub mod safe_write;
pub mod shard;
