//! The artist's files and the files skytune writes for engines: watching them, hot reload of sky
//! files, snapshots for before/after comparisons, and exports (EXR/HDR stills, environment maps).

pub mod bitmap_edit;
pub mod env_light;
pub mod export;
pub mod hot_reload;
pub mod ktx2;
pub mod snapshot;
pub mod watch;
