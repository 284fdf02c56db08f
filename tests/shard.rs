//! Work split with `--shard K/N` and put back together with `skytune merge`: three shards give
//! the same bytes as one run (the reference's tables), the same counts (the sweep), and the
//! same sky folders (bake).

use std::path::Path;
use std::process::Command;

use skytune::atmosphere::dome::{Haze, ReferenceDome};
use skytune::atmosphere::reference::ReferenceSettings;
use skytune::support::shard::{self, Shard};

fn skytune(args: &[&str], at: &Path) {
    let out = Command::new(env!("CARGO_BIN_EXE_skytune")).args(args).current_dir(at).env("SKYTUNE_ADAPTER", "cpu").output().expect("running skytune");
    assert!(out.status.success(), "skytune {args:?} failed:\n{}", String::from_utf8_lossy(&out.stderr));
}

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

#[test]
fn three_reference_shards_merge_into_the_unsharded_table() {
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    // Twilight and day, both cameras, ground albedo on and off: cases of different costs.
    let mut cases = String::from("camera_km,albedo,sun_elev_deg,view_elev_deg,rel_azimuth_deg\n");
    for (k, sun) in [-6.0, -3.0, 2.0, 30.0].iter().enumerate() {
        for az in [0.0, 90.0, 180.0] {
            cases.push_str(&format!("{},{},{sun},{},{az}\n", if k % 2 == 0 { 0.2 } else { 5.0 }, if az == 90.0 { 0.3 } else { 0.0 }, k as f64 * 5.0));
        }
    }
    std::fs::write(d.join("cases.csv"), cases).expect("cases");
    let common = ["radiance", "--model", "reference", "--paths", "64", "--cases", "cases.csv"];
    skytune(&[&common[..], &["--out", "whole.csv"]].concat(), d);
    for k in 1..=3 {
        let (shard, out) = (format!("{k}/3"), format!("part{k}.csv"));
        skytune(&[&common[..], &["--shard", &shard, "--out", &out]].concat(), d);
    }
    // The parts in any order.
    skytune(&["merge", "--out", "merged.csv", "part3.csv", "part1.csv", "part2.csv"], d);
    let whole = read(&d.join("whole.csv"));
    assert_eq!(whole.lines().count(), 2 + 1 + 12, "{whole}");
    assert_eq!(read(&d.join("merged.csv")), whole, "3 shards merged differ from the unsharded run");
    // A missing shard is an error naming it.
    let out = Command::new(env!("CARGO_BIN_EXE_skytune")).args(["merge", "--out", "x.csv", "part1.csv", "part3.csv"]).current_dir(d).output().expect("ran");
    assert!(!out.status.success() && String::from_utf8_lossy(&out.stderr).contains("missing 2/3"), "{}", String::from_utf8_lossy(&out.stderr));
}

#[test]
fn three_reference_dome_shards_merge_into_the_saved_dataset() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (hazes, suns, dome, paths) = ([Haze::Default, Haze::Hazy], [-4.0, 1.0, 30.0], (2, 3), ReferenceSettings { paths: 16, ..Default::default() });
    let whole = ReferenceDome::compute(&hazes, &suns, dome, paths, &|_, _| Ok(())).expect("computed");
    let path = dir.path().join("whole.csv");
    whole.save(&path).expect("saved");
    let parts: Vec<(String, String)> =
        (0..3).map(|k| (format!("part{k}"), ReferenceDome::shard_table(&hazes, &suns, dome, paths, Shard { index: k, count: 3 }, &|_, _| Ok(())).expect("shard"))).collect();
    assert_eq!(shard::merge_tables(&parts).expect("merged"), read(&path));
}

