//! Sky models against measured skies: scans of spectral sky radiance (data/measured/, derived
//! from Kider et al. 2014 by scripts/derive-kider-scans.py), the sun's position from the scan's
//! place and time, and the figures `skytune validate` reports: the luminance-shape error with one
//! free scale, and the blue/red ratio error. GPU-free: the models come in as closures.
//!
//! Radiance here is relative to the solar irradiance at the top of the atmosphere, per channel,
//! as the models' is (sr^-1): a measurement is divided by the extraterrestrial spectral
//! irradiance at its wavelength (ASTM G173-03, from Gueymard's SMARTS 2.9.2) at that day's
//! Earth-Sun distance.

use std::path::Path;

use crate::atmosphere::reference::Case;
use crate::atmosphere::Rgb;

/// Extraterrestrial solar spectral irradiance at 1 AU, W m^-2 nm^-1, mean over 10 nm around 680,
/// 550 and 440 nm (ASTM G173-03, the "extraterrestrial" column).
pub const SOLAR_IRRADIANCE_W_M2_NM: Rgb = [1.4905, 1.8682, 1.8273];

/// Rec. 709 luminance weights, as the renderer treats the three channels.
pub const LUMINANCE: Rgb = [0.2126, 0.7152, 0.0722];

/// Samples closer to the sun than this are left out by default, degrees: the scanner's field of
/// view and pointing put the aureole's steep slope between neighbouring readings.
pub const DEFAULT_SUN_EXCLUSION_DEG: f64 = 10.0;

/// Whether a scan may be used to choose anything (settings, defaults) or only to report.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Split {
    /// May inform choices.
    Tuning,
    /// Reported separately; never used to choose.
    HeldOut,
}

impl Split {
    /// The name in the scan files and the report.
    pub fn name(self) -> &'static str {
        match self {
            Split::Tuning => "tuning",
            Split::HeldOut => "held_out",
        }
    }
}

/// One direction of a scan.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Compass azimuth, degrees clockwise from north.
    pub azimuth_deg: f64,
    /// Elevation above the horizon, degrees.
    pub elevation_deg: f64,
    /// Spectral radiance at 680, 550, 440 nm, W m^-2 sr^-1 nm^-1.
    pub radiance: Rgb,
    /// False for readings the file marks unusable.
    pub used: bool,
}

/// A whole-sky scan.
#[derive(Debug, Clone, PartialEq)]
pub struct Scan {
    /// File stem (`2013-09-24_13-10`).
    pub name: String,
    /// Site latitude, degrees north.
    pub latitude_deg: f64,
    /// Site longitude, degrees east.
    pub longitude_deg: f64,
    /// Local civil time of the scan's start: year, month, day, hour, minute, second.
    pub local_time: [i32; 6],
    /// Local time minus UTC, hours.
    pub utc_offset_h: f64,
    /// Tuning or held out.
    pub split: Split,
    /// The directions.
    pub samples: Vec<Sample>,
}

/// A scan file that cannot be read, with where.
#[derive(Debug, thiserror::Error)]
#[error("{file}:{line}: {field}: {message}")]
pub struct ScanError {
    /// The file.
    pub file: String,
    /// 1-based line.
    pub line: usize,
    /// The header key or column.
    pub field: String,
    /// What is wrong.
    pub message: String,
}

