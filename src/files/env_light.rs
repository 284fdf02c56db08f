//! Image-based lighting from a sky's cube map, on the CPU: the GGX-prefiltered specular mip chain,
//! the diffuse irradiance, its order-2 spherical harmonics, and where the sun is. What engines
//! otherwise compute from an environment map each (docs/export.md).
//!
//! Faces follow [`super::export::CUBE_FACES`]; every function takes and returns linear light.

use glam::Vec3;

use super::export::{LinearImage, CUBE_FACES};

/// The direction through the centre of texel (`x`, `y`) of face `face`, `size` texels a side.
pub fn texel_direction(face: usize, x: u32, y: u32, size: u32) -> Vec3 {
    let (_, forward, up) = CUBE_FACES[face];
    let right = forward.cross(up);
    let s = (x as f32 + 0.5) / size as f32 * 2.0 - 1.0;
    let t = 1.0 - (y as f32 + 0.5) / size as f32 * 2.0;
    (forward + right * s + up * t).normalize()
}

/// The solid angle of texel (`x`, `y`) of a face `size` texels a side, sr (exact: the area of the
/// texel's projection, from the antiderivative atan(st / sqrt(s^2 + t^2 + 1))).
pub fn texel_solid_angle(x: u32, y: u32, size: u32) -> f32 {
    let area = |s: f64, t: f64| (s * t).atan2((s * s + t * t + 1.0).sqrt());
    let edge = |i: u32| i as f64 / size as f64 * 2.0 - 1.0;
    let (s0, s1, t0, t1) = (edge(x), edge(x + 1), edge(y), edge(y + 1));
    (area(s1, t1) - area(s0, t1) - area(s1, t0) + area(s0, t0)) as f32
}

/// Every texel's direction and solid angle with its colour: (direction, sr, rgb).
fn texels(faces: &[LinearImage]) -> impl Iterator<Item = (Vec3, f32, [f32; 3])> + '_ {
    let size = faces[0].width();
    faces
        .iter()
        .enumerate()
        .flat_map(move |(f, img)| img.enumerate_pixels().map(move |(x, y, p)| (texel_direction(f, x, y, size), texel_solid_angle(x, y, size), [p[0], p[1], p[2]])))
}

/// Half the size, each texel the solid-angle weighted mean of its four (the radiance pyramid of
/// filtered importance sampling and the irradiance's source): an unweighted mean would count
/// the small texels of a face's corners as much as its middle's and move the map's mean.
pub fn downsample(faces: &[LinearImage]) -> Vec<LinearImage> {
    faces
        .iter()
        .map(|img| {
            let size = img.width();
            let half = (size / 2).max(1);
            LinearImage::from_fn(half, half, |x, y| {
                let mut sum = [0.0f32; 4];
                let mut total = 0.0;
                for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                    let (cx, cy) = ((2 * x + dx).min(size - 1), (2 * y + dy).min(size - 1));
                    let w = texel_solid_angle(cx, cy, size);
                    let p = img.get_pixel(cx, cy);
                    for c in 0..4 {
                        sum[c] += p[c] * w;
                    }
                    total += w;
                }
                image::Rgba(sum.map(|v| v / total))
            })
        })
        .collect()
}

/// Bilinear lookups in the two pyramid levels around `lod`, blended.
fn trilinear(pyramid: &[Vec<LinearImage>], lod: f32, dir: Vec3) -> [f32; 3] {
    let (lo, t) = (lod.floor() as usize, lod.fract());
    let hi = (lo + 1).min(pyramid.len() - 1);
    let (a, b) = (super::export::cube_lookup(&pyramid[lo], dir), super::export::cube_lookup(&pyramid[hi], dir));
    std::array::from_fn(|c| a[c] * (1.0 - t) + b[c] * t)
}

/// The Hammersley point `i` of `n`.
fn hammersley(i: u32, n: u32) -> (f32, f32) {
    (i as f32 / n as f32, i.reverse_bits() as f32 * 2.328_306_4e-10)
}

/// The perceptual roughness of mip `level` of `levels`: linear from 0 (the unfiltered map) to 1,
/// as Bevy's `EnvironmentMapLight` and Unity's HDRP read a specular chain (docs/export.md).
pub fn roughness_of_level(level: usize, levels: usize) -> f32 {
    if levels <= 1 {
        0.0
    } else {
        level as f32 / (levels - 1) as f32
    }
}

