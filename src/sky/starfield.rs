//! The point stars: a procedural field (uniform directions, magnitudes following the observed
//! growth of star counts, about x3.2 per magnitude) or the Bright Star Catalogue (real positions
//! and magnitudes, embedded from assets/bsc5.bin, converted by scripts/convert_bsc.py), cut at the
//! sky's magnitude limit.

use glam::Vec3;

use super::procedural::SplitMix;
use super::resolved::Stars;

/// Brightest magnitude generated (Sirius is about -1.5).
pub const BRIGHTEST: f32 = -1.5;
/// Faintest magnitude generated before the cutoff (naked-eye limit in a dark site).
pub const FAINTEST: f32 = 7.0;
/// log10 growth of the number of stars per magnitude.
pub const COUNT_SLOPE: f32 = 0.5;

/// One star in the celestial frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Star {
    /// Unit direction in the celestial frame.
    pub direction: Vec3,
    /// Visual magnitude (smaller is brighter).
    pub magnitude: f32,
}

impl Star {
    /// Linear brightness relative to a magnitude-0 star.
    pub fn brightness(&self) -> f32 {
        10f32.powf(-0.4 * self.magnitude)
    }
}

/// The embedded Bright Star Catalogue (format: scripts/convert_bsc.py).
const BSC: &[u8] = include_bytes!("../../assets/bsc5.bin");

/// One catalogue entry: declination and right ascension (degrees), visual magnitude.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CatalogueStar {
    /// Declination, degrees.
    pub declination_deg: f32,
    /// Right ascension, degrees (15 per hour).
    pub right_ascension_deg: f32,
    /// Visual magnitude.
    pub magnitude: f32,
}

/// Every star of the embedded catalogue, brightest first.
pub fn catalogue() -> Vec<CatalogueStar> {
    let count = BSC.get(8..12).map_or(0, |b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize);
    BSC.get(12..)
        .unwrap_or_default()
        .chunks_exact(6)
        .take(count)
        .map(|c| CatalogueStar {
            declination_deg: i16::from_le_bytes([c[0], c[1]]) as f32 / 100.0,
            right_ascension_deg: u16::from_le_bytes([c[2], c[3]]) as f32 / 65536.0 * 360.0,
            magnitude: i16::from_le_bytes([c[4], c[5]]) as f32 / 100.0,
        })
        .collect()
}

/// The world direction at hour 0 of a star (the celestial frame: the renderer turns it about the
/// pole as the day goes), for a pole at `pole_elevation_deg` above the northern horizon and
/// `sidereal_deg` of right ascension on the meridian.
pub fn celestial_direction(star: &CatalogueStar, pole_elevation_deg: f32, sidereal_deg: f32) -> Vec3 {
    let lat = pole_elevation_deg.to_radians();
    let pole = Vec3::new(0.0, lat.sin(), -lat.cos());
    // Where the celestial equator crosses the meridian (due south), and the west point.
    let equator_south = Vec3::new(0.0, lat.cos(), lat.sin());
    let west = Vec3::NEG_X;
    let dec = star.declination_deg.to_radians();
    let hour_angle = (sidereal_deg - star.right_ascension_deg).to_radians();
    (dec.sin() * pole + dec.cos() * (hour_angle.cos() * equator_south + hour_angle.sin() * west)).normalize()
}

/// The sky's stars: generated or from the catalogue, at or below its magnitude cutoff.
pub fn generate(s: &Stars) -> Vec<Star> {
    match s.source {
        super::model::StarSource::Procedural => procedural(s),
        super::model::StarSource::Catalogue => catalogue()
            .into_iter()
            .filter(|c| c.magnitude <= s.magnitude_cutoff)
            .map(|c| Star { direction: celestial_direction(&c, s.pole_elevation_deg, s.sidereal_hours_at_midnight * 15.0), magnitude: c.magnitude })
            .collect(),
    }
}

/// Generates `count` stars over [BRIGHTEST, FAINTEST] and keeps those at or below the cutoff.
fn procedural(s: &Stars) -> Vec<Star> {
    let mut rng = SplitMix::new(s.seed);
    let span = FAINTEST - BRIGHTEST;
    // Inverse CDF of N(<m) ~ 10^(slope m): m = faintest + log10(u') / slope, u' in [10^(-slope span), 1].
    let floor = 10f32.powf(-COUNT_SLOPE * span);
    (0..s.count)
        .map(|_| {
            let z = rng.next_f32() * 2.0 - 1.0;
            let phi = rng.next_f32() * std::f32::consts::TAU;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let u = floor + (1.0 - floor) * rng.next_f32().max(1e-7);
            Star { direction: Vec3::new(r * phi.cos(), z, r * phi.sin()), magnitude: FAINTEST + u.log10() / COUNT_SLOPE }
        })
        .filter(|star| star.magnitude <= s.magnitude_cutoff)
        .collect()
}
