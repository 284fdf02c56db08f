//! Loading a sky file: parse, resolve references, decode bitmaps, validate.
//!
//! Every error names the file, line:column and field. Validation collects all the errors it can
//! find in one go, so an artist fixes a broken file in one round trip.

use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use toml::Spanned;

use super::bitmap::ColorBitmap;
use super::error::{SkyError, SkyErrors};
use super::model::{self, FileRef, ModelChoice, SkyFile};
use super::resolved::*;

/// The error budget of `kind = "auto"` without `budget`: mean CIE dE2000 over the dome (2.3 is
/// about one just-noticeable difference).
pub const DEFAULT_DE2000_BUDGET: f64 = 2.0;

/// Where a sky's text and images come from: files next to the sky file, or the built-in sky.
pub trait AssetSource: Send + Sync {
    /// Name of the sky file, for error messages.
    fn sky_name(&self) -> String;
    /// The sky file's text.
    fn sky_text(&self) -> Result<String, String>;
    /// Decodes an image referenced from the sky file (path relative to the sky file).
    fn image(&self, rel: &str) -> Result<image::RgbaImage, String>;
    /// Display name of a referenced file.
    fn display(&self, rel: &str) -> String;
    /// Files on disk whose change should trigger a reload (none for built-in data).
    fn file_on_disk(&self, rel: &str) -> Option<PathBuf>;
}

/// Sky file on disk; referenced paths resolve relative to its folder.
#[derive(Debug, Clone)]
pub struct FsSource {
    /// The sky file.
    pub path: PathBuf,
}

impl FsSource {
    fn resolve(&self, rel: &str) -> PathBuf {
        self.path.parent().unwrap_or(Path::new(".")).join(rel)
    }
}

impl AssetSource for FsSource {
    fn sky_name(&self) -> String {
        self.path.display().to_string()
    }
    fn sky_text(&self) -> Result<String, String> {
        // Checked before reading: a huge file (a wrong path, a binary) is refused without loading it.
        let len = std::fs::metadata(&self.path).map_err(|e| format!("cannot read the sky file: {e}"))?.len();
        if len > MAX_SKY_FILE_BYTES as u64 {
            return Err(format!("the sky file is {len} bytes; at most {MAX_SKY_FILE_BYTES} are accepted"));
        }
        std::fs::read_to_string(&self.path).map_err(|e| format!("cannot read the sky file: {e}"))
    }
    fn image(&self, rel: &str) -> Result<image::RgbaImage, String> {
        let path = self.resolve(rel);
        let img = image::ImageReader::open(&path)
            .map_err(|e| format!("cannot open {}: {e}", path.display()))?
            .with_guessed_format()
            .map_err(|e| format!("cannot read {}: {e}", path.display()))?
            .decode()
            .map_err(|e| format!("cannot decode {}: {e}", path.display()))?;
        Ok(img.to_rgba8())
    }
    fn display(&self, rel: &str) -> String {
        self.resolve(rel).display().to_string()
    }
    fn file_on_disk(&self, rel: &str) -> Option<PathBuf> {
        Some(self.resolve(rel))
    }
}

/// Largest accepted texture or bitmap side, texels.
pub const MAX_IMAGE_SIDE: u32 = 4096;
/// Most stars a field may generate.
pub const MAX_STARS: u32 = 200_000;
/// Largest sky file, bytes (a sky file is a few hundred lines of text; this is 25,000 or so).
pub const MAX_SKY_FILE_BYTES: usize = 1 << 20;
/// Most objects in a sky.
pub const MAX_OBJECTS: usize = 256;
/// Most fallback versions of one object (for GPUs with fewer texture stages).
pub const MAX_FALLBACKS: usize = 2;
/// Most paths in a sky.
pub const MAX_PATHS: usize = 64;
/// Most keys of one path.
pub const MAX_PATH_KEYS: usize = 1024;
/// Most emitters in a sky (each may hold `model::MAX_PARTICLES_PER_EMITTER` particles).
pub const MAX_EMITTERS: usize = 32;
/// Most memory the distinct images of a sky may take once decoded (RGBA8), bytes: 512 MiB, eight
/// textures of 4096 x 4096.
pub const MAX_TEXTURE_BYTES: u64 = 512 << 20;

/// Loads and validates a sky file from disk.
pub fn load_sky_file(path: &Path) -> Result<Sky, SkyErrors> {
    load_sky(&FsSource { path: path.to_path_buf() })
}

/// Loads and validates a sky from any source.
pub fn load_sky(source: &dyn AssetSource) -> Result<Sky, SkyErrors> {
    let file = source.sky_name();
    let text = source.sky_text().map_err(|message| one(&file, 1, 1, "<file>", message))?;
    if text.len() > MAX_SKY_FILE_BYTES {
        return Err(one(&file, 1, 1, "<file>", format!("the sky file is {} bytes; at most {MAX_SKY_FILE_BYTES} are accepted", text.len())));
    }
    let parsed: SkyFile = parse_toml(&file, &text)?;
    let mut v = Validator {
        source,
        file,
        text: &text,
        errors: Vec::new(),
        images: HashMap::new(),
        bitmaps: HashMap::new(),
        watched: HashSet::new(),
        texture_bytes: 0,
        warnings: Vec::new(),
    };
    let sky = v.sky(parsed);
    match sky {
        Some(sky) if v.errors.is_empty() => Ok(Sky { warnings: std::mem::take(&mut v.warnings), ..sky }),
        _ => Err(SkyErrors(v.errors)),
    }
}

