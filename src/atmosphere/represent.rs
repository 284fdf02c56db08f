//! Cheap stand-ins for any sky model, measured as points of the speed-against-accuracy chart:
//!
//! - [`DomeMapTable`]: the procedural-sky text's sky-dome map
//!   (../shared/references/procedural-sky-scattering-blog.txt): `res` x `res` texels indexed by
//!   (sin of the view pitch, sqrt((1 - cos yaw) / 2)) with its non-uniform sampling, tabulated
//!   over sun elevations and interpolated between them.
//! - [`Regression`]: the same text's sky-dome regression: five coefficients per channel and sun
//!   elevation, reconstructed from a few arithmetic functions of the view and the sun.
//! - [`Baked`]: NeL gradient and halo bitmaps (24 hours, 8-bit display values), what
//!   `skytune bake` writes, reconstructed as the renderer samples them.
//!
//! Each is built from a radiance source (`eval(sun_elev_deg, cases)`) and answers radiance in the
//! source's units. No GPU types.

use super::dome::{self, DomeDir};
use super::reference::Case;
use super::Rgb;

/// Evaluates a model for one sun elevation and a list of cases.
pub type Source<'a> = dyn FnMut(f64, &[Case]) -> anyhow::Result<Vec<Rgb>> + 'a;

/// Sun elevations the tables are built at, degrees (16 table points, finer near the horizon).
pub const TABLE_SUNS_DEG: [f64; 16] = [-10.0, -6.0, -3.0, -1.0, 0.0, 1.0, 2.0, 4.0, 7.0, 11.0, 16.0, 23.0, 32.0, 45.0, 65.0, 90.0];

/// Bracketing table points and the weight of the upper one.
fn bracket(table: &[f64], x: f64) -> (usize, usize, f64) {
    let last = table.len() - 1;
    if x <= table[0] {
        return (0, 0, 0.0);
    }
    if x >= table[last] {
        return (last, last, 0.0);
    }
    let i = table.partition_point(|t| *t <= x).clamp(1, last);
    let t = (x - table[i - 1]) / (table[i] - table[i - 1]);
    (i - 1, i, t)
}

fn lerp3(a: Rgb, b: Rgb, t: f64) -> Rgb {
    std::array::from_fn(|c| a[c] + (b[c] - a[c]) * t)
}

fn case(sun_elev_deg: f64, elev_deg: f64, rel_az_deg: f64) -> Case {
    Case { camera_km: dome::CAMERA_KM, albedo: dome::ALBEDO, sun_elev_deg, view_elev_deg: elev_deg, rel_azimuth_deg: rel_az_deg, distance_km: None }
}

/// The sky-dome map, tabulated over sun elevations.
#[derive(Debug, Clone, PartialEq)]
pub struct DomeMapTable {
    /// Texels per side.
    pub res: usize,
    /// One map per [`TABLE_SUNS_DEG`] entry, row-major (v rows of u texels).
    pub maps: Vec<Vec<Rgb>>,
}

/// The text's non-uniform mapping keeps texel centres off the edges: uv = 0.021 + 0.958 (sin p, s).
const UV_MARGIN: f64 = 0.021;
const UV_SPAN: f64 = 0.958;

impl DomeMapTable {
    /// The view direction at the centre of texel (i, j): elevation and azimuth from the sun, degrees.
    pub fn texel_direction(res: usize, i: usize, j: usize) -> (f64, f64) {
        let u = ((i as f64 + 0.5) / res as f64 - UV_MARGIN) / UV_SPAN;
        let v = ((j as f64 + 0.5) / res as f64 - UV_MARGIN) / UV_SPAN;
        let sin_pitch = u.clamp(0.0, 1.0);
        let s = (1.0 - v).clamp(0.0, 1.0);
        let cos_yaw = 1.0 - 2.0 * s * s;
        (sin_pitch.asin().to_degrees(), cos_yaw.clamp(-1.0, 1.0).acos().to_degrees())
    }

