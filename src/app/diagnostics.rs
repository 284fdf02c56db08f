//! The statistics at the foot of the controls panel: frame times, time per phase, what the
//! renderer drew and skipped, and its switches. The long parts are sections that stay closed
//! until opened, so they never set the panel's width.

use std::collections::VecDeque;

use super::controls::{section, Controls, UiInfo};

/// The frame's statistics: frame time and its graph, then collapsible sections for the time per
/// phase and section, what was drawn and skipped, and the renderer's switches.
pub fn stats(ui: &mut egui::Ui, c: &mut Controls, info: &UiInfo<'_>) {
    let times: Vec<[f64; 2]> = info.frame_times_ms.iter().enumerate().map(|(i, t)| [i as f64, *t as f64]).collect();
    let last = info.frame_times_ms.back().copied().unwrap_or(0.0);
    let mut sorted: Vec<f32> = info.frame_times_ms.iter().copied().collect();
    sorted.sort_by(f32::total_cmp);
    let median = sorted.get(sorted.len() / 2).copied().unwrap_or(0.0);
    ui.label(format!("frame {last:.1} ms (median {median:.1} ms, {:.0} fps)", if median > 0.0 { 1000.0 / median } else { 0.0 }));
    egui_plot::Plot::new("frame_times").height(70.0).show_axes([false, true]).allow_drag(false).allow_zoom(false).allow_scroll(false).show(ui, |p| {
        p.line(egui_plot::Line::new("frame ms", times));
    });
    if let Some(floor) = info.floor_ms.filter(|f| *f > 0.0 && !info.gpu_ms.is_empty()) {
        let sky: f32 = info.gpu_ms.iter().map(|(_, ms)| ms).sum();
        ui.label(format!("fill-limit ratio {:.1} (sky {sky:.2} ms / floor {floor:.2} ms)", sky / floor))
            .on_hover_text("the floor is one full-screen pass sampling one texture; skytune bench frame measures the ratio for every sky; the goal is 3");
    }
    let rows = |ui: &mut egui::Ui, title: &str, rows: &[(&str, f32)]| {
        if !rows.is_empty() {
            ui.label(title);
            for (name, ms) in rows {
                ui.label(format!("  {name}: {ms:.2} ms"));
            }
        }
    };
    section(ui, c, "times", "Time per phase and section", |ui, _| {
        rows(ui, "GPU time per phase (timestamp queries):", info.gpu_ms);
        rows(ui, "CPU time per frame section:", info.cpu_ms);
    });
    let s = info.stats;
    ui.label(format!("draw calls {}, objects drawn {}, hidden {}", s.draw_calls, s.objects_drawn, s.objects_hidden));
    section(ui, c, "skipped", "Drawn and skipped this frame", |ui, _| skipped(ui, info));
    section(ui, c, "switches", "Renderer switches and skips", |ui, c| switches(ui, c, info));
    if let Some(g) = info.glare {
        ui.label(format!("sun visibility {:.3}, glare intensity {:.3}", g.ratio, g.intensity));
    }
}

/// What the renderer drew and skipped this frame, a line each.
fn skipped(ui: &mut egui::Ui, info: &UiInfo<'_>) {
    let s = info.stats;
    ui.label(format!("stars {} of {}", s.stars_drawn, s.stars));
    let mut skipped = vec![
        format!("{} objects hidden by their ref colour", s.objects_ref_hidden),
        format!("{} below the horizon behind the scene", s.objects_below_horizon),
        format!("{} dome layers out of view", s.objects_off_screen),
        format!("{} black texture stages", s.stages_skipped),
        format!("{} blended draws black and transparent", s.draws_dark),
        format!("mip selection of {} stages no pixel minifies", s.stages_level0),
    ];
    if s.stars_skipped {
        skipped.push("the star field (transparent)".into());
    }
    if s.tables_skipped {
        skipped.push("the lut tables' rebuild (unchanged)".into());
    }
    if s.map_skipped {
        skipped.push("the sky-view map (unchanged)".into());
    } else if s.map_texels > 0 {
        let (w, h) = crate::render::plan::resolution::SKY_VIEW_SIZE;
        skipped.push(format!("{} of the sky-view map's {} texels (the rest computed in other frames)", (w * h).saturating_sub(s.map_texels), w * h));
    }
    ui.label("skipped:");
    for line in skipped {
        ui.label(format!("  {line}"));
    }
    let runs: Vec<String> = s.reduced_runs.iter().map(|d| format!("1/{d}")).collect();
    ui.label(format!("{} of {} objects in reduced buffers ({})", s.objects_reduced, s.objects_drawn, if runs.is_empty() { "none".into() } else { runs.join(", ") }));
}

