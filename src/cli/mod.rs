//! The binary's commands: arguments (clap) and the commands that write reports (`bench`,
//! `bench frame`, `bench models` with its charts, `sweep`). The window and the library's
//! measurements do the work; these modules drive them and write docs/.

pub mod args;
pub mod bench_aerial;
pub mod bench_frame;
pub mod bench_models;
pub mod bench_passes;
pub mod bench_reference;
pub mod charts;
pub mod export_env;
pub mod lookup_paths;
pub mod stability_report;
pub mod validate;
pub mod validate_aerial;

pub use args::*;
