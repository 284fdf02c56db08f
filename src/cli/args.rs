//! Command-line interface of the `skytune` binary.

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand};
use skytune::sky::resolved::SkyModelKind;
use skytune::support::shard::Shard;

/// Author and debug real-time skies: live preview, headless renders, validation and benchmarks.
#[derive(Debug, Parser)]
#[command(name = "skytune", version, about)]
pub struct Cli {
    /// Sky or continent file to open in the window (default: the built-in sky).
    pub sky: Option<PathBuf>,
    /// Window options (used when no subcommand is given).
    #[command(flatten)]
    pub app: AppArgs,
    /// Subcommand; none opens the window.
    #[command(subcommand)]
    pub command: Option<Command>,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Render one frame headless and write a PNG.
    Render(RenderArgs),
    /// Validate a sky or continent file and print its errors or a summary.
    Check {
        /// Sky or continent file.
        sky: PathBuf,
    },
    /// Re-render a PNG every time the sky file or one of its bitmaps changes (Ctrl-C to stop).
    Watch {
        /// Frame and output settings.
        #[command(flatten)]
        render: RenderArgs,
        /// Stop after this many reloads (for scripts and tests).
        #[arg(long)]
        max_reloads: Option<u32>,
    },
    /// Write a new sky folder (sky.toml + bitmaps) from a palette preset.
    NewSky {
        /// Folder to create.
        dir: PathBuf,
        /// Palette: default, desert, forest, lakes, jungle.
        #[arg(long, default_value = "default")]
        preset: String,
        /// Seed of the procedural textures.
        #[arg(long, default_value_t = 7)]
        seed: u64,
        /// Write into an existing folder (its files of the same names are replaced).
        #[arg(long)]
        force: bool,
    },
    /// Measure the sky passes (depth split and tiers) and write a Markdown report;
    /// `skytune bench frame` compares whole frames with the adapter's fill-rate floor.
    Bench(BenchCommand),
    /// Stability where methods fail: random parameter sets across and beyond every model's
    /// domain, counting NaN, infinite, negative and discontinuous radiance (docs/stability.md).
    Sweep(SweepArgs),
    /// NeL gradient and halo bitmaps (24 hours x N weather steps) baked from a physical model,
    /// written as a sky folder.
    Bake(BakeArgs),
    /// Sky radiance of a list of cases (CSV in, CSV out) from a physical sky model.
    Radiance(RadianceArgs),
    /// Environment lighting for engines at one hour or every hour: unfiltered EXR, GGX-prefiltered
    /// specular and diffuse irradiance cube maps (KTX2), spherical harmonics and the sun (JSON).
    ExportEnv(ExportEnvArgs),
    /// Compare the sky models with measured skies (data/measured/): fit each one's aerosol or
    /// turbidity per scan, report its luminance-shape and colour errors (docs/validation.md).
    Validate(ValidateArgs),
    /// Aerial perspective against the reference: the exact march and the volume at each size,
    /// per sun band and distance band, on a freshly drawn set of finite rays.
    ValidateAerial(ValidateAerialArgs),
    /// Render the same view twice (two skies, models, tiers or times), print the difference
    /// (FLIP and channel figures) and write A, B and the heat map; exit status 1 above a threshold.
    Compare(CompareArgs),
    /// Combine the outputs of `--shard K/N` runs (radiance, bench models' reference, sweep) into
    /// the files one unsharded run writes (docs/batch.md).
    Merge(MergeArgs),
    /// Render many frames with random changes, sky reloads (good and broken) and shader rebuilds;
    /// fail on memory growth or any unexpected error; write a report.
    Soak(SoakArgs),
}

/// `merge` arguments.
#[derive(Debug, Args, Clone)]
pub struct MergeArgs {
    /// The file to write: what the unsharded run writes.
    #[arg(long)]
    pub out: PathBuf,
    /// Every shard's output, in any order.
    #[arg(required = true)]
    pub parts: Vec<PathBuf>,
}

/// `soak` arguments.
#[derive(Debug, Args, Clone)]
pub struct SoakArgs {
    /// Frames to render.
    #[arg(long, default_value_t = 10_000)]
    pub frames: u64,
    /// Image size, WIDTHxHEIGHT.
    #[arg(long, default_value = "160x90")]
    pub size: String,
    /// Seed of the random changes.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Largest accepted growth of GPU memory and buffers after warm-up, percent.
    #[arg(long, default_value_t = 5.0)]
    pub max_growth_percent: f64,
    /// Largest accepted growth of resident memory after warm-up, percent (default: --max-growth-percent).
    #[arg(long)]
    pub max_rss_growth_percent: Option<f64>,
    /// Frames of warm-up before growth is measured (default: a quarter of the run).
    #[arg(long)]
    pub warm_up_frames: Option<u64>,
    /// Folder of the sky to soak (sky.toml and its bitmaps; copied first). Default: the built-in sky.
    #[arg(long)]
    pub sky_dir: Option<PathBuf>,
    /// Markdown report to write (none: print only).
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// SVG plot of memory over frames to write (linked from the report).
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Force the software adapter (lavapipe).
    #[arg(long)]
    pub cpu: bool,
}

