//! Measurements of the sky models and of the renderer: the points of the speed-against-accuracy
//! chart, `kind = "auto"`'s pick, the stability sweep, soak runs, bakes of a model into bitmaps
//! and differences between two renders.

pub mod aerial;
pub mod auto_model;
pub mod bake;
pub mod image_diff;
pub mod model_points;
pub mod sky_view_map;
pub mod soak;
pub mod stability;
pub mod validation;
