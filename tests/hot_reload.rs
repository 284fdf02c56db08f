//! Hot reload: edits of the sky file and its bitmaps reach the live sky; a broken edit is
//! reported and the last good sky stays.

mod common;

use std::time::Duration;

use skytune::live::{LiveSky, ReloadEvent, SkySpec};

const WAIT: Duration = Duration::from_secs(20);

fn rewrite(path: &std::path::Path, from: &str, to: &str) {
    let text = std::fs::read_to_string(path).unwrap();
    assert!(text.contains(from), "{from}");
    std::fs::write(path, text.replacen(from, to, 1)).unwrap();
}

#[test]
fn edits_reload_and_broken_edits_keep_the_last_good_sky() {
    let (dir, sky_path) = common::default_sky_folder();
    let mut live = LiveSky::new(SkySpec::File(sky_path.clone())).unwrap();
    assert_eq!(live.sky().name, "default");

    // A plain edit (truncate + write).
    rewrite(&sky_path, "name = \"default\"", "name = \"Edited\"");
    assert_eq!(live.wait(WAIT), Some(ReloadEvent::Reloaded));
    assert_eq!(live.sky().name, "Edited");
    let generation = live.generation;

    // A broken edit: error names the file, line and field; the last good sky stays.
    rewrite(&sky_path, "priority = 20", "priority = 99");
    match live.wait(WAIT) {
        Some(ReloadEvent::Failed(e)) => {
            let err = &e.0[0];
            assert_eq!(err.field, "object[9].priority", "{e}");
            assert!(err.file.ends_with("sky.toml"));
            assert!(err.line > 1);
        }
        other => panic!("expected a failed reload, got {other:?}"),
    }
    assert_eq!(live.sky().name, "Edited");
    assert_eq!(live.generation, generation);
    assert!(live.error.is_some());

    // The fix, saved the way many editors do: write a temporary file and rename it over.
    let text = std::fs::read_to_string(&sky_path).unwrap().replacen("priority = 99", "priority = 21", 1);
    let tmp = dir.path().join(".sky.toml.tmp");
    std::fs::write(&tmp, text).unwrap();
    std::fs::rename(&tmp, &sky_path).unwrap();
    assert_eq!(live.wait(WAIT), Some(ReloadEvent::Reloaded));
    assert!(live.error.is_none());
    assert_eq!(live.sky().objects.last().unwrap().priority, 21);

    // Editing a referenced bitmap reloads too: the fog turns red.
    let red = image::RgbaImage::from_pixel(24, 3, image::Rgba([255, 0, 0, 255]));
    red.save(dir.path().join("fog.png")).unwrap();
    assert_eq!(live.wait(WAIT), Some(ReloadEvent::Reloaded));
    let frame = live.sky().evaluate(&skytune::sky::FrameInput::new(12.0, 0.0));
    assert_eq!(frame.fog_color, [1.0, 0.0, 0.0, 1.0]);
}

#[test]
fn a_new_file_fixes_a_missing_reference() {
    let (dir, sky_path) = common::default_sky_folder();
    let mut live = LiveSky::new(SkySpec::File(sky_path.clone())).unwrap();
    rewrite(&sky_path, "texture = \"galaxy.png\"", "texture = \"galaxy2.png\"");
    assert!(matches!(live.wait(WAIT), Some(ReloadEvent::Failed(_))));
    // The artist adds the missing bitmap: the sky reloads without touching sky.toml again.
    std::fs::copy(dir.path().join("galaxy.png"), dir.path().join("galaxy2.png")).unwrap();
    assert_eq!(live.wait(WAIT), Some(ReloadEvent::Reloaded));
}

#[test]
fn reading_the_files_does_not_trigger_reloads() {
    let (_dir, sky_path) = common::default_sky_folder();
    let mut live = LiveSky::new(SkySpec::File(sky_path.clone())).unwrap();
    // A manual reload reads every file; those reads must not schedule further reloads.
    live.request_reload();
    assert_eq!(live.wait(WAIT), Some(ReloadEvent::Reloaded));
    assert_eq!(live.wait(Duration::from_millis(1500)), None, "a reload without any edit");
    let _ = std::fs::read_to_string(&sky_path).unwrap();
    assert_eq!(live.wait(Duration::from_millis(1000)), None, "reading the sky file is not an edit");
}
