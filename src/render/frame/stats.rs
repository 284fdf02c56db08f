//! What a frame and a sky upload report: the renderer's counters, read by the window's
//! statistics, the frame snapshot and the benchmarks.

use crate::render::plan::resolution::Divisor;

/// Counters of the last frame, for the stats panel and logs.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FrameStats {
    /// Draw calls recorded.
    pub draw_calls: u32,
    /// Sky objects drawn.
    pub objects_drawn: u32,
    /// Sky objects hidden (ref alpha, tier, toggle, view).
    pub objects_hidden: u32,
    /// Stars in the field after the magnitude cutoff.
    pub stars: u32,
    /// Of those, the stars drawn this frame: bright enough to add half a level of 255 somewhere
    /// ([`Skips::invisible_stars`]).
    pub stars_drawn: u32,
    /// Texture stages of sky objects not sampled because their term is black this frame.
    pub stages_skipped: u32,
    /// Alpha-blended and additive draws of sky objects left out because every term of theirs is
    /// black and transparent this frame (they would leave the frame as it is).
    pub draws_dark: u32,
    /// Sky objects not drawn because their ref colour's alpha is 0 this frame.
    pub objects_ref_hidden: u32,
    /// Sky objects not drawn because they are below the horizon, behind the main scene.
    pub objects_below_horizon: u32,
    /// Dome layers not drawn because the frame does not show their elevations, and billboards
    /// and quads not drawn because they lie wholly outside the frame.
    pub objects_off_screen: u32,
    /// Texture stages sampled from level 0 alone (no pixel minifies them), over every draw.
    pub stages_level0: u32,
    /// Sky objects drawn into a reduced-resolution buffer ([`dome_resolution`](crate::render::plan::strategy::FillStrategy::dome_resolution)).
    pub objects_reduced: u32,
    /// Each run of reduced layers this frame, in draw order: its buffer's divisor (2: half the
    /// frame's width and height, 2.5: two fifths, 4: a quarter). One composite each.
    pub reduced_runs: Vec<Divisor>,
    /// Full-screen composites of those runs (the background included): one for all the runs
    /// joined ([`Combined`](crate::render::plan::strategy::RunJoining::Combined)).
    pub composites: u32,
    /// Additive draws put under the background ([`Additive`](crate::render::plan::strategy::UnderBackground::Additive)).
    pub drawn_first: u32,
    /// One of them (the skydome's fine stars) covered the frame and was drawn as the background
    /// itself, its run's colour plus its term: no separate composite of the background.
    pub background_fused: bool,
    /// The first two runs were joined by seeding the second's buffer with the first
    /// ([`Seeded`](crate::render::plan::strategy::RunJoining::Seeded)): no combining pass.
    pub seeded: bool,
    /// The seeded buffer's first layer was drawn over the lower run itself ([`SeededFolded`](crate::render::plan::strategy::RunJoining::SeededFolded)).
    pub seed_folded: bool,
    /// Pairs of reduced layers drawn at once ([`AtOnce`](crate::render::plan::strategy::LayerPairs::AtOnce)).
    pub layers_paired: u32,
    /// Costly layers drawn apart from their runs into buffers of their own
    /// ([`OwnBuffer`](crate::render::plan::strategy::CostlyLayers::OwnBuffer)).
    pub own_buffers: u32,
    /// Triangles of texel polygons drawn in place of a sparse stage's sample
    /// ([`TexelPolygons`](crate::render::plan::strategy::SparseStages::TexelPolygons)).
    pub texel_triangles: u32,
    /// Scissor rectangles in which the background without its sparse stage went as one triangle
    /// over the frame ([`TexelPolygonsOnBands`](crate::render::plan::strategy::SparseStages::TexelPolygonsOnBands)).
    pub background_rects: u32,
    /// Draws added to a run of reduced layers only because the run was there
    /// ([`DrawItem::joins_only`]: the lightning flash, [`InRun`](crate::render::plan::strategy::FlashPlacement::InRun)).
    pub joined_runs_only: u32,
    /// Clears of the frame left out ([`Skips::covered_clears`]): the colour's, the depth's.
    pub clears_skipped: u32,
    /// The star field was not drawn: transparent this frame.
    pub stars_skipped: bool,
    /// The `lut` or `precomputed` tables were not rebuilt: nothing they depend on moved.
    pub tables_skipped: bool,
    /// The sky-view map was not recomputed: nothing it depends on moved.
    pub map_skipped: bool,
    /// Texels of the sky-view map computed this frame (a slice of it while a moving sun's maps are
    /// spread over frames: [`crate::render::plan::map_updates`]).
    pub map_texels: u32,
    /// Particles alive (every emitter).
    pub particles: u32,
}

/// What the last sky upload did with the textures of the sky before it.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct UploadStats {
    /// Textures uploaded (new files, or files whose content changed).
    pub textures_uploaded: u32,
    /// Textures taken over from the previous sky unchanged.
    pub textures_reused: u32,
}
