//! Parsing and validation: good files load, bad ones give located errors and never panic.

mod common;

use skytune::sky::builtin::{default_sky, DEFAULT_SKY_TOML};
use skytune::sky::{load_sky_file, SkyErrors};

/// Writes the default sky with `from` replaced by `to`; returns the errors and the 1-based line of `to`.
fn broken(from: &str, to: &str) -> (SkyErrors, usize, String) {
    let (dir, sky) = common::default_sky_folder();
    let text = DEFAULT_SKY_TOML.replacen(from, to, 1);
    assert_ne!(text, DEFAULT_SKY_TOML, "the replacement must change the file: {from}");
    std::fs::write(&sky, &text).unwrap();
    let errors = load_sky_file(&sky).expect_err("the broken sky must not load");
    let line = text[..text.find(to).unwrap()].matches('\n').count() + 1;
    let file = sky.display().to_string();
    drop(dir);
    (errors, line, file)
}

fn assert_error(errors: &SkyErrors, file: &str, line: usize, field: &str, message: &str) {
    let found = errors.0.iter().any(|e| e.file == file && e.line == line && e.field == field && e.message.contains(message));
    assert!(found, "expected {file}:{line}: {field}: ...{message}...; got:\n{errors}");
}

#[test]
fn builtin_sky_is_valid() {
    let sky = default_sky();
    assert_eq!(sky.name, "Default");
    assert_eq!(sky.objects.len(), 10);
    // Sorted by priority, file order among equals.
    let priorities: Vec<u8> = sky.objects.iter().map(|o| o.priority).collect();
    assert!(priorities.windows(2).all(|w| w[0] <= w[1]), "{priorities:?}");
    assert_eq!(sky.objects[0].name, "skydome");
    assert_eq!(sky.objects.last().unwrap().name, "fog_dome");
}

#[test]
fn written_sky_folder_is_valid_and_lists_its_files() {
    let (_dir, path) = common::default_sky_folder();
    let sky = load_sky_file(&path).unwrap();
    assert!(sky.watched_files.iter().any(|p| p.ends_with("gradient_storm.png")));
    assert!(sky.watched_files.iter().any(|p| p.ends_with("fog.png")));
}

#[test]
fn priority_out_of_range() {
    let (e, line, file) = broken("priority = 20", "priority = 64");
    assert_error(&e, &file, line, "object[9].priority", "expected a priority in 0..=63, found 64");
}

#[test]
fn unknown_field_is_rejected() {
    let (e, line, file) = broken("blend = \"opaque\"", "blennd = \"opaque\"");
    assert_error(&e, &file, line, "object[0].standard.blennd", "unknown field `blennd`, expected one of");
}

#[test]
fn nan_is_rejected() {
    let (e, line, file) = broken("uv_offset_factor = 1.0", "uv_offset_factor = nan");
    assert_error(&e, &file, line, "object[9].standard.stage[0].uv_offset_factor", "expected a finite number");
}

#[test]
fn elevation_out_of_range() {
    let (e, line, file) = broken("{ hour = 12, azimuth_deg = 180, elevation_deg = 60 }", "{ hour = 12, azimuth_deg = 180, elevation_deg = 95 }");
    assert_error(&e, &file, line, "path[0].keys[2].elevation_deg", "within [-90, 90]");
}

#[test]
fn missing_image_names_file_line_and_field() {
    let (e, line, file) = broken("texture = \"galaxy.png\"", "texture = \"galaxxy.png\"");
    assert_error(&e, &file, line, "object[1].standard.stage[0].texture", "galaxxy.png");
}

#[test]
fn missing_path_reference() {
    let (e, line, file) = broken("path = \"small_moon\"", "path = \"tiny_moon\"");
    assert_error(&e, &file, line, "object[4].path", "no path named \"tiny_moon\"");
}

