//! Exports for engines: linear-light stills (OpenEXR, Radiance HDR) and environment maps
//! (equirectangular, or six cube faces) of any sky, for image-based lighting and NeL's water
//! environment map.
//!
//! Linear values: with a physical or analytic model, the frame's HDR target (exposed radiance,
//! before tone mapping) divided by the exposure scale, so sr^-1 per unit of solar irradiance as
//! in `skytune radiance` (display-referred NeL layers become the radiance the tone mapper takes
//! back to their authored colour). With the NeL bitmap model there is no radiance: the display
//! image is sRGB-decoded (linear display values, 0..1).
//!
//! Cube faces: each is what a 90-degree camera at the dome centre sees along the face's axis with
//! the face's up vector (right = forward x up), in the world frame of the sky (x east, y up,
//! -z north). The side faces stand upright; `py` has north at its top and `ny` south, so the six
//! images fold into a horizontal cross around `pz` (docs/sky-models.md).

use std::path::{Path, PathBuf};

use glam::Vec3;

use crate::render::headless;
use crate::render::{Camera, Headless, RenderError, RenderOptions, RenderResult};
use crate::sky::{FrameInput, Sky};

/// A float image, rgba per pixel.
pub type LinearImage = image::Rgba32FImage;

/// The six cube faces: file suffix, forward, up.
pub const CUBE_FACES: [(&str, Vec3, Vec3); 6] =
    [("px", Vec3::X, Vec3::Y), ("nx", Vec3::NEG_X, Vec3::Y), ("py", Vec3::Y, Vec3::NEG_Z), ("ny", Vec3::NEG_Y, Vec3::Z), ("pz", Vec3::Z, Vec3::Y), ("nz", Vec3::NEG_Z, Vec3::Y)];

/// sRGB-encoded to linear.
fn srgb_decode(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// A display image as floats: linear (`linear`) or its display values.
pub fn display_to_float(img: &image::RgbaImage, linear: bool) -> LinearImage {
    LinearImage::from_fn(img.width(), img.height(), |x, y| {
        let p = img.get_pixel(x, y).0;
        let f = |v: u8| if linear { srgb_decode(v as f32 / 255.0) } else { v as f32 / 255.0 };
        image::Rgba([f(p[0]), f(p[1]), f(p[2]), p[3] as f32 / 255.0])
    })
}

/// Float display values back to 8 bits.
pub fn float_to_display(img: &LinearImage) -> image::RgbaImage {
    image::RgbaImage::from_fn(img.width(), img.height(), |x, y| image::Rgba(img.get_pixel(x, y).0.map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8)))
}

/// Renders a still and returns it in linear light (see the module documentation for units).
pub fn render_linear(hl: &mut Headless, sky: &Sky, input: &FrameInput, camera: &Camera, options: &RenderOptions) -> RenderResult<LinearImage> {
    // Radiance is read back from the HDR target, whatever the strategy draws on screen.
    let options = &RenderOptions { strategy: options.strategy.with_hdr(), ..*options };
    let display = hl.render(sky, input, camera, options)?;
    let model = input.sky_model.unwrap_or(sky.model);
    if !model.kind.is_physical() {
        return Ok(display_to_float(&display, true));
    }
    let (w, h) = (hl.target.width, hl.target.height);
    let texture = hl.renderer.hdr_texture().ok_or_else(|| RenderError::Readback("the frame drew no HDR target".into()))?;
    let texels = headless::read_texture(&hl.ctx, texture, w, h, 8)?;
    let light = headless::read_buffer(&hl.ctx, &hl.renderer.atmosphere().sky_light, 16)?;
    let scale = f32::from_le_bytes([light[0], light[1], light[2], light[3]]);
    let scale = if scale.is_finite() && scale > 0.0 { scale } else { 1.0 };
    log::debug!("render_linear: exposure scale {scale}");
    Ok(LinearImage::from_fn(w, h, |x, y| {
        let i = ((y * w + x) * 8) as usize;
        let v = |c: usize| half::f16::from_bits(u16::from_le_bytes([texels[i + 2 * c], texels[i + 2 * c + 1]])).to_f32() / scale;
        image::Rgba([v(0), v(1), v(2), 1.0])
    }))
}

/// The six cube faces (order of [`CUBE_FACES`]), `face` texels square; linear or display values.
/// Leaves `hl` at the face size.
pub fn cube_faces(hl: &mut Headless, sky: &Sky, input: &FrameInput, options: &RenderOptions, face: u32, linear: bool) -> RenderResult<Vec<LinearImage>> {
    hl.resize(face, face);
    CUBE_FACES
        .iter()
        .map(|&(_, forward, up)| {
            let camera = Camera { fov_y_deg: 90.0, look: Some((forward, up)), ..Camera::default() };
            if linear {
                render_linear(hl, sky, input, &camera, options)
            } else {
                hl.render(sky, input, &camera, options).map(|img| display_to_float(&img, false))
            }
        })
        .collect()
}

