//! The choice of resolution: how finely each dome layer is drawn this frame, from the texel
//! density of the stages it samples and the strategy's [`DomeResolution`]. Pure: the sky objects
//! pass asks per drawn version; the plan then groups reduced draws into runs
//! ([`crate::render::passes::reduced_layers`] draws them).

use crate::sky::resolved::{BlendMode, MAX_STAGES};

/// Frame pixels per reduced-buffer pixel along each side of the frame (x across, y down), in
/// steps of a quarter: a run's buffer can be just as coarse as its layers' textures allow (the
/// built-in clouds resolve at 2.5, where a half-resolution buffer would draw 1.6 times their
/// pixels), and coarser across than down where they do (a physical model's sky-view map, whose
/// rows crowd at the horizon and whose columns do not).
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct Divisor {
    x: u8,
    y: u8,
}

impl Divisor {
    /// The frame's own resolution.
    pub const FULL: Divisor = Divisor::steps(4);
    /// Half the width and height.
    pub const HALF: Divisor = Divisor::steps(8);
    /// A quarter of the width and height.
    pub const QUARTER: Divisor = Divisor::steps(16);
    /// An eighth of the width and height: the coarsest `Auto` goes.
    pub const EIGHTH: Divisor = Divisor::steps(32);
    /// Quarter steps of one divisor.
    const STEPS: f32 = 4.0;

    /// `n` quarter steps along both sides.
    const fn steps(n: u8) -> Divisor {
        Divisor { x: n, y: n }
    }

    /// `n` frame pixels per buffer pixel along both sides.
    pub const fn whole(n: u8) -> Divisor {
        Divisor::steps(n * 4)
    }

    /// Frame pixels per buffer pixel across the frame.
    pub fn x(self) -> f32 {
        f32::from(self.x) / Self::STEPS
    }

    /// Frame pixels per buffer pixel down the frame.
    pub fn y(self) -> f32 {
        f32::from(self.y) / Self::STEPS
    }

    /// Frame pixels per buffer pixel along the coarser side.
    pub fn coarser(self) -> f32 {
        self.x().max(self.y())
    }

    /// Frame pixels per buffer pixel by area, as the side of a square (the geometric mean).
    pub fn mean(self) -> f32 {
        (self.x() * self.y()).sqrt()
    }

    /// The coarsest step at most `factor`, within `[finest, coarsest]` (`finest` where `factor`
    /// is not a number), along both sides; `finest` and `coarsest` as along x.
    pub fn at_most(factor: f32, finest: Divisor, coarsest: Divisor) -> Divisor {
        Divisor::steps(Self::steps_at_most(factor, finest, coarsest))
    }

    /// [`Divisor::at_most`] along each side: `factors` across and down.
    pub fn at_most_each((across, down): (f32, f32), finest: Divisor, coarsest: Divisor) -> Divisor {
        Divisor { x: Self::steps_at_most(across, finest, coarsest), y: Self::steps_at_most(down, finest, coarsest) }
    }

    fn steps_at_most(factor: f32, finest: Divisor, coarsest: Divisor) -> u8 {
        let steps = (factor * Self::STEPS).floor();
        if steps.is_nan() {
            return finest.x;
        }
        steps.clamp(f32::from(finest.x), f32::from(coarsest.x)) as u8
    }

    /// The finer of two along each side: a buffer that resolves what both do.
    pub fn finer(self, other: Divisor) -> Divisor {
        Divisor { x: self.x.min(other.x), y: self.y.min(other.y) }
    }

    /// Whether a buffer at `self` is at least as fine as one at `other` along both sides.
    pub fn resolves(self, other: Divisor) -> bool {
        self.x <= other.x && self.y <= other.y
    }

    /// Whether `self` is finer than `other`: at least as fine along both sides, finer along one.
    pub fn finer_than(self, other: Divisor) -> bool {
        self.resolves(other) && self != other
    }

    /// Whether the buffer is coarser than the frame along some side.
    pub fn reduces(self) -> bool {
        self != Divisor::FULL
    }

    /// The buffer covering a frame of `(width, height)` pixels, rounded up: it holds the whole frame.
    pub fn buffer_size(self, (width, height): (u32, u32)) -> (u32, u32) {
        let len = |frame_px: u32, steps: u8| (frame_px * u32::from(Self::STEPS as u8)).div_ceil(u32::from(steps.max(1))).max(1);
        (len(width, self.x), len(height, self.y))
    }
}

/// Quarter steps: `Divisor(20)` along both sides, `Divisor(32x20)` across and down.
impl std::fmt::Debug for Divisor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.x == self.y {
            write!(f, "Divisor({})", self.x)
        } else {
            write!(f, "Divisor({}x{})", self.x, self.y)
        }
    }
}