#[test]
fn cyclic_follow_is_an_error() {
    // sun -> (keys) is fine; make planet follow moon and moon follow planet.
    let (dir, sky) = common::default_sky_folder();
    let text = DEFAULT_SKY_TOML.replacen("name = \"moon\"\nfollow = \"sun\"", "name = \"moon\"\nfollow = \"planet\"", 1).replacen(
        "name = \"planet\"\nfollow = \"sun\"",
        "name = \"planet\"\nfollow = \"moon\"",
        1,
    );
    std::fs::write(&sky, &text).unwrap();
    let e = load_sky_file(&sky).unwrap_err();
    let line = text[..text.find("follow = \"planet\"").unwrap()].matches('\n').count() + 1;
    assert_error(&e, &sky.display().to_string(), line, "path[1].follow", "cyclic follow: moon -> planet -> moon");
    drop(dir);
}

#[test]
fn gradient_heights_must_match() {
    let (dir, sky) = common::default_sky_folder();
    image::RgbaImage::new(24, 16).save(dir.path().join("gradient_cloudy.png")).unwrap();
    let e = load_sky_file(&sky).unwrap_err();
    let text = std::fs::read_to_string(&sky).unwrap();
    let line = text[..text.find("weather_gradients = { stage = 0").unwrap()].matches('\n').count() + 1;
    assert_error(&e, &sky.display().to_string(), line, "object[0].standard.weather_gradients.bitmaps[1]", "all weather steps must share a height");
}

#[test]
fn undecodable_image() {
    let (dir, sky) = common::default_sky_folder();
    std::fs::write(dir.path().join("fog.png"), b"not a png").unwrap();
    let e = load_sky_file(&sky).unwrap_err();
    let line = DEFAULT_SKY_TOML.lines().position(|l| l.starts_with("fog_color")).unwrap() + 1;
    assert_error(&e, &sky.display().to_string(), line, "fog_color", "cannot decode");
}

#[test]
fn undefined_constant_and_ref_color() {
    let (e, line, file) =
        broken("ref_color = \"constant0\"\n[[object.standard.stage]]\ntexture = \"galaxy.png\"", "ref_color = \"constant3\"\n[[object.standard.stage]]\ntexture = \"galaxy.png\"");
    assert_error(&e, &file, line, "object[1].standard.ref_color", "constant 3, which is not defined");
}

#[test]
fn syntax_error_has_line_and_column() {
    let (e, line, file) = broken("hours_per_day = 24", "hours_per_day = = 24");
    let err = &e.0[0];
    assert_eq!((err.file.as_str(), err.line, err.field.as_str()), (file.as_str(), line, "<syntax>"), "{e}");
    assert!(err.column > 1);
}

#[test]
fn several_errors_are_reported_together() {
    let (dir, sky) = common::default_sky_folder();
    let text = DEFAULT_SKY_TOML.replacen("texture = \"stars.png\"", "texture = \"nostars.png\"", 1).replacen("texture = \"moon.png\"", "texture = \"nomoon.png\"", 1);
    std::fs::write(&sky, text).unwrap();
    let e = load_sky_file(&sky).unwrap_err();
    assert!(e.0.len() >= 2, "{e}");
    drop(dir);
}

#[test]
fn continent_file_picks_a_sky_per_season() {
    let (dir, _sky) = common::default_sky_folder();
    let c = dir.path().join("continent.toml");
    std::fs::write(&c, "name = \"Test\"\n[seasons]\nspring = \"sky.toml\"\nsummer = \"sky.toml\"\nautumn = \"sky.toml\"\nwinter = \"nosky.toml\"\n").unwrap();
    let e = skytune::sky::load::load_continent(&c).unwrap_err();
    assert_error(&e, &c.display().to_string(), 6, "seasons", "nosky.toml does not exist");
    assert!(skytune::sky::load::is_continent_file(&c));
}