impl Scan {
    /// Reads a scan file.
    pub fn read(path: &Path) -> Result<Scan, ScanError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| ScanError { file: file.clone(), line: 0, field: "file".into(), message: e.to_string() })?;
        let name = path.file_stem().map_or_else(|| file.clone(), |s| s.to_string_lossy().into_owned());
        Scan::parse(&text, &file, &name)
    }

    /// Parses a scan file's text: `# key = value` header lines, then
    /// `sample,azimuth_deg,elevation_deg,r,g,b,use` rows.
    pub fn parse(text: &str, file: &str, name: &str) -> Result<Scan, ScanError> {
        let err = |line: usize, field: &str, message: String| ScanError { file: file.to_string(), line, field: field.to_string(), message };
        let mut header = std::collections::HashMap::new();
        let mut samples = Vec::new();
        let mut columns_seen = false;
        for (i, line) in text.lines().enumerate() {
            let n = i + 1;
            if let Some(rest) = line.strip_prefix('#') {
                if let Some((k, v)) = rest.split_once('=') {
                    header.insert(k.trim().to_string(), (n, v.trim().to_string()));
                }
                continue;
            }
            if line.trim().is_empty() {
                continue;
            }
            if !columns_seen {
                let want = "sample,azimuth_deg,elevation_deg,r,g,b,use";
                if line.trim() != want {
                    return Err(err(n, "columns", format!("expected \"{want}\", found \"{line}\"")));
                }
                columns_seen = true;
                continue;
            }
            let cells: Vec<&str> = line.split(',').map(str::trim).collect();
            if cells.len() != 7 {
                return Err(err(n, "row", format!("expected 7 values, found {}", cells.len())));
            }
            let names = ["sample", "azimuth_deg", "elevation_deg", "r", "g", "b", "use"];
            let mut v = [0.0; 7];
            for (k, c) in cells.iter().enumerate() {
                v[k] = c.parse::<f64>().ok().filter(|x| x.is_finite()).ok_or_else(|| err(n, names[k], format!("expected a number, found \"{c}\"")))?;
            }
            if !(-90.0..=90.0).contains(&v[2]) {
                return Err(err(n, "elevation_deg", format!("expected -90..=90, found {}", v[2])));
            }
            samples.push(Sample { azimuth_deg: v[1], elevation_deg: v[2], radiance: [v[3], v[4], v[5]], used: v[6] != 0.0 });
        }
        let get = |key: &str| header.get(key).ok_or_else(|| err(1, key, format!("missing header line \"# {key} = ...\"")));
        let number = |key: &str| -> Result<f64, ScanError> {
            let (n, v) = get(key)?;
            v.parse::<f64>().ok().filter(|x| x.is_finite()).ok_or_else(|| err(*n, key, format!("expected a number, found \"{v}\"")))
        };
        let (time_line, time) = get("local_time")?;
        let local_time = parse_time(time).ok_or_else(|| err(*time_line, "local_time", format!("expected YYYY-MM-DDTHH:MM:SS, found \"{time}\"")))?;
        let split = match header.get("split").map(|(n, v)| (*n, v.as_str())) {
            None | Some((_, "tuning")) => Split::Tuning,
            Some((_, "held_out")) => Split::HeldOut,
            Some((n, other)) => return Err(err(n, "split", format!("expected tuning or held_out, found \"{other}\""))),
        };
        if samples.is_empty() {
            return Err(err(text.lines().count(), "rows", "no samples".into()));
        }
        Ok(Scan {
            name: name.to_string(),
            latitude_deg: number("latitude_deg")?,
            longitude_deg: number("longitude_deg")?,
            local_time,
            utc_offset_h: number("utc_offset_h")?,
            split,
            samples,
        })
    }

    /// Julian day (UT) of the scan's start.
    pub fn julian_day(&self) -> f64 {
        let [y, mo, d, h, mi, s] = self.local_time;
        julian_day(y, mo, d) + (h as f64 + mi as f64 / 60.0 + s as f64 / 3600.0 - self.utc_offset_h) / 24.0
    }

    /// The sun's elevation and compass azimuth, degrees, at the scan's start.
    pub fn sun(&self) -> (f64, f64) {
        sun_position(self.julian_day(), self.latitude_deg, self.longitude_deg)
    }

    /// The used samples at least `exclusion_deg` from the sun, as model cases (camera on the
    /// ground, `albedo`) with their radiance relative to the solar irradiance (sr^-1).
    pub fn cases(&self, albedo: f64, exclusion_deg: f64) -> (Vec<Case>, Vec<Rgb>) {
        let (sun_elev, sun_az) = self.sun();
        let towards_sun = direction(sun_elev, sun_az);
        let sun_irradiance = SOLAR_IRRADIANCE_W_M2_NM.map(|e| e * earth_sun_factor(self.julian_day()));
        let mut cases = Vec::new();
        let mut measured = Vec::new();
        for s in self.samples.iter().filter(|s| s.used && s.elevation_deg > 0.0) {
            let d = direction(s.elevation_deg, s.azimuth_deg);
            let from_sun = d.iter().zip(towards_sun).map(|(a, b)| a * b).sum::<f64>().clamp(-1.0, 1.0).acos().to_degrees();
            if from_sun < exclusion_deg || s.radiance.iter().any(|r| *r <= 0.0) {
                continue;
            }
            cases.push(Case {
                camera_km: 0.0,
                albedo,
                sun_elev_deg: sun_elev,
                view_elev_deg: s.elevation_deg,
                rel_azimuth_deg: (s.azimuth_deg - sun_az).rem_euclid(360.0),
                distance_km: None,
            });
            measured.push(std::array::from_fn(|c| s.radiance[c] / sun_irradiance[c]));
        }
        (cases, measured)
    }
}

