//! Texel density and level-of-detail bounds: how many texels per degree a stage puts on the
//! screen (pure functions of the stage, the shape and the view), which decide each stage's mip
//! choice and each layer's resolution.

#[allow(unused_imports)]
use super::*;

/// The finest detail a stage's texture puts on the sky, texels per degree of view direction:
/// what a buffer needs at least to show it. The gradient stage (no texture) varies only slowly,
/// by elevation.
pub(super) fn stage_texels_per_deg(stage: &crate::sky::resolved::Stage, shape: &Shape) -> f32 {
    let Some(t) = &stage.texture else { return 0.0 };
    let (w, h) = (t.width as f32 * stage.uv_scale[0].abs(), t.height as f32 * stage.uv_scale[1].abs());
    let (bottom_deg, top_deg) = match *shape {
        Shape::Dome { bottom_deg } => (bottom_deg.get(), 90.0),
        Shape::DomeBand { bottom_deg, top_deg } => (bottom_deg.get(), top_deg.get()),
        Shape::Billboard { size_deg } | Shape::Quad { size_deg } => (0.0, size_deg.get()),
    };
    let span_deg = (top_deg - bottom_deg).abs().max(1e-3);
    match stage.uv {
        UvSource::Mesh => (w / 360.0).max(h / span_deg),
        UvSource::Sun { size_deg } => w.max(h) / size_deg.get().abs().max(1e-3),
        UvSource::Celestial => (w / 360.0).max(h / 180.0),
        UvSource::Quake { z_scale, z_offset, t_scale, .. } => {
            w.max(h) * quake_uv_per_rad(z_scale.get(), z_offset.get(), t_scale.get(), bottom_deg.min(top_deg), bottom_deg.max(top_deg)).to_radians()
        }
        // Densest at the horizon, where the fade takes most of the texture's contrast away: the
        // detail that reaches the image is the density times the fade.
        UvSource::Layer { .. } => match (layer_params(stage.uv), shape) {
            (Some(p), Shape::Dome { .. } | Shape::DomeBand { .. }) => w.max(h) * (p.steepest(bottom_deg, top_deg, |e| p.fade_at(e)) as f32).to_radians(),
            _ => f32::INFINITY,
        },
    }
}

/// How much larger a stage's computed peak texel density may be than the level-of-detail the
/// rasteriser derives (from differences across 2x2 pixels, along triangles' chords rather than
/// arcs) before a level-0 sampler could differ from the mipmapped one.
pub(super) const LOD_MARGIN: f32 = 1.25;
/// The further margin of a cloud layer's coordinates interpolated per vertex, whose rate over the
/// grid's chords of the layer departs from the layer's own in places: found by tests/skips.rs (at
/// 1.0 a level-0 sampler moved 0.04% of the pixels at dusk looking up), not derived.
pub(super) const PER_VERTEX_LOD_MARGIN: f32 = 1.2;

/// Each stage's finest detail (texels per degree) where a frame showing elevations `shown_deg`
/// (lowest, highest) draws a dome on `grid`: its peak density over the rings in view
/// ([`StageMap::ring_peaks`]) over its oversampling, where that is less than `whole` (over the
/// whole shape, as [`stage_texels_per_deg`] bounds it, over the same oversampling). A cloud
/// layer's texels crowd towards the horizon, so a frame looking up can draw it in a coarser
/// buffer. As dense as what the frame shows or denser: a ring's peak covers all of the ring, and
/// a layer's horizon fade, which `whole` counts, only lowers the detail. Stage `keep` (the sparse
/// one drawn texel by texel: its polygons go at full resolution, where a reduced buffer would
/// blur its points) and stages without ring peaks keep `whole`.
pub(super) fn texels_per_deg_shown(
    maps: &[Option<StageMap>; MAX_STAGES],
    (whole, oversampling): ([f32; MAX_STAGES], [f32; MAX_STAGES]),
    keep: Option<usize>,
    grid: DomeGrid,
    (lowest_deg, highest_deg): (f32, f32),
) -> [f32; MAX_STAGES] {
    std::array::from_fn(|k| match &maps[k] {
        Some(m) if m.ring_peaks.len() == grid.rings as usize && keep != Some(k) => {
            let shown = (0..grid.rings).filter(|&r| grid.ring_shown(r, lowest_deg, highest_deg));
            let peak = shown.map(|r| m.ring_peaks[r as usize]).fold(0.0, f32::max);
            whole[k].min(peak / oversampling[k].max(1.0))
        }
        _ => whole[k],
    })
}

