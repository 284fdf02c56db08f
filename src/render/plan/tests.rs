//! The frame plan's decisions, without a GPU.

use super::*;
use crate::render::plan::items::Caps;
use crate::render::plan::strategy::{CostlyLayers, LayerPairs, RunJoining, UnderBackground};

fn item(key: usize, reduced: bool, additive: bool) -> (usize, DrawItem) {
    (0, DrawItem { reduced, additive, divisor: if reduced { Divisor::HALF } else { Divisor::FULL }, ..DrawItem::new(0, key) })
}

#[test]
fn additive_draws_move_past_reduced_additive_layers_only() {
    // Skydome (reduced, opaque), its fine stars (full, additive), galaxy (reduced, additive),
    // sun (full, additive), clouds (reduced, alpha), fog (reduced, alpha).
    let list = [item(0, true, false), item(1, false, true), item(2, true, true), item(3, false, true), item(4, true, false), item(5, true, false)];
    let mut joined = list;
    join_additive_runs(&mut joined);
    let keys: Vec<usize> = joined.iter().map(|(_, it)| it.key).collect();
    // The stars go past the galaxy; the sun stays before the alpha-blended clouds.
    assert_eq!(keys, [0, 2, 1, 3, 4, 5]);
    assert_eq!(reduced_runs(&list, true), [(0, 1), (2, 3), (4, 6)]);
    assert_eq!(reduced_runs(&joined, true), [(0, 2), (4, 6)]);
    // Nothing to join: unchanged.
    let plain = [item(0, true, false), item(1, false, false), item(2, true, true)];
    let mut unchanged = plain;
    join_additive_runs(&mut unchanged);
    assert_eq!(unchanged, plain);
}

#[test]
fn items_that_only_join_runs_stay_at_full_resolution_alone() {
    let joiner = |key: usize| (0, DrawItem { reduced: true, additive: true, divisor: Divisor::QUARTER, joins_only: true, ..DrawItem::new(0, key) });
    // The flash after the fog's run joins it, the bolts before it moving past it; after an
    // alpha-blended billboard, or first, it is alone.
    let mut after_bolts = [item(0, true, false), item(1, false, true), joiner(2)];
    join_additive_runs(&mut after_bolts);
    leave_lone_joiners(&mut after_bolts);
    assert_eq!(reduced_runs(&after_bolts, true), [(0, 2)]);
    assert_eq!(after_bolts[1].1.divisor, Divisor::QUARTER);
    let mut after_moon = [item(0, true, false), item(1, false, false), joiner(2)];
    join_additive_runs(&mut after_moon);
    leave_lone_joiners(&mut after_moon);
    assert_eq!(reduced_runs(&after_moon, true), [(0, 1)]);
    let mut alone = [joiner(0), item(1, false, false), joiner(2), joiner(3)];
    leave_lone_joiners(&mut alone);
    assert!(alone.iter().all(|(_, it)| !it.reduced && it.divisor == Divisor::FULL), "{alone:?}");
}

