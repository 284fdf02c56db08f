//! Resource limits of a sky: at each limit the sky loads; one past it gives a clear error naming
//! the file, the line and the field.

mod common;

use std::path::Path;

use skytune::sky::load::{MAX_FALLBACKS, MAX_IMAGE_SIDE, MAX_OBJECTS, MAX_PATHS, MAX_PATH_KEYS, MAX_SKY_FILE_BYTES, MAX_STARS, MAX_TEXTURE_BYTES};
use skytune::sky::{load_sky_file, SkyErrors};

/// The default sky's text with `extra` appended, written over the folder's sky.toml.
fn with_extra(sky: &Path, extra: &str) -> Result<skytune::sky::Sky, SkyErrors> {
    let base = std::fs::read_to_string(sky.with_file_name("sky.base")).unwrap_or_else(|_| {
        let t = std::fs::read_to_string(sky).unwrap();
        std::fs::write(sky.with_file_name("sky.base"), &t).unwrap();
        t
    });
    std::fs::write(sky, format!("{base}\n{extra}")).unwrap();
    load_sky_file(sky)
}

fn object(name: &str, fallbacks: usize, texture: Option<&str>) -> String {
    let stage = |t: Option<&str>| t.map_or(String::new(), |t| format!("[[object.{{}}.stage]]\ntexture = \"{t}\"\n"));
    let mut s = format!(
        "[[object]]\nname = \"{name}\"\npriority = 30\npath = \"sun\"\n[object.standard]\nshape = {{ kind = \"billboard\", size_deg = 1 }}\nblend = \"additive\"\n{}",
        stage(texture).replace("{}", "standard")
    );
    for _ in 0..fallbacks {
        s.push_str("[[object.fallback]]\nshape = { kind = \"billboard\", size_deg = 1 }\nblend = \"additive\"\n");
    }
    s
}

fn expect_error(result: Result<skytune::sky::Sky, SkyErrors>, field: &str, says: &str) -> String {
    let text = match result {
        Ok(_) => panic!("expected an error on {field}"),
        Err(e) => e.to_string(),
    };
    assert!(text.contains("sky.toml:") && text.contains(field) && text.contains(says), "{text}");
    text
}

#[test]
fn objects_fallbacks_paths_and_keys_load_at_their_limits_and_not_past_them() {
    let (_dir, sky) = common::default_sky_folder();
    let base_objects = load_sky_file(&sky).unwrap().objects.len();

    let objects = |n: usize| (0..n).map(|i| object(&format!("extra_{i}"), 0, None)).collect::<String>();
    let at = with_extra(&sky, &objects(MAX_OBJECTS - base_objects)).unwrap();
    assert_eq!(at.objects.len(), MAX_OBJECTS);
    let e = expect_error(with_extra(&sky, &objects(MAX_OBJECTS - base_objects + 1)), &format!("object[{MAX_OBJECTS}]"), "at most 256 objects");
    // The line named is the first object past the limit.
    let text = std::fs::read_to_string(&sky).unwrap();
    let line = text[..text.match_indices("[[object]]").nth(MAX_OBJECTS).unwrap().0].matches('\n').count() + 1;
    assert!(e.contains(&format!("sky.toml:{line}:")), "{e}");

    let r = with_extra(&sky, &object("many_fallbacks", MAX_FALLBACKS, None));
    assert!(r.is_ok(), "{:?}", r.err().map(|e| e.to_string()));
    expect_error(with_extra(&sky, &object("too_many_fallbacks", MAX_FALLBACKS + 1, None)), "fallback", "at most 2 fallback versions");

    let base_paths = load_sky_file(&sky.with_file_name("sky.base")).unwrap().paths.len();
    let paths = |n: usize| (0..n).map(|i| format!("[[path]]\nname = \"p{i}\"\nfollow = \"sun\"\n")).collect::<String>();
    assert!(with_extra(&sky, &paths(MAX_PATHS - base_paths)).is_ok());
    expect_error(with_extra(&sky, &paths(MAX_PATHS - base_paths + 1)), &format!("path[{MAX_PATHS}]"), "at most 64 paths");

    let keys = |n: usize| {
        let list = (0..n).map(|i| format!("{{ hour = {}, azimuth_deg = 0, elevation_deg = 10 }}", i as f32 * 24.0 / n as f32)).collect::<Vec<_>>().join(",\n");
        format!("[[path]]\nname = \"busy\"\nkeys = [\n{list}\n]\n")
    };
    assert!(with_extra(&sky, &keys(MAX_PATH_KEYS)).is_ok());
    expect_error(with_extra(&sky, &keys(MAX_PATH_KEYS + 1)), "keys", "at most 1024 keys");
}