/// What the frame shows, for bounding how finely a texture lands on its pixels.
pub(super) struct FrameView {
    /// Lowest and highest elevation in the frame, degrees.
    pub(super) elevation_deg: (f32, f32),
    /// Largest angle between the sun and a direction in the frame, degrees.
    pub(super) sun_max_deg: f32,
    /// Half the frame's vertical field of view, radians.
    pub(super) half_fov_y: f32,
    /// A lower bound of the angle between the frame and the nearer pole of the celestial
    /// mapping's texture (where its columns converge), degrees.
    pub(super) celestial_pole_deg: f32,
}

impl FrameView {
    pub(super) fn new(camera: &Camera, aspect: f32, elevation_deg: (f32, f32), towards_sun: Vec3, celestial_from_world: Quat) -> Self {
        let half_fov_y = (camera.fov_y_deg.to_radians() * 0.5).min(1.55);
        let t = half_fov_y.tan();
        let half_diagonal = (t * t * (1.0 + aspect * aspect)).sqrt().atan();
        let to_sun = camera.forward().dot(towards_sun.normalize_or_zero()).clamp(-1.0, 1.0).acos();
        // The mapping's latitude is that of the celestial frame's y axis (shaders/sky_objects/material.wgsl,
        // `celestial_uv`). The largest cone round each pole that the frame does not show, by
        // bisection: `sees_cone` only errs towards showing.
        let north = celestial_from_world.inverse() * Vec3::Y;
        let unseen = |r: f32| !camera.sees_cone(aspect, north, r) && !camera.sees_cone(aspect, -north, r);
        let mut celestial_pole_deg = 0.0;
        if unseen(0.0) {
            let mut above = 90.0;
            for _ in 0..12 {
                let mid = 0.5 * (celestial_pole_deg + above);
                if unseen(mid) {
                    celestial_pole_deg = mid;
                } else {
                    above = mid;
                }
            }
        }
        Self { elevation_deg, sun_max_deg: (to_sun + half_diagonal).to_degrees().min(180.0), half_fov_y, celestial_pole_deg }
    }

    /// Pixels per degree of view direction at the frame's centre for a frame `height_px` high.
    pub(super) fn centre_px_per_deg(&self, height_px: u32) -> f32 {
        height_px as f32 * 0.5 / self.half_fov_y.tan() * std::f32::consts::PI / 180.0
    }
}

/// How one stage's texture lies on the sky: its mapping and its size in texels across one
/// repeat of the mapping, times the stage's repeats (u, v).
#[derive(Debug, Clone)]
pub(super) struct StageMap {
    pub(super) uv: UvSource,
    pub(super) texels: (f32, f32),
    /// On a dome, under the mesh, Quake or layer mapping: the peak density over each ring of
    /// triangles (top first), which does not depend on the view (the Quake and layer mappings'
    /// take a dense search: computed once, not every frame).
    pub(super) ring_peaks: Vec<f32>,
}

impl StageMap {
    /// None for a stage without a texture of its own (the gradient: one texel wide, no levels).
    pub(super) fn of(stage: &crate::sky::resolved::Stage, shape: &Shape) -> Option<Self> {
        let t = stage.texture.as_ref()?;
        Some(Self::with_texels(stage.uv, (t.width as f32 * stage.uv_scale[0].abs(), t.height as f32 * stage.uv_scale[1].abs()), shape))
    }

