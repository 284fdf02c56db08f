//! Aerial perspective: the atmosphere between the viewer and the scene, as settings and as the
//! depth layout of the froxel volume the renderer builds (`shaders/sky_model/aerial_volume.wgsl`
//! is the GPU form of [`AerialSettings::slice_distance_km`] and [`AerialSettings::slice_position`];
//! the tests here pin them). No GPU types.

use super::AtmosphereError;

/// How the scene is given the atmosphere in front of it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum AerialMethod {
    /// A froxel volume (screen x, y and distance) built once a frame, read at each scene vertex.
    #[default]
    Volume,
    /// The sky's own march stopped at each scene vertex's distance (the volume's accuracy bound,
    /// at the cost of a full view-ray march per vertex).
    Exact,
    /// No aerial perspective: the model's fog colour at the fixed density of the NeL scene (what
    /// the scene drew before aerial perspective; the cost benchmark's baseline).
    Fog,
}

impl AerialMethod {
    /// Name in the sky file.
    pub fn name(self) -> &'static str {
        match self {
            AerialMethod::Volume => "volume",
            AerialMethod::Exact => "exact",
            AerialMethod::Fog => "fog",
        }
    }
}

/// How the volume's depth slices are spread over its distance.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SliceSpread {
    /// Slice k ends at distance D (k / n)^2: fine near the viewer, where the air is densest
    /// relative to the distance covered and where most of the scene is (Hillaire 2020's layout).
    #[default]
    Quadratic,
    /// Slices of equal length.
    Linear,
}

impl SliceSpread {
    /// Name in the sky file.
    pub fn name(self) -> &'static str {
        match self {
            SliceSpread::Quadratic => "quadratic",
            SliceSpread::Linear => "linear",
        }
    }
}

/// The aerial-perspective settings (`[aerial_perspective]`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AerialSettings {
    /// Volume or exact integration.
    pub method: AerialMethod,
    /// Cells across, down and in depth.
    pub volume_size: [u32; 3],
    /// Distance the last slice ends at, km; beyond it the scene reads the last slice.
    pub distance_km: f64,
    /// How the slices are spread over that distance.
    pub slices: SliceSpread,
    /// View-ray samples per slice.
    pub steps_per_slice: u32,
}

impl Default for AerialSettings {
    fn default() -> Self {
        // 16 cells across and 32 down (4.4 and 2.2 degrees of the default view): a scene's light
        // changes fastest with elevation near the horizon, slowly with azimuth. One sample a
        // slice. Chosen on the tests' set 67 (docs/sky-models.md) for its build under 0.2x
        // the fill-rate floor on lavapipe at 1280x720 (0.15x; 32 across with 2 samples: 0.67x).
        Self { method: AerialMethod::Volume, volume_size: [16, 32, 32], distance_km: 128.0, slices: SliceSpread::Quadratic, steps_per_slice: 1 }
    }
}

impl AerialSettings {
    /// Largest volume the renderer holds, cells per axis (its textures are this size; a smaller
    /// volume uses a corner of them).
    pub const MAX_SIZE: [u32; 3] = [64, 64, 128];

    /// Checks every setting's domain.
    pub fn validate(&self) -> Result<(), AtmosphereError> {
        let bad = |field: &'static str, message: String| Err(AtmosphereError { field, message });
        for (axis, (&n, &max)) in ["across", "down", "in depth"].iter().zip(self.volume_size.iter().zip(Self::MAX_SIZE.iter())) {
            if !(2..=max).contains(&n) {
                return bad("volume_size", format!("expected 2..={max} cells {axis}, found {n}"));
            }
        }
        if !(self.distance_km.is_finite() && (0.1..=10_000.0).contains(&self.distance_km)) {
            return bad("distance_km", format!("expected 0.1..=10000 km, found {}", self.distance_km));
        }
        if !(1..=64).contains(&self.steps_per_slice) {
            return bad("steps_per_slice", format!("expected 1..=64, found {}", self.steps_per_slice));
        }
        Ok(())
    }

    /// Distance at which slice `k` (0-based) ends, km: the distance its cells hold the
    /// atmosphere up to.
    pub fn slice_distance_km(&self, k: u32) -> f64 {
        let w = (k as f64 + 1.0) / self.volume_size[2] as f64;
        self.distance_km * self.spread(w)
    }

    fn spread(&self, w: f64) -> f64 {
        match self.slices {
            SliceSpread::Quadratic => w * w,
            SliceSpread::Linear => w,
        }
    }

    /// Where a scene point at `distance_km` reads the volume: the texture coordinate along depth
    /// (slice centres at (k + 0.5) / n, clamped to the first and last), and the fraction of the
    /// first slice's values to take (below 1 only nearer than the first slice's end, where the
    /// values fall to none at the viewer).
    pub fn slice_position(&self, distance_km: f64) -> (f64, f64) {
        let n = self.volume_size[2] as f64;
        let x = (distance_km / self.distance_km).max(0.0);
        let w = match self.slices {
            SliceSpread::Quadratic => x.sqrt(),
            SliceSpread::Linear => x,
        };
        // w n = k + 1 at slice k's end, which is texel k's centre.
        let texel = w * n - 1.0;
        let z = (texel.clamp(0.0, n - 1.0) + 0.5) / n;
        (z, (w * n).min(1.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_slice_end_reads_its_own_texel_centre() {
        for slices in [SliceSpread::Quadratic, SliceSpread::Linear] {
            let s = AerialSettings { slices, volume_size: [8, 8, 16], ..Default::default() };
            for k in 0..16 {
                let (z, fraction) = s.slice_position(s.slice_distance_km(k));
                assert!((z - (k as f64 + 0.5) / 16.0).abs() < 1e-12, "{slices:?} slice {k}: z {z}");
                assert_eq!(fraction, 1.0);
            }
            // Half way to the first slice's end: its values, halved in the quadratic layout's w.
            let (z, fraction) = s.slice_position(s.slice_distance_km(0) * 0.25);
            assert!((z - 0.5 / 16.0).abs() < 1e-12);
            let expected = if slices == SliceSpread::Quadratic { 0.5 } else { 0.25 };
            assert!((fraction - expected).abs() < 1e-12, "{slices:?}: {fraction}");
            // Beyond the volume: the last slice, whole.
            assert_eq!(s.slice_position(10.0 * s.distance_km), (15.5 / 16.0, 1.0));
        }
    }

    #[test]
    fn the_quadratic_layout_crowds_slices_near_the_viewer() {
        let s = AerialSettings::default();
        assert!((s.slice_distance_km(31) - 128.0).abs() < 1e-9);
        // 128 km (1/32)^2 = 125 m.
        assert!((s.slice_distance_km(0) - 0.125).abs() < 1e-12);
        assert!(s.slice_distance_km(31) - s.slice_distance_km(30) > 50.0 * s.slice_distance_km(0));
    }

    #[test]
    fn settings_out_of_their_domain_are_named() {
        let bad = |s: AerialSettings| s.validate().unwrap_err().field;
        assert_eq!(bad(AerialSettings { volume_size: [1, 32, 32], ..Default::default() }), "volume_size");
        assert_eq!(bad(AerialSettings { volume_size: [32, 32, 129], ..Default::default() }), "volume_size");
        assert_eq!(bad(AerialSettings { distance_km: 0.0, ..Default::default() }), "distance_km");
        assert_eq!(bad(AerialSettings { distance_km: f64::NAN, ..Default::default() }), "distance_km");
        assert_eq!(bad(AerialSettings { steps_per_slice: 0, ..Default::default() }), "steps_per_slice");
        assert!(AerialSettings::default().validate().is_ok());
    }
}