#[test]
fn stars_and_file_size_load_at_their_limits_and_not_past_them() {
    let (_dir, sky) = common::default_sky_folder();
    let text = std::fs::read_to_string(&sky).unwrap();
    let stars = |n: u32| text.replace("count = 6000", &format!("count = {n}"));
    std::fs::write(&sky, stars(MAX_STARS)).unwrap();
    assert_eq!(load_sky_file(&sky).unwrap().stars.unwrap().count, MAX_STARS);
    std::fs::write(&sky, stars(MAX_STARS + 1)).unwrap();
    expect_error(load_sky_file(&sky), "stars.count", "at most 200000 stars");

    // Padded with a comment to exactly the limit, then one byte more.
    let pad = |total: usize| {
        let mut t = text.clone();
        t.push('#');
        while t.len() < total - 1 {
            t.push('x');
        }
        t.push('\n');
        t
    };
    std::fs::write(&sky, pad(MAX_SKY_FILE_BYTES)).unwrap();
    assert!(load_sky_file(&sky).is_ok());
    std::fs::write(&sky, pad(MAX_SKY_FILE_BYTES + 1)).unwrap();
    let e = load_sky_file(&sky).unwrap_err().to_string();
    assert!(e.contains("sky.toml:1:1") && e.contains("<file>") && e.contains("at most 1048576"), "{e}");
}

#[test]
fn texture_memory_and_image_size_load_at_their_limits_and_not_past_them() {
    let (dir, sky) = common::default_sky_folder();
    let base = load_sky_file(&sky).unwrap();
    let used: u64 = base
        .objects
        .iter()
        .flat_map(|o| std::iter::once(&o.standard).chain(&o.fallback))
        .flat_map(|v| &v.stages)
        .filter_map(|s| s.texture.as_ref())
        .map(|t| (t.key.clone(), t.width as u64 * t.height as u64 * 4))
        .collect::<std::collections::HashMap<_, _>>()
        .values()
        .sum();
    // Every other image of the default sky (colour bitmaps, glare sprites) is small: count them
    // by loading with the big textures at the limit minus what the sky itself decodes.
    let side = MAX_IMAGE_SIDE;
    let big = image::RgbaImage::from_pixel(side, side, image::Rgba([40, 40, 60, 255]));
    big.save(dir.path().join("big_0.png")).unwrap();
    let per = side as u64 * side as u64 * 4;
    let fits = (MAX_TEXTURE_BYTES - used) / per;
    assert!(fits >= 6, "the default sky's own images leave room for {fits} big textures");
    for i in 1..=fits {
        std::fs::copy(dir.path().join("big_0.png"), dir.path().join(format!("big_{i}.png"))).unwrap();
    }
    let objects = |n: u64| (0..n).map(|i| object(&format!("big_{i}"), 0, Some(&format!("big_{i}.png")))).collect::<String>();
    // At most the limit (the small colour bitmaps fill part of the remainder): loads.
    let at = with_extra(&sky, &objects(fits - 1));
    assert!(at.is_ok(), "{:?}", at.err().map(|e| e.to_string()));
    drop(at);
    expect_error(with_extra(&sky, &objects(fits + 1)), "stage", "at most 512 MiB");

    // One texel past the largest side.
    image::RgbaImage::new(side + 1, 1).save(dir.path().join("wide.png")).unwrap();
    expect_error(with_extra(&sky, &object("wide", 0, Some("wide.png"))), "stage", "expected sides in 1..=4096");
}
