//! `[atmosphere]`: overrides of the physical models' atmosphere, and of its aerosol.

use serde::Deserialize;

use super::*;

/// `[atmosphere]`: any of the default atmosphere's parameters (km, km^-1, rad); the rest keep
/// Hillaire 2020's Earth values. Cross-field rules (top above ground, Mie extinction >= Mie
/// scattering) are checked after loading.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AtmosphereDef {
    /// Planet radius, km.
    pub ground_radius_km: Option<Positive>,
    /// Radius of the top of the atmosphere, km.
    pub top_radius_km: Option<Positive>,
    /// Rayleigh scattering at sea level, km^-1 (r, g, b).
    pub rayleigh_scattering_per_km: Option<[NonNegative; 3]>,
    /// Rayleigh scale height, km.
    pub rayleigh_scale_height_km: Option<Positive>,
    /// Mie scattering at sea level, km^-1: one grey number or (r, g, b).
    pub mie_scattering_per_km: Option<Coefficients>,
    /// Mie extinction at sea level, km^-1: one grey number or (r, g, b).
    pub mie_extinction_per_km: Option<Coefficients>,
    /// Mie scale height, km.
    pub mie_scale_height_km: Option<Positive>,
    /// Mie asymmetry, (-1, 1).
    pub mie_g: Option<Asymmetry>,
    /// Ozone absorption at its peak, km^-1 (r, g, b).
    pub ozone_absorption_per_km: Option<[NonNegative; 3]>,
    /// Altitude of the ozone peak, km.
    pub ozone_center_km: Option<Finite>,
    /// Half width of the ozone tent, km.
    pub ozone_half_width_km: Option<Positive>,
    /// Sun's angular radius, rad.
    pub sun_angular_radius_rad: Option<Positive>,
    /// A named aerosol (`clean`, `continental`, `hazy`, `urban`, `desert_dust`, `maritime`,
    /// `high_altitude`): its optical depth, Angstrom exponent, albedo, g and scale height.
    pub aerosol: Option<crate::atmosphere::aerosol::AerosolPreset>,
    /// Vertical aerosol optical depth at 550 nm (instead of Mie coefficients).
    pub aerosol_optical_depth: Option<NonNegative>,
    /// Preetham's turbidity, total over Rayleigh optical depth at 550 nm, >= 1 (instead of
    /// `aerosol_optical_depth`).
    pub turbidity: Option<Finite>,
    /// Visibility at the ground, km (Koschmieder; instead of `aerosol_optical_depth`).
    pub visibility_km: Option<Positive>,
    /// How the aerosol optical depth falls with wavelength (default 1.3, or the preset's).
    pub angstrom_exponent: Option<Finite>,
    /// Aerosol single-scattering albedo, (0, 1] (default the atmosphere's, or the preset's).
    pub aerosol_albedo: Option<Unit>,
    /// Per weather step, from weather 0 to weather 1, overrides on top of these (e.g. aerosols
    /// rising with the storm); the atmosphere is interpolated between steps like a NeL bitmap.
    #[serde(default)]
    pub weather: Vec<AtmosphereDef>,
}

impl AtmosphereDef {
    /// The ways this definition states an aerosol amount.
    fn amounts(&self) -> Vec<crate::atmosphere::aerosol::AerosolAmount> {
        use crate::atmosphere::aerosol::AerosolAmount as A;
        let tau = self.aerosol_optical_depth.map(|v| A::OpticalDepth(v.get() as f64));
        let t = self.turbidity.map(|v| A::Turbidity(v.get() as f64));
        let v = self.visibility_km.map(|v| A::VisibilityKm(v.get() as f64));
        [tau, t, v].into_iter().flatten().collect()
    }

    /// Whether this definition says anything about the aerosol (coefficients, amount, preset,
    /// slope or albedo).
    pub fn states_aerosol(&self) -> bool {
        self.has_coefficients() || self.aerosol.is_some() || !self.amounts().is_empty() || self.angstrom_exponent.is_some() || self.aerosol_albedo.is_some()
    }