impl std::fmt::Display for Divisor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.x == self.y {
            write!(f, "{}", self.x())
        } else {
            write!(f, "{}x{}", self.x(), self.y())
        }
    }
}

/// How finely dome layers are drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum DomeResolution {
    /// At the frame's resolution, straight into it.
    Full,
    /// Half the width and height (a quarter of the pixels), composited.
    Half,
    /// A quarter of the width and height, composited.
    Quarter,
    /// Each run of layers in the coarsest buffer, in quarter steps from half the width and
    /// height to an eighth, that still resolves the textures of all its layers: the default.
    /// Layers go to a buffer only when a half-resolution one resolves them, or, alpha-blended
    /// ones whose terms cannot be split, one at 1.5 ([`DomeResolution::finest_whole`]).
    #[default]
    Auto,
}

impl DomeResolution {
    /// Every choice, finest first.
    pub const ALL: [DomeResolution; 4] = [DomeResolution::Full, DomeResolution::Half, DomeResolution::Quarter, DomeResolution::Auto];

    /// Frame pixels per buffer pixel along each side: the finest buffer a layer may go to, and
    /// the coarsest (1: layers stay on the frame).
    pub fn divisors(self) -> (Divisor, Divisor) {
        match self {
            DomeResolution::Full => (Divisor::FULL, Divisor::FULL),
            DomeResolution::Half => (Divisor::HALF, Divisor::HALF),
            DomeResolution::Quarter => (Divisor::QUARTER, Divisor::QUARTER),
            DomeResolution::Auto => (Divisor::HALF, Divisor::EIGHTH),
        }
    }

    /// The finest buffer an alpha-blended layer goes to whole when some texture it samples is
    /// too fine for the finest of [`Self::divisors`] (its terms cannot be split as an opaque
    /// layer's are): with `Auto`, 1.5 (such a layer drawn on the frame costs lavapipe its full
    /// resolution, blended and depth-tested; below 1.5 the buffer's composite costs more than its
    /// pixels save); the finest of [`Self::divisors`] otherwise.
    pub fn finest_whole(self) -> Divisor {
        match self {
            DomeResolution::Auto => Divisor::steps(6),
            other => other.divisors().0,
        }
    }

    /// Name in the CLI, the app and reports.
    pub fn name(self) -> &'static str {
        match self {
            DomeResolution::Full => "full",
            DomeResolution::Half => "half",
            DomeResolution::Quarter => "quarter",
            DomeResolution::Auto => "auto",
        }
    }

    /// Parses [`DomeResolution::name`].
    pub fn parse(s: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|r| r.name() == s)
    }
}

/// Size of the sky-view map, texels: Hillaire 2020's sky-view LUT's 192 x 108 over half the
/// circle of azimuth (shaders/sky_model/sky_view_map.wgsl), 1.9 degrees a column. The plan
/// bounds buffers by its texel density; the sky-view pass makes it
/// (the sky-view map of `crate::render::atmosphere::AtmosphereGpu` has this size).
pub const SKY_VIEW_SIZE: (u32, u32) = (96, 108);

/// What the choice of resolution knows about the frame.
#[derive(Debug, Clone, Copy)]
pub struct ResolutionFacts {
    /// Frame pixels per degree of view at the frame's centre.
    pub frame_px_per_deg: f32,
    /// The finest and the coarsest buffer a layer may go to ([`DomeResolution::divisors`]).
    pub finest: Divisor,
    /// The coarsest buffer a layer may go to.
    pub coarsest: Divisor,
    /// The finest buffer an alpha-blended layer goes to whole ([`DomeResolution::finest_whole`]).
    pub finest_whole: Divisor,
    /// Texels per degree the sky-view map holds where the frame shows it densest, across the
    /// frame and down it ([`map_texels_per_deg`]).
    pub map_texels_per_deg: (f32, f32),
    /// The lowest and highest elevation the frame shows, degrees.
    pub shown_deg: (f32, f32),
}

impl ResolutionFacts {
    /// The facts of a frame `height_px` pixels high with a vertical field of view of
    /// `fov_y_deg`, showing elevations from `elevations_deg.0` to `.1`, at `resolution`.
    pub fn new(resolution: DomeResolution, height_px: u32, fov_y_deg: f32, elevations_deg: (f32, f32)) -> Self {
        let (finest, coarsest) = resolution.divisors();
        Self {
            frame_px_per_deg: height_px as f32 / fov_y_deg.max(1.0),
            finest,
            coarsest,
            finest_whole: resolution.finest_whole(),
            map_texels_per_deg: map_texels_per_deg(elevations_deg),
            shown_deg: elevations_deg,
        }
    }

