//! The GPU passes other than the sky objects (their own folder, [`crate::render::sky_objects`]):
//! one module each with a `.wgsl` of the same name in `shaders/`. The atmosphere's passes live
//! with its GPU owner in [`crate::render::atmosphere`].

pub mod baseline;
pub mod glare;
pub mod particle_sim;
pub mod particles;
pub mod precipitation;
pub mod reduced_layers;
pub mod scene;
pub mod stars;
pub mod tone_map;

use crate::render::frame::pass::{boxed, PassConstructor};

/// Every pass of the renderer, in recording order within its phase. The one list: pipelines,
/// shader reloads, sky uploads, per-frame steps and GPU timings all follow it.
pub const PASSES: &[(&str, PassConstructor)] = &[
    ("sky_luts", |b| boxed(crate::render::atmosphere::sky_luts::SkyLutsPass::new, b)),
    ("precomputed_tables", |b| boxed(crate::render::atmosphere::precomputed_tables::PrecomputedTablesPass::new, b)),
    ("sky_view", |b| boxed(crate::render::atmosphere::sky_view::SkyViewPass::new, b)),
    ("aerial_perspective", |b| boxed(crate::render::atmosphere::aerial_perspective::AerialPerspectivePass::new, b)),
    ("scene", |b| boxed(scene::ScenePass::new, b)),
    ("sky_objects", |b| boxed(crate::render::sky_objects::SkyObjectsPass::new, b)),
    ("stars", |b| boxed(stars::StarsPass::new, b)),
    ("particles", |b| boxed(particles::ParticlesPass::new, b)),
    ("precipitation", |b| boxed(precipitation::PrecipitationPass::new, b)),
    ("glare", |b| boxed(glare::GlarePass::new, b)),
    ("tone_map", |b| boxed(tone_map::ToneMapPass::new, b)),
    ("reduced_layers", |b| boxed(reduced_layers::ReducedLayersPass::new, b)),
];
