//! The `skytune` binary's subcommands, end to end.

mod common;

use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn skytune() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_skytune"));
    c.env("SKYTUNE_ADAPTER", "cpu").env_remove("DISPLAY");
    c
}

#[test]
fn render_writes_a_png_of_the_requested_size() {
    let (dir, sky) = common::default_sky_folder();
    let out = dir.path().join("shot.png");
    let o = skytune().arg("render").arg(&sky).args(["--hour", "18.5", "--weather", "0.3", "--size", "96x54", "--tier", "2", "--out"]).arg(&out).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stdout).contains("adapter: llvmpipe"));
    assert_eq!(image::open(&out).unwrap().to_rgba8().dimensions(), (96, 54));
}

#[test]
fn check_prints_a_summary_or_located_errors() {
    let (_dir, sky) = common::default_sky_folder();
    let o = skytune().arg("check").arg(&sky).output().unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success());
    assert!(stdout.contains("10 objects") && stdout.contains("skydome") && stdout.contains("fallback versions with 1 + 2 stage(s)"), "{stdout}");

    let text = std::fs::read_to_string(&sky).unwrap().replacen("size_deg = 6", "size_deg = -6", 1);
    std::fs::write(&sky, &text).unwrap();
    let line = text[..text.find("size_deg = -6").unwrap()].matches('\n').count() + 1;
    let o = skytune().arg("check").arg(&sky).output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(stderr.contains(&format!("sky.toml:{line}:")) && stderr.contains("object[2].standard.shape:") && stderr.contains("expected a finite number > 0"), "{stderr}");
}

#[test]
fn check_warns_where_a_tiled_mesh_texture_meets_the_zenith() {
    let (_dir, sky) = common::default_sky_folder();
    let cloud_warnings = |o: &std::process::Output| String::from_utf8_lossy(&o.stdout).lines().filter(|l| l.starts_with("warning:") && l.contains("\"clouds_clear\"")).count();
    let o = skytune().arg("check").arg(&sky).output().unwrap();
    assert_eq!(cloud_warnings(&o), 0, "{}", String::from_utf8_lossy(&o.stdout));
    // The first cloud stage back on the dome's mesh coordinates, tiled 3 x 2.
    let layer = "uv_scale = [3, 3]\nuv = { kind = \"layer\", height_km = 2, radius_km = 4, size_km = 10, horizon_fade_deg = 0 }\n";
    let text = std::fs::read_to_string(&sky).unwrap();
    assert!(text.contains(layer), "the written sky's clouds changed");
    let text = text.replacen(layer, "uv_scale = [3, 2]\n", 1);
    std::fs::write(&sky, &text).unwrap();
    let line = text[..text.find("uv_scale = [3, 2]").unwrap()].matches('\n').count() + 1;
    let o = skytune().arg("check").arg(&sky).output().unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "a warning is not an error");
    let warning = stdout.lines().find(|l| l.starts_with("warning:") && l.contains("\"clouds_clear\"")).unwrap_or_else(|| panic!("no warning in {stdout}"));
    assert!(warning.contains(&format!("sky.toml:{line}:")) && warning.contains(".stage[0].uv_scale:") && warning.contains("zenith"), "{warning}");
    // Untiled, or on a band below the zenith, the mesh mapping is fine.
    std::fs::write(&sky, text.replacen("uv_scale = [3, 2]\n", "uv_scale = [1, 1]\n", 1)).unwrap();
    let o = skytune().arg("check").arg(&sky).output().unwrap();
    assert_eq!(cloud_warnings(&o), 0);
}

#[test]
fn bad_arguments_are_clear_errors() {
    let o = skytune().args(["render", "--tier", "3", "--out", "/tmp/never.png"]).output().unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("--tier: expected 4, 2 or 1, found 3"));
    let o = skytune().args(["render", "--size", "12by4"]).output().unwrap();
    assert!(String::from_utf8_lossy(&o.stderr).contains("expected WIDTHxHEIGHT"));
}