/// The specular mip chain: level 0 is `faces`, each next level half the size, prefiltered with
/// the GGX lobe of its roughness ([`roughness_of_level`], alpha = roughness^2) under the usual
/// split-sum assumption (normal = view = reflection), by importance sampling `samples` half
/// vectors per texel from the radiance pyramid (filtered importance sampling, Krivanek and
/// Colbert 2008), each weighted by the cosine to the normal.
pub fn prefilter_ggx(faces: &[LinearImage], levels: usize, samples: u32) -> Vec<Vec<LinearImage>> {
    let mut pyramid = vec![faces.to_vec()];
    while pyramid.last().is_some_and(|f| f[0].width() > 1) {
        pyramid.push(downsample(pyramid.last().map_or(faces, |f| &f[..])));
    }
    let base_size = faces[0].width();
    let texel_sr = 4.0 * std::f32::consts::PI / (6.0 * (base_size * base_size) as f32);
    let mut chain = vec![faces.to_vec()];
    for level in 1..levels {
        let size = (base_size >> level).max(1);
        let alpha = roughness_of_level(level, levels).powi(2).max(1e-4);
        let a2 = alpha * alpha;
        let face = |f: usize| {
            LinearImage::from_fn(size, size, |x, y| {
                let n = texel_direction(f, x, y, size);
                let (t, b) = basis(n);
                let mut sum = [0.0f32; 3];
                let mut weight = 0.0;
                // Each texel's points shifted by its own offset (Cranley-Patterson rotation):
                // one pattern everywhere would err the same way in every texel and move the
                // level's mean.
                let (du, dv) = hammersley((f as u32 * size + y) * size + x, 6 * size * size);
                let shift = (du * 0.618_034 + dv).fract();
                for i in 0..samples {
                    let (u, v) = hammersley(i, samples);
                    let (u, v) = ((u + shift).fract(), (v + dv).fract());
                    // GGX half vector around n.
                    let cos_h = ((1.0 - u) / (1.0 + (a2 - 1.0) * u)).sqrt();
                    let sin_h = (1.0 - cos_h * cos_h).max(0.0).sqrt();
                    let phi = std::f32::consts::TAU * v;
                    let h = t * (sin_h * phi.cos()) + b * (sin_h * phi.sin()) + n * cos_h;
                    let l = 2.0 * n.dot(h) * h - n;
                    let n_l = n.dot(l);
                    if n_l <= 0.0 {
                        continue;
                    }
                    // pdf of l with n = v: D(h) / 4; the texel footprint picks the pyramid level.
                    let d = a2 / (std::f32::consts::PI * (cos_h * cos_h * (a2 - 1.0) + 1.0).powi(2));
                    let sample_sr = 4.0 / (samples as f32 * d.max(1e-8));
                    let lod = (0.5 * (sample_sr / texel_sr).log2()).clamp(0.0, (pyramid.len() - 1) as f32);
                    let c = trilinear(&pyramid, lod, l);
                    for k in 0..3 {
                        sum[k] += c[k] * n_l;
                    }
                    weight += n_l;
                }
                let w = weight.max(1e-12);
                image::Rgba([sum[0] / w, sum[1] / w, sum[2] / w, 1.0])
            })
        };
        // One thread per face: the faces are independent and this is most of an export's time.
        let out: Vec<LinearImage> = std::thread::scope(|s| {
            let handles: Vec<_> = (0..6).map(|f| s.spawn(move || face(f))).collect();
            handles.into_iter().map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e))).collect()
        });
        chain.push(out);
    }
    chain
}

/// Two unit vectors completing `n` to an orthonormal basis.
fn basis(n: Vec3) -> (Vec3, Vec3) {
    let up = if n.y.abs() < 0.999 { Vec3::Y } else { Vec3::X };
    let t = up.cross(n).normalize();
    (t, n.cross(t))
}

