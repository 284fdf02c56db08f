// Exposure, tone mapping and display encoding of physical radiance.

// Stephen Hill's fit of the ACES reference rendering and output device transforms (sRGB primaries).
fn tone_map_aces(color: vec3<f32>) -> vec3<f32> {
    let input = transpose(mat3x3<f32>(
        vec3<f32>(0.59719, 0.35458, 0.04823),
        vec3<f32>(0.07600, 0.90834, 0.01566),
        vec3<f32>(0.02840, 0.13383, 0.83777),
    ));
    let output = transpose(mat3x3<f32>(
        vec3<f32>(1.60475, -0.53108, -0.07367),
        vec3<f32>(-0.10208, 1.10813, -0.00605),
        vec3<f32>(-0.00327, -0.07276, 1.07602),
    ));
    let v = input * color;
    let fitted = (v * (v + 0.0245786) - 0.000090537) / (v * (0.983729 * v + 0.4329510) + 0.238081);
    return clamp(output * fitted, vec3<f32>(0.0), vec3<f32>(1.0));
}

// Inverse of `tone_map_aces` for display values below 1: the exposed linear value the mapper
// takes to `display_linear` (the top 2% of the curve is cut, so white maps to about 12).
fn tone_map_aces_inverse(display_linear: vec3<f32>) -> vec3<f32> {
    let output_inverse = transpose(mat3x3<f32>(
        vec3<f32>(0.643038, 0.311187, 0.045775),
        vec3<f32>(0.059269, 0.931436, 0.009295),
        vec3<f32>(0.005962, 0.063929, 0.930118),
    ));
    let input_inverse = transpose(mat3x3<f32>(
        vec3<f32>(1.764741, -0.675778, -0.088963),
        vec3<f32>(-0.147028, 1.160252, -0.013224),
        vec3<f32>(-0.036337, -0.162436, 1.198773),
    ));
    let y = clamp(output_inverse * clamp(display_linear, vec3<f32>(0.0), vec3<f32>(1.0)), vec3<f32>(0.0), vec3<f32>(0.98));
    // The fit y = (v (v + a) - b) / (v (c v + d) + e) solved for v: a quadratic in v.
    let qa = 1.0 - 0.983729 * y;
    let qb = 0.0245786 - 0.4329510 * y;
    let qc = 0.000090537 + 0.238081 * y;
    let v = (-qb + sqrt(qb * qb + 4.0 * qa * qc)) / (2.0 * qa);
    return max(input_inverse * v, vec3<f32>(0.0));
}

// Khronos PBR Neutral: identity below 0.76, then highlights compress and desaturate.
fn tone_map_neutral(color_in: vec3<f32>) -> vec3<f32> {
    let start = 0.8 - 0.04;
    let desaturation = 0.15;
    var color = color_in;
    let x = min(color.r, min(color.g, color.b));
    var offset = 0.04;
    if (x < 0.08) {
        offset = x - 6.25 * x * x;
    }
    color -= vec3<f32>(offset);
    let peak = max(color.r, max(color.g, color.b));
    if (peak < start) {
        return color;
    }
    let d = 1.0 - start;
    let new_peak = 1.0 - d * d / (peak + d - start);
    color *= new_peak / peak;
    let g = 1.0 - 1.0 / (desaturation * (peak - new_peak) + 1.0);
    return mix(color, vec3<f32>(new_peak), g);
}

// Inverse of `tone_map_neutral` for display values below 1, up to its highlight desaturation
// (white maps to about 6).
fn tone_map_neutral_inverse(display_linear: vec3<f32>) -> vec3<f32> {
    let start = 0.8 - 0.04;
    let d = 1.0 - start;
    var color = clamp(display_linear, vec3<f32>(0.0), vec3<f32>(0.99));
    let new_peak = max(color.r, max(color.g, color.b));
    if (new_peak >= start) {
        let peak = d * d / (1.0 - new_peak) - d + start;
        color *= peak / new_peak;
    }
    // The offset: x - (x - 6.25 x^2) below x = 0.08, 0.04 above.
    let x = min(color.r, min(color.g, color.b));
    var offset = 0.04;
    if (x < 0.04) {
        offset = sqrt(x / 6.25) - x;
    }
    return color + vec3<f32>(offset);
}

// How the sRGB curves are evaluated (`DisplayCurves` in src/render/plan/strategy.rs): 0 `pow`, 1
// polynomials fitted to them (within 0.001 of a level encoding, 0.04% decoding; a software
// rasteriser's `pow` is a logarithm and an exponential per lane). tests/tone_curves.rs runs both
// against the definition.
override CURVES_KIND: u32 = 0u;

