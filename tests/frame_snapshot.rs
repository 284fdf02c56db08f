//! The renderer's pictures and counters, byte for byte: every committed sky and the built-in one,
//! at four (hour, weather) pairs, looking at the horizon and at the zenith, on the display target
//! (the NeL bitmaps), the HDR target (a physical model) and display-referred (the physical model
//! on the display target), with the `software` and the `plain` fill strategies. Each case records a hash of the image's bytes (and of the HDR target's) and
//! the frame's `FrameStats`, in tests/snapshots/frames.txt.
//!
//! A restructuring of the renderer leaves this file as it is: a change of any picture or counter
//! is a change of behaviour, to be made on purpose (`SKYTUNE_ACCEPT=1` rewrites the snapshot).
//! Hashes are exact only on the adapter that recorded them (llvmpipe's code depends on its LLVM
//! and the CPU's vector width); elsewhere the counters are compared and the hashes reported.

mod common;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use skytune::render::plan::strategy::PhysicalTarget;
use skytune::render::{headless, Camera, FillStrategy, Headless, RenderOptions};
use skytune::sky::builtin::default_sky;
use skytune::sky::resolved::{SkyModel, SkyModelKind};
use skytune::sky::{load_sky_file, FrameInput, Sky};

const SIZE: (u32, u32) = (320, 180);
const MOMENTS: [(f32, f32); 4] = [(12.0, 0.0), (18.5, 0.3), (23.0, 0.0), (15.0, 1.0)];

/// 64-bit FNV-1a: stable across platforms and Rust versions, unlike `DefaultHasher`.
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| (h ^ b as u64).wrapping_mul(0x0100_0000_01b3))
}

fn snapshot_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/snapshots/frames.txt")
}

/// Every sky file in skies/ (continents name skies, they are not skies), by name, and the
/// built-in sky.
fn skies() -> Vec<(String, Sky)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("skies");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&root)
        .expect("reading skies/")
        .flat_map(|d| std::fs::read_dir(d.expect("an entry").path()).into_iter().flatten())
        .map(|e| e.expect("an entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml") && p.file_name().is_some_and(|n| n != "continent.toml"))
        .collect();
    files.sort();
    let mut skies: Vec<(String, Sky)> = files
        .iter()
        .map(|p| {
            let name = p.strip_prefix(&root).expect("under skies/").display().to_string();
            (name, load_sky_file(p).unwrap_or_else(|e| panic!("{}: {e:?}", p.display())))
        })
        .collect();
    skies.push(("built-in".into(), default_sky()));
    skies
}

/// The lines of one sky: every case in a fixed order on one renderer (frames carry history:
/// tables, simulations, the glare).
fn sky_lines(h: &mut Headless, name: &str, sky: &Sky) -> Vec<String> {
    h.set_sky(sky).expect("uploaded");
    let views = [("horizon", Camera { yaw_deg: 220.0, pitch_deg: 4.0, ..Camera::default() }), ("zenith", Camera::preset("zenith").expect("a preset"))];
    let mut lines = Vec::new();
    for (strategy_name, strategy) in [("software", FillStrategy::software()), ("plain", FillStrategy::plain())] {
        // The bitmaps on the display target, the `lut` model on the HDR target, and the `lut` model
        // drawn display-referred (the `software` strategy's own way).
        for target in ["display", "hdr", "display-referred"] {
            let options = RenderOptions::default().with_strategy(match target {
                "hdr" => strategy.with_hdr(),
                "display-referred" => FillStrategy { physical_target: PhysicalTarget::DisplayMatched, ..strategy },
                _ => strategy,
            });
            for (view_name, camera) in &views {
                for (hour, weather) in MOMENTS {
                    let mut input = FrameInput::new(hour, weather);
                    input.sky_model = Some(match target {
                        "display" => SkyModel { kind: SkyModelKind::Bitmap, ..sky.model },
                        _ => SkyModel { kind: SkyModelKind::Lut, ..sky.model },
                    });
                    let img = h.render(sky, &input, camera, &options).expect("rendered");
                    let mut line = format!("{name} {hour} {weather} {view_name} {target} {strategy_name} image={:016x}", fnv1a(img.as_raw()));
                    if target == "hdr" {
                        let texture = h.renderer.hdr_texture().expect("an HDR target");
                        let texels = headless::read_texture(&h.ctx, texture, SIZE.0, SIZE.1, 8).expect("read back");
                        write!(line, " hdr={:016x}", fnv1a(&texels)).expect("a string");
                    }
                    write!(line, " {:?}", h.renderer.stats).expect("a string");
                    lines.push(line);
                }
            }
        }
    }
    lines
}

#[test]
fn every_sky_renders_as_recorded() {
    let mut h = common::headless(SIZE.0, SIZE.1);
    let adapter = h.ctx.adapter_line();
    let mut actual = vec![format!("adapter {adapter}")];
    for (name, sky) in skies() {
        actual.extend(sky_lines(&mut h, &name, &sky));
    }
    let path = snapshot_path();
    if std::env::var("SKYTUNE_ACCEPT").is_ok_and(|v| v == "1") {
        std::fs::create_dir_all(path.parent().expect("a folder")).expect("creating tests/snapshots");
        std::fs::write(&path, actual.join("\n") + "\n").expect("writing the snapshot");
        eprintln!("accepted {}", path.display());
        return;
    }
    let recorded = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}; run with SKYTUNE_ACCEPT=1 to record it", path.display()));
    let recorded: Vec<&str> = recorded.lines().collect();
    let exact = recorded.first() == Some(&actual[0].as_str());
    if !exact {
        eprintln!("{} was recorded on {:?}, this is {adapter:?}: comparing counters only", path.display(), recorded.first());
    }
    // Without the hashes: the case and its counters.
    let strip = |l: &str| l.split(' ').filter(|w| !w.starts_with("image=") && !w.starts_with("hdr=")).collect::<Vec<_>>().join(" ");
    let out = common::output_dir().join("frames.actual.txt");
    std::fs::write(&out, actual.join("\n") + "\n").expect("writing the actual snapshot");
    assert_eq!(recorded.len(), actual.len(), "cases recorded and rendered differ in number; see {}", out.display());
    let differing: Vec<String> =
        recorded[1..].iter().zip(&actual[1..]).filter(|(r, a)| if exact { r != a } else { strip(r) != strip(a) }).map(|(r, a)| format!("recorded {r}\nrendered {a}")).collect();
    assert!(differing.is_empty(), "{} of {} cases differ (all in {}):\n{}", differing.len(), actual.len() - 1, out.display(), differing.join("\n"));
}