/// Order-2 real spherical harmonics (9 coefficients) of a direction.
pub fn sh_basis(d: Vec3) -> [f32; 9] {
    let (x, y, z) = (d.x, d.y, d.z);
    [0.282_095, 0.488_603 * y, 0.488_603 * z, 0.488_603 * x, 1.092_548 * x * y, 1.092_548 * y * z, 0.315_392 * (3.0 * z * z - 1.0), 1.092_548 * x * z, 0.546_274 * (x * x - y * y)]
}

/// The map's radiance projected onto order-2 spherical harmonics: 9 rgb coefficients, in the
/// basis order of [`sh_basis`] (y, z, x as the three linear terms' axes).
pub fn sh9(faces: &[LinearImage]) -> [[f32; 3]; 9] {
    let mut sh = [[0.0f64; 3]; 9];
    for (d, sr, c) in texels(faces) {
        for (k, b) in sh_basis(d).iter().enumerate() {
            for ch in 0..3 {
                sh[k][ch] += (c[ch] * b * sr) as f64;
            }
        }
    }
    sh.map(|c| c.map(|v| v as f32))
}

/// Irradiance at a surface facing `n` from order-2 harmonics of radiance (Ramamoorthi and
/// Hanrahan 2001: the clamped cosine's bands scale by pi, 2 pi / 3, pi / 4).
pub fn sh_irradiance(sh: &[[f32; 3]; 9], n: Vec3) -> [f32; 3] {
    let a = [std::f32::consts::PI, 2.0 * std::f32::consts::PI / 3.0, std::f32::consts::PI / 4.0];
    let band = [0, 1, 1, 1, 2, 2, 2, 2, 2];
    let b = sh_basis(n);
    std::array::from_fn(|ch| (0..9).map(|k| a[band[k]] * sh[k][ch] * b[k]).sum::<f32>().max(0.0))
}

/// Irradiance at a surface facing `n` by summing every texel (W m^-2 in the map's unit of
/// radiance times sr).
pub fn irradiance_brute(faces: &[LinearImage], n: Vec3) -> [f32; 3] {
    let mut e = [0.0f64; 3];
    for (d, sr, c) in texels(faces) {
        let cos = n.dot(d);
        if cos > 0.0 {
            for ch in 0..3 {
                e[ch] += (c[ch] * cos * sr) as f64;
            }
        }
    }
    e.map(|v| v as f32)
}

/// The diffuse irradiance cube map, `size` texels a side, each texel the irradiance divided by pi
/// (the radiance a white Lambertian surface facing there reflects: what engines sample), summed
/// over every texel of `faces` reduced to at most 32 texels a side.
pub fn irradiance_cube(faces: &[LinearImage], size: u32) -> Vec<LinearImage> {
    let mut source = faces.to_vec();
    while source[0].width() > 32 {
        source = downsample(&source);
    }
    (0..6)
        .map(|f| {
            LinearImage::from_fn(size, size, |x, y| {
                let e = irradiance_brute(&source, texel_direction(f, x, y, size));
                image::Rgba([e[0] / std::f32::consts::PI, e[1] / std::f32::consts::PI, e[2] / std::f32::consts::PI, 1.0])
            })
        })
        .collect()
}

/// The direction of the map's brightest texel (luminance).
pub fn brightest_direction(faces: &[LinearImage]) -> Vec3 {
    texels(faces).map(|(d, _, c)| (d, 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2])).fold((Vec3::Y, f32::MIN), |best, x| if x.1 > best.1 { x } else { best }).0
}

/// The solid-angle weighted mean colour of a cube map as a sampler reads it (bilinear), over a
/// grid of `grid` texels a side: a few texels a side are too coarse a quadrature of their own
/// mean.
pub fn mean_sampled(faces: &[LinearImage], grid: u32) -> [f32; 3] {
    let mut sum = [0.0f64; 3];
    let mut total = 0.0f64;
    for f in 0..6 {
        for y in 0..grid {
            for x in 0..grid {
                let sr = texel_solid_angle(x, y, grid) as f64;
                let c = super::export::cube_lookup(faces, texel_direction(f, x, y, grid));
                for ch in 0..3 {
                    sum[ch] += c[ch] as f64 * sr;
                }
                total += sr;
            }
        }
    }
    sum.map(|v| (v / total) as f32)
}

