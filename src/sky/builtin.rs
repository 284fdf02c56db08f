//! The built-in default sky: the embedded sky file with bitmaps generated in code, so
//! `skytune` runs with no arguments and no files.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use super::bitmap::ColorBitmap;
use super::load::{load_sky, AssetSource};
use super::procedural;
use super::resolved::Sky;

/// The default sky file's text.
pub const DEFAULT_SKY_TOML: &str = include_str!("default_sky.toml");
/// Name shown for the built-in sky in errors and titles.
pub const BUILTIN_NAME: &str = "<built-in default sky>";

/// Asset source serving a sky text and procedurally generated images from memory.
pub struct BuiltinSource {
    text: String,
    images: HashMap<&'static str, ColorBitmap>,
}

impl BuiltinSource {
    /// The default sky with a palette's images.
    pub fn new(palette: &procedural::Palette) -> Self {
        Self { text: DEFAULT_SKY_TOML.to_string(), images: procedural::all_images(palette, 7).into_iter().collect() }
    }
}

impl AssetSource for BuiltinSource {
    fn sky_name(&self) -> String {
        BUILTIN_NAME.to_string()
    }
    fn sky_text(&self) -> Result<String, String> {
        Ok(self.text.clone())
    }
    fn image(&self, rel: &str) -> Result<image::RgbaImage, String> {
        let b = self.images.get(rel).ok_or_else(|| format!("the built-in sky has no image \"{rel}\""))?;
        image::RgbaImage::from_raw(b.width, b.height, b.to_rgba8()).ok_or_else(|| format!("bad built-in image {rel}"))
    }
    fn display(&self, rel: &str) -> String {
        format!("builtin:{rel}")
    }
    fn file_on_disk(&self, _rel: &str) -> Option<PathBuf> {
        None
    }
}

/// The built-in default sky (built once; cloned on request).
pub fn default_sky() -> Sky {
    static SKY: OnceLock<Sky> = OnceLock::new();
    SKY.get_or_init(|| {
        let palette = procedural::preset("default").expect("default preset exists");
        // The embedded sky is part of the binary and covered by tests: failing here is a build bug.
        load_sky(&BuiltinSource::new(palette)).unwrap_or_else(|e| panic!("built-in sky is invalid:\n{e}"))
    })
    .clone()
}

/// Writes the default sky file and a palette's images into `dir` (created if needed).
pub fn write_sky_folder(dir: &Path, palette: &procedural::Palette, seed: u64) -> std::io::Result<PathBuf> {
    std::fs::create_dir_all(dir)?;
    for (name, bitmap) in procedural::all_images(palette, seed) {
        let img = image::RgbaImage::from_raw(bitmap.width, bitmap.height, bitmap.to_rgba8()).ok_or_else(|| std::io::Error::other("image size mismatch"))?;
        crate::support::safe_write::save_png(&img, &dir.join(name)).map_err(std::io::Error::other)?;
    }
    let sky = dir.join("sky.toml");
    crate::support::safe_write::write_atomic(&sky, DEFAULT_SKY_TOML.replace("name = \"Default\"", &format!("name = \"{}\"", palette.name)).as_bytes())
        .map_err(std::io::Error::other)?;
    Ok(sky)
}
