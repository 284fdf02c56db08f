// The analytic sky models (Preetham, Hosek-Wilkie RGB, Braun-Cohen), evaluated from coefficients
// the CPU computes once per sun (src/atmosphere/analytic.rs, `AnalyticModel::coefficients`, keep
// the layout in sync). Results are finite and non-negative for every direction: view rays below
// the horizon take the horizon's value, out-of-gamut colours clamp at 0.

fn preetham_perez(a: f32, b: f32, c: f32, d: f32, e: f32, cos_theta: f32, gamma: f32) -> f32 {
    let cg = cos(gamma);
    return (1.0 + a * exp(b / max(cos_theta, 1e-3))) * (1.0 + c * exp(d * gamma) + e * cg * cg);
}

// CIE xyY to linear Rec. 709.
fn xyy_to_rec709(x: f32, y_in: f32, lum: f32) -> vec3<f32> {
    let y = max(y_in, 1e-6);
    let xyz = vec3<f32>(x / y * lum, lum, (1.0 - x - y) / y * lum);
    let m = transpose(mat3x3<f32>(
        vec3<f32>(3.2406, -1.5372, -0.4986),
        vec3<f32>(-0.9689, 1.8758, 0.0415),
        vec3<f32>(0.0557, -0.2040, 1.0570),
    ));
    return max(m * xyz, vec3<f32>(0.0));
}

// `c`: the coefficients (c[11].w: 0 preetham, 1 hosek, 2 linear); `view`: unit direction, y up.
fn analytic_radiance(c: array<vec4<f32>, 12>, view: vec3<f32>) -> vec3<f32> {
    let kind = u32(c[11].w + 0.5);
    if (kind == 2u) {
        return c[0].rgb;
    }
    let sun = c[11].xyz;
    let cos_theta = clamp(view.y, 0.0, 1.0);
    let gamma = acos(clamp(dot(view, sun), -1.0, 1.0));
    if (kind == 0u) {
        let fy = preetham_perez(c[0].x, c[1].x, c[2].x, c[3].x, c[4].x, cos_theta, gamma);
        let fx = preetham_perez(c[0].y, c[1].y, c[2].y, c[3].y, c[4].y, cos_theta, gamma);
        let fyc = preetham_perez(c[0].z, c[1].z, c[2].z, c[3].z, c[4].z, cos_theta, gamma);
        let lum = c[5].x * fy / c[6].x;
        let x = c[5].y * fx / c[6].y;
        let y = c[5].z * fyc / c[6].z;
        return xyy_to_rec709(x, y, lum * c[5].w);
    }
    // Hosek-Wilkie: (1 + A e^(B / (cos theta + 0.01))) (C + D e^(E gamma) + F cos^2 gamma + G chi(H, gamma) + I sqrt(cos theta)),
// the crate's coefficient order: A B C D E F G I H.
    let cg = cos(gamma);
    let chi = (1.0 + cg * cg) / pow(max(vec3<f32>(1.0) + c[8].rgb * c[8].rgb - 2.0 * c[8].rgb * cg, vec3<f32>(1e-6)), vec3<f32>(1.5));
    let lhs = vec3<f32>(1.0) + c[0].rgb * exp(c[1].rgb / (cos_theta + 0.01));
    let rhs = c[2].rgb + c[3].rgb * exp(c[4].rgb * gamma) + c[5].rgb * cg * cg + c[6].rgb * chi + c[7].rgb * sqrt(cos_theta);
    return max(c[9].rgb * lhs * rhs, vec3<f32>(0.0));
}