/// The renderer's switches and skips, and what switching skips off costs: the median frame time
/// now against the median when they were last all on.
fn switches(ui: &mut egui::Ui, c: &mut Controls, info: &UiInfo<'_>) {
    let s = info.stats;
    use crate::render::plan::strategy::{CostlyLayers, FlashPlacement, LayerCoordinates, LayerPairs, PhysicalTarget, RunJoining, SparseStages, UnderBackground, PRESETS};
    let st = &mut c.options.strategy;
    ui.horizontal_wrapped(|ui| {
        ui.label(format!("fill strategy: {} (preset", st.name()));
        for (name, preset) in PRESETS {
            ui.radio_value(st, preset, name);
        }
        ui.label(format!("; {} for this adapter)", info.adapter_strategy.name()));
    });
    ui.horizontal_wrapped(|ui| {
        ui.label("dome layers at");
        for r in crate::render::DomeResolution::ALL {
            ui.radio_value(&mut st.dome_resolution, r, r.name());
        }
        ui.label("resolution");
    });
    let frame = |on: bool| if on { "this frame" } else { "not this frame" };
    choice(
        ui,
        &format!("first runs ({} composites, seeded {}, folded {})", s.composites, frame(s.seeded), frame(s.seed_folded)),
        &mut st.runs,
        &[(RunJoining::Separate, "apart"), (RunJoining::Combined, "joined"), (RunJoining::Seeded, "seeded"), (RunJoining::SeededFolded, "seeded, first layer over the seed")],
    );
    choice(
        ui,
        &format!("under the background ({} draws, fused {})", s.drawn_first, frame(s.background_fused)),
        &mut st.under_background,
        &[(UnderBackground::Nothing, "nothing"), (UnderBackground::Additive, "additive draws"), (UnderBackground::AdditiveFused, "additive draws, one as the background")],
    );
    choice(
        ui,
        &format!("sparse stars ({} triangles, {} rectangles)", s.texel_triangles, s.background_rects),
        &mut st.sparse_stages,
        &[(SparseStages::Sampled, "sampled"), (SparseStages::TexelPolygons, "texel by texel"), (SparseStages::TexelPolygonsOnBands, "texel by texel, the rest on bands")],
    );
    choice(
        ui,
        "cloud-layer coordinates on a grid",
        &mut st.layer_coordinates,
        &[(LayerCoordinates::PerPixel, "per pixel"), (LayerCoordinates::PerVertex, "per vertex, on the layer's chords")],
    );
    choice(
        ui,
        &format!("lightning flash ({})", frame(s.joined_runs_only > 0)),
        &mut st.flash,
        &[(FlashPlacement::OverFrame, "over the frame"), (FlashPlacement::InRun, "in a run")],
    );
    choice(ui, &format!("alpha layers ({} pairs)", s.layers_paired), &mut st.pairs, &[(LayerPairs::OneByOne, "one by one"), (LayerPairs::AtOnce, "two at once")]);
    choice(
        ui,
        &format!("costly layers ({} apart)", s.own_buffers),
        &mut st.costly_layers,
        &[(CostlyLayers::InRun, "in their run"), (CostlyLayers::OwnBuffer, "apart, at their resolution")],
    );
    choice(
        ui,
        "physical skies",
        &mut st.physical_target,
        &[
            (PhysicalTarget::Hdr, "HDR target, tone-mapped after"),
            (PhysicalTarget::DisplayMatched, "display target, layers matched to the HDR picture"),
            (PhysicalTarget::DisplayAsPainted, "display target, layers blended as over a painted sky"),
        ],
    );
    let median = |v: &VecDeque<f32>| {
        let mut x: Vec<f32> = v.iter().rev().take(30).copied().collect();
        x.sort_by(f32::total_cmp);
        x.get(x.len() / 2).copied()
    };
    let before = c.options.skips;
    let k = &mut c.options.skips;
    ui.vertical(|ui| {
        ui.checkbox(&mut k.dark_stages, "skip black stages");
        ui.checkbox(&mut k.invisible_stars, "skip transparent stars");
        ui.checkbox(&mut k.unchanged_tables, "skip unchanged tables and map");
        ui.checkbox(&mut k.below_horizon, "skip objects behind the scene");
        ui.checkbox(&mut k.off_screen, "skip dome layers and scene out of view");
        ui.checkbox(&mut k.unneeded_mips, "skip unneeded mip selection");
        ui.checkbox(&mut k.covered_clears, "skip clears the background covers");
    });
    let all_on = c.options.skips == crate::render::Skips::default();
    if before == crate::render::Skips::default() && !all_on {
        // Switching a skip off: remember what frames cost with every skip on.
        c.skips_baseline_ms = median(info.frame_times_ms);
    }
    match (all_on, c.skips_baseline_ms, median(info.frame_times_ms)) {
        (false, Some(with), Some(now)) => {
            ui.label(format!("these skips save {:.2} ms per frame here (median frame {now:.2} ms without them, {with:.2} ms with all skips)", now - with));
        }
        _ => {
            ui.label("switch a skip off to measure what it saves in this view");
        }
    }
}

/// One row of radio buttons choosing among `values`, after `label`.
fn choice<T: PartialEq + Copy>(ui: &mut egui::Ui, label: &str, value: &mut T, values: &[(T, &str)]) {
    ui.horizontal_wrapped(|ui| {
        ui.label(label);
        for &(v, name) in values {
            ui.radio_value(value, v, name);
        }
    });
}
