//! GPU-free validation of every WGSL file with naga (each pass is prepended with globals.wgsl,
//! exactly as the renderer loads it).

use std::path::Path;

#[test]
fn every_wgsl_file_validates() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders");
    let globals = std::fs::read_to_string(dir.join("globals.wgsl")).unwrap();
    let mut checked = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "wgsl") || path.file_stem().is_some_and(|s| s == "globals") {
            continue;
        }
        let source = format!("{globals}\n{}", std::fs::read_to_string(&path).unwrap());
        let module = naga::front::wgsl::parse_str(&source).unwrap_or_else(|e| panic!("{}: {}", path.display(), e.emit_to_string(&source)));
        naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::default())
            .validate(&module)
            .unwrap_or_else(|e| panic!("{}: {}", path.display(), e.emit_to_string(&source)));
        checked += 1;
    }
    // Every pass of the renderer has a shader: a missing file must not pass silently.
    assert_eq!(checked, skytune::render::shaders::PASSES.len(), "expected one .wgsl per pass");
}

#[test]
fn embedded_shaders_match_the_files() {
    let lib = skytune::render::ShaderLibrary::embedded();
    let disk = skytune::render::ShaderLibrary { dir: Some(Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders")) };
    for pass in skytune::render::shaders::PASSES {
        assert_eq!(lib.source(pass).unwrap(), disk.source(pass).unwrap(), "{pass}");
    }
}
