// The sky-view map: the skydome's colour by direction relative to the sun. u is the azimuth from
// the sun's, either way (0 towards the sun, 1 away from it): every model's sky is symmetric about
// the vertical plane through the sun (a horizontally uniform atmosphere and ground), so half the
// circle holds all of it, at half the texels. v is the elevation with the horizon in the middle
// and more texels near it (v - 0.5 goes as the square root of the elevation), as in Hillaire
// 2020's sky-view LUT.

// Map coordinates of direction `dir` (any length) with the sun towards `sun` (any length). Read
// per fragment by every layer over a physical sky: both angles come from `fast_atan2`, on the
// unnormalised directions. A sun overhead has no azimuth: every direction reads u = 0, where
// the map was computed (`sky_view_direction`), and its sky has none either.
fn sky_view_uv(dir: vec3<f32>, sun: vec3<f32>) -> vec2<f32> {
    // Cosine and sine of the azimuth from the sun's, times the two horizontal lengths.
    let along = dir.x * sun.x + dir.z * sun.z;
    let across = abs(dir.x * sun.z - dir.z * sun.x);
    let azimuth = fast_atan2(across, along);
    let elevation = fast_atan2(dir.y, length(dir.xz));
    let e = sign(elevation) * sqrt(abs(elevation) / (0.5 * PI));
    return vec2<f32>(azimuth / PI, 0.5 - 0.5 * e);
}

// atan2(y, x) within 4e-6 radians (a two-thousandth of a map texel): an odd polynomial of the
// smaller ratio (the Cg reference's) and three selects, on the direction as given: cheaper than
// `atan2`, `asin` and the normalisation before them, though on lavapipe only by about 1% of a
// physical frame (docs/performance-notes.md).
fn fast_atan2(y: f32, x: f32) -> f32 {
    let ax = abs(x);
    let ay = abs(y);
    let a = min(ax, ay) / max(max(ax, ay), 1e-30);
    let s = a * a;
    var r = (((((-0.013480470 * s + 0.057477314) * s - 0.121239071) * s + 0.195635925) * s - 0.332994597) * s + 0.999995630) * a;
    r = select(r, 1.57079637 - r, ay > ax);
    r = select(r, 3.14159274 - r, x < 0.0);
    return select(r, -r, y < 0.0);
}

// The unit direction at map coordinates `uv` with the sun towards `sun`: the inverse of
// `sky_view_uv` on the side of the sun's plane where the compass azimuth grows (from -z towards
// +x) from the sun's.
fn sky_view_direction(uv: vec2<f32>, sun: vec3<f32>) -> vec3<f32> {
    let azimuth = atan2(sun.x, -sun.z) + uv.x * PI;
    let e = (0.5 - uv.y) * 2.0;
    let elevation = sign(e) * e * e * 0.5 * PI;
    return vec3<f32>(sin(azimuth) * cos(elevation), sin(elevation), -cos(azimuth) * cos(elevation));
}
