//! Aerosols as a person states them: an optical depth at 550 nm and its spectral slope (the
//! Angstrom exponent), a turbidity, a visibility, or a named preset, turned into the Mie
//! coefficients of an [`Atmosphere`] at the models' three wavelengths.
//!
//! Mappings (docs/sky-format.md lists them with their sources):
//! - optical depth: `tau(lambda) = tau_550 (lambda / 550 nm)^-angstrom` (Angstrom 1929), the
//!   vertical column from the ground to the top of the atmosphere of the exponential Mie profile,
//!   so `extinction_per_km = tau / (H (1 - exp(-thickness / H)))`; scattering is the
//!   single-scattering albedo times extinction;
//! - turbidity (Preetham, Shirley and Smits 1999): `T = (tau_rayleigh + tau_aerosol) / tau_rayleigh`
//!   at 550 nm, with the atmosphere's own Rayleigh column;
//! - visibility (Koschmieder, 2% contrast): the extinction at the ground at 550 nm is
//!   `3.912 / V`, of which the aerosols hold what the air's Rayleigh scattering does not.

use serde::Deserialize;

use super::{Atmosphere, AtmosphereError, Rgb};

/// The wavelengths of the three channels, nm (r, g, b): those of Bruneton's and Hillaire's
/// Rayleigh and ozone coefficients, which the default atmosphere uses.
pub const WAVELENGTHS_NM: Rgb = [680.0, 550.0, 440.0];

/// Angstrom exponent when an optical depth is given without one: Angstrom's own mean for
/// continental air (1.3), the value most radiative-transfer codes default to.
pub const DEFAULT_ANGSTROM_EXPONENT: f64 = 1.3;

/// ln(1 / 0.02): Koschmieder's visibility constant for a 2% contrast threshold.
pub const KOSCHMIEDER: f64 = 3.912;

/// An aerosol layer: how much, how its optical depth falls with wavelength, how much it absorbs,
/// how forward it scatters and how high it reaches.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aerosol {
    /// Vertical optical depth at 550 nm, ground to top (extinction).
    pub optical_depth_550: f64,
    /// Angstrom exponent: optical depth ~ wavelength^-exponent (0 grey dust, ~1.3 continental
    /// haze, ~2 fine smoke).
    pub angstrom_exponent: f64,
    /// Single-scattering albedo: scattering / extinction, (0, 1].
    pub single_scattering_albedo: f64,
    /// Asymmetry of the Cornette-Shanks phase function.
    pub g: f64,
    /// Density falls as exp(-altitude / this), km.
    pub scale_height_km: f64,
}

/// How much aerosol, in one of the ways a person says it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum AerosolAmount {
    /// Vertical optical depth at 550 nm.
    OpticalDepth(f64),
    /// Preetham's turbidity: total over Rayleigh optical depth at 550 nm, >= 1.
    Turbidity(f64),
    /// Meteorological visibility at the ground, km.
    VisibilityKm(f64),
}

/// Named aerosols. Sources: the aerosol types of OPAC (Hess, Koepke and Schult 1998, "Optical
/// Properties of Aerosols and Clouds: The Software Package OPAC", BAMS 79, table 4, 80% relative
/// humidity): their optical depth at 550 nm, single-scattering albedo and asymmetry parameter;
/// the Angstrom exponent is the mean of OPAC's two (350-500 and 500-800 nm), the scale height
/// the mean altitude of OPAC's mixing-layer profile. `high_altitude` is the background aerosol
/// above a mountain observatory (optical depth about 0.02 at 550 nm, as at Mauna Loa) with
/// OPAC's clean continental particles.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AerosolPreset {
    /// OPAC continental clean: remote land air.
    Clean,
    /// OPAC continental average.
    Continental,
    /// OPAC continental polluted: a hazy summer day.
    Hazy,
    /// OPAC urban.
    Urban,
    /// OPAC desert: mineral dust, nearly grey.
    DesertDust,
    /// OPAC maritime clean: sea salt, grey and bright.
    Maritime,
    /// Free-troposphere background above a mountain site.
    HighAltitude,
}

impl AerosolPreset {
    /// Every preset, in the order of the docs.
    pub const ALL: [AerosolPreset; 7] = [Self::Clean, Self::Continental, Self::Hazy, Self::Urban, Self::DesertDust, Self::Maritime, Self::HighAltitude];

