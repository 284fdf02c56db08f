//! `skytune bake`: NeL gradient and halo bitmaps (24 hours x N weather steps) from a physical
//! model, written as a complete sky folder, so an artist can start a continent from physics and
//! the runtime pays only the bitmap cost (docs/sky-models.md).
//!
//! Hours follow the source sky's sun path; weather step i takes the atmosphere of the sky's
//! weather table at i / (N - 1), or, without a table, the sky's atmosphere with its aerosols times
//! 1 + 3 i / (N - 1) (clear to hazy). Colours are display values at the benchmark's fixed exposure
//! ([`dome::display`]), sRGB-encoded as NeL bitmaps are.

use std::fmt::Write as _;
use std::path::Path;

use crate::atmosphere::dome;
use crate::atmosphere::reference::Case;
use crate::atmosphere::represent::{self, Baked, BAKED_HOURS};
use crate::atmosphere::{Atmosphere, Rgb};
use crate::measure::model_points::{Evaluator, Fit, Method, Prepared};
use crate::sky::Sky;

/// The atmosphere of weather step `i` of `n`.
pub fn weather_atmosphere(sky: &Sky, i: usize, n: usize) -> Atmosphere {
    let w = if n > 1 { i as f64 / (n - 1) as f64 } else { 0.0 };
    if !sky.atmosphere_by_weather.is_empty() {
        return Atmosphere::at_weather(&sky.atmosphere_by_weather, w).unwrap_or(sky.atmosphere);
    }
    let k = 1.0 + 3.0 * w;
    Atmosphere {
        mie_scattering_per_km: sky.atmosphere.mie_scattering_per_km.map(|b| b * k),
        mie_extinction_per_km: sky.atmosphere.mie_extinction_per_km.map(|b| b * k),
        ..sky.atmosphere
    }
}

/// The sun's elevation at each baked hour (column i at hour i x hours_per_day / 24), degrees.
pub fn sun_elevations(sky: &Sky) -> [f64; BAKED_HOURS] {
    std::array::from_fn(|i| sky.path_at(sky.sun_path, i as f32 * sky.hours_per_day / BAKED_HOURS as f32).0.y.clamp(-1.0, 1.0).asin().to_degrees() as f64)
}

/// Bakes `method` (with the sky's turbidity for analytic models) for `sky`.
pub fn bake(ev: &Evaluator<'_>, sky: &Sky, method: Method, rows: usize, weathers: usize) -> anyhow::Result<Baked> {
    anyhow::ensure!((2..=1024).contains(&rows), "--rows: expected 2..=1024, found {rows}");
    anyhow::ensure!((1..=16).contains(&weathers), "--weathers: expected 1..=16, found {weathers}");
    let atmospheres: Vec<Atmosphere> = (0..weathers).map(|i| weather_atmosphere(sky, i, weathers)).collect();
    let prepared: Vec<Prepared> = atmospheres
        .iter()
        .map(|atm| match method {
            Method::Preetham | Method::Hosek => {
                Ok(Prepared::Analytic(method, Fit { turbidity: sky.model.settings.analytic.turbidity as f64, scale: 1.0, units: sky.model.settings.analytic.units }))
            }
            m => ev.prepare(&m, atm, &[]),
        })
        .collect::<anyhow::Result<_>>()?;
    let mut sources: Vec<Box<represent::Source<'_>>> = prepared
        .iter()
        .zip(&atmospheres)
        .map(|(p, atm)| Box::new(move |sun: f64, cases: &[Case]| -> anyhow::Result<Vec<Rgb>> { ev.radiance(p, atm, sun, cases) }) as Box<represent::Source<'_>>)
        .collect();
    let mut refs: Vec<&mut represent::Source<'_>> = sources.iter_mut().map(|b| b.as_mut()).collect();
    Baked::build(rows, &sun_elevations(sky), &mut refs)
}

/// A sky bitmap a bake can fill, and what its texels mean.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BakeTarget {
    /// Weather step `step` of a dome's `weather_gradients`: rows from the zenith down.
    Gradient {
        /// Which step.
        step: usize,
        /// Of how many.
        steps: usize,
    },
    /// `fog_color`: the horizon row.
    Fog,
    /// `sun_ambient`: the mean of the rows above the horizon.
    Ambient,
    /// `sun_diffuse`: the sun-side glow.
    Diffuse,
}

/// The scene's light at weather step `w` and baked hour `h`, approximated from the sky as
/// `skytune bake` writes it: fog the horizon row, ambient the mean of the rows above the horizon,
/// diffuse the sun-side glow. sRGB-encoded.
pub fn scene_colour(baked: &Baked, target: BakeTarget, w: usize, h: usize) -> [u8; 3] {
    let rows = baked.rows;
    let horizon_row = ((90.0 / (90.0 - represent::BAKED_BOTTOM_DEG)) * rows as f64).floor().min(rows as f64 - 1.0) as usize;
    match target {
        BakeTarget::Fog => baked.gradient[w][horizon_row * BAKED_HOURS + h],
        BakeTarget::Ambient => {
            let n = horizon_row.max(1);
            std::array::from_fn(|c| ((0..n).map(|r| baked.gradient[w][r * BAKED_HOURS + h][c] as u32).sum::<u32>() / n as u32) as u8)
        }
        BakeTarget::Diffuse => baked.halo_color[w][h],
        BakeTarget::Gradient { step, .. } => baked.gradient[step][h],
    }
}

