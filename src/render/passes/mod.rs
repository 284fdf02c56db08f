//! The GPU passes other than the sky objects (their own folder, [`crate::render::sky_objects`]):
//! one module each with a `.wgsl` of the same name in `shaders/`, plus the GPU forms of the sky
//! models and the probes that evaluate them.

pub mod baseline;
pub mod glare;
pub mod particle_sim;
pub mod particles;
pub mod precipitation;
pub mod precomputed_tables;
pub mod radiance_probe;
pub mod reduced_layers;
pub mod scene;
pub mod sky_luts;
pub mod sky_model;
pub mod sky_view;
pub mod stars;
pub mod tone_map;
