//! GPU-free validation of every WGSL file with naga (each module is prepended with globals.wgsl,
//! exactly as the renderer loads it).

use std::path::{Path, PathBuf};

fn shader_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders")
}

/// Every module under shaders/ by name (`NAME` or `folder/NAME`), except the globals.
fn modules_on_disk(dir: &Path, prefix: &str, out: &mut Vec<(String, PathBuf)>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        let stem = path.file_stem().unwrap().to_string_lossy().to_string();
        if path.is_dir() {
            modules_on_disk(&path, &format!("{prefix}{stem}/"), out);
        } else if path.extension().is_some_and(|e| e == "wgsl") && !(prefix.is_empty() && stem == "globals") {
            out.push((format!("{prefix}{stem}"), path));
        }
    }
}

#[test]
fn every_wgsl_file_validates() {
    let dir = shader_dir();
    let library = skytune::render::ShaderLibrary { dir: Some(dir.clone()) };
    let mut modules = Vec::new();
    modules_on_disk(&dir, "", &mut modules);
    assert!(!modules.is_empty());
    // Files with entry points are validated as the renderer loads them (globals, the modules they
    // require, the file); library files (no entry point, e.g. one that uses bindings its users
    // declare) through every file that requires them, and each must be required by one.
    let is_entry = |path: &Path| std::fs::read_to_string(path).unwrap().lines().any(|l| ["@compute", "@vertex", "@fragment"].iter().any(|a| l.trim_start().starts_with(a)));
    let mut required = std::collections::HashSet::new();
    for (name, path) in &modules {
        if !is_entry(path) {
            continue;
        }
        let source = library.source(name).unwrap();
        for (other, other_path) in &modules {
            if !is_entry(other_path) && source.contains(&std::fs::read_to_string(other_path).unwrap()) {
                required.insert(other.clone());
            }
        }
        let module = naga::front::wgsl::parse_str(&source).unwrap_or_else(|e| panic!("{}: {}", path.display(), e.emit_to_string(&source)));
        naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::default())
            .validate(&module)
            .unwrap_or_else(|e| panic!("{}: {}", path.display(), e.emit_to_string(&source)));
    }
    for (name, path) in &modules {
        assert!(is_entry(path) || required.contains(name), "shaders/{name}.wgsl has no entry point and no shader requires it");
    }
    // Every pass of the renderer has its shader, a file or a folder: a missing one must not pass silently.
    for (name, _) in skytune::render::PASSES {
        assert!(dir.join(format!("{name}.wgsl")).is_file() || dir.join(name).is_dir(), "pass {name} has no shaders/{name}.wgsl nor shaders/{name}/");
    }
}

#[test]
fn embedded_shaders_match_the_files() {
    let lib = skytune::render::ShaderLibrary::embedded();
    let disk = skytune::render::ShaderLibrary { dir: Some(shader_dir()) };
    let mut modules = Vec::new();
    modules_on_disk(&shader_dir(), "", &mut modules);
    let mut on_disk: Vec<String> = modules.into_iter().map(|(n, _)| n).collect();
    let mut embedded: Vec<String> = skytune::render::ShaderLibrary::embedded_modules().map(String::from).collect();
    on_disk.sort();
    embedded.sort();
    assert_eq!(embedded, on_disk, "build.rs embeds every file under shaders/");
    for name in &on_disk {
        assert_eq!(lib.source(name).unwrap(), disk.source(name).unwrap(), "{name}");
    }
}
