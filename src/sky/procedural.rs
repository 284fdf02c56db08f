//! Procedural sky art: gradients, colour bitmaps and textures generated from a palette.
//!
//! The built-in default sky is made entirely from this, and `skytune new-sky` writes the same
//! images to disk as a starting point for artists (the skies in `skies/` were made that way).

use super::bitmap::{ColorBitmap, Rgba};

/// Colours and climate of a continent's sky.
#[derive(Debug, Clone, Copy)]
pub struct Palette {
    /// Preset name.
    pub name: &'static str,
    /// Zenith colour at noon.
    pub day_zenith: [f32; 3],
    /// Horizon colour at noon.
    pub day_horizon: [f32; 3],
    /// Horizon colour at sunrise/sunset.
    pub dusk_horizon: [f32; 3],
    /// Zenith colour at night.
    pub night_zenith: [f32; 3],
    /// Horizon colour at night.
    pub night_horizon: [f32; 3],
    /// Tint of overcast and storm skies.
    pub storm: [f32; 3],
    /// Hour of sunrise.
    pub sunrise: f32,
    /// Hour of sunset.
    pub sunset: f32,
    /// Cloud coverage 0..1 of the clear-weather layer.
    pub clear_clouds: f32,
    /// How much the horizon haze rises (fog band height factor).
    pub haze: f32,
}

/// The preset palettes: `default`, `desert`, `forest`, `lakes`, `jungle`.
pub const PRESETS: [Palette; 5] = [
    Palette {
        name: "default",
        day_zenith: [0.22, 0.42, 0.82],
        day_horizon: [0.70, 0.82, 0.95],
        dusk_horizon: [0.98, 0.55, 0.25],
        night_zenith: [0.01, 0.015, 0.05],
        night_horizon: [0.04, 0.06, 0.12],
        storm: [0.45, 0.47, 0.52],
        sunrise: 6.0,
        sunset: 18.0,
        clear_clouds: 0.25,
        haze: 0.4,
    },
    Palette {
        name: "desert",
        day_zenith: [0.30, 0.50, 0.85],
        day_horizon: [0.93, 0.85, 0.70],
        dusk_horizon: [1.00, 0.45, 0.15],
        night_zenith: [0.015, 0.015, 0.04],
        night_horizon: [0.07, 0.05, 0.06],
        storm: [0.70, 0.55, 0.38],
        sunrise: 5.5,
        sunset: 19.0,
        clear_clouds: 0.05,
        haze: 0.7,
    },
    Palette {
        name: "forest",
        day_zenith: [0.16, 0.36, 0.72],
        day_horizon: [0.62, 0.78, 0.84],
        dusk_horizon: [0.92, 0.50, 0.35],
        night_zenith: [0.008, 0.015, 0.03],
        night_horizon: [0.03, 0.06, 0.07],
        storm: [0.38, 0.43, 0.42],
        sunrise: 6.5,
        sunset: 17.5,
        clear_clouds: 0.35,
        haze: 0.5,
    },
    Palette {
        name: "lakes",
        day_zenith: [0.20, 0.48, 0.80],
        day_horizon: [0.72, 0.88, 0.95],
        dusk_horizon: [0.95, 0.60, 0.55],
        night_zenith: [0.01, 0.02, 0.06],
        night_horizon: [0.05, 0.08, 0.15],
        storm: [0.50, 0.56, 0.62],
        sunrise: 6.0,
        sunset: 18.5,
        clear_clouds: 0.3,
        haze: 0.8,
    },
    Palette {
        name: "jungle",
        day_zenith: [0.18, 0.45, 0.70],
        day_horizon: [0.75, 0.85, 0.78],
        dusk_horizon: [0.95, 0.62, 0.30],
        night_zenith: [0.01, 0.02, 0.03],
        night_horizon: [0.04, 0.07, 0.05],
        storm: [0.36, 0.42, 0.38],
        sunrise: 6.0,
        sunset: 18.0,
        clear_clouds: 0.45,
        haze: 0.9,
    },
];

/// Looks a preset up by name.
pub fn preset(name: &str) -> Option<&'static Palette> {
    PRESETS.iter().find(|p| p.name == name)
}

/// Columns of the colour bitmaps: one per hour.
pub const HOURS: u32 = 24;
/// Rows of the colour bitmaps: weather steps clear, cloudy, storm.
pub const WEATHERS: u32 = 3;
/// Texels along the dome in gradient bitmaps.
pub const GRADIENT_ROWS: u32 = 32;
/// Lowest elevation of the default dome, degrees (gradients span 90 .. this).
pub const DOME_BOTTOM_DEG: f32 = -20.0;

