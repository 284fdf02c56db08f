//! How the sky's pixels are filled: the renderer's tricks that pay on one kind of adapter and
//! not necessarily on another, as one value with named presets.
//!
//! Each trick was measured on lavapipe, a software rasteriser, where a full-screen pass costs
//! about a millisecond and shading is paid per 4 x 4 block (docs/performance-notes.md). On a
//! hardware GPU the same tricks may cost more than they save, or blur what need not be blurred,
//! so the default strategy follows the adapter's device type ([`FillStrategy::for_device`]).
//! The switches that depend on each other are one enum each: only valid combinations exist.

pub use crate::render::plan::resolution::DomeResolution;

/// How the first runs of reduced dome layers reach the frame (with dome layers in reduced
/// buffers; nothing to join otherwise).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RunJoining {
    /// One composite per run.
    Separate,
    /// The first runs (the skydome's, the clouds', and the fog's after a lightning bolt) are
    /// composited at once, and the billboards between them drawn afterwards, corrected by the
    /// runs above them (the same picture, one full-screen pass less per run joined); the joined
    /// runs are combined in passes of their own.
    Combined,
    /// As `Combined`, and with two runs joined the second run's buffer starts as the first run's
    /// colour instead of nothing, so that its layers leave the two runs' combination there (one
    /// pass at reduced resolution less). Where the first run is the finer one: combined as with
    /// `Combined`. With more runs joined, the first two are seeded where nothing lies between
    /// them, and the runs above combined over the seeded buffer. A first run whose layers get
    /// finer part-way (the skydome under the clouds) is split there into two such runs.
    Seeded,
    /// As `Seeded`, and the seeded buffer's first layer, when a dome that can, is drawn over the
    /// lower run's colour itself, replacing the clear colour, and the seeding pass only fills the
    /// rows below that dome: one reduced-resolution pass less, for one sample of the lower run.
    SeededFolded,
}

/// What is drawn onto the cleared frame before the background (the first run of reduced dome
/// layers) is composited over it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum UnderBackground {
    /// Nothing: the additive draws after the background are drawn in the sky phase,
    /// depth-tested, each sampling the run above it.
    Nothing,
    /// The additive draws that follow the background (the skydome's fine stars, the star field)
    /// go first onto the cleared frame, neither depth-tested nor corrected by a run, and the
    /// background is composited over them (the same sums; the scene drawn next covers what it
    /// hides).
    Additive,
    /// As `Additive`, and one that covers the frame (the skydome's fine stars looking up) is drawn
    /// as the background itself, writing the background run's colour plus its term, the others
    /// added after it: one full-screen pass, neither blended nor depth-tested, in place of that
    /// draw and the background's blended composite.
    AdditiveFused,
}

/// How a sparse texture stage of the fused background (the skydome's stars times their mask:
/// under 1% of texels lit) is drawn on the display target.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SparseStages {
    /// Sampled everywhere, as every other stage.
    Sampled,
    /// Texel by texel where it is sampled from level 0: one small polygon per lit texel adding
    /// the texel times its bilinear weight ([`crate::render::sky_objects::texel_quads`]), over the background drawn
    /// without that stage. The same sum as the sample, for the pixels near a lit texel only.
    TexelPolygons,
    /// As `TexelPolygons`, and the rest of the background's draw, which then maps nothing from
    /// the dome's grid, goes as one triangle over the frame scissored round the rings that still
    /// sample the stage and the rows below the dome, and inside those as one band of quads
    /// between the rings' chords: the same pixels, without most of the triangle edges whose
    /// 4 x 4 blocks lavapipe shades twice.
    TexelPolygonsOnBands,
}

/// Where a cloud-layer mapping's texture coordinates (`uv = { kind = "layer" }`) are computed for
/// a layer drawn on its dome's grid (one with a stage of the mesh's own; layers mapped only by
/// the view direction go on the dome's outline, per pixel either way).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LayerCoordinates {
    /// Per pixel from the view direction: exact.
    PerPixel,
    /// Per vertex of the grid, the grid's vertices moved along their rays onto the layer so that
    /// the rasteriser's perspective-correct interpolation runs over chords of the layer itself
    /// (the view direction stays exact; the coordinates are off by the chords' sag: for the
    /// stars' layer 0.01 texels near the zenith to 3 in the bottom ring, src/render/sky_objects/upload.rs
    /// tests). Lavapipe takes interpolated coordinates' derivatives from
    /// the triangle's setup instead of differencing across pixels, and a sparse stage under the
    /// layer can then be drawn texel by texel on the same chords ([`SparseStages`]).
    PerVertex,
}

/// Where the lightning flash (one additive colour over the sky, above every layer) is added.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FlashPlacement {
    /// Over the whole frame at full resolution.
    OverFrame,
    /// With dome layers in reduced buffers: to the run of layers before it, at that run's
    /// resolution (the same sum; one full-screen blended pass less while a flash lasts). With no
    /// run before it: over the frame.
    InRun,
}

