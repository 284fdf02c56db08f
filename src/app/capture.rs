//! Screenshots and contact sheets: file names and the sheet layout. The pixels come from
//! [`crate::render::Headless`], the same still path as `skytune render`
//! ([`super::window::WindowGpu::capture`]).

use std::path::{Path, PathBuf};

use anyhow::Context as _;

/// File name for a screenshot: sky name, time and weather.
pub fn screenshot_name(sky: &str, hour: f32, weather: f32) -> String {
    let clean: String = sky.chars().map(|c| if c.is_ascii_alphanumeric() { c.to_ascii_lowercase() } else { '_' }).collect();
    format!("{clean}_{hour:05.2}h_w{weather:.2}.png")
}

/// A free path in `dir` for `name` (adds -2, -3, ... when taken).
pub fn free_path(dir: &Path, name: &str) -> anyhow::Result<PathBuf> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let (stem, ext) = name.rsplit_once('.').unwrap_or((name, "png"));
    let mut path = dir.join(name);
    let mut n = 2;
    while path.exists() {
        path = dir.join(format!("{stem}-{n}.{ext}"));
        n += 1;
    }
    Ok(path)
}

/// A contact sheet being rendered, one cell per frame so the window stays responsive.
pub struct ContactSheet {
    /// Hours of the columns.
    pub hours: Vec<f32>,
    /// Weathers of the rows.
    pub weathers: Vec<f32>,
    /// Cell size, pixels.
    pub cell: (u32, u32),
    /// Cells done.
    pub done: usize,
    /// The sheet.
    pub image: image::RgbaImage,
    /// Where it will be written.
    pub path: PathBuf,
}

impl ContactSheet {
    /// A sheet of `columns` hours over the day by `rows` weathers.
    pub fn new(hours_per_day: f32, columns: u32, rows: u32, cell: (u32, u32), path: PathBuf) -> Self {
        let hours = (0..columns).map(|c| hours_per_day * c as f32 / columns as f32).collect();
        let weathers = (0..rows).map(|r| if rows == 1 { 0.0 } else { r as f32 / (rows - 1) as f32 }).collect();
        Self { hours, weathers, cell, done: 0, image: image::RgbaImage::new(cell.0 * columns, cell.1 * rows), path }
    }

    /// Total cells.
    pub fn total(&self) -> usize {
        self.hours.len() * self.weathers.len()
    }

    /// The (hour, weather) of the next cell and its grid position.
    pub fn next_cell(&self) -> Option<(f32, f32, u32, u32)> {
        (self.done < self.total()).then(|| {
            let (c, r) = (self.done % self.hours.len(), self.done / self.hours.len());
            (self.hours[c], self.weathers[r], c as u32, r as u32)
        })
    }

    /// Places a rendered cell.
    pub fn put(&mut self, column: u32, row: u32, cell: &image::RgbaImage) {
        image::imageops::replace(&mut self.image, cell, (column * self.cell.0) as i64, (row * self.cell.1) as i64);
        self.done += 1;
    }
}
