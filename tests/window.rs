//! The window as an artist sees it: the real window under Xvfb, its pixels read back from the X
//! server (panels included, not a headless render), at three sizes; an auto sky whose pick is
//! measured while the window keeps drawing.

mod common;

use std::io::BufRead;
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// The window running under its own Xvfb, its log lines collected as they come.
struct Window {
    app: Child,
    server: Child,
    display: String,
    lines: Arc<Mutex<Vec<String>>>,
}

impl Window {
    /// Starts `skytune` with `args` in a window of `size` (its settings file says so) on an
    /// Xvfb screen of `screen`, with `cache` as its cache folder.
    fn start(size: (u32, u32), screen: (u32, u32), cache: &Path, args: &[&str]) -> Window {
        let (server, display) = common::xvfb(screen).expect("Xvfb is required: run scripts/setup.sh");
        let config = cache.join("state.toml");
        std::fs::write(&config, format!("window_size = [{}, {}]\n", size.0, size.1)).unwrap();
        let mut app = Command::new(env!("CARGO_BIN_EXE_skytune"))
            .args(["--cpu"])
            .args(args)
            .env("DISPLAY", &display)
            .env("SKYTUNE_CONFIG", &config)
            .env("XDG_CACHE_HOME", cache)
            .env("RUST_LOG", "info")
            .stderr(Stdio::piped())
            .stdout(Stdio::null())
            .spawn()
            .expect("running skytune");
        let lines = Arc::new(Mutex::new(Vec::new()));
        let (stderr, sink) = (app.stderr.take().expect("piped"), lines.clone());
        std::thread::spawn(move || {
            for line in std::io::BufReader::new(stderr).lines().map_while(Result::ok) {
                sink.lock().unwrap().push(line);
            }
        });
        Window { app, server, display, lines }
    }

    /// The last log line holding `needle`, waiting up to `timeout` for one.
    fn wait_for(&mut self, needle: &str, timeout: Duration) -> String {
        let start = Instant::now();
        loop {
            if let Some(l) = self.lines.lock().unwrap().iter().rev().find(|l| l.contains(needle)) {
                return l.clone();
            }
            if let Ok(Some(status)) = self.app.try_wait() {
                panic!("skytune exited ({status}) before logging \"{needle}\":\n{}", self.log());
            }
            assert!(start.elapsed() < timeout, "no \"{needle}\" within {timeout:?}:\n{}", self.log());
            std::thread::sleep(Duration::from_millis(100));
        }
    }

    fn log(&self) -> String {
        self.lines.lock().unwrap().join("\n")
    }
}

impl Drop for Window {
    fn drop(&mut self) {
        let _ = self.app.kill();
        let _ = self.app.wait();
        let _ = self.server.kill();
        let _ = self.server.wait();
    }
}

/// The numbers after each of `keys` in `line` (`sky view: x 261 y 0 width 819 ...`).
fn numbers(line: &str, keys: &[&str]) -> Vec<f64> {
    keys.iter()
        .map(|k| {
            // The key as a word: `y` is not the end of `sky`, `longest` may follow a bracket.
            let word = format!("{k} ");
            let at = line
                .match_indices(&word)
                .find(|(i, _)| line[..*i].chars().next_back().is_none_or(|c| !c.is_alphanumeric()))
                .map(|(i, _)| i + word.len())
                .unwrap_or_else(|| panic!("no {k} in {line}"));
            line[at..].split(|c: char| !(c.is_ascii_digit() || c == '.')).next().and_then(|v| v.parse().ok()).unwrap_or_else(|| panic!("no number after {k} in {line}"))
        })
        .collect()
}

#[test]
fn the_sky_is_most_of_the_window_and_shows_what_a_still_renders() {
    let (_dir, sky) = common::default_sky_folder();
    let sky = sky.to_str().unwrap().to_string();
    // Noon, clear: no particles or glare, whose timing differs between a window and a still.
    let frame = ["--hour", "12", "--weather", "0"];
    for size in [(800, 600), (1280, 720), (1920, 1080)] {
        let cache = tempfile::tempdir().unwrap();
        let mut window = Window::start(size, (1920, 1080), cache.path(), &[&[sky.as_str()][..], &frame[..]].concat());
        let line = window.wait_for("sky view:", Duration::from_secs(120));
        // The view is laid out; let a few more frames settle (time stands still).
        std::thread::sleep(Duration::from_secs(3));
        let line = window.lines.lock().unwrap().iter().rev().find(|l| l.contains("sky view:")).cloned().unwrap_or(line);
        let v = numbers(&line, &["x", "y", "width", "height"]).into_iter().map(|n| n as u32).collect::<Vec<_>>();
        let (x, y, w, h) = (v[0], v[1], v[2], v[3]);
        // A loaded machine may not have presented the laid-out view yet: until it has (the sky
        // view's pixels not all black), look again, for at most a minute.
        let started = std::time::Instant::now();
        let screen = loop {
            let screen = common::x_screenshot(&window.display).expect("a screenshot of the X server");
            let drawn = image::imageops::crop_imm(&screen, x, y, w, h).to_image().pixels().any(|p| p[0] > 0 || p[1] > 0 || p[2] > 0);
            if drawn || started.elapsed() > Duration::from_secs(60) {
                break screen;
            }
            std::thread::sleep(Duration::from_secs(2));
        };
        drop(window);
        let name = format!("window_{}x{}", size.0, size.1);
        screen.save(common::output_dir().join(format!("{name}.screen.png"))).unwrap();

        let share = (w * h) as f64 / (size.0 * size.1) as f64;
        assert!(share >= 0.6, "{name}: the sky view {w}x{h} at ({x}, {y}) covers {:.0}% of the window", share * 100.0);
        assert!(x + w <= size.0 && y + h <= size.1, "{name}: {line}");

        let still_path = common::output_dir().join(format!("{name}.still.png"));
        let o = Command::new(env!("CARGO_BIN_EXE_skytune")).args(["render", &sky, "--cpu", "--size", &format!("{w}x{h}"), "--out"]).arg(&still_path).args(frame).output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let still = image::open(&still_path).unwrap().to_rgba8();
        let shown = image::imageops::crop_imm(&screen, x, y, w, h).to_image();
        let (d, diff) = common::diff(&shown, &still, common::CHANNEL_TOLERANCE);
        if d.differing > common::PIXEL_BUDGET {
            shown.save(common::output_dir().join(format!("{name}.actual.png"))).unwrap();
            diff.save(common::output_dir().join(format!("{name}.diff.png"))).unwrap();
            panic!(
                "{name}: {:.2}% of the sky view's pixels differ from a still of {w}x{h} (max {}, mean {:.2}); see tests/output/{name}.*.png",
                d.differing * 100.0,
                d.max,
                d.mean
            );
        }
        // The panels are there too: the window is not all sky.
        let panel = screen.get_pixel(x.saturating_sub(20), size.1 / 2);
        assert_ne!(panel, still.get_pixel(0, h / 2), "{name}: no panel left of the sky");
    }
}