/// The rows and weather steps to bake for `target` in a bitmap `height` rows tall.
pub fn bake_shape(target: BakeTarget, height: u32) -> (usize, usize) {
    match target {
        BakeTarget::Gradient { steps, .. } => (height.max(2) as usize, steps.max(1)),
        _ => (32, height.max(1) as usize),
    }
}

/// The texels of `columns` of a `width` x `height` bitmap for `target` from `baked` (made with
/// [`bake_shape`]), 0..1 as stored (sRGB); a column between two baked hours blends them.
pub fn bitmap_texels(baked: &Baked, target: BakeTarget, width: u32, height: u32, columns: &[u32]) -> Vec<(u32, u32, [f32; 4])> {
    let mut out = Vec::new();
    for &x in columns.iter().filter(|x| **x < width) {
        let f = x as f64 * BAKED_HOURS as f64 / width as f64;
        let (h0, t) = (f.floor() as usize % BAKED_HOURS, f.fract() as f32);
        let h1 = (h0 + 1) % BAKED_HOURS;
        for y in 0..height {
            let at = |h: usize| -> [u8; 3] {
                match target {
                    BakeTarget::Gradient { step, .. } => baked.gradient[step][y as usize * BAKED_HOURS + h],
                    scene => scene_colour(baked, scene, y as usize, h),
                }
            };
            let (a, b) = (at(h0), at(h1));
            let c = |k: usize| (a[k] as f32 * (1.0 - t) + b[k] as f32 * t) / 255.0;
            out.push((x, y, [c(0), c(1), c(2), 1.0]));
        }
    }
    out
}

/// Which [`BakeTarget`] the sky's bitmap named `key` is, if a bake can fill it.
pub fn bake_target(sky: &Sky, key: &str) -> Option<BakeTarget> {
    let is = |b: &crate::sky::bitmap::ColorBitmap| b.source.as_deref() == Some(key);
    if is(&sky.fog_color) {
        return Some(BakeTarget::Fog);
    }
    if is(&sky.sun_ambient) {
        return Some(BakeTarget::Ambient);
    }
    if is(&sky.sun_diffuse) {
        return Some(BakeTarget::Diffuse);
    }
    sky.objects
        .iter()
        .flat_map(|o| o.standard.gradients.iter())
        .find_map(|g| g.bitmaps.iter().position(|b| is(b)).map(|step| BakeTarget::Gradient { step, steps: g.bitmaps.len() }))
}

/// The benchmark method that renders `model` (None for the bitmap model and the reference,
/// which is too slow to bake from in the window).
pub fn method_of(model: &crate::sky::resolved::SkyModel) -> Option<Method> {
    use crate::sky::model::SkyModelKind as K;
    match model.kind {
        K::Single => Some(Method::Single(model.settings.single)),
        K::Lut => Some(Method::Lut(model.settings.lut)),
        K::Precomputed => Some(Method::Precomputed(model.settings.precomputed)),
        K::Cells => Some(Method::Cells(model.settings.cell_iterations as usize)),
        K::Preetham => Some(Method::Preetham),
        K::Hosek => Some(Method::Hosek),
        _ => None,
    }
}

fn png(path: &Path, width: u32, height: u32, rgba: Vec<u8>) -> anyhow::Result<()> {
    let image = image::RgbaImage::from_raw(width, height, rgba).ok_or_else(|| anyhow::anyhow!("{}: wrong pixel count", path.display()))?;
    let mut bytes = Vec::new();
    image.write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png)?;
    crate::support::safe_write::write_atomic(path, &bytes)?;
    Ok(())
}

/// A 24 x N colour bitmap (x = hour, y = weather) from `color(weather, hour)`.
fn colour_bitmap(path: &Path, weathers: usize, color: impl Fn(usize, usize) -> [u8; 3]) -> anyhow::Result<()> {
    let mut rgba = Vec::new();
    for w in 0..weathers {
        for h in 0..BAKED_HOURS {
            rgba.extend_from_slice(&color(w, h));
            rgba.push(255);
        }
    }
    png(path, BAKED_HOURS as u32, weathers as u32, rgba)
}

