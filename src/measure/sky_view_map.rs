//! The sky-view map on the CPU: its layout (a twin of shaders/sky_model/sky_view_map.wgsl), its
//! rgba16float storage and its bilinear sampling, so that `skytune bench models` can measure what
//! drawing a model through the map costs in accuracy against looking the model up per pixel.

use crate::atmosphere::Rgb;

/// (u, v) of the direction at `elev_deg` above the horizon and `rel_azimuth_deg` from the sun's
/// azimuth (either way; any angle): u the azimuth from the sun's over half the circle (0 towards
/// the sun, 1 away from it: the sky is symmetric about the sun's vertical plane), v the elevation
/// with the horizon at 0.5 and v - 0.5 going as the square root of the elevation. Keep in sync with
/// `sky_view_uv` in shaders/sky_model/sky_view_map.wgsl.
pub fn map_uv(elev_deg: f64, rel_azimuth_deg: f64) -> (f64, f64) {
    let e = elev_deg.signum() * (elev_deg.abs() / 90.0).sqrt();
    let from_sun = (rel_azimuth_deg + 180.0).rem_euclid(360.0) - 180.0;
    (from_sun.abs() / 180.0, 0.5 - 0.5 * e)
}

/// The direction (elevation, azimuth from the sun's, 0 to 180; degrees) at (u, v): the inverse
/// of [`map_uv`] (`sky_view_direction` in the shader).
pub fn map_direction(u: f64, v: f64) -> (f64, f64) {
    let e = (0.5 - v) * 2.0;
    (e.signum() * e * e * 90.0, u * 180.0)
}

/// `x` rounded to the nearest half float, as an rgba16float texel stores it (the map holds
/// exposed radiance, within the half's normal range; rounding is relative there, so the exposure
/// does not change it).
pub fn round_to_half(x: f64) -> f64 {
    let bits = (x as f32).to_bits();
    // Round the 23-bit mantissa to 10 bits, to nearest, ties to even.
    let odd = (bits >> 13) & 1;
    f64::from(f32::from_bits(bits.wrapping_add(0x0fff + odd) & !0x1fff))
}

/// A filled sky-view map.
#[derive(Debug, Clone)]
pub struct SkyViewMap {
    size: (usize, usize),
    texels: Vec<Rgb>,
}

impl SkyViewMap {
    /// Directions (elevation, azimuth from the sun's; degrees) of the texel centres of a `size`
    /// map, row-major: what a model is evaluated at to fill it.
    pub fn texel_directions(size: (usize, usize)) -> Vec<(f64, f64)> {
        let (w, h) = size;
        (0..w * h).map(|k| map_direction(((k % w) as f64 + 0.5) / w as f64, ((k / w) as f64 + 0.5) / h as f64)).collect()
    }

    /// The map of `size` holding `radiance` at [`Self::texel_directions`], stored as half floats.
    pub fn new(size: (usize, usize), radiance: &[Rgb]) -> Self {
        assert_eq!(radiance.len(), size.0 * size.1, "one radiance per texel");
        Self { size, texels: radiance.iter().map(|c| c.map(round_to_half)).collect() }
    }

    /// The map sampled bilinearly at a direction (elevation, azimuth from the sun's; degrees), as
    /// the skydome's linear sampler does (both axes clamp to the edge).
    pub fn sample(&self, elev_deg: f64, rel_azimuth_deg: f64) -> Rgb {
        let (w, h) = self.size;
        let (u, v) = map_uv(elev_deg, rel_azimuth_deg);
        let x = (u * w as f64 - 0.5).clamp(0.0, (w - 1) as f64);
        let y = (v * h as f64 - 0.5).clamp(0.0, (h - 1) as f64);
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let col = |i: f64| (i as usize).min(w - 1);
        let row = |j: f64| (j as usize).min(h - 1);
        let at = |i: f64, j: f64| self.texels[row(j) * w + col(i)];
        let (a, b, c, d) = (at(x0, y0), at(x0 + 1.0, y0), at(x0, y0 + 1.0), at(x0 + 1.0, y0 + 1.0));
        std::array::from_fn(|k| (a[k] * (1.0 - fx) + b[k] * fx) * (1.0 - fy) + (c[k] * (1.0 - fx) + d[k] * fx) * fy)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uv_and_direction_are_inverse_and_the_horizon_is_the_middle() {
        for (e, a) in [(0.0, 0.0), (1.0, 170.0), (-4.0, 33.0), (45.0, 90.0), (89.0, 179.0)] {
            let (u, v) = map_uv(e, a);
            let (e2, a2) = map_direction(u, v);
            assert!((e - e2).abs() < 1e-9 && (a - a2).abs() < 1e-9, "{e} {a} -> {e2} {a2}");
        }
        assert_eq!(map_uv(0.0, 0.0), (0.0, 0.5), "towards the sun, at the horizon");
        assert_eq!(map_uv(90.0, 180.0), (1.0, 0.0), "away from the sun, overhead");
        // Either side of the sun's plane, and any turn, reads the same texel.
        for a in [-33.0, 327.0, -393.0] {
            assert!((map_uv(10.0, a).0 - map_uv(10.0, 33.0).0).abs() < 1e-12, "{a}");
        }
    }

    #[test]
    fn half_rounding_keeps_eleven_significant_bits() {
        for x in [1.0, 0.18, 3.3e-3, 12345.0] {
            let r = round_to_half(x);
            assert!(((r - x) / x).abs() <= 2f64.powi(-11), "{x} -> {r}");
        }
        assert_eq!(round_to_half(0.5), 0.5);
        assert_eq!(round_to_half(1.0 + 2f64.powi(-10)), 1.0 + 2f64.powi(-10));
    }

    #[test]
    fn sampling_returns_texels_at_their_centres_and_blends_between_them() {
        let size = (8, 4);
        let dirs = SkyViewMap::texel_directions(size);
        // Radiance linear in u within a row: bilinear sampling reproduces it between centres.
        let radiance: Vec<Rgb> = (0..32).map(|k| [(k % 8) as f64 + 1.0, (k / 8) as f64 + 1.0, 1.0]).collect();
        let map = SkyViewMap::new(size, &radiance);
        for (k, (e, a)) in dirs.iter().enumerate() {
            let s = map.sample(*e, *a);
            assert!((s[0] - radiance[k][0]).abs() < 1e-9 && (s[1] - radiance[k][1]).abs() < 1e-9, "texel {k}: {s:?}");
        }
        let (e, a0) = dirs[2];
        let a1 = dirs[3].1;
        let mid = map.sample(e, 0.5 * (a0 + a1));
        assert!((mid[0] - 3.5).abs() < 1e-9, "{mid:?}");
        // Past the last column's centre, towards 180 degrees, the last column (the sky is
        // symmetric about it); the same before the first.
        assert!((map.sample(e, 179.99)[0] - 8.0).abs() < 1e-9);
        assert!((map.sample(e, 0.01)[0] - 1.0).abs() < 1e-9);
    }
}