fn wait_for_line(reader: &mut impl BufRead, needle: &str) -> String {
    let deadline = Instant::now() + Duration::from_secs(60);
    let mut all = String::new();
    while Instant::now() < deadline {
        let mut line = String::new();
        if reader.read_line(&mut line).unwrap() == 0 {
            break;
        }
        all.push_str(&line);
        if line.contains(needle) {
            return all;
        }
    }
    panic!("never saw \"{needle}\" in:\n{all}");
}

#[test]
fn watch_rerenders_on_edits_and_keeps_the_last_good_image() {
    let (dir, sky) = common::default_sky_folder();
    let out = dir.path().join("live.png");
    let mut child = skytune()
        .arg("watch")
        .arg(&sky)
        .args(["--size", "64x36", "--view", "zenith", "--no-scene", "--out"])
        .arg(&out)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let stderr = std::sync::Arc::new(std::sync::Mutex::new(String::new()));
    let sink = stderr.clone();
    let mut child_err = BufReader::new(child.stderr.take().unwrap());
    std::thread::spawn(move || {
        let mut line = String::new();
        while child_err.read_line(&mut line).unwrap_or(0) > 0 {
            sink.lock().unwrap().push_str(&line);
            line.clear();
        }
    });
    let mut stdout = BufReader::new(child.stdout.take().unwrap());
    wait_for_line(&mut stdout, "watching");
    let first = image::open(&out).unwrap().to_rgba8();

    // Paint the clear-weather gradient red: the re-rendered zenith turns red.
    image::RgbaImage::from_pixel(24, 32, image::Rgba([255, 0, 0, 255])).save(dir.path().join("gradient_clear.png")).unwrap();
    wait_for_line(&mut stdout, "wrote");
    std::thread::sleep(Duration::from_millis(500));
    let second = image::open(&out).unwrap().to_rgba8();
    let p = second.get_pixel(32, 18).0;
    assert!(p[0] > 200 && p[1] < 80, "zenith should be red after the edit: {p:?} (before {:?})", first.get_pixel(32, 18).0);

    // A broken edit: reported, and the image stays the last good one.
    let text = std::fs::read_to_string(&sky).unwrap().replacen("priority = 20", "priority = 99", 1);
    std::fs::write(&sky, text).unwrap();
    let deadline = Instant::now() + Duration::from_secs(60);
    while !stderr.lock().unwrap().contains("reload failed") && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(50));
    }
    let _ = child.kill();
    let _ = child.wait();
    let log = stderr.lock().unwrap().clone();
    assert!(log.contains("reload failed") && log.contains("object[9].priority"), "{log}");
    assert_eq!(image::open(&out).unwrap().to_rgba8(), second);
}

#[test]
fn new_sky_writes_a_valid_folder_for_every_preset() {
    let dir = tempfile::tempdir().unwrap();
    for preset in ["default", "desert", "forest", "lakes", "jungle"] {
        let o = skytune().args(["new-sky"]).arg(dir.path().join(preset)).args(["--preset", preset]).output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        skytune::sky::load_sky_file(&dir.path().join(preset).join("sky.toml")).unwrap();
    }
    let o = skytune().args(["new-sky"]).arg(dir.path().join("x")).args(["--preset", "moon"]).output().unwrap();
    assert!(String::from_utf8_lossy(&o.stderr).contains("unknown preset \"moon\""));
}

#[test]
fn the_built_in_sky_and_a_new_one_load_without_warnings() {
    let sky = skytune::sky::builtin::default_sky();
    assert!(sky.warnings.is_empty(), "{:?}", sky.warnings.iter().map(ToString::to_string).collect::<Vec<_>>());
    // What `skytune check` prints for a sky folder written from the built-in one.
    let (_dir, written) = common::default_sky_folder();
    let o = skytune().arg("check").arg(&written).output().unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success() && !stdout.lines().any(|l| l.starts_with("warning:")), "{stdout}");
}

#[test]
fn every_committed_sky_is_valid() {
    let skies = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("skies");
    let mut n = 0;
    for entry in std::fs::read_dir(&skies).unwrap() {
        let path = entry.unwrap().path().join("sky.toml");
        if path.is_file() {
            let sky = skytune::sky::load_sky_file(&path).unwrap_or_else(|e| panic!("{e}"));
            // The skydome's stars and every cloud layer are on the layer mapping: nothing tiled
            // converges at the zenith, and nothing else warns.
            assert!(sky.warnings.is_empty(), "{}: {:?}", path.display(), sky.warnings.iter().map(ToString::to_string).collect::<Vec<_>>());
            n += 1;
        }
    }
    assert!(n >= 4, "expected at least four continent skies, found {n}");
    let c = skytune::sky::load::load_continent(&skies.join("lakes/continent.toml")).unwrap();
    assert!(c.skies[3].ends_with("winter.toml"));
}

