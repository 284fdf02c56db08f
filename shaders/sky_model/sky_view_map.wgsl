// The sky-view map: the skydome's colour by world direction. u is the compass azimuth (wraps),
// v the elevation with the horizon in the middle and more texels near it (v - 0.5 goes as the
// square root of the elevation), as in Hillaire 2020's sky-view LUT.
fn sky_view_uv(dir: vec3<f32>) -> vec2<f32> {
    let azimuth = atan2(dir.x, -dir.z);
    let elevation = asin(clamp(dir.y, -1.0, 1.0));
    let e = sign(elevation) * sqrt(abs(elevation) / (0.5 * PI));
    return vec2<f32>(azimuth / (2.0 * PI) + 0.5, 0.5 - 0.5 * e);
}

fn sky_view_direction(uv: vec2<f32>) -> vec3<f32> {
    let azimuth = (uv.x - 0.5) * 2.0 * PI;
    let e = (0.5 - uv.y) * 2.0;
    let elevation = sign(e) * e * e * 0.5 * PI;
    return vec3<f32>(sin(azimuth) * cos(elevation), sin(elevation), -cos(azimuth) * cos(elevation));
}
