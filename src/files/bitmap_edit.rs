//! Editing a sky's colour bitmap in place: the operations of the window's curve editor on one PNG
//! (a column's channel or colour, smoothing, shifting or stretching a span of hours, copying and
//! blending weather rows), undo and redo, and saving it back as the same PNG (size, channels and
//! bit depth; untouched pixels keep their values; an atomic write), with the file's changes on
//! disk detected rather than overwritten. GPU- and UI-free: the panel drives it.

use std::path::{Path, PathBuf};

use image::DynamicImage;

use crate::sky::bitmap::{ColorBitmap, Rgba};

/// What can go wrong with a bitmap being edited.
#[derive(Debug, thiserror::Error)]
pub enum EditError {
    /// The file cannot be read or decoded.
    #[error("{path}: {message}")]
    Read {
        /// The file.
        path: String,
        /// Why.
        message: String,
    },
    /// The file cannot be written back as it is.
    #[error("{path}: {message}")]
    Unsupported {
        /// The file.
        path: String,
        /// Why.
        message: String,
    },
    /// The file changed on disk since it was opened or last saved; saving would lose that.
    #[error("{path} changed on disk while it had unsaved edits: keep yours (save anyway) or take the file's")]
    Conflict {
        /// The file.
        path: String,
    },
    /// Writing failed; the old file is intact.
    #[error("{path}: {message}")]
    Write {
        /// The file.
        path: String,
        /// Why.
        message: String,
    },
}

/// One edit. Columns are texels along the time of day (column `x` sits at hour
/// `x * hours_per_day / width`, as sampling reads it), rows the weather steps (or, for gradient
/// bitmaps, positions from the zenith down). Spans of columns run from `from` to `to` inclusive
/// and wrap past midnight when `to < from`.
#[derive(Debug, Clone, PartialEq)]
pub enum Edit {
    /// One channel (0 r, 1 g, 2 b, 3 a) of one texel, 0..=1.
    SetChannel {
        /// Column.
        x: u32,
        /// Row.
        y: u32,
        /// Channel.
        channel: usize,
        /// Value.
        value: f32,
    },
    /// One texel's colour, 0..=1 per channel.
    SetColor {
        /// Column.
        x: u32,
        /// Row.
        y: u32,
        /// RGBA.
        rgba: Rgba,
    },
    /// A [1, 2, 1] / 4 blur along the hours over a span of one row, `passes` times (the span's
    /// ends stay, so it joins what is around it).
    Smooth {
        /// Row.
        y: u32,
        /// First column.
        from: u32,
        /// Last column.
        to: u32,
        /// Repetitions.
        passes: u32,
    },
    /// A span's colours moved `by` columns later (earlier when negative) within the row, wrapping
    /// round the day; what they leave behind takes the colours that were displaced.
    Shift {
        /// Row.
        y: u32,
        /// First column.
        from: u32,
        /// Last column.
        to: u32,
        /// Columns.
        by: i32,
    },
    /// A span resampled (linearly) onto `from ..= new_to`: a time of day stretched or squeezed;
    /// the columns after the old span keep their colours where the new one does not reach.
    Stretch {
        /// Row.
        y: u32,
        /// First column.
        from: u32,
        /// Last column.
        to: u32,
        /// The span's new last column.
        new_to: u32,
    },
    /// Column `x` of row `from_row` copied into the other rows.
    CopyColumn {
        /// Column.
        x: u32,
        /// Source row.
        from_row: u32,
        /// Target rows.
        to_rows: Vec<u32>,
    },
    /// Row `into` becomes `a + (b - a) * t`, every column.
    BlendRows {
        /// First row.
        a: u32,
        /// Second row.
        b: u32,
        /// Blend factor, 0..=1.
        t: f32,
        /// Target row.
        into: u32,
    },
    /// Texels replaced wholesale (a bake of a sky model over some hours), row-major, 0..=1.
    Replace {
        /// (x, y, colour) per texel.
        texels: Vec<(u32, u32, Rgba)>,
    },
}

/// A colour bitmap open for editing.
#[derive(Debug, Clone)]
pub struct BitmapEditor {
    path: PathBuf,
    /// Key of the bitmap in the sky (as its file names it), for live updates.
    key: String,
    /// The file as opened: written back verbatim when the edits are all undone.
    opened_bytes: Vec<u8>,
    opened: DynamicImage,
    /// The file's bytes when last opened, saved or taken from disk: what "unchanged on disk" means.
    baseline: Vec<u8>,
    /// The image as it was saved or opened (unsaved edits = current differs from it).
    saved: DynamicImage,
    current: DynamicImage,
    undo: Vec<DynamicImage>,
    redo: Vec<DynamicImage>,
    /// Counts changes to the current image (edits, undo, redo, taking the file's version).
    revision: u64,
}