fn parse_time(s: &str) -> Option<[i32; 6]> {
    let (date, time) = s.split_once('T')?;
    let d: Vec<i32> = date.split('-').map(|x| x.parse().ok()).collect::<Option<_>>()?;
    let t: Vec<i32> = time.split(':').map(|x| x.parse().ok()).collect::<Option<_>>()?;
    match (&d[..], &t[..]) {
        ([y, mo, dd], [h, mi, sec]) if (1..=12).contains(mo) && (1..=31).contains(dd) && (0..24).contains(h) && (0..60).contains(mi) && (0..61).contains(sec) => {
            Some([*y, *mo, *dd, *h, *mi, *sec])
        }
        _ => None,
    }
}

/// Julian day at 0h UT of a Gregorian date (Meeus, "Astronomical Algorithms", chapter 7).
pub fn julian_day(year: i32, month: i32, day: i32) -> f64 {
    let (y, m) = if month <= 2 { (year - 1, month + 12) } else { (year, month) };
    let a = (y as f64 / 100.0).floor();
    let b = 2.0 - a + (a / 4.0).floor();
    (365.25 * (y as f64 + 4716.0)).floor() + (30.6001 * (m as f64 + 1.0)).floor() + day as f64 + b - 1524.5
}

/// Unit vector (east, north, up) of an elevation and compass azimuth, degrees.
fn direction(elevation_deg: f64, azimuth_deg: f64) -> [f64; 3] {
    let (e, a) = (elevation_deg.to_radians(), azimuth_deg.to_radians());
    [e.cos() * a.sin(), e.cos() * a.cos(), e.sin()]
}

/// (1 AU / Earth-Sun distance)^2 on a Julian day (the mean anomaly's first two harmonics).
pub fn earth_sun_factor(jd: f64) -> f64 {
    let g = (357.529 + 0.985_600_28 * (jd - 2_451_545.0)).to_radians();
    let r_au = 1.000_14 - 0.016_71 * g.cos() - 0.000_14 * (2.0 * g).cos();
    1.0 / (r_au * r_au)
}

