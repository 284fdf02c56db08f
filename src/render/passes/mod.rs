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

use crate::render::frame::pass::{boxed, PassConstructor};

/// Every pass of the renderer, in recording order within its phase. The one list: pipelines,
/// shader reloads, sky uploads, per-frame steps and GPU timings all follow it.
pub const PASSES: &[(&str, PassConstructor)] = &[
    ("sky_luts", |b| boxed(sky_luts::SkyLutsPass::new, b)),
    ("precomputed_tables", |b| boxed(precomputed_tables::PrecomputedTablesPass::new, b)),
    ("sky_view", |b| boxed(sky_view::SkyViewPass::new, b)),
    ("scene", |b| boxed(scene::ScenePass::new, b)),
    ("sky_objects", |b| boxed(crate::render::sky_objects::SkyObjectsPass::new, b)),
    ("stars", |b| boxed(stars::StarsPass::new, b)),
    ("particles", |b| boxed(particles::ParticlesPass::new, b)),
    ("precipitation", |b| boxed(precipitation::PrecipitationPass::new, b)),
    ("glare", |b| boxed(glare::GlarePass::new, b)),
    ("tone_map", |b| boxed(tone_map::ToneMapPass::new, b)),
    ("reduced_layers", |b| boxed(reduced_layers::ReducedLayersPass::new, b)),
];