    /// A texture `texels` across one repeat of mapping `uv` on `shape`.
    pub(super) fn with_texels(uv: UvSource, texels: (f32, f32), shape: &Shape) -> Self {
        let mut map = Self { uv, texels, ring_peaks: Vec::new() };
        if let (UvSource::Mesh | UvSource::Quake { .. } | UvSource::Layer { .. }, Some((top_deg, bottom_deg, rings, _))) = (uv, crate::render::gpu::mesh::dome_grid(shape)) {
            map.ring_peaks = (0..rings)
                .map(|r| {
                    let (a, b) = (top_deg + (bottom_deg - top_deg) * r as f32 / rings as f32, top_deg + (bottom_deg - top_deg) * (r + 1) as f32 / rings as f32);
                    // A view of just this ring (neither mapping looks at the sun or the frame).
                    map.peak_texels_per_deg(shape, &FrameView { elevation_deg: (a.min(b), a.max(b)), sun_max_deg: 180.0, half_fov_y: 0.0, celestial_pole_deg: 0.0 })
                })
                .collect();
        }
        map
    }

    /// [`Self::peak_texels_per_deg`] over ring `ring` of a dome's triangles (all of it, where the
    /// frame shows part: as high or higher), or over what `view` shows of the shape.
    pub(super) fn peak(&self, shape: &Shape, ring: Option<usize>, view: &FrameView) -> f32 {
        match ring.and_then(|r| self.ring_peaks.get(r)) {
            Some(&peak) => peak,
            None => self.peak_texels_per_deg(shape, view),
        }
    }

    /// The most texels of this stage that one degree of view direction crosses anywhere `view`
    /// shows of `shape`, along any screen direction (infinite where unbounded: the celestial
    /// mapping's poles, the antisolar point of a repeating sun mapping).
    pub(super) fn peak_texels_per_deg(&self, shape: &Shape, view: &FrameView) -> f32 {
        let (w, h) = self.texels;
        let (lo, hi) = view.elevation_deg;
        match self.uv {
            UvSource::Mesh => match crate::render::gpu::mesh::dome_grid(shape) {
                // u runs once round the azimuth, v once from the top ring to the bottom one. Along
                // a ring a degree of view crosses 1 / cos(elevation) degrees of azimuth. Each band
                // of triangles between two rings spans a chord of both; the triangles round a pole
                // are spanned by the ring next to it.
                Some((top_deg, bottom_deg, rings, _)) => {
                    let (shape_lo, shape_hi) = (bottom_deg.min(top_deg), bottom_deg.max(top_deg));
                    let (a, b) = (lo.max(shape_lo), hi.min(shape_hi));
                    if a > b {
                        return 0.0;
                    }
                    let step = ((shape_hi - shape_lo) / rings as f32).max(1e-3);
                    let ring_lo = shape_lo + ((a - shape_lo) / step).floor() * step;
                    let ring_hi = (shape_lo + ((b - shape_lo) / step).ceil() * step).min(shape_hi);
                    let inward = |e: f32| if e.abs() >= 90.0 - 1e-3 { e - step * e.signum() } else { e };
                    let steepest = inward(ring_lo).abs().max(inward(ring_hi).abs()).min(89.9);
                    let along = w / 360.0 / steepest.to_radians().cos();
                    let across = h / (shape_hi - shape_lo).max(1e-3);
                    along.max(across)
                }
                // A square size_deg across, flat at its distance: a texel is smaller in angle
                // away from its centre (by cos^2 at the corners, half a diagonal out).
                None => {
                    let size_deg = match *shape {
                        Shape::Billboard { size_deg } | Shape::Quad { size_deg } => size_deg.get(),
                        _ => return f32::INFINITY,
                    };
                    let half_diagonal = (size_deg * 0.5 * std::f32::consts::SQRT_2).to_radians();
                    if half_diagonal >= 1.5 {
                        return f32::INFINITY;
                    }
                    w.max(h) / size_deg / half_diagonal.cos().powi(2)
                }
            },
            // Distance from the sun maps linearly to radius, size_deg across; round the sun a
            // degree of view crosses angle / sin(angle) degrees of that map.
            UvSource::Sun { size_deg } => {
                let angle = view.sun_max_deg.to_radians();
                if angle >= std::f32::consts::PI - 0.02 {
                    return f32::INFINITY;
                }
                let stretch = if angle > 1e-3 { (angle / angle.sin()).max(1.0) } else { 1.0 };
                w.max(h) / size_deg.get().abs().max(1e-3) * stretch
            }
            // Plate carree: along a circle of latitude a degree of view crosses 1 / cos(latitude)
            // degrees of longitude, most near a pole.
            UvSource::Celestial => {
                let from_pole = view.celestial_pole_deg.to_radians().sin();
                if from_pole < 1e-3 {
                    return f32::INFINITY;
                }
                (w / 360.0 / from_pole).max(h / 180.0)
            }
            UvSource::Quake { z_scale, z_offset, t_scale, .. } => {
                let (shape_lo, shape_hi) = match *shape {
                    Shape::Dome { bottom_deg } => (bottom_deg.get(), 90.0),
                    Shape::DomeBand { bottom_deg, top_deg } => (bottom_deg.get().min(top_deg.get()), bottom_deg.get().max(top_deg.get())),
                    Shape::Billboard { .. } | Shape::Quad { .. } => return f32::INFINITY,
                };
                let (a, b) = (lo.max(shape_lo), hi.min(shape_hi));
                if a > b {
                    return 0.0;
                }
                w.max(h) * quake_uv_per_rad(z_scale.get(), z_offset.get(), t_scale.get(), a, b).to_radians()
            }
            // Where texels land on pixels, faded or not.
            UvSource::Layer { .. } => {
                let (Some(p), Some((top_deg, bottom_deg, _, _))) = (layer_params(self.uv), crate::render::gpu::mesh::dome_grid(shape)) else { return f32::INFINITY };
                let (a, b) = (lo.max(bottom_deg.min(top_deg)), hi.min(bottom_deg.max(top_deg)));
                if a > b {
                    return 0.0;
                }
                w.max(h) * (p.steepest(a, b, |_| 1.0) as f32).to_radians()
            }
        }
    }
}

