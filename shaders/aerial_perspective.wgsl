//! requires: sky_model/aerial_volume
// Aerial-perspective pass (compute phase): builds the froxel volume of the frame's camera, one
// invocation per screen cell marching its view ray through the depth slices in order, so each
// slice costs its own samples only (sky_model/aerial_volume.wgsl has the march and the layout).
@group(1) @binding(0) var<uniform> atmosphere: Atmosphere;
@group(1) @binding(1) var<uniform> aerial_params: AerialParams;
@group(1) @binding(2) var<storage, read> lut_params: LutParams;
@group(1) @binding(3) var<storage, read> transmittance_lut: array<vec4<f32>>;
@group(1) @binding(4) var<storage, read> multiscattering_lut: array<vec4<f32>>;
// Light scattered into the ray up to each slice's end (units: sr^-1 per unit of solar irradiance;
// the reader applies the exposure), and the ray's transmittance there.
@group(1) @binding(5) var in_scatter_volume: texture_storage_3d<rgba16float, write>;
@group(1) @binding(6) var transmittance_volume: texture_storage_3d<rgba16float, write>;

@compute @workgroup_size(8, 8)
fn cs_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let p = aerial_params;
    if (gid.x >= p.size.x || gid.y >= p.size.y) {
        return;
    }
    let view = aerial_cell_view(p, gid.xy);
    let sun = p.towards_sun.xyz;
    var ray = view_ray(atmosphere, p.camera.w, view, sun);
    // Through the planet's ground, in air of the ground's density: the scene, not the planet,
    // ends a ray here. A cell whose centre meets the ground short of a scene point seen through
    // its neighbour would otherwise freeze its values there, and the point, read between the two,
    // would come out too clear (transmittance up to 0.1 high, views a degree below the horizon).
    ray.distance_km = distance_to_top(atmosphere, ray.r, ray.mu);
    var state = AerialMarch(vec3<f32>(0.0), vec3<f32>(0.0));
    var start = 0.0;
    let multiple = p.shape.z > 0.5;
    var c: array<vec3<f32>, 6>;
    for (var k = 0u; k < p.size.z; k++) {
        let end = aerial_slice_distance_km(p, k);
        if (multiple && k % AERIAL_SLICES_PER_MS_READ == 0u) {
            // At the middle of the slices this read serves.
            let last = min(k + AERIAL_SLICES_PER_MS_READ, p.size.z) - 1u;
            c = aerial_ms_at(atmosphere, ray, view, sun, min(0.5 * (start + aerial_slice_distance_km(p, last)), ray.distance_km));
        }
        aerial_advance(atmosphere, ray, view, sun, start, end, p.size.w, multiple, c, &state);
        start = end;
        // Finite in half precision whatever the atmosphere.
        textureStore(in_scatter_volume, vec3<u32>(gid.xy, k), vec4<f32>(min(state.sum, vec3<f32>(60000.0)), 1.0));
        textureStore(transmittance_volume, vec3<u32>(gid.xy, k), vec4<f32>(exp(-state.tau), 1.0));
    }
}