/// Parses TOML into `T`, turning serde errors into located `SkyError`s with the field path.
pub fn parse_toml<T: serde::de::DeserializeOwned>(file: &str, text: &str) -> Result<T, SkyErrors> {
    let de = toml::Deserializer::parse(text).map_err(|e| {
        let (line, column) = e.span().map(|s| line_col(text, s.start)).unwrap_or((1, 1));
        one(file, line, column, "<syntax>", e.message().trim().to_string())
    })?;
    serde_path_to_error::deserialize(de).map_err(|e| {
        let field = e.path().to_string();
        let inner = e.into_inner();
        let (line, column) = inner.span().map(|s| line_col(text, s.start)).unwrap_or((1, 1));
        one(file, line, column, if field == "." { "<root>" } else { &field }, inner.message().trim().to_string())
    })
}

fn one(file: &str, line: usize, column: usize, field: &str, message: impl Into<String>) -> SkyErrors {
    SkyErrors(vec![SkyError { file: file.to_string(), line, column, field: field.to_string(), message: message.into() }])
}

/// Byte offset of the `n`th (0-based) occurrence of `needle`, or 0.
fn nth_offset(text: &str, needle: &str, n: usize) -> usize {
    text.match_indices(needle).nth(n).map_or(0, |(i, _)| i)
}

/// 1-based line and column of a byte offset.
pub fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, column)
}

struct Validator<'a> {
    source: &'a dyn AssetSource,
    file: String,
    text: &'a str,
    errors: Vec<SkyError>,
    images: HashMap<String, Arc<TextureImage>>,
    bitmaps: HashMap<String, Arc<ColorBitmap>>,
    watched: HashSet<PathBuf>,
    /// Decoded bytes of the distinct images so far ([`MAX_TEXTURE_BYTES`]).
    texture_bytes: u64,
    /// Problems that do not stop the sky from loading ([`Sky::warnings`]).
    warnings: Vec<SkyError>,
}

