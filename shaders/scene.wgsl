//! requires: sky_model/tone
// Main-scene stand-in: terrain and buildings lit by the sun colours and fogged with the sky's
// fog colour. Drawn first, in depth range [0, 0.95], so the sky behind it fails the depth test.
// (globals.wgsl is prepended by the loader.)

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world_position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) albedo: vec3<f32>,
};

@vertex
fn vs_main(@location(0) position: vec3<f32>, @location(1) normal: vec3<f32>, @location(2) albedo: vec3<f32>) -> VertexOut {
    var out: VertexOut;
    out.clip = globals.clip_from_world * vec4<f32>(position, 1.0);
    out.world_position = position;
    out.normal = normal;
    out.albedo = albedo;
    return out;
}

// Fog density, m^-1.
const FOG_DENSITY: f32 = 0.0018;

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    let n = normalize(in.normal);
    let light = globals.sun_ambient.rgb + globals.sun_diffuse.rgb * max(dot(n, globals.towards_sun.xyz), 0.0);
    let lit = in.albedo * light;
    let distance_m = length(in.world_position - globals.camera_position.xyz);
    let fog = 1.0 - exp(-distance_m * FOG_DENSITY);
    return vec4<f32>(to_target(mix(lit, globals.fog_color.rgb, fog)), 1.0);
}

// Test occluder: a rectangle given directly in clip space, written into the scene's depth.
@vertex
fn vs_occluder(@location(0) clip_xy: vec2<f32>) -> @builtin(position) vec4<f32> {
    return vec4<f32>(clip_xy, 0.1, 1.0);
}

@fragment
fn fs_occluder() -> @location(0) vec4<f32> {
    return vec4<f32>(to_target(vec3<f32>(0.05, 0.05, 0.06)), 1.0);
}
