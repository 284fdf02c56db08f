//! Two texture stages of one term folded into one texture at load: a texture times a modulating
//! one, both under the same mesh or cloud-layer mapping of a dome and neither panned nor offset,
//! is one texture over those coordinates (the built-in skydome's tiled stars times their mask). The
//! draw then samples one texture where it sampled two, and the second stage reads as white
//! without sampling (`UV_WHITE` in shaders/sky_objects/draw.wgsl). On a software rasteriser each
//! full-screen sample costs about as much as the fill-rate floor's one (docs/architecture.md).
//!
//! The folded texture holds both stages' texels: per axis, as many texels across the dome as the
//! finer stage puts there (the stars' 128 texels ten times over: 1280), so the finer stage's
//! texels land on its texels exactly and the product differs from the two samples multiplied only
//! by how the coarser one varies within one folded texel.
//!
//! Under the layer mapping the coordinates are a plane's, unbounded, and the two stages' repeats
//! need not share a period: the folded texture covers the square of the plane the dome sees
//! ([`Fold::half_extent`], with a margin), centred on the zenith and rolled by half a turn so that
//! it repeats with its seam outside the dome. A layer's horizon fade would multiply the product
//! once where the two stages had it twice: only layers without a fade fold.

use std::hash::{Hash, Hasher};

use crate::render::sky_objects::layer_map::{layer_params, LayerParams};
use crate::sky::resolved::{Shape, Stage, StageOp, TextureImage, UvSource, Version};

/// The most texels a folded texture may have along a side; larger products stay two stages.
const MAX_SIDE: u32 = 4096;
/// The most texels a folded texture may have (16 MiB at level 0).
const MAX_TEXELS: u32 = 4096 * 1024;

/// Stage `stage + 1` of a version folded into stage `stage`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fold {
    /// The first of the two stages: it samples the folded texture.
    pub stage: usize,
    /// Texels of the folded texture, (u, v).
    pub size: (u32, u32),
    /// Clamped where either stage is; else repeated.
    pub clamp: bool,
    /// Under the layer mapping: half the sides (u, v) of the rectangle of the layer's
    /// coordinates the folded texture covers (the folded stage scales the coordinates by
    /// `1 / (2 half_extent)`), each a whole number of the finer stage's texels, so that its texels
    /// land on the folded ones. None under the mesh mapping, whose coordinates span one repeat of
    /// the folded texture.
    pub half_extent: Option<[f32; 2]>,
}

impl Fold {
    /// The folded stage's scale of its mapping's coordinates (its offset is zero).
    pub fn uv_scale(&self) -> [f32; 2] {
        self.half_extent.map_or([1.0, 1.0], |e| [0.5 / e[0], 0.5 / e[1]])
    }
}

/// Folded texels a layer's square leaves outside the dome at each side: the bilinear tent of a
/// texel and a little more, so that neither its repeat nor its clamp is ever read.
const LAYER_MARGIN_TEXELS: f32 = 2.0;

/// The largest horizontal displacement, in the layer's coordinates, of any direction of `shape`
/// on layer `p`: the bottom ring's (the displacement grows downwards until the ray meets the
/// layer level with its centre, below any dome's bottom), sampled densely to be sure.
fn layer_reach(p: &LayerParams, shape: &Shape) -> Option<f64> {
    let (bottom_deg, top_deg) = match *shape {
        Shape::Dome { bottom_deg } => (bottom_deg.get(), 90.0),
        Shape::DomeBand { bottom_deg, top_deg } => (bottom_deg.get(), top_deg.get()),
        Shape::Billboard { .. } | Shape::Quad { .. } => return None,
    };
    let (lo, hi) = (f64::from(bottom_deg.min(top_deg)), f64::from(bottom_deg.max(top_deg)));
    Some((0..=256).map(|i| (lo + (hi - lo) * f64::from(i) / 256.0).to_radians()).map(|e| p.distance([e.cos(), e.sin(), 0.0]) * e.cos()).fold(0.0, f64::max))
}

/// A stage that samples a texture of its own at fixed coordinates of a dome's mesh, or of a
/// cloud layer without a fade.
fn static_stage(v: &Version, k: usize) -> Option<(&Stage, &TextureImage)> {
    let s = v.stages.get(k)?;
    let gradient = v.gradients.as_ref().map(|g| g.stage);
    let fixed = s.panner == [0.0, 0.0] && s.uv_offset.is_none();
    let t = s.texture.as_deref()?;
    let mapped = match s.uv {
        UvSource::Mesh => true,
        UvSource::Layer { .. } => layer_params(s.uv).is_some_and(|p| p.fade_sin <= 0.0),
        _ => false,
    };
    (mapped && fixed && gradient != Some(k)).then_some((s, t))
}

