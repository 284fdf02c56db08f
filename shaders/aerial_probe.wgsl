//! requires: sky_model/aerial_lookup
// Reads the aerial-perspective volume for one radiance case, as the scene reads it
// (`aerial_lookup`), for `skytune radiance` and the tests. Keep in sync with
// src/render/atmosphere/aerial_probe.rs.
@group(1) @binding(0) var<uniform> aerial_params: AerialParams;
@group(1) @binding(1) var aerial_in_scatter: texture_3d<f32>;
@group(1) @binding(2) var aerial_transmittance: texture_3d<f32>;
@group(1) @binding(3) var aerial_sampler: sampler;
// x, y: the screen position (0..1, y down); z: the distance (km); w: the case's index.
@group(1) @binding(4) var<uniform> query: vec4<f32>;
// Two vectors per case: in-scatter, transmittance.
@group(1) @binding(5) var<storage, read_write> answers: array<vec4<f32>>;
// Declared for the volume's library (the probe reads no table).
@group(1) @binding(6) var<storage, read> lut_params: LutParams;
@group(1) @binding(7) var<storage, read> transmittance_lut: array<vec4<f32>>;
@group(1) @binding(8) var<storage, read> multiscattering_lut: array<vec4<f32>>;

@compute @workgroup_size(1)
fn cs_main() {
    let a = aerial_lookup(query.xy, query.z);
    let k = u32(query.w);
    answers[2u * k] = vec4<f32>(a.in_scatter, 1.0);
    answers[2u * k + 1u] = vec4<f32>(a.transmittance, 1.0);
}