fn mix3(a: [f32; 3], b: [f32; 3], t: f32) -> [f32; 3] {
    [0, 1, 2].map(|i| a[i] + (b[i] - a[i]) * t)
}
fn smoothstep(e0: f32, e1: f32, x: f32) -> f32 {
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}
fn rgba(c: [f32; 3], a: f32) -> Rgba {
    [c[0].clamp(0.0, 1.0), c[1].clamp(0.0, 1.0), c[2].clamp(0.0, 1.0), a.clamp(0.0, 1.0)]
}

impl Palette {
    /// Sun elevation in degrees over the day: 60 at solar noon, 0 at sunrise/sunset, -40 at midnight.
    pub fn sun_elevation(&self, hour: f32) -> f32 {
        let (rise, set) = (self.sunrise, self.sunset);
        let h = hour.rem_euclid(24.0);
        if h >= rise && h <= set {
            60.0 * (std::f32::consts::PI * (h - rise) / (set - rise)).sin()
        } else {
            let night = 24.0 - (set - rise);
            let t = (h - set).rem_euclid(24.0) / night;
            -40.0 * (std::f32::consts::PI * t).sin()
        }
    }

    fn daylight(&self, hour: f32) -> f32 {
        smoothstep(-8.0, 12.0, self.sun_elevation(hour))
    }

    fn dusk(&self, hour: f32) -> f32 {
        let e = self.sun_elevation(hour) - 1.0;
        (-(e / 9.0) * (e / 9.0)).exp()
    }

    /// Sky colour at an elevation (degrees) for an hour and a weather 0..1.
    pub fn sky_color(&self, hour: f32, weather: f32, elevation_deg: f32) -> [f32; 3] {
        let (day, dusk) = (self.daylight(hour), self.dusk(hour));
        let zenith = mix3(self.night_zenith, self.day_zenith, day);
        let mut horizon = mix3(self.night_horizon, self.day_horizon, day);
        horizon = mix3(horizon, self.dusk_horizon, dusk * 0.85);
        let h = (1.0 - elevation_deg.max(0.0) / 90.0).powf(3.5);
        let mut c = mix3(zenith, horizon, h);
        if elevation_deg < 0.0 {
            // Below the horizon: fade into a darker ground haze.
            c = mix3(c, [c[0] * 0.55, c[1] * 0.55, c[2] * 0.55], (-elevation_deg / 20.0).min(1.0));
        }
        let grey = 0.3 * c[0] + 0.59 * c[1] + 0.11 * c[2];
        let overcast = [0, 1, 2].map(|i| self.storm[i] * (0.25 + 0.75 * day) * (0.6 + 0.6 * grey));
        let c = mix3(c, overcast, smoothstep(0.0, 1.0, weather) * 0.85);
        c.map(|x| x * (1.0 - 0.35 * weather))
    }

    /// One gradient bitmap (x: hour, y: position along the dome, zenith first) for a weather.
    pub fn gradient(&self, weather: f32) -> ColorBitmap {
        ColorBitmap::from_fn(HOURS, GRADIENT_ROWS, |x, y| {
            let v = y as f32 / (GRADIENT_ROWS - 1) as f32;
            let elevation = 90.0 - v * (90.0 - DOME_BOTTOM_DEG);
            rgba(self.sky_color(x as f32, weather, elevation), 1.0)
        })
    }

    fn weather_bitmap(&self, f: impl Fn(f32, f32) -> Rgba) -> ColorBitmap {
        ColorBitmap::from_fn(HOURS, WEATHERS, |x, y| f(x as f32, y as f32 / (WEATHERS - 1) as f32))
    }

