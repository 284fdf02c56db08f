//! The frame: the renderer that carries out the plan ([`renderer`]), the interface every pass
//! implements ([`pass`]), what a frame is drawn with ([`options`]) and what it reports
//! ([`stats`]), the camera and bind group 0: the globals and the scene's light ([`light`]).

pub mod camera;
pub mod depth;
pub mod globals;
pub mod history;
pub mod light;
pub mod options;
pub mod pass;
pub mod renderer;
pub mod stats;