/// The folds of a version: each a stage and the modulating stage after it, both static under the
/// same mapping of a dome (its mesh's, or one cloud layer's without a fade) and at most one with
/// a constant colour (the folded stage takes it).
pub fn folds(v: &Version) -> Vec<Fold> {
    if !matches!(v.shape, Shape::Dome { .. } | Shape::DomeBand { .. }) {
        return Vec::new();
    }
    let mut out = Vec::new();
    let mut k = 0;
    while k + 1 < v.stages.len() {
        if let (Some((a, ta)), Some((b, tb))) = (static_stage(v, k), static_stage(v, k + 1)) {
            // Texels per unit of the mapping's coordinates.
            let density = |ta: u32, sa: f32, tb: u32, sb: f32| (ta as f32 * sa.abs()).max(tb as f32 * sb.abs());
            let (du, dv) = (density(ta.width, a.uv_scale[0], tb.width, b.uv_scale[0]), density(ta.height, a.uv_scale[1], tb.height, b.uv_scale[1]));
            // The texture's extent and size: one repeat of the mesh's coordinates; under a layer,
            // the dome's reach and the margin, rounded up to whole texels of the finer stage.
            let whole = |reach: f32, d: f32| (2.0 * (reach + LAYER_MARGIN_TEXELS / d.max(1e-6)) * d).ceil() / (2.0 * d.max(1e-6));
            let side = |texels: f32| texels.round().clamp(1.0, u32::MAX as f32) as u32;
            let folded = match (a.uv, layer_params(a.uv)) {
                (UvSource::Layer { .. }, Some(p)) if a.uv == b.uv && !(a.clamp || b.clamp) => layer_reach(&p, &v.shape).map(|reach| {
                    let e = [whole(reach as f32, du), whole(reach as f32, dv)];
                    (Some(e), (side(2.0 * e[0] * du), side(2.0 * e[1] * dv)))
                }),
                (UvSource::Mesh, _) if b.uv == UvSource::Mesh => Some((None, (side(du.ceil()), side(dv.ceil())))),
                _ => None,
            };
            let Some((half_extent, size)) = folded else {
                k += 1;
                continue;
            };
            let fits = size.0 <= MAX_SIDE && size.1 <= MAX_SIDE && size.0 * size.1 <= MAX_TEXELS;
            if b.op == StageOp::Modulate && (a.constant.is_none() || b.constant.is_none()) && fits {
                out.push(Fold { stage: k, size, clamp: a.clamp || b.clamp, half_extent });
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
    let name = format!("fold({} x {:?} * {} x {:?} on {:?})", key(a), a.uv_scale, key(b), b.uv_scale, a.uv);
    let mut h = std::collections::hash_map::DefaultHasher::new();
    for s in [a, b] {
        s.texture.as_deref().map(crate::render::gpu::textures::content_hash).hash(&mut h);
        s.uv_scale.map(f32::to_bits).hash(&mut h);
        s.clamp.hash(&mut h);
    }
    f.size.hash(&mut h);
    f.half_extent.map(|e| e.map(f32::to_bits)).hash(&mut h);
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

/// The mapping's coordinate along `axis` (0: u, 1: v) at folded texture coordinate `t` (0..1) of
/// fold `f`: the same under the mesh mapping; under a layer's, the rectangle of sides
/// `2 half_extent` rolled by half a turn, so that the layer's origin (the zenith) lies at 0 and
/// repeating the texture is the identity.
pub fn mapped_at(f: &Fold, axis: usize, t: f32) -> f32 {
    match f.half_extent {
        Some(e) => (((t + 0.5).fract()) - 0.5) * 2.0 * e[axis],
        None => t,
    }
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
        let mv = mapped_at(f, 1, (j as f32 + 0.5) / h as f32);
        for i in 0..w {
            let mu = mapped_at(f, 0, (i as f32 + 0.5) / w as f32);
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

    /// The built-in skydome's folded stars and mask, texels: 2 x (3.17 + 2 / 128) repeats of the
    /// stars' layer at 128 texels a repeat, the dome's reach at -20 degrees and the margin.
    const SKYDOME_FOLD: (u32, u32) = (816, 816);

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
                    // Stars (128 x 128 a repeat of their layer) times their mask, over the dome's
                    // reach and the margin in whole stars' texels.
                    assert_eq!(f.iter().map(|f| (f.stage, f.size, f.clamp)).collect::<Vec<_>>(), vec![(1, SKYDOME_FOLD, false)], "{}", o.name);
                } else if o.name == "skydome" {
                    assert!(f.len() <= 1, "{}", o.name);
                } else {
                    // Billboards, the galaxy (celestial mapping), panned clouds.
                    assert!(f.is_empty(), "{} folds {f:?}", o.name);
                }
            }
        }
    }

    /// The skydome's version with its stars and mask under the mesh mapping instead.
    fn under_the_mesh(mut v: Version) -> Version {
        for k in [1, 2] {
            v.stages[k].uv = UvSource::Mesh;
            v.stages[k].uv_scale = [[10.0, 5.0], [1.7, 1.3]][k - 1];
        }
        v
    }

    #[test]
    fn the_folded_texture_is_the_product_of_the_two_samples() {
        for (what, v) in [("layer", version_of("skydome")), ("mesh", under_the_mesh(version_of("skydome")))] {
            let f = folds(&v)[0];
            assert_eq!(f.half_extent.is_some(), what == "layer");
            let (key, _) = identity(&v, &f);
            let baked = bake(&v, &f, &key);
            assert_eq!((baked.width, baked.height), f.size);
            let (a, b) = (&v.stages[f.stage], &v.stages[f.stage + 1]);
            let mut rng = fastrand::Rng::with_seed(5);
            let mut worst = 0.0f32;
            for _ in 0..2000 {
                // Anywhere the folded texture covers, between texel centres too (under a layer,
                // not in its margin, where the roll joins its far sides).
                let (fu, fv) = match f.half_extent {
                    Some(_) => (((0.9 * rng.f32() - 0.45) + 1.0).fract(), ((0.9 * rng.f32() - 0.45) + 1.0).fract()),
                    None => (rng.f32(), rng.f32()),
                };
                let (mu, mv) = (mapped_at(&f, 0, fu), mapped_at(&f, 1, fv));
                let x = bilinear(a.texture.as_deref().expect("stars"), (mu * a.uv_scale[0], mv * a.uv_scale[1]), a.clamp);
                let y = bilinear(b.texture.as_deref().expect("mask"), (mu * b.uv_scale[0], mv * b.uv_scale[1]), b.clamp);
                let folded = bilinear(&baked, (fu, fv), f.clamp);
                for c in 0..4 {
                    worst = worst.max((x[c] * y[c] - folded[c]).abs());
                }
            }
            // The stars' texels land on the folded texels, so only the mask's variation across one
            // folded texel and the 8-bit rounding remain: a few levels of 255 at most.
            assert!(worst * 255.0 <= 3.0, "{what}: worst difference {:.2} levels", worst * 255.0);
        }
    }

    #[test]
    fn a_layer_fold_covers_the_dome_with_its_margin() {
        let v = version_of("skydome");
        let f = folds(&v)[0];
        let e = f.half_extent.expect("a layer fold");
        let p = layer_params(v.stages[1].uv).expect("a layer");
        // The stars' texels (128 per unit of the layer's coordinates) land on the folded ones: a
        // whole number of them across.
        for axis in 0..2 {
            let across = 2.0 * e[axis] * 128.0 * v.stages[1].uv_scale[axis];
            assert!((across - [f.size.0, f.size.1][axis] as f32).abs() < 1e-3, "axis {axis}: {across} stars' texels over {:?}", f.size);
        }
        // Every direction of the dome lands inside the rectangle, at least the margin from its edge.
        let texel = [2.0 * e[0] / f.size.0 as f32, 2.0 * e[1] / f.size.1 as f32];
        for el in (-20..=90).map(f64::from) {
            for az in (0..360).step_by(5).map(f64::from) {
                let (er, ar) = (el.to_radians(), az.to_radians());
                let uv = p.uv([er.cos() * ar.sin(), er.sin(), er.cos() * ar.cos()]);
                assert!((0..2).all(|k| uv[k].abs() as f32 <= e[k] - 1.9 * texel[k]), "{el}, {az}: {uv:?} beyond {e:?}");
            }
        }
        // And not much more: the bottom ring reaches within a few texels of the edge.
        let reach = p.distance([20f64.to_radians().cos(), -20f64.to_radians().sin(), 0.0]) * 20f64.to_radians().cos();
        assert!((0..2).all(|k| (e[k] - reach as f32) < 3.5 * texel[k]), "half extent {e:?}, reach {reach}");
    }

    #[test]
    fn panned_or_unmapped_stages_do_not_fold() {
        let mut v = version_of("skydome");
        v.stages[2].panner = [0.1, 0.0];
        assert!(folds(&v).is_empty());
        let mut v = version_of("skydome");
        v.stages[1].uv = UvSource::Celestial;
        assert!(folds(&v).is_empty());
        // Two different layers, or one with a fade, do not fold.
        let mut v = version_of("skydome");
        v.stages[1].uv = UvSource::Mesh;
        assert!(folds(&v).is_empty());
        let mut v = version_of("skydome");
        if let UvSource::Layer { horizon_fade_deg, .. } = &mut v.stages[1].uv {
            horizon_fade_deg.0 = 5.0;
        }
        v.stages[2].uv = v.stages[1].uv;
        assert!(folds(&v).is_empty());
        let mut v = version_of("skydome");
        v.stages[2].op = StageOp::Add;
        assert!(folds(&v).is_empty());
    }
}
