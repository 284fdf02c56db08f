//! Particle emitters: the emission switch, the cap under any rate, particles outliving their
//! hidden object, determinism (the same input, the same particles and pixels), stability under
//! extreme rates and time steps, reloads keeping living particles, the GPU evaluation's count,
//! and image tests of rain, snow and shooting stars on lavapipe.

mod common;

use skytune::render::plan::strategy::FlashPlacement;
use skytune::render::{Camera, FillStrategy, RenderOptions};
use skytune::sky::builtin::default_sky;
use skytune::sky::particles::{Burst, ParticleClock};
use skytune::sky::resolved::{Color, ColorMode, EmitterAttach};
use skytune::sky::{FrameInput, Sky};

/// A frame with every particle on the CPU (the reference the GPU path is held to below).
fn at(sky: &Sky, hour: f32, weather: f32, time_s: f64) -> skytune::sky::FrameSky {
    sky.evaluate(&FrameInput { particle_clock: Some(ParticleClock { time_s, hours_per_s: 0.0 }), gpu_particles: false, ..FrameInput::new(hour, weather) })
}

fn count(frame: &skytune::sky::FrameSky, sky: &Sky, name: &str) -> usize {
    let index = sky.emitters.iter().position(|e| e.name == name).unwrap();
    frame.particles.emitters.iter().find(|f| f.emitter == index).map_or(0, |f| f.instances.len())
}

/// The built-in sky with its shooting stars frequent enough to count.
fn busy_sky() -> Sky {
    let mut sky = default_sky();
    let e = sky.emitters.iter_mut().find(|e| e.name == "shooting_stars").unwrap();
    e.rate = 200.0;
    e.max_particles = 1000;
    sky
}

#[test]
fn emission_is_off_while_the_bitmap_is_black() {
    let sky = busy_sky();
    let e = sky.emitters.iter().find(|e| e.name == "shooting_stars").unwrap();
    let bitmap = e.emission.bitmap.as_ref().unwrap();
    for hour in 0..24 {
        let c = bitmap.sample(hour as f32, 24.0, 0.0);
        let black = c[0].max(c[1]).max(c[2]) <= 0.5 / 255.0;
        let frame = at(&sky, hour as f32, 0.0, 1000.0);
        let n = count(&frame, &sky, "shooting_stars");
        let emitting = frame.particles.emitters.iter().find(|f| sky.emitters[f.emitter].name == "shooting_stars").unwrap().emitting;
        assert_eq!(emitting, !black, "hour {hour}: emitting {emitting}, bitmap {c:?}");
        if black {
            assert_eq!(n, 0, "hour {hour}: {n} particles under a black bitmap");
        } else {
            assert!(n > 50, "hour {hour}: only {n} particles");
        }
    }
    // Rain: amount times the weather, and off in fair weather.
    let sky = default_sky();
    assert_eq!(count(&at(&sky, 12.0, 0.2, 50.0), &sky, "rain"), 0);
    let (half, full) = (count(&at(&sky, 12.0, 0.85, 50.0), &sky, "rain") as f64, count(&at(&sky, 12.0, 1.0, 50.0), &sky, "rain") as f64);
    assert!(full > 1000.0 && half < full, "rain {half} at 0.85, {full} at 1");
}

#[test]
fn the_count_never_exceeds_the_cap() {
    let mut rng = fastrand::Rng::with_seed(2);
    for &rate in &[0.0f32, 0.5, 1e3, 1e6, 1e12, f32::MAX] {
        for &cap in &[1u32, 7, 1000] {
            let mut sky = default_sky();
            for e in sky.emitters.iter_mut() {
                e.rate = rate;
                e.max_particles = cap;
                e.emission = Color { mode: ColorMode::Unused, bitmap: None, value: [1.0; 4] };
            }
            for _ in 0..5 {
                let time_s = rng.f64() * 1e5;
                let bursts: Vec<Burst> = sky.emitters.iter().map(|e| Burst { emitter: e.name.clone(), time_s: time_s - 0.01, count: 100_000 }).collect();
                for gpu_particles in [false, true] {
                    let frame = sky.evaluate(&FrameInput {
                        particle_clock: Some(ParticleClock { time_s, hours_per_s: 0.0 }),
                        bursts: bursts.clone(),
                        gpu_particles,
                        ..FrameInput::new(23.0, 1.0)
                    });
                    for f in &frame.particles.emitters {
                        let drawn = f.instances.len() + f.gpu.as_ref().map_or(0, |g| g.slots as usize);
                        assert!(drawn <= cap as usize, "rate {rate}, cap {cap}: {drawn} drawn");
                    }
                }
            }
        }
    }
}