#[test]
fn radiance_takes_the_atmosphere_camera_and_albedo_of_a_sky_file() {
    // A sky whose storm step has more aerosol, a camera 1.5 km up and a bright ground; the same
    // atmosphere written out as keys, and the same camera and ground in the cases, give the
    // same numbers.
    let (dir, sky) = common::default_sky_folder();
    let mut text = std::fs::read_to_string(&sky).unwrap();
    text.push_str(
        "\n[sky_model]\ncamera_km = 1.5\nground_albedo = 0.6\n\n[atmosphere]\nmie_scattering_per_km = 0.012\nmie_extinction_per_km = 0.0133\n\n\
         [[atmosphere.weather]]\n\n[[atmosphere.weather]]\nmie_scattering_per_km = 0.03\nmie_extinction_per_km = 0.0333\n",
    );
    std::fs::write(&sky, text).unwrap();
    let header = "camera_km,albedo,sun_elev_deg,view_elev_deg,rel_azimuth_deg\n";
    let rows = "30,90,0\n12,5,0\n12,20,180\n";
    let (ground, written) = (dir.path().join("ground.csv"), dir.path().join("written.csv"));
    std::fs::write(&ground, format!("{header}{}", rows.lines().map(|r| format!("0,0.3,{r}\n")).collect::<String>())).unwrap();
    std::fs::write(&written, format!("{header}{}", rows.lines().map(|r| format!("1.5,0.6,{r}\n")).collect::<String>())).unwrap();
    let run = |extra: &[&str], cases: &std::path::Path, out: &str| {
        let out = dir.path().join(out);
        let o = skytune().args(["radiance", "--model", "lut", "--cpu", "--cases"]).arg(cases).arg("--out").arg(&out).args(extra).output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let text = std::fs::read_to_string(&out).unwrap();
        let values: Vec<Vec<f64>> = text.lines().filter(|l| !l.starts_with('#')).skip(1).map(|l| l.split(',').map(|x| x.parse().unwrap()).collect()).collect();
        (text, values)
    };
    let sky_arg = sky.to_str().unwrap();
    let (from_sky, a) = run(&["--sky", sky_arg, "--weather", "1"], &ground, "a.csv");
    let (_, b) = run(&["--atmosphere", "mie_scattering_per_km=0.03", "--atmosphere", "mie_extinction_per_km = 0.0333"], &written, "b.csv");
    assert_eq!(a, b);
    assert!(a.iter().all(|r| r[0] == 1.5 && r[1] == 0.6), "the sky's camera and ground replace the cases': {a:?}");
    assert!(
        from_sky.starts_with("# ") && from_sky.contains("sky.toml at weather 1") && from_sky.contains("mie_scattering_per_km: [0.0299"),
        "the header names the atmosphere: {from_sky}"
    );
    // Clear weather is the base atmosphere; the aerosol whitens the low sky.
    let (_, clear) = run(&["--sky", sky_arg, "--weather", "0"], &ground, "c.csv");
    let blue_over_red = |r: &Vec<f64>| r[7] / r[5];
    assert!(blue_over_red(&clear[2]) > blue_over_red(&a[2]), "{clear:?} {a:?}");
    // A bad key is a located error.
    let o = skytune().args(["radiance", "--cases"]).arg(&ground).arg("--out").arg(dir.path().join("d.csv")).args(["--atmosphere", "mie_g=2"]).output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && stderr.contains("mie_g") && stderr.contains("between -1 and 1"), "{stderr}");
}