    /// Whether any layer may go to a reduced buffer.
    pub fn reduces(&self) -> bool {
        self.finest.reduces()
    }

    /// The coarsest buffer that still resolves a physical model's sky-view map where the frame
    /// shows it ([`map_texels_per_deg`]): what a layer whose colour follows the map (the map's
    /// own, or one matched over it) may be drawn at.
    pub fn map_divisor(&self) -> Divisor {
        self.divisor_resolving(self.map_texels_per_deg)
    }

    /// The coarsest buffer that resolves `(across, down)` texels per degree.
    fn divisor_resolving(&self, (across, down): (f32, f32)) -> Divisor {
        Divisor::at_most_each((self.frame_px_per_deg / across, self.frame_px_per_deg / down), self.finest, self.coarsest)
    }
}

/// Texels per degree the sky-view map holds where a frame showing elevations `elevations_deg`
/// (lowest, highest in view) shows it densest: across the frame (along the azimuth) and down it
/// (along the elevation).
///
/// Down: its rows, square-root spaced about the horizon (shaders/sky_model/sky_view_map.wgsl),
/// lie `h / 4 / sqrt(90 e)` to a degree at `e` degrees from it, at most
/// [`SKY_VIEW_TEXELS_PER_DEG`], at the elevation nearest the horizon in view. A frame looking up
/// (every elevation above 35 degrees at the zenith) sees half a texel per degree.
///
/// Across: its columns lie 180 / w degrees of azimuth apart, `cos e` times that in angle at
/// elevation `e`, so densest at the elevation farthest from the horizon in view; but never
/// denser than the rows: towards the pole the columns crowd only by the parametrisation, not with
/// the sky's detail. A frame across the horizon sees about 0.75 texels per degree across against
/// 2 down, so its map's buffer is coarser across than down ([`Divisor`]). Frames have no roll (the
/// camera's yaw and pitch, or cube faces level or looking straight up or down, whose rows and
/// columns then count the same), so across the frame is along the azimuth.
pub fn map_texels_per_deg((lowest, highest): (f32, f32)) -> (f32, f32) {
    let nearest = if lowest <= 0.0 && highest >= 0.0 { 0.0 } else { lowest.abs().min(highest.abs()) };
    let farthest = lowest.abs().max(highest.abs()).min(90.0);
    let (columns, rows) = SKY_VIEW_SIZE;
    let down = (rows as f32 / 4.0 / (90.0 * nearest).max(1e-6).sqrt()).min(SKY_VIEW_TEXELS_PER_DEG);
    let across = columns as f32 / 180.0 / farthest.to_radians().cos().max(1e-6);
    (across.min(down), down)
}

/// Texels per degree a physical model's sky-view map holds down the frame near the horizon, for
/// the buffer its layer goes to: its rows 2 degrees above the horizon (square-root spaced, 108
/// over the sphere) are half a degree apart. Nearer the horizon the rows crowd further; there the
/// sky's colour changes over a degree or two, which a buffer pixel of half a degree still follows
/// (docs/performance-notes.md measures the difference). Its columns are 1.9 degrees apart there (96
/// over half the circle, the other half its mirror).
pub const SKY_VIEW_TEXELS_PER_DEG: f32 = 2.0;

/// What the choice of resolution knows about one dome layer's material this frame.
#[derive(Debug, Clone, Copy)]
pub struct LayerStages {
    /// Stages of the material (at most [`MAX_STAGES`]).
    pub count: usize,
    /// The term each stage belongs to: an `add` stage starts one, `modulate` stages join it.
    pub terms: [usize; MAX_STAGES],
    /// Whether each stage's term is sampled this frame (not black).
    pub live: [bool; MAX_STAGES],
    /// The most texels per degree of view each stage's texture shows anywhere on the shape.
    pub texels_per_deg: [f32; MAX_STAGES],
    /// A stage is fed by a physical sky model's map, which resolves
    /// [`ResolutionFacts::map_texels_per_deg`].
    pub physical: bool,
    /// How the layer blends over what is below it.
    pub blend: BlendMode,
}

/// How finely one dome layer is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Resolution {
    /// On the frame, at its resolution.
    Full,
    /// Whole, into a buffer `divisor` times coarser.
    Reduced(Divisor),
    /// Its terms split (opaque layers only: under alpha blending the terms' alphas do not add):
    /// the `coarse` stages into a buffer, the `fine` ones added on top at full resolution.
    Split { coarse: [bool; MAX_STAGES], divisor: Divisor, fine: [bool; MAX_STAGES] },
}