#[test]
fn particles_of_a_hidden_object_live_out_their_lifetime() {
    let mut sky = default_sky();
    let galaxy = sky.object_index("galaxy").unwrap();
    // Long-lived particles on the galaxy, which its ref colour hides by day.
    let e = sky.emitters.iter_mut().find(|e| e.name == "shooting_stars").unwrap();
    e.attach = EmitterAttach::Object(galaxy);
    e.emission = Color { mode: ColorMode::Unused, bitmap: None, value: [1.0; 4] };
    e.lifetime_s = 600.0;
    e.lifetime_spread = 0.0;
    e.rate = 2.0;
    e.max_particles = 5000;
    let sph = sky.particle_seconds_per_hour as f64;
    let visible = |hour: f32| sky.object_ref_alpha(galaxy, &FrameInput::new(hour, 0.0)) >= 0.5 / 255.0;
    // The first hour of the morning that hides the galaxy.
    let hidden_at = (0..240).map(|i| i as f32 * 0.1).find(|h| *h > 2.0 && !visible(*h) && visible(*h - 0.1)).expect("the galaxy hides in the morning");
    let frame_at = |hour: f32| sky.evaluate(&FrameInput { game_hours: hour as f64, ..FrameInput::new(hour, 0.0) });
    let hidden = frame_at(hidden_at + 0.05);
    assert!(matches!(hidden.objects.iter().find(|o| o.index == galaxy).unwrap().versions, Err(skytune::sky::eval::Hidden::RefAlphaZero(_))));
    let f = &hidden.particles.emitters[0];
    assert!(!f.emitting);
    assert!(!f.instances.is_empty(), "the particles born before the galaxy hid must live on");
    // A lifetime later they are gone (no births since).
    let later_hour = hidden_at + 0.05 + (600.0 / sph) as f32 + 0.01;
    assert!((0..=40).all(|i| !visible(hidden_at + 0.05 + i as f32 * (later_hour - hidden_at) / 40.0)), "the galaxy must stay hidden meanwhile");
    assert!(frame_at(later_hour).particles.emitters[0].instances.is_empty());
}

#[test]
fn the_same_input_gives_the_same_particles_and_a_reload_keeps_them() {
    let sky = busy_sky();
    let a = at(&sky, 23.0, 0.9, 4321.5);
    let b = at(&sky, 23.0, 0.9, 4321.5);
    for (x, y) in a.particles.emitters.iter().zip(&b.particles.emitters) {
        assert_eq!(x.instances, y.instances);
    }
    // A reload that removes another emitter keeps the living particles of those that remain.
    let mut edited = sky.clone();
    edited.emitters.retain(|e| e.name != "lightning");
    let c = at(&edited, 23.0, 0.9, 4321.5);
    let stars = |f: &skytune::sky::FrameSky, s: &Sky| f.particles.emitters.iter().find(|e| s.emitters[e.emitter].name == "shooting_stars").unwrap().instances.clone();
    assert_eq!(stars(&a, &sky), stars(&c, &edited));
}

#[test]
fn extreme_rates_and_steps_stay_finite_and_bounded() {
    let mut rng = fastrand::Rng::with_seed(7);
    let mut sky = default_sky();
    for e in sky.emitters.iter_mut() {
        e.rate = 1e9;
        e.max_particles = 2000;
        e.gravity = 1e6;
        e.speed = 1e7;
        e.emission = Color { mode: ColorMode::Unused, bitmap: None, value: [1.0; 4] };
    }
    let mut time_s = 0.0f64;
    let mut most = 0;
    for step in 0..10_000 {
        let dt = match step % 5 {
            0 => 1e-9,
            1 => rng.f64() * 0.1,
            2 => rng.f64() * 1e6,
            3 => -rng.f64() * 10.0,
            _ => 1.0 / 60.0,
        };
        time_s = (time_s + dt).clamp(-1e12, 1e12);
        let input = FrameInput { particle_clock: Some(ParticleClock { time_s, hours_per_s: rng.f64() }), dt_s: dt as f32, ..FrameInput::new(rng.f32() * 24.0, rng.f32()) };
        let frame = sky.evaluate(&input);
        let alive = frame.particles.alive();
        most = most.max(alive);
        assert!(alive <= 2000 * sky.emitters.len());
        for f in &frame.particles.emitters {
            for p in &f.instances {
                assert!(p.position.iter().chain(&p.velocity).chain(&p.color).all(|v| v.is_finite()), "step {step}: {p:?}");
            }
            if let Some(g) = &f.gpu {
                assert!(
                    g.slots <= 2000 && g.conditions.len() <= 3 * (skytune::sky::particles::MAX_GPU_BUCKETS + 1),
                    "step {step}: {} slots, {} conditions",
                    g.slots,
                    g.conditions.len()
                );
                assert!(
                    [g.first_age_s, g.slot_interval_s, g.acceptance, g.bucket_offset_s, g.bucket_s].iter().chain(g.conditions.iter().flatten()).all(|v| v.is_finite()),
                    "step {step}: {g:?}"
                );
            }
        }
    }
    assert!(most > 0);
}