    /// The name in a sky file.
    pub fn name(self) -> &'static str {
        match self {
            Self::Clean => "clean",
            Self::Continental => "continental",
            Self::Hazy => "hazy",
            Self::Urban => "urban",
            Self::DesertDust => "desert_dust",
            Self::Maritime => "maritime",
            Self::HighAltitude => "high_altitude",
        }
    }

    /// The preset's aerosol.
    pub fn aerosol(self) -> Aerosol {
        let (optical_depth_550, angstrom_exponent, single_scattering_albedo, g, scale_height_km) = match self {
            Self::Clean => (0.064, 1.26, 0.972, 0.709, 1.0),
            Self::Continental => (0.151, 1.27, 0.925, 0.703, 1.0),
            Self::Hazy => (0.327, 1.29, 0.892, 0.698, 1.0),
            Self::Urban => (0.643, 1.29, 0.817, 0.689, 1.0),
            Self::DesertDust => (0.286, 0.19, 0.888, 0.729, 1.6),
            Self::Maritime => (0.096, 0.10, 0.997, 0.772, 0.7),
            Self::HighAltitude => (0.02, 1.26, 0.972, 0.709, 3.0),
        };
        Aerosol { optical_depth_550, angstrom_exponent, single_scattering_albedo, g, scale_height_km }
    }
}

/// The fraction of an exponential profile's column below `thickness_km`.
fn column_km(scale_height_km: f64, thickness_km: f64) -> f64 {
    scale_height_km * (1.0 - (-thickness_km / scale_height_km).exp())
}

impl Aerosol {
    /// The aerosol an atmosphere holds, read back from its Mie coefficients (the Angstrom
    /// exponent from the red and blue channels: 0 when grey).
    pub fn of(atm: &Atmosphere) -> Aerosol {
        let column = column_km(atm.mie_scale_height_km, atm.thickness_km());
        let tau = atm.mie_extinction_per_km.map(|e| e * column);
        let angstrom_exponent = if tau[0] > 0.0 && tau[2] > 0.0 { -(tau[0] / tau[2]).ln() / (WAVELENGTHS_NM[0] / WAVELENGTHS_NM[2]).ln() } else { 0.0 };
        let ext = atm.mie_extinction_per_km[1];
        Aerosol {
            optical_depth_550: tau[1],
            angstrom_exponent,
            single_scattering_albedo: if ext > 0.0 { atm.mie_scattering_per_km[1] / ext } else { 1.0 },
            g: atm.mie_g,
            scale_height_km: atm.mie_scale_height_km,
        }
    }

    /// Vertical optical depth at the three channels' wavelengths.
    pub fn optical_depth(&self) -> Rgb {
        WAVELENGTHS_NM.map(|l| self.optical_depth_550 * (l / 550.0).powf(-self.angstrom_exponent))
    }

    /// `atm` with its Mie coefficients, asymmetry and scale height replaced by this aerosol's.
    pub fn apply(&self, atm: Atmosphere) -> Atmosphere {
        let column = column_km(self.scale_height_km, atm.thickness_km());
        let extinction = self.optical_depth().map(|t| t / column);
        Atmosphere {
            mie_extinction_per_km: extinction,
            mie_scattering_per_km: extinction.map(|e| e * self.single_scattering_albedo),
            mie_g: self.g,
            mie_scale_height_km: self.scale_height_km,
            ..atm
        }
    }

    /// Checks the values' domains, naming the sky file's keys.
    pub fn validate(&self) -> Result<(), Vec<AtmosphereError>> {
        let mut errors = Vec::new();
        let mut check = |field: &'static str, ok: bool, message: String| {
            if !ok {
                errors.push(AtmosphereError { field, message });
            }
        };
        let tau = self.optical_depth_550;
        check("aerosol_optical_depth", tau.is_finite() && tau >= 0.0, format!("expected an optical depth >= 0, found {tau}"));
        let a = self.angstrom_exponent;
        check("angstrom_exponent", a.is_finite() && (-1.0..=4.0).contains(&a), format!("expected an Angstrom exponent in [-1, 4], found {a}"));
        let w = self.single_scattering_albedo;
        check("aerosol_albedo", w.is_finite() && w > 0.0 && w <= 1.0, format!("expected a single-scattering albedo in (0, 1], found {w}"));
        if errors.is_empty() {
            Ok(())
        } else {
            Err(errors)
        }
    }
}