impl Validator<'_> {
    /// A problem at `span` of the sky file, in `field`.
    fn located(&self, span: std::ops::Range<usize>, field: &str, message: impl Into<String>) -> SkyError {
        let (line, column) = line_col(self.text, span.start);
        SkyError { file: self.file.clone(), line, column, field: field.to_string(), message: message.into() }
    }

    fn err_at(&mut self, span: std::ops::Range<usize>, field: &str, message: impl Into<String>) {
        let e = self.located(span, field, message);
        self.errors.push(e);
    }

    /// Warns when stage `s` of version `v` tiles its texture under the mesh mapping of a dome
    /// that reaches the zenith: u runs round the azimuth there, so the repeats converge on the
    /// pole into a star (the cloud-layer mapping has no pole).
    fn warn_if_pinched(&mut self, v: &model::VersionDef, s: &model::StageDef, sf: &str, name: &str) {
        let reaches_zenith = match v.shape {
            model::Shape::Dome { .. } => true,
            model::Shape::DomeBand { top_deg, .. } => top_deg.get() >= 90.0,
            model::Shape::Billboard { .. } | model::Shape::Quad { .. } => false,
        };
        let scale = s.uv_scale.get_ref();
        if reaches_zenith && s.texture.is_some() && s.uv == model::UvSource::Mesh && scale.iter().any(|x| x.get().abs() > 1.0) {
            let message = format!(
                "\"{name}\": a texture repeated [{}, {}] times under the mesh mapping converges into a star at the zenith; \
                 use uv = {{ kind = \"layer\" }} for tiled clouds and stars",
                scale[0].get(),
                scale[1].get()
            );
            let w = self.located(s.uv_scale.span(), &format!("{sf}.uv_scale"), message);
            self.warnings.push(w);
        }
    }

    /// Errors without a span of their own point at the first `key` after `anchor` (usually the
    /// object's quoted name), or at the anchor itself when the key is absent.
    fn err_in(&mut self, anchor: &str, key: &str, field: &str, message: impl Into<String>) {
        let start = self.text.find(anchor).unwrap_or(0);
        let offset = self.text[start..].find(key).map_or(start, |k| start + k);
        self.err_at(offset..offset, field, message);
    }

    /// Braun and Cohen's parameters: a preset of the paper, then the file's overrides.
    fn linear(&mut self, l: &model::LinearDef) -> crate::atmosphere::analytic::LinearParams {
        use crate::atmosphere::analytic::{LinearParams, LINEAR_PRESETS};
        let mut p = LinearParams::default();
        if let Some(name) = &l.preset {
            match LinearParams::preset(name.get_ref()) {
                Some(preset) => p = preset,
                None => self.err_at(
                    name.span(),
                    "sky_model.linear.preset",
                    format!("unknown preset \"{}\"; expected one of {}", name.get_ref(), LINEAR_PRESETS.map(|p| p.0).join(", ")),
                ),
            }
        }
        if let Some(min) = l.min {
            p.min = min.map(|v| v.get() as f64);
        }
        if let Some(max) = l.max {
            p.max = max.map(|v| v.get() as f64);
        }
        p.sunrise_hour = l.sunrise_hour.map_or(p.sunrise_hour, |h| h.get() as f64);
        p.sunset_hour = l.sunset_hour.map_or(p.sunset_hour, |h| h.get() as f64);
        p.ramp_hours = l.ramp_hours.map_or(p.ramp_hours, |h| h.get() as f64);
        p.ramp = l.ramp;
        if (0..3).any(|c| p.min[c] > p.max[c]) {
            self.err_in("[sky_model.linear]", "min", "sky_model.linear.min", format!("expected min <= max per channel, found min {:?} and max {:?}", p.min, p.max));
        }
        if p.ramp_hours * 2.0 > 24.0 || (p.sunset_hour - p.sunrise_hour).abs() < p.ramp_hours {
            self.err_in(
                "[sky_model.linear]",
                "ramp_hours",
                "sky_model.linear.ramp_hours",
                format!("the sunrise ({} h) and sunset ({} h) ramps of {} h overlap", p.sunrise_hour, p.sunset_hour, p.ramp_hours),
            );
        }
        p
    }

    fn err_near(&mut self, needle: &str, field: &str, message: impl Into<String>) {
        self.err_in(needle, needle, field, message);
    }

    fn image(&mut self, r: &FileRef, field: &str) -> Option<Arc<TextureImage>> {
        let key = r.get_ref().clone();
        if let Some(img) = self.images.get(&key) {
            return Some(img.clone());
        }
        if let Some(p) = self.source.file_on_disk(&key) {
            self.watched.insert(p);
        }
        match self.source.image(&key) {
            Ok(img) => {
                let (w, h) = img.dimensions();
                if w == 0 || h == 0 || w > MAX_IMAGE_SIDE || h > MAX_IMAGE_SIDE {
                    self.err_at(r.span(), field, format!("{} is {w}x{h}; expected sides in 1..={MAX_IMAGE_SIDE}", self.source.display(&key)));
                    return None;
                }
                self.texture_bytes += u64::from(w) * u64::from(h) * 4;
                if self.texture_bytes > MAX_TEXTURE_BYTES {
                    let mib = |b: u64| b as f64 / (1 << 20) as f64;
                    let message = format!(
                        "{} ({w}x{h}) brings the sky's decoded images to {:.1} MiB; at most {:.0} MiB are accepted",
                        self.source.display(&key),
                        mib(self.texture_bytes),
                        mib(MAX_TEXTURE_BYTES)
                    );
                    self.err_at(r.span(), field, message);
                    return None;
                }
                let tex = Arc::new(TextureImage { key: self.source.display(&key), width: w, height: h, rgba8: img.into_raw() });
                self.images.insert(key, tex.clone());
                Some(tex)
            }
            Err(message) => {
                self.err_at(r.span(), field, message);
                None
            }
        }
    }

    fn bitmap(&mut self, r: &FileRef, field: &str) -> Option<Arc<ColorBitmap>> {
        if let Some(b) = self.bitmaps.get(r.get_ref()) {
            return Some(b.clone());
        }
        let tex = self.image(r, field)?;
        let b = Arc::new(ColorBitmap::from_rgba8(tex.width, tex.height, &tex.rgba8).with_source(r.get_ref()));
        self.bitmaps.insert(r.get_ref().clone(), b.clone());
        Some(b)
    }

    fn sky(&mut self, f: SkyFile) -> Option<Sky> {
        let fog = self.bitmap(&f.fog_color, "fog_color");
        let ambient = self.bitmap(&f.sun_ambient, "sun_ambient");
        let diffuse = self.bitmap(&f.sun_diffuse, "sun_diffuse");
        let hours = f.hours_per_day.get();
        let paths = self.paths(&f.paths, hours);
        let path_index: HashMap<&str, usize> = f.paths.iter().enumerate().map(|(i, p)| (p.name.as_str(), i)).collect();
        let sun_path = self.path_ref(&path_index, &f.sun_path, "sun_path");

        if f.paths.len() > MAX_PATHS {
            let at = nth_offset(self.text, "[[path]]", MAX_PATHS);
            self.err_at(at..at, &format!("path[{MAX_PATHS}]"), format!("a sky has at most {MAX_PATHS} paths; this one has {}", f.paths.len()));
        }
        if f.objects.len() > MAX_OBJECTS {
            let at = nth_offset(self.text, "[[object]]", MAX_OBJECTS);
            self.err_at(at..at, &format!("object[{MAX_OBJECTS}]"), format!("a sky has at most {MAX_OBJECTS} objects; this one has {}", f.objects.len()));
            return None;
        }
        let mut names = HashSet::new();
        let mut objects = Vec::new();
        for (i, o) in f.objects.iter().enumerate() {
            let field = format!("object[{i}]");
            if !names.insert(o.name.as_str()) {
                self.err_near(&format!("\"{}\"", o.name), &format!("{field}.name"), format!("duplicate object name \"{}\"", o.name));
            }
            if let Some(obj) = self.object(o, &field, &path_index) {
                objects.push(obj);
            }
        }
        // Stable: equal priorities keep file order, as NeL's sorted insertion did.
        objects.sort_by_key(|o: &SkyObject| o.priority);
        let emitters = self.emitters(&f.emitters, &objects);

        let stars = f.stars.as_ref().and_then(|s| {
            if s.count > MAX_STARS {
                self.err_near("[stars]", "stars.count", format!("expected at most {MAX_STARS} stars, found {}", s.count));
            }
            let color = self.color(&s.color, "stars.color", "[stars]")?;
            Some(Stars {
                source: s.source,
                sidereal_hours_at_midnight: s.sidereal_hours_at_midnight.get(),
                count: s.count.min(MAX_STARS),
                magnitude_cutoff: s.magnitude_cutoff.get(),
                seed: s.seed,
                pole_elevation_deg: s.pole_elevation_deg.get(),
                color,
                size_px: s.size_px.get(),
                priority: s.priority.0,
            })
        });
        let glare = f.glare.as_ref().and_then(|g| self.glare(g));
        let mut model = f.sky_model.as_ref().map_or_else(SkyModel::default, |m| {
            let d = crate::atmosphere::LutSettings::default();
            let lut = crate::atmosphere::LutSettings {
                transmittance_size: m.transmittance_size.map_or(d.transmittance_size, |[w, h]| [w.0, h.0]),
                transmittance_steps: m.transmittance_steps.map_or(d.transmittance_steps, |s| s.0),
                multiscattering_size: m.multiscattering_size.map_or(d.multiscattering_size, |s| s.0),
                multiscattering_grid: m.multiscattering_grid.map_or(d.multiscattering_grid, |s| s.0),
                multiscattering_steps: m.multiscattering_steps.map_or(d.multiscattering_steps, |s| s.0),
                view_steps: m.view_steps.0,
            };
            SkyModel {
                // Until `auto_model::resolve` picks, an auto sky renders with the default `lut`.
                kind: match m.kind {
                    ModelChoice::Model(k) => k,
                    ModelChoice::Auto => SkyModelKind::Lut,
                },
                drive_scene: m.drive_scene,
                settings: ModelSettings {
                    single: crate::atmosphere::SingleSettings { view_steps: m.view_steps.0, sun_steps: m.sun_steps.0, optical_depth: m.optical_depth },
                    lut,
                    precomputed: m.precomputed.as_ref().map_or_else(Default::default, |p| p.settings()),
                    cell_iterations: m.cell_iterations.map_or(6, |s| s.0),
                    reference: ReferenceSampling { paths: m.reference_paths.map_or(256, |s| s.0), grid: m.reference_grid.map_or([48, 27], |[a, b]| [a.0.max(2), b.0.max(2)]) },
                    analytic: AnalyticSettings {
                        turbidity: m.turbidity.map_or(crate::atmosphere::analytic::DEFAULT_TURBIDITY as f32, |t| t.get()),
                        turbidity_from_atmosphere: false,
                        units: m.analytic_units,
                    },
                    linear: crate::atmosphere::analytic::LinearParams { hours_per_day: hours as f64, ..m.linear.as_ref().map_or_else(Default::default, |l| self.linear(l)) },
                },
                camera: CameraResponse {
                    exposure_ev: m.exposure_ev.map_or(if m.auto_exposure { 0.0 } else { 5.0 }, |e| e.get()),
                    auto_exposure: m.auto_exposure,
                    tone_mapper: m.tone_mapper,
                },
                world: World { camera_km: m.camera_km.get(), ground_albedo: m.ground_albedo.get() },
                aerial: Default::default(),
            }
        });
        if let Some(a) = &f.aerial_perspective {
            model.aerial = a.settings();
            if let Err(e) = model.aerial.validate() {
                self.err_in("[aerial_perspective]", e.field, &format!("aerial_perspective.{}", e.field), e.message);
            }
        }
        let auto_model = match f.sky_model.as_ref() {
            Some(m) if m.kind == ModelChoice::Auto => Some(super::resolved::Budget { de2000: m.budget.as_ref().map_or(DEFAULT_DE2000_BUDGET, |b| b.de2000.get() as f64) }),
            Some(m) => {
                if m.budget.is_some() {
                    self.err_in("[sky_model]", "budget", "sky_model.budget", "an error budget only applies with kind = \"auto\"");
                }
                None
            }
            None => None,
        };
        if model.settings.cell_iterations > 32 {
            self.err_in("[sky_model]", "cell_iterations", "sky_model.cell_iterations", format!("expected 1..=32, found {}", model.settings.cell_iterations));
        }
        if let Err(e) = model.settings.lut.validate() {
            self.err_in("[sky_model]", e.field, &format!("sky_model.{}", e.field), e.message);
        }
        if let Err(e) = model.settings.precomputed.validate() {
            self.err_in("[sky_model.precomputed]", e.field, &format!("sky_model.precomputed.{}", e.field), e.message);
        }
        let atmosphere = match f.atmosphere.as_ref().map(|a| a.apply(crate::atmosphere::Atmosphere::default(), None)) {
            None => Ok(crate::atmosphere::Atmosphere::default()),
            Some(Ok(a)) => a.validate().map(|()| a),
            Some(Err(e)) => Err(e),
        };
        let atmosphere = atmosphere.unwrap_or_else(|errors| {
            for e in errors {
                self.err_in("[atmosphere]", e.field, &format!("atmosphere.{}", e.field), e.message);
            }
            crate::atmosphere::Atmosphere::default()
        });
        let weather_defs = f.atmosphere.as_ref().map_or(&[][..], |a| &a.weather[..]);
        let mut atmosphere_by_weather = Vec::new();
        for (k, def) in weather_defs.iter().enumerate() {
            if !def.weather.is_empty() {
                self.err_near("[[atmosphere.weather.weather]]", &format!("atmosphere.weather[{k}].weather"), "weather steps cannot have weather steps of their own");
            }
            match def.apply(atmosphere, f.atmosphere.as_ref()).and_then(|step| step.validate().map(|()| step)) {
                Ok(step) => atmosphere_by_weather.push(step),
                Err(errors) => {
                    for e in errors {
                        self.err_in("[[atmosphere.weather]]", e.field, &format!("atmosphere.weather[{k}].{}", e.field), e.message);
                    }
                }
            }
        }
        // The analytic models describe the same sky as the physical ones: an atmosphere whose
        // aerosol is written out sets their turbidity unless [sky_model] states one.
        let stated_turbidity = f.sky_model.as_ref().is_some_and(|m| m.turbidity.is_some());
        if !stated_turbidity && f.atmosphere.as_ref().is_some_and(|a| a.states_aerosol()) {
            model.settings.analytic.turbidity = atmosphere.turbidity().clamp(1.0, 10.0) as f32;
            model.settings.analytic.turbidity_from_atmosphere = true;
        }
        if model.world.camera_km as f64 >= atmosphere.thickness_km() {
            self.err_in("[sky_model]", "camera_km", "sky_model.camera_km", format!("expected an altitude below the top of the atmosphere ({} km)", atmosphere.thickness_km()));
        }

        let paths = paths?;
        let watched = {
            let mut w: Vec<PathBuf> = self.watched.iter().cloned().collect();
            w.sort();
            w
        };
        Some(Sky {
            name: f.name,
            hours_per_day: hours,
            weather_names: f.weather_names,
            source_name: self.file.clone(),
            fog_color: fog?,
            sun_ambient: ambient?,
            sun_diffuse: diffuse?,
            sun_path: sun_path?,
            paths,
            objects,
            emitters,
            particle_seconds_per_hour: f.particle_seconds_per_hour.map_or(180.0, |s| s.get()),
            stars,
            glare,
            watched_files: watched,
            model,
            atmosphere,
            atmosphere_by_weather,
            auto_model,
            warnings: Vec::new(),
        })
    }

    /// Checks the emitters: unique names, an attachment that exists, at most 4 parameters and
    /// `MAX_EMITTERS` emitters, a cone of at most 180 degrees, an alpha or additive blend.
    fn emitters(&mut self, defs: &[model::EmitterDef], objects: &[SkyObject]) -> Vec<Emitter> {
        if defs.len() > MAX_EMITTERS {
            let at = nth_offset(self.text, "[[emitter]]", MAX_EMITTERS);
            self.err_at(at..at, &format!("emitter[{MAX_EMITTERS}]"), format!("a sky has at most {MAX_EMITTERS} emitters; this one has {}", defs.len()));
            return Vec::new();
        }
        let mut names = HashSet::new();
        let mut out = Vec::new();
        for (i, e) in defs.iter().enumerate() {
            let field = format!("emitter[{i}]");
            let anchor = format!("\"{}\"", e.name);
            if !names.insert(e.name.as_str()) {
                self.err_near(&anchor, &format!("{field}.name"), format!("duplicate emitter name \"{}\"", e.name));
            }
            let attach = if e.attach.get_ref() == "camera" {
                Some(EmitterAttach::Camera)
            } else if let Some(index) = objects.iter().position(|o| &o.name == e.attach.get_ref()) {
                Some(EmitterAttach::Object(index))
            } else {
                let known: Vec<&str> = objects.iter().map(|o| o.name.as_str()).collect();
                self.err_at(
                    e.attach.span(),
                    &format!("{field}.attach"),
                    format!("no object \"{}\" to attach to; expected \"camera\" or one of {}", e.attach.get_ref(), known.join(", ")),
                );
                None
            };
            if e.params.len() > 4 {
                self.err_in(&anchor, "params", &format!("{field}.params"), format!("an emitter has at most 4 parameters; this one has {}", e.params.len()));
            }
            if e.spread_deg.get() > 180.0 {
                self.err_in(&anchor, "spread_deg", &format!("{field}.spread_deg"), format!("expected 0..=180 degrees, found {}", e.spread_deg.get()));
            }
            if e.blend == BlendMode::Opaque {
                self.err_in(&anchor, "blend", &format!("{field}.blend"), "particles blend as \"alpha\" or \"additive\"");
            }
            let emission = self.color(&e.emission, &format!("{field}.emission"), &anchor);
            let texture = match &e.texture {
                Some(t) => self.image(t, &format!("{field}.texture")).map(Some),
                None => Some(None),
            };
            let params: Option<Vec<_>> =
                e.params.iter().enumerate().take(4).map(|(k, p)| self.bitmap(&p.bitmap, &format!("{field}.params[{k}].bitmap")).map(|b| (b, p.scales))).collect();
            let (Some(attach), Some(emission), Some(texture), Some(params)) = (attach, emission, texture, params) else { continue };
            let v = |c: [model::Unit; 4]| c.map(|x| x.get());
            out.push(Emitter {
                name: e.name.clone(),
                attach,
                kind: e.kind,
                shape: e.shape,
                texture,
                blend: e.blend,
                rate: e.rate.get(),
                lifetime_s: e.lifetime_s.get(),
                lifetime_spread: e.lifetime_spread.get(),
                speed: e.speed.get(),
                speed_spread: e.speed_spread.get(),
                direction: glam::Vec3::from_array(e.direction.map(|d| d.get())),
                spread_deg: e.spread_deg.get(),
                gravity: e.gravity.get(),
                size: e.size.map(|s| s.get()),
                color: e.color.map(v),
                max_particles: e.max_particles.0,
                emission,
                params,
                region_deg: e.region_deg.map_or(5.0, |r| r.get()),
                min_elevation_deg: e.min_elevation_deg.map_or(15.0, |r| r.get()),
                box_m: e.box_m.map_or(24.0, |b| b.get()),
                streak_s: e.streak_s.map_or(0.04, |s| s.get()),
                flash: e.flash.get(),
                rain_to_snow: e.rain_to_snow.get(),
                seed: e.seed,
            });
        }
        out
    }

    fn path_ref(&mut self, index: &HashMap<&str, usize>, name: &Spanned<String>, field: &str) -> Option<usize> {
        match index.get(name.get_ref().as_str()) {
            Some(&i) => Some(i),
            None => {
                let known: Vec<&str> = index.keys().copied().collect();
                self.err_at(name.span(), field, format!("no path named \"{}\" (paths: {})", name.get_ref(), list(&known)));
                None
            }
        }
    }

    fn paths(&mut self, defs: &[model::PathDef], hours: f32) -> Option<Vec<SkyPath>> {
        let index: HashMap<&str, usize> = defs.iter().enumerate().map(|(i, p)| (p.name.as_str(), i)).collect();
        let mut out = Vec::new();
        let mut ok = true;
        let mut seen = HashSet::new();
        for (i, p) in defs.iter().enumerate() {
            let field = format!("path[{i}]");
            if p.keys.len() > MAX_PATH_KEYS {
                self.err_near(&format!("\"{}\"", p.name), &format!("{field}.keys"), format!("a path has at most {MAX_PATH_KEYS} keys; this one has {}", p.keys.len()));
                ok = false;
                continue;
            }
            if !seen.insert(p.name.as_str()) {
                self.err_near(&format!("\"{}\"", p.name), &format!("{field}.name"), format!("duplicate path name \"{}\"", p.name));
                ok = false;
            }
            let kind = match (&p.follow, p.keys.is_empty()) {
                (Some(_), false) => {
                    self.err_near(&format!("\"{}\"", p.name), &field, "a path has either `keys` or `follow`, not both");
                    ok = false;
                    continue;
                }
                (None, true) => {
                    self.err_near(&format!("\"{}\"", p.name), &format!("{field}.keys"), "a path needs at least one key (or `follow = \"other path\"`)");
                    ok = false;
                    continue;
                }
                (Some(target), true) => match self.path_ref(&index, target, &format!("{field}.follow")) {
                    Some(t) => PathKind::Follow {
                        target: t,
                        lag_hours: p.lag_hours.get(),
                        azimuth_offset_deg: p.azimuth_offset_deg.get(),
                        elevation_offset_deg: p.elevation_offset_deg.get(),
                    },
                    None => {
                        ok = false;
                        continue;
                    }
                },
                (None, false) => {
                    let mut keys = Vec::new();
                    for (k, key) in p.keys.iter().enumerate() {
                        if !(0.0..hours).contains(&key.hour.get()) {
                            self.err_near(&format!("\"{}\"", p.name), &format!("{field}.keys[{k}].hour"), format!("expected an hour in [0, {hours}), found {}", key.hour.get()));
                            ok = false;
                        }
                        keys.push(PathKeyframe { hour: key.hour.get(), azimuth_deg: key.azimuth_deg.get(), elevation_deg: key.elevation_deg.get(), roll_deg: key.roll_deg.get() });
                    }
                    keys.sort_by(|a, b| a.hour.total_cmp(&b.hour));
                    PathKind::Keys(keys)
                }
            };
            out.push(SkyPath { name: p.name.clone(), kind });
        }
        if !ok {
            return None;
        }
        // A follow chain must end on keyed paths.
        for (start, def) in defs.iter().enumerate().take(out.len()) {
            let mut visited = vec![start];
            let mut cur = start;
            while let PathKind::Follow { target, .. } = out[cur].kind {
                if visited.contains(&target) {
                    let chain: Vec<&str> = visited.iter().chain([&target]).map(|&i| out[i].name.as_str()).collect();
                    let span = def.follow.as_ref().map(|s| s.span()).unwrap_or(0..0);
                    self.err_at(span, &format!("path[{start}].follow"), format!("cyclic follow: {}", chain.join(" -> ")));
                    return None;
                }
                visited.push(target);
                cur = target;
            }
        }
        Some(out)
    }

    fn object(&mut self, o: &model::ObjectDef, field: &str, paths: &HashMap<&str, usize>) -> Option<SkyObject> {
        let path = match &o.path {
            Some(p) => Some(self.path_ref(paths, p, &format!("{field}.path"))?),
            None => None,
        };
        let standard = self.version(&o.standard, &format!("{field}.standard"), &o.name, path.is_some());
        if o.fallback.len() > MAX_FALLBACKS {
            self.err_in(
                &format!("\"{}\"", o.name),
                "[[object.fallback]]",
                &format!("{field}.fallback"),
                format!("at most {MAX_FALLBACKS} fallback versions, found {}", o.fallback.len()),
            );
        }
        let fallback: Vec<Option<Version>> = o.fallback.iter().enumerate().map(|(k, v)| self.version(v, &format!("{field}.fallback[{k}]"), &o.name, path.is_some())).collect();
        let fallback: Option<Vec<Version>> = fallback.into_iter().collect();
        Some(SkyObject {
            name: o.name.clone(),
            priority: o.priority.0,
            visible_in_main_scene: o.visible_in_main_scene,
            visible_in_env_map: o.visible_in_env_map,
            layer: o.layer,
            path,
            standard: standard?,
            fallback: fallback?,
        })
    }

    fn version(&mut self, v: &model::VersionDef, field: &str, name: &str, has_path: bool) -> Option<Version> {
        let mut ok = true;
        let anchor = format!("\"{name}\"");
        if v.stages.len() > MAX_STAGES {
            self.err_in(&anchor, "[[object", &format!("{field}.stage"), format!("at most {MAX_STAGES} texture stages, found {}", v.stages.len()));
            ok = false;
        }
        if v.constants.len() > 4 {
            self.err_in(&anchor, "constants", &format!("{field}.constants"), format!("at most 4 constant colours, found {}", v.constants.len()));
            ok = false;
        }
        match v.shape {
            model::Shape::DomeBand { bottom_deg, top_deg } if bottom_deg.get() >= top_deg.get() => {
                self.err_in(&anchor, "shape", &format!("{field}.shape"), format!("dome band needs bottom_deg < top_deg, found {} >= {}", bottom_deg.get(), top_deg.get()));
                ok = false;
            }
            model::Shape::Billboard { .. } | model::Shape::Quad { .. } if !has_path => {
                self.err_in(&anchor, "shape", &format!("{field}.shape"), "billboards and quads need the object to have a `path`");
                ok = false;
            }
            _ => {}
        }
        let gradient_stage = v.weather_gradients.as_ref().map(|g| *g.stage.get_ref() as usize);
        let gradients = match &v.weather_gradients {
            None => None,
            Some(g) => {
                let s = *g.stage.get_ref() as usize;
                if s >= v.stages.len() {
                    self.err_at(g.stage.span(), &format!("{field}.weather_gradients.stage"), format!("stage {s} does not exist ({} stages)", v.stages.len()));
                    ok = false;
                }
                if g.bitmaps.is_empty() {
                    self.err_at(g.stage.span(), &format!("{field}.weather_gradients.bitmaps"), "expected at least one gradient bitmap");
                    ok = false;
                }
                let mut bitmaps = Vec::new();
                for (k, b) in g.bitmaps.iter().enumerate() {
                    let f = format!("{field}.weather_gradients.bitmaps[{k}]");
                    if let Some(bm) = self.bitmap(b, &f) {
                        if let Some(first) = bitmaps.first() {
                            let first: &Arc<ColorBitmap> = first;
                            if bm.height != first.height {
                                self.err_at(
                                    b.span(),
                                    &f,
                                    format!("gradient is {} texels high but the first one is {}; all weather steps must share a height", bm.height, first.height),
                                );
                                ok = false;
                            }
                        }
                        if bm.height < 2 {
                            self.err_at(b.span(), &f, "a gradient needs at least 2 texels along the dome");
                            ok = false;
                        }
                        bitmaps.push(bm);
                    } else {
                        ok = false;
                    }
                }
                Some(Gradients { stage: s, bitmaps })
            }
        };
        let mut stages = Vec::new();
        for (k, s) in v.stages.iter().enumerate().take(MAX_STAGES) {
            let sf = format!("{field}.stage[{k}]");
            let texture = match &s.texture {
                Some(t) => self.image(t, &format!("{sf}.texture")),
                None if gradient_stage == Some(k) => None,
                None => {
                    self.err_in(&anchor, "[[object", &format!("{sf}.texture"), "missing texture (only the stage fed by weather_gradients may omit it)");
                    ok = false;
                    None
                }
            };
            if s.texture.is_some() && texture.is_none() {
                ok = false;
            }
            if let Some(c) = &s.constant {
                let c_idx = *c.get_ref() as usize;
                if c_idx >= v.constants.len() {
                    self.err_at(c.span(), &format!("{sf}.constant"), format!("constant {c_idx} is not defined ({} constants)", v.constants.len()));
                    ok = false;
                }
            }
            self.warn_if_pinched(v, s, &sf, name);
            if k == 0 && s.op == model::StageOp::Modulate {
                self.err_in(&anchor, "op = \"modulate\"", &format!("{sf}.op"), "the first stage cannot modulate: there is nothing before it");
                ok = false;
            }
            let uv_offset = match &s.uv_offset_bitmap {
                Some(b) => match self.bitmap(b, &format!("{sf}.uv_offset_bitmap")) {
                    Some(bm) => Some((bm, s.uv_offset_factor.get())),
                    None => {
                        ok = false;
                        None
                    }
                },
                None => None,
            };
            stages.push(Stage {
                texture,
                op: s.op,
                constant: s.constant.as_ref().map(|c| *c.get_ref() as usize),
                uv: s.uv,
                uv_scale: s.uv_scale.get_ref().map(|x| x.get()),
                panner: s.panner.map(|x| x.get()),
                uv_offset,
                clamp: s.clamp,
            });
        }
        let diffuse = self.color(&v.diffuse, &format!("{field}.diffuse"), &anchor);
        let mut constants = Vec::new();
        for (k, c) in v.constants.iter().enumerate().take(4) {
            constants.push(self.color(c, &format!("{field}.constants[{k}]"), &anchor));
        }
        let ref_index = match v.ref_color {
            model::RefColor::Constant0 => Some(0),
            model::RefColor::Constant1 => Some(1),
            model::RefColor::Constant2 => Some(2),
            model::RefColor::Constant3 => Some(3),
            _ => None,
        };
        if let Some(r) = ref_index {
            if r >= v.constants.len() {
                self.err_in(&anchor, "ref_color", &format!("{field}.ref_color"), format!("ref_color names constant {r}, which is not defined ({} constants)", v.constants.len()));
                ok = false;
            }
        }
        let diffuse = diffuse?;
        let constants: Option<Vec<Color>> = constants.into_iter().collect();
        if !ok {
            return None;
        }
        Some(Version {
            shape: v.shape,
            blend: v.blend,
            stages,
            diffuse,
            constants: constants?,
            ref_color: v.ref_color,
            gradients,
            lighting: v.lighting,
            cloud_density: v.cloud_density.map_or(3.0, |d| d.get()),
        })
    }

    /// `anchor` locates the owner in the text (an object's quoted name, `[stars]`, `[glare]`).
    fn color(&mut self, c: &model::ColorDef, field: &str, anchor: &str) -> Option<Color> {
        use model::ColorMode::*;
        let needs_bitmap = matches!(c.mode, Bitmap | BitmapTimesFog);
        let bitmap = match (&c.bitmap, needs_bitmap) {
            (Some(b), true) => Some(self.bitmap(b, &format!("{field}.bitmap"))?),
            (None, true) => {
                let key = field.rsplit('.').next().unwrap_or(field).split('[').next().unwrap_or(field);
                self.err_in(anchor, key, field, format!("mode {:?} needs a `bitmap`", c.mode));
                return None;
            }
            (Some(b), false) => {
                self.err_at(b.span(), &format!("{field}.bitmap"), format!("a bitmap is set but mode is {:?}; use mode = \"bitmap\" or remove it", c.mode));
                return None;
            }
            (None, false) => None,
        };
        Some(Color { mode: c.mode, bitmap, value: c.value.map(|x| x.get()) })
    }

    fn glare(&mut self, g: &model::GlareDef) -> Option<Glare> {
        let halo = self.image(&g.halo, "glare.halo");
        let color = self.color(&g.color, "glare.color", "[glare]");
        if g.flares.len() > MAX_FLARES {
            self.err_near("[glare]", "glare.flare", format!("at most {MAX_FLARES} flare sprites, found {}", g.flares.len()));
            return None;
        }
        let mut flares = Vec::new();
        for (k, f) in g.flares.iter().enumerate() {
            let texture = self.image(&f.texture, &format!("glare.flare[{k}].texture"))?;
            flares.push(Flare { texture, position: f.position.get(), size: f.size.get(), tint: f.tint.map(|x| x.get()) });
        }
        Some(Glare {
            halo: halo?,
            halo_size_deg: g.halo_size_deg.get(),
            disc_size_deg: g.disc_size_deg.get(),
            persistence_s: g.persistence_s.get(),
            shrink: g.shrink,
            rotate: g.rotate.get(),
            color: color?,
            flares,
        })
    }
}