#[test]
fn a_first_run_that_gets_finer_is_split_where_it_does() {
    let at = |key: usize, divisor: u8| (0, DrawItem { reduced: true, divisor: Divisor::whole(divisor), ..DrawItem::new(0, key) });
    // Skydome and galaxy at a quarter, clouds at half, fog at a quarter: the billboards
    // between the skydome and the clouds out of the frame.
    let lone = [at(0, 4), at(1, 4), at(2, 2), at(3, 4)];
    assert_eq!(reduced_runs(&lone, true), [(0, 2), (2, 4)]);
    assert_eq!(reduced_runs(&lone, false), [(0, 4)]);
    // Finer first, or all alike: one run.
    assert_eq!(reduced_runs(&[at(0, 2), at(1, 4)], true), [(0, 2)]);
    assert_eq!(reduced_runs(&[at(0, 4), at(1, 4)], true), [(0, 2)]);
    // Not at the start of the list: as they are.
    let after = [item(0, false, false), at(1, 4), at(2, 2)];
    assert_eq!(reduced_runs(&after, true), [(1, 3)]);
    // Followed by other runs (rain between the clouds and the fog): split all the same.
    let two = [at(0, 4), at(1, 2), item(2, false, false), at(3, 2)];
    assert_eq!(reduced_runs(&two, true), [(0, 1), (1, 2), (3, 4)]);
    assert_eq!(reduced_runs(&two, false), [(0, 2), (3, 4)]);
    // A physical skydome coarser across than down (8 x 5) under clouds at 2: the clouds are
    // finer along both sides, so they split off. Finer across only (5 x 8 under 8 x 5): not.
    let each = |key: usize, across: f32, down: f32| {
        (0, DrawItem { reduced: true, divisor: Divisor::at_most_each((across, down), Divisor::HALF, Divisor::EIGHTH), ..DrawItem::new(0, key) })
    };
    assert_eq!(reduced_runs(&[each(0, 8.0, 5.0), at(1, 2)], true), [(0, 1), (1, 2)]);
    assert_eq!(reduced_runs(&[each(0, 8.0, 5.0), each(1, 5.0, 8.0)], true), [(0, 2)]);
}

#[test]
fn each_combination_is_as_fine_as_its_finest_run() {
    // Skydome at a quarter, clouds at half, fog at a quarter: combination 0 holds all three,
    // combination 1 the clouds and the fog; the fog's own buffer stands for itself.
    let [half, quarter] = [Divisor::HALF, Divisor::QUARTER];
    assert_eq!(combined_divisors(&[quarter, half, quarter]), [half, half]);
    assert_eq!(combined_divisors(&[quarter, quarter, half]), [half, half]);
    assert_eq!(combined_divisors(&[half, quarter]), [half]);
    assert_eq!(combined_divisors(&[Divisor::whole(3), Divisor::whole(3), Divisor::at_most(2.6, half, quarter)]), [Divisor::at_most(2.5, half, quarter); 2]);
    // Along each side on its own: the finer of both.
    let [wide, tall] = [(8.0, 5.0), (5.0, 8.0)].map(|f| Divisor::at_most_each(f, half, Divisor::EIGHTH));
    assert_eq!(combined_divisors(&[wide, tall]), [Divisor::whole(5)]);
    assert_eq!(combined_divisors(&[quarter]), Vec::<Divisor>::new());
    assert_eq!(combined_divisors(&[]), Vec::<Divisor>::new());
}

const FACTS: FrameFacts = FrameFacts { scene_in_view: false, reduced_layers: true, covered_clears: true, depth_clean: false };

/// A night sky as the renderer meets it looking up: the skydome (a reduced dome), its fine
/// stars (additive, spanning the frame, able to be the background), a bolt (additive, able to
/// go under a run) and two cloud layers (reduced, pairable), then the sun (plain).
fn night(bolt_under_run: bool) -> Vec<(usize, DrawItem)> {
    let dome = Caps { over_seed: true, background: [true, true], ..Caps::default() };
    let stars = Caps { first: true, under_run: true, spans_frame: true, background: [true, true], ..Caps::default() };
    let clouds = Caps { over_seed: true, pair_next: Some((4, [true, true])), background_gap: Some([0, 100, 320, 80]), ..Caps::default() };
    vec![
        (0, DrawItem { priority: 0, reduced: true, divisor: Divisor::QUARTER, caps: dome, ..DrawItem::new(0, 0) }),
        (0, DrawItem { priority: 1, additive: true, caps: stars, ..DrawItem::new(1, 1) }),
        (1, DrawItem { priority: 2, additive: true, caps: Caps { under_run: bolt_under_run, ..Caps::default() }, ..DrawItem::new(2, 0) }),
        (0, DrawItem { priority: 3, reduced: true, divisor: Divisor::HALF, caps: clouds, ..DrawItem::new(3, 3) }),
        (0, DrawItem { priority: 3, reduced: true, divisor: Divisor::HALF, ..DrawItem::new(3, 4) }),
        (0, DrawItem { priority: 9, additive: true, ..DrawItem::new(9, 5) }),
    ]
}