/// The resolution of a dome layer with `stages` (only asked when [`ResolutionFacts::reduces`]).
///
/// A term is fine when a texture it samples this frame has finer detail than the finest
/// buffer's pixels (the skydome's stars at night). A layer with no fine term goes whole to the
/// coarsest buffer that resolves every stage sampled (no stage sampled: the coarsest); an opaque
/// one with both kinds is split; an alpha-blended one with a fine texture goes whole into a
/// buffer between `finest_whole` and the finest where one resolves it, or stays on the frame.
pub fn resolution(stages: &LayerStages, facts: &ResolutionFacts) -> Resolution {
    let count = stages.count.min(MAX_STAGES);
    let (live, terms) = (stages.live, stages.terms);
    let reduced_px_per_deg = facts.frame_px_per_deg / facts.finest.coarser();
    let fine_stage = |k: usize| live[k] && stages.texels_per_deg[k] > reduced_px_per_deg;
    let fine: [bool; MAX_STAGES] = std::array::from_fn(|k| k < count && (0..count).any(|j| terms[j] == terms[k] && fine_stage(j)));
    let coarse: [bool; MAX_STAGES] = std::array::from_fn(|k| k < count && !fine[k]);
    let any_fine = (0..count).any(|k| fine[k] && live[k]);
    let any_coarse = (0..count).any(|k| coarse[k] && live[k]);
    // The most texels per degree among the stages sampled of `of`.
    let densest = |of: [bool; MAX_STAGES]| (0..count).filter(|&k| of[k] && live[k]).map(|k| stages.texels_per_deg[k]).fold(0.0, f32::max);
    let density = densest(coarse);
    let (map_across, map_down) = if stages.physical { facts.map_texels_per_deg } else { (0.0, 0.0) };
    let divisor = facts.divisor_resolving((density.max(map_across), density.max(map_down)));
    match (any_fine, any_coarse, stages.blend) {
        (false, _, _) => Resolution::Reduced(divisor),
        (true, true, BlendMode::Opaque) => Resolution::Split { coarse, divisor, fine },
        (true, _, BlendMode::Alpha) if !stages.physical => {
            let factor = facts.frame_px_per_deg / densest([true; MAX_STAGES]);
            if factor >= facts.finest_whole.coarser() {
                Resolution::Reduced(Divisor::at_most(factor, facts.finest_whole, facts.finest))
            } else {
                Resolution::Full
            }
        }
        _ => Resolution::Full,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 720 pixels over 60 degrees: 12 frame pixels per degree, 6 in a half-resolution buffer.
    fn auto() -> ResolutionFacts {
        ResolutionFacts::new(DomeResolution::Auto, 720, 60.0, (-20.0, 40.0))
    }

    fn layer(texels_per_deg: &[f32], terms: &[usize], blend: BlendMode) -> LayerStages {
        let mut s = LayerStages { count: texels_per_deg.len(), terms: [0; 4], live: [false; 4], texels_per_deg: [0.0; 4], physical: false, blend };
        for (k, (&t, &term)) in texels_per_deg.iter().zip(terms).enumerate() {
            (s.texels_per_deg[k], s.terms[k], s.live[k]) = (t, term, true);
        }
        s
    }

    #[test]
    fn coarse_layers_go_to_the_coarsest_buffer_that_resolves_them() {
        let f = auto();
        assert_eq!(f.frame_px_per_deg, 12.0);
        // 12 / 4.8 = 2.5 frame pixels per texel: a buffer 2.5 times coarser.
        assert_eq!(resolution(&layer(&[4.8], &[0], BlendMode::Alpha), &f), Resolution::Reduced(Divisor::steps(10)));
        // Smoother than an eighth's pixels: the coarsest; nothing sampled: the coarsest too.
        assert_eq!(resolution(&layer(&[0.5], &[0], BlendMode::Opaque), &f), Resolution::Reduced(Divisor::EIGHTH));
        let mut dark = layer(&[30.0], &[0], BlendMode::Opaque);
        dark.live = [false; 4];
        assert_eq!(resolution(&dark, &f), Resolution::Reduced(Divisor::EIGHTH));
        // The densest stage decides; a physical map counts as its texels where the frame shows
        // it: SKY_VIEW_TEXELS_PER_DEG down (12 / 2), 0.7 across (12 / 0.7 = 17: an eighth).
        assert_eq!(resolution(&layer(&[0.5, 3.0], &[0, 1], BlendMode::Opaque), &f), Resolution::Reduced(Divisor::whole(4)));
        let physical = LayerStages { physical: true, ..layer(&[0.5], &[0], BlendMode::Opaque) };
        let map = Divisor::at_most_each((8.0, 6.0), Divisor::HALF, Divisor::EIGHTH);
        assert_eq!((map.x(), map.y(), map.to_string()), (8.0, 6.0, "8x6".to_string()));
        assert_eq!(resolution(&physical, &f), Resolution::Reduced(map));
        assert_eq!(f.map_divisor(), map);
        // A stage denser than the map along both sides: as that stage along both.
        let physical_dense = LayerStages { physical: true, ..layer(&[4.0], &[0], BlendMode::Opaque) };
        assert_eq!(resolution(&physical_dense, &f), Resolution::Reduced(Divisor::whole(3)));
        // Fixed resolutions keep their divisor.
        let half = ResolutionFacts::new(DomeResolution::Half, 720, 60.0, (-20.0, 40.0));
        assert_eq!(resolution(&layer(&[0.5], &[0], BlendMode::Opaque), &half), Resolution::Reduced(Divisor::HALF));
        assert!(!ResolutionFacts::new(DomeResolution::Full, 720, 60.0, (-20.0, 40.0)).reduces());
    }

    #[test]
    fn a_frame_looking_up_draws_the_map_as_coarsely_as_the_map_is_there() {
        // Across the horizon, or just above it: the map's densest rows down the frame; across it,
        // its columns (96 over 180 degrees) at the elevation farthest from the horizon.
        let columns = 96.0 / 180.0;
        let near = |(a, b): (f32, f32), (x, y): (f32, f32)| (a - x).abs() < 1e-3 && (b - y).abs() < 1e-3;
        assert!(near(map_texels_per_deg((-20.0, 40.0)), (columns / 40f32.to_radians().cos(), SKY_VIEW_TEXELS_PER_DEG)));
        assert!(near(map_texels_per_deg((1.0, 60.0)), (2.0 * columns, SKY_VIEW_TEXELS_PER_DEG)));
        assert!(near(map_texels_per_deg((-60.0, 1.0)), (2.0 * columns, SKY_VIEW_TEXELS_PER_DEG)));
        // Rows 27 / sqrt(90 e) to a degree: half a texel at 32 degrees, whichever side; the
        // columns crowding round the pole count no denser than that.
        assert!(near(map_texels_per_deg((32.4, 90.0)), (0.5, 0.5)));
        assert!(near(map_texels_per_deg((-90.0, -32.4)), (0.5, 0.5)));
        // Looking up, physical layers go to the coarsest buffer (12 / 0.5 = 24 frame pixels a texel).
        let up = ResolutionFacts::new(DomeResolution::Auto, 720, 60.0, (32.4, 90.0));
        assert_eq!(up.map_divisor(), Divisor::EIGHTH);
        let physical = LayerStages { physical: true, ..layer(&[0.5], &[0], BlendMode::Opaque) };
        assert_eq!(resolution(&physical, &up), Resolution::Reduced(Divisor::EIGHTH));
    }

    #[test]
    fn fine_terms_split_opaque_layers_and_keep_blended_ones_whole() {
        let f = auto();
        // Gradient (coarse) + stars x mask (fine, one term) + halo (coarse).
        let sky = layer(&[0.5, 20.0, 1.0, 0.8], &[0, 1, 1, 2], BlendMode::Opaque);
        let Resolution::Split { coarse, divisor, fine } = resolution(&sky, &f) else { panic!("{:?}", resolution(&sky, &f)) };
        // The mask shares the stars' term: fine with them.
        assert_eq!((coarse, fine), ([true, false, false, true], [false, true, true, false]));
        // 12 / 0.8 = 15 frame pixels per texel: the coarsest, an eighth.
        assert_eq!(divisor, Divisor::EIGHTH);
        // Every stage fine: nothing to reduce.
        assert_eq!(resolution(&layer(&[20.0], &[0], BlendMode::Opaque), &f), Resolution::Full);
        // Alpha-blended with a fine texture: whole between 1.5 and the finest where it resolves,
        // on the frame where even 1.5 is too coarse.
        assert_eq!(resolution(&layer(&[7.0], &[0], BlendMode::Alpha), &f), Resolution::Reduced(Divisor::steps(6)));
        assert_eq!(resolution(&layer(&[9.0], &[0], BlendMode::Alpha), &f), Resolution::Full);
        // Additive layers with fine terms stay on the frame.
        assert_eq!(resolution(&layer(&[20.0, 0.5], &[0, 1], BlendMode::Additive), &f), Resolution::Full);
    }
}