// sRGB-encoded display value to linear.
fn linear_from_display(display: vec3<f32>) -> vec3<f32> {
    let c = max(display, vec3<f32>(0.0));
    var curve: vec3<f32>;
    if CURVES_KIND == 1u {
        // ((c + 0.055) / 1.055)^2.4 on [0.04045, 1], a quintic fitted for relative error.
        curve = ((((0.11661877 * c - 0.3690054) * c + 0.71040345) * c + 0.50754543) * c + 0.03392317) * c + 0.00088328;
    } else {
        curve = pow((c + 0.055) / 1.055, vec3<f32>(2.4));
    }
    return select(curve, c / 12.92, c <= vec3<f32>(0.04045));
}

// What the frame's target holds for a display-referred colour (a bitmap, a scene colour): the
// value itself on the display target (the 2005 look); on the HDR target, the exposed radiance that
// the frame's tone mapper takes back to that display value, so NeL layers look as authored when
// alone and blend with the physical sky in linear light (and a white sun over a bright sky still
// saturates).
// The target a render pipeline was built for: 1 the display target, 2 the HDR target, 0 not
// known (read globals.output). Lavapipe runs both sides of every branch, uniform ones included,
// so render pipelines set it (`PassBuild::target_constants`) and the other side compiles away.
override TARGET_KIND: u32 = 0u;
// The HDR target's tone mapper, where the pipeline knows it (sky objects' specialised pipelines):
// 1 ACES, 2 neutral, 0 not known (read globals.output).
override TONE_KIND: u32 = 0u;

fn to_target(display: vec3<f32>) -> vec3<f32> {
    if on_display_target() {
        return display;
    }
    return exposed_from_display(display);
}

// Whether the pipeline draws into the display target (display values).
fn on_display_target() -> bool {
    return TARGET_KIND == 1u || (TARGET_KIND == 0u && globals.output.x < 0.5);
}

// The exposed radiance the frame's tone mapper takes to display value `display`.
fn exposed_from_display(display: vec3<f32>) -> vec3<f32> {
    let l = linear_from_display(display);
    if frame_tone_mapper() == 1u {
        return tone_map_neutral_inverse(l);
    }
    // Black is no light. The ACES fit is 0 up to about 0.0037, and its inverse gives the foot of
    // that toe for black (about 0.0033): every black term (a stage left dark or to another draw
    // of the layer, a black texel of an additive layer) would add it, and a night sky drawn in
    // parts would come out several levels brighter than drawn whole.
    return select(tone_map_aces_inverse(l), vec3<f32>(0.0), all(display <= vec3<f32>(0.0)));
}

// The frame's tone mapper as `display_from_exposed` takes it (0 ACES, 1 neutral).
fn frame_tone_mapper() -> u32 {
    if TONE_KIND == 2u || (TONE_KIND == 0u && globals.output.y > 0.5) {
        return 1u;
    }
    return 0u;
}

// Linear to sRGB-encoded display values.
fn srgb_encode(linear: vec3<f32>) -> vec3<f32> {
    let c = clamp(linear, vec3<f32>(0.0), vec3<f32>(1.0));
    var curve: vec3<f32>;
    if CURVES_KIND == 1u {
        // 1.055 c^(1/2.4) - 0.055 on [0.0031308, 1] in the square roots c^(1/2), c^(1/4), c^(1/8).
        let s1 = sqrt(c);
        let s2 = sqrt(s1);
        let s3 = sqrt(s2);
        curve = 0.87762006 * s1 + 0.45507623 * s2 - 0.16787247 * s3 + 0.02876196 * c - 0.03261282 - 0.16097048 * s1 * s2;
    } else {
        curve = 1.055 * pow(c, vec3<f32>(1.0 / 2.4)) - 0.055;
    }
    return select(curve, 12.92 * c, c <= vec3<f32>(0.0031308));
}

// Exposed linear radiance to a display value: tone mapper (0 ACES fitted, 1 Khronos PBR
// Neutral), then sRGB encoding.
fn display_from_exposed(exposed: vec3<f32>, tone_mapper: u32) -> vec3<f32> {
    let c = max(exposed, vec3<f32>(0.0));
    if (tone_mapper == 1u) {
        return srgb_encode(tone_map_neutral(c));
    }
    return srgb_encode(tone_map_aces(c));
}
