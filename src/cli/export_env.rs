//! `skytune export-env`: what an engine needs to light a scene with the sky of one moment, or of
//! every hour of a day: the unfiltered map (EXR), a GGX-prefiltered specular cube map and a
//! diffuse irradiance cube map (KTX2, RGBA16F), the irradiance's spherical harmonics (JSON) and
//! the sun (JSON). docs/export.md shows how engines load them.

use std::path::{Path, PathBuf};

use anyhow::{anyhow, Context as _};
use glam::Vec3;

use super::{ExportEnvArgs, Projection};
use skytune::files::env_light;
use skytune::files::export::{self, Format, LinearImage};
use skytune::render::{GpuContext, Headless, RenderOptions};
use skytune::sky::Sky;
use skytune::support::safe_write::write_atomic;

/// Runs `skytune export-env`.
pub fn run(args: &ExportEnvArgs) -> anyhow::Result<()> {
    anyhow::ensure!(args.size.is_power_of_two() && (8..=2048).contains(&args.size), "--size: expected a power of two from 8 to 2048, found {}", args.size);
    anyhow::ensure!((1..=256).contains(&args.irradiance_size), "--irradiance-size: expected 1..=256, found {}", args.irradiance_size);
    let levels = args.levels.unwrap_or(args.size.trailing_zeros().saturating_sub(1) as usize).max(1);
    anyhow::ensure!(levels <= args.size.trailing_zeros() as usize + 1, "--levels: a {} face has at most {} levels", args.size, args.size.trailing_zeros() + 1);
    let hours = match &args.hours {
        Some(range) => parse_hours(range)?,
        None => vec![args.frame.hour],
    };
    let shard = args.shard.unwrap_or(skytune::support::shard::Shard::WHOLE);
    let hours = shard.take(&hours);
    let spec = crate::spec_for(args.sky.as_deref(), args.frame.season.as_deref())?;
    let mut sky = spec.load().map_err(|e| anyhow!("{e}"))?;
    let ctx = GpuContext::headless(crate::adapter(args.frame.cpu))?;
    println!("adapter: {}", ctx.adapter_line());
    if let Some(pick) = skytune::support::progress::run_reported("auto model", |job| skytune::measure::auto_model::resolve(&mut sky, &ctx, job))? {
        println!("{}", pick.describe());
    }
    let strategy = crate::strategy_from_args(&args.frame, &ctx)?;
    let mut headless = Headless::new(ctx, args.size, args.size)?;
    headless.set_sky(&sky)?;
    let options = RenderOptions { strategy, ..Default::default() }.for_environment_map(args.frame.with_scene);
    std::fs::create_dir_all(&args.out).with_context(|| format!("creating {}", args.out.display()))?;
    for hour in hours {
        let dir = if args.hours.is_some() { args.out.join(format!("hour-{hour:05.2}")) } else { args.out.clone() };
        std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
        export_one(&mut headless, &sky, args, hour, levels, &options, &dir)?;
    }
    Ok(())
}

/// `FROM:TO:STEP` game hours, TO excluded.
fn parse_hours(range: &str) -> anyhow::Result<Vec<f32>> {
    let parts: Vec<f32> = range.split(':').map(|p| p.trim().parse::<f32>()).collect::<Result<_, _>>().map_err(|_| anyhow!("--hours: expected FROM:TO:STEP, found \"{range}\""))?;
    let [from, to, step] = parts[..] else { anyhow::bail!("--hours: expected FROM:TO:STEP, found \"{range}\"") };
    anyhow::ensure!(step > 0.0 && to > from && ((to - from) / step) <= 1000.0, "--hours: expected FROM < TO and a STEP > 0 giving at most 1000 hours, found \"{range}\"");
    Ok((0..).map(|k| from + k as f32 * step).take_while(|h| *h < to - step * 1e-3).collect())
}