    /// Whether this definition gives Mie coefficients by hand.
    fn has_coefficients(&self) -> bool {
        self.mie_scattering_per_km.is_some() || self.mie_extinction_per_km.is_some()
    }

    /// `base` with these overrides. `parent` is the `[atmosphere]` a weather step sits in (and
    /// `base` its atmosphere). Errors name the keys.
    pub fn apply(&self, base: crate::atmosphere::Atmosphere, parent: Option<&AtmosphereDef>) -> Result<crate::atmosphere::Atmosphere, Vec<crate::atmosphere::AtmosphereError>> {
        use crate::atmosphere::aerosol::AerosolStatement;
        use crate::atmosphere::AtmosphereError;
        let raw = self.apply_coefficients(base);
        let amounts = self.amounts();
        let mut errors = Vec::new();
        if amounts.len() > 1 {
            let keys: Vec<&str> = amounts.iter().map(|a| a.key()).collect();
            errors.push(AtmosphereError { field: amounts[1].key(), message: format!("give the aerosol amount one way, found {}", keys.join(" and ")) });
        }
        if self.has_coefficients() && (self.aerosol.is_some() || !amounts.is_empty()) {
            let field = if self.mie_scattering_per_km.is_some() { "mie_scattering_per_km" } else { "mie_extinction_per_km" };
            errors.push(AtmosphereError {
                field,
                message: "give the aerosol either as Mie coefficients or by aerosol, aerosol_optical_depth, turbidity or visibility_km, not both".into(),
            });
        }
        if !errors.is_empty() {
            return Err(errors);
        }
        let statement = |d: &AtmosphereDef| AerosolStatement {
            preset: d.aerosol,
            amount: d.amounts().first().copied(),
            g: d.mie_g.map(|g| g.get() as f64),
            scale_height_km: d.mie_scale_height_km.map(|h| h.get() as f64),
            angstrom_exponent: d.angstrom_exponent.map(|a| a.get() as f64),
            single_scattering_albedo: d.aerosol_albedo.map(|w| w.get() as f64),
        };
        statement(self).apply(raw, parent.is_some_and(|p| statement(p).states_aerosol()))
    }

    /// `base` with the coefficients written here.
    fn apply_coefficients(&self, base: crate::atmosphere::Atmosphere) -> crate::atmosphere::Atmosphere {
        let f = |v: Option<Positive>, d: f64| v.map_or(d, |x| x.get() as f64);
        let rgb = |v: Option<[NonNegative; 3]>, d: [f64; 3]| v.map_or(d, |x| x.map(|c| c.get() as f64));
        crate::atmosphere::Atmosphere {
            ground_radius_km: f(self.ground_radius_km, base.ground_radius_km),
            top_radius_km: f(self.top_radius_km, base.top_radius_km),
            rayleigh_scattering_per_km: rgb(self.rayleigh_scattering_per_km, base.rayleigh_scattering_per_km),
            rayleigh_scale_height_km: f(self.rayleigh_scale_height_km, base.rayleigh_scale_height_km),
            mie_scattering_per_km: self.mie_scattering_per_km.map_or(base.mie_scattering_per_km, Coefficients::rgb),
            mie_extinction_per_km: self.mie_extinction_per_km.map_or(base.mie_extinction_per_km, Coefficients::rgb),
            mie_scale_height_km: f(self.mie_scale_height_km, base.mie_scale_height_km),
            mie_g: self.mie_g.map_or(base.mie_g, |g| g.get() as f64),
            ozone_absorption_per_km: rgb(self.ozone_absorption_per_km, base.ozone_absorption_per_km),
            ozone_center_km: self.ozone_center_km.map_or(base.ozone_center_km, |x| x.get() as f64),
            ozone_half_width_km: f(self.ozone_half_width_km, base.ozone_half_width_km),
            sun_angular_radius_rad: f(self.sun_angular_radius_rad, base.sun_angular_radius_rad),
        }
    }
}
