//! The frame plan: how the sky phase's draws reach the frame, decided by a pure function with no
//! GPU types ([`plan`]), so that unit tests reach every decision without a device. Recording
//! ([`crate::render::frame::renderer::SkyRenderer::render`]) only carries the plan out.
//!
//! The decisions, in order:
//! 1. Draw order: items sorted by priority; full-resolution additive draws moved past the
//!    reduced additive layers after them (they commute), so reduced layers share runs; items
//!    that go to a buffer only in company and found none stay at full resolution.
//! 2. Runs of consecutive reduced layers, each into a buffer as fine as its finest layer.
//! 3. The background: the first run, when nothing precedes it, drawn first in the scene's pass;
//!    the runs after it joined to it while every draw between two can go under a run
//!    ([`RunJoining`](crate::render::plan::strategy::RunJoining)); the first two joined runs seeded
//!    rather than combined, any above them combined over the seeded buffer.
//! 4. What goes under the background ([`UnderBackground`](crate::render::plan::strategy::UnderBackground)):
//!    the additive draws after it, and one of them as the background itself.
//! 5. Inside each run: the seeding of a seeded buffer, its first layer over the seed, pairs, and
//!    costly layers drawn apart at their own resolution and composited into the run's buffer.
//! 6. Which clears the frame can skip.

pub mod items;
pub mod map_updates;
pub mod mip_bounds;
pub mod resolution;
pub mod strategy;
pub mod visibility;

use std::ops::Range;

use self::items::{DrawItem, OwnBuffer, Placement, Target};
use crate::render::plan::resolution::Divisor;
use crate::render::plan::strategy::FillStrategy;

/// The target a frame draws into: the HDR target for a physical sky model unless the strategy
/// draws physical skies display-referred ([`strategy::PhysicalTarget`]); painted skies always
/// go to the display target.
pub fn frame_target(physical: bool, strategy: &FillStrategy) -> Target {
    match (physical, strategy.physical_target) {
        (true, strategy::PhysicalTarget::Hdr) => Target::Hdr,
        _ => Target::Display,
    }
}

/// Whether a frame's blended layers are drawn as the HDR path's blend over the model's sky would
/// leave them: a physical sky drawn display-referred with [`strategy::PhysicalTarget::DisplayMatched`].
pub fn matches_hdr_picture(physical: bool, strategy: &FillStrategy) -> bool {
    physical && strategy.physical_target == strategy::PhysicalTarget::DisplayMatched
}

/// What the plan needs to know of the frame besides its draws.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FrameFacts {
    /// The main scene covers part of the frame (drawn, and looking low enough to see it).
    pub scene_in_view: bool,
    /// The renderer has a pass that draws reduced buffers (without one, reduced items are drawn
    /// at full resolution).
    pub reduced_layers: bool,
    /// Clears of what the frame overwrites may be skipped ([`crate::render::frame::options::Skips::covered_clears`]).
    pub covered_clears: bool,
    /// The depth view still holds the clear value (no scene drawn into it since it was cleared).
    pub depth_clean: bool,
}

/// Which run's buffer a draw reads, as bind group 2.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RunInput {
    /// None: the pass's neutral group.
    None,
    /// The combination of run `j` and those above it (`ReducedLayersPass::upper_bind_group`).
    Upper(usize),
    /// The seeded buffer's lower run (`ReducedLayersPass::seed_source`).
    Seed,
    /// Own buffer `p` of the frame ([`SkyPlan::own_buffers`]): the step's item is drawn
    /// beforehand into it (at [`Placement::Reduced`]), and in its place in the run that buffer is
    /// composited into the run's ([`crate::render::frame::pass::Caps::own_buffer`]).
    Own(usize),
}

/// One draw of the plan: item `item` of [`SkyPlan::items`] at `placement`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Step {
    /// Index into the plan's sky items.
    pub item: usize,
    /// How it is drawn.
    pub placement: Placement,
    /// The run buffer it reads.
    pub input: RunInput,
}