/// `compare` arguments.
#[derive(Debug, Args, Clone)]
pub struct CompareArgs {
    /// Side A, the reference: SKY, SKY@key=value,... or @key=value,... (keys: hour, weather, tier,
    /// model, season, exposure_ev), e.g. `skies/desert/sky.toml@model=reference`.
    pub a: String,
    /// Side B, the one measured against A, in the same form.
    pub b: String,
    /// Sky or continent file of the sides that name none (default: the built-in sky).
    #[arg(long)]
    pub sky: Option<PathBuf>,
    /// Frame settings shared by both sides (a side's keys override them).
    #[command(flatten)]
    pub frame: FrameArgs,
    /// Image size of each side, WIDTHxHEIGHT.
    #[arg(long, default_value = "640x360")]
    pub size: String,
    /// Output PNG.
    #[arg(long, short, default_value = "compare.png")]
    pub out: PathBuf,
    /// Picture: side (A, B, heat map), split (A left, B right) or diff (heat map alone).
    #[arg(long, default_value = "side")]
    pub layout: String,
    /// Position of the split, 0..1 of the width (layout split).
    #[arg(long, default_value_t = 0.5)]
    pub split: f32,
    /// Channel tolerance of the pixel figures, of 255.
    #[arg(long, default_value_t = 12)]
    pub tolerance: u8,
    /// Leave the sun glare out of both sides.
    #[arg(long)]
    pub no_glare: bool,
    /// Exit with status 1 when the FLIP mean is above this.
    #[arg(long)]
    pub max_flip_mean: Option<f32>,
    /// Exit with status 1 when more than this fraction of pixels differ beyond --tolerance.
    #[arg(long)]
    pub max_differing: Option<f64>,
}

/// How `skytune radiance` answers finite rays.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum AerialArg {
    /// The renderer's aerial-perspective volume, read as the scene reads it.
    Volume,
    /// The model's own march stopped at the distance.
    Exact,
}

/// A `--volume-size` value: AxBxC cells.
fn parse_volume_size(s: &str) -> Result<[u32; 3], String> {
    let parts: Vec<Result<u32, _>> = s.split('x').map(|p| p.trim().parse::<u32>()).collect();
    match parts.as_slice() {
        [Ok(a), Ok(b), Ok(c)] => Ok([*a, *b, *c]),
        _ => Err(format!("expected ACROSSxDOWNxDEPTH cells, found \"{s}\"")),
    }
}

/// Optical depth towards the sun of the `single` model.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum OpticalDepthArg {
    /// The analytic erf approximation.
    Erf,
    /// Numerical integration.
    Numerical,
}

/// `export-env` arguments.
#[derive(Debug, Args, Clone)]
pub struct ExportEnvArgs {
    /// Sky or continent file (default: the built-in sky).
    pub sky: Option<PathBuf>,
    /// The moment (`--hour`, `--weather`), the model, the adapter and `--with-scene` (keep the
    /// main scene's stand-in in the maps); the view settings do not apply.
    #[command(flatten)]
    pub frame: FrameArgs,
    /// One set per hour, FROM:TO:STEP game hours (TO excluded; `0:24:1` is a day), each in
    /// OUT/hour-HH.HH/.
    #[arg(long)]
    pub hours: Option<String>,
    /// Only every N-th hour from the K-th (K/N, or `auto` from a Slurm job array or a Kubernetes
    /// indexed Job: docs/batch.md).
    #[arg(long)]
    pub shard: Option<Shard>,
    /// Face size of the unfiltered map and the specular level 0, texels (a power of two).
    #[arg(long, default_value_t = 128)]
    pub size: u32,
    /// Specular mip levels (default: down to 4 texels a side).
    #[arg(long)]
    pub levels: Option<usize>,
    /// GGX samples per specular texel.
    #[arg(long, default_value_t = 256)]
    pub samples: u32,
    /// Face size of the diffuse irradiance map, texels.
    #[arg(long, default_value_t = 32)]
    pub irradiance_size: u32,
    /// KTX2 cube maps for engines that sample cube maps at (x, y, -z) of the world direction
    /// (Bevy): each texel holds the sky mirrored in z (docs/export.md).
    #[arg(long)]
    pub mirror_z: bool,
    /// Layout of the unfiltered EXR: six faces or one equirectangular image.
    #[arg(long, value_enum, default_value = "cube")]
    pub projection: Projection,
    /// Output folder.
    #[arg(long, short)]
    pub out: PathBuf,
}