/// The Quake sky's mapping (`stage_uv` in shaders/sky_objects/material.wgsl: the direction's y scaled by
/// `z_scale` and moved by `z_offset`, then uv = t_scale x xz / length) at its steepest over the
/// elevations `bottom_deg..top_deg`: texture-coordinate units per radian of view direction. At
/// elevation e the ring of directions lands on a circle of radius t cos(e) / L(e), with
/// L(e) = sqrt(cos^2 e + (z sin e + o)^2): along the ring that is t / L(e) per radian, across it
/// t |d/de (cos e / L(e))|. Sampled densely (the derivative by central differences); the shader's
/// floor on L bounds it where L vanishes.
pub(super) fn quake_uv_per_rad(z_scale: f32, z_offset: f32, t_scale: f32, bottom_deg: f32, top_deg: f32) -> f32 {
    let (z, o, t) = (z_scale as f64, z_offset as f64, t_scale.abs() as f64);
    let radius = |e: f64| e.cos() / (e.cos().powi(2) + (z * e.sin() + o).powi(2)).sqrt().max(1e-4);
    pub(super) const SAMPLES: u32 = 512;
    let (lo, hi) = ((bottom_deg as f64).to_radians(), (top_deg as f64).to_radians());
    let step = (hi - lo) / SAMPLES as f64;
    let h = 1e-4;
    let mut steepest: f64 = 0.0;
    for i in 0..=SAMPLES {
        let e = lo + step * i as f64;
        let l = (e.cos().powi(2) + (z * e.sin() + o).powi(2)).sqrt().max(1e-4);
        let across = ((radius(e + h) - radius(e - h)) / (2.0 * h)).abs();
        steepest = steepest.max(1.0 / l).max(across);
    }
    (t * steepest) as f32
}