#[test]
fn radiance_answers_every_case_and_locates_bad_rows() {
    let dir = tempfile::tempdir().unwrap();
    let cases = dir.path().join("cases.csv");
    std::fs::write(&cases, "camera_km,albedo,sun_elev_deg,view_elev_deg,rel_azimuth_deg\n0,0.3,30,90,0\n0.5,0,5,10,180\n1,0.1,-20,45,0\n").unwrap();
    let out = dir.path().join("out.csv");
    let o = skytune().args(["radiance", "--model", "reference", "--max-order", "1", "--cases"]).arg(&cases).arg("--out").arg(&out).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(&out).unwrap();
    let rows: Vec<Vec<f64>> = text.lines().filter(|l| !l.starts_with('#')).skip(1).map(|l| l.split(',').map(|x| x.parse().unwrap()).collect()).collect();
    // The reference reports its standard errors and paths beside its radiance: none for single
    // scattering.
    assert!(text.lines().any(|l| l == "camera_km,albedo,sun_elev_deg,view_elev_deg,rel_azimuth_deg,r,g,b,se_r,se_g,se_b,paths"), "{text}");
    assert!(rows.iter().all(|r| r.len() == 12 && r[8..] == [0.0; 4]), "{rows:?}");
    assert!(text.starts_with("# ") && text.contains("sr^-1"), "the units are stated: {text}");
    assert_eq!(rows.len(), 3);
    // The input columns are repeated; a day sky is blue, the night sky is black.
    assert_eq!(rows[1][..5], [0.5, 0.0, 5.0, 10.0, 180.0]);
    assert!(rows[0][7] > rows[0][6] && rows[0][6] > rows[0][5] && rows[0][5] > 0.0, "{:?}", rows[0]);
    assert!(rows[2][5..].iter().all(|x| *x < 1e-9), "{:?}", rows[2]);

    // A bad value names the file, the line and the column.
    std::fs::write(&cases, "camera_km,albedo,sun_elev_deg,view_elev_deg,rel_azimuth_deg\n0,0.3,30,90,0\n0,1.5,30,90,0\n").unwrap();
    let o = skytune().args(["radiance", "--cases"]).arg(&cases).arg("--out").arg(&out).output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && stderr.contains("cases.csv:3: albedo: expected 0..1"), "{stderr}");
    std::fs::write(&cases, "camera_km,albedo,sun_elev_deg,view_elev_deg,rel_azimuth_deg\n0,0.3,thirty,90,0\n").unwrap();
    let o = skytune().args(["radiance", "--cases"]).arg(&cases).arg("--out").arg(&out).output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && stderr.contains("cases.csv:2: column 3:"), "{stderr}");
}

