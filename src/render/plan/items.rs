//! The frame plan's vocabulary: the phases of a frame, the target its drawing phases write, the
//! items passes offer the plan with what each can do ([`Caps`]), and where the plan places each
//! one. Plain data, so that the plan ([`super`]) imports no GPU module; the passes
//! (`crate::render::frame::pass`) speak it.

use super::resolution::Divisor;

/// The slots of a frame, in the order they run. Each is one wgpu pass.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Phase {
    /// Compute work before any drawing: look-up tables, particle simulation.
    Compute,
    /// The main scene, drawn first in depth range [`crate::render::frame::renderer::SCENE_DEPTH`]; the phase clears the target.
    Scene,
    /// Sky objects and stars, merged by priority, in depth range [`crate::render::frame::renderer::SKY_DEPTH`].
    Sky,
    /// Things drawn in the scene's depth range after the sky, so the scene occludes them (particles).
    SceneAfterSky,
    /// Overlays on top of everything (glare).
    Overlay,
    /// From the frame's HDR target to the display target: exposure was applied upstream, here the
    /// tone mapper and display encoding (physical sky models only; the NeL bitmap path draws
    /// display values straight into the display target and skips it).
    Display,
}

impl Phase {
    /// Every phase, in frame order.
    pub const ALL: [Phase; 6] = [Phase::Compute, Phase::Scene, Phase::Sky, Phase::SceneAfterSky, Phase::Overlay, Phase::Display];

    /// Name used in GPU labels and timings.
    pub fn name(self) -> &'static str {
        match self {
            Phase::Compute => "compute",
            Phase::Scene => "scene",
            Phase::Sky => "sky",
            Phase::SceneAfterSky => "scene_after_sky",
            Phase::Overlay => "overlay",
            Phase::Display => "display",
        }
    }

    /// Position in [`Phase::ALL`].
    pub fn index(self) -> usize {
        self as usize
    }
}

/// Which colour target a frame's drawing phases write.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Target {
    /// Display values straight into the display target (the NeL bitmap path, as in 2005).
    #[default]
    Display,
    /// Exposed linear radiance into the frame's HDR target ([`crate::render::gpu::parts::HDR_FORMAT`]); the display
    /// phase tone-maps it (physical sky models).
    Hdr,
}

/// One draw a pass wants in its phase. The sky phase orders the items of all its passes by
/// `priority` (stable: list order among equals); other phases keep list order.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DrawItem {
    /// Transparency priority (sky phase only).
    pub priority: u8,
    /// The pass's own index of what to draw.
    pub key: usize,
    /// A dome layer the sky phase may draw at reduced resolution ([`Placement::Reduced`](crate::render::frame::pass::Placement::Reduced)).
    pub reduced: bool,
    /// The draw only adds to what lies behind it (target + something, clamped): it commutes with
    /// every other such draw, so the sky phase may reorder them (to join reduced runs).
    pub additive: bool,
    /// Frame pixels per buffer pixel along each side where `reduced` (the coarsest buffer that
    /// still resolves the layer); [`Divisor::FULL`] otherwise.
    pub divisor: Divisor,
    /// A `reduced` item that goes to a reduced buffer only to join a run of other layers: alone,
    /// its run's full-resolution composite would cost what drawing it at full resolution does
    /// (the lightning flash: one constant colour over the sky).
    pub joins_only: bool,
    /// The placements other than plain and reduced that the pass can draw this item at, this
    /// frame (the frame plan chooses among them: [`crate::render::plan`]).
    pub caps: Caps,
}

impl DrawItem {
    /// A plain full-resolution draw: not reduced, not known to commute, no other placement.
    pub fn new(priority: u8, key: usize) -> Self {
        Self { priority, key, reduced: false, additive: false, divisor: Divisor::FULL, joins_only: false, caps: Caps::default() }
    }
}

