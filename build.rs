//! Embeds every `shaders/**/*.wgsl` in the binary: adding a pass's shader file (or folder) needs
//! no edit of a shader list.

use std::path::Path;

fn collect(dir: &Path, prefix: &str, out: &mut Vec<(String, String)>) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    let mut entries: Vec<_> = entries.filter_map(Result::ok).map(|e| e.path()).collect();
    entries.sort();
    for path in entries {
        let Some(stem) = path.file_stem().and_then(|s| s.to_str()) else { continue };
        if path.is_dir() {
            collect(&path, &format!("{prefix}{stem}/"), out);
        } else if path.extension().is_some_and(|e| e == "wgsl") {
            out.push((format!("{prefix}{stem}"), path.canonicalize().expect("shader path").display().to_string()));
        }
    }
}

fn main() {
    let dir = Path::new(&std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets it")).join("shaders");
    println!("cargo:rerun-if-changed={}", dir.display());
    let mut files = Vec::new();
    collect(&dir, "", &mut files);
    let mut code = String::from("/// Every shader module, by name (path under shaders/ without .wgsl), and its source.\npub const EMBEDDED: &[(&str, &str)] = &[\n");
    for (name, path) in files {
        code.push_str(&format!("    ({name:?}, include_str!({path:?})),\n"));
    }
    code.push_str("];\n");
    // The commit measurements name (docs that hold figures say which build made them).
    let commit = std::process::Command::new("git")
        .args(["rev-parse", "--short=7", "HEAD"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map_or_else(|| "unknown".to_string(), |o| String::from_utf8_lossy(&o.stdout).trim().to_string());
    println!("cargo:rustc-env=SKYTUNE_COMMIT={commit}");
    println!("cargo:rerun-if-changed=.git/logs/HEAD");
    let out = Path::new(&std::env::var("OUT_DIR").expect("cargo sets it")).join("embedded_shaders.rs");
    std::fs::write(out, code).expect("writing embedded_shaders.rs");
}