/// `validate-aerial` arguments.
#[derive(Debug, Args, Clone)]
pub struct ValidateAerialArgs {
    /// Seed of the drawn rays (the tests use 67 and 68; docs/validation.md 69).
    #[arg(long, default_value_t = 69)]
    pub seed: u64,
    /// Rays drawn.
    #[arg(long, default_value_t = 192)]
    pub cases: usize,
    /// Reference paths per ray.
    #[arg(long, default_value_t = 1024)]
    pub paths: u32,
    /// Volume sizes, comma-separated ACROSSxDOWNxDEPTH.
    #[arg(long, value_delimiter = ',', default_value = "16x16x16,16x32x32,32x32x32,64x64x64", value_parser = parse_volume_size)]
    pub sizes: Vec<[u32; 3]>,
    /// View-ray samples per slice of every volume (default: `[aerial_perspective]`'s).
    #[arg(long)]
    pub steps_per_slice: Option<u32>,
    /// Results CSV (a row per method and band).
    #[arg(long)]
    pub out: PathBuf,
    /// Write the Markdown table into this file, between its validate-aerial markers (the rest of
    /// the file is kept).
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Use the CPU (software) adapter.
    #[arg(long)]
    pub cpu: bool,
}

/// `validate` arguments.
#[derive(Debug, Args, Clone)]
pub struct ValidateArgs {
    /// Scan files (data/measured/kider2014/*.csv) or folders of them.
    #[arg(required = true)]
    pub scans: Vec<PathBuf>,
    /// Models to compare, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "preetham,hosek,single,lut,reference", value_parser = model_among(VALIDATE_MODELS))]
    pub models: Vec<SkyModelKind>,
    /// The aerosol the physical models assume while its optical depth is fitted (a preset of
    /// `[atmosphere] aerosol`).
    #[arg(long, default_value = "continental", value_parser = parse_aerosol)]
    pub aerosol: skytune::atmosphere::aerosol::AerosolPreset,
    /// Fit the Angstrom exponent too (from 0 to 2.5 in steps of 0.5), not only the optical depth.
    #[arg(long)]
    pub fit_angstrom: bool,
    /// Ground albedo of the models.
    #[arg(long, default_value_t = 0.2)]
    pub albedo: f64,
    /// Leave out samples closer to the sun than this, degrees.
    #[arg(long, default_value_t = skytune::measure::validation::DEFAULT_SUN_EXCLUSION_DEG)]
    pub sun_exclusion_deg: f64,
    /// `reference`: most Monte Carlo paths per direction (it stops at a 2% standard error).
    #[arg(long, default_value_t = 2048)]
    pub reference_paths: u32,
    /// Results CSV: rows of other scans or models already there are kept, these replace theirs
    /// (so a long validation runs a few scans at a time).
    #[arg(long)]
    pub out: PathBuf,
    /// Write the Markdown report of every row in `--out` (between its validate markers; the
    /// rest of the file is kept).
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Write the chart of every row in `--out`: STEM.svg and STEM.png.
    #[arg(long)]
    pub chart: Option<PathBuf>,
    /// Write each scan's samples, measured and fitted (scaled), to DIR/SCAN.csv.
    #[arg(long)]
    pub samples: Option<PathBuf>,
    /// Use the CPU (software) adapter.
    #[arg(long)]
    pub cpu: bool,
}

fn parse_sky_model_kind(s: &str) -> Result<SkyModelKind, String> {
    SkyModelKind::from_name(s).ok_or_else(|| format!("expected one of {}", SkyModelKind::ALL.map(|k| k.name()).join(", ")))
}

/// Sky models `radiance` can evaluate: every physical one (`reference` and `cells` on the CPU;
/// `preetham` and `hosek` on the GPU, or with `--on-cpu` their CPU evaluations; `linear` in
/// display values, the time of day from the sun's elevation on an equinox morning).
pub const RADIANCE_MODELS: &[SkyModelKind] = &[
    SkyModelKind::Reference,
    SkyModelKind::Single,
    SkyModelKind::Lut,
    SkyModelKind::Precomputed,
    SkyModelKind::Cells,
    SkyModelKind::Preetham,
    SkyModelKind::Hosek,
    SkyModelKind::Linear,
];

/// Sky models `validate` compares with measured skies, in the order it fits them (`reference`
/// is searched near `lut`'s fit): turbidity fitted for the analytic ones, the aerosol optical
/// depth for the physical ones.
pub const VALIDATE_MODELS: &[SkyModelKind] = &[SkyModelKind::Preetham, SkyModelKind::Hosek, SkyModelKind::Single, SkyModelKind::Lut, SkyModelKind::Reference];

/// Sky models `bake` can bake from, each with the sky file's settings.
pub const BAKE_MODELS: &[SkyModelKind] = &[SkyModelKind::Single, SkyModelKind::Lut, SkyModelKind::Precomputed, SkyModelKind::Cells, SkyModelKind::Preetham, SkyModelKind::Hosek];

/// A `--model` parser: the sky file's model names (one enum, [`SkyModelKind`]), those of `allowed` only.
fn model_among(allowed: &'static [SkyModelKind]) -> impl clap::builder::TypedValueParser<Value = SkyModelKind> {
    use clap::builder::TypedValueParser as _;
    clap::builder::PossibleValuesParser::new(allowed.iter().map(|k| k.name())).try_map(|s: String| parse_sky_model_kind(&s))
}