    /// Every colour bitmap of the palette, by file name.
    pub fn color_bitmaps(&self) -> Vec<(&'static str, ColorBitmap)> {
        let p = *self;
        let clouds_rgb = move |h: f32, w: f32| {
            let (day, dusk) = (p.daylight(h), p.dusk(h));
            let lit = mix3([0.08, 0.09, 0.13], [0.97, 0.97, 0.97], day);
            let lit = mix3(lit, [1.0, 0.62, 0.42], dusk * 0.7);
            lit.map(|c| c * (1.0 - 0.55 * w))
        };
        vec![
            ("fog.png", self.weather_bitmap(|h, w| rgba(self.sky_color(h, w, 2.0), 1.0))),
            (
                "sun_ambient.png",
                self.weather_bitmap(|h, w| {
                    let c = mix3([0.05, 0.06, 0.12], [0.45, 0.48, 0.55], self.daylight(h));
                    rgba(c.map(|x| x * (1.0 - 0.3 * w)), 1.0)
                }),
            ),
            (
                "sun_diffuse.png",
                self.weather_bitmap(|h, w| {
                    let c = mix3([0.0, 0.0, 0.0], [1.0, 0.96, 0.88], self.daylight(h));
                    let c = mix3(c, [1.0, 0.55, 0.3], self.dusk(h) * 0.6);
                    rgba(c.map(|x| x * (1.0 - 0.7 * w)), 1.0)
                }),
            ),
            // Alpha 0 in daylight: the ref colour hides the stars object and saves its fill.
            (
                "star_visibility.png",
                self.weather_bitmap(|h, w| {
                    let a = (1.0 - smoothstep(-14.0, -2.0, self.sun_elevation(h))) * (1.0 - w).powi(2);
                    let a = if a < 0.02 { 0.0 } else { a };
                    // Premultiplied: stages multiply by the constant's rgb, ref_color reads its alpha.
                    rgba([a, a, a], a)
                }),
            ),
            (
                "halo_visibility.png",
                self.weather_bitmap(|h, w| {
                    let e = self.sun_elevation(h);
                    let a = smoothstep(-6.0, 2.0, e) * (1.0 - w).powf(1.5);
                    rgba(mix3([1.0, 0.95, 0.8], [1.0, 0.6, 0.3], self.dusk(h)).map(|c| c * a), a)
                }),
            ),
            (
                "sun_color.png",
                self.weather_bitmap(|h, w| {
                    let a = smoothstep(-4.0, 0.5, self.sun_elevation(h)) * (1.0 - 0.85 * w);
                    rgba(mix3([1.0, 0.98, 0.9], [1.0, 0.55, 0.25], self.dusk(h)), if a < 0.01 { 0.0 } else { a })
                }),
            ),
            (
                "moon_color.png",
                self.weather_bitmap(|h, w| {
                    let a = (1.0 - 0.6 * self.daylight(h)) * (1.0 - 0.9 * w);
                    rgba([0.95, 0.95, 1.0], a)
                }),
            ),
            (
                "glare_color.png",
                self.weather_bitmap(|h, w| {
                    let a = smoothstep(-2.0, 4.0, self.sun_elevation(h)) * (1.0 - w).powi(2);
                    rgba(mix3([1.0, 0.95, 0.85], [1.0, 0.6, 0.35], self.dusk(h)), a)
                }),
            ),
            // Cloud layers: rgb = lit colour, alpha = how much this weather shows the layer.
            ("clouds_clear.png", self.weather_bitmap(move |h, w| rgba(clouds_rgb(h, w), p.clear_clouds * (1.0 - smoothstep(0.3, 0.7, w)) + 0.15 * (1.0 - w)))),
            (
                "clouds_cloudy.png",
                self.weather_bitmap(move |h, w| {
                    let a = smoothstep(0.15, 0.5, w) * (1.0 - 0.5 * smoothstep(0.7, 1.0, w));
                    rgba(clouds_rgb(h, w), if a < 0.01 { 0.0 } else { a })
                }),
            ),
            (
                "clouds_storm.png",
                self.weather_bitmap(move |h, w| {
                    let a = smoothstep(0.55, 0.95, w);
                    rgba(clouds_rgb(h, w).map(|c| c * 0.7), if a < 0.01 { 0.0 } else { a })
                }),
            ),
            // Particle emitters: on (not black) when they should give birth.
            (
                "shooting_stars.png",
                self.weather_bitmap(|h, w| {
                    let a = (1.0 - smoothstep(-14.0, -4.0, self.sun_elevation(h))) * (1.0 - smoothstep(0.2, 0.5, w));
                    let a = if a < 0.05 { 0.0 } else { a };
                    rgba([a, a, a], 1.0)
                }),
            ),
            (
                "rain.png",
                self.weather_bitmap(|h, w| {
                    let a = smoothstep(0.6, 0.8, w);
                    let light = 0.35 + 0.65 * self.daylight(h);
                    rgba([0.75 * a * light, 0.8 * a * light, 0.9 * a * light], 1.0)
                }),
            ),
            (
                "lightning.png",
                self.weather_bitmap(|_, w| {
                    let a = smoothstep(0.85, 0.95, w);
                    rgba([a, a, a], 1.0)
                }),
            ),
            (
                "eruptions.png",
                self.weather_bitmap(|h, w| {
                    let a = smoothstep(-2.0, 4.0, self.sun_elevation(h)) * (1.0 - w);
                    let a = if a < 0.05 { 0.0 } else { a };
                    rgba([a, 0.75 * a, 0.45 * a], 1.0)
                }),
            ),
            // Red/green 0.5 = no offset; lower green lifts the fog band (denser haze in bad weather).
            (
                "fog_height.png",
                self.weather_bitmap(|h, w| {
                    let dawn = self.dusk(h);
                    let lift = (self.haze * 0.35 + 0.4 * w + 0.1 * dawn).min(0.49);
                    [0.5, 0.5 - lift, 0.5, 1.0]
                }),
            ),
        ]
    }
}