/// How two alpha-blended layers next to each other in a run, on the same mesh (the cloud
/// layers), are drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LayerPairs {
    /// One after the other.
    OneByOne,
    /// With dome layers in reduced buffers: at once, one shader evaluating both and one blend
    /// leaving what the two would (one set of triangles and one blend per pixel less).
    AtOnce,
}

/// Where a layer whose fragments cost many reads of a buffer each (an alpha layer matched over a
/// physical model's sky: a sample of its map and three tone curves) is drawn, when its run's
/// buffer is much finer than the layer needs (the fog's band in the clouds' buffer).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CostlyLayers {
    /// In its run's buffer, at the run's resolution.
    InRun,
    /// With dome layers in reduced buffers: beforehand, at its own resolution, into a buffer of
    /// its own, which is then composited into its run's buffer in its place (the same blend;
    /// the costly fragments on a fraction of the pixels, one read of a buffer on the others).
    OwnBuffer,
}

/// Where a frame with a physical sky model is drawn and how its radiance reaches the display.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PhysicalTarget {
    /// Into a linear rgba16float target, every layer blended in exposed radiance (display colours
    /// through the tone mapper's inverse), tone-mapped into the display target by a full-screen
    /// display phase. What HDR exports read; the reference picture of a physical sky.
    Hdr,
    /// Onto the display target as a painted sky is, with no HDR target and no display phase: the
    /// layer holding the model's map sums its terms in radiance and tone-maps them itself, and
    /// each blended layer above it writes what the HDR path's blend over the model's sky would
    /// leave (exact over the bare sky; over what lies under it, the seed, where the first layer
    /// of a seeded buffer is drawn over the seed). The HDR picture within a few levels, at the
    /// cost of two tone curves and an inverse per blended fragment. A frame that must read
    /// radiance back (an HDR export) asks for [`Self::Hdr`].
    DisplayMatched,
    /// As `DisplayMatched` for the map's layer, and the layers above it blend in display values
    /// as over a painted sky (the NeL look of 2005): no tone curve per cloud fragment, but
    /// clouds greyer over a bright sky than on the HDR target (docs/performance-notes.md
    /// measures both).
    DisplayAsPainted,
}

/// How the sky objects' shaders take display values to linear light and back (the sRGB curves of
/// the tone mapping, the matching and the display-referred skydome).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DisplayCurves {
    /// `pow`, as the sRGB definition writes them.
    Exact,
    /// Polynomials fitted to the curves (within 0.001 of a level encoding and 0.04% decoding:
    /// tests/tone_curves.rs): square roots and multiply-adds, where a software rasteriser's `pow`
    /// is a logarithm and an exponential per lane.
    Polynomial,
}

impl DisplayCurves {
    /// The value of the shaders' `CURVES_KIND` override (shaders/sky_model/tone.wgsl).
    pub fn shader_kind(self) -> u32 {
        match self {
            DisplayCurves::Exact => 0,
            DisplayCurves::Polynomial => 1,
        }
    }
}

/// How the sky's pixels are filled: every trick of the renderer that trades work for work, as
/// one value. [`Self::software`] and [`Self::plain`] are the named presets.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FillStrategy {
    /// Resolution of the dome layers (skydome, galaxy, clouds, fog): below full, each run of
    /// consecutive dome layers is drawn into a smaller buffer and composited in its place.
    pub dome_resolution: DomeResolution,
    /// How the first runs of reduced layers reach the frame.
    pub runs: RunJoining,
    /// What goes under the background.
    pub under_background: UnderBackground,
    /// How a sparse stage of the fused background is drawn.
    pub sparse_stages: SparseStages,
    /// Where cloud-layer coordinates of a layer on its dome's grid are computed (a sparse stage
    /// under the layer mapping is drawn texel by texel only per vertex).
    pub layer_coordinates: LayerCoordinates,
    /// Where the lightning flash is added.
    pub flash: FlashPlacement,
    /// How two neighbouring alpha-blended layers of a run are drawn.
    pub pairs: LayerPairs,
    /// Where a costly layer of a finer run is drawn.
    pub costly_layers: CostlyLayers,
    /// How the `precomputed` model's tables are built: at once, or over frames.
    pub table_builds: TableBuilds,
    /// Where physical-model frames are drawn.
    pub physical_target: PhysicalTarget,
    /// How the sky-view map follows a sun that moves a little every frame.
    pub map_updates: crate::render::plan::map_updates::MapUpdates,
    /// How the sky objects evaluate the sRGB curves.
    pub display_curves: DisplayCurves,
}

