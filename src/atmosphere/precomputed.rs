//! Settings of the `precomputed` model (after Bruneton 2017, precomputed atmospheric scattering):
//! table sizes, scattering orders and sample counts, the accuracy axis of the benchmark. The
//! tables themselves are built on the GPU (`render::atmosphere::precomputed_tables`).

use serde::Deserialize;

use super::error::AtmosphereError;

/// How the tables the lookup reads are stored (the build always works in single precision). The
/// discriminant is the tables' header value (`PrecomputedHeader::steps[3]`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TablePrecision {
    /// rgba32f: the scattering and single-Mie tables apart, 32 bytes per 4D texel read.
    #[default]
    Single = 0,
    /// Both 4D tables packed as half floats into one 16-byte texel after the build: half the
    /// bytes a lookup reads (Bruneton 2017 stores its textures in half precision too).
    Half = 1,
}

impl TablePrecision {
    /// Its name in the sky file and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            TablePrecision::Single => "single",
            TablePrecision::Half => "half",
        }
    }
}

impl std::fmt::Display for TablePrecision {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for TablePrecision {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        [TablePrecision::Single, TablePrecision::Half].into_iter().find(|p| p.name() == s).ok_or_else(|| format!("expected single or half, found {s:?}"))
    }
}

/// Table sizes and sample counts of the `precomputed` model.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PrecomputedSettings {
    /// Transmittance table, texels (width: view angle, height: altitude).
    pub transmittance_size: [u32; 2],
    /// Irradiance tables, texels (width: sun angle, height: altitude).
    pub irradiance_size: [u32; 2],
    /// Scattering tables, texels along nu (view-sun angle), mu_s (sun angle), mu (view angle,
    /// both halves: rays that meet the ground and rays that leave) and r (altitude).
    pub scattering_size: [u32; 4],
    /// Scattering orders computed: 1 is single scattering alone. From 3 on, the orders above the
    /// last are added as a geometric series of the last two (per texel and channel).
    pub orders: u32,
    /// Samples per transmittance texel.
    pub transmittance_steps: u32,
    /// Samples along each scattering texel's ray.
    pub ray_steps: u32,
    /// Directions per half turn of the scattering-density integral (twice as many in azimuth).
    pub density_directions: u32,
    /// How the looked-up tables are stored.
    pub precision: TablePrecision,
}

impl PrecomputedSettings {
    /// Largest transmittance table.
    pub const MAX_TRANSMITTANCE: [u32; 2] = [512, 256];
    /// Largest irradiance table.
    pub const MAX_IRRADIANCE: [u32; 2] = [256, 64];
    /// Most texels of one scattering table (five share one storage buffer of at most 128 MiB).
    pub const MAX_SCATTERING_TEXELS: u32 = 1 << 20;
    /// Most scattering orders.
    pub const MAX_ORDERS: u32 = 16;
    /// Smallest cosine of the sun to the vertical the tables hold (Bruneton's 102 degrees from
    /// the zenith); darker suns read the edge, where the sky is black already.
    pub const MU_S_MIN: f32 = -0.2;

    /// A small, fast point of the chart: an eighth of the default table's texels, half of them
    /// along mu and r, four azimuths, and 32 suns. Twilight needs the suns: on the 768 cases of
    /// docs/sky-models.md, 8 x 16 x 64 x 16 read twilight median / p95 16% / 85%, this 3.8% / 26%,
    /// day 2.5% / 6.3% either way.
    pub const SMALL: Self = Self {
        transmittance_size: [128, 32],
        irradiance_size: [32, 8],
        scattering_size: [4, 32, 64, 16],
        orders: 4,
        transmittance_steps: 30,
        ray_steps: 30,
        density_directions: 8,
        precision: TablePrecision::Single,
    };

    /// Texels of one scattering table.
    pub fn scattering_texels(&self) -> u32 {
        self.scattering_size.iter().product()
    }

    /// Checks every setting's domain.
    pub fn validate(&self) -> Result<(), AtmosphereError> {
        let bad = |field: &'static str, message: String| Err(AtmosphereError { field, message });
        for (field, [w, h], [mw, mh]) in [("transmittance_size", self.transmittance_size, Self::MAX_TRANSMITTANCE), ("irradiance_size", self.irradiance_size, Self::MAX_IRRADIANCE)]
        {
            if !(2..=mw).contains(&w) || !(2..=mh).contains(&h) {
                return bad(field, format!("expected 2..={mw} x 2..={mh} texels, found {w} x {h}"));
            }
        }
        let [nu, mu_s, mu, r] = self.scattering_size;
        if nu < 2 || mu_s < 2 || r < 2 || mu < 4 || mu % 2 != 0 {
            return bad("scattering_size", format!("expected at least 2 texels along nu, mu_s and r and an even count of at least 4 along mu, found {nu} x {mu_s} x {mu} x {r}"));
        }
        if self.scattering_size.iter().map(|x| *x as u64).product::<u64>() > Self::MAX_SCATTERING_TEXELS as u64 {
            return bad("scattering_size", format!("{nu} x {mu_s} x {mu} x {r} texels is more than the {} a table may hold", Self::MAX_SCATTERING_TEXELS));
        }
        if !(1..=Self::MAX_ORDERS).contains(&self.orders) {
            return bad("orders", format!("expected 1..={}, found {}", Self::MAX_ORDERS, self.orders));
        }
        for (field, v) in [("transmittance_steps", self.transmittance_steps), ("ray_steps", self.ray_steps), ("density_directions", self.density_directions)] {
            if !(2..=1024).contains(&v) {
                return bad(field, format!("expected 2..=1024, found {v}"));
            }
        }
        Ok(())
    }
}

impl Default for PrecomputedSettings {
    fn default() -> Self {
        Self {
            transmittance_size: [256, 64],
            irradiance_size: [64, 16],
            scattering_size: [6, 40, 128, 32],
            orders: 4,
            transmittance_steps: 40,
            ray_steps: 50,
            density_directions: 16,
            precision: TablePrecision::Single,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_bad_sizes_are_refused() {
        assert!(PrecomputedSettings::default().validate().is_ok());
        let odd_mu = PrecomputedSettings { scattering_size: [8, 32, 127, 32], ..Default::default() };
        assert_eq!(odd_mu.validate().unwrap_err().field, "scattering_size");
        let huge = PrecomputedSettings { scattering_size: [16, 64, 256, 64], ..Default::default() };
        assert_eq!(huge.validate().unwrap_err().field, "scattering_size");
        assert_eq!(PrecomputedSettings { orders: 0, ..Default::default() }.validate().unwrap_err().field, "orders");
    }
}