    /// Evaluates `source` on every texel of every table point.
    pub fn build(res: usize, source: &mut Source<'_>) -> anyhow::Result<Self> {
        let mut maps = Vec::new();
        for &sun in &TABLE_SUNS_DEG {
            let cases: Vec<Case> = (0..res * res)
                .map(|k| {
                    let (e, a) = Self::texel_direction(res, k % res, k / res);
                    case(sun, e, a)
                })
                .collect();
            maps.push(source(sun, &cases)?);
        }
        Ok(Self { res, maps })
    }

    fn sample(&self, map: &[Rgb], elev_deg: f64, rel_az_deg: f64) -> Rgb {
        let sin_pitch = elev_deg.to_radians().sin().abs();
        let cos_yaw = rel_az_deg.to_radians().cos();
        let u = UV_MARGIN + UV_SPAN * sin_pitch;
        let v = UV_MARGIN + UV_SPAN * (1.0 - (0.5 * (1.0 - cos_yaw)).max(0.0).sqrt());
        // Bilinear, clamped to the edge, texel centres at (k + 0.5) / res: as a GPU sampler.
        let n = self.res;
        let x = (u * n as f64 - 0.5).clamp(0.0, (n - 1) as f64);
        let y = (v * n as f64 - 0.5).clamp(0.0, (n - 1) as f64);
        let (x0, y0) = (x.floor() as usize, y.floor() as usize);
        let (x1, y1) = ((x0 + 1).min(n - 1), (y0 + 1).min(n - 1));
        let (tx, ty) = (x - x0 as f64, y - y0 as f64);
        let row = |yy: usize| lerp3(map[yy * n + x0], map[yy * n + x1], tx);
        lerp3(row(y0), row(y1), ty)
    }

    /// Radiance towards (elevation, azimuth from the sun) with the sun at `sun_elev_deg`.
    pub fn radiance(&self, sun_elev_deg: f64, elev_deg: f64, rel_az_deg: f64) -> Rgb {
        let (a, b, t) = bracket(&TABLE_SUNS_DEG, sun_elev_deg);
        lerp3(self.sample(&self.maps[a], elev_deg, rel_az_deg), self.sample(&self.maps[b], elev_deg, rel_az_deg), t)
    }
}

/// Mie-like asymmetry of the regression's forward lobe.
const REGRESSION_G: f64 = 0.8;

/// The regression's five functions of the view (sin of pitch) and the cosine of the angle to the sun.
fn regression_basis(sin_pitch: f64, cos_sun: f64) -> [f64; 5] {
    let horizon = (1.0 - sin_pitch.clamp(0.0, 1.0)).powi(3);
    let g = REGRESSION_G;
    let lobe = (1.0 - g * g) / (1.0 + g * g - 2.0 * g * cos_sun).powf(1.5) / 10.0;
    [1.0, horizon, cos_sun * cos_sun, lobe, horizon * 0.5 * (1.0 + cos_sun)]
}

/// Five coefficients per channel and table sun elevation.
#[derive(Debug, Clone, PartialEq)]
pub struct Regression {
    /// Per [`TABLE_SUNS_DEG`] entry, per channel, the coefficients of [`regression_basis`].
    pub coefficients: Vec<[[f64; 5]; 3]>,
}

/// Solves the 5 x 5 system `a x = b` (Gaussian elimination with partial pivoting; a singular
/// system gives zeros in the free unknowns).
fn solve5(mut a: [[f64; 5]; 5], mut b: [f64; 5]) -> [f64; 5] {
    for col in 0..5 {
        let pivot = (col..5).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs())).unwrap_or(col);
        a.swap(col, pivot);
        b.swap(col, pivot);
        if a[col][col].abs() < 1e-300 {
            continue;
        }
        let pivot_row = a[col];
        for row in col + 1..5 {
            let f = a[row][col] / pivot_row[col];
            for (x, p) in a[row].iter_mut().zip(pivot_row).skip(col) {
                *x -= f * p;
            }
            b[row] -= f * b[col];
        }
    }
    let mut x = [0.0; 5];
    for row in (0..5).rev() {
        if a[row][row].abs() < 1e-300 {
            continue;
        }
        let s: f64 = (row + 1..5).map(|k| a[row][k] * x[k]).sum();
        x[row] = (b[row] - s) / a[row][row];
    }
    x
}