/// How much finer a texture's texels are than the detail it carries: 2^k for the largest k (at
/// most 4) such that halving it k times and scaling it back up (box down, bilinear up, as a
/// reduced buffer would show it) changes 99% of its channel values by at most
/// [`DETAIL_TOLERANCE`] levels of 255. Soft cloud noise drops levels; a star field does not.
pub fn texture_oversampling(img: &TextureImage) -> f32 {
    use image::imageops::{resize, FilterType};
    let Some(full) = image::RgbaImage::from_raw(img.width, img.height, img.rgba8.clone()) else { return 1.0 };
    let mut factor = 1.0;
    for k in 1..=4u32 {
        let (w, h) = (img.width >> k, img.height >> k);
        if w < 2 || h < 2 {
            break;
        }
        let back = resize(&resize(&full, w, h, FilterType::Triangle), img.width, img.height, FilterType::Triangle);
        let mut diffs: Vec<u8> = full.as_raw().iter().zip(back.as_raw()).map(|(a, b)| a.abs_diff(*b)).collect();
        let at = diffs.len() * 99 / 100;
        let (_, p99, _) = diffs.select_nth_unstable(at);
        if *p99 > DETAIL_TOLERANCE {
            break;
        }
        factor = (1u32 << k) as f32;
    }
    factor
}

/// Levels of 255 a texture may lose in 99% of its values and still count as carried by a
/// coarser sampling ([`texture_oversampling`]).
pub const DETAIL_TOLERANCE: u8 = 4;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::gpu::mesh::dome_grid;
    use crate::sky::builtin::default_sky;

    #[test]
    fn a_layer_looking_up_is_coarser_than_across_the_horizon_and_never_coarser_than_shown() {
        // The built-in clear-weather clouds: two stages on a layer 2 km up round a 4 km planet.
        let sky = default_sky();
        let v = &sky.objects.iter().find(|o| o.name == "clouds_clear").expect("the clouds").standard;
        let maps: [Option<StageMap>; MAX_STAGES] = std::array::from_fn(|k| v.stages.get(k).and_then(|s| StageMap::of(s, &v.shape)));
        let whole: [f32; MAX_STAGES] = std::array::from_fn(|k| v.stages.get(k).map_or(0.0, |s| stage_texels_per_deg(s, &v.shape)));
        let detail = (whole, [1.0; MAX_STAGES]);
        let grid = DomeGrid::from_tuple(dome_grid(&v.shape).expect("a dome"));
        // Across the horizon (the bench's view, -30 to 38 degrees): the whole dome's.
        assert_eq!(texels_per_deg_shown(&maps, detail, None, grid, (-30.0, 38.0)), whole);
        // Looking up (the zenith preset shows 34.5 to 90 degrees): measured 0.662 of it for both.
        let up = texels_per_deg_shown(&maps, detail, None, grid, (34.5, 90.0));
        for k in 0..2 {
            let ratio = up[k] / whole[k];
            assert!((0.64..0.68).contains(&ratio), "stage {k}: {ratio}");
        }
        // The stage drawn texel by texel keeps the whole dome's.
        assert_eq!(texels_per_deg_shown(&maps, detail, Some(1), grid, (34.5, 90.0))[1], whole[1]);
        // Never less than the exact peak over what a frame shows, nor more than the whole dome's.
        for lo in (-25..=85).step_by(5) {
            let shown_deg = (lo as f32, (lo as f32 + 30.0).min(90.0));
            let shown = texels_per_deg_shown(&maps, detail, None, grid, shown_deg);
            let view = FrameView { elevation_deg: shown_deg, sun_max_deg: 180.0, half_fov_y: 0.0, celestial_pole_deg: 0.0 };
            for k in 0..2 {
                let exact = maps[k].as_ref().expect("a texture").peak_texels_per_deg(&v.shape, &view);
                assert!(shown[k] >= exact * 0.999 && shown[k] <= whole[k], "{shown_deg:?}, stage {k}: {} against {exact}, whole {}", shown[k], whole[k]);
            }
        }
    }
}
