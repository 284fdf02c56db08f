//! GPU forms of the physical sky models' parameters, shared by every pass that evaluates a model
//! (`shaders/sky_model/`). The atmosphere types themselves know nothing of wgpu.

use bytemuck::{Pod, Zeroable};

use crate::atmosphere::{Atmosphere, OpticalDepth, SingleSettings};

/// Keep in sync with `Atmosphere` in shaders/sky_model/atmosphere.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable, PartialEq)]
pub struct AtmosphereUniform {
    /// Rayleigh scattering rgb, km^-1; scale height, km.
    pub rayleigh: [f32; 4],
    /// Mie scattering, extinction (km^-1), scale height (km), g.
    pub mie: [f32; 4],
    /// Ozone absorption rgb (km^-1), tent centre (km).
    pub ozone: [f32; 4],
    /// Ground radius, top radius (km), ozone half width (km), sun angular radius (rad).
    pub shape: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<AtmosphereUniform>() == 64);

impl From<&Atmosphere> for AtmosphereUniform {
    fn from(a: &Atmosphere) -> Self {
        let [r, g, b] = a.rayleigh_scattering_per_km.map(|x| x as f32);
        let [or, og, ob] = a.ozone_absorption_per_km.map(|x| x as f32);
        Self {
            rayleigh: [r, g, b, a.rayleigh_scale_height_km as f32],
            mie: [a.mie_scattering_per_km as f32, a.mie_extinction_per_km as f32, a.mie_scale_height_km as f32, a.mie_g as f32],
            ozone: [or, og, ob, a.ozone_center_km as f32],
            shape: [a.ground_radius_km as f32, a.top_radius_km as f32, a.ozone_half_width_km as f32, a.sun_angular_radius_rad as f32],
        }
    }
}

/// Keep in sync with `SingleSettings` in shaders/sky_model/single.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable, PartialEq, Eq)]
pub struct SingleUniform {
    /// Samples along the view ray.
    pub view_steps: u32,
    /// Samples towards the sun (numerical mode).
    pub sun_steps: u32,
    /// 0: erf, 1: numerical.
    pub numeric: u32,
    /// Padding.
    pub pad: u32,
}
const _: () = assert!(std::mem::size_of::<SingleUniform>() == 16);

impl From<&SingleSettings> for SingleUniform {
    fn from(s: &SingleSettings) -> Self {
        Self { view_steps: s.view_steps.max(1), sun_steps: s.sun_steps.max(1), numeric: matches!(s.optical_depth, OpticalDepth::Numerical) as u32, pad: 0 }
    }
}