/// What a sky file's `[atmosphere]` table (or a weather step's) states of the aerosol, in the
/// atmosphere's terms: a preset, one amount, and keys that refine them. The sky file checks
/// which keys may go together; this says what they mean.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct AerosolStatement {
    /// A preset to start from.
    pub preset: Option<AerosolPreset>,
    /// The amount, stated one way.
    pub amount: Option<AerosolAmount>,
    /// The Cornette-Shanks asymmetry.
    pub g: Option<f64>,
    /// The scale height, km.
    pub scale_height_km: Option<f64>,
    /// The Angstrom exponent.
    pub angstrom_exponent: Option<f64>,
    /// The single-scattering albedo.
    pub single_scattering_albedo: Option<f64>,
}

impl AerosolStatement {
    /// Whether it states anything that makes an aerosol (the asymmetry and the scale height alone
    /// only refine the Mie coefficients as written).
    pub fn states_aerosol(&self) -> bool {
        self.preset.is_some() || self.amount.is_some() || self.angstrom_exponent.is_some() || self.single_scattering_albedo.is_some()
    }

    /// `raw` (the atmosphere with any Mie coefficients written by hand, or the parent's aerosol)
    /// with this aerosol. `parent_stated`: the table this one sits in stated an aerosol, so
    /// `raw` holds it. A step changes what it states and keeps the rest, its spectral slope
    /// included once the parent gave one or the coefficients have one; grey coefficients given an
    /// amount get the default slope.
    pub fn apply(&self, raw: Atmosphere, parent_stated: bool) -> Result<Atmosphere, Vec<AtmosphereError>> {
        if !self.states_aerosol() {
            return Ok(raw);
        }
        let mut aerosol = match self.preset {
            Some(p) => p.aerosol(),
            None if parent_stated || raw.mie_extinction_per_km[0] != raw.mie_extinction_per_km[2] => Aerosol::of(&raw),
            None => Aerosol { angstrom_exponent: DEFAULT_ANGSTROM_EXPONENT, ..Aerosol::of(&raw) },
        };
        // Keys written beside a preset refine it.
        if let Some(g) = self.g {
            aerosol.g = g;
        }
        if let Some(h) = self.scale_height_km {
            aerosol.scale_height_km = h;
        }
        if let Some(a) = self.angstrom_exponent {
            aerosol.angstrom_exponent = a;
        }
        if let Some(w) = self.single_scattering_albedo {
            aerosol.single_scattering_albedo = w;
        }
        if let Some(amount) = self.amount {
            aerosol.optical_depth_550 = amount.optical_depth_550(&raw, aerosol.scale_height_km).map_err(|e| vec![e])?;
        }
        aerosol.validate()?;
        Ok(aerosol.apply(raw))
    }
}

impl AerosolAmount {
    /// The sky file's key for this way of stating the amount.
    pub fn key(self) -> &'static str {
        match self {
            Self::OpticalDepth(_) => "aerosol_optical_depth",
            Self::Turbidity(_) => "turbidity",
            Self::VisibilityKm(_) => "visibility_km",
        }
    }

    /// The optical depth at 550 nm this amount means in `atm` for aerosol with a scale height
    /// of `scale_height_km`.
    pub fn optical_depth_550(self, atm: &Atmosphere, scale_height_km: f64) -> Result<f64, AtmosphereError> {
        let err = |message: String| AtmosphereError { field: self.key(), message };
        match self {
            Self::OpticalDepth(tau) => Ok(tau),
            Self::Turbidity(t) if t >= 1.0 => Ok((t - 1.0) * atm.rayleigh_optical_depth_550()),
            Self::Turbidity(t) => Err(err(format!("expected a turbidity >= 1 (1 is air without aerosol), found {t}"))),
            Self::VisibilityKm(v) => {
                let rayleigh = atm.rayleigh_scattering_per_km[1];
                let aerosol_per_km = KOSCHMIEDER / v - rayleigh;
                if v.is_finite() && v > 0.0 && aerosol_per_km >= 0.0 {
                    Ok(aerosol_per_km * column_km(scale_height_km, atm.thickness_km()))
                } else {
                    Err(err(format!("expected a visibility in (0, {:.0}] km: beyond it even air without aerosol is hazier; found {v}", KOSCHMIEDER / rayleigh)))
                }
            }
        }
    }
}