fn parse_aerosol(s: &str) -> Result<skytune::atmosphere::aerosol::AerosolPreset, String> {
    use skytune::atmosphere::aerosol::AerosolPreset;
    AerosolPreset::ALL.into_iter().find(|p| p.name() == s).ok_or_else(|| format!("expected one of {}", AerosolPreset::ALL.map(|p| p.name()).join(", ")))
}

/// `radiance` arguments.
#[derive(Debug, Args, Clone)]
pub struct RadianceArgs {
    /// Model to evaluate ([`RADIANCE_MODELS`]).
    #[arg(long, default_value = "reference", value_parser = model_among(RADIANCE_MODELS))]
    pub model: SkyModelKind,
    /// Input CSV: camera_km,albedo,sun_elev_deg,view_elev_deg,rel_azimuth_deg.
    #[arg(long)]
    pub cases: PathBuf,
    /// Output CSV: the input columns plus r,g,b in sr^-1 per unit of solar irradiance.
    #[arg(long)]
    pub out: PathBuf,
    /// Take the atmosphere, the camera's altitude and the ground albedo from this sky file (its
    /// atmosphere at `--weather`): they replace the cases' camera_km and albedo columns.
    #[arg(long)]
    pub sky: Option<PathBuf>,
    /// With `--sky`: the weather, 0 (clear) .. 1 (storm).
    #[arg(long, default_value_t = 0.0, requires = "sky")]
    pub weather: f64,
    /// One key of the atmosphere as a sky file's `[atmosphere]` writes it, over the sky's (or
    /// the default) atmosphere; repeatable: `--atmosphere mie_scattering_per_km=0.02`.
    #[arg(long = "atmosphere", value_name = "KEY=VALUE")]
    pub atmosphere: Vec<String>,
    /// Highest order of scattering (1: single scattering).
    #[arg(long, default_value_t = 24)]
    pub max_order: u32,
    /// Monte Carlo paths per case for orders >= 2 (the reference's noise falls as 1/sqrt); with
    /// `--target-se`, the most a case may draw.
    #[arg(long, default_value_t = 8192)]
    pub paths: u32,
    /// Draw paths in fixed batches until every channel's standard error is at most this
    /// fraction of its radiance (0.005: 0.5%), or `--paths` are drawn; the `paths` column says
    /// how many each case used.
    #[arg(long, value_parser = parse_target_se)]
    pub target_se: Option<f64>,
    /// Seed of the reference's paths.
    #[arg(long, default_value_t = 0x5eed)]
    pub seed: u64,
    /// Only every N-th case from the K-th (K/N, or `auto` from a Slurm job array or a
    /// Kubernetes indexed Job: docs/batch.md); `skytune merge` combines the shards' files.
    #[arg(long)]
    pub shard: Option<Shard>,
    /// Finite rays (a `distance_km` column): `exact` marches each ray (`lut` only), `volume`
    /// reads the renderer's aerial-perspective volume (every physical model but `linear`;
    /// `lut`'s default is `exact`, the others' `volume`).
    #[arg(long, value_enum)]
    pub aerial: Option<AerialArg>,
    /// With the volume: cells across, down and in depth, AxBxC (default: `[aerial_perspective]`'s).
    #[arg(long, value_parser = parse_volume_size)]
    pub volume_size: Option<[u32; 3]>,
    /// With the volume: where its last slice ends, km (default: `[aerial_perspective]`'s).
    #[arg(long)]
    pub volume_distance_km: Option<f64>,
    /// `single` and `lut`: samples along the view ray.
    #[arg(long, default_value_t = 32)]
    pub view_steps: u32,
    /// `lut`: transmittance table, WIDTHxHEIGHT texels.
    #[arg(long, default_value = "256x64")]
    pub transmittance_size: String,
    /// `lut`: multiple-scattering table side, texels.
    #[arg(long, default_value_t = 32)]
    pub multiscattering_size: u32,
    /// `lut`: the multiple-scattering integral uses GRID polar bands x GRID azimuths over the half sphere (mirrored: GRID x 2 GRID over the sphere).
    #[arg(long, default_value_t = 8)]
    pub multiscattering_grid: u32,
    /// `cells`: refinement iterations (0: single scattering).
    #[arg(long, default_value_t = 6)]
    pub iterations: usize,
    /// `single`: samples towards the sun (numerical optical depth).
    #[arg(long, default_value_t = 16)]
    pub sun_steps: u32,
    /// `single`: how the optical depth towards the sun is found.
    #[arg(long, value_enum, default_value = "erf")]
    pub optical_depth: OpticalDepthArg,
    /// Force the software adapter (lavapipe) for GPU models.
    #[arg(long)]
    pub cpu: bool,
    /// `preetham`, `hosek`: atmospheric turbidity (clamped into each model's domain).
    #[arg(long, default_value_t = skytune::atmosphere::analytic::DEFAULT_TURBIDITY)]
    pub turbidity: f64,
    /// `preetham`, `hosek`: radiance in the model's published unit instead of the calibrated
    /// one (the physical models' unit, which rendering uses by default).
    #[arg(long)]
    pub published_units: bool,
    /// `linear`: parameter table of the paper (snow, desert, forest).
    #[arg(long, default_value = "snow")]
    pub preset: String,
    /// `preetham`, `hosek`, `linear`: evaluate on the CPU (double precision; the crate's for hosek).
    #[arg(long)]
    pub on_cpu: bool,
    /// `precomputed`: scattering orders computed (1: single scattering alone; from 3, the orders above are added as a geometric series).
    #[arg(long, default_value_t = skytune::atmosphere::PrecomputedSettings::default().orders)]
    pub orders: u32,
    /// `precomputed`: scattering table texels along nu, mu_s, mu and r, e.g. 8,32,128,32.
    #[arg(long, value_parser = parse_scattering_size)]
    pub scattering_size: Option<[u32; 4]>,
    /// `precomputed`: directions per half turn of the scattering-density integral.
    #[arg(long, default_value_t = skytune::atmosphere::PrecomputedSettings::default().density_directions)]
    pub density_directions: u32,
    /// `precomputed`: storage of the looked-up tables, single or half.
    #[arg(long, default_value_t = skytune::atmosphere::TablePrecision::default())]
    pub precision: skytune::atmosphere::TablePrecision,
}