impl Regression {
    /// Fits each table point by weighted least squares over a 16 x 24 equal-area dome.
    pub fn build(source: &mut Source<'_>) -> anyhow::Result<Self> {
        let dirs = dome::dome_directions(16, 24);
        let mut coefficients = Vec::new();
        for &sun in &TABLE_SUNS_DEG {
            let cases = dome::cases(sun, &dirs);
            let values = source(sun, &cases)?;
            let mut ata = [[0.0; 5]; 5];
            let mut atb = [[0.0; 5]; 3];
            for (d, l) in dirs.iter().zip(&values) {
                let f = regression_basis(d.elev_deg.to_radians().sin(), cos_to_sun(sun, d.elev_deg, d.rel_az_deg));
                for i in 0..5 {
                    for j in 0..5 {
                        ata[i][j] += d.weight_sr * f[i] * f[j];
                    }
                    for c in 0..3 {
                        atb[c][i] += d.weight_sr * f[i] * l[c];
                    }
                }
            }
            coefficients.push([0, 1, 2].map(|c| solve5(ata, atb[c])));
        }
        Ok(Self { coefficients })
    }

    /// Radiance towards (elevation, azimuth from the sun), clamped at 0 as the text's shader does.
    pub fn radiance(&self, sun_elev_deg: f64, elev_deg: f64, rel_az_deg: f64) -> Rgb {
        let f = regression_basis(elev_deg.to_radians().sin().abs(), cos_to_sun(sun_elev_deg, elev_deg, rel_az_deg));
        let (a, b, t) = bracket(&TABLE_SUNS_DEG, sun_elev_deg);
        std::array::from_fn(|c| {
            let at = |k: usize| (0..5).map(|i| self.coefficients[k][c][i] * f[i]).sum::<f64>();
            (at(a) + (at(b) - at(a)) * t).max(0.0)
        })
    }
}

/// Cosine of the angle between a view and the sun.
pub fn cos_to_sun(sun_elev_deg: f64, elev_deg: f64, rel_az_deg: f64) -> f64 {
    let (s, e, a) = (sun_elev_deg.to_radians(), elev_deg.to_radians(), rel_az_deg.to_radians());
    (s.sin() * e.sin() + s.cos() * e.cos() * a.cos()).clamp(-1.0, 1.0)
}

/// Hours in a baked day (one gradient column per hour).
pub const BAKED_HOURS: usize = 24;
/// Lowest elevation of the baked skydome, degrees (its last gradient row).
pub const BAKED_BOTTOM_DEG: f64 = -10.0;
/// Angular radius of the baked halo texture, degrees (the stage's `size_deg` is twice this).
pub const BAKED_HALO_RADIUS_DEG: f64 = 90.0;
/// Samples of the halo's radial profile.
pub const BAKED_HALO_BINS: usize = 32;

/// The sun's elevation at each hour of an equinox day at the equator (6:00 on the horizon, noon at
/// the zenith, 15 degrees an hour): the day the benchmark bakes.
pub fn equinox_elevation_deg(hour: f64) -> f64 {
    90.0 - 15.0 * (hour - 12.0).abs()
}

/// NeL bitmaps baked from a model: display values at the fixed exposure of [`dome::display`],
/// quantised to 8 bits as a PNG stores them.
#[derive(Debug, Clone, PartialEq)]
pub struct Baked {
    /// Gradient rows, zenith first, down to [`BAKED_BOTTOM_DEG`].
    pub rows: usize,
    /// `gradient[weather][row * 24 + hour]`, sRGB-encoded display values 0..255.
    pub gradient: Vec<Vec<[u8; 3]>>,
    /// `halo_color[weather][hour]`, sRGB-encoded 0..255.
    pub halo_color: Vec<Vec<[u8; 3]>>,
    /// Radial profile of the halo texture (0 at the sun .. [`BAKED_HALO_RADIUS_DEG`]), 0..255.
    pub halo_profile: Vec<u8>,
}

fn to_u8(x: f64) -> u8 {
    (x.clamp(0.0, 1.0) * 255.0).round() as u8
}