/// Colour type 3 in a PNG's header: indexed colour.
const PNG_PALETTE: u8 = 3;

fn decode(bytes: &[u8], path: &Path) -> Result<DynamicImage, EditError> {
    let read = |message: String| EditError::Read { path: path.display().to_string(), message };
    if bytes.len() < 26 || &bytes[..8] != b"\x89PNG\r\n\x1a\n" {
        return Err(read("not a PNG file".into()));
    }
    if bytes[25] == PNG_PALETTE {
        return Err(EditError::Unsupported {
            path: path.display().to_string(),
            message: "an indexed-colour PNG cannot be written back as it is: save it as RGB or RGBA to edit it here".into(),
        });
    }
    image::load_from_memory_with_format(bytes, image::ImageFormat::Png).map_err(|e| read(e.to_string()))
}

impl BitmapEditor {
    /// Opens `path`; `key` is how the sky file names it.
    pub fn open(path: &Path, key: &str) -> Result<Self, EditError> {
        let bytes = std::fs::read(path).map_err(|e| EditError::Read { path: path.display().to_string(), message: e.to_string() })?;
        let image = decode(&bytes, path)?;
        Ok(Self {
            path: path.to_path_buf(),
            key: key.to_string(),
            opened_bytes: bytes.clone(),
            opened: image.clone(),
            baseline: bytes,
            saved: image.clone(),
            current: image,
            undo: Vec::new(),
            redo: Vec::new(),
            revision: 0,
        })
    }

    /// The file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The sky's name for it.
    pub fn key(&self) -> &str {
        &self.key
    }

    /// Columns (hours) and rows (weather steps).
    pub fn size(&self) -> (u32, u32) {
        (self.current.width(), self.current.height())
    }

    /// The texel at (x, y), 0..=1 per channel (alpha 1 for files without it).
    pub fn texel(&self, x: u32, y: u32) -> Rgba {
        texel_of(&self.current, x, y)
    }

    /// The hour column `x` stands for.
    pub fn hour_of_column(&self, x: u32, hours_per_day: f32) -> f32 {
        x as f32 * hours_per_day / self.current.width() as f32
    }

    /// The column nearest to `hour` (wrapping).
    pub fn column_of_hour(&self, hour: f32, hours_per_day: f32) -> u32 {
        let w = self.current.width();
        (((hour / hours_per_day).rem_euclid(1.0) * w as f32).round() as u32) % w
    }

    /// Changes so far to what the editor holds (a new value means the sky must show it anew).
    pub fn revision(&self) -> u64 {
        self.revision
    }

    /// Whether there are edits to undo, or undone edits to redo.
    pub fn can_undo_redo(&self) -> (bool, bool) {
        (!self.undo.is_empty(), !self.redo.is_empty())
    }

    /// Whether there are edits not saved.
    pub fn is_dirty(&self) -> bool {
        self.current != self.saved
    }