fn list(names: &[&str]) -> String {
    if names.is_empty() {
        "none".into()
    } else {
        let mut n = names.to_vec();
        n.sort();
        n.join(", ")
    }
}

/// A continent: which sky file each season uses.
#[derive(Debug, Clone)]
pub struct Continent {
    /// Continent name.
    pub name: String,
    /// Sky files for spring, summer, autumn, winter.
    pub skies: [PathBuf; 4],
}

/// The four seasons, in file order.
pub const SEASONS: [&str; 4] = ["spring", "summer", "autumn", "winter"];

/// Loads a continent file; sky paths resolve relative to it and must exist.
pub fn load_continent(path: &Path) -> Result<Continent, SkyErrors> {
    let file = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| one(&file, 1, 1, "<file>", format!("cannot read: {e}")))?;
    let c: model::ContinentFile = parse_toml(&file, &text)?;
    let dir = path.parent().unwrap_or(Path::new("."));
    let s = &c.seasons;
    let refs = [&s.spring, &s.summer, &s.autumn, &s.winter];
    let mut errors = Vec::new();
    let skies = refs.map(|r| {
        let p = dir.join(r.get_ref());
        if !p.is_file() {
            let (line, column) = line_col(&text, r.span().start);
            errors.push(SkyError { file: file.clone(), line, column, field: "seasons".into(), message: format!("sky file {} does not exist", p.display()) });
        }
        p
    });
    if errors.is_empty() {
        Ok(Continent { name: c.name, skies })
    } else {
        Err(SkyErrors(errors))
    }
}

/// Whether a TOML file is a continent file (has a `[seasons]` table) rather than a sky file.
pub fn is_continent_file(path: &Path) -> bool {
    std::fs::read_to_string(path).ok().and_then(|t| t.parse::<toml::Table>().ok()).is_some_and(|t| t.contains_key("seasons"))
}
