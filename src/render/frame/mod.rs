//! The frame: the renderer that carries out the plan ([`renderer`]), the interface every pass
//! implements ([`pass`]), what a frame is drawn with ([`options`]) and what it reports
//! ([`stats`]), the camera, bind group 0 (the globals and the scene's light, [`light`]), the scene's
//! depth and the histories the renderer owns, and [`headless`], the offscreen driver of stills.

pub mod camera;
pub mod depth;
pub mod globals;
pub mod headless;
pub mod history;
pub mod light;
pub mod options;
pub mod pass;
pub mod renderer;
pub mod stats;