    /// Applies `edit` as one undo step, or, with `merge`, into the last one (the moves of one
    /// drag). Out-of-range columns or rows are ignored.
    pub fn apply(&mut self, edit: &Edit, merge: bool) {
        let before = self.current.clone();
        let mut texels: Vec<Rgba> = self.all_texels();
        let (w, h) = self.size();
        let at = |x: u32, y: u32| (y * w + x) as usize;
        let span = |from: u32, to: u32| -> Vec<u32> {
            if from >= w || to >= w {
                return Vec::new();
            }
            let len = if to >= from { to - from + 1 } else { w - from + to + 1 };
            (0..len).map(|k| (from + k) % w).collect()
        };
        match edit {
            Edit::SetChannel { x, y, channel, value } if *x < w && *y < h && *channel < 4 => texels[at(*x, *y)][*channel] = value.clamp(0.0, 1.0),
            Edit::SetColor { x, y, rgba } if *x < w && *y < h => texels[at(*x, *y)] = rgba.map(|c| c.clamp(0.0, 1.0)),
            Edit::Smooth { y, from, to, passes } if *y < h => {
                let cols = span(*from, *to);
                for _ in 0..*passes {
                    let row: Vec<Rgba> = cols.iter().map(|&x| texels[at(x, *y)]).collect();
                    for k in 1..cols.len().saturating_sub(1) {
                        texels[at(cols[k], *y)] = std::array::from_fn(|c| 0.25 * row[k - 1][c] + 0.5 * row[k][c] + 0.25 * row[k + 1][c]);
                    }
                }
            }
            Edit::Shift { y, from, to, by } if *y < h => {
                let cols = span(*from, *to);
                let n = cols.len() as i64;
                if n > 0 {
                    // The span and the stretch it moves over, rotated together.
                    let reach = (n + by.unsigned_abs() as i64).min(w as i64);
                    let start = if *by >= 0 { *from as i64 } else { *from as i64 + *by as i64 };
                    let window: Vec<u32> = (0..reach).map(|k| (start + k).rem_euclid(w as i64) as u32).collect();
                    let values: Vec<Rgba> = window.iter().map(|&x| texels[at(x, *y)]).collect();
                    let shift = (*by as i64).rem_euclid(reach) as usize;
                    for (k, &x) in window.iter().enumerate() {
                        texels[at(x, *y)] = values[(k + values.len() - shift) % values.len()];
                    }
                }
            }
            Edit::Stretch { y, from, to, new_to } if *y < h => {
                let (old, new) = (span(*from, *to), span(*from, *new_to));
                if old.len() > 1 && new.len() > 1 {
                    let values: Vec<Rgba> = old.iter().map(|&x| texels[at(x, *y)]).collect();
                    for (k, &x) in new.iter().enumerate() {
                        let f = k as f32 * (values.len() - 1) as f32 / (new.len() - 1) as f32;
                        let (i, t) = (f.floor() as usize, f.fract());
                        let j = (i + 1).min(values.len() - 1);
                        texels[at(x, *y)] = crate::sky::bitmap::lerp(values[i], values[j], t);
                    }
                }
            }
            Edit::CopyColumn { x, from_row, to_rows } if *x < w && *from_row < h => {
                let v = texels[at(*x, *from_row)];
                for &r in to_rows.iter().filter(|r| **r < h) {
                    texels[at(*x, r)] = v;
                }
            }
            Edit::BlendRows { a, b, t, into } if *a < h && *b < h && *into < h => {
                for x in 0..w {
                    texels[at(x, *into)] = crate::sky::bitmap::lerp(texels[at(x, *a)], texels[at(x, *b)], t.clamp(0.0, 1.0));
                }
            }
            Edit::Replace { texels: new } => {
                for (x, y, c) in new.iter().filter(|(x, y, _)| *x < w && *y < h) {
                    texels[at(*x, *y)] = c.map(|v| v.clamp(0.0, 1.0));
                }
            }
            _ => return,
        }
        self.write_texels(&texels);
        if self.current == before {
            return;
        }
        if !merge || self.undo.is_empty() {
            self.undo.push(before);
        }
        self.redo.clear();
        self.revision += 1;
    }

    fn all_texels(&self) -> Vec<Rgba> {
        let (w, h) = self.size();
        (0..h).flat_map(|y| (0..w).map(move |x| (x, y))).map(|(x, y)| self.texel(x, y)).collect()
    }

    /// Stores `texels` in the file's own type, changing only texels whose value changed: a
    /// texel the edit left alone keeps its stored value exactly (no round trip through floats).
    fn write_texels(&mut self, texels: &[Rgba]) {
        let (w, _) = self.size();
        let old: Vec<Rgba> = self.all_texels();
        for (i, (new, was)) in texels.iter().zip(&old).enumerate() {
            if new != was {
                set_texel(&mut self.current, i as u32 % w, i as u32 / w, *new);
            }
        }
    }

    /// Takes the last edit back; false when there is none.
    pub fn undo(&mut self) -> bool {
        match self.undo.pop() {
            Some(prev) => {
                self.redo.push(std::mem::replace(&mut self.current, prev));
                self.revision += 1;
                true
            }
            None => false,
        }
    }

    /// Does again what `undo` took back; false when there is nothing.
    pub fn redo(&mut self) -> bool {
        match self.redo.pop() {
            Some(next) => {
                self.undo.push(std::mem::replace(&mut self.current, next));
                self.revision += 1;
                true
            }
            None => false,
        }
    }

    /// The bitmap as the sky samples it (8 bits per channel, as the loader reads files).
    pub fn color_bitmap(&self) -> ColorBitmap {
        let rgba = self.current.to_rgba8();
        ColorBitmap::from_rgba8(rgba.width(), rgba.height(), rgba.as_raw()).with_source(&self.key)
    }