fn export_one(headless: &mut Headless, sky: &Sky, args: &ExportEnvArgs, hour: f32, levels: usize, options: &RenderOptions, dir: &Path) -> anyhow::Result<()> {
    let started = std::time::Instant::now();
    let mut input = skytune::sky::FrameInput::new(hour, args.frame.weather);
    input.env_map = true;
    input.sky_model = crate::model_override(sky, &args.frame)?;
    let faces = export::cube_faces(headless, sky, &input, options, args.size, true)?;
    let mut written: Vec<PathBuf> = Vec::new();
    match args.projection {
        Projection::Cube => {
            for ((suffix, _, _), face) in export::CUBE_FACES.iter().zip(&faces) {
                let path = dir.join(format!("env_{suffix}.exr"));
                export::save(face, Format::Exr, &path)?;
                written.push(path);
            }
        }
        Projection::Equirect => {
            let path = dir.join("env.exr");
            export::save(&export::equirect_from_cube(&faces, 4 * args.size, 2 * args.size), Format::Exr, &path)?;
            written.push(path);
        }
    }
    let writer = format!("skytune {}", env!("CARGO_PKG_VERSION"));
    let chain: Vec<Vec<LinearImage>> = env_light::prefilter_ggx(&faces, levels, args.samples).iter().map(|l| skytune::files::ktx2::to_vulkan_faces(l, args.mirror_z)).collect();
    let specular = dir.join("specular.ktx2");
    write_atomic(&specular, &skytune::files::ktx2::cube_map_rgba16f(&chain, &writer))?;
    written.push(specular);
    let irradiance = skytune::files::ktx2::to_vulkan_faces(&env_light::irradiance_cube(&faces, args.irradiance_size), args.mirror_z);
    let diffuse = dir.join("diffuse.ktx2");
    write_atomic(&diffuse, &skytune::files::ktx2::cube_map_rgba16f(&[irradiance], &writer))?;
    written.push(diffuse);
    let sh = env_light::sh9(&faces);
    let sh_path = dir.join("sh.json");
    write_atomic(&sh_path, sh_json(&sh).as_bytes())?;
    written.push(sh_path);
    let sun_path = dir.join("sun.json");
    write_atomic(&sun_path, sun_json(sky, &input).as_bytes())?;
    written.push(sun_path);
    let names: Vec<String> = written.iter().map(|p| p.file_name().map_or_else(String::new, |n| n.to_string_lossy().into_owned())).collect();
    println!("hour {hour}: wrote {} in {} ({:.1} s): {}", names.len(), dir.display(), started.elapsed().as_secs_f64(), names.join(", "));
    Ok(())
}

/// The sky's moons above the horizon (objects with `lighting = "moon"` seen in environment
/// maps): direction, angular radius and display colour. The bitmap sky gives them no physical
/// brightness.
fn moons_json(sky: &Sky, frame: &skytune::sky::FrameSky) -> String {
    let mut out = Vec::new();
    for o in &frame.objects {
        let object = &sky.objects[o.index];
        let v = &object.standard;
        let (Some((towards, _)), Ok(versions)) = (o.placement, &o.versions) else { continue };
        let size_deg = match v.shape {
            skytune::sky::model::Shape::Billboard { size_deg } | skytune::sky::model::Shape::Quad { size_deg } => f64::from(size_deg.get()),
            _ => continue,
        };
        if v.lighting != skytune::sky::model::Lighting::Moon || !object.visible_in_env_map || towards.y <= 0.0 {
            continue;
        }
        let d = towards.normalize();
        let c = versions.first().map_or([1.0; 4], |f| f.diffuse);
        out.push(format!(
            "\n    {{\"name\": \"{}\", \"towards\": [{:.6}, {:.6}, {:.6}], \"elevation_deg\": {:.4}, \"angular_radius_rad\": {:.6}, \"color\": {}}}",
            object.name.replace('"', "'"),
            d.x,
            d.y,
            d.z,
            d.y.asin().to_degrees(),
            (size_deg / 2.0).to_radians(),
            json_rgb([c[0], c[1], c[2]].map(|v| skytune::atmosphere::dome::srgb_decode(f64::from(v.clamp(0.0, 1.0)))))
        ));
    }
    if out.is_empty() {
        String::new()
    } else {
        format!("{}\n  ", out.join(","))
    }
}