/// How a seeded buffer gets the lower run's colour before its layers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Seeding {
    /// Not seeded (every run but a seeded second one), or its first layer covers it all.
    None,
    /// The seeding pass over the whole buffer.
    Whole,
    /// The seeding pass confined to frame pixels `[x, y, width, height]`: where the first layer,
    /// drawn over the seed itself, does not reach.
    Within([u32; 4]),
}

/// One run of reduced layers: drawn into its own buffer before the scene.
#[derive(Debug, Clone, PartialEq)]
pub struct RunPlan {
    /// Its items in the plan's sky items.
    pub range: Range<usize>,
    /// Its buffer's divisor: the finest its layers need.
    pub divisor: Divisor,
    /// The seeding of its buffer.
    pub seeding: Seeding,
    /// Its draws, in order.
    pub draws: Vec<Step>,
}

/// The background: the first run (or the joined runs' combination), drawn first in the scene's
/// pass.
#[derive(Debug, Clone, PartialEq)]
pub enum Background {
    /// The additive draws `first` onto the cleared frame, then the background's composite (over
    /// them, blended, when there are any).
    Composite {
        /// Items drawn first.
        first: Vec<usize>,
    },
    /// One additive draw as the background itself ([`Placement::Background`]), the background's
    /// composite confined to `gap` first (where that draw does not reach), and the other draws
    /// under the background after it.
    Fused {
        /// Pixels the fused draw leaves uncovered.
        gap: Option<[u32; 4]>,
        /// The fused draw.
        fused: Step,
        /// The others, each under the background.
        others: Vec<Step>,
    },
}

/// What the sky phase records, in order.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SkyStep {
    /// One draw.
    Draw(Step),
    /// The composite of run `r` in its place (runs not joined to the background).
    Composite(usize),
}

/// The plan of a frame's sky phase and the reduced runs before it.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SkyPlan {
    /// The sky phase's items in drawing order: (pass index, item).
    pub items: Vec<(usize, DrawItem)>,
    /// The runs of reduced layers.
    pub runs: Vec<RunPlan>,
    /// Runs joined into the background (0: no background; 1: the first run alone).
    pub chain: usize,
    /// The first two runs joined by seeding the second's buffer with the first.
    pub seeded: bool,
    /// The joined runs' combinations' divisors: combination j holds runs j and above, or seeded,
    /// runs j + 1 and above (none for a chain of two).
    pub combined: Vec<Divisor>,
    /// The background, if the first run is one.
    pub background: Option<Background>,
    /// The sky phase's steps.
    pub steps: Vec<SkyStep>,
    /// The frame's colour is cleared (not every pixel is written by the background first).
    pub clear_color: bool,
    /// The depth is cleared.
    pub clear_depth: bool,
    /// Full-screen composites of runs, the background's included.
    pub composites: u32,
    /// Draws put under the background.
    pub drawn_first: u32,
    /// The seeded buffer's first layer goes over the seed itself.
    pub seed_folded: bool,
    /// Pairs of reduced layers drawn at once.
    pub layers_paired: u32,
    /// The buffers of layers drawn apart from their runs ([`RunInput::Own`]).
    pub own_buffers: Vec<OwnBuffer>,
}

impl SkyPlan {
    /// Whether more than one run is joined into the background.
    pub fn joined(&self) -> bool {
        self.chain >= 2
    }

    /// The runs' divisors, in draw order.
    pub fn divisors(&self) -> Vec<Divisor> {
        self.runs.iter().map(|r| r.divisor).collect()
    }