    /// Whether the file on disk is no longer what was opened or last saved.
    pub fn changed_on_disk(&self) -> bool {
        std::fs::read(&self.path).map_or(true, |b| b != self.baseline)
    }

    /// The file's current version on disk (for a conflict: to compare, or to take).
    pub fn disk_version(&self) -> Result<DynamicImage, EditError> {
        let bytes = std::fs::read(&self.path).map_err(|e| EditError::Read { path: self.path.display().to_string(), message: e.to_string() })?;
        decode(&bytes, &self.path)
    }

    /// Takes the file's version on disk as the current image, as an edit (undo brings the
    /// unsaved edits back).
    pub fn take_disk_version(&mut self) -> Result<(), EditError> {
        let bytes = std::fs::read(&self.path).map_err(|e| EditError::Read { path: self.path.display().to_string(), message: e.to_string() })?;
        let image = decode(&bytes, &self.path)?;
        self.undo.push(std::mem::replace(&mut self.current, image.clone()));
        self.redo.clear();
        self.revision += 1;
        self.baseline = bytes;
        self.saved = image;
        Ok(())
    }

    /// Writes the bitmap back (same size, channels and bit depth; atomically). Refuses when the
    /// file changed on disk since it was opened or saved, unless `overwrite` (the artist chose
    /// their version). With every edit undone, the file as opened is written back byte for byte.
    pub fn save(&mut self, overwrite: bool) -> Result<(), EditError> {
        let path = self.path.display().to_string();
        if !overwrite && self.changed_on_disk() {
            return Err(EditError::Conflict { path });
        }
        let bytes = if self.current == self.opened {
            self.opened_bytes.clone()
        } else {
            let mut out = std::io::Cursor::new(Vec::new());
            self.current.write_to(&mut out, image::ImageFormat::Png).map_err(|e| EditError::Write { path: path.clone(), message: e.to_string() })?;
            out.into_inner()
        };
        crate::support::safe_write::write_atomic(&self.path, &bytes).map_err(|e| EditError::Write { path, message: e.to_string() })?;
        self.baseline = bytes;
        self.saved = self.current.clone();
        Ok(())
    }
}

fn texel_of(img: &DynamicImage, x: u32, y: u32) -> Rgba {
    match img {
        DynamicImage::ImageLuma16(_) | DynamicImage::ImageLumaA16(_) | DynamicImage::ImageRgb16(_) | DynamicImage::ImageRgba16(_) => {
            let p = image::GenericImageView::get_pixel(&img.to_rgba16(), x, y).0;
            p.map(|c| c as f32 / 65535.0)
        }
        _ => {
            use image::GenericImageView as _;
            img.get_pixel(x, y).0.map(|c| c as f32 / 255.0)
        }
    }
}

/// Writes one texel in the image's own type (grey files take the mean of r, g, b).
fn set_texel(img: &mut DynamicImage, x: u32, y: u32, c: Rgba) {
    let q8 = |v: f32| (v.clamp(0.0, 1.0) * 255.0).round() as u8;
    let q16 = |v: f32| (v.clamp(0.0, 1.0) * 65535.0).round() as u16;
    let grey = (c[0] + c[1] + c[2]) / 3.0;
    match img {
        DynamicImage::ImageLuma8(i) => i.put_pixel(x, y, image::Luma([q8(grey)])),
        DynamicImage::ImageLumaA8(i) => i.put_pixel(x, y, image::LumaA([q8(grey), q8(c[3])])),
        DynamicImage::ImageRgb8(i) => i.put_pixel(x, y, image::Rgb([q8(c[0]), q8(c[1]), q8(c[2])])),
        DynamicImage::ImageRgba8(i) => i.put_pixel(x, y, image::Rgba(c.map(q8))),
        DynamicImage::ImageLuma16(i) => i.put_pixel(x, y, image::Luma([q16(grey)])),
        DynamicImage::ImageLumaA16(i) => i.put_pixel(x, y, image::LumaA([q16(grey), q16(c[3])])),
        DynamicImage::ImageRgb16(i) => i.put_pixel(x, y, image::Rgb([q16(c[0]), q16(c[1]), q16(c[2])])),
        DynamicImage::ImageRgba16(i) => i.put_pixel(x, y, image::Rgba(c.map(q16))),
        other => {
            let mut rgba = other.to_rgba8();
            rgba.put_pixel(x, y, image::Rgba(c.map(q8)));
            *other = DynamicImage::ImageRgba8(rgba);
        }
    }
}