impl Atmosphere {
    /// Vertical Rayleigh optical depth at 550 nm (the green channel), ground to top.
    pub fn rayleigh_optical_depth_550(&self) -> f64 {
        self.rayleigh_scattering_per_km[1] * column_km(self.rayleigh_scale_height_km, self.thickness_km())
    }

    /// Preetham's turbidity of this atmosphere: total over Rayleigh optical depth at 550 nm.
    pub fn turbidity(&self) -> f64 {
        1.0 + Aerosol::of(self).optical_depth_550 / self.rayleigh_optical_depth_550()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn optical_depth_becomes_coefficients_by_hand() {
        // tau 0.2 at 550 nm, exponent 1, H 1 km, albedo 0.9 over 100 km: the column is 1 km (to
        // 1e-43), so extinction at 550 nm is 0.2 km^-1; at 440 nm 0.2 * 550/440 = 0.25; at
        // 680 nm 0.2 * 550/680 = 0.161765.
        let a = Aerosol { optical_depth_550: 0.2, angstrom_exponent: 1.0, single_scattering_albedo: 0.9, g: 0.7, scale_height_km: 1.0 };
        let atm = a.apply(Atmosphere::default());
        let expected = [0.161_764_7, 0.2, 0.25];
        for (c, e) in expected.iter().enumerate() {
            assert!((atm.mie_extinction_per_km[c] - e).abs() < 1e-6, "{:?}", atm.mie_extinction_per_km);
            assert!((atm.mie_scattering_per_km[c] - 0.9 * e).abs() < 1e-6);
        }
        assert_eq!((atm.mie_g, atm.mie_scale_height_km), (0.7, 1.0));
        // And back.
        let back = Aerosol::of(&atm);
        assert!((back.optical_depth_550 - 0.2).abs() < 1e-12 && (back.angstrom_exponent - 1.0).abs() < 1e-9 && (back.single_scattering_albedo - 0.9).abs() < 1e-12);
    }

    #[test]
    fn turbidity_and_visibility_by_hand() {
        let atm = Atmosphere::default();
        // Rayleigh at 550 nm: 0.013558 km^-1 * 8 km * (1 - exp(-12.5)) = 0.108463.
        let tau_r = atm.rayleigh_optical_depth_550();
        assert!((tau_r - 0.108_463).abs() < 1e-5, "{tau_r}");
        let tau = AerosolAmount::Turbidity(3.0).optical_depth_550(&atm, 1.2).unwrap();
        assert!((tau - 2.0 * tau_r).abs() < 1e-12);
        // 20 km visibility: 3.912 / 20 - 0.013558 = 0.182042 km^-1 at the ground, 1.2 km high.
        let tau = AerosolAmount::VisibilityKm(20.0).optical_depth_550(&atm, 1.2).unwrap();
        assert!((tau - 0.182_042 * 1.2).abs() < 1e-5, "{tau}");
        assert!(AerosolAmount::VisibilityKm(400.0).optical_depth_550(&atm, 1.2).is_err());
        assert!(AerosolAmount::Turbidity(0.5).optical_depth_550(&atm, 1.2).is_err());
        // The default atmosphere's turbidity: 1 + 0.00444 * 1.2 / 0.108463.
        assert!((atm.turbidity() - (1.0 + 0.00444 * 1.2 / tau_r)).abs() < 1e-9);
    }

    #[test]
    fn presets_are_valid_and_ordered_by_haze() {
        for p in AerosolPreset::ALL {
            p.aerosol().validate().unwrap();
        }
        let tau = |p: AerosolPreset| p.aerosol().optical_depth_550;
        assert!(tau(AerosolPreset::HighAltitude) < tau(AerosolPreset::Clean) && tau(AerosolPreset::Clean) < tau(AerosolPreset::Continental));
        assert!(tau(AerosolPreset::Continental) < tau(AerosolPreset::Hazy) && tau(AerosolPreset::Hazy) < tau(AerosolPreset::Urban));
    }
}