/// The report without its timings (seconds differ from run to run).
fn without_timings(md: &str) -> String {
    md.lines()
        .filter(|l| !l.starts_with("Written by"))
        .map(|l| if l.starts_with("| ") && l.ends_with(" |") { l.rsplitn(3, '|').nth(2).unwrap_or(l).to_string() } else { l.to_string() })
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn three_sweep_shards_merge_into_the_unsharded_report() {
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    // 2,100 sets: three atmospheres (batches) for most models, one for the cell model.
    let common = ["sweep", "--count", "2100", "--seed", "3"];
    skytune(&[&common[..], &["--out", "whole.md"]].concat(), d);
    for k in 1..=3 {
        let (shard, out) = (format!("{k}/3"), format!("part{k}.toml"));
        skytune(&[&common[..], &["--shard", &shard, "--out", &out]].concat(), d);
    }
    skytune(&["merge", "--out", "merged.md", "part2.toml", "part3.toml", "part1.toml"], d);
    let (whole, merged) = (read(&d.join("whole.md")), read(&d.join("merged.md")));
    assert!(merged.contains("in 3 shards"), "{merged}");
    assert_eq!(without_timings(&merged), without_timings(&whole));
}

#[test]
fn baking_several_skies_in_shards_writes_each_sky_once() {
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let skies: Vec<String> = ["desert", "forest", "lakes"].iter().map(|s| root.join("skies").join(s).join("sky.toml").display().to_string()).collect();
    let common = ["bake", "--cpu", "--model", "preetham", "--rows", "4", "--weathers", "1"];
    let with_skies = |extra: &[&str]| -> Vec<String> { common.iter().map(|s| s.to_string()).chain(skies.iter().cloned()).chain(extra.iter().map(|s| s.to_string())).collect() };
    let run = |args: Vec<String>| skytune(&args.iter().map(|s| s.as_str()).collect::<Vec<_>>(), d);
    run(with_skies(&["--out", "whole"]));
    for k in 1..=3 {
        run(with_skies(&["--shard", &format!("{k}/3"), "--out", "sharded"]));
    }
    for sky in ["desert", "forest", "lakes"] {
        for file in ["sky.toml", "gradient_0.png"] {
            let (a, b) = (d.join("whole").join(sky).join(file), d.join("sharded").join(sky).join(file));
            assert_eq!(std::fs::read(&a).unwrap_or_else(|e| panic!("{}: {e}", a.display())), std::fs::read(&b).expect("sharded file"), "{sky}/{file}");
        }
    }
}

/// A few radiance cases: twilight and day, so that a shard takes a while.
fn write_cases(d: &Path, n: usize) {
    let mut cases = String::from("camera_km,albedo,sun_elev_deg,view_elev_deg,rel_azimuth_deg\n");
    for k in 0..n {
        cases.push_str(&format!("0.2,0.3,{},{},{}\n", [-4.0, 20.0, 3.0][k % 3], (k % 4) as f64 * 10.0, (k * 45) % 360));
    }
    std::fs::write(d.join("cases.csv"), cases).expect("cases");
}

#[test]
fn an_interrupted_shard_leaves_no_file_and_runs_again_to_the_same_bytes_and_a_complete_one_is_skipped() {
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    write_cases(d, 9);
    let args = ["radiance", "--model", "reference", "--paths", "2048", "--target-se", "0.004", "--cases", "cases.csv", "--shard", "2/2"];
    // Killed mid-way: nothing written, not even in part.
    let mut child = Command::new(env!("CARGO_BIN_EXE_skytune")).args(args).args(["--out", "cut.csv"]).current_dir(d).spawn().expect("started");
    std::thread::sleep(std::time::Duration::from_millis(1500));
    let finished_early = child.try_wait().expect("waited").is_some();
    let _ = child.kill();
    let _ = child.wait();
    if !finished_early {
        assert!(!d.join("cut.csv").exists(), "an interrupted shard left a file");
    }
    // Run again, and once uninterrupted elsewhere: the same bytes.
    skytune(&[&args[..], &["--out", "cut.csv"]].concat(), d);
    skytune(&[&args[..], &["--out", "clean.csv"]].concat(), d);
    assert_eq!(read(&d.join("cut.csv")), read(&d.join("clean.csv")));
    // A complete shard with the same inputs is skipped (the file is not rewritten)...
    let before = std::fs::metadata(d.join("clean.csv")).and_then(|m| m.modified()).expect("mtime");
    let out = Command::new(env!("CARGO_BIN_EXE_skytune")).args(args).args(["--out", "clean.csv"]).current_dir(d).output().expect("ran");
    assert!(out.status.success() && String::from_utf8_lossy(&out.stdout).contains("skipped"), "{}", String::from_utf8_lossy(&out.stdout));
    assert_eq!(std::fs::metadata(d.join("clean.csv")).and_then(|m| m.modified()).expect("mtime"), before);
    // ...but not one of other settings, nor a cut one.
    let text = read(&d.join("clean.csv"));
    std::fs::write(d.join("clean.csv"), &text[..text.len() - 10]).expect("cut");
    let out = Command::new(env!("CARGO_BIN_EXE_skytune")).args(args).args(["--out", "clean.csv"]).current_dir(d).output().expect("ran");
    assert!(out.status.success() && !String::from_utf8_lossy(&out.stdout).contains("skipped"));
    assert_eq!(read(&d.join("clean.csv")), text);
    let out = Command::new(env!("CARGO_BIN_EXE_skytune"))
        .args(["radiance", "--model", "reference", "--paths", "256", "--cases", "cases.csv", "--shard", "2/2", "--out", "clean.csv"])
        .current_dir(d)
        .output()
        .expect("ran");
    assert!(out.status.success() && !String::from_utf8_lossy(&out.stdout).contains("skipped"), "other settings were skipped");
}

#[test]
fn shard_auto_reads_the_job_array_and_a_target_run_writes_the_paths_column() {
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    write_cases(d, 6);
    let common = ["radiance", "--model", "reference", "--paths", "512", "--target-se", "0.02", "--cases", "cases.csv"];
    skytune(&[&common[..], &["--out", "whole.csv"]].concat(), d);
    // Slurm (1-based here), then a Kubernetes indexed Job (0-based, the count given once).
    let run = |env: &[(&str, &str)], shard: &str, out: &str| {
        let o = Command::new(env!("CARGO_BIN_EXE_skytune")).args(common).args(["--shard", shard, "--out", out]).envs(env.iter().copied()).current_dir(d).output().expect("ran");
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    };
    run(&[("SLURM_ARRAY_TASK_ID", "1"), ("SLURM_ARRAY_TASK_COUNT", "2")], "auto", "a.csv");
    run(&[("JOB_COMPLETION_INDEX", "1")], "auto/2", "b.csv");
    skytune(&["merge", "--out", "merged.csv", "a.csv", "b.csv"], d);
    let whole = read(&d.join("whole.csv"));
    assert_eq!(read(&d.join("merged.csv")), whole);
    let columns = whole.lines().find(|l| !l.starts_with('#')).expect("columns");
    assert!(columns.ends_with("se_r,se_g,se_b,paths"), "{columns}");
    for row in whole.lines().filter(|l| !l.starts_with('#')).skip(1) {
        let paths: u32 = row.rsplit(',').next().and_then(|p| p.parse().ok()).expect("paths column");
        assert!((256..=512).contains(&paths), "{row}");
    }
    let o = Command::new(env!("CARGO_BIN_EXE_skytune"))
        .args(common)
        .args(["--shard", "auto", "--out", "x.csv"])
        .env_remove("SLURM_ARRAY_TASK_ID")
        .env_remove("JOB_COMPLETION_INDEX")
        .current_dir(d)
        .output()
        .expect("ran");
    assert!(!o.status.success() && String::from_utf8_lossy(&o.stderr).contains("SLURM_ARRAY_TASK_ID"), "{}", String::from_utf8_lossy(&o.stderr));
}

#[test]
fn the_one_machine_recipe_of_docs_batch_runs_as_written() {
    // The block after "<!-- test: one machine -->" in docs/batch.md, run by bash in a folder
    // with a small cases.csv and this build's skytune first on the PATH.
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let doc = read(&root.join("docs/batch.md"));
    let start = doc.find("<!-- test: one machine -->").expect("docs/batch.md marks its one-machine recipe");
    let block = doc[start..].split("```bash\n").nth(1).and_then(|b| b.split("\n```").next()).expect("a bash block after the marker");
    let dir = tempfile::tempdir().expect("temp dir");
    let d = dir.path();
    write_cases(d, 6);
    let bin = Path::new(env!("CARGO_BIN_EXE_skytune")).parent().expect("bin dir").to_path_buf();
    let path = format!("{}:{}", bin.display(), std::env::var("PATH").unwrap_or_default());
    let out = Command::new("bash").args(["-euo", "pipefail", "-c", block]).env("PATH", path).current_dir(d).output().expect("bash");
    assert!(out.status.success(), "the recipe failed:\n{block}\n{}", String::from_utf8_lossy(&out.stderr));
    let merged = read(&d.join("reference.csv"));
    assert_eq!(merged.lines().filter(|l| !l.starts_with('#')).count(), 1 + 6, "{merged}");
    assert!(!merged.contains("skytune shard"), "the merge keeps no shard line");
}