fn keys(plan: &SkyPlan, steps: &[Step]) -> Vec<usize> {
    steps.iter().map(|s| plan.items[s.item].1.key).collect()
}

#[test]
fn a_second_run_seeds_only_when_finer_along_both_sides() {
    let with_dome = |across: f32, down: f32| {
        let mut items = night(true);
        items[0].1.divisor = Divisor::at_most_each((across, down), Divisor::FULL, Divisor::EIGHTH);
        plan(items, &FillStrategy::software(), FACTS)
    };
    // A physical skydome's buffer, coarser across than down, under clouds at half: seeded.
    assert!(with_dome(8.0, 3.0).seeded);
    // Finer than the clouds down the frame: the clouds' buffer cannot hold it; combined instead.
    let p = with_dome(8.0, 1.5);
    assert!(!p.seeded && p.combined == [Divisor::at_most_each((2.0, 1.5), Divisor::FULL, Divisor::EIGHTH)], "{p:?}");
}

/// A stormy sky: the skydome (a quarter), the clouds (half, over a seed), rain between the
/// clouds and the fog (additive, able to go under a run when `rain_under_run`), the fog (a
/// quarter).
fn storm(rain_under_run: bool) -> Vec<(usize, DrawItem)> {
    let dome = Caps { over_seed: true, background: [true, true], ..Caps::default() };
    let clouds = Caps { over_seed: true, background_gap: Some([0, 100, 320, 80]), ..Caps::default() };
    vec![
        (0, DrawItem { priority: 0, reduced: true, divisor: Divisor::QUARTER, caps: dome, ..DrawItem::new(0, 0) }),
        (0, DrawItem { priority: 3, reduced: true, divisor: Divisor::HALF, caps: clouds, ..DrawItem::new(3, 1) }),
        (1, DrawItem { priority: 4, additive: true, caps: Caps { under_run: rain_under_run, ..Caps::default() }, ..DrawItem::new(4, 0) }),
        (0, DrawItem { priority: 5, reduced: true, divisor: Divisor::QUARTER, ..DrawItem::new(5, 2) }),
    ]
}

#[test]
fn the_first_two_runs_seed_under_a_combination_of_those_above() {
    let p = plan(storm(true), &FillStrategy::software(), FACTS);
    // The skydome splits off the clouds' run and seeds it; the fog's run, past the rain, is
    // combined over the seeded buffer (one combination, at the clouds' half), and the rain goes
    // under the fog's run.
    assert_eq!(p.runs.iter().map(|r| r.range.clone()).collect::<Vec<_>>(), [0..1, 1..2, 3..4]);
    assert_eq!((p.chain, p.seeded, p.composites, p.combined.as_slice()), (3, true, 1, &[Divisor::HALF][..]));
    assert!(p.seed_folded && p.runs[1].draws[0].placement == Placement::OverSeed, "{:?}", p.runs[1]);
    assert_eq!(p.steps, [SkyStep::Draw(Step { item: 2, placement: Placement::UnderRun, input: RunInput::Upper(2) })]);
    // Rain that cannot go under a run: the seeded pair is the background, the fog composited.
    let apart = plan(storm(false), &FillStrategy::software(), FACTS);
    assert_eq!((apart.chain, apart.seeded, apart.composites), (2, true, 2));
    assert!(apart.combined.is_empty());
    assert!(matches!(apart.steps.as_slice(), [SkyStep::Draw(Step { placement: Placement::Plain, .. }), SkyStep::Composite(2)]), "{:?}", apart.steps);
    // A fog as fine as the clouds: the two runs as they are seed already, and splitting the
    // skydome off would add a combination; not split.
    let mut fine_fog = storm(true);
    fine_fog[3].1.divisor = Divisor::HALF;
    let p = plan(fine_fog, &FillStrategy::software(), FACTS);
    assert_eq!(p.runs.iter().map(|r| r.range.clone()).collect::<Vec<_>>(), [0..2, 3..4]);
    assert!(p.seeded && p.combined.is_empty(), "{p:?}");
    // The first run alone, something drawn between it and the clouds: not split, and runs that
    // do not touch are combined, not seeded (the draw between would need the runs above it
    // without the skydome).
    let mut between = storm(true);
    between.insert(1, (1, DrawItem { priority: 1, additive: true, caps: Caps { under_run: true, ..Caps::default() }, ..DrawItem::new(1, 1) }));
    let p = plan(between, &FillStrategy::software(), FACTS);
    assert_eq!((p.chain, p.seeded, p.combined.as_slice()), (3, false, &[Divisor::HALF, Divisor::HALF][..]));
}