#[test]
fn an_auto_sky_keeps_the_window_drawing_while_its_pick_is_measured() {
    let (dir, sky_file) = common::default_sky_folder();
    // An atmosphere outside the committed benchmark, in a fresh cache: the pick must measure.
    let mut text = std::fs::read_to_string(&sky_file).unwrap();
    text.push_str("\n[sky_model]\nkind = \"auto\"\n\n[atmosphere]\nmie_scattering_per_km = 12e-3\nmie_extinction_per_km = 13.3e-3\n");
    std::fs::write(&sky_file, text).unwrap();
    let cache = tempfile::tempdir().unwrap();
    let mut window = Window::start((640, 360), (1024, 768), cache.path(), &[sky_file.to_str().unwrap()]);
    window.wait_for("auto model: measuring the candidates", Duration::from_secs(120));
    let line = window.wait_for("auto model: picked after", Duration::from_secs(1500));
    let n = numbers(&line, &["drew", "longest"]);
    let (frames, longest_ms) = (n[0], n[1]);
    assert!(frames >= 30.0, "the window drew {frames} frames while the pick was measured: {line}");
    assert!(longest_ms < 1000.0, "a frame took {longest_ms} ms while the pick was measured: {line}");
    assert!(line.contains(" (dE2000 ") && line.contains("budget 2.00"), "the pick and its error: {line}");
    // The pick was cached: a second window has it at once, measuring nothing.
    drop(window);
    let mut again = Window::start((640, 360), (1024, 768), cache.path(), &[sky_file.to_str().unwrap(), "--frames", "3"]);
    again.wait_for("rendered 3 frames", Duration::from_secs(120));
    assert!(!again.log().contains("measuring the candidates"), "{}", again.log());
    drop(dir);
}

#[test]
fn a_reload_that_changes_the_atmosphere_cancels_the_pick_under_way() {
    let (_dir, sky_file) = common::default_sky_folder();
    let base = std::fs::read_to_string(&sky_file).unwrap();
    let with_mie = |mie: f64| format!("{base}\n[sky_model]\nkind = \"auto\"\n\n[atmosphere]\nmie_scattering_per_km = {mie:e}\nmie_extinction_per_km = {:e}\n", mie * 1.11);
    std::fs::write(&sky_file, with_mie(14e-3)).unwrap();
    let cache = tempfile::tempdir().unwrap();
    let mut window = Window::start((480, 270), (1024, 768), cache.path(), &[sky_file.to_str().unwrap()]);
    window.wait_for("auto model: measuring the candidates", Duration::from_secs(120));
    // The artist edits the atmosphere while the pick is measured.
    std::thread::sleep(Duration::from_secs(2));
    skytune::support::safe_write::write_atomic(&sky_file, with_mie(15e-3).as_bytes()).unwrap();
    window.wait_for("is cancelled", Duration::from_secs(60));
    let stopped = window.wait_for("stopped measuring for a superseded version", Duration::from_secs(60));
    assert!(numbers(&stopped, &["after"])[0] < 60.0, "the old measurement stopped promptly: {stopped}");
    let log = window.log();
    assert_eq!(log.matches("auto model: measuring the candidates").count(), 2, "the new version is measured: {log}");
    // A change that leaves the atmosphere as it is (a bitmap's name here: any other key) keeps the
    // measurement running.
    let edited = std::fs::read_to_string(&sky_file).unwrap().replacen("name = ", "name = \"renamed\"\n# was: ", 1);
    skytune::support::safe_write::write_atomic(&sky_file, edited.as_bytes()).unwrap();
    window.wait_for("reloaded sky \"renamed\"", Duration::from_secs(60));
    std::thread::sleep(Duration::from_secs(1));
    assert_eq!(window.log().matches("is cancelled").count(), 1, "{}", window.log());
}