    /// Every draw the plan records, as (pass index, the pass's item key, placement), in
    /// recording order: the passes build the pipelines for these and no others.
    pub fn uses(&self) -> Vec<(usize, usize, Placement)> {
        let first = match &self.background {
            Some(Background::Composite { first }) => first.iter().map(|&item| Step { item, placement: Placement::First, input: RunInput::None }).collect(),
            Some(Background::Fused { fused, others, .. }) => std::iter::once(*fused).chain(others.iter().copied()).collect(),
            None => Vec::new(),
        };
        let runs = self.runs.iter().flat_map(|r| r.draws.iter().copied());
        let sky = self.steps.iter().filter_map(|s| match s {
            SkyStep::Draw(step) => Some(*step),
            SkyStep::Composite(_) => None,
        });
        runs.chain(first).chain(sky).map(|step| (self.items[step.item].0, self.items[step.item].1.key, step.placement)).collect()
    }
}

/// Plans the sky phase: `items` are its draws in list order, (pass index, item).
pub fn plan(mut items: Vec<(usize, DrawItem)>, strategy: &FillStrategy, facts: FrameFacts) -> SkyPlan {
    // Sky objects and stars interleave by priority; list order among equals.
    items.sort_by_key(|(_, it)| it.priority);
    let reduce = strategy.dome_resolution.divisors().0.reduces();
    if reduce {
        join_additive_runs(&mut items);
        leave_lone_joiners(&mut items);
    }
    let mut runs = if reduce && facts.reduced_layers { reduced_runs(&items, false) } else { Vec::new() };
    let mut divisors = run_divisors(&items, &runs);
    let mut chain = joined_chain(&items, &runs, strategy);
    // The first run split where it gets finer, unless its two first runs as they are seed
    // already: the split would then add a combination pass for the runs above them.
    let seeds_already = chain == 2 && divisors[1].resolves(divisors[0]);
    if strategy.seeds_joined() && !seeds_already && split_first_run(&items, &mut runs) {
        divisors = run_divisors(&items, &runs);
        chain = joined_chain(&items, &runs, strategy);
    }
    // The first run, when the sky phase draws nothing before it, is the frame's background:
    // drawn first in the scene's pass, over the clear colour.
    let background = runs.first().is_some_and(|&(start, _)| start == 0);
    let joined = chain >= 2;
    // The first two joined runs, the second at least as fine: the second's buffer is seeded with
    // the first and ends as their combination. Joined runs above them (or all, not seeded) are
    // combined from the top down. Under a combination, only runs that touch (nothing drawn
    // between them) are seeded: a draw between would need the runs above it without the first,
    // which a combination over the seeded buffer no longer tells apart.
    let touching = chain == 2 || runs.get(1).is_some_and(|r| r.0 == runs[0].1);
    let seeded = strategy.seeds_joined() && chain >= 2 && touching && divisors[1].resolves(divisors[0]);
    let combined = combined_divisors(&divisors[usize::from(seeded)..chain]);
    let first = under_background(&items, &runs, background && strategy.additive_first() && !facts.scene_in_view);
    // One of them that covers the frame can be the background itself; the others then go under
    // the runs above the first (joined) or onto it.
    let fused = first.clone().filter(|_| strategy.fuses_background()).find(|&k| items[k].1.caps.background[usize::from(joined)]).filter(|&f| {
        first.clone().filter(|&k| k != f).all(|k| {
            let caps = &items[k].1.caps;
            if joined {
                caps.under_run
            } else {
                caps.first
            }
        })
    });
    let background_plan = background.then(|| match fused {
        Some(f) => Background::Fused {
            gap: items[f].1.caps.background_gap,
            fused: Step { item: f, placement: Placement::Background { joined }, input: RunInput::Upper(0) },
            others: first
                .clone()
                .filter(|&k| k != f)
                .map(|k| {
                    if joined {
                        Step { item: k, placement: Placement::UnderRun, input: RunInput::Upper(0) }
                    } else {
                        Step { item: k, placement: Placement::First, input: RunInput::None }
                    }
                })
                .collect(),
        },
        None => Background::Composite { first: first.clone().collect() },
    });
    let mut seed_folded = false;
    let mut layers_paired = 0;
    let mut own_buffers = Vec::new();
    let run_plans: Vec<RunPlan> = runs
        .iter()
        .zip(&divisors)
        .enumerate()
        .map(|(r, (&(start, end), &divisor))| {
            let (seeding, draws, folded) = run_draws(&items, (start..end, divisor), strategy, (r == 1 && seeded, &mut own_buffers));
            seed_folded |= folded;
            layers_paired += draws.iter().filter(|s| matches!(s.placement, Placement::Pair { .. })).count() as u32;
            RunPlan { range: start..end, divisor, seeding, draws }
        })
        .collect();
    let steps = sky_steps(&items, &runs, chain, first.clone());
    // The background writes every pixel before anything reads it: the fused draw (and the
    // composite below its dome), or the composite's full-screen triangle, unless additive draws
    // went onto the cleared frame before it.
    let color_covered = facts.covered_clears && background && (fused.is_some() || first.is_empty());
    let depth_clean = facts.covered_clears && facts.depth_clean;
    SkyPlan {
        composites: (runs.len() + 1).saturating_sub(chain.max(1)) as u32,
        drawn_first: first.len() as u32,
        items,
        runs: run_plans,
        chain,
        seeded,
        combined,
        background: background_plan,
        steps,
        clear_color: !color_covered,
        clear_depth: !depth_clean,
        seed_folded,
        layers_paired,
        own_buffers,
    }
}

