//! requires: sky_model/aerial_volume
// Reading the aerial-perspective volume (sky_model/aerial_volume.wgsl). A library: the module that
// requires it declares `aerial_params`, `aerial_in_scatter`, `aerial_transmittance` and
// `aerial_sampler` (the scene, the radiance probe).

// The volume at screen position `uv` (0..1, y down) and `distance_km`: trilinear between cell
// and slice centres, edges clamped; nearer than the first slice's end, the first slice's values
// scaled towards none at the viewer.
fn aerial_lookup(uv: vec2<f32>, distance_km: f32) -> Aerial {
    let n = vec2<f32>(aerial_params.size.xy);
    let across = clamp(clamp(uv, vec2<f32>(0.0), vec2<f32>(1.0)) * n, vec2<f32>(0.5), n - 0.5);
    let depth = aerial_slice_position(aerial_params, distance_km);
    let coord = vec3<f32>(across, depth.x) / AERIAL_MAX_SIZE;
    let in_scatter = textureSampleLevel(aerial_in_scatter, aerial_sampler, coord, 0.0).rgb;
    let transmittance = textureSampleLevel(aerial_transmittance, aerial_sampler, coord, 0.0).rgb;
    return Aerial(in_scatter * depth.y, mix(vec3<f32>(1.0), transmittance, depth.y));
}
