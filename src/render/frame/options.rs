//! What a frame is drawn with: the caller's switches (the scene, the depth split, the glare, a
//! test occluder), the work skipped because it contributes nothing, and the fill strategy.

use crate::render::plan::strategy::FillStrategy;

/// What to draw besides the sky.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RenderOptions {
    /// Draw the main-scene stand-in (terrain, buildings).
    pub scene: bool,
    /// Draw the scene first in [0, 0.95] and the sky in [0.99, 1] (early depth rejection of hidden
    /// sky). Off: the sky is painted first over the whole screen, then the scene, as without the split.
    pub depth_split: bool,
    /// Draw the sun glare (and run its occlusion queries).
    pub glare: bool,
    /// Draw a test occluder into the scene's depth.
    pub occluder: Option<Occluder>,
    /// Draw a flat wall of the scene's own shading at a known place (what aerial perspective is
    /// measured on).
    pub wall: Option<TestWall>,
    /// Work skipped because it would contribute nothing (all on by default; off to measure
    /// what each saves).
    pub skips: Skips,
    /// How the sky's pixels are filled: reduced buffers and the tricks that go with them, a
    /// preset per kind of adapter ([`FillStrategy::for_device`]).
    pub strategy: FillStrategy,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self { scene: true, depth_split: true, glare: true, occluder: None, wall: None, skips: Skips::default(), strategy: FillStrategy::default() }
    }
}

impl RenderOptions {
    /// These options filling the sky's pixels with `strategy`.
    pub fn with_strategy(self, strategy: FillStrategy) -> Self {
        Self { strategy, ..self }
    }

    /// These options for an environment map: light from the sky only. No glare (an effect of
    /// the viewing camera, which the glare pass also leaves out of any frame marked `env_map`),
    /// and the main scene's stand-in only `with_scene`.
    pub fn for_environment_map(self, with_scene: bool) -> Self {
        Self { glare: false, scene: with_scene, ..self }
    }
}

/// The renderer's skips of work that contributes nothing to the frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Skips {
    /// Texture stages whose term is black this frame are not sampled, and alpha-blended or
    /// additive draws whose every term is (black and transparent) are not drawn.
    pub dark_stages: bool,
    /// The star field is not drawn while its colour is transparent (daylight), nor its stars
    /// too faint this frame to add half a level of 255 (dusk).
    pub invisible_stars: bool,
    /// The `lut` tables and the sky-view map are not recomputed while nothing they depend on moved.
    pub unchanged_tables: bool,
    /// With the main scene drawn, billboards and quads entirely below the horizon (by more than
    /// [`crate::render::plan::visibility::SCENE_COVERS_BELOW_DEG`]) are not drawn, nor the rows of dome triangles there (domes
    /// are drawn by rows with `unneeded_mips`): the scene covers that part of the sky.
    pub below_horizon: bool,
    /// Dome layers whose band of elevations the frame does not show (a fog band under a view
    /// of the zenith) are not drawn, nor composited; nor are billboards and quads wholly
    /// outside the frame, nor the parts of the main-scene stand-in wholly outside the view, nor
    /// the glare's occlusion queries while the sun's disc lies wholly outside the frame (both
    /// would count no sample: that result stands for them).
    pub off_screen: bool,
    /// Texture stages that no pixel of a draw minifies are sampled from level 0 alone (the same
    /// texels; lavapipe then skips computing the level of detail).
    pub unneeded_mips: bool,
    /// The frame's colour is not cleared when the background (the first run of reduced dome
    /// layers, composited or fused with the skydome's stars) writes every pixel before anything
    /// reads it, nor the depth while it still holds the clear value: no main scene drawn into
    /// that depth view since the renderer last cleared it. Each clear is a pass over the frame.
    pub covered_clears: bool,
}

impl Default for Skips {
    fn default() -> Self {
        Self { dark_stages: true, invisible_stars: true, unchanged_tables: true, below_horizon: true, off_screen: true, unneeded_mips: true, covered_clears: true }
    }
}

/// A square in the world facing the viewer, lit and given the atmosphere in front of it as the
/// scene's terrain is (shaders/scene.wgsl's `vs_main`): a scene point at a known distance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TestWall {
    /// Its centre in the world, m.
    pub centre_m: [f32; 3],
    /// Half its side, m.
    pub half_size_m: f32,
    /// Its albedo (display values, as the terrain's).
    pub albedo: [f32; 3],
}

/// A rectangle in clip space (NDC x, y) drawn into the scene's depth: a known occluder.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Occluder {
    /// Left, bottom corner (NDC).
    pub min: [f32; 2],
    /// Right, top corner (NDC).
    pub max: [f32; 2],
}