/// The additive draws right after the background that go under it, first onto the cleared frame
/// (`allowed`: there is a background, the strategy puts draws under it, and no scene covers part
/// of the frame, where they would pay for its pixels, which the depth test spares them).
fn under_background(items: &[(usize, DrawItem)], runs: &[(usize, usize)], allowed: bool) -> Range<usize> {
    let Some(&(_, start)) = runs.first().filter(|_| allowed) else { return 0..0 };
    let limit = runs.get(1).map_or(items.len(), |r| r.0);
    let end = (start..limit).find(|&k| !(items[k].1.additive && items[k].1.caps.first)).unwrap_or(limit);
    // Blending the background costs a full-screen pass: worth it only when a draw spanning the
    // frame (the skydome's fine stars) is among them.
    if items[start..end].iter().any(|(_, it)| it.caps.spans_frame) {
        start..end
    } else {
        0..0
    }
}

/// A run's buffer is at least this many times finer along each side than a costly layer needs
/// (by area: [`Divisor::mean`]) before the layer goes to a buffer of its own ([`RunInput::Own`]):
/// its fragments then cost a quarter as many or fewer, and the composite into the run's buffer costs about what a plain
/// layer's fragment does.
const OWN_BUFFER_RATIO: f32 = 2.0;

/// The seeding and draws of the run `range` at `divisor`; `seeded`: the seeded second buffer.
/// Also whether its first layer went over the seed itself. Layers drawn apart from the run get
/// buffers in `own` ([`RunInput::Own`]).
fn run_draws(
    items: &[(usize, DrawItem)],
    (range, divisor): (Range<usize>, Divisor),
    strategy: &FillStrategy,
    (seeded, own): (bool, &mut Vec<OwnBuffer>),
) -> (Seeding, Vec<Step>, bool) {
    let (start, end) = (range.start, range.end);
    let pair = |k: usize, over_seed: bool| pair_at(items, k, end, over_seed).filter(|_| strategy.pairs_layers());
    let mut draws = Vec::new();
    let mut k = start;
    let mut seeding = Seeding::None;
    let mut folded = false;
    if seeded {
        let caps = &items[start].1.caps;
        if strategy.folds_seed() && caps.over_seed {
            // The first layer goes over the seed itself; the seeding pass fills what it does not
            // reach (below its dome), first. With the layer after it, at once, where they pair.
            seeding = caps.background_gap.map_or(Seeding::None, Seeding::Within);
            match pair(start, true) {
                Some(upper) => {
                    draws.push(Step { item: start, placement: Placement::Pair { upper, over_seed: true }, input: RunInput::Seed });
                    k += 2;
                }
                None => {
                    draws.push(Step { item: start, placement: Placement::OverSeed, input: RunInput::Seed });
                    k += 1;
                }
            }
            folded = true;
        } else {
            seeding = Seeding::Whole;
        }
    }
    while k < end {
        match pair(k, false) {
            Some(upper) => {
                draws.push(Step { item: k, placement: Placement::Pair { upper, over_seed: false }, input: RunInput::None });
                k += 2;
            }
            None => {
                let apart = items[k].1.caps.own_buffer.filter(|o| strategy.own_buffers() && o.divisor.mean() >= OWN_BUFFER_RATIO * divisor.mean());
                let input = match apart {
                    Some(o) => {
                        own.push(o);
                        RunInput::Own(own.len() - 1)
                    }
                    None => RunInput::None,
                };
                draws.push(Step { item: k, placement: Placement::Reduced, input });
                k += 1;
            }
        }
    }
    (seeding, draws, folded)
}