/// Bilinear sample of a face at continuous texel coordinates (clamped at its edges).
fn sample(img: &LinearImage, x: f32, y: f32) -> [f32; 4] {
    let (w, h) = (img.width() as i64, img.height() as i64);
    let (x, y) = (x - 0.5, y - 0.5);
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let at = |xi: i64, yi: i64| img.get_pixel(xi.clamp(0, w - 1) as u32, yi.clamp(0, h - 1) as u32).0;
    let (x0, y0) = (x0 as i64, y0 as i64);
    let (a, b, c, d) = (at(x0, y0), at(x0 + 1, y0), at(x0, y0 + 1), at(x0 + 1, y0 + 1));
    std::array::from_fn(|i| (a[i] * (1.0 - fx) + b[i] * fx) * (1.0 - fy) + (c[i] * (1.0 - fx) + d[i] * fx) * fy)
}

/// The face a direction falls on and its continuous texel coordinates there.
pub fn cube_texel(dir: Vec3, face: u32) -> (usize, f32, f32) {
    let (index, _) = CUBE_FACES.iter().enumerate().map(|(i, (_, f, _))| (i, dir.dot(*f))).fold((0, f32::MIN), |best, c| if c.1 > best.1 { c } else { best });
    let (_, forward, up) = CUBE_FACES[index];
    let right = forward.cross(up);
    let depth = dir.dot(forward).max(1e-6);
    let (sx, sy) = (dir.dot(right) / depth, dir.dot(up) / depth);
    let size = face as f32;
    (index, (sx + 1.0) * 0.5 * size, (1.0 - sy) * 0.5 * size)
}

/// The colour of the cube map towards `dir`.
pub fn cube_lookup(faces: &[LinearImage], dir: Vec3) -> [f32; 4] {
    let (i, x, y) = cube_texel(dir, faces[0].width());
    sample(&faces[i], x, y)
}

/// The direction of an equirectangular texel centre: u from north (centre) through east (right),
/// v from the zenith (top) to the nadir (bottom).
pub fn equirect_direction(x: u32, y: u32, width: u32, height: u32) -> Vec3 {
    let azimuth = ((x as f32 + 0.5) / width as f32 - 0.5) * std::f32::consts::TAU;
    let elevation = (0.5 - (y as f32 + 0.5) / height as f32) * std::f32::consts::PI;
    Vec3::new(azimuth.sin() * elevation.cos(), elevation.sin(), -azimuth.cos() * elevation.cos())
}

/// Resamples six cube faces into a `width` x `height` equirectangular map.
pub fn equirect_from_cube(faces: &[LinearImage], width: u32, height: u32) -> LinearImage {
    LinearImage::from_fn(width, height, |x, y| image::Rgba(cube_lookup(faces, equirect_direction(x, y, width, height))))
}

/// File formats of an export.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// 8-bit sRGB display values.
    Png,
    /// OpenEXR, 32-bit float linear values.
    Exr,
    /// Radiance RGBE, linear values.
    Hdr,
}

impl Format {
    /// Whether the format holds linear light.
    pub fn linear(self) -> bool {
        self != Format::Png
    }

    /// File extension.
    pub fn extension(self) -> &'static str {
        match self {
            Format::Png => "png",
            Format::Exr => "exr",
            Format::Hdr => "hdr",
        }
    }
}

/// Writes a float image (linear for EXR and HDR, display values for PNG) through a temporary
/// file, so a failed write leaves no half file.
pub fn save(img: &LinearImage, format: Format, path: &Path) -> anyhow::Result<()> {
    use anyhow::Context as _;
    let bytes = match format {
        Format::Png => return crate::support::safe_write::save_png(&float_to_display(img), path).map_err(Into::into),
        Format::Exr => {
            let mut out = std::io::Cursor::new(Vec::new());
            image::DynamicImage::ImageRgba32F(img.clone()).write_to(&mut out, image::ImageFormat::OpenExr).context("encoding OpenEXR")?;
            out.into_inner()
        }
        Format::Hdr => {
            let rgb: Vec<image::Rgb<f32>> = img.pixels().map(|p| image::Rgb([p[0], p[1], p[2]])).collect();
            let mut out = Vec::new();
            image::codecs::hdr::HdrEncoder::new(&mut out).encode(&rgb, img.width() as usize, img.height() as usize).context("encoding Radiance HDR")?;
            out
        }
    };
    crate::support::safe_write::write_atomic(path, &bytes).map_err(|e| anyhow::anyhow!("{e}"))
}

/// The file of cube face `suffix` next to `out` (`sky.exr` -> `sky_px.exr`).
pub fn face_path(out: &Path, suffix: &str, format: Format) -> PathBuf {
    let stem = out.file_stem().map_or_else(|| "env".into(), |s| s.to_string_lossy().into_owned());
    out.with_file_name(format!("{stem}_{suffix}.{}", format.extension()))
}