/// The sun's geometric elevation and compass azimuth, degrees, at Julian day `jd` (UT) seen from
/// a latitude and longitude (east positive): the NOAA solar calculator's equations (after Meeus),
/// good to about 0.01 degrees in this century. No refraction: the models place the sun
/// geometrically.
pub fn sun_position(jd: f64, latitude_deg: f64, longitude_deg: f64) -> (f64, f64) {
    let t = (jd - 2_451_545.0) / 36_525.0;
    let l0 = (280.466_46 + t * (36_000.769_83 + t * 0.000_303_2)).rem_euclid(360.0);
    let m = 357.529_11 + t * (35_999.050_29 - 0.000_153_7 * t);
    let e = 0.016_708_634 - t * (0.000_042_037 + 0.000_000_126_7 * t);
    let mr = m.to_radians();
    let c = mr.sin() * (1.914_602 - t * (0.004_817 + 0.000_014 * t)) + (2.0 * mr).sin() * (0.019_993 - 0.000_101 * t) + (3.0 * mr).sin() * 0.000_289;
    let true_long = l0 + c;
    let omega = 125.04 - 1_934.136 * t;
    let lambda = (true_long - 0.005_69 - 0.004_78 * omega.to_radians().sin()).to_radians();
    let eps0 = 23.0 + (26.0 + (21.448 - t * (46.815 + t * (0.000_59 - t * 0.001_813))) / 60.0) / 60.0;
    let eps = (eps0 + 0.002_56 * omega.to_radians().cos()).to_radians();
    let decl = (eps.sin() * lambda.sin()).asin();
    // Equation of time, minutes.
    let y = (eps / 2.0).tan().powi(2);
    let l0r = l0.to_radians();
    let eot = 4.0
        * (y * (2.0 * l0r).sin() - 2.0 * e * mr.sin() + 4.0 * e * y * mr.sin() * (2.0 * l0r).cos() - 0.5 * y * y * (4.0 * l0r).sin() - 1.25 * e * e * (2.0 * mr).sin())
            .to_degrees();
    let minutes_ut = (jd + 0.5).fract() * 1440.0;
    let true_solar = (minutes_ut + eot + 4.0 * longitude_deg).rem_euclid(1440.0);
    let hour_angle = (true_solar / 4.0 - 180.0).to_radians();
    let lat = latitude_deg.to_radians();
    let cos_zenith = (lat.sin() * decl.sin() + lat.cos() * decl.cos() * hour_angle.cos()).clamp(-1.0, 1.0);
    let zenith = cos_zenith.acos();
    let elevation = 90.0 - zenith.to_degrees();
    // Azimuth from north, clockwise: atan2 of the east and north components.
    let east = -decl.cos() * hour_angle.sin();
    let north = lat.cos() * decl.sin() - lat.sin() * decl.cos() * hour_angle.cos();
    (elevation, east.atan2(north).to_degrees().rem_euclid(360.0))
}

/// How well a model's radiance matches a measurement over a scan's samples.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Agreement {
    /// The scale that best brings the model's luminance to the measured (geometric mean of the
    /// ratios): 1 when the model's absolute level is right.
    pub scale: f64,
    /// Median over samples of |scaled model luminance / measured - 1|.
    pub luminance_median: f64,
    /// Median over samples of |model blue/red / measured blue/red - 1|.
    pub blue_red_median: f64,
    /// What a fit minimises: mean squared log luminance ratio (after the scale) plus mean squared
    /// log blue/red ratio.
    pub objective: f64,
}