/// The sky phase's steps: every item not in a run nor under the background, and the composites
/// of the runs not joined into the background, in order.
fn sky_steps(items: &[(usize, DrawItem)], runs: &[(usize, usize)], chain: usize, first: Range<usize>) -> Vec<SkyStep> {
    let mut steps = Vec::new();
    let mut k = 0;
    while k < items.len() {
        // Already under the background.
        if k == first.start && !first.is_empty() {
            k = first.end;
            continue;
        }
        if let Some(r) = runs.iter().position(|&(start, _)| start == k) {
            // The background's runs are already in the frame.
            if r >= chain {
                steps.push(SkyStep::Composite(r));
            }
            k = runs[r].1;
            continue;
        }
        // Between two joined runs: under the combination of those above.
        let step = match (1..chain).find(|&j| k >= runs[j - 1].1 && k < runs[j].0) {
            Some(j) => Step { item: k, placement: Placement::UnderRun, input: RunInput::Upper(j) },
            None => Step { item: k, placement: Placement::Plain, input: RunInput::None },
        };
        steps.push(SkyStep::Draw(step));
        k += 1;
    }
    steps
}

/// The key of the item after item `k` of a run ending at `end` when the two can be drawn at once
/// by their pass (`over_seed`: item `k` as a seeded buffer's first layer). A pass states pairs
/// with its next item in its own priority order ([`crate::render::frame::pass::Caps::pair_next`]): two items of
/// one pass next to each other here are next to each other there, since the sort is stable and
/// [`join_additive_runs`] moves only additive draws past additive layers, never between the
/// alpha-blended layers that pair.
fn pair_at(items: &[(usize, DrawItem)], k: usize, end: usize, over_seed: bool) -> Option<usize> {
    let ((i, lower), (j, upper)) = (items.get(k)?, items.get(k + 1).filter(|_| k + 1 < end)?);
    (i == j && lower.caps.pair_next.is_some_and(|(key, ok)| key == upper.key && ok[usize::from(over_seed)])).then_some(upper.key)
}

/// Moves every full-resolution additive draw of the sky phase past the reduced additive layers
/// that follow it. Additive draws commute (target + a + b, clamped, in either order), so the
/// picture is the same; reduced layers that only such draws kept apart (the skydome's fine stars
/// between it and the galaxy) then share a run and one composite.
fn join_additive_runs(list: &mut [(usize, DrawItem)]) {
    let mut moved = true;
    while moved {
        moved = false;
        for k in 0..list.len().saturating_sub(1) {
            let (a, b) = (list[k].1, list[k + 1].1);
            if !a.reduced && a.additive && b.reduced && b.additive {
                list.swap(k, k + 1);
                moved = true;
            }
        }
    }
}