#[test]
fn the_gpu_evaluation_matches_the_cpu_in_number_and_kind() {
    let ctx = skytune::render::GpuContext::headless(skytune::render::AdapterChoice::Cpu).unwrap();
    let mut sky = default_sky();
    let index = sky.emitters.iter().position(|e| e.name == "rain").unwrap();
    {
        let e = &mut sky.emitters[index];
        e.lifetime_spread = 0.0;
        e.max_particles = 4000;
    }
    let e = sky.emitters[index].clone();
    let mut gpu = skytune::render::passes::particle_sim::StandaloneSim::new(&ctx, &skytune::render::ShaderLibrary::embedded(), e.max_particles).unwrap();
    // Full storm (every slot born), light rain (thinned by the weather), and fair weather (none).
    for (weather, time_s) in [(1.0f32, 3.0), (1.0, 1000.125), (0.7, 17.25), (0.3, 40.0)] {
        let cpu = at(&sky, 12.0, weather, time_s);
        let cpu = &cpu.particles.emitters.iter().find(|f| f.emitter == index).unwrap().instances;
        let frame = sky.evaluate(&FrameInput { particle_clock: Some(ParticleClock { time_s, hours_per_s: 0.0 }), ..FrameInput::new(12.0, weather) });
        let births = frame.particles.emitters.iter().find(|f| f.emitter == index).unwrap().gpu.clone().unwrap_or_default();
        gpu.sim.prepare(&ctx.queue, &e, &births);
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        gpu.record(&mut encoder);
        ctx.queue.submit([encoder.finish()]);
        let live: Vec<_> = gpu.read(&ctx).unwrap().into_iter().filter(|p| p.position[3] > 0.0).collect();
        // Same count within the random thinning's noise (3 sigma), the same box and speeds.
        let (n, m) = (cpu.len() as f64, live.len() as f64);
        assert!((n - m).abs() <= 3.0 * n.sqrt().max(1.0) + 1.0, "weather {weather}, t {time_s}: CPU {n}, GPU {m}");
        let half = e.box_m * 0.5 + e.speed * 1.2 * e.lifetime_s + 1.0;
        for p in &live {
            assert!(p.position[..3].iter().all(|v| v.abs() <= half), "{p:?}");
            let speed = (p.velocity[0].powi(2) + p.velocity[1].powi(2) + p.velocity[2].powi(2)).sqrt();
            assert!(speed <= e.speed * (1.0 + e.speed_spread) * 1.001, "{p:?}");
        }
    }
}

fn render(sky: &Sky, hour: f32, weather: f32, time_s: f64, camera: Camera) -> image::RgbaImage {
    let mut h = common::headless(160, 90);
    h.set_sky(sky).unwrap();
    // Camera emitters on the GPU, as the renderer does by default.
    let input = FrameInput { particle_clock: Some(ParticleClock { time_s, hours_per_s: 0.0 }), ..FrameInput::new(hour, weather) };
    h.render(sky, &input, &camera, &RenderOptions { glare: false, ..Default::default() }).unwrap()
}

