//! Hot reload: edits of the sky file and its bitmaps reach the live sky; a broken edit is
//! reported and the last good sky stays.

mod common;

use std::time::Duration;

use skytune::files::hot_reload::{LiveSky, ReloadEvent, SkySpec};

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

#[test]
fn rapid_saves_end_on_the_final_content_and_never_show_a_stale_error() {
    let (dir, sky_path) = common::default_sky_folder();
    let mut live = LiveSky::new(SkySpec::File(sky_path.clone())).unwrap();
    let good = std::fs::read_to_string(&sky_path).unwrap();
    let version = {
        let good = good.clone();
        move |k: usize| good.replacen("name = \"default\"", &format!("name = \"rapid {k}\""), 1)
    };
    let final_text = good.replacen("name = \"default\"", "name = \"final\"", 1);
    let writer = {
        let (sky_path, dir) = (sky_path.clone(), dir.path().to_path_buf());
        let final_text = final_text.clone();
        std::thread::spawn(move || {
            // 200 saves in about 2 seconds, the ways editors save.
            for k in 0..200 {
                let text = version(k);
                match k % 4 {
                    0 => std::fs::write(&sky_path, &text).unwrap(),
                    1 => {
                        // Truncated, completed 10 ms later.
                        std::fs::write(&sky_path, &text[..text.len() / 2]).unwrap();
                        std::thread::sleep(Duration::from_millis(10));
                        std::fs::write(&sky_path, &text).unwrap();
                    }
                    2 => {
                        let tmp = dir.join(format!(".sky.toml.{k}.tmp"));
                        std::fs::write(&tmp, &text).unwrap();
                        std::fs::rename(&tmp, &sky_path).unwrap();
                    }
                    _ => {
                        // Deleted and created again.
                        std::fs::remove_file(&sky_path).unwrap();
                        std::thread::sleep(Duration::from_millis(2));
                        std::fs::write(&sky_path, &text).unwrap();
                    }
                }
                std::thread::sleep(Duration::from_millis(8));
            }
            std::fs::write(&sky_path, &final_text).unwrap();
        })
    };
    // The window's loop: poll every frame while the saves go on.
    let started = std::time::Instant::now();
    while !writer.is_finished() {
        let _ = live.poll();
        assert!(started.elapsed() < Duration::from_secs(60), "the writer hangs");
        std::thread::sleep(Duration::from_millis(5));
    }
    writer.join().unwrap();
    let final_written = std::time::Instant::now();
    // From now on the file is good: no error may show, and the final content arrives.
    let mut errors_after_final = Vec::new();
    while started.elapsed() < Duration::from_secs(60) {
        if let Some(ReloadEvent::Failed(e)) = live.poll() {
            errors_after_final.push(e.to_string());
        }
        if live.sky().name == "final" && live.error.is_none() && final_written.elapsed() > Duration::from_millis(800) {
            break;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    assert_eq!(live.sky().name, "final", "ends on the final content");
    assert!(live.error.is_none(), "{:?}", live.error.as_ref().map(|e| e.to_string()));
    assert!(errors_after_final.is_empty(), "a half-written file's error showed after the final save: {errors_after_final:?}");
}