#[test]
fn radiance_stops_rays_at_a_distance_and_reports_their_transmittance() {
    let dir = tempfile::tempdir().unwrap();
    let cases = dir.path().join("cases.csv");
    let header = "camera_km,albedo,sun_elev_deg,view_elev_deg,rel_azimuth_deg,distance_km\n";
    std::fs::write(&cases, format!("{header}0,0.3,30,2,90,\n0,0.3,30,2,90,1\n0,0.3,30,2,90,20\n")).unwrap();
    let out = dir.path().join("out.csv");
    let o = skytune().args(["radiance", "--model", "reference", "--max-order", "1", "--cases"]).arg(&cases).arg("--out").arg(&out).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(&out).unwrap();
    assert!(text.lines().any(|l| l == "camera_km,albedo,sun_elev_deg,view_elev_deg,rel_azimuth_deg,distance_km,r,g,b,t_r,t_g,t_b,se_r,se_g,se_b,paths"), "{text}");
    let rows: Vec<Vec<Option<f64>>> = text.lines().filter(|l| !l.starts_with('#')).skip(1).map(|l| l.split(',').map(|x| x.parse().ok()).collect()).collect();
    assert_eq!(rows.len(), 3);
    assert_eq!((rows[0][5], rows[1][5], rows[2][5]), (None, Some(1.0), Some(20.0)), "the distance is repeated, empty for the edge");
    let [sky, near, far] = [0, 1, 2].map(|k| rows[k][6..12].iter().map(|x| x.unwrap()).collect::<Vec<f64>>());
    for c in 0..3 {
        // The in-scatter grows with the distance towards the sky's; the transmittance falls.
        assert!(0.0 < near[c] && near[c] < far[c] && far[c] < sky[c], "{near:?} {far:?} {sky:?}");
        assert!(1.0 > near[c + 3] && near[c + 3] > far[c + 3] && far[c + 3] > sky[c + 3], "{near:?} {far:?} {sky:?}");
    }
    // Blue light is scattered, and lost, fastest.
    assert!(far[2] > far[0] && far[5] < far[3], "{far:?}");

    // The lut model's exact integration on the GPU answers the same rays, with the same columns
    // but the reference's noise.
    std::fs::write(&cases, format!("{header}0,0.3,30,2,90,\n0,0.3,30,2,90,1\n0,0.3,30,2,90,20\n")).unwrap();
    let o = skytune().args(["radiance", "--model", "lut", "--cpu", "--cases"]).arg(&cases).arg("--out").arg(&out).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(&out).unwrap();
    assert!(text.lines().any(|l| l == "camera_km,albedo,sun_elev_deg,view_elev_deg,rel_azimuth_deg,distance_km,r,g,b,t_r,t_g,t_b"), "{text}");
    let lut: Vec<Vec<f64>> = text.lines().filter(|l| !l.starts_with('#')).skip(1).map(|l| l.split(',').skip(6).map(|x| x.parse().unwrap()).collect()).collect();
    for (row, reference) in lut.iter().zip([&sky, &near, &far]) {
        // Transmittance alike; in-scatter above the reference's single scattering (lut has every order).
        for c in 0..3 {
            assert!((row[c + 3] - reference[c + 3]).abs() < 1e-3 && row[c] > reference[c], "{row:?} against {reference:?}");
        }
    }

    // A bad distance names its line; a model that cannot stop a ray short says so.
    std::fs::write(&cases, format!("{header}0,0.3,30,2,90,1\n0,0.3,30,2,90,-4\n")).unwrap();
    let o = skytune().args(["radiance", "--model", "reference", "--cases"]).arg(&cases).arg("--out").arg(&out).output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && stderr.contains("cases.csv:3: distance_km: expected a distance > 0 km"), "{stderr}");
    std::fs::write(&cases, format!("{header}0,0.3,30,2,90,1\n")).unwrap();
    let o = skytune().args(["radiance", "--model", "linear", "--cases"]).arg(&cases).arg("--out").arg(&out).output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && stderr.contains("distance_km: --model linear gives one display colour, not a radiance along a ray"), "{stderr}");
    let o = skytune().args(["radiance", "--model", "single", "--aerial", "exact", "--cases"]).arg(&cases).arg("--out").arg(&out).output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && stderr.contains("--aerial exact: only --model lut marches"), "{stderr}");
    let o = skytune().args(["radiance", "--model", "lut", "--aerial", "volume", "--volume-size", "32x32x300", "--cases"]).arg(&cases).arg("--out").arg(&out).output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && stderr.contains("--volume-size: expected 2..=128 cells in depth, found 300"), "{stderr}");
}

/// Every physical runtime model answers finite rays through the renderer's aerial-perspective
/// volume; `lut`'s volume is near its exact march, and `single`'s, without the orders above
/// the first, gathers less.
#[test]
fn radiance_answers_finite_rays_through_the_volume() {
    let dir = tempfile::tempdir().unwrap();
    let cases = dir.path().join("cases.csv");
    std::fs::write(&cases, "camera_km,albedo,sun_elev_deg,view_elev_deg,rel_azimuth_deg,distance_km\n0.5,0.3,20,2,90,3\n0.5,0.3,20,2,90,40\n").unwrap();
    let out = dir.path().join("out.csv");
    let run = |extra: &[&str]| {
        let o = skytune().args(["radiance", "--cpu", "--cases"]).arg(&cases).arg("--out").arg(&out).args(extra).output().unwrap();
        assert!(o.status.success(), "{extra:?}: {}", String::from_utf8_lossy(&o.stderr));
        let text = std::fs::read_to_string(&out).unwrap();
        assert!(text.lines().any(|l| l == "camera_km,albedo,sun_elev_deg,view_elev_deg,rel_azimuth_deg,distance_km,r,g,b,t_r,t_g,t_b"), "{text}");
        text.lines().filter(|l| !l.starts_with('#')).skip(1).map(|l| l.split(',').skip(6).map(|x| x.parse().unwrap()).collect::<Vec<f64>>()).collect::<Vec<_>>()
    };
    let exact = run(&["--model", "lut"]);
    let volume = run(&["--model", "lut", "--aerial", "volume"]);
    let single = run(&["--model", "single"]);
    let precomputed = run(&["--model", "precomputed"]);
    for k in 0..2 {
        for c in 0..3 {
            // Within 3% of the exact march and 0.01 of its transmittance (the p95s);
            // measured at 40 km 1.0% (red) and 0.0036 (red: read between cells 2.2 degrees apart
            // near the horizon).
            assert!((volume[k][c] - exact[k][c]).abs() <= 0.03 * exact[k][c] && (volume[k][c + 3] - exact[k][c + 3]).abs() <= 0.01, "{:?} against {:?}", volume[k], exact[k]);
            assert!(single[k][c] < volume[k][c] && (single[k][c + 3] - volume[k][c + 3]).abs() < 1e-6, "{:?} against {:?}", single[k], volume[k]);
            assert_eq!(precomputed[k], volume[k], "precomputed's volume is the LUT march with every order");
        }
    }
}