#[test]
fn starfield_respects_magnitude_cutoff() {
    let sky = default_sky();
    let mut stars = sky.stars.clone().unwrap();
    let all = skytune::sky::starfield::generate(&stars);
    assert!(all.iter().all(|s| s.magnitude <= stars.magnitude_cutoff));
    stars.magnitude_cutoff = 3.0;
    let bright = skytune::sky::starfield::generate(&stars);
    // Counts grow ~x3.2 per magnitude: 2.5 magnitudes fewer keeps about 10^(-0.5 * 2.5) = 5.6%.
    let ratio = bright.len() as f64 / all.len() as f64;
    assert!((0.03..0.10).contains(&ratio), "ratio {ratio}");
    assert!(bright.iter().all(|s| s.magnitude <= 3.0));
}

#[test]
fn bad_emitters_are_located() {
    let base = "[[emitter]]\nname = \"sparks\"\nattach = \"sun\"\nrate = 5\nlifetime_s = 1\nmax_particles = 10\n";
    for (from, to, field, message) in [
        ("rate = 5", "rate = -5", "emitter[3].rate", "expected a finite number >= 0, found -5"),
        ("max_particles = 10", "max_particles = 0", "emitter[3].max_particles", "expected a particle cap in 1..=100000"),
        ("max_particles = 10", "max_particles = 1000000", "emitter[3].max_particles", "found 1000000"),
        ("lifetime_s = 1", "lifetime_s = nan", "emitter[3].lifetime_s", "expected a finite number > 0, found NaN"),
        ("attach = \"sun\"", "attach = \"sunn\"", "emitter[3].attach", "no object \"sunn\" to attach to; expected \"camera\" or one of"),
        ("rate = 5", "rate = 5\nspread_deg = 270", "emitter[3].spread_deg", "expected 0..=180 degrees, found 270"),
        ("rate = 5", "rate = 5\nblend = \"opaque\"", "emitter[3].blend", "particles blend as \"alpha\" or \"additive\""),
        ("rate = 5", "rate = 5\nshape = \"square\"", "emitter[3].shape", "unknown variant `square`"),
    ] {
        let section = base.replacen(from, to, 1);
        let (result, file, text) = with_sections(&section);
        let errors = result.expect_err(&section);
        let needle = to.lines().last().unwrap();
        let line = text.rfind(needle).map(|at| text[..at].matches('\n').count() + 1).unwrap();
        assert_error(&errors, &file, line, field, message);
    }
    // A good emitter loads, attached to its object.
    let (result, _, _) = with_sections(base);
    let sky = result.unwrap();
    let e = sky.emitters.iter().find(|e| e.name == "sparks").unwrap();
    assert_eq!(e.attach, skytune::sky::resolved::EmitterAttach::Object(sky.object_index("sun").unwrap()));
}

#[test]
fn unknown_star_source_and_layer_are_located() {
    let (e, line, file) = broken("[stars]\ncount = 6000", "[stars]\nsource = \"hipparcos\"\ncount = 6000");
    assert_error(&e, &file, line + 1, "stars.source", "unknown variant `hipparcos`, expected `procedural` or `catalogue`");
    let (e, line, file) = broken("name = \"galaxy\"", "name = \"galaxy\"\nlayer = \"dusk\"");
    assert_error(&e, &file, line + 1, "object[1].layer", "unknown variant `dusk`, expected `day` or `night`");
}

#[test]
fn bitmap_mode_without_bitmap_points_at_the_owner() {
    let (e, line, file) = broken("diffuse = { mode = \"bitmap\", bitmap = \"clouds_storm.png\" }", "diffuse = { mode = \"bitmap\" }");
    assert_error(&e, &file, line, "object[8].standard.diffuse", "needs a `bitmap`");
}

/// The default sky with `extra` appended; the errors (or the sky), the file and its text.
fn with_sections(extra: &str) -> (Result<skytune::sky::Sky, SkyErrors>, String, String) {
    let (dir, sky) = common::default_sky_folder();
    let text = format!("{DEFAULT_SKY_TOML}\n{extra}");
    std::fs::write(&sky, &text).unwrap();
    let result = load_sky_file(&sky);
    let file = sky.display().to_string();
    drop(dir);
    (result, file, text)
}