/// What a pass can do with one of its items this frame, as data for the frame plan.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Caps {
    /// [`Placement::UnderRun`]: drawn after the composite of the run of reduced layers that
    /// follows it, as if drawn before that run. Two runs join into one composite only when every
    /// item between them can.
    pub under_run: bool,
    /// [`Placement::First`] (additive items): onto the cleared frame, before the background.
    pub first: bool,
    /// It spans much of the frame (a dome layer): drawing it first pays for the blended
    /// background; a few small billboards or sprites do not.
    pub spans_frame: bool,
    /// [`Placement::OverSeed`] (reduced items): it covers every pixel of its buffer outside
    /// `background_gap`.
    pub over_seed: bool,
    /// [`Placement::Background`] over one run (index 0) and over joined runs (index 1): it covers
    /// every pixel of the frame outside `background_gap`.
    pub background: [bool; 2],
    /// A rectangle of pixels (x, y, width, height) holding every pixel the item leaves uncovered
    /// as the background or over a seed (below a dome's lowest row). None: it covers the frame.
    pub background_gap: Option<[u32; 4]>,
    /// The pass's next item (its key) in priority order, and whether the two can be drawn at once
    /// as [`Placement::Pair`]: plain (index 0) and over a seed (index 1).
    pub pair_next: Option<(usize, [bool; 2])>,
    /// [`RunInput::Own`](crate::render::plan::RunInput::Own) (reduced items): its fragments cost
    /// many reads of a buffer each (an alpha layer matched over the model's sky), so where its
    /// run's buffer is much finer than it needs it may be drawn beforehand into a buffer of its
    /// own, which is then composited into the run's buffer in its place.
    pub own_buffer: Option<OwnBuffer>,
}

/// A buffer of its own for a costly layer drawn apart from its run ([`Caps::own_buffer`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct OwnBuffer {
    /// Frame pixels per buffer pixel.
    pub divisor: Divisor,
    /// Frame pixels (x, y, width, height) that hold every pixel the layer covers (a band's rows),
    /// where its composite into the run's buffer is confined; None: the whole frame.
    pub covers: Option<[u32; 4]>,
}

/// How one draw reaches the frame: chosen by the frame plan, carried out by [`Pass::draw`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Placement {
    /// In its place in its phase, at full resolution, depth-tested against the scene.
    Plain,
    /// Into a reduced-resolution buffer of a run of dome layers ([`crate::render::passes::reduced_layers`]:
    /// premultiplied colour and transmittance, blended with
    /// [`crate::render::passes::reduced_layers::REDUCED_BLENDS`]).
    Reduced,
    /// After the composite of the run of reduced layers that follows it in the sky phase, as if
    /// drawn before that run: corrected by the run's colour and transmittance (the run's buffer
    /// as group 2: [`crate::render::passes::reduced_layers::run_layout`]).
    UnderRun,
    /// Additive, onto the cleared frame before the background run is composited over it
    /// ([`crate::render::plan::strategy::UnderBackground::Additive`]): without depth test, since the scene
    /// drawn afterwards covers what it hides. Adding onto black is writing.
    First,
    /// Reduced, as the first layer of a seeded buffer
    /// ([`crate::render::plan::strategy::RunJoining::SeededFolded`]): over the lower run's colour (group 2),
    /// replacing the clear colour, unblended: what its blend would leave over the seed.
    OverSeed,
    /// Reduced, at once with the pass's item `upper` right after it in the run
    /// ([`crate::render::plan::strategy::LayerPairs::AtOnce`]): one draw that leaves what the two would, one
    /// after the other; over the seed (group 2) when `over_seed`.
    Pair {
        /// The upper item's key.
        upper: usize,
        /// The pair is a seeded buffer's first layers.
        over_seed: bool,
    },
    /// Additive, as the frame's background in place of the background run's composite: the
    /// run's colour (group 2) plus its own term, weighed by the transmittance of the runs above
    /// it when `joined`. One full-screen pass, neither blended nor depth-tested.
    Background {
        /// The background is the combination of joined runs.
        joined: bool,
    },
}
