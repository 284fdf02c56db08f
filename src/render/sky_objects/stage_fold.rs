//! Two texture stages of one term folded into one texture at load: a texture times a modulating
//! one, both under the mesh mapping of a dome and neither panned nor offset, is one texture over
//! the dome's texture coordinates (the built-in skydome's tiled stars times their mask). The
//! draw then samples one texture where it sampled two, and the second stage reads as white
//! without sampling (`UV_WHITE` in shaders/sky_objects/draw.wgsl). On a software rasteriser each
//! full-screen sample costs about as much as the fill-rate floor's one (docs/architecture.md).
//!
//! The folded texture holds both stages' texels: per axis, as many texels across the dome as the
//! finer stage puts there (the stars' 128 texels ten times over: 1280), so the finer stage's
//! texels land on its texels exactly and the product differs from the two samples multiplied only
//! by how the coarser one varies within one folded texel.

use std::hash::{Hash, Hasher};

use crate::sky::resolved::{Shape, Stage, StageOp, TextureImage, UvSource, Version};

/// The most texels a folded texture may have along a side; larger products stay two stages.
const MAX_SIDE: u32 = 4096;
/// The most texels a folded texture may have (16 MiB at level 0).
const MAX_TEXELS: u32 = 4096 * 1024;

/// Stage `stage + 1` of a version folded into stage `stage`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Fold {
    /// The first of the two stages: it samples the folded texture.
    pub stage: usize,
    /// Texels of the folded texture, (u, v).
    pub size: (u32, u32),
    /// Clamped where either stage is; else repeated.
    pub clamp: bool,
}

/// A stage that samples a texture of its own at fixed texture coordinates of a dome's mesh.
fn static_mesh_stage(v: &Version, k: usize) -> Option<(&Stage, &TextureImage)> {
    let s = v.stages.get(k)?;
    let gradient = v.gradients.as_ref().map(|g| g.stage);
    let fixed = s.panner == [0.0, 0.0] && s.uv_offset.is_none();
    let t = s.texture.as_deref()?;
    (matches!(s.uv, UvSource::Mesh) && fixed && gradient != Some(k)).then_some((s, t))
}

/// The folds of a version: each a stage and the modulating stage after it, both static under a
/// dome's mesh mapping and at most one with a constant colour (the folded stage takes it).
pub fn folds(v: &Version) -> Vec<Fold> {
    if !matches!(v.shape, Shape::Dome { .. } | Shape::DomeBand { .. }) {
        return Vec::new();
    }
    let mut out = Vec::new();
    let mut k = 0;
    while k + 1 < v.stages.len() {
        if let (Some((a, ta)), Some((b, tb))) = (static_mesh_stage(v, k), static_mesh_stage(v, k + 1)) {
            let side = |ta: u32, sa: f32, tb: u32, sb: f32| (ta as f32 * sa.abs()).max(tb as f32 * sb.abs()).ceil().max(1.0) as u32;
            let size = (side(ta.width, a.uv_scale[0], tb.width, b.uv_scale[0]), side(ta.height, a.uv_scale[1], tb.height, b.uv_scale[1]));
            let fits = size.0 <= MAX_SIDE && size.1 <= MAX_SIDE && size.0 * size.1 <= MAX_TEXELS;
            if b.op == StageOp::Modulate && (a.constant.is_none() || b.constant.is_none()) && fits {
                out.push(Fold { stage: k, size, clamp: a.clamp || b.clamp });
                k += 2;
                continue;
            }
        }
        k += 1;
    }
    out
}

/// The cache key and content identity of fold `f` of version `v`.
pub fn identity(v: &Version, f: &Fold) -> (String, u64) {
    let (a, b) = (&v.stages[f.stage], &v.stages[f.stage + 1]);
    let key = |s: &Stage| s.texture.as_ref().map_or(String::new(), |t| t.key.clone());
    let name = format!("fold({} x {:?} * {} x {:?})", key(a), a.uv_scale, key(b), b.uv_scale);
    let mut h = std::collections::hash_map::DefaultHasher::new();
    for s in [a, b] {
        s.texture.as_deref().map(crate::render::gpu::textures::content_hash).hash(&mut h);
        s.uv_scale.map(f32::to_bits).hash(&mut h);
        s.clamp.hash(&mut h);
    }
    f.size.hash(&mut h);
    (name, h.finish())
}