#[test]
fn the_plain_strategy_draws_every_item_in_its_place() {
    let p = plan(night(true), &FillStrategy::plain(), FACTS);
    assert!(p.runs.is_empty() && p.background.is_none() && p.chain == 0);
    assert!(p.clear_color && p.clear_depth, "nothing covers the frame: both cleared");
    assert_eq!(p.steps.len(), 6);
    assert!(p.steps.iter().all(|s| matches!(s, SkyStep::Draw(Step { placement: Placement::Plain, input: RunInput::None, .. }))), "{:?}", p.steps);
    assert_eq!((p.composites, p.drawn_first, p.layers_paired), (0, 0, 0));
}

#[test]
fn software_joins_seeds_fuses_and_pairs_where_the_items_allow() {
    let p = plan(night(true), &FillStrategy::software(), FACTS);
    // The stars moved nowhere (no reduced additive layer after them); two runs, joined by the
    // bolt's draw under the run, seeded: the second is finer than the first.
    assert_eq!(p.runs.iter().map(|r| r.range.clone()).collect::<Vec<_>>(), [0..1, 3..5]);
    // One composite: the background, for both runs.
    assert_eq!((p.chain, p.seeded, p.composites), (2, true, 1));
    assert!(p.combined.is_empty());
    // The clouds go over the seed at once as a pair; the seeding pass fills only their gap.
    assert_eq!(p.runs[1].seeding, Seeding::Within([0, 100, 320, 80]));
    assert_eq!(p.runs[1].draws, [Step { item: 3, placement: Placement::Pair { upper: 4, over_seed: true }, input: RunInput::Seed }]);
    assert!(p.seed_folded && p.layers_paired == 1);
    // The stars are the background itself, over the joined runs; the bolt is not under it (it
    // does not follow the first run directly), it goes under the combination of run 1.
    match &p.background {
        Some(Background::Fused { fused, others, .. }) => {
            assert_eq!(*fused, Step { item: 1, placement: Placement::Background { joined: true }, input: RunInput::Upper(0) });
            assert!(others.is_empty());
        }
        other => panic!("expected a fused background, found {other:?}"),
    }
    assert_eq!(
        p.steps,
        [
            SkyStep::Draw(Step { item: 2, placement: Placement::UnderRun, input: RunInput::Upper(1) }),
            SkyStep::Draw(Step { item: 5, placement: Placement::Plain, input: RunInput::None })
        ]
    );
    assert!(!p.clear_color, "the fused background writes every pixel");
}

#[test]
fn a_draw_that_cannot_go_under_a_run_keeps_the_runs_apart() {
    let p = plan(night(false), &FillStrategy::software(), FACTS);
    assert_eq!((p.chain, p.seeded, p.composites), (1, false, 2));
    assert_eq!(p.runs[1].seeding, Seeding::None);
    // Unseeded, the clouds still pair, plainly.
    assert_eq!(p.runs[1].draws, [Step { item: 3, placement: Placement::Pair { upper: 4, over_seed: false }, input: RunInput::None }]);
    assert!(p.steps.contains(&SkyStep::Composite(1)));
    assert!(matches!(&p.background, Some(Background::Fused { fused: Step { placement: Placement::Background { joined: false }, .. }, .. })));
    // The same without pairs: one draw each.
    let one_by_one = FillStrategy { pairs: LayerPairs::OneByOne, ..FillStrategy::software() };
    let p = plan(night(false), &one_by_one, FACTS);
    assert_eq!(keys(&p, &p.runs[1].draws), [3, 4]);
    assert!(p.runs[1].draws.iter().all(|s| s.placement == Placement::Reduced));
}