/// Which frame to render.
#[derive(Debug, Args, Clone)]
pub struct FrameArgs {
    /// Time of day, game hours.
    #[arg(long, default_value_t = 12.0)]
    pub hour: f32,
    /// Weather, 0 (clear) .. 1 (storm).
    #[arg(long, default_value_t = 0.0)]
    pub weather: f32,
    /// Season, for continent files: spring, summer, autumn, winter.
    #[arg(long)]
    pub season: Option<String>,
    /// GPU tier to emulate: texture stages available (4, 2 or 1).
    #[arg(long, default_value_t = 4)]
    pub tier: u8,
    /// Preset view: south, east, west, north, zenith.
    #[arg(long, default_value = "south")]
    pub view: String,
    /// Override the view's compass direction, degrees.
    #[arg(long)]
    pub yaw: Option<f32>,
    /// Override the view's elevation, degrees.
    #[arg(long)]
    pub pitch: Option<f32>,
    /// Vertical field of view, degrees.
    #[arg(long, default_value_t = 70.0)]
    pub fov: f32,
    /// Hide the main-scene stand-in (sky only).
    #[arg(long)]
    pub no_scene: bool,
    /// Resolution of the dome layers: full, half, quarter, or auto (each run of layers in the
    /// coarsest buffer, from half the width and height to an eighth in steps of a quarter pixel,
    /// that still resolves its textures). Layers with finer texture detail than a
    /// half-resolution buffer stay at full resolution (with auto, alpha-blended ones go whole to
    /// a buffer from 1.5 to 2 where one resolves them). Default: the fill strategy's.
    #[arg(long, value_parser = parse_dome_resolution)]
    pub dome_resolution: Option<skytune::render::DomeResolution>,
    /// Fill strategy preset: software (every trick tuned for CPU rasterisers), plain (dome layers
    /// at full resolution, drawn one by one), or a variant of software that turns one trick off
    /// (docs/architecture.md). Default: the adapter's (software on a CPU adapter).
    #[arg(long, value_parser = parse_strategy())]
    pub strategy: Option<skytune::render::plan::strategy::FillStrategy>,
    /// Render what the environment map sees (objects with visible_in_env_map): light from the sky
    /// only, without the glare and the main scene's stand-in.
    #[arg(long)]
    pub env_map: bool,
    /// With --env-map: keep the main scene's stand-in (its horizon).
    #[arg(long)]
    pub with_scene: bool,
    /// Colour source of the skydome instead of the sky file's (a sky file's `[sky_model] kind`, `auto` aside).
    #[arg(long, value_parser = parse_sky_model_kind)]
    pub sky_model: Option<skytune::sky::resolved::SkyModelKind>,
    /// Exposure of physical sky models, stops (default: the sky file's).
    #[arg(long)]
    pub exposure_ev: Option<f32>,
    /// Physical sky models: expose for the sky's mean luminance (--exposure-ev compensates, default 0).
    #[arg(long)]
    pub auto_exposure: bool,
    /// Physical sky models: light the main scene (fog, ambient, sun) from the model.
    #[arg(long)]
    pub drive_scene: bool,
    /// Force the software adapter (lavapipe).
    #[arg(long)]
    pub cpu: bool,
}

