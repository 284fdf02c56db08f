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

// Linear to sRGB-encoded display values.
fn srgb_encode(linear: vec3<f32>) -> vec3<f32> {
    let c = clamp(linear, vec3<f32>(0.0), vec3<f32>(1.0));
    return select(1.055 * pow(c, vec3<f32>(1.0 / 2.4)) - 0.055, 12.92 * c, c <= vec3<f32>(0.0031308));
}

// Radiance (sr^-1 per unit of solar irradiance) to a display value: exposure scale, tone mapper
// (0 ACES fitted, 1 Khronos PBR Neutral), sRGB encoding.
fn display_from_radiance(radiance: vec3<f32>, exposure: f32, tone_mapper: u32) -> vec3<f32> {
    let exposed = max(radiance, vec3<f32>(0.0)) * exposure;
    if (tone_mapper == 1u) {
        return srgb_encode(tone_map_neutral(exposed));
    }
    return srgb_encode(tone_map_aces(exposed));
}