/// The named presets, for the command line and reports.
pub const PRESETS: [(&str, FillStrategy); 7] = [
    ("software", FillStrategy::software()),
    ("plain", FillStrategy::plain()),
    ("software-hdr", FillStrategy::software().with_hdr()),
    ("software-as-painted", FillStrategy { physical_target: PhysicalTarget::DisplayAsPainted, ..FillStrategy::software() }),
    ("software-exact-curves", FillStrategy { display_curves: DisplayCurves::Exact, ..FillStrategy::software() }),
    ("software-costly-in-run", FillStrategy { costly_layers: CostlyLayers::InRun, ..FillStrategy::software() }),
    ("software-layer-per-pixel", FillStrategy { layer_coordinates: LayerCoordinates::PerPixel, ..FillStrategy::software() }),
];

impl FillStrategy {
    /// Every trick on: what measured fastest on lavapipe (docs/performance-notes.md), for CPU
    /// rasterisers.
    pub const fn software() -> Self {
        Self {
            dome_resolution: DomeResolution::Auto,
            runs: RunJoining::SeededFolded,
            under_background: UnderBackground::AdditiveFused,
            sparse_stages: SparseStages::TexelPolygonsOnBands,
            layer_coordinates: LayerCoordinates::PerVertex,
            flash: FlashPlacement::InRun,
            pairs: LayerPairs::AtOnce,
            costly_layers: CostlyLayers::OwnBuffer,
            // One r-layer of a default table per frame: about half a second each on lavapipe.
            table_builds: TableBuilds::Spread { slices: 32 },
            // The HDR target and its display phase were 17 to 20 ms of a 25 ms frame at 1280x720.
            physical_target: PhysicalTarget::DisplayMatched,
            // The `lut` map costs about 9 ms at 96 x 108 on lavapipe: a twelfth per frame. Each
            // map is computed for the sun of the frame that shows it alone, 23 frames on.
            map_updates: crate::render::plan::map_updates::MapUpdates::Spread { slices: 12 },
            // The matched layers' three curves per fragment cost about 3.6 ms at 1280x720 on
            // lavapipe, the sRGB powers about a third of it.
            display_curves: DisplayCurves::Polynomial,
        }
    }

    /// The straightforward path: every dome layer at the frame's resolution, drawn in list order
    /// one after the other, every stage sampled.
    pub const fn plain() -> Self {
        Self {
            dome_resolution: DomeResolution::Full,
            runs: RunJoining::Separate,
            under_background: UnderBackground::Nothing,
            sparse_stages: SparseStages::Sampled,
            layer_coordinates: LayerCoordinates::PerPixel,
            flash: FlashPlacement::OverFrame,
            pairs: LayerPairs::OneByOne,
            costly_layers: CostlyLayers::InRun,
            table_builds: TableBuilds::AtOnce,
            physical_target: PhysicalTarget::Hdr,
            map_updates: crate::render::plan::map_updates::MapUpdates::Whole,
            display_curves: DisplayCurves::Exact,
        }
    }

    /// The preset for an adapter of this type: `software` on a CPU rasteriser, where its tricks
    /// were measured to pay, `plain` elsewhere (no trick was measured on a hardware GPU yet:
    /// docs/performance.md).
    pub fn for_device(device_type: wgpu::DeviceType) -> Self {
        match device_type {
            wgpu::DeviceType::Cpu => Self::software(),
            _ => Self::plain(),
        }
    }

    /// The strategy a frame uses: the one asked for (`--strategy`, the diagnostics panel), else
    /// the adapter's ([`Self::for_device`]). The one place the two meet: the window, the CLI's
    /// renders and `bench frame` all resolve through it.
    pub fn resolve(asked: Option<Self>, device_type: wgpu::DeviceType) -> Self {
        asked.unwrap_or_else(|| Self::for_device(device_type))
    }

    /// The preset of this name (`software`, `plain`).
    pub fn preset(name: &str) -> Option<Self> {
        PRESETS.iter().find(|(n, _)| *n == name).map(|(_, s)| *s)
    }

    /// The preset named by a command-line value, or an error naming `--strategy` and the presets.
    pub fn preset_arg(name: &str) -> Result<Self, String> {
        Self::preset(name).ok_or_else(|| format!("--strategy: unknown fill strategy \"{name}\"; expected {}", PRESETS.map(|p| p.0).join(", ")))
    }