/// `render` and `watch` arguments.
#[derive(Debug, Args, Clone)]
pub struct RenderArgs {
    /// Sky or continent file (default: the built-in sky).
    pub sky: Option<PathBuf>,
    /// Frame settings.
    #[command(flatten)]
    pub frame: FrameArgs,
    /// Image size, WIDTHxHEIGHT.
    #[arg(long, default_value = "1280x720")]
    pub size: String,
    /// Output PNG.
    #[arg(long, short, default_value = "shot.png")]
    pub out: PathBuf,
    /// File format: png (display values), exr or hdr (linear light); default from --out's extension.
    #[arg(long, value_enum)]
    pub format: Option<ExportFormat>,
    /// With --env-map: write an environment map instead of a view (equirect: one 2:1 image of
    /// --size; cube: six faces OUT_px .. OUT_nz, each as tall as --size).
    #[arg(long, value_enum)]
    pub projection: Option<Projection>,
}

/// File format of `render`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ExportFormat {
    /// 8-bit sRGB display values.
    Png,
    /// OpenEXR, 32-bit float linear light.
    Exr,
    /// Radiance RGBE, linear light.
    Hdr,
}

/// Environment-map projection of `render --env-map`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Projection {
    /// Equirectangular (latitude-longitude), north in the middle, east to its right.
    Equirect,
    /// Six cube faces.
    Cube,
}

/// Window options.
#[derive(Debug, Args, Clone, Default)]
pub struct AppArgs {
    /// Open the curve editor on this colour bitmap of the sky (its path, or its name next to the
    /// sky file).
    #[arg(long)]
    pub edit: Option<PathBuf>,
    /// Exit after rendering this many frames.
    #[arg(long)]
    pub frames: Option<u64>,
    /// Take a screenshot after the first frames, then exit.
    #[arg(long)]
    pub screenshot_and_exit: bool,
    /// Folder for screenshots (default: ./shots).
    #[arg(long)]
    pub shots: Option<PathBuf>,
    /// Season, for continent files.
    #[arg(long)]
    pub season: Option<String>,
    /// GPU tier to start with (4, 2 or 1).
    #[arg(long)]
    pub tier: Option<u8>,
    /// Force the software adapter (lavapipe).
    #[arg(long)]
    pub cpu: bool,
    /// Read shaders from this folder and hot-reload them (default: the checkout's shaders/, if any).
    #[arg(long)]
    pub shader_dir: Option<PathBuf>,
    /// Soak the window: random hour, weather, tier, view and model every frame, the sky file (a
    /// temporary copy) rewritten every 100 frames alternating good and broken, shaders rebuilt
    /// every 500; memory logged every 100 frames. Use with --frames.
    #[arg(long)]
    pub soak: bool,
    /// Open the compare view with B: last-good, model=NAME, tier=N, hour=H, weather=W or snapshot=NAME.
    #[arg(long)]
    pub compare: Option<String>,
    /// Time of day to start at, game hours (default 17.5).
    #[arg(long)]
    pub hour: Option<f32>,
    /// Weather to start at, 0 (clear) .. 1 (storm) (default 0.1).
    #[arg(long)]
    pub weather: Option<f32>,
    /// Preset view to start with: south (default), east, west, north, zenith.
    #[arg(long)]
    pub view: Option<String>,
    /// Fill strategy preset to start with (default: the adapter's; the diagnostics panel switches
    /// it).
    #[arg(long, value_parser = parse_strategy())]
    pub strategy: Option<skytune::render::plan::strategy::FillStrategy>,
}

/// `bench` and its subcommands.
#[derive(Debug, Args, Clone)]
#[command(args_conflicts_with_subcommands = true)]
pub struct BenchCommand {
    /// What to measure (none: the sky passes).
    #[command(subcommand)]
    pub what: Option<BenchWhat>,
    /// Settings of the sky-pass benchmark.
    #[command(flatten)]
    pub args: BenchArgs,
}

/// Benchmarks besides the sky passes.
#[derive(Debug, Subcommand, Clone)]
pub enum BenchWhat {
    /// Every sky at several hours, weathers and two views against a full-screen pass sampling one
    /// texture (the fill-rate floor), measured side by side; per-object and CPU costs; reload latency.
    Frame(FrameBenchArgs),
    /// Every sky model at several quality settings: error against the reference over the dome
    /// (sun -10 to 90 degrees, three atmospheres) against GPU cost; CSV, Markdown and charts.
    Models(ModelBenchArgs),
    /// How the reference converges: relative error against paths per regime, reported and
    /// measured against a longer run (docs/reference-convergence.md and its chart).
    Reference(ReferenceBenchArgs),
    /// What aerial perspective costs: frames with the scene's fog, the default volume and the
    /// exact march side by side with the fill-rate floor, and the volume's build per size.
    Aerial(AerialBenchArgs),
}