#[test]
fn radiance_progress_in_a_log_is_whole_lines() {
    let dir = tempfile::tempdir().unwrap();
    let cases = dir.path().join("cases.csv");
    let mut text = String::from("camera_km,albedo,sun_elev_deg,view_elev_deg,rel_azimuth_deg\n");
    let count = 48;
    for k in 0..count {
        text.push_str(&format!("0.2,0.3,{},{},{}\n", k as i32 % 12 - 6, k % 9 * 10, k * 15 % 180));
    }
    std::fs::write(&cases, text).unwrap();
    let log = dir.path().join("stderr.txt");
    let o = skytune()
        .args(["radiance", "--model", "reference", "--paths", "256", "--cases"])
        .arg(&cases)
        .arg("--out")
        .arg(dir.path().join("out.csv"))
        .stderr(std::fs::File::create(&log).unwrap())
        .output()
        .unwrap();
    let stderr = std::fs::read_to_string(&log).unwrap();
    assert!(o.status.success(), "{stderr}");
    // Not a terminal: no bar, no carriage returns; a line now and then and a summary, each whole.
    assert!(!stderr.contains('\r'), "{stderr:?}");
    assert!(stderr.ends_with('\n'), "{stderr:?}");
    let lines: Vec<&str> = stderr.lines().collect();
    assert!(lines.len() < count, "{} lines for {count} cases: {stderr}", lines.len());
    assert!(lines.iter().any(|l| l.starts_with("radiance: done, 48 in ")), "a summary line: {stderr}");
    // Every order: each daylit case's standard error is positive and below its radiance.
    let text = std::fs::read_to_string(dir.path().join("out.csv")).unwrap();
    let rows: Vec<Vec<f64>> = text.lines().filter(|l| !l.starts_with('#')).skip(1).map(|l| l.split(',').map(|x| x.parse().unwrap()).collect()).collect();
    assert_eq!(rows.len(), count);
    for r in rows.iter().filter(|r| r[2] > 0.0) {
        assert!((0..3).all(|c| r[8 + c] > 0.0 && r[8 + c] < r[5 + c]), "{r:?}");
    }
}

#[test]
fn new_sky_refuses_an_existing_folder_and_writes_never_leave_half_files() {
    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("my_sky");
    let o = skytune().arg("new-sky").arg(&target).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(target.join("sky.toml").is_file());
    // Again: refused, the artist's folder untouched.
    std::fs::write(target.join("sky.toml"), "# my edits\n").unwrap();
    let o = skytune().arg("new-sky").arg(&target).output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && stderr.contains("exists already") && stderr.contains("--force"), "{stderr}");
    assert_eq!(std::fs::read_to_string(target.join("sky.toml")).unwrap(), "# my edits\n");
    let o = skytune().arg("new-sky").arg(&target).arg("--force").output().unwrap();
    assert!(o.status.success());
    assert!(std::fs::read_to_string(target.join("sky.toml")).unwrap().contains("[[object]]"));
    // A folder that cannot be created (a file is in the way): a clear error, nothing left behind.
    let blocker = dir.path().join("blocker");
    std::fs::write(&blocker, "x").unwrap();
    let o = skytune().arg("new-sky").arg(blocker.join("sky")).output().unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("blocker"));
    // A screenshot that cannot be written names its path; an existing one is never truncated.
    let shot = dir.path().join("shot.png");
    std::fs::write(&shot, "previous").unwrap();
    let o = skytune().args(["render", "--size", "32x18", "--out"]).arg(blocker.join("shot.png")).output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && stderr.contains("blocker/shot.png"), "{stderr}");
    let leftovers: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().contains(".tmp") || e.file_name().to_string_lossy().contains(".partial"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
}