fn line_of(text: &str, needle: &str) -> usize {
    text[..text.rfind(needle).unwrap()].matches('\n').count() + 1
}

#[test]
fn sky_model_and_atmosphere_sections_load() {
    let (sky, _, _) = with_sections("[sky_model]\nkind = \"single\"\nexposure_ev = 4.5\ntone_mapper = \"neutral\"\noptical_depth = \"numerical\"\nview_steps = 48\n\n[atmosphere]\nmie_scattering_per_km = 0.02\nmie_extinction_per_km = 0.022\n");
    let sky = sky.unwrap();
    assert_eq!(sky.model.kind, skytune::sky::resolved::SkyModelKind::Single);
    assert_eq!((sky.model.camera.exposure_ev, sky.model.settings.single.view_steps), (4.5, 48));
    assert_eq!(sky.model.settings.single.optical_depth, skytune::atmosphere::OpticalDepth::Numerical);
    assert!((sky.atmosphere.mie_scattering_per_km[2] - 0.02).abs() < 1e-9 && sky.atmosphere.rayleigh_scale_height_km == 8.0);
    // Without the sections: the NeL bitmaps and Earth.
    assert_eq!(default_sky().model, skytune::sky::resolved::SkyModel::default());
}

#[test]
fn bad_sky_model_and_atmosphere_values_are_located() {
    for (extra, needle, field, message) in [
        ("[sky_model]\nkind = \"single\"\nview_steps = 0\n", "view_steps = 0", "sky_model.view_steps", "expected a sample count in 1..=1024, found 0"),
        ("[sky_model]\nview_steps = 1000000\n", "view_steps = 1000000", "sky_model.view_steps", "found 1000000"),
        ("[sky_model]\nkind = \"hosek-wilkie\"\n", "kind = \"hosek-wilkie\"", "sky_model.kind", "unknown model \"hosek-wilkie\"; expected auto, bitmap"),
        ("[sky_model]\nkind = \"preetham\"\nturbidity = 0.5\n", "turbidity = 0.5", "sky_model.turbidity", "expected a turbidity in [1, 10], found 0.5"),
        ("[sky_model]\nkind = \"hosek\"\nturbidity = nan\n", "turbidity = nan", "sky_model.turbidity", "expected a turbidity in [1, 10]"),
        (
            "[sky_model]\nkind = \"linear\"\n[sky_model.linear]\npreset = \"tundra\"\n",
            "preset = \"tundra\"",
            "sky_model.linear.preset",
            "unknown preset \"tundra\"; expected one of snow, desert, forest",
        ),
        (
            "[sky_model]\nkind = \"linear\"\n[sky_model.linear]\nmax = [200, 300, 200]\n",
            "max = [200, 300, 200]",
            "sky_model.linear.max[1]",
            "expected a light factor in [0, 255], found 300",
        ),
        (
            "[sky_model]\nkind = \"linear\"\n[sky_model.linear]\nmin = [100, 100, 100]\nmax = [90, 200, 200]\n",
            "min = [100, 100, 100]",
            "sky_model.linear.min",
            "expected min <= max per channel",
        ),
        (
            "[sky_model]\nkind = \"linear\"\n[sky_model.linear]\nsunrise_hour = 5\nsunset_hour = 7\nramp_hours = 4\n",
            "ramp_hours = 4",
            "sky_model.linear.ramp_hours",
            "ramps of 4 h overlap",
        ),
        ("[atmosphere]\nrayleigh_scale_height_km = nan\n", "rayleigh_scale_height_km = nan", "atmosphere.rayleigh_scale_height_km", "expected a finite number > 0"),
        (
            "[atmosphere]\nmie_scattering_per_km = -1\n",
            "mie_scattering_per_km = -1",
            "atmosphere.mie_scattering_per_km",
            "expected one number >= 0 (grey) or three, [r, g, b], found -1",
        ),
        ("[atmosphere]\nmie_scattering_per_km = [0.01, 0.02]\n", "mie_scattering_per_km = [0.01, 0.02]", "atmosphere.mie_scattering_per_km", "found [0.01, 0.02]"),
        ("[atmosphere]\ntop_radius_km = 6000\n", "top_radius_km = 6000", "atmosphere.top_radius_km", "expected more than ground_radius_km"),
        ("[atmosphere]\nmie_extinction_per_km = 0.001\n", "mie_extinction_per_km = 0.001", "atmosphere.mie_extinction_per_km", "expected at least mie_scattering_per_km"),
        ("[sky_model]\nkind = \"lut\"\nmultiscattering_size = 1000\n", "multiscattering_size = 1000", "sky_model.multiscattering_size", "expected 2..=64 texels, found 1000"),
        ("[sky_model]\nkind = \"lut\"\ntransmittance_size = [1000000, 64]\n", "transmittance_size = [1000000, 64]", "sky_model.transmittance_size[0]", "found 1000000"),
        (
            "[sky_model]\nkind = \"precomputed\"\n[sky_model.precomputed]\nscattering_size = [8, 32, 127, 32]\n",
            "scattering_size = [8, 32, 127, 32]",
            "sky_model.precomputed.scattering_size",
            "an even count of at least 4 along mu, found 8 x 32 x 127 x 32",
        ),
        (
            "[sky_model]\nkind = \"precomputed\"\n[sky_model.precomputed]\nscattering_size = [16, 64, 256, 64]\n",
            "scattering_size = [16, 64, 256, 64]",
            "sky_model.precomputed.scattering_size",
            "more than the 1048576 a table may hold",
        ),
        ("[aerial_perspective]\nvolume_size = [32, 32, 200]\n", "volume_size = [32, 32, 200]", "aerial_perspective.volume_size", "expected 2..=128 cells in depth, found 200"),
        ("[aerial_perspective]\ndistance_km = 20000\n", "distance_km = 20000", "aerial_perspective.distance_km", "expected 0.1..=10000 km, found 20000"),
        ("[aerial_perspective]\nmethod = \"froxels\"\n", "method = \"froxels\"", "aerial_perspective.method", "unknown variant `froxels`"),
    ] {
        let (result, file, text) = with_sections(extra);
        let errors = result.expect_err(extra);
        assert_error(&errors, &file, line_of(&text, needle), field, message);
    }
}