fn from_u8(x: u8) -> f64 {
    x as f64 / 255.0
}

/// The two hour columns a time of day falls between (wrapping at midnight) and the weight of the
/// second, as the renderer samples colour bitmaps.
fn hour_columns(hour: f64) -> (usize, usize, f64) {
    let h = hour.rem_euclid(BAKED_HOURS as f64);
    let h0 = h.floor() as usize % BAKED_HOURS;
    (h0, (h0 + 1) % BAKED_HOURS, h - h.floor())
}

/// Elevation at the centre of gradient row `r` of `rows`.
fn row_elevation_deg(r: usize, rows: usize) -> f64 {
    90.0 - (r as f64 + 0.5) / rows as f64 * (90.0 - BAKED_BOTTOM_DEG)
}

impl Baked {
    /// Bakes `rows` gradient rows for every hour and weather step: `sources[w]` gives the model in
    /// weather step w; `sun_elev_by_hour` the sun's elevation at each whole hour.
    pub fn build(rows: usize, sun_elev_by_hour: &[f64; BAKED_HOURS], sources: &mut [&mut Source<'_>]) -> anyhow::Result<Self> {
        let azimuths: Vec<f64> = (0..=12).map(|k| k as f64 * 15.0).collect();
        let mut gradient = Vec::new();
        // Per weather, per hour: mean positive display residual by angle to the sun.
        let mut residuals: Vec<Vec<Vec<Rgb>>> = Vec::new();
        for source in sources.iter_mut() {
            let mut g = vec![[0u8; 3]; rows * BAKED_HOURS];
            let mut res_w = Vec::new();
            for (hour, &sun) in sun_elev_by_hour.iter().enumerate() {
                // Rows below the horizon repeat the horizon's colour (the view never sees the ground).
                let elevations: Vec<f64> = (0..rows).map(|r| row_elevation_deg(r, rows).max(0.5)).collect();
                let cases: Vec<Case> = elevations.iter().flat_map(|&e| azimuths.iter().map(move |&a| case(sun, e, a))).collect();
                let values = source(sun, &cases)?;
                // NeL adds its stages' sRGB-encoded values: gradient and halo are split in that space.
                let displays: Vec<Rgb> = values.iter().map(|l| dome::display(*l).map(dome::srgb_encode)).collect();
                let mut column = vec![[0.0; 3]; rows];
                for r in 0..rows {
                    // The side away from the sun: the halo stage adds the sun side's excess.
                    let away: Vec<&Rgb> = (0..azimuths.len()).filter(|&k| azimuths[k] >= 90.0).map(|k| &displays[r * azimuths.len() + k]).collect();
                    column[r] = std::array::from_fn(|c| away.iter().map(|d| d[c]).sum::<f64>() / away.len() as f64);
                    g[r * BAKED_HOURS + hour] = column[r].map(to_u8);
                }
                let mut bins = vec![[0.0; 3]; BAKED_HALO_BINS];
                let mut counts = vec![0.0; BAKED_HALO_BINS];
                for (k, d) in displays.iter().enumerate() {
                    let (r, a) = (k / azimuths.len(), azimuths[k % azimuths.len()]);
                    let angle = cos_to_sun(sun, elevations[r], a).acos().to_degrees();
                    let bin = (angle / BAKED_HALO_RADIUS_DEG * BAKED_HALO_BINS as f64) as usize;
                    if bin < BAKED_HALO_BINS {
                        for c in 0..3 {
                            bins[bin][c] += (d[c] - column[r][c]).max(0.0);
                        }
                        counts[bin] += 1.0;
                    }
                }
                res_w.push(bins.iter().zip(&counts).map(|(b, n)| if *n > 0.0 { b.map(|x| x / n) } else { [0.0; 3] }).collect());
            }
            gradient.push(g);
            residuals.push(res_w);
        }
        // One radial shape for the whole sky (one texture), normalised to 1 at the sun; one colour
        // per hour and weather (the constant's bitmap) by least squares against it.
        let lum = |x: &Rgb| x[0] + x[1] + x[2];
        let mut profile = vec![0.0; BAKED_HALO_BINS];
        for res_w in &residuals {
            for r in res_w {
                for (p, x) in profile.iter_mut().zip(r) {
                    *p += lum(x);
                }
            }
        }
        let peak = profile.iter().cloned().fold(0.0, f64::max);
        let profile: Vec<f64> = profile.iter().map(|p| if peak > 0.0 { p / peak } else { 0.0 }).collect();
        let halo_profile: Vec<u8> = profile.iter().map(|p| to_u8(*p)).collect();
        let quantised: Vec<f64> = halo_profile.iter().map(|p| from_u8(*p)).collect();
        let norm: f64 = quantised.iter().map(|p| p * p).sum::<f64>().max(1e-12);
        let halo_color = residuals
            .iter()
            .map(|res_w| {
                res_w
                    .iter()
                    .map(|r| {
                        let c: Rgb = std::array::from_fn(|c| r.iter().zip(&quantised).map(|(x, p)| x[c] * p).sum::<f64>() / norm);
                        c.map(to_u8)
                    })
                    .collect()
            })
            .collect();
        Ok(Self { rows, gradient, halo_color, halo_profile })
    }

    /// Gradient value (sRGB-encoded display value 0..1) at `hour` and elevation, in weather step
    /// `w`: bilinear over hours (wrapping) and rows after the renderer's [1, 1, 1] / 3 blur.
    fn gradient_display(&self, w: usize, hour: f64, elev_deg: f64) -> Rgb {
        let (h0, h1, th) = hour_columns(hour);
        let n = self.rows;
        let column: Vec<Rgb> = (0..n)
            .map(|r| {
                let at = |hh: usize| self.gradient[w][r * BAKED_HOURS + hh].map(from_u8);
                lerp3(at(h0), at(h1), th)
            })
            .collect();
        let blurred: Vec<Rgb> = (0..n).map(|r| std::array::from_fn(|c| (column[r.saturating_sub(1)][c] + column[r][c] + column[(r + 1).min(n - 1)][c]) / 3.0)).collect();
        let v = (90.0 - elev_deg) / (90.0 - BAKED_BOTTOM_DEG);
        let y = (v * n as f64 - 0.5).clamp(0.0, (n - 1) as f64);
        let (y0, t) = (y.floor() as usize, y - y.floor());
        lerp3(blurred[y0], blurred[(y0 + 1).min(n - 1)], t)
    }

    /// Radiance (through the inverse of the display transform) towards (elevation, azimuth from
    /// the sun) at `hour`, the sun at `sun_elev_deg`, weather step `w`.
    pub fn radiance(&self, w: usize, hour: f64, sun_elev_deg: f64, elev_deg: f64, rel_az_deg: f64) -> Rgb {
        let g = self.gradient_display(w, hour, elev_deg);
        let angle = cos_to_sun(sun_elev_deg, elev_deg, rel_az_deg).acos().to_degrees();
        let x = (angle / BAKED_HALO_RADIUS_DEG * BAKED_HALO_BINS as f64 - 0.5).clamp(0.0, (BAKED_HALO_BINS - 1) as f64);
        let (x0, t) = (x.floor() as usize, x - x.floor());
        let p = if angle >= BAKED_HALO_RADIUS_DEG {
            0.0
        } else {
            from_u8(self.halo_profile[x0]) + (from_u8(self.halo_profile[(x0 + 1).min(BAKED_HALO_BINS - 1)]) - from_u8(self.halo_profile[x0])) * t
        };
        let (h0, h1, th) = hour_columns(hour);
        let color = lerp3(self.halo_color[w][h0].map(from_u8), self.halo_color[w][h1].map(from_u8), th);
        // NeL adds the stages' display values; the sum is what the display shows.
        let display_encoded: Rgb = std::array::from_fn(|c| g[c] + color[c] * p);
        dome::radiance_from_display(display_encoded.map(dome::srgb_decode))
    }
}

/// Radiance of a representation over `dirs` for one sun elevation.
pub fn over_dome(dirs: &[DomeDir], f: impl Fn(f64, f64) -> Rgb) -> Vec<Rgb> {
    dirs.iter().map(|d| f(d.elev_deg, d.rel_az_deg)).collect()
}