/// Renders, checks the reference, and that switching `emitter` off changes at least `share` of
/// the pixels (the particles show).
fn check(name: &str, sky: &Sky, emitter: &str, (hour, weather): (f32, f32), camera: Camera, share: f64) {
    let img = render(sky, hour, weather, 777.0, camera);
    assert_eq!(img, render(sky, hour, weather, 777.0, camera), "the same input must give the same picture");
    let mut without = sky.clone();
    without.emitters.retain(|e| e.name != emitter);
    let (d, _) = common::diff(&img, &render(&without, hour, weather, 777.0, camera), 6);
    assert!(d.differing >= share, "{name}: the particles change only {:.2}% of the pixels", d.differing * 100.0);
    common::check_reference(name, &img);
}

/// Drops big enough to see at 160 x 90.
fn visible_rain(rain_to_snow: f32) -> Sky {
    let mut sky = default_sky();
    let e = sky.emitters.iter_mut().find(|e| e.name == "rain").unwrap();
    e.rain_to_snow = rain_to_snow;
    e.size = [0.05, 0.05];
    sky
}

#[test]
fn rain_image() {
    check("particles_rain", &visible_rain(0.0), "rain", (13.0, 1.0), Camera::default(), 0.02);
}

#[test]
fn snow_image() {
    check("particles_snow", &visible_rain(1.0), "rain", (13.0, 1.0), Camera::default(), 0.02);
}

#[test]
fn shooting_stars_image() {
    let mut sky = busy_sky();
    let e = sky.emitters.iter_mut().find(|e| e.name == "shooting_stars").unwrap();
    e.size = [1.0, 0.5];
    e.streak_s = 0.4;
    check("particles_shooting_stars", &sky, "shooting_stars", (23.5, 0.0), Camera { pitch_deg: 50.0, ..Camera::default() }, 0.01);
}

#[test]
fn lightning_flash_adds_its_colour_over_the_sky() {
    let sky = default_sky();
    // A storm moment with a bright flash (the built-in sky's lightning, in the storm clouds).
    let (input, flash) = (0..8000)
        .map(|i| {
            let input = FrameInput { particle_clock: Some(ParticleClock { time_s: i as f64 * 0.05, hours_per_s: 0.0 }), gpu_particles: false, ..FrameInput::new(15.0, 1.0) };
            let flash = sky.evaluate(&input).particles.flash;
            (input, flash)
        })
        .find(|(_, f)| *f > 0.3)
        .expect("a flash within 400 s of storm");
    let mut h = common::headless(1280, 720);
    h.set_sky(&sky).expect("uploaded");
    let camera = Camera::preset("zenith").expect("zenith view");
    let lit = sky.evaluate(&input);
    // The same frame (bolts, light lifted by the evaluation) without the flash's own draw.
    let mut unlit = lit.clone();
    unlit.particles.flash = 0.0;
    // Drawn over the frame, and added to the run of reduced dome layers before it.
    for in_run in [false, true] {
        let placement = if in_run { FlashPlacement::InRun } else { FlashPlacement::OverFrame };
        let options = RenderOptions { glare: false, scene: false, strategy: FillStrategy { flash: placement, ..FillStrategy::software() }, ..Default::default() };
        let mut draw = |frame: &skytune::sky::FrameSky| {
            let mut encoder = h.ctx.device.create_command_encoder(&Default::default());
            h.renderer.render(&h.ctx, &mut encoder, &h.target.target(), frame, &camera, &options);
            h.ctx.queue.submit([encoder.finish()]);
            h.renderer.after_submit();
            (h.target.read(&h.ctx).expect("read back"), h.renderer.stats.clone())
        };
        let (a, s) = draw(&lit);
        assert_eq!(s.joined_runs_only, u32::from(in_run), "flash in a run: {in_run} ({s:?})");
        let (b, _) = draw(&unlit);
        // The flash is an additive cold white, (0.55, 0.6, 0.7) x its strength, over every pixel
        // of the sky (display target: added as it is, clamped at white).
        let f = flash.min(1.0);
        for (c, k) in [0.55f32, 0.6, 0.7].into_iter().enumerate() {
            let mut lifts: Vec<i32> = a.pixels().zip(b.pixels()).filter(|(_, q)| q[c] < 150).map(|(p, q)| p[c] as i32 - q[c] as i32).collect();
            assert!(lifts.len() > 1000, "channel {c}: the storm sky is dark enough to see the flash");
            lifts.sort_unstable();
            let median = lifts[lifts.len() / 2];
            let expected = (k * f * 255.0).round() as i32;
            assert!((median - expected).abs() <= 2, "channel {c}, in a run {in_run}: the flash lifts the sky by {median} levels, expected {expected} (flash {f})");
        }
    }
}