#[test]
fn the_atmosphere_follows_the_weather() {
    let (sky, _, _) = with_sections(
        "[atmosphere]\nrayleigh_scale_height_km = 8.5\n[[atmosphere.weather]]\nmie_scattering_per_km = 0.004\n[[atmosphere.weather]]\nmie_scattering_per_km = 0.02\nmie_extinction_per_km = 0.022\n",
    );
    let sky = sky.unwrap();
    assert_eq!(sky.atmosphere_by_weather.len(), 2);
    let at = |w: f32| sky.evaluate(&skytune::sky::FrameInput::new(12.0, w)).atmosphere;
    assert!((at(0.0).mie_scattering_per_km[0] - 0.004).abs() < 1e-9);
    assert!((at(0.5).mie_scattering_per_km[1] - 0.012).abs() < 1e-6, "{:?}", at(0.5).mie_scattering_per_km);
    assert!((at(1.0).mie_scattering_per_km[2] - 0.02).abs() < 1e-9);
    // The base section applies to every step.
    assert!((at(0.7).rayleigh_scale_height_km - 8.5).abs() < 1e-6);
    // A step breaking a cross-field rule names its step.
    let (bad, _, _) = with_sections("[atmosphere]\n[[atmosphere.weather]]\nmie_scattering_per_km = 0.02\n");
    let errors = bad.expect_err("Mie extinction below scattering");
    assert!(errors.0.iter().any(|e| e.field == "atmosphere.weather[0].mie_extinction_per_km"), "{errors}");
}

