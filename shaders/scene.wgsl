//! requires: sky_model/tone
// Main-scene stand-in: terrain and buildings lit by the sun colours and fogged with the sky's
// fog colour. Drawn first, in depth range [0, 0.95], so the sky behind it fails the depth test.
// (globals.wgsl is prepended by the loader.)

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    // Lit and fogged colour (display values), per vertex: the light and the fog vary slowly over
    // a 52 m cell (the fog's curvature moves the colour by under half a level of 255 across one),
    // and on lavapipe the per-pixel lighting, fog and normalisation cost about 2 ms a frame when
    // the terrain fills the lower half of a 1280x720 frame.
    @location(0) color: vec3<f32>,
};

// Fog density, m^-1.
const FOG_DENSITY: f32 = 0.0018;

@vertex
fn vs_main(@location(0) position: vec3<f32>, @location(1) normal: vec3<f32>, @location(2) albedo: vec3<f32>) -> VertexOut {
    var out: VertexOut;
    out.clip = globals.clip_from_world * vec4<f32>(position, 1.0);
    let n = normalize(normal);
    let light = scene_ambient() + scene_diffuse() * max(dot(n, globals.towards_sun.xyz), 0.0);
    let lit = albedo * light;
    let distance_m = length(position - globals.camera_position.xyz);
    let fog = 1.0 - exp(-distance_m * FOG_DENSITY);
    out.color = mix(lit, scene_fog_color(), fog);
    return out;
}

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    return vec4<f32>(to_target(in.color), 1.0);
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