    /// The preset's name, or `custom` for a strategy that is none of them.
    pub fn name(&self) -> &'static str {
        PRESETS.iter().find(|(_, s)| s == self).map_or("custom", |(n, _)| n)
    }

    /// Whether the first runs are joined (composited at once).
    pub fn joins_runs(&self) -> bool {
        self.runs != RunJoining::Separate
    }

    /// Whether two joined runs are joined by seeding the second's buffer with the first.
    pub fn seeds_joined(&self) -> bool {
        matches!(self.runs, RunJoining::Seeded | RunJoining::SeededFolded)
    }

    /// Whether the seeded buffer's first layer is drawn over the seed itself.
    pub fn folds_seed(&self) -> bool {
        self.runs == RunJoining::SeededFolded
    }

    /// Whether additive draws go under the background.
    pub fn additive_first(&self) -> bool {
        self.under_background != UnderBackground::Nothing
    }

    /// Whether one of the draws under the background may be the background itself.
    pub fn fuses_background(&self) -> bool {
        self.under_background == UnderBackground::AdditiveFused
    }

    /// Whether sparse stages are drawn texel by texel.
    pub fn texel_polygons(&self) -> bool {
        self.sparse_stages != SparseStages::Sampled
    }

    /// Whether cloud-layer coordinates on a dome's grid are interpolated from its vertices.
    pub fn layer_per_vertex(&self) -> bool {
        self.layer_coordinates == LayerCoordinates::PerVertex
    }

    /// Whether the background without its sparse stage goes on one triangle and bands.
    pub fn grid_bands(&self) -> bool {
        self.sparse_stages == SparseStages::TexelPolygonsOnBands
    }

    /// Whether the lightning flash is added to the run before it.
    pub fn flash_in_run(&self) -> bool {
        self.flash == FlashPlacement::InRun
    }

    /// This strategy with physical frames on the HDR target: for callers that read the frame's
    /// radiance back.
    pub const fn with_hdr(self) -> Self {
        Self { physical_target: PhysicalTarget::Hdr, ..self }
    }

    /// Whether neighbouring alpha-blended layers of a run are drawn at once.
    pub fn pairs_layers(&self) -> bool {
        self.pairs == LayerPairs::AtOnce
    }

    /// Whether a costly layer of a finer run is drawn into a buffer of its own.
    pub fn own_buffers(&self) -> bool {
        self.costly_layers == CostlyLayers::OwnBuffer
    }
}

impl Default for FillStrategy {
    /// The software preset: the renderer's pictures and tests are defined on lavapipe.
    fn default() -> Self {
        Self::software()
    }
}

/// How a frame builds the tables: all at once (a GPU: milliseconds), or spread over frames so
/// that a software rasteriser keeps drawing while it builds (seconds to a minute at the default
/// settings on lavapipe).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TableBuilds {
    /// Every step in one frame.
    AtOnce,
    /// Each 4D stage in this many slices, one step per frame.
    Spread {
        /// Slices per 4D stage.
        slices: u32,
    },
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_are_named_and_found_by_name() {
        for (name, s) in PRESETS {
            assert_eq!(FillStrategy::preset(name), Some(s));
            assert_eq!(s.name(), name);
        }
        assert_eq!(FillStrategy::preset("fast"), None);
        let custom = FillStrategy { pairs: LayerPairs::OneByOne, ..FillStrategy::software() };
        assert_eq!(custom.name(), "custom");
    }

    #[test]
    fn each_enum_implies_the_switches_it_stands_for() {
        let s = |runs| FillStrategy { runs, ..FillStrategy::software() };
        assert!(!s(RunJoining::Separate).joins_runs() && !s(RunJoining::Separate).seeds_joined());
        assert!(s(RunJoining::Combined).joins_runs() && !s(RunJoining::Combined).seeds_joined());
        assert!(s(RunJoining::Seeded).seeds_joined() && !s(RunJoining::Seeded).folds_seed());
        assert!(s(RunJoining::SeededFolded).joins_runs() && s(RunJoining::SeededFolded).folds_seed());
        let u = |under_background| FillStrategy { under_background, ..FillStrategy::plain() };
        assert!(!u(UnderBackground::Nothing).additive_first());
        assert!(u(UnderBackground::Additive).additive_first() && !u(UnderBackground::Additive).fuses_background());
        assert!(u(UnderBackground::AdditiveFused).additive_first() && u(UnderBackground::AdditiveFused).fuses_background());
        let t = |sparse_stages| FillStrategy { sparse_stages, ..FillStrategy::plain() };
        assert!(!t(SparseStages::Sampled).texel_polygons() && !t(SparseStages::Sampled).grid_bands());
        assert!(t(SparseStages::TexelPolygons).texel_polygons() && !t(SparseStages::TexelPolygons).grid_bands());
        assert!(t(SparseStages::TexelPolygonsOnBands).grid_bands());
    }

    #[test]
    fn the_adapter_picks_the_preset() {
        assert_eq!(FillStrategy::for_device(wgpu::DeviceType::Cpu), FillStrategy::software());
        for t in [wgpu::DeviceType::DiscreteGpu, wgpu::DeviceType::IntegratedGpu, wgpu::DeviceType::VirtualGpu, wgpu::DeviceType::Other] {
            assert_eq!(FillStrategy::for_device(t), FillStrategy::plain());
        }
    }
}