/// `img` filtered bilinearly at texture coordinates `(u, v)` at level 0, as a GPU's linear filter
/// reads it (texel centres at half-integers), repeated or clamped at the edges; values 0..1.
fn bilinear(img: &TextureImage, (u, v): (f32, f32), clamp: bool) -> [f32; 4] {
    let (w, h) = (img.width.max(1) as i64, img.height.max(1) as i64);
    let index = |i: i64, n: i64| if clamp { i.clamp(0, n - 1) } else { i.rem_euclid(n) };
    let (x, y) = (u * w as f32 - 0.5, v * h as f32 - 0.5);
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let texel = |i: i64, j: i64| {
        let at = ((index(j, h) * w + index(i, w)) * 4) as usize;
        std::array::from_fn::<f32, 4, _>(|c| f32::from(img.rgba8.get(at + c).copied().unwrap_or(255)) / 255.0)
    };
    let (x0, y0) = (x0 as i64, y0 as i64);
    let (t00, t10, t01, t11) = (texel(x0, y0), texel(x0 + 1, y0), texel(x0, y0 + 1), texel(x0 + 1, y0 + 1));
    std::array::from_fn(|c| {
        let top = t00[c] + (t10[c] - t00[c]) * fx;
        let bottom = t01[c] + (t11[c] - t01[c]) * fx;
        top + (bottom - top) * fy
    })
}

/// The folded texture of fold `f` of version `v`: at each of its texel centres, the first stage's
/// texture at its coordinates times the second's at theirs.
pub fn bake(v: &Version, f: &Fold, key: &str) -> TextureImage {
    let (a, b) = (&v.stages[f.stage], &v.stages[f.stage + 1]);
    let (w, h) = f.size;
    let mut rgba8 = Vec::with_capacity((w * h * 4) as usize);
    let (Some(ta), Some(tb)) = (a.texture.as_deref(), b.texture.as_deref()) else {
        return TextureImage { key: key.to_string(), width: 1, height: 1, rgba8: vec![255; 4] };
    };
    for j in 0..h {
        let mv = (j as f32 + 0.5) / h as f32;
        for i in 0..w {
            let mu = (i as f32 + 0.5) / w as f32;
            let x = bilinear(ta, (mu * a.uv_scale[0], mv * a.uv_scale[1]), a.clamp);
            let y = bilinear(tb, (mu * b.uv_scale[0], mv * b.uv_scale[1]), b.clamp);
            rgba8.extend((0..4).map(|c| (x[c] * y[c] * 255.0).round().clamp(0.0, 255.0) as u8));
        }
    }
    TextureImage { key: key.to_string(), width: w, height: h, rgba8 }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sky::builtin::default_sky;

    fn version_of(name: &str) -> Version {
        default_sky().objects.iter().find(|o| o.name == name).map(|o| o.standard.clone()).expect("built-in object")
    }

    #[test]
    fn the_skydome_folds_its_stars_and_mask_and_nothing_else_folds() {
        let sky = default_sky();
        for o in &sky.objects {
            for v in std::iter::once(&o.standard).chain(&o.fallback) {
                let f = folds(v);
                if o.name == "skydome" && v.stages.len() > 2 {
                    // Stars (128 x 128, ten by five times) times their mask.
                    assert_eq!(f, vec![Fold { stage: 1, size: (1280, 640), clamp: false }], "{}", o.name);
                } else if o.name == "skydome" {
                    assert!(f.len() <= 1, "{}", o.name);
                } else {
                    // Billboards, the galaxy (celestial mapping), panned clouds.
                    assert!(f.is_empty(), "{} folds {f:?}", o.name);
                }
            }
        }
    }

    #[test]
    fn the_folded_texture_is_the_product_of_the_two_samples() {
        let v = version_of("skydome");
        let f = folds(&v)[0];
        let (key, _) = identity(&v, &f);
        let baked = bake(&v, &f, &key);
        assert_eq!((baked.width, baked.height), f.size);
        let (a, b) = (&v.stages[f.stage], &v.stages[f.stage + 1]);
        let mut rng = fastrand::Rng::with_seed(5);
        let mut worst = 0.0f32;
        for _ in 0..2000 {
            // Anywhere on the dome's texture coordinates, between texel centres too.
            let (mu, mv) = (rng.f32(), rng.f32());
            let x = bilinear(a.texture.as_deref().expect("stars"), (mu * a.uv_scale[0], mv * a.uv_scale[1]), a.clamp);
            let y = bilinear(b.texture.as_deref().expect("mask"), (mu * b.uv_scale[0], mv * b.uv_scale[1]), b.clamp);
            let folded = bilinear(&baked, (mu, mv), f.clamp);
            for c in 0..4 {
                worst = worst.max((x[c] * y[c] - folded[c]).abs());
            }
        }
        // The stars' texels land on the folded texels, so only the mask's variation across one
        // folded texel and the 8-bit rounding remain: a few levels of 255 at most.
        assert!(worst * 255.0 <= 3.0, "worst difference {:.2} levels", worst * 255.0);
    }

    #[test]
    fn panned_or_unmapped_stages_do_not_fold() {
        let mut v = version_of("skydome");
        v.stages[2].panner = [0.1, 0.0];
        assert!(folds(&v).is_empty());
        let mut v = version_of("skydome");
        v.stages[1].uv = UvSource::Celestial;
        assert!(folds(&v).is_empty());
        let mut v = version_of("skydome");
        v.stages[2].op = StageOp::Add;
        assert!(folds(&v).is_empty());
    }
}
