//! Comparing two renders of the same view: what an edit changed, how far a cheap model is from
//! the reference, what a GPU tier loses. Sides are described by [`SideSpec`] (a sky file and frame
//! overrides); the difference is NVIDIA's FLIP (the `nv-flip` crate: perceptual, 0 to 1, with a
//! magma heat map) plus a plain per-pixel channel difference, the measure the image tests use.
//! No GPU types here: the renders come from [`crate::render::Headless`].

use std::path::PathBuf;

use image::{Rgba, RgbaImage};
use thiserror::Error;

use crate::sky::resolved::SkyModelKind;

/// A side of a comparison that cannot be parsed.
#[derive(Debug, Error, PartialEq)]
#[error("compare side \"{spec}\": {message}")]
pub struct SideError {
    /// The side as given.
    pub spec: String,
    /// What is wrong.
    pub message: String,
}

/// One side of a comparison: `SKY`, `SKY@key=value,...` or `@key=value,...` (the common sky).
/// Keys: `hour`, `weather`, `tier` (4, 2, 1), `model` (a sky model name), `season`,
/// `exposure_ev`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SideSpec {
    /// Sky or continent file; `None`: the comparison's common sky.
    pub sky: Option<PathBuf>,
    /// Time of day, game hours.
    pub hour: Option<f32>,
    /// Weather, 0..1.
    pub weather: Option<f32>,
    /// GPU tier (texture stages): 4, 2 or 1.
    pub tier: Option<u8>,
    /// Skydome colour source.
    pub model: Option<SkyModelKind>,
    /// Season of a continent file.
    pub season: Option<String>,
    /// Exposure of physical models, stops.
    pub exposure_ev: Option<f32>,
}

impl std::str::FromStr for SideSpec {
    type Err = SideError;

    fn from_str(spec: &str) -> Result<Self, SideError> {
        let err = |message: String| SideError { spec: spec.to_string(), message };
        let (sky, overrides) = match spec.rsplit_once('@') {
            Some((sky, o)) => (sky, o),
            None => (spec, ""),
        };
        let mut side = SideSpec { sky: (!sky.is_empty()).then(|| PathBuf::from(sky)), ..Default::default() };
        for pair in overrides.split(',').map(str::trim).filter(|p| !p.is_empty()) {
            let (key, value) = pair.split_once('=').ok_or_else(|| err(format!("expected key=value, found \"{pair}\"")))?;
            let (key, value) = (key.trim(), value.trim());
            let number = || -> Result<f32, SideError> {
                value.parse::<f32>().ok().filter(|v| v.is_finite()).ok_or_else(|| err(format!("{key}: expected a finite number, found \"{value}\"")))
            };
            match key {
                "hour" => side.hour = Some(number()?),
                "weather" => side.weather = Some(number()?),
                "exposure_ev" => side.exposure_ev = Some(number()?),
                "tier" => side.tier = Some(value.parse().ok().filter(|t| [4, 2, 1].contains(t)).ok_or_else(|| err(format!("tier: expected 4, 2 or 1, found \"{value}\"")))?),
                "model" => {
                    side.model = Some(
                        SkyModelKind::ALL
                            .into_iter()
                            .find(|k| k.name() == value)
                            .ok_or_else(|| err(format!("model: unknown model \"{value}\"; expected one of {}", SkyModelKind::ALL.map(|k| k.name()).join(", "))))?,
                    )
                }
                "season" => side.season = Some(value.to_string()),
                _ => return Err(err(format!("unknown key \"{key}\"; expected hour, weather, tier, model, season or exposure_ev"))),
            }
        }
        Ok(side)
    }
}

/// The per-pixel channel difference the image tests use.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PixelDiff {
    /// Fraction of pixels whose largest channel difference exceeds the tolerance.
    pub differing: f64,
    /// Largest channel difference (of 255).
    pub max: u8,
    /// Mean absolute channel difference (of 255).
    pub mean: f64,
}