/// `bench aerial` arguments.
#[derive(Debug, Args, Clone)]
pub struct AerialBenchArgs {
    /// Measured frames per case (after 2 warm-up frames).
    #[arg(long, default_value_t = 15)]
    pub frames: u32,
    /// Image size, WIDTHxHEIGHT.
    #[arg(long, default_value = "1280x720")]
    pub size: String,
    /// Markdown report to write.
    #[arg(long)]
    pub out: PathBuf,
    /// Volume sizes whose build is timed, comma-separated ACROSSxDOWNxDEPTH.
    #[arg(long, value_delimiter = ',', default_value = "16x16x16,16x32x32,32x32x32,64x64x64", value_parser = parse_volume_size)]
    pub sizes: Vec<[u32; 3]>,
    /// View-ray samples per slice of every volume (default: `[aerial_perspective]`'s).
    #[arg(long)]
    pub steps_per_slice: Option<u32>,
    /// Force the software adapter (lavapipe).
    #[arg(long)]
    pub cpu: bool,
}

/// `bench reference` arguments.
#[derive(Debug, Args, Clone)]
pub struct ReferenceBenchArgs {
    /// Path counts to measure, comma-separated.
    #[arg(long, default_value = "256,1024,4096")]
    pub paths: String,
    /// Paths of the long run every count is compared with (another seed).
    #[arg(long, default_value_t = 16384)]
    pub long: u32,
    /// Seed of the measured runs.
    #[arg(long, default_value_t = 0x5eed)]
    pub seed: u64,
    /// Folder of reference-convergence.md, .svg and .png.
    #[arg(long, default_value = "docs")]
    pub out: PathBuf,
}

/// `bake` arguments.
#[derive(Debug, Args, Clone)]
pub struct BakeArgs {
    /// The skies whose sun paths and atmospheres are baked (default: the built-in sky). With
    /// more than one, `--out` holds one folder per sky, named after the sky's folder.
    pub skies: Vec<PathBuf>,
    /// The model to bake from.
    #[arg(long, default_value = "lut", value_parser = model_among(BAKE_MODELS))]
    pub model: SkyModelKind,
    /// Gradient rows (zenith to 10 degrees below the horizon).
    #[arg(long, default_value_t = 32)]
    pub rows: usize,
    /// Weather steps (one gradient bitmap each).
    #[arg(long, default_value_t = 3)]
    pub weathers: usize,
    /// Folder to write (sky.toml and its bitmaps; with several skies, a folder per sky in it).
    #[arg(long)]
    pub out: PathBuf,
    /// Only every N-th sky from the K-th (K/N or `auto`): each shard writes its skies' folders,
    /// complete, so the shards' outputs together are the unsharded run's and need no merge.
    #[arg(long)]
    pub shard: Option<Shard>,
    /// Force the software adapter (lavapipe).
    #[arg(long)]
    pub cpu: bool,
}

/// `sweep` arguments.
#[derive(Debug, Args, Clone)]
pub struct SweepArgs {
    /// Random parameter sets per model (each evaluated twice, the sun moved between).
    #[arg(long, default_value_t = 100_000)]
    pub count: usize,
    /// Seed of the parameter sets (the same seed gives the same sets).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Markdown report to write (with `--shard`: the shard's counts, a .toml file).
    #[arg(long, default_value = "docs/stability.md")]
    pub out: PathBuf,
    /// Only every N-th atmosphere from the K-th (K/N or `auto`); `skytune merge` writes the report.
    #[arg(long)]
    pub shard: Option<Shard>,
    /// Force the software adapter (lavapipe).
    #[arg(long)]
    pub cpu: bool,
}

/// What a shard of `bench models` computes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum BenchPart {
    /// Its directions of the reference dome.
    Reference,
    /// Its points' errors against the reference, per atmosphere and sun elevation.
    Errors,
}

/// `bench models` arguments.
#[derive(Debug, Args, Clone)]
pub struct ModelBenchArgs {
    /// Few settings, one atmosphere, five sun elevations, few frames (CI: well under 5 minutes).
    #[arg(long)]
    pub quick: bool,
    /// Measured frames per model for the cost (after 2 warm-up frames).
    #[arg(long, default_value_t = 9)]
    pub frames: u32,
    /// Frame size of the cost measurement, WIDTHxHEIGHT.
    #[arg(long, default_value = "1280x720")]
    pub size: String,
    /// Folder the report, the CSV and the charts are written to (models.md, models.csv,
    /// models-by-sun.csv, models-cost.svg/png, models-by-sun.svg/png).
    #[arg(long, default_value = "docs")]
    pub out: PathBuf,
    /// The reference's radiance over the dome (computed and written when missing or stale).
    #[arg(long, default_value = "assets/reference_dome.csv")]
    pub reference: PathBuf,
    /// Monte Carlo paths per direction of the reference (with `--target-se`, the most).
    #[arg(long, default_value_t = skytune::atmosphere::dome::COMMITTED_PATHS)]
    pub paths: u32,
    /// The reference's target relative standard error per direction (see `radiance`).
    #[arg(long, value_parser = parse_target_se, default_value_t = skytune::atmosphere::dome::COMMITTED_TARGET_SE)]
    pub target_se: f64,
    /// Compute only the K-th of N shards (K/N or `auto`) of `--part`; `skytune merge` combines
    /// them. The costs are not sharded: they compare only within one run on one machine.
    #[arg(long)]
    pub shard: Option<Shard>,
    /// What `--shard` computes: the reference dome (written to `--out`, a .csv, merged into
    /// `--reference`), or the points' errors against it (`--out` a folder holding
    /// models-by-sun.csv, merged folder by folder into the unsharded run's file).
    #[arg(long, value_enum, default_value = "reference")]
    pub part: BenchPart,
    /// Force the software adapter (lavapipe).
    #[arg(long)]
    pub cpu: bool,
}