/// Items that go to a reduced buffer only in company ([`DrawItem::joins_only`]) and found none
/// (a run of nothing else) are drawn at full resolution.
fn leave_lone_joiners(list: &mut [(usize, DrawItem)]) {
    for (start, end) in reduced_runs(list, false) {
        if list[start..end].iter().all(|(_, it)| it.joins_only) {
            for (_, it) in &mut list[start..end] {
                it.reduced = false;
                it.divisor = Divisor::FULL;
            }
        }
    }
}

/// Each run's divisor: its buffer is as fine as its finest layer needs.
fn run_divisors(items: &[(usize, DrawItem)], runs: &[(usize, usize)]) -> Vec<Divisor> {
    runs.iter().map(|&(start, end)| items[start..end].iter().map(|(_, it)| it.divisor).reduce(Divisor::finer).unwrap_or(Divisor::FULL)).collect()
}

/// How many runs form the background's chain: the first run, when the sky phase draws nothing
/// before it, is the frame's background (drawn first in the scene's pass, over the clear
/// colour; none otherwise), and the runs after it join it for as long as every draw between two
/// can be drawn after it, corrected by the runs above it (a lightning bolt between the clouds and
/// the fog).
fn joined_chain(items: &[(usize, DrawItem)], runs: &[(usize, usize)], strategy: &FillStrategy) -> usize {
    let background = runs.first().is_some_and(|&(start, _)| start == 0);
    let mut chain = usize::from(background);
    while background && strategy.joins_runs() && chain < runs.len() && items[runs[chain - 1].1..runs[chain].0].iter().all(|(_, it)| it.caps.under_run) {
        chain += 1;
    }
    chain
}

/// Divisors of the combinations of a chain of joined runs (their buffers' `divisors`, lowest
/// first): combination j holds runs j.. and is as fine as the finest of them. The last run
/// needs none (its own buffer); fewer than two runs, none at all.
fn combined_divisors(divisors: &[Divisor]) -> Vec<Divisor> {
    let n = divisors.len();
    (0..n.saturating_sub(1)).map(|j| divisors[j..].iter().copied().reduce(Divisor::finer).unwrap_or(Divisor::FULL)).collect()
}

/// The runs of consecutive items marked `reduced` in a sorted phase list: (start, end) indices.
/// `split_first`: a run at the start of the list whose layers get finer part-way (the skydome's
/// at a quarter of the resolution, the clouds' at half, when the billboards between them lie out
/// of the frame) is two runs, the coarse layers in their own buffer seeding the finer one
/// ([`Seeded`](crate::render::plan::strategy::RunJoining::Seeded)), rather than every layer at the
/// finer resolution; runs after it (past rain drawn between the clouds and the fog) are then
/// combined over the seeded buffer.
fn reduced_runs(list: &[(usize, DrawItem)], split_first: bool) -> Vec<(usize, usize)> {
    let mut runs = Vec::new();
    let mut k = 0;
    while k < list.len() {
        if list[k].1.reduced {
            let start = k;
            while k < list.len() && list[k].1.reduced {
                k += 1;
            }
            runs.push((start, k));
        } else {
            k += 1;
        }
    }
    if split_first {
        split_first_run(list, &mut runs);
    }
    runs
}

/// Splits the first of `runs`, when it starts the list, where its layers get finer
/// ([`reduced_runs`]'s `split_first`); whether it did.
fn split_first_run(list: &[(usize, DrawItem)], runs: &mut Vec<(usize, usize)>) -> bool {
    let Some(&(0, end)) = runs.first() else { return false };
    let divisor = |k: usize| list[k].1.divisor;
    let Some(k) = (1..end).find(|&k| (0..k).all(|j| divisor(k).finer_than(divisor(j)))) else { return false };
    runs.splice(0..1, [(0, k), (k, end)]);
    true
}

#[cfg(test)]
mod tests;