#[test]
fn each_enum_value_takes_its_step_away() {
    // Runs apart: every run composited in its place, the first as the background.
    let apart = FillStrategy { runs: RunJoining::Separate, ..FillStrategy::software() };
    let p = plan(night(true), &apart, FACTS);
    assert_eq!((p.chain, p.composites), (1, 2));
    // Joined but combined: no seed, one combination.
    let combined = FillStrategy { runs: RunJoining::Combined, ..FillStrategy::software() };
    let p = plan(night(true), &combined, FACTS);
    assert!(p.chain == 2 && !p.seeded && p.combined == [Divisor::HALF]);
    // Seeded, not folded: the seeding pass over the whole buffer, then the pair.
    let seeded = FillStrategy { runs: RunJoining::Seeded, ..FillStrategy::software() };
    let p = plan(night(true), &seeded, FACTS);
    assert!(p.seeded && !p.seed_folded && p.runs[1].seeding == Seeding::Whole);
    // Drawn first but not fused: the background composited over the stars; the frame cleared.
    let additive = FillStrategy { under_background: UnderBackground::Additive, ..FillStrategy::software() };
    let p = plan(night(true), &additive, FACTS);
    assert_eq!(p.background, Some(Background::Composite { first: vec![1] }));
    assert!(p.clear_color && p.drawn_first == 1);
    // Nothing under the background: the stars are drawn in the sky phase, under the joined run.
    let nothing = FillStrategy { under_background: UnderBackground::Nothing, ..FillStrategy::software() };
    let p = plan(night(true), &nothing, FACTS);
    assert_eq!(p.background, Some(Background::Composite { first: vec![] }));
    assert_eq!(p.steps[0], SkyStep::Draw(Step { item: 1, placement: Placement::UnderRun, input: RunInput::Upper(1) }));
    assert!(!p.clear_color, "the composite's full-screen triangle writes every pixel");
}

#[test]
fn the_scene_in_view_and_the_depth_decide_the_rest() {
    // With the scene covering part of the frame nothing goes under the background.
    let p = plan(night(true), &FillStrategy::software(), FrameFacts { scene_in_view: true, ..FACTS });
    assert_eq!(p.background, Some(Background::Composite { first: vec![] }));
    // A clean depth is not cleared again, unless covered clears are off.
    let p = plan(night(true), &FillStrategy::software(), FrameFacts { depth_clean: true, ..FACTS });
    assert!(!p.clear_depth);
    let p = plan(night(true), &FillStrategy::software(), FrameFacts { depth_clean: true, covered_clears: false, ..FACTS });
    assert!(p.clear_depth && p.clear_color);
    // Without a pass for reduced buffers every item is drawn in its place.
    let p = plan(night(true), &FillStrategy::software(), FrameFacts { reduced_layers: false, ..FACTS });
    assert!(p.runs.is_empty() && p.background.is_none());
}

#[test]
fn a_pair_needs_the_next_item_it_was_checked_with() {
    // The clouds' pair capability names item 4; with another item after them, no pair.
    let mut items = night(false);
    items[4].1.key = 7;
    let p = plan(items, &FillStrategy::software(), FACTS);
    assert!(p.runs[1].draws.iter().all(|s| s.placement == Placement::Reduced), "{:?}", p.runs[1].draws);
}