#[test]
fn bench_reference_writes_its_table_and_chart() {
    let dir = tempfile::tempdir().unwrap();
    let o = skytune().args(["bench", "reference", "--paths", "64,128", "--long", "256", "--out"]).arg(dir.path()).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let md = std::fs::read_to_string(dir.path().join("reference-convergence.md")).unwrap();
    for regime in ["day", "low sun", "twilight"] {
        assert!(md.contains(regime), "{md}");
    }
    let png = image::open(dir.path().join("reference-convergence.png")).unwrap().to_rgb8();
    assert!(png.pixels().any(|p| p.0 != [255, 255, 255]), "the chart is not blank");
}

#[test]
fn more_aerosol_whitens_the_horizon_and_widens_the_aureole() {
    // Sun 30 degrees up; the almucantar through the sun from 3 to 90 degrees away, and the
    // horizon opposite the sun.
    let dir = tempfile::tempdir().unwrap();
    let cases = dir.path().join("cases.csv");
    let away = [3.0, 6.0, 10.0, 15.0, 20.0, 30.0, 45.0, 60.0, 90.0];
    let mut text = "camera_km,albedo,sun_elev_deg,view_elev_deg,rel_azimuth_deg\n".to_string();
    for a in away {
        text.push_str(&format!("0,0.3,30,30,{a}\n"));
    }
    text.push_str("0,0.3,30,2,180\n");
    std::fs::write(&cases, text).unwrap();
    let run = |tau: &str| {
        let out = dir.path().join(format!("{tau}.csv"));
        let o = skytune()
            .args(["radiance", "--model", "lut", "--cpu", "--cases"])
            .arg(&cases)
            .arg("--out")
            .arg(&out)
            .args(["--atmosphere", &format!("aerosol_optical_depth={tau}")])
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let text = std::fs::read_to_string(&out).unwrap();
        assert!(text.starts_with("# ") && text.contains(&format!("with aerosol_optical_depth={tau}")), "{text}");
        let rows: Vec<Vec<f64>> = text.lines().filter(|l| !l.starts_with('#')).skip(1).map(|l| l.split(',').map(|x| x.parse().unwrap()).collect()).collect();
        rows
    };
    let (clean, hazy) = (run("0.05"), run("0.5"));
    // The aureole: the angle from the sun at which the sky falls to twice its brightness 90
    // degrees away (green channel, interpolated in log radiance).
    let width = |rows: &[Vec<f64>]| {
        let far = rows[away.len() - 1][6];
        let k = (1..away.len()).find(|&k| rows[k][6] <= 2.0 * far).unwrap();
        let (l0, l1) = ((rows[k - 1][6] / far).ln(), (rows[k][6] / far).ln());
        away[k - 1] + (away[k] - away[k - 1]) * (l0 - 2f64.ln()) / (l0 - l1)
    };
    assert!(width(&hazy) > width(&clean), "aureole {} vs {} degrees", width(&hazy), width(&clean));
    let blue_over_red = |rows: &[Vec<f64>]| rows[away.len()][7] / rows[away.len()][5];
    let (b_clean, b_hazy) = (blue_over_red(&clean), blue_over_red(&hazy));
    assert!(b_hazy < b_clean && (b_hazy - 1.0).abs() < (b_clean - 1.0).abs(), "horizon blue/red {b_hazy} vs {b_clean}");
}

