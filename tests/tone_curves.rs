//! The sRGB curves of shaders/sky_model/tone.wgsl, run on lavapipe under both `CURVES_KIND`s
//! (`DisplayCurves` of the fill strategy) and compared with the sRGB definition in double
//! precision: `pow` to float precision, the fitted polynomials within their documented error.

mod common;

use skytune::render::plan::strategy::DisplayCurves;
use skytune::render::{AdapterChoice, GpuContext, ShaderLibrary};

/// Points evaluated over [0, 1], ends included.
const POINTS: u32 = 4097;

/// The curves' entry point, appended to the module that holds them.
const PROBE: &str = "
@group(0) @binding(15) var<storage, read_write> curves_out: array<vec2<f32>>;

@compute @workgroup_size(64)
fn cs_curves(@builtin(global_invocation_id) id: vec3<u32>) {
    let n = arrayLength(&curves_out);
    if id.x >= n { return; }
    let x = f32(id.x) / f32(n - 1u);
    curves_out[id.x] = vec2<f32>(srgb_encode(vec3<f32>(x)).x, linear_from_display(vec3<f32>(x)).x);
}
";

fn encode(linear: f64) -> f64 {
    if linear <= 0.0031308 {
        12.92 * linear
    } else {
        1.055 * linear.powf(1.0 / 2.4) - 0.055
    }
}

fn decode(display: f64) -> f64 {
    if display <= 0.04045 {
        display / 12.92
    } else {
        ((display + 0.055) / 1.055).powf(2.4)
    }
}

/// (encoded, decoded) at each of `POINTS` points on [0, 1], by the shader built with `curves`.
fn shader_curves(ctx: &GpuContext, curves: DisplayCurves) -> Vec<[f32; 2]> {
    let source = ShaderLibrary::embedded().source("sky_model/tone").expect("tone.wgsl") + PROBE;
    let bytes = common::run_compute_probe(ctx, source, "cs_curves", &[("CURVES_KIND", f64::from(curves.shader_kind()))], None, POINTS, 8);
    bytemuck::cast_slice::<u8, [f32; 2]>(&bytes).to_vec()
}

/// Largest encoding error in levels of 255, and largest decoding error relative to the value
/// (absolute, in levels of the re-encoded value, below the linear segment's end).
fn errors(values: &[[f32; 2]]) -> (f64, f64) {
    let mut worst = (0.0f64, 0.0f64);
    for (i, v) in values.iter().enumerate() {
        let x = i as f64 / f64::from(POINTS - 1);
        worst.0 = worst.0.max((f64::from(v[0]) - encode(x)).abs() * 255.0);
        let exact = decode(x);
        let relative = if exact > 1e-6 { (f64::from(v[1]) - exact).abs() / exact } else { f64::from(v[1]).abs() };
        worst.1 = worst.1.max(relative);
    }
    worst
}

#[test]
fn the_shaders_srgb_curves_hold_their_documented_error_under_both_kinds() {
    let ctx = GpuContext::headless(AdapterChoice::Cpu).expect("lavapipe (mesa-vulkan-drivers) is required: run scripts/setup.sh");
    let exact = errors(&shader_curves(&ctx, DisplayCurves::Exact));
    let fitted = errors(&shader_curves(&ctx, DisplayCurves::Polynomial));
    // `pow` in single precision.
    assert!(exact.0 < 0.01 && exact.1 < 1e-4, "pow: {exact:?}");
    // The documented bounds (tone.wgsl, DisplayCurves): 0.001 of a level, 0.04%; a little room for
    // single precision.
    assert!(fitted.0 < 0.002, "fitted encoding off by {} levels", fitted.0);
    assert!(fitted.1 < 4.5e-4, "fitted decoding off by {}", fitted.1);
    // Fitted, a display value taken to linear light and back lands on its own level.
    let values = shader_curves(&ctx, DisplayCurves::Polynomial);
    for (i, v) in values.iter().enumerate().step_by(16) {
        let x = i as f64 / f64::from(POINTS - 1);
        let back = encode(f64::from(v[1]));
        assert!((back - x).abs() * 255.0 < 0.25, "level {}: back at {}", x * 255.0, back * 255.0);
    }
}