/// Compares two equally sized images channel by channel; the image marks differing pixels in
/// magenta and scales the others' difference x20 in grey.
pub fn pixel_diff(a: &RgbaImage, b: &RgbaImage, tolerance: u8) -> (PixelDiff, RgbaImage) {
    assert_eq!(a.dimensions(), b.dimensions(), "image sizes differ");
    let mut out = RgbaImage::new(a.width(), a.height());
    let (mut differing, mut max, mut sum) = (0u64, 0u8, 0u64);
    for ((pa, pb), po) in a.pixels().zip(b.pixels()).zip(out.pixels_mut()) {
        let d = (0..3).map(|i| pa[i].abs_diff(pb[i])).max().unwrap_or(0);
        sum += (0..3).map(|i| pa[i].abs_diff(pb[i]) as u64).sum::<u64>();
        max = max.max(d);
        if d > tolerance {
            differing += 1;
            *po = Rgba([255, 0, 255, 255]);
        } else {
            let g = (d as u32 * 20).min(255) as u8;
            *po = Rgba([g, g, g, 255]);
        }
    }
    let n = (a.width() * a.height()).max(1) as f64;
    (PixelDiff { differing: differing as f64 / n, max, mean: sum as f64 / (n * 3.0) }, out)
}

/// FLIP figures of a frame (0: identical, 1: as different as it gets).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlipSummary {
    /// Mean over the pixels.
    pub mean: f32,
    /// 95th percentile.
    pub p95: f32,
    /// Largest value.
    pub max: f32,
}

/// The difference between two renders.
pub struct Difference {
    /// FLIP figures.
    pub flip: FlipSummary,
    /// Channel difference figures at `tolerance`.
    pub pixels: PixelDiff,
    /// Tolerance of `pixels`, of 255.
    pub tolerance: u8,
    /// FLIP error per pixel, row-major.
    pub error: Vec<f32>,
    /// Size, pixels.
    pub size: (u32, u32),
}

/// FLIP and channel differences of two equally sized images (A is the reference, B the test).
pub fn difference(a: &RgbaImage, b: &RgbaImage, tolerance: u8) -> Difference {
    assert_eq!(a.dimensions(), b.dimensions(), "image sizes differ");
    let (w, h) = a.dimensions();
    let rgb = |img: &RgbaImage| img.pixels().flat_map(|p| [p[0], p[1], p[2]]).collect::<Vec<u8>>();
    let (pixels, _) = pixel_diff(a, b, tolerance);
    let (ra, rb) = (rgb(a), rgb(b));
    // FLIP reports a small error for identical images (its filters see the frame's edges as
    // content); identical inputs are exactly zero here.
    let error = if ra == rb {
        vec![0.0; (w * h) as usize]
    } else {
        let reference = nv_flip::FlipImageRgb8::with_data(w, h, &ra);
        let test = nv_flip::FlipImageRgb8::with_data(w, h, &rb);
        nv_flip::flip(reference, test, nv_flip::DEFAULT_PIXELS_PER_DEGREE).to_vec()
    };
    let mut sorted: Vec<f32> = error.iter().copied().filter(|e| e.is_finite()).collect();
    sorted.sort_by(f32::total_cmp);
    let at = |q: f64| sorted.get(((sorted.len().max(1) - 1) as f64 * q).round() as usize).copied().unwrap_or(0.0);
    let mean = if sorted.is_empty() { 0.0 } else { (sorted.iter().map(|&e| e as f64).sum::<f64>() / sorted.len() as f64) as f32 };
    Difference { flip: FlipSummary { mean, p95: at(0.95), max: at(1.0) }, pixels, tolerance, error, size: (w, h) }
}

impl Difference {
    /// One line of figures, as `skytune compare` prints it.
    pub fn summary(&self) -> String {
        format!(
            "FLIP mean {:.4} p95 {:.4} max {:.4}; pixels beyond {}/255: {:.2}%; mean channel difference {:.3}/255 (max {})",
            self.flip.mean,
            self.flip.p95,
            self.flip.max,
            self.tolerance,
            self.pixels.differing * 100.0,
            self.pixels.mean,
            self.pixels.max
        )
    }