#[test]
fn the_plans_uses_are_every_draw_it_records_and_no_other() {
    // What the passes build pipelines for: each draw once, at the placement it is recorded with.
    let p = plan(night(true), &FillStrategy::software(), FACTS);
    assert_eq!(
        p.uses(),
        [
            (0, 0, Placement::Reduced),
            (0, 3, Placement::Pair { upper: 4, over_seed: true }),
            (0, 1, Placement::Background { joined: true }),
            (1, 0, Placement::UnderRun),
            (0, 5, Placement::Plain),
        ]
    );
    // The pair's upper layer is in the pair's use, not one of its own.
    let plain = plan(night(true), &FillStrategy::plain(), FACTS);
    assert_eq!(
        plain.uses().iter().map(|&(pass, key, placement)| (pass, key, placement == Placement::Plain)).collect::<Vec<_>>(),
        [(0, 0, true), (0, 1, true), (1, 0, true), (0, 3, true), (0, 4, true), (0, 5, true)]
    );
    // Draws under a composited background are used as drawn first.
    let composite = plan(night(true), &FillStrategy { under_background: UnderBackground::Additive, ..FillStrategy::software() }, FACTS);
    assert!(matches!(composite.background, Some(Background::Composite { .. })), "{:?}", composite.background);
    assert!(composite.uses().contains(&(0, 1, Placement::First)), "{:?}", composite.uses());
}

#[test]
fn physical_skies_go_to_the_hdr_target_only_when_the_strategy_asks() {
    use crate::render::plan::items::Target;
    use crate::render::plan::strategy::PhysicalTarget;
    assert_eq!(frame_target(true, &FillStrategy::plain()), Target::Hdr);
    assert_eq!(frame_target(true, &FillStrategy::software()), Target::Display);
    assert_eq!(frame_target(true, &FillStrategy::software().with_hdr()), Target::Hdr);
    for s in [FillStrategy::plain(), FillStrategy::software(), FillStrategy { physical_target: PhysicalTarget::Hdr, ..FillStrategy::software() }] {
        assert_eq!(frame_target(false, &s), Target::Display, "a painted sky is display-referred");
        assert!(!matches_hdr_picture(false, &s), "a painted sky's layers are drawn as authored");
    }
    assert!(matches_hdr_picture(true, &FillStrategy::software()));
    assert!(!matches_hdr_picture(true, &FillStrategy::software().with_hdr()), "on the HDR target the blend itself is the HDR path's");
    assert!(!matches_hdr_picture(true, &FillStrategy { physical_target: PhysicalTarget::DisplayAsPainted, ..FillStrategy::software() }));
}

#[test]
fn a_costly_layer_much_coarser_than_its_run_is_drawn_apart() {
    // The night sky with a matched fog band after the clouds: an eighth's buffer would do for it
    // (covering the frame's lower 120 rows); the clouds' buffer is a half's.
    let own = OwnBuffer { divisor: Divisor::EIGHTH, covers: Some([0, 60, 320, 120]) };
    let mut items = night(true);
    items.insert(5, (0, DrawItem { priority: 4, reduced: true, divisor: Divisor::EIGHTH, caps: Caps { own_buffer: Some(own), ..Caps::default() }, ..DrawItem::new(4, 6) }));
    let p = plan(items.clone(), &FillStrategy::software(), FACTS);
    assert_eq!(p.runs[1].range, 3..6);
    assert_eq!(p.runs[1].draws[1], Step { item: 5, placement: Placement::Reduced, input: RunInput::Own(0) });
    assert_eq!(p.own_buffers, [own]);
    // Its pipeline is the reduced one, drawn into its own buffer.
    assert!(p.uses().contains(&(0, 6, Placement::Reduced)));
    // In its run where the strategy says so, or where the run's buffer is less than twice as
    // fine along each side.
    let in_run = FillStrategy { costly_layers: CostlyLayers::InRun, ..FillStrategy::software() };
    let p = plan(items.clone(), &in_run, FACTS);
    assert!(p.own_buffers.is_empty() && p.runs[1].draws[1].input == RunInput::None);
    let near = OwnBuffer { divisor: Divisor::whole(3), ..own };
    items[5].1.caps.own_buffer = Some(near);
    let p = plan(items.clone(), &FillStrategy::software(), FACTS);
    assert!(p.own_buffers.is_empty());
    // A plain layer (no buffer of its own offered) stays in its run.
    items[5].1.caps.own_buffer = None;
    assert!(plan(items, &FillStrategy::software(), FACTS).own_buffers.is_empty());
}
