//! Fuzzing the sky parser and validator (proptest, in the normal test run): structure-aware
//! mutations of every committed sky (types swapped, keys deleted or renamed, extreme numbers, long
//! strings, deep nesting, duplicated tables) and raw byte damage of the mutated text. No input may
//! panic; every rejection names the file, a line and a field. `SKYTUNE_FUZZ_CASES` sets the number
//! of cases (CI runs the default; docs/reliability.md records a run of 100,000).

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};
use skytune::sky::load::{load_sky, AssetSource};

/// A sky file's text with its images in memory (large textures shrunk to 8 x 8: the validator
/// checks references, sizes of colour bitmaps and limits, not texture content).
struct MemorySource {
    name: String,
    text: String,
    images: HashMap<String, image::RgbaImage>,
}

impl AssetSource for MemorySource {
    fn sky_name(&self) -> String {
        self.name.clone()
    }
    fn sky_text(&self) -> Result<String, String> {
        Ok(self.text.clone())
    }
    fn image(&self, rel: &str) -> Result<image::RgbaImage, String> {
        self.images.get(rel).cloned().ok_or_else(|| format!("cannot open {rel}: no such file"))
    }
    fn display(&self, rel: &str) -> String {
        rel.to_string()
    }
    fn file_on_disk(&self, _rel: &str) -> Option<PathBuf> {
        None
    }
}

/// Every committed sky file (sky files only, not continents) with its folder's images.
fn corpus() -> Vec<(String, String, HashMap<String, image::RgbaImage>)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("skies");
    let mut out = Vec::new();
    let mut dirs: Vec<_> = std::fs::read_dir(&root).unwrap().map(|e| e.unwrap().path()).filter(|p| p.is_dir()).collect();
    dirs.sort();
    for dir in dirs {
        let mut images = HashMap::new();
        let mut tomls = Vec::new();
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            let name = path.file_name().unwrap().to_string_lossy().into_owned();
            match path.extension().and_then(|e| e.to_str()) {
                Some("png") => {
                    let img = image::open(&path).unwrap().to_rgba8();
                    let img = if img.width() > 64 || img.height() > 64 { image::imageops::resize(&img, 8, 8, image::imageops::FilterType::Nearest) } else { img };
                    images.insert(name, img);
                }
                Some("toml") => tomls.push(path),
                _ => {}
            }
        }
        for t in tomls {
            let text = std::fs::read_to_string(&t).unwrap();
            if text.contains("[seasons]") {
                continue;
            }
            out.push((t.display().to_string(), text, images.clone()));
        }
    }
    assert!(out.len() >= 4, "the committed skies: {}", out.len());
    out
}

/// A step from a table or array to one of its children.
#[derive(Debug, Clone)]
enum Step {
    Key(String),
    Index(usize),
}

/// Paths of every value in `v`.
fn paths(v: &toml::Value, prefix: &mut Vec<Step>, out: &mut Vec<Vec<Step>>) {
    out.push(prefix.clone());
    match v {
        toml::Value::Table(t) => {
            for (k, child) in t {
                prefix.push(Step::Key(k.clone()));
                paths(child, prefix, out);
                prefix.pop();
            }
        }
        toml::Value::Array(a) => {
            for (i, child) in a.iter().enumerate() {
                prefix.push(Step::Index(i));
                paths(child, prefix, out);
                prefix.pop();
            }
        }
        _ => {}
    }
}

fn at<'a>(v: &'a mut toml::Value, path: &[Step]) -> Option<&'a mut toml::Value> {
    let mut cur = v;
    for s in path {
        cur = match (s, cur) {
            (Step::Key(k), toml::Value::Table(t)) => t.get_mut(k)?,
            (Step::Index(i), toml::Value::Array(a)) => a.get_mut(*i)?,
            _ => return None,
        };
    }
    Some(cur)
}

const EXTREMES: [f64; 10] = [0.0, -0.0, -1.0, 1e308, -1e308, f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 5e-324, 4294967297.0];
const KEYS: [&str; 8] = ["name", "priority", "texture", "path", "stage", "bitmap", "mode", "kind"];