    /// The FLIP error as a heat map (magma: black 0, yellow-white 1).
    pub fn heat_map(&self) -> RgbaImage {
        let (w, h) = self.size;
        let mut out = RgbaImage::new(w, h);
        for (p, e) in out.pixels_mut().zip(&self.error) {
            *p = magma(*e);
        }
        out
    }
}

/// The magma colour map at `t` in 0..1 (FLIP's own table).
pub fn magma(t: f32) -> Rgba<u8> {
    static LUT: std::sync::OnceLock<Vec<[u8; 3]>> = std::sync::OnceLock::new();
    let lut = LUT.get_or_init(|| {
        let map = nv_flip::magma_lut();
        let data = map.to_vec();
        data.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect()
    });
    let i = ((t.clamp(0.0, 1.0) * (lut.len() - 1) as f32).round() as usize).min(lut.len() - 1);
    let [r, g, b] = lut[i];
    Rgba([r, g, b, 255])
}

/// How the two sides are shown.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Layout {
    /// A, B and the heat map next to each other, the legend under the heat map.
    #[default]
    SideBySide,
    /// A left of the split, B right of it, a white line between.
    Split,
    /// The heat map alone, with its legend.
    Difference,
}

impl Layout {
    /// Every layout.
    pub const ALL: [Layout; 3] = [Layout::SideBySide, Layout::Split, Layout::Difference];

    /// Name on the command line and in the app.
    pub fn name(self) -> &'static str {
        match self {
            Layout::SideBySide => "side",
            Layout::Split => "split",
            Layout::Difference => "diff",
        }
    }
}

/// A left of `at` (0..1 of the width), B right of it, and a white line at the split.
pub fn split(a: &RgbaImage, b: &RgbaImage, at: f32) -> RgbaImage {
    assert_eq!(a.dimensions(), b.dimensions(), "image sizes differ");
    let (w, h) = a.dimensions();
    let x_split = (at.clamp(0.0, 1.0) * w as f32).round() as u32;
    RgbaImage::from_fn(w, h, |x, y| match x.cmp(&x_split) {
        std::cmp::Ordering::Less => *a.get_pixel(x, y),
        std::cmp::Ordering::Equal => Rgba([255, 255, 255, 255]),
        std::cmp::Ordering::Greater => *b.get_pixel(x, y),
    })
}

/// Height of the legend strip under a heat map, pixels.
pub const LEGEND_HEIGHT: u32 = 16;

/// A legend for the heat map: the colour ramp from 0 (left) to 1 (right) with ticks at 0, 0.25,
/// 0.5, 0.75 and 1, the ends labelled "0" and "1".
pub fn legend(width: u32) -> RgbaImage {
    let mut out = RgbaImage::from_pixel(width, LEGEND_HEIGHT, Rgba([20, 20, 20, 255]));
    let ramp_height = LEGEND_HEIGHT - 6;
    for x in 0..width {
        let c = magma(x as f32 / (width.max(2) - 1) as f32);
        for y in 0..ramp_height {
            out.put_pixel(x, y, c);
        }
    }
    for k in 0..=4u32 {
        let x = (k * (width.max(1) - 1)) / 4;
        for y in ramp_height..LEGEND_HEIGHT {
            out.put_pixel(x, y, Rgba([255, 255, 255, 255]));
        }
    }
    out
}