#[test]
fn aerosol_knobs_become_mie_coefficients() {
    use skytune::atmosphere::aerosol::{Aerosol, AerosolPreset};
    use skytune::atmosphere::Atmosphere;
    let close = |a: [f64; 3], b: [f64; 3]| (0..3).all(|c| (a[c] - b[c]).abs() <= 1e-6 * b[c].abs().max(1e-6));
    // A preset is a documented set of the existing coefficients.
    let (sky, _, _) = with_sections("[atmosphere]\naerosol = \"hazy\"\n");
    let hazy = AerosolPreset::Hazy.aerosol().apply(Atmosphere::default());
    let atm = sky.unwrap().atmosphere;
    assert!(close(atm.mie_extinction_per_km, hazy.mie_extinction_per_km) && close(atm.mie_scattering_per_km, hazy.mie_scattering_per_km), "{atm:?}");
    assert_eq!(atm.mie_g, hazy.mie_g);
    // An optical depth with an exponent, by hand: tau 0.2, exponent 1, scale height 1 km.
    let (sky, _, _) = with_sections("[atmosphere]\naerosol_optical_depth = 0.2\nangstrom_exponent = 1\nmie_scale_height_km = 1\naerosol_albedo = 0.9\n");
    let atm = sky.unwrap().atmosphere;
    assert!(close(atm.mie_extinction_per_km, [0.2 * 550.0 / 680.0, 0.2, 0.2 * 550.0 / 440.0]), "{atm:?}");
    assert!(close(atm.mie_scattering_per_km, [0.18 * 550.0 / 680.0, 0.18, 0.18 * 550.0 / 440.0]), "{atm:?}");
    // Alone, an optical depth takes the default exponent; turbidity and visibility say the same.
    let (sky, _, _) = with_sections("[atmosphere]\naerosol_optical_depth = 0.1\n");
    let tau = Aerosol::of(&sky.unwrap().atmosphere);
    assert!((tau.optical_depth_550 - 0.1).abs() < 1e-7 && (tau.angstrom_exponent - 1.3).abs() < 1e-6, "{tau:?}");
    let (sky, _, _) = with_sections("[sky_model]\nkind = \"hosek\"\n\n[atmosphere]\nturbidity = 3\n");
    let sky = sky.unwrap();
    let t = Atmosphere::default().rayleigh_optical_depth_550();
    assert!((Aerosol::of(&sky.atmosphere).optical_depth_550 - 2.0 * t).abs() < 1e-6);
    // ... and the analytic models take the atmosphere's turbidity.
    assert!((sky.model.settings.analytic.turbidity - 3.0).abs() < 1e-5, "{}", sky.model.settings.analytic.turbidity);
    let (sky, _, _) = with_sections("[sky_model]\nkind = \"preetham\"\n\n[atmosphere]\naerosol = \"urban\"\n");
    let sky = sky.unwrap();
    assert!(
        (sky.model.settings.analytic.turbidity as f64 - sky.atmosphere.turbidity()).abs() < 1e-4 && sky.model.settings.analytic.turbidity > 5.0,
        "{}",
        sky.model.settings.analytic.turbidity
    );
    let (sky, _, _) = with_sections("[sky_model]\nkind = \"preetham\"\nturbidity = 2\n\n[atmosphere]\naerosol = \"urban\"\n");
    assert_eq!(sky.unwrap().model.settings.analytic.turbidity, 2.0, "a stated turbidity wins");
    // The analytic models follow the weather steps' aerosol too.
    let (sky, _, _) = with_sections("[sky_model]\nkind = \"hosek\"\n\n[atmosphere]\naerosol = \"clean\"\n[[atmosphere.weather]]\n[[atmosphere.weather]]\naerosol = \"urban\"\n");
    let sky = sky.unwrap();
    let turbidity = |w: f32| sky.evaluate(&skytune::sky::FrameInput::new(12.0, w)).sky_model.settings.analytic.turbidity as f64;
    let (clean, urban) = (AerosolPreset::Clean.aerosol().apply(Atmosphere::default()), AerosolPreset::Urban.aerosol().apply(Atmosphere::default()));
    assert!((turbidity(0.0) - clean.turbidity()).abs() < 1e-4 && (turbidity(1.0) - urban.turbidity()).abs() < 1e-4, "{} {}", turbidity(0.0), turbidity(1.0));
    // A weather step changes the amount and keeps the preset's slope and albedo.
    let (sky, _, _) = with_sections("[atmosphere]\naerosol = \"desert_dust\"\n[[atmosphere.weather]]\n[[atmosphere.weather]]\naerosol_optical_depth = 1.0\n");
    let sky = sky.unwrap();
    let (clear, storm) = (Aerosol::of(&sky.atmosphere_by_weather[0]), Aerosol::of(&sky.atmosphere_by_weather[1]));
    let dust = AerosolPreset::DesertDust.aerosol();
    assert!((clear.optical_depth_550 - dust.optical_depth_550).abs() < 1e-6 && (storm.optical_depth_550 - 1.0).abs() < 1e-6);
    assert!((storm.angstrom_exponent - dust.angstrom_exponent).abs() < 1e-4 && (storm.single_scattering_albedo - dust.single_scattering_albedo).abs() < 1e-6, "{storm:?}");
}

