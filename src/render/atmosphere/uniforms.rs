//! GPU forms of the atmosphere and the physical models' settings, as the shaders under
//! `shaders/sky_model/` read them. The atmosphere types themselves (`crate::atmosphere`) know
//! nothing of wgpu.

use bytemuck::{Pod, Zeroable};

use crate::atmosphere::{Atmosphere, LutSettings, OpticalDepth, SingleSettings};

/// Keep in sync with `Atmosphere` in shaders/sky_model/atmosphere.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable, PartialEq)]
pub struct AtmosphereUniform {
    /// Rayleigh scattering rgb, km^-1; scale height, km.
    pub rayleigh: [f32; 4],
    /// Mie scattering rgb (km^-1), scale height (km).
    pub mie_scattering: [f32; 4],
    /// Mie extinction rgb (km^-1), Cornette-Shanks g.
    pub mie_extinction: [f32; 4],
    /// Ozone absorption rgb (km^-1), tent centre (km).
    pub ozone: [f32; 4],
    /// Ground radius, top radius (km), ozone half width (km), sun angular radius (rad).
    pub shape: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<AtmosphereUniform>() == 80);

impl From<&Atmosphere> for AtmosphereUniform {
    fn from(a: &Atmosphere) -> Self {
        let [r, g, b] = a.rayleigh_scattering_per_km.map(|x| x as f32);
        let [or, og, ob] = a.ozone_absorption_per_km.map(|x| x as f32);
        let [sr, sg, sb] = a.mie_scattering_per_km.map(|x| x as f32);
        let [er, eg, eb] = a.mie_extinction_per_km.map(|x| x as f32);
        Self {
            rayleigh: [r, g, b, a.rayleigh_scale_height_km as f32],
            mie_scattering: [sr, sg, sb, a.mie_scale_height_km as f32],
            mie_extinction: [er, eg, eb, a.mie_g as f32],
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

/// Keep in sync with `LutParams` in shaders/sky_model/lut_sampling.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable, PartialEq)]
pub struct LutUniform {
    /// Transmittance width, height; multiple-scattering side; direction grid.
    pub sizes: [u32; 4],
    /// Transmittance, multiple-scattering and view-ray samples; unused.
    pub steps: [u32; 4],
    /// Ground albedo; the Mie phase function's Legendre moments g_1, g_2; unused.
    pub albedo_phase: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<LutUniform>() == 48);

impl LutUniform {
    /// The GPU form of `settings` with a ground albedo and the Mie asymmetry `mie_g`.
    pub fn new(settings: &LutSettings, albedo: f32, mie_g: f64) -> Self {
        let [w, h] = settings.transmittance_size;
        let [g1, g2] = crate::atmosphere::cornette_shanks_moments(mie_g);
        Self {
            sizes: [w, h, settings.multiscattering_size, settings.multiscattering_grid],
            steps: [settings.transmittance_steps, settings.multiscattering_steps, settings.view_steps, 0],
            albedo_phase: [albedo, g1 as f32, g2 as f32, 0.0],
        }
    }
}

/// The aerial-perspective volume's settings and camera. Keep in sync with `AerialParams` in
/// shaders/sky_model/aerial_volume.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable, PartialEq)]
pub struct AerialUniform {
    /// The camera the volume follows, clip to world (m), column-major.
    pub world_from_clip: [[f32; 4]; 4],
    /// Its position (m), and its altitude in the atmosphere (km).
    pub camera: [f32; 4],
    /// Unit vector towards the sun; w the method (0 none: the scene keeps its fog, 1 volume,
    /// 2 exact).
    pub towards_sun: [f32; 4],
    /// Cells across, down and in depth; view-ray samples per slice.
    pub size: [u32; 4],
    /// The last slice's end (km); the spread (0 quadratic, 1 linear); 1 with the
    /// multiple-scattering orders; unused.
    pub shape: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<AerialUniform>() == 128);

/// What the scene is given of the atmosphere in front of it: none (its fog), or the model's
/// aerial perspective by the settings' method.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum AerialUse {
    /// The scene keeps its fog.
    None,
    /// The model's aerial perspective, with or without the multiple-scattering orders.
    Model { multiple: bool },
}

impl AerialUniform {
    /// The GPU form of `settings` for a camera (`world_from_clip`, at `position` m and
    /// `altitude_km` in the atmosphere) under the sun `towards_sun`.
    pub fn new(
        settings: &crate::atmosphere::aerial::AerialSettings,
        using: AerialUse,
        world_from_clip: glam::Mat4,
        position: glam::Vec3,
        altitude_km: f32,
        towards_sun: glam::Vec3,
    ) -> Self {
        use crate::atmosphere::aerial::{AerialMethod, SliceSpread};
        let (method, multiple) = match (using, settings.method) {
            (AerialUse::None, _) | (_, AerialMethod::Fog) => (0.0, false),
            (AerialUse::Model { multiple }, AerialMethod::Volume) => (1.0, multiple),
            (AerialUse::Model { multiple }, AerialMethod::Exact) => (2.0, multiple),
        };
        let [x, y, z] = settings.volume_size;
        Self {
            world_from_clip: world_from_clip.to_cols_array_2d(),
            camera: position.extend(altitude_km).to_array(),
            towards_sun: towards_sun.extend(method).to_array(),
            size: [x, y, z, settings.steps_per_slice],
            shape: [settings.distance_km as f32, if settings.slices == SliceSpread::Linear { 1.0 } else { 0.0 }, if multiple { 1.0 } else { 0.0 }, 0.0],
        }
    }
}