/// Writes `baked` as a sky folder: sky.toml, one gradient per weather step, the halo texture and
/// its colour, and the main scene's fog, ambient and diffuse bitmaps.
pub fn write_folder(dir: &Path, sky: &Sky, baked: &Baked, source: &str) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir)?;
    let weathers = baked.gradient.len();
    let rows = baked.rows;
    for (w, g) in baked.gradient.iter().enumerate() {
        let rgba: Vec<u8> = g.iter().flat_map(|c| [c[0], c[1], c[2], 255]).collect();
        png(&dir.join(format!("gradient_{w}.png")), BAKED_HOURS as u32, rows as u32, rgba)?;
    }
    // The halo: its radial profile around the texture's centre, the texture spanning twice the radius.
    let side = 64u32;
    let profile = &baked.halo_profile;
    let halo: Vec<u8> = (0..side * side)
        .flat_map(|k| {
            let (x, y) = ((k % side) as f64 + 0.5 - side as f64 / 2.0, (k / side) as f64 + 0.5 - side as f64 / 2.0);
            let r = (x * x + y * y).sqrt() / (side as f64 / 2.0);
            let pos = (r * profile.len() as f64 - 0.5).max(0.0);
            let i = (pos.floor() as usize).min(profile.len() - 1);
            let t = pos - pos.floor();
            let v = if r >= 1.0 { 0.0 } else { profile[i] as f64 * (1.0 - t) + profile[(i + 1).min(profile.len() - 1)] as f64 * t };
            let v = v.round() as u8;
            [v, v, v, 255]
        })
        .collect();
    png(&dir.join("halo.png"), side, side, halo)?;
    colour_bitmap(&dir.join("halo_color.png"), weathers, |w, h| baked.halo_color[w][h])?;
    // The scene's light, approximated from the sky: fog = the horizon row, ambient = the mean of
    // the rows above the horizon, diffuse = the sun-side glow.
    colour_bitmap(&dir.join("fog.png"), weathers, |w, h| scene_colour(baked, BakeTarget::Fog, w, h))?;
    colour_bitmap(&dir.join("sun_ambient.png"), weathers, |w, h| scene_colour(baked, BakeTarget::Ambient, w, h))?;
    colour_bitmap(&dir.join("sun_diffuse.png"), weathers, |w, h| scene_colour(baked, BakeTarget::Diffuse, w, h))?;

    let mut toml = String::new();
    let _ = writeln!(toml, "# Baked by `skytune bake` from the {source} model of \"{}\": NeL gradient and halo bitmaps,", sky.name);
    let _ = writeln!(toml, "# 24 hours x {weathers} weather step(s), {rows} gradient rows (zenith first, down to {} degrees).", represent::BAKED_BOTTOM_DEG);
    let _ = writeln!(toml, "# Display values at exposure 2^{} (tone curve 1 - exp(-x), sRGB). Edit the bitmaps freely.\n", dome::EXPOSURE_EV);
    let _ = writeln!(toml, "name = {:?}", format!("{} (baked {source})", sky.name));
    let _ = writeln!(toml, "hours_per_day = {}", sky.hours_per_day);
    let names: Vec<String> = (0..weathers).map(|w| format!("{:?}", format!("weather {w}"))).collect();
    let _ = writeln!(toml, "weather_names = [{}]", names.join(", "));
    let _ = writeln!(toml, "fog_color = \"fog.png\"\nsun_ambient = \"sun_ambient.png\"\nsun_diffuse = \"sun_diffuse.png\"\nsun_path = \"sun\"\n");
    let _ = writeln!(toml, "[[path]]\nname = \"sun\"\nkeys = [");
    for i in 0..BAKED_HOURS {
        let hour = i as f32 * sky.hours_per_day / BAKED_HOURS as f32;
        let (az, el) = crate::sky::eval::azimuth_elevation(sky.path_at(sky.sun_path, hour).0);
        let _ = writeln!(toml, "    {{ hour = {hour}, azimuth_deg = {:.3}, elevation_deg = {:.3} }},", az.rem_euclid(360.0), el);
    }
    let _ = writeln!(toml, "]\n");
    let gradients: Vec<String> = (0..weathers).map(|w| format!("\"gradient_{w}.png\"")).collect();
    let _ = writeln!(
        toml,
        "[[object]]\nname = \"skydome\"\npriority = 0\nvisible_in_env_map = true\n\n[object.standard]\nshape = {{ kind = \"dome\", bottom_deg = {} }}\nblend = \"opaque\"\nconstants = [{{ mode = \"bitmap\", bitmap = \"halo_color.png\" }}]\nweather_gradients = {{ stage = 0, bitmaps = [{}] }}\n\n[[object.standard.stage]] # the gradient (fed by weather_gradients)\nop = \"add\"\nclamp = true\n\n[[object.standard.stage]] # the sun-side glow\ntexture = \"halo.png\"\nop = \"add\"\nconstant = 0\nuv = {{ kind = \"sun\", size_deg = {} }}\nclamp = true",
        represent::BAKED_BOTTOM_DEG,
        gradients.join(", "),
        2.0 * represent::BAKED_HALO_RADIUS_DEG
    );
    crate::support::safe_write::write_atomic(&dir.join("sky.toml"), toml.as_bytes())?;
    Ok(())
}