/// The picture of a comparison in a layout (`split_at`: the split's position, 0..1).
pub fn compose(a: &RgbaImage, b: &RgbaImage, diff: &Difference, layout: Layout, split_at: f32) -> RgbaImage {
    let (w, h) = a.dimensions();
    match layout {
        Layout::Split => split(a, b, split_at),
        Layout::Difference => {
            let mut out = RgbaImage::from_pixel(w, h + LEGEND_HEIGHT, Rgba([20, 20, 20, 255]));
            image::imageops::replace(&mut out, &diff.heat_map(), 0, 0);
            image::imageops::replace(&mut out, &legend(w), 0, h as i64);
            out
        }
        Layout::SideBySide => {
            let gap = 4;
            let mut out = RgbaImage::from_pixel(3 * w + 2 * gap, h + LEGEND_HEIGHT, Rgba([20, 20, 20, 255]));
            image::imageops::replace(&mut out, a, 0, 0);
            image::imageops::replace(&mut out, b, (w + gap) as i64, 0);
            image::imageops::replace(&mut out, &diff.heat_map(), (2 * (w + gap)) as i64, 0);
            image::imageops::replace(&mut out, &legend(w), (2 * (w + gap)) as i64, h as i64);
            out
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sides_parse_with_clear_errors() {
        let s: SideSpec = "skies/desert/sky.toml@hour=18.5,model=lut,tier=2".parse().unwrap();
        assert_eq!(s.sky, Some(PathBuf::from("skies/desert/sky.toml")));
        assert_eq!((s.hour, s.tier, s.model), (Some(18.5), Some(2), Some(SkyModelKind::Lut)));
        let s: SideSpec = "@weather=1".parse().unwrap();
        assert_eq!((s.sky, s.weather), (None, Some(1.0)));
        assert_eq!("a.toml".parse::<SideSpec>().unwrap().sky, Some(PathBuf::from("a.toml")));
        for (bad, says) in [("@tier=3", "tier: expected 4, 2 or 1"), ("@hour=nan", "hour: expected a finite number"), ("@model=x", "unknown model"), ("@colour=1", "unknown key")] {
            let e = bad.parse::<SideSpec>().unwrap_err().to_string();
            assert!(e.contains(says), "{bad}: {e}");
        }
    }

    fn gradient(w: u32, h: u32, scale: f32) -> RgbaImage {
        RgbaImage::from_fn(w, h, |x, y| Rgba([((x * 255 / w) as f32 * scale) as u8, ((y * 255 / h) as f32 * scale) as u8, 90, 255]))
    }

    #[test]
    fn identical_images_differ_by_nothing_and_a_darkened_one_by_its_darkening() {
        let a = gradient(64, 48, 1.0);
        let d = difference(&a, &a, 2);
        assert_eq!((d.flip.mean, d.flip.max, d.pixels.differing, d.pixels.mean), (0.0, 0.0, 0.0, 0.0));
        // Half the brightness in every channel: the channel mean is the image's mean over 2.
        let b = RgbaImage::from_fn(64, 48, |x, y| {
            let p = a.get_pixel(x, y);
            Rgba([p[0] / 2, p[1] / 2, p[2] / 2, 255])
        });
        let expected = a.pixels().map(|p| (0..3).map(|i| (p[i] - p[i] / 2) as f64).sum::<f64>()).sum::<f64>() / (64.0 * 48.0 * 3.0);
        let d = difference(&a, &b, 2);
        assert!((d.pixels.mean - expected).abs() < 1e-9, "{} vs {expected}", d.pixels.mean);
        assert!(d.flip.mean > 0.05 && d.flip.p95 >= d.flip.mean && d.flip.max >= d.flip.p95, "{:?}", d.flip);
        // Darker still: a larger error.
        let c = gradient(64, 48, 0.25);
        assert!(difference(&a, &c, 2).flip.mean > difference(&a, &gradient(64, 48, 0.75), 2).flip.mean);
    }

    #[test]
    fn split_takes_each_half_from_its_side() {
        let (a, b) = (gradient(40, 10, 1.0), gradient(40, 10, 0.5));
        let s = split(&a, &b, 0.5);
        assert_eq!(s.get_pixel(5, 5), a.get_pixel(5, 5));
        assert_eq!(s.get_pixel(20, 5), &Rgba([255, 255, 255, 255]));
        assert_eq!(s.get_pixel(30, 5), b.get_pixel(30, 5));
        let d = difference(&a, &b, 2);
        for layout in Layout::ALL {
            let img = compose(&a, &b, &d, layout, 0.3);
            assert!(img.width() >= 40 && img.height() >= 10);
        }
    }
}
