//! Shared helpers of the integration tests: GPU setup on lavapipe and image comparison.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

use skytune::render::{AdapterChoice, GpuContext, Headless};

/// A headless renderer on the software adapter (lavapipe): the same pixels on every machine.
pub fn headless(width: u32, height: u32) -> Headless {
    let ctx = GpuContext::headless(AdapterChoice::Cpu).expect("lavapipe (mesa-vulkan-drivers) is required: run scripts/setup.sh");
    Headless::new(ctx, width, height).expect("creating the renderer")
}

/// Folder of committed reference images.
pub fn reference_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/reference")
}

/// Git-ignored folder receiving actual and diff images of failed comparisons.
pub fn output_dir() -> PathBuf {
    let d = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/output");
    std::fs::create_dir_all(&d).expect("creating tests/output");
    d
}

/// Per-pixel tolerance: a pixel differs when a channel differs by more than this (of 255).
pub const CHANNEL_TOLERANCE: u8 = 10;
/// Budget: the comparison fails when more than this fraction of pixels differ.
pub const PIXEL_BUDGET: f64 = 0.01;

/// Result of comparing two images (the library's measure, also behind `skytune compare`).
pub type Diff = skytune::compare::PixelDiff;

/// Compares two equally sized images: pixels whose largest channel difference exceeds
/// `tolerance`, and an image marking them.
pub fn diff(a: &image::RgbaImage, b: &image::RgbaImage, tolerance: u8) -> (Diff, image::RgbaImage) {
    skytune::compare::pixel_diff(a, b, tolerance)
}

/// Compares with `tests/reference/NAME.png`. `SKYTUNE_ACCEPT=1` writes the reference instead.
/// On failure, writes NAME.actual.png and NAME.diff.png into tests/output and panics.
pub fn check_reference(name: &str, actual: &image::RgbaImage) {
    let reference = reference_dir().join(format!("{name}.png"));
    if std::env::var("SKYTUNE_ACCEPT").is_ok_and(|v| v == "1") {
        actual.save(&reference).expect("writing the reference");
        eprintln!("accepted new reference {}", reference.display());
        return;
    }
    let expected = match image::open(&reference) {
        Ok(img) => img.to_rgba8(),
        Err(e) => {
            let out = output_dir().join(format!("{name}.actual.png"));
            actual.save(&out).expect("writing the actual image");
            panic!("no reference {} ({e}); actual written to {}; run with SKYTUNE_ACCEPT=1 to accept it", reference.display(), out.display());
        }
    };
    let (d, diff_img) = diff(actual, &expected, CHANNEL_TOLERANCE);
    if d.differing > PIXEL_BUDGET {
        let out = output_dir();
        actual.save(out.join(format!("{name}.actual.png"))).expect("writing actual");
        diff_img.save(out.join(format!("{name}.diff.png"))).expect("writing diff");
        panic!(
            "{name}: {:.2}% of pixels differ by more than {CHANNEL_TOLERANCE}/255 (budget {:.2}%), max {}, mean {:.2}; see tests/output/{name}.actual.png and .diff.png",
            d.differing * 100.0,
            PIXEL_BUDGET * 100.0,
            d.max,
            d.mean
        );
    }
}

/// A fresh folder holding a copy of the default sky (sky.toml + bitmaps).
pub fn default_sky_folder() -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().expect("temp dir");
    let palette = skytune::sky::procedural::preset("default").unwrap();
    let sky = skytune::sky::builtin::write_sky_folder(dir.path(), palette, 7).expect("writing the default sky");
    (dir, sky)
}

/// Copies the checkout's shaders/ (with its folders) into `dst`.
pub fn copy_shaders(dst: &Path) {
    fn copy(src: &Path, dst: &Path) {
        std::fs::create_dir_all(dst).expect("creating the shader folder");
        for e in std::fs::read_dir(src).expect("reading shaders/") {
            let p = e.expect("a folder entry").path();
            let to = dst.join(p.file_name().expect("a file name"));
            if p.is_dir() {
                copy(&p, &to);
            } else {
                std::fs::copy(&p, &to).expect("copying a shader");
            }
        }
    }
    copy(&Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders"), dst);
}