/// The solid-angle weighted mean colour of a cube map.
pub fn mean(faces: &[LinearImage]) -> [f32; 3] {
    let mut sum = [0.0f64; 3];
    let mut total = 0.0f64;
    for (_, sr, c) in texels(faces) {
        for ch in 0..3 {
            sum[ch] += (c[ch] * sr) as f64;
        }
        total += sr as f64;
    }
    sum.map(|v| (v / total) as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A sky within the harmonics' second order: irradiance from them is exact.
    fn smooth_sky(size: u32) -> Vec<LinearImage> {
        (0..6)
            .map(|f| {
                LinearImage::from_fn(size, size, |x, y| {
                    let d = texel_direction(f, x, y, size);
                    let v = 0.5 + 0.3 * d.y + 0.1 * d.x - 0.2 * d.y * d.z + 0.15 * d.x * d.x;
                    image::Rgba([v, 1.2 * v, 1.5 * v + 0.05 * d.z, 1.0])
                })
            })
            .collect()
    }

    fn sky(size: u32) -> Vec<LinearImage> {
        // A smooth sky brighter towards +x and above the horizon, with a soft bright spot.
        let spot = Vec3::new(0.6, 0.5, -0.62).normalize();
        (0..6)
            .map(|f| {
                LinearImage::from_fn(size, size, |x, y| {
                    let d = texel_direction(f, x, y, size);
                    let s = (d.dot(spot) * 4.0 - 4.0).exp() * 2.0;
                    let base = 0.2 + 0.3 * d.y.max(0.0) + 0.1 * d.x;
                    image::Rgba([base + s, base * 1.2 + s, base * 1.5 + s, 1.0])
                })
            })
            .collect()
    }

    #[test]
    fn solid_angles_cover_the_sphere() {
        let n = 16;
        let total: f32 = (0..n).flat_map(|x| (0..n).map(move |y| texel_solid_angle(x, y, n))).sum::<f32>() * 6.0;
        assert!((total - 4.0 * std::f32::consts::PI).abs() < 1e-4, "{total}");
    }

    #[test]
    fn texel_directions_land_on_their_texels() {
        for f in 0..6 {
            for (x, y) in [(0, 0), (5, 9), (15, 15)] {
                let (face, fx, fy) = super::super::export::cube_texel(texel_direction(f, x, y, 16), 16);
                assert_eq!((face, fx.floor() as u32, fy.floor() as u32), (f, x, y));
            }
        }
    }

    #[test]
    fn harmonics_match_the_brute_force_irradiance() {
        let faces = smooth_sky(32);
        let sh = sh9(&faces);
        for n in [Vec3::Y, Vec3::X, Vec3::NEG_Z, Vec3::new(0.6, 0.5, -0.62).normalize(), Vec3::new(-0.3, 0.2, 0.9).normalize()] {
            let (a, b) = (sh_irradiance(&sh, n), irradiance_brute(&faces, n));
            for c in 0..3 {
                assert!((a[c] / b[c] - 1.0).abs() < 0.002, "{n}: {a:?} vs {b:?}");
            }
        }
    }

    #[test]
    fn prefiltering_keeps_the_energy_and_ends_in_the_cosine_lobe() {
        let faces = sky(32);
        // As export-env's default chain: down to 4 texels a side.
        let chain = prefilter_ggx(&faces, 4, 256);
        assert_eq!(chain.len(), 4);
        assert_eq!(chain[3][0].width(), 4);
        let m0 = mean_sampled(&faces, 32);
        for (l, level) in chain.iter().enumerate() {
            let m = mean_sampled(level, 32);
            for c in 0..3 {
                assert!((m[c] / m0[c] - 1.0).abs() < 0.01, "level {l}: {m:?} vs {m0:?}");
            }
        }
        // Roughness 1 is the cosine lobe: irradiance / pi.
        let roughest = &chain[3];
        for (f, face) in roughest.iter().enumerate() {
            for (x, y) in [(0, 0), (1, 2), (3, 3)] {
                let n = texel_direction(f, x, y, 4);
                let e = irradiance_brute(&faces, n);
                let p = face.get_pixel(x, y);
                for c in 0..3 {
                    assert!((p[c] / (e[c] / std::f32::consts::PI) - 1.0).abs() < 0.05, "face {f}: {p:?} vs {e:?}");
                }
            }
        }
    }
}