/// Applies one structure-aware mutation chosen by `op` with randomness from `seed`.
fn mutate(doc: &mut toml::Value, op: u8, seed: u64) {
    let mut rng = fastrand::Rng::with_seed(seed);
    let mut all = Vec::new();
    paths(doc, &mut Vec::new(), &mut all);
    let path = all[rng.usize(..all.len())].clone();
    let Some(target) = at(doc, &path) else { return };
    match op % 8 {
        // Delete a key of a table (or an element of an array).
        0 => match target {
            toml::Value::Table(t) if !t.is_empty() => {
                let k = t.keys().nth(rng.usize(..t.len())).cloned().unwrap();
                t.remove(&k);
            }
            toml::Value::Array(a) if !a.is_empty() => {
                a.remove(rng.usize(..a.len()));
            }
            _ => {}
        },
        // Swap the value's type.
        1 => {
            *target = match rng.u8(..6) {
                0 => toml::Value::String("swapped".into()),
                1 => toml::Value::Integer(rng.i64(..)),
                2 => toml::Value::Float(rng.f64() * 1e3 - 500.0),
                3 => toml::Value::Boolean(rng.bool()),
                4 => toml::Value::Array(vec![toml::Value::Integer(1), toml::Value::String("x".into())]),
                _ => toml::Value::Table(toml::map::Map::new()),
            }
        }
        // Extreme numbers.
        2 => {
            *target =
                if rng.bool() { toml::Value::Float(EXTREMES[rng.usize(..EXTREMES.len())]) } else { toml::Value::Integer([i64::MAX, i64::MIN, 0, -1, 1 << 40][rng.usize(..5)]) };
        }
        // Long strings (and odd characters).
        3 => {
            let unit = ["a", "é", "\u{1F600}", "\\", "\"", "../", "\u{0}"][rng.usize(..7)];
            *target = toml::Value::String(unit.repeat(rng.usize(1..20_000)));
        }
        // Deep nesting.
        4 => {
            let mut v = toml::Value::Integer(1);
            for _ in 0..rng.usize(10..300) {
                v = if rng.bool() { toml::Value::Array(vec![v]) } else { toml::Value::Table([("k".to_string(), v)].into_iter().collect()) };
            }
            *target = v;
        }
        // Duplicate an element of an array (objects, stages, keys).
        5 => {
            if let toml::Value::Array(a) = target {
                if !a.is_empty() {
                    let e = a[rng.usize(..a.len())].clone();
                    for _ in 0..rng.usize(1..4) {
                        a.push(e.clone());
                    }
                }
            }
        }
        // Rename a key, to a neighbour's name or nonsense.
        6 => {
            if let toml::Value::Table(t) = target {
                if let Some(k) = t.keys().nth(rng.usize(..t.len().max(1))).cloned() {
                    let v = t.remove(&k).unwrap();
                    let new = if rng.bool() { KEYS[rng.usize(..KEYS.len())].to_string() } else { format!("{k}_x") };
                    t.insert(new, v);
                }
            }
        }
        // A number where a reference is expected, or a missing file.
        _ => {
            if let toml::Value::String(s) = target {
                *s = if rng.bool() { format!("missing_{}.png", rng.u32(..)) } else { s.chars().rev().collect() };
            }
        }
    }
}

/// Raw damage of the text: truncation, a byte flipped, a line duplicated.
fn damage(text: &str, kind: u8, seed: u64) -> String {
    let mut rng = fastrand::Rng::with_seed(seed);
    let mut bytes = text.as_bytes().to_vec();
    if bytes.is_empty() {
        return String::new();
    }
    match kind % 3 {
        0 => bytes.truncate(rng.usize(..bytes.len())),
        1 => {
            let i = rng.usize(..bytes.len());
            bytes[i] = rng.u8(..);
        }
        _ => {
            let lines: Vec<&str> = text.lines().collect();
            let i = rng.usize(..lines.len().max(1));
            let mut out = lines.clone();
            if let Some(l) = lines.get(i) {
                out.insert(i, l);
            }
            return out.join("\n");
        }
    }
    String::from_utf8_lossy(&bytes).into_owned()
}

#[test]
fn mutated_skies_never_panic_and_every_error_is_located() {
    let corpus = corpus();
    let docs: Vec<toml::Value> = corpus.iter().map(|(_, text, _)| toml::from_str(text).unwrap()).collect();
    let cases: u32 = std::env::var("SKYTUNE_FUZZ_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(3000);
    let mut runner = TestRunner::new(Config { cases, failure_persistence: None, ..Config::default() });
    let strategy = (0..corpus.len(), proptest::collection::vec((any::<u8>(), any::<u64>()), 1..6), proptest::option::of((any::<u8>(), any::<u64>())));
    let (mut accepted, mut rejected) = (0u64, 0u64);
    let counts = std::cell::RefCell::new((0u64, 0u64));
    let result = runner.run(&strategy, |(which, mutations, raw)| {
        let mut doc = docs[which].clone();
        for (op, seed) in &mutations {
            mutate(&mut doc, *op, *seed);
        }
        let mut text = toml::to_string(&doc).unwrap_or_default();
        if let Some((kind, seed)) = raw {
            text = damage(&text, kind, seed);
        }
        let (name, _, images) = &corpus[which];
        let source = MemorySource { name: name.clone(), text, images: images.clone() };
        match load_sky(&source) {
            Ok(_) => counts.borrow_mut().0 += 1,
            Err(errors) => {
                counts.borrow_mut().1 += 1;
                prop_assert!(!errors.0.is_empty(), "a rejection without an error");
                for e in &errors.0 {
                    prop_assert!(e.file == *name && e.line >= 1 && e.column >= 1 && !e.field.is_empty() && !e.message.is_empty(), "unlocated error: {e}");
                }
            }
        }
        Ok(())
    });
    (accepted, rejected) = (accepted + counts.borrow().0, rejected + counts.borrow().1);
    eprintln!("fuzz: {cases} cases, {accepted} accepted, {rejected} rejected with located errors, 0 panics");
    if let Err(e) = result {
        panic!("{e}");
    }
    assert!(rejected > 0 && accepted + rejected == cases as u64, "the mutations reach both outcomes: {accepted} accepted, {rejected} rejected");
}