#[test]
fn validation_on_a_committed_scan_matches_the_committed_table() {
    // One held-out scan of Kider et al. 2014 (data/measured/kider2014/), the GPU and analytic
    // models (the reference's figures take minutes): the fitted parameter and both errors as
    // docs/validation.csv records them.
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let scan = root.join("data/measured/kider2014/2013-09-24_13-10.csv");
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("v.csv");
    let o = skytune().args(["validate", "--models", "preetham,hosek,single,lut", "--cpu", "--out"]).arg(&out).arg(&scan).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let read = |p: &std::path::Path| -> Vec<std::collections::HashMap<String, String>> {
        let text = std::fs::read_to_string(p).unwrap();
        let mut r = csv::Reader::from_reader(text.as_bytes());
        let headers = r.headers().unwrap().clone();
        r.records().map(|rec| headers.iter().zip(rec.unwrap().iter()).map(|(h, v)| (h.to_string(), v.to_string())).collect()).collect()
    };
    let committed = read(&root.join("docs/validation.csv"));
    let ours = read(&out);
    assert_eq!(ours.len(), 4);
    let f = |row: &std::collections::HashMap<String, String>, k: &str| row[k].parse::<f64>().unwrap();
    for row in &ours {
        let table = committed
            .iter()
            .find(|c| c["scan"] == row["scan"] && c["model"] == row["model"])
            .unwrap_or_else(|| panic!("{} {} not in docs/validation.csv", row["scan"], row["model"]));
        let (v, t) = (f(row, "value"), f(table, "value"));
        assert!((v / t - 1.0).abs() < 0.05, "{}: fitted {v} vs the table's {t}", row["model"]);
        for k in ["luminance_median", "blue_red_median"] {
            assert!((f(row, k) - f(table, k)).abs() < 0.01, "{} {k}: {} vs the table's {}", row["model"], f(row, k), f(table, k));
        }
    }
}

#[test]
fn each_command_names_the_sky_file_models_it_takes() {
    // One enum of models (the sky file's names); each command takes its own subset and names it.
    for (args, taken, refused) in [
        (&["radiance", "--cases", "none.csv", "--out", "none.csv", "--model"][..], "reference, single, lut, precomputed, cells, preetham, hosek, linear", "bitmap"),
        (&["bake", "--out", "none", "--model"][..], "single, lut, precomputed, cells, preetham, hosek", "reference"),
        (&["validate", "none.csv", "--models"][..], "preetham, hosek, single, lut, reference", "cells"),
    ] {
        let o = skytune().args(args).arg(refused).output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{args:?} {refused}");
        assert!(err.contains(&format!("invalid value '{refused}'")) && err.contains(taken), "{args:?} {refused}: {err}");
    }
}

/// `validate-aerial` writes a row per method and band, and its table between markers, keeping
/// the rest of the report file.
#[test]
fn validate_aerial_tabulates_every_method_by_band() {
    let dir = tempfile::tempdir().unwrap();
    let (out, report) = (dir.path().join("aerial.csv"), dir.path().join("validation.md"));
    std::fs::write(&report, "# Validation\n\nkept text\n").unwrap();
    let o = skytune()
        .args(["validate-aerial", "--cpu", "--cases", "6", "--paths", "16", "--sizes", "8x8x8,16x16x16", "--out"])
        .arg(&out)
        .arg("--report")
        .arg(&report)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let csv = std::fs::read_to_string(&out).unwrap();
    let rows: Vec<&str> = csv.lines().skip(1).collect();
    // Three methods (exact, two sizes) x (three sun bands + three distance bands).
    assert_eq!(rows.len(), 18, "{csv}");
    assert!(rows.iter().any(|r| r.starts_with("volume 16x16x16,twilight,2,")), "{csv}");
    let md = std::fs::read_to_string(&report).unwrap();
    assert!(md.starts_with("# Validation\n\nkept text\n") && md.contains("| volume 8x8x8, 10-100 km |") && md.contains("<!-- skytune validate-aerial: end -->"), "{md}");
    let o = skytune().args(["validate-aerial", "--cpu", "--sizes", "8x8x300", "--out"]).arg(&out).output().unwrap();
    assert!(!o.status.success() && String::from_utf8_lossy(&o.stderr).contains("--sizes: expected 2..=128 cells in depth, found 300"), "{}", String::from_utf8_lossy(&o.stderr));
}