/// Small deterministic generator (SplitMix64) so procedural art is identical everywhere.
#[derive(Debug, Clone)]
pub struct SplitMix(u64);

impl SplitMix {
    /// A generator from a seed.
    pub fn new(seed: u64) -> Self {
        SplitMix(seed ^ 0x9E37_79B9_7F4A_7C15)
    }
    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// Tileable value noise with `period` lattice cells per side, in [0, 1].
fn value_noise(x: f32, y: f32, period: u32, seed: u64) -> f32 {
    let hash = |ix: i64, iy: i64| {
        let (ix, iy) = (ix.rem_euclid(period as i64) as u64, iy.rem_euclid(period as i64) as u64);
        SplitMix::new(seed ^ (ix * 73_856_093) ^ (iy * 19_349_663)).next_f32()
    };
    let (x0, y0) = (x.floor(), y.floor());
    let (tx, ty) = (x - x0, y - y0);
    let (sx, sy) = (tx * tx * (3.0 - 2.0 * tx), ty * ty * (3.0 - 2.0 * ty));
    let (ix, iy) = (x0 as i64, y0 as i64);
    let a = hash(ix, iy) + (hash(ix + 1, iy) - hash(ix, iy)) * sx;
    let b = hash(ix, iy + 1) + (hash(ix + 1, iy + 1) - hash(ix, iy + 1)) * sx;
    a + (b - a) * sy
}

/// Tileable fractal noise over a `size`-texel square, in [0, 1].
fn fbm(u: f32, v: f32, base_period: u32, octaves: u32, seed: u64) -> f32 {
    let (mut sum, mut amp, mut norm, mut period) = (0.0, 0.5, 0.0, base_period);
    for o in 0..octaves {
        sum += amp * value_noise(u * period as f32, v * period as f32, period, seed + o as u64);
        norm += amp;
        amp *= 0.5;
        period *= 2;
    }
    sum / norm
}

fn image_from_fn(w: u32, h: u32, f: impl Fn(f32, f32) -> Rgba) -> ColorBitmap {
    ColorBitmap::from_fn(w, h, |x, y| f((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32))
}

/// `img` rolled (it repeats) so that its brightest neighbourhood, the mean of red over a square of
/// `radius` texels either side, lies at texel (0, 0): under the cloud-layer mapping the origin of
/// the texture is the zenith, and a star mask should not leave the zenith starless.
fn brightest_at_origin(img: &ColorBitmap, radius: i64) -> ColorBitmap {
    let (w, h) = (i64::from(img.width), i64::from(img.height));
    let at = |x: i64, y: i64| img.texels[(y.rem_euclid(h) * w + x.rem_euclid(w)) as usize];
    let mut best = (f32::NEG_INFINITY, 0, 0);
    for y in 0..h {
        for x in 0..w {
            let sum: f32 = (-radius..=radius).flat_map(|dy| (-radius..=radius).map(move |dx| (dx, dy))).map(|(dx, dy)| at(x + dx, y + dy)[0]).sum();
            if sum > best.0 {
                best = (sum, x, y);
            }
        }
    }
    let (_, bx, by) = best;
    ColorBitmap::from_fn(img.width, img.height, |x, y| at(i64::from(x) + bx, i64::from(y) + by))
}

fn radial(u: f32, v: f32) -> f32 {
    ((u - 0.5).powi(2) + (v - 0.5).powi(2)).sqrt() * 2.0
}

/// Every texture of the procedural sky, by file name.
pub fn textures(seed: u64) -> Vec<(&'static str, ColorBitmap)> {
    vec![
        ("stars.png", {
            let mut rng = SplitMix::new(seed + 1);
            let mut img = ColorBitmap::from_fn(128, 128, |_, _| [0.0, 0.0, 0.0, 1.0]);
            for _ in 0..140 {
                let (x, y) = ((rng.next_f32() * 128.0) as u32, (rng.next_f32() * 128.0) as u32);
                let b = 0.25 + 0.75 * rng.next_f32().powi(3);
                let i = (y * 128 + x) as usize;
                img.texels[i] = [b, b, b * 0.95 + 0.05, 1.0];
            }
            img
        }),
        (
            "star_mask.png",
            brightest_at_origin(
                &image_from_fn(64, 64, |u, v| {
                    let n = smoothstep(0.35, 0.75, fbm(u, v, 4, 4, seed + 2));
                    [n, n, n, 1.0]
                }),
                6,
            ),
        ),
        (
            "halo.png",
            image_from_fn(64, 64, |u, v| {
                let r = radial(u, v);
                let g = ((1.0 - r).max(0.0)).powf(2.2);
                [g, g, g, 1.0]
            }),
        ),
        (
            "sun.png",
            image_from_fn(64, 64, |u, v| {
                let r = radial(u, v);
                let core = 1.0 - smoothstep(0.22, 0.28, r);
                let glow = (1.0 - r).max(0.0).powi(3) * 0.5;
                let g = (core + glow).min(1.0);
                [1.0, 1.0, 0.95, g]
            }),
        ),
        (
            "moon.png",
            image_from_fn(64, 64, |u, v| {
                let r = radial(u, v);
                let n = fbm(u, v, 6, 4, seed + 3);
                let g = 0.55 + 0.45 * smoothstep(0.3, 0.7, n);
                [g, g, g * 1.02, 1.0 - smoothstep(0.94, 1.0, r)]
            }),
        ),
        (
            "planet.png",
            image_from_fn(16, 16, |u, v| {
                let g = (1.0 - radial(u, v)).max(0.0).powi(2);
                [1.0, 0.9, 0.8, g]
            }),
        ),
        (
            "galaxy.png",
            image_from_fn(256, 128, |u, v| {
                let lat = (v - 0.5) * 2.0;
                let band = (-(lat * 6.0).powi(2)).exp();
                let n = fbm(u, v * 0.5, 8, 5, seed + 4);
                let g = band * smoothstep(0.3, 0.8, n) * 0.35;
                [g * 0.9, g * 0.9, g, 1.0]
            }),
        ),
        (
            "clouds_a.png",
            image_from_fn(128, 128, |u, v| {
                let n = smoothstep(0.42, 0.72, fbm(u, v, 4, 5, seed + 5));
                [1.0, 1.0, 1.0, n]
            }),
        ),
        (
            "clouds_b.png",
            image_from_fn(128, 128, |u, v| {
                let n = 0.35 + 0.65 * smoothstep(0.3, 0.7, fbm(u, v, 8, 4, seed + 6));
                [n, n, n, n]
            }),
        ),
        // White-to-black along the band: top transparent, horizon opaque.
        (
            "fog_band.png",
            image_from_fn(4, 32, |_, v| {
                let g = smoothstep(0.05, 0.95, v);
                [g, g, g, g]
            }),
        ),
        (
            "glare_halo.png",
            image_from_fn(64, 64, |u, v| {
                let g = (1.0 - radial(u, v)).max(0.0).powi(4);
                [g, g, g, 1.0]
            }),
        ),
        (
            "flare_ring.png",
            image_from_fn(64, 64, |u, v| {
                let r = radial(u, v);
                let g = (-((r - 0.8) * 9.0).powi(2)).exp() * 0.6;
                [g, g, g, 1.0]
            }),
        ),
        (
            "flare_disc.png",
            image_from_fn(32, 32, |u, v| {
                let g = (1.0 - smoothstep(0.7, 1.0, radial(u, v))) * 0.35;
                [g, g, g, 1.0]
            }),
        ),
    ]
}

/// Every image of a procedural sky (colour bitmaps, gradients, textures), by file name.
pub fn all_images(palette: &Palette, seed: u64) -> Vec<(&'static str, ColorBitmap)> {
    let mut out = palette.color_bitmaps();
    out.push(("gradient_clear.png", palette.gradient(0.0)));
    out.push(("gradient_cloudy.png", palette.gradient(0.5)));
    out.push(("gradient_storm.png", palette.gradient(1.0)));
    out.extend(textures(seed));
    out
}