fn json_rgb(c: [f64; 3]) -> String {
    format!("[{:.6e}, {:.6e}, {:.6e}]", c[0], c[1], c[2])
}

fn sh_json(sh: &[[f32; 3]; 9]) -> String {
    let rows: Vec<String> = sh.iter().map(|c| format!("    {}", json_rgb(c.map(f64::from)))).collect();
    format!(
        "{{\n  \"about\": \"order-2 real spherical harmonics of the sky's radiance (the unfiltered map), 9 rgb coefficients; basis order and constants: Y00 0.282095; Y1-1 0.488603 y; Y10 0.488603 z; Y11 0.488603 x; Y2-2 1.092548 xy; Y2-1 1.092548 yz; Y20 0.315392 (3z^2 - 1); Y21 1.092548 xz; Y22 0.546274 (x^2 - y^2); world axes x east, y up, z south. Irradiance: multiply band 0 by pi, band 1 by 2pi/3, band 2 by pi/4 (Ramamoorthi and Hanrahan 2001)\",\n  \"coefficients\": [\n{}\n  ]\n}}\n",
        rows.join(",\n")
    )
}

/// The sun of the frame: direction, size, and colour and irradiance after the atmosphere in the
/// maps' units.
fn sun_json(sky: &Sky, input: &skytune::sky::FrameInput) -> String {
    let frame = sky.evaluate(input);
    let d: Vec3 = frame.towards_sun.normalize();
    let elevation = d.y.clamp(-1.0, 1.0).asin().to_degrees();
    let azimuth = d.x.atan2(-d.z).to_degrees().rem_euclid(360.0);
    let atm = frame.atmosphere;
    let (irradiance, units) = if frame.sky_model.kind.is_physical() {
        let camera_km = f64::from(frame.sky_model.world.camera_km);
        let tau = skytune::atmosphere::reference::Reference::new(atm, Default::default()).optical_depth(camera_km, f64::from(elevation));
        (
            tau.map(|t| if t.is_finite() { (-t).exp() } else { 0.0 }),
            "irradiance per unit of solar irradiance at the top of the atmosphere (the maps' radiance is sr^-1 in the same unit)",
        )
    } else {
        let c = frame.sun_diffuse;
        (
            [c[0], c[1], c[2]].map(|v| skytune::atmosphere::dome::srgb_decode(f64::from(v.clamp(0.0, 1.0)))),
            "display-linear: the sky's sun diffuse colour (the NeL bitmap model has no physical unit)",
        )
    };
    let moons = moons_json(sky, &frame);
    let peak = irradiance.iter().cloned().fold(0.0, f64::max);
    let colour = if peak > 0.0 { irradiance.map(|c| c / peak) } else { [0.0; 3] };
    let illuminance = 0.2126 * irradiance[0] + 0.7152 * irradiance[1] + 0.0722 * irradiance[2];
    format!(
        "{{\n  \"hour\": {},\n  \"weather\": {},\n  \"towards_sun\": [{:.6}, {:.6}, {:.6}],\n  \"axes\": \"x east, y up, z south (north is -z)\",\n  \"elevation_deg\": {elevation:.4},\n  \"azimuth_deg\": {azimuth:.4},\n  \"above_horizon\": {},\n  \"angular_radius_rad\": {},\n  \"color\": {},\n  \"irradiance\": {},\n  \"illuminance\": {illuminance:.6e},\n  \"units\": \"{units}\",\n  \"moons\": [{moons}]\n}}\n",
        input.hour,
        input.weather,
        d.x,
        d.y,
        d.z,
        elevation > 0.0,
        atm.sun_angular_radius_rad,
        json_rgb(colour),
        json_rgb(irradiance)
    )
}
