//! requires: sky_model/tone, sky_model/aerial_lookup
// Main-scene stand-in: terrain and buildings lit by the sun colours and fogged with the sky's
// fog colour, or, when the sky's physical model lights the scene, given the model's aerial
// perspective (lit * T + in-scatter, from the volume or the exact march). Drawn first, in depth
// range [0, 0.95], so the sky behind it fails the depth test. (globals.wgsl is prepended by the
// loader.)

// The aerial-perspective volume (aerial_perspective.wgsl builds it in the compute phase).
@group(1) @binding(0) var<uniform> aerial_params: AerialParams;
@group(1) @binding(1) var aerial_in_scatter: texture_3d<f32>;
@group(1) @binding(2) var aerial_transmittance: texture_3d<f32>;
@group(1) @binding(3) var aerial_sampler: sampler;
// The frame's atmosphere and the LUT tables, for the exact march.
@group(1) @binding(4) var<uniform> atmosphere: Atmosphere;
@group(1) @binding(5) var<storage, read> lut_params: LutParams;
@group(1) @binding(6) var<storage, read> transmittance_lut: array<vec4<f32>>;
@group(1) @binding(7) var<storage, read> multiscattering_lut: array<vec4<f32>>;

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    // Lit and fogged colour, per vertex: display values under the fog, the target's values under
    // aerial perspective. The light and the fog vary slowly over a 52 m cell (the fog's
    // curvature moves the colour by under half a level of 255 across one), and on lavapipe the
    // per-pixel lighting, fog and normalisation cost about 2 ms a frame when the terrain fills
    // the lower half of a 1280x720 frame.
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
    let to_point = position - globals.camera_position.xyz;
    let distance_m = length(to_point);
    if (takes_aerial_perspective()) {
        var a: Aerial;
        if (aerial_params.towards_sun.w > 1.5) {
            a = lut_aerial(atmosphere, aerial_params.camera.w, to_point / max(distance_m, 1e-3), aerial_params.towards_sun.xyz, distance_m * 0.001);
        } else {
            let ndc = out.clip.xy / max(out.clip.w, 1e-6);
            a = aerial_lookup(vec2<f32>(0.5 + 0.5 * ndc.x, 0.5 - 0.5 * ndc.y), distance_m * 0.001);
        }
        // The model's light is display values; the volume's in-scatter radiance, exposed here
        // with the map's exposure scale.
        let exposed = exposed_from_display(lit) * a.transmittance + a.in_scatter * scene_light.model[0].x;
        if (on_display_target()) {
            out.color = display_from_exposed(exposed, frame_tone_mapper());
        } else {
            out.color = exposed;
        }
        return out;
    }
    let fog = 1.0 - exp(-distance_m * FOG_DENSITY);
    out.color = mix(lit, scene_fog_color(), fog);
    return out;
}

// Whether the frame gives the scene the model's aerial perspective: the model lights the scene
// and the aerial-perspective pass names a method.
fn takes_aerial_perspective() -> bool {
    return scene_light.source.x > 0.5 && aerial_params.towards_sun.w > 0.5;
}

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    if (takes_aerial_perspective()) {
        return vec4<f32>(in.color, 1.0);
    }
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
