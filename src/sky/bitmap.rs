//! Colour bitmaps sampled as the NeL engine does: x is the time of day (wrapping over midnight),
//! y is the weather (clamped), bilinear in RGBA.

/// RGBA colour with components in 0..1 (display-encoded, like the 2005 pipeline).
pub type Rgba = [f32; 4];

/// An RGBA bitmap held as floats in 0..1.
#[derive(Debug, Clone, PartialEq)]
pub struct ColorBitmap {
    /// Width in texels (time axis).
    pub width: u32,
    /// Height in texels (weather axis, or position along the dome for gradients).
    pub height: u32,
    /// Row-major texels, `width * height` of them.
    pub texels: Vec<Rgba>,
    /// The sky file's name for the file it came from (None for built-in or generated ones): how
    /// an edit in the window finds every slot that shows it.
    pub source: Option<String>,
}

impl ColorBitmap {
    /// Builds a bitmap from 8-bit RGBA rows.
    pub fn from_rgba8(width: u32, height: u32, bytes: &[u8]) -> Self {
        assert_eq!(bytes.len(), (width * height * 4) as usize, "RGBA8 size mismatch");
        let texels = bytes.chunks_exact(4).map(|c| [c[0] as f32 / 255.0, c[1] as f32 / 255.0, c[2] as f32 / 255.0, c[3] as f32 / 255.0]).collect();
        Self { width, height, texels, source: None }
    }

    /// The same bitmap, marked as coming from the file the sky names `key`.
    pub fn with_source(self, key: &str) -> Self {
        Self { source: Some(key.to_string()), ..self }
    }

    /// Builds a bitmap from a function of (x, y) texel indices.
    pub fn from_fn(width: u32, height: u32, f: impl Fn(u32, u32) -> Rgba) -> Self {
        let mut texels = Vec::with_capacity((width * height) as usize);
        for y in 0..height {
            for x in 0..width {
                texels.push(f(x, y));
            }
        }
        Self { width, height, texels, source: None }
    }

    /// Converts to 8-bit RGBA (rounded), for textures and PNG files.
    pub fn to_rgba8(&self) -> Vec<u8> {
        self.texels.iter().flat_map(|t| t.map(|c| (c.clamp(0.0, 1.0) * 255.0).round() as u8)).collect()
    }

    /// The texel at (x, y); indices must be in range.
    pub fn texel(&self, x: u32, y: u32) -> Rgba {
        self.texels[(y * self.width + x) as usize]
    }

    /// Texel columns and blend weight for a time of day: column i sits at hour i * hours / width,
    /// and the last column blends into the first towards midnight.
    fn time_columns(&self, hour: f32, hours_per_day: f32) -> (u32, u32, f32) {
        let day_part = (hour / hours_per_day).rem_euclid(1.0);
        let fx = day_part * self.width as f32;
        let x0 = (fx.floor() as u32).min(self.width - 1);
        let x1 = (x0 + 1) % self.width;
        (x0, x1, (fx - x0 as f32).clamp(0.0, 1.0))
    }

    /// Samples at (time of day, weather) exactly as NeL does: x = hour / hours_per_day * width,
    /// wrapping; y = clamp(weather, 0, 1) * (height - 1); bilinear.
    pub fn sample(&self, hour: f32, hours_per_day: f32, weather: f32) -> Rgba {
        let (x0, x1, tx) = self.time_columns(hour, hours_per_day);
        let fy = weather.clamp(0.0, 1.0) * (self.height - 1) as f32;
        let y0 = (fy.floor() as u32).min(self.height - 1);
        let y1 = (y0 + 1).min(self.height - 1);
        let ty = fy - y0 as f32;
        let top = lerp(self.texel(x0, y0), self.texel(x1, y0), tx);
        let bottom = lerp(self.texel(x0, y1), self.texel(x1, y1), tx);
        lerp(top, bottom, ty)
    }

    /// Column of a gradient bitmap at a time of day: one colour per row, interpolated in x only.
    pub fn column_at(&self, hour: f32, hours_per_day: f32) -> Vec<Rgba> {
        let (x0, x1, tx) = self.time_columns(hour, hours_per_day);
        (0..self.height).map(|y| lerp(self.texel(x0, y), self.texel(x1, y), tx)).collect()
    }

    /// Texel-space position (x, y) that `sample` reads for (hour, weather): for the bitmap inspector.
    pub fn sample_position(&self, hour: f32, hours_per_day: f32, weather: f32) -> (f32, f32) {
        let day_part = (hour / hours_per_day).rem_euclid(1.0);
        (day_part * self.width as f32, weather.clamp(0.0, 1.0) * (self.height - 1) as f32)
    }
}

/// Component-wise linear interpolation.
pub fn lerp(a: Rgba, b: Rgba, t: f32) -> Rgba {
    [0, 1, 2, 3].map(|i| a[i] + (b[i] - a[i]) * t)
}

/// Component-wise product.
pub fn mul(a: Rgba, b: Rgba) -> Rgba {
    [0, 1, 2, 3].map(|i| a[i] * b[i])
}

/// The per-frame gradient as NeL builds it from one bitmap per weather step: weather picks two
/// steps i0 = min(floor(w N), N-1), i1 = min(floor(w N) + 1, N-1) blended by frac(w N); each step is
/// read at the time of day; then a [1, 1, 1] / 3 blur runs along the gradient (edges clamped).
/// The result is the 1xH texture of the dome's gradient stage.
pub fn weather_gradient<B: std::borrow::Borrow<ColorBitmap>>(bitmaps: &[B], hour: f32, hours_per_day: f32, weather: f32) -> Vec<Rgba> {
    assert!(!bitmaps.is_empty(), "weather_gradient needs at least one bitmap");
    let n = bitmaps.len();
    let wn = weather.clamp(0.0, 1.0) * n as f32;
    let i = wn.floor() as usize;
    let (i0, i1, t) = (i.min(n - 1), (i + 1).min(n - 1), wn - wn.floor());
    let a = bitmaps[i0].borrow().column_at(hour, hours_per_day);
    let b = bitmaps[i1].borrow().column_at(hour, hours_per_day);
    let blended: Vec<Rgba> = a.iter().zip(&b).map(|(&a, &b)| lerp(a, b, t)).collect();
    blur3(&blended)
}

/// [1, 1, 1] / 3 box blur with clamped edges.
pub fn blur3(column: &[Rgba]) -> Vec<Rgba> {
    let last = column.len() - 1;
    (0..column.len())
        .map(|y| {
            let (p, c, n) = (column[y.saturating_sub(1)], column[y], column[(y + 1).min(last)]);
            [0, 1, 2, 3].map(|i| (p[i] + c[i] + n[i]) / 3.0)
        })
        .collect()
}