/// The median of `v` (NaN when empty).
pub fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    match n {
        0 => f64::NAN,
        _ if n % 2 == 1 => v[n / 2],
        _ => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

/// The agreement of `model` with `measured` (the same samples, sr^-1).
pub fn agreement(model: &[Rgb], measured: &[Rgb]) -> Agreement {
    let lum = |c: &Rgb| c.iter().zip(LUMINANCE).map(|(x, w)| x * w).sum::<f64>();
    let pairs: Vec<(&Rgb, &Rgb)> = model.iter().zip(measured).filter(|(m, _)| lum(m) > 0.0 && m[0] > 0.0 && m[2] > 0.0).collect();
    if pairs.is_empty() {
        return Agreement { scale: f64::NAN, luminance_median: f64::INFINITY, blue_red_median: f64::INFINITY, objective: f64::INFINITY };
    }
    let log_lum: Vec<f64> = pairs.iter().map(|(m, y)| (lum(y) / lum(m)).ln()).collect();
    let log_scale = log_lum.iter().sum::<f64>() / log_lum.len() as f64;
    let log_br: Vec<f64> = pairs.iter().map(|(m, y)| ((m[2] / m[0]) / (y[2] / y[0])).ln()).collect();
    let mean_sq = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64;
    let lum_residual: Vec<f64> = log_lum.iter().map(|x| x - log_scale).collect();
    Agreement {
        scale: log_scale.exp(),
        luminance_median: median(lum_residual.iter().map(|r| ((-r).exp() - 1.0).abs()).collect()),
        blue_red_median: median(log_br.iter().map(|r| (r.exp() - 1.0).abs()).collect()),
        objective: mean_sq(&lum_residual) + mean_sq(&log_br),
    }
}

/// The parameter in `[lo, hi]` (searched in its logarithm, golden section, `iterations` steps)
/// that minimises `objective`, with the value there. Evaluations are cached by the caller's
/// closure if they are dear.
pub fn minimise_log(lo: f64, hi: f64, iterations: usize, mut objective: impl FnMut(f64) -> anyhow::Result<f64>) -> anyhow::Result<(f64, f64)> {
    let phi = (5f64.sqrt() - 1.0) / 2.0;
    let (mut a, mut b) = (lo.ln(), hi.ln());
    let mut x1 = b - phi * (b - a);
    let mut x2 = a + phi * (b - a);
    let (mut f1, mut f2) = (objective(x1.exp())?, objective(x2.exp())?);
    for _ in 0..iterations {
        if f1 <= f2 {
            b = x2;
            (x2, f2) = (x1, f1);
            x1 = b - phi * (b - a);
            f1 = objective(x1.exp())?;
        } else {
            a = x1;
            (x1, f1) = (x2, f2);
            x2 = a + phi * (b - a);
            f2 = objective(x2.exp())?;
        }
    }
    Ok(if f1 <= f2 { (x1.exp(), f1) } else { (x2.exp(), f2) })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_sun_where_the_almanac_puts_it() {
        // Overhead at noon on the tropics at the solstices and on the equator at the equinox
        // (12:00 UT at longitude 0 is within the equation of time, 15 minutes, of solar noon).
        for (y, m, d, lat) in [(2013, 6, 21, 23.44), (2013, 12, 21, -23.44), (2013, 3, 20, 0.0)] {
            let (e, _) = sun_position(julian_day(y, m, d) + 0.5, lat, 0.0);
            assert!(e > 86.0, "{y}-{m}-{d} at {lat}: {e}");
        }
        // Morning in the east, afternoon in the west; below the horizon at midnight.
        let ithaca = |hour_edt: f64| sun_position(julian_day(2013, 9, 24) + (hour_edt + 4.0) / 24.0, 42.443449, -76.481962);
        let (morning, afternoon, night) = (ithaca(7.83), ithaca(13.17), ithaca(0.0));
        assert!(morning.0 > 5.0 && morning.0 < 15.0 && morning.1 > 80.0 && morning.1 < 110.0, "{morning:?}");
        assert!(afternoon.0 > 40.0 && afternoon.1 > 180.0 && afternoon.1 < 200.0, "{afternoon:?}");
        assert!(night.0 < -30.0, "{night:?}");
        assert_eq!(julian_day(2000, 1, 1), 2_451_544.5);
    }

    #[test]
    fn agreement_sees_shape_and_colour_not_scale() {
        let measured = vec![[1.0, 2.0, 3.0], [2.0, 3.0, 5.0], [0.5, 1.0, 2.0]];
        let scaled: Vec<Rgb> = measured.iter().map(|c| c.map(|x| x * 7.0)).collect();
        let a = agreement(&scaled, &measured);
        assert!((a.scale - 1.0 / 7.0).abs() < 1e-12 && a.luminance_median < 1e-12 && a.blue_red_median < 1e-12);
        let bluer: Vec<Rgb> = measured.iter().map(|c| [c[0], c[1], c[2] * 1.1]).collect();
        assert!((agreement(&bluer, &measured).blue_red_median - 0.1).abs() < 1e-9);
    }

    #[test]
    fn golden_section_finds_a_log_minimum() {
        let (x, _) = minimise_log(0.001, 10.0, 40, |x| Ok((x.ln() - 0.3f64.ln()).powi(2))).unwrap();
        assert!((x / 0.3 - 1.0).abs() < 1e-4, "{x}");
    }

    #[test]
    fn a_bad_scan_row_is_located() {
        let text = "# latitude_deg = 42\n# longitude_deg = -76\n# local_time = 2013-09-24T13:10:00\n# utc_offset_h = -4\nsample,azimuth_deg,elevation_deg,r,g,b,use\n0,10,12,0.1,x,0.3,1\n";
        let e = Scan::parse(text, "scan.csv", "scan").unwrap_err();
        assert_eq!((e.line, e.field.as_str()), (6, "g"), "{e}");
        let e = Scan::parse(&text.replace("# utc_offset_h = -4\n", "").replace(",x,", ",0.2,"), "scan.csv", "scan").unwrap_err();
        assert!(e.to_string().contains("utc_offset_h"), "{e}");
    }
}