/// `bench frame` arguments.
#[derive(Debug, Args, Clone)]
pub struct FrameBenchArgs {
    /// Measured frames per case (after 2 warm-up frames).
    #[arg(long, default_value_t = 9)]
    pub frames: u32,
    /// Image size, WIDTHxHEIGHT.
    #[arg(long, default_value = "1280x720")]
    pub size: String,
    /// Folder of the skies to measure besides the built-in one (each SUBFOLDER/sky.toml).
    #[arg(long, default_value = "skies")]
    pub skies: PathBuf,
    /// Markdown report to write.
    #[arg(long, default_value = "docs/performance.md")]
    pub out: PathBuf,
    /// Few frames at a small size (CI).
    #[arg(long)]
    pub quick: bool,
    /// Force the software adapter (lavapipe).
    #[arg(long)]
    pub cpu: bool,
    /// Resolution of the dome layers, overriding each strategy's: full, half, quarter or auto.
    #[arg(long, value_parser = parse_dome_resolution)]
    pub dome_resolution: Option<skytune::render::DomeResolution>,
    /// Measure only these fill strategy presets (comma-separated); software and plain by default,
    /// side by side.
    #[arg(long, value_parser = parse_strategy(), value_delimiter = ',')]
    pub strategy: Vec<skytune::render::plan::strategy::FillStrategy>,
    /// Also measure every sky with these skydome colour sources (comma-separated `[sky_model]`
    /// kinds, e.g. `bitmap,lut,precomputed`), besides its own; physical cases are reported
    /// against the same sky's bitmap case (`precomputed` with its small tables, waited for).
    #[arg(long, value_parser = parse_sky_model_kind, value_delimiter = ',')]
    pub sky_models: Vec<skytune::sky::resolved::SkyModelKind>,
}

/// Parses a fill strategy preset by name; clap lists the names in the help and in its errors.
fn parse_strategy() -> impl clap::builder::TypedValueParser<Value = skytune::render::plan::strategy::FillStrategy> {
    use clap::builder::TypedValueParser as _;
    use skytune::render::plan::strategy::{FillStrategy, PRESETS};
    clap::builder::PossibleValuesParser::new(PRESETS.map(|(name, _)| name)).try_map(|name: String| FillStrategy::preset_arg(&name))
}

/// Parses a dome resolution name (full, half, quarter, auto).
pub fn parse_dome_resolution(s: &str) -> Result<skytune::render::DomeResolution, String> {
    skytune::render::DomeResolution::parse(s).ok_or_else(|| format!("unknown dome resolution {s:?}: full, half, quarter or auto"))
}

/// `bench` arguments.
#[derive(Debug, Args, Clone)]
pub struct BenchArgs {
    /// Frames per measured configuration.
    #[arg(long, default_value_t = 15)]
    pub frames: u32,
    /// Image size, WIDTHxHEIGHT.
    #[arg(long, default_value = "960x540")]
    pub size: String,
    /// Markdown report to write.
    #[arg(long, default_value = "docs/benchmarks.md")]
    pub out: PathBuf,
    /// Force the software adapter (lavapipe).
    #[arg(long)]
    pub cpu: bool,
}

/// Parses `WIDTHxHEIGHT`.
pub fn parse_size(s: &str) -> anyhow::Result<(u32, u32)> {
    let (w, h) = s.split_once('x').ok_or_else(|| anyhow::anyhow!("--size: expected WIDTHxHEIGHT, found \"{s}\""))?;
    let (w, h): (u32, u32) = (w.trim().parse()?, h.trim().parse()?);
    anyhow::ensure!((1..=8192).contains(&w) && (1..=8192).contains(&h), "--size: sides must be in 1..=8192, found {w}x{h}");
    Ok((w, h))
}

/// A `--target-se` value: a fraction in (0, 1).
fn parse_target_se(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v > 0.0 && v < 1.0 => Ok(v),
        _ => Err(format!("expected a relative standard error between 0 and 1 (0.005 for 0.5%), found \"{s}\"")),
    }
}

fn parse_scattering_size(s: &str) -> Result<[u32; 4], String> {
    let bad = || format!("expected four texel counts nu,mu_s,mu,r such as 8,32,128,32, found \"{s}\"");
    let v: Vec<u32> = s.split(',').map(|x| x.trim().parse::<u32>()).collect::<Result<_, _>>().map_err(|_| bad())?;
    v.try_into().map_err(|_| bad())
}