#[test]
fn conflicting_or_impossible_aerosol_is_a_located_error() {
    for (extra, needle, field, message) in [
        ("[atmosphere]\nmie_scattering_per_km = 0.01\naerosol_optical_depth = 0.2\n", "mie_scattering_per_km = 0.01", "atmosphere.mie_scattering_per_km", "not both"),
        ("[atmosphere]\naerosol_optical_depth = 0.2\nvisibility_km = 20\n", "visibility_km = 20", "atmosphere.visibility_km", "give the aerosol amount one way"),
        ("[atmosphere]\nvisibility_km = 500\n", "visibility_km = 500", "atmosphere.visibility_km", "expected a visibility in (0, 289] km"),
        ("[atmosphere]\nturbidity = 0.5\n", "turbidity = 0.5", "atmosphere.turbidity", "expected a turbidity >= 1"),
        ("[atmosphere]\naerosol = \"smog\"\n", "aerosol = \"smog\"", "atmosphere.aerosol", "desert_dust"),
        ("[atmosphere]\nangstrom_exponent = 7\n", "angstrom_exponent = 7", "atmosphere.angstrom_exponent", "expected an Angstrom exponent in [-1, 4]"),
    ] {
        let (result, file, text) = with_sections(extra);
        let errors = result.expect_err(extra);
        assert_error(&errors, &file, line_of(&text, needle), field, message);
    }
}

#[test]
fn a_sky_states_its_aerial_perspective() {
    use skytune::atmosphere::aerial::{AerialMethod, AerialSettings, SliceSpread};
    let (sky, _, _) = with_sections("[aerial_perspective]\nmethod = \"exact\"\nvolume_size = [16, 8, 64]\nslices = \"linear\"\n");
    let aerial = sky.unwrap().model.aerial;
    assert_eq!((aerial.method, aerial.volume_size, aerial.slices), (AerialMethod::Exact, [16, 8, 64], SliceSpread::Linear));
    // Keys left out keep their defaults.
    assert_eq!((aerial.distance_km, aerial.steps_per_slice), (AerialSettings::default().distance_km, AerialSettings::default().steps_per_slice));
}

#[test]
fn a_precomputed_sky_states_its_tables() {
    let (sky, _, _) = with_sections("[sky_model]\nkind = \"precomputed\"\n[sky_model.precomputed]\norders = 6\nscattering_size = [8, 16, 64, 16]\n");
    let model = sky.unwrap().model;
    assert_eq!(model.kind, skytune::sky::resolved::SkyModelKind::Precomputed);
    assert_eq!((model.settings.precomputed.orders, model.settings.precomputed.scattering_size), (6, [8, 16, 64, 16]));
    // Keys left out keep their defaults.
    assert_eq!(model.settings.precomputed.ray_steps, skytune::atmosphere::PrecomputedSettings::default().ray_steps);
}
