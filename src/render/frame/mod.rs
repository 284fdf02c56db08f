//! The frame: the renderer that carries out the plan ([`renderer`]), the interface every pass
//! implements ([`pass`]), the camera and bind group 0's globals.

pub mod camera;
pub mod globals;
pub mod pass;
pub mod renderer;
