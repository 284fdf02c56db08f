// Per-frame globals, bind group 0, shared by every pass.
// Keep in sync with `Globals` in src/render/frame/globals.rs.
struct Globals {
    clip_from_world: mat4x4<f32>,      // main-scene camera
    clip_from_sky: mat4x4<f32>,        // rotation-only camera: sky objects sit at the dome centre
    celestial_from_world: mat4x4<f32>, // rotating star frame
    world_from_clip: mat4x4<f32>,      // main-scene camera, clip -> world
    previous_clip_from_world: mat4x4<f32>, // the previous frame's main-scene camera (this frame's on the first)
    towards_sun: vec4<f32>,            // xyz unit vector, w unused
    time: vec4<f32>,                   // hour, hours_per_day, weather, game_hours
    viewport: vec4<f32>,               // width, height, 1/width, 1/height (pixels)
    camera_position: vec4<f32>,        // world position of the main-scene camera, m
    output: vec4<f32>,                 // x: 1 when drawing exposed linear radiance into the HDR target (0: display values), y: tone mapper, z: 1 on a display-referred physical frame matched to the HDR picture
    depth: vec4<f32>,                  // the scene depth's viewport range (x, y), the camera's near and far planes (z, w; m)
};
@group(0) @binding(0) var<uniform> globals: Globals;

// Unit world direction of the main-scene camera's ray through `pixel` (framebuffer
// coordinates, pixels; a pixel's centre is at + 0.5).
fn camera_ray(pixel: vec2<f32>) -> vec3<f32> {
    let uv = pixel * globals.viewport.zw;
    let far = globals.world_from_clip * vec4<f32>(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0, 1.0, 1.0);
    return normalize(far.xyz / far.w - globals.camera_position.xyz);
}

// Distance along the camera's forward axis of what the scene's depth holds (m): the stored
// value with the viewport's range undone, then the projection's (depth 0 at the near plane, 1 at
// the far one). The far plane where nothing was drawn.
fn scene_view_depth_m(stored: f32) -> f32 {
    let ndc_z = clamp((stored - globals.depth.x) / max(globals.depth.y - globals.depth.x, 1e-6), 0.0, 1.0);
    let near = globals.depth.z;
    let far = globals.depth.w;
    return near * far / (far - ndc_z * (far - near));
}

// Distance from the main-scene camera along the ray through `pixel` to what the scene's depth
// holds there, m.
fn scene_distance_m(stored: f32, pixel: vec2<f32>) -> f32 {
    let forward = camera_ray(globals.viewport.xy * 0.5);
    return scene_view_depth_m(stored) / max(dot(camera_ray(pixel), forward), 1e-4);
}

// The light of the main scene and of lit clouds: the NeL bitmaps' colours, the sky model's
// (its atmosphere stage writes `model`: src/render/atmosphere/sky_view.rs) and which of them the
// frame uses. Display values. Keep in sync with `SceneLight` in src/render/frame/light.rs.
struct SceneLight {
    fog_color: vec4<f32>,          // the bitmaps'
    sun_ambient: vec4<f32>,
    sun_diffuse: vec4<f32>,
    model: array<vec4<f32>, 4>,    // [0].x exposure scale, [1] fog colour, [2] ambient, [3] diffuse (E T / pi)
    source: vec4<f32>,             // x: 1 when the model lights the main scene, y: 1 when it lights the clouds
};
@group(0) @binding(1) var<uniform> scene_light: SceneLight;

// The main scene's fog colour.
fn scene_fog_color() -> vec3<f32> {
    if (scene_light.source.x > 0.5) {
        return scene_light.model[1].rgb;
    }
    return scene_light.fog_color.rgb;
}

// The main scene's ambient light.
fn scene_ambient() -> vec3<f32> {
    if (scene_light.source.x > 0.5) {
        return scene_light.model[2].rgb;
    }
    return scene_light.sun_ambient.rgb;
}

// The main scene's diffuse sun light.
fn scene_diffuse() -> vec3<f32> {
    if (scene_light.source.x > 0.5) {
        return scene_light.model[3].rgb;
    }
    return scene_light.sun_diffuse.rgb;
}

// Sun light on lit clouds: the model's transmitted sun when a model shows, else the bitmaps'.
fn cloud_sun() -> vec3<f32> {
    if (scene_light.source.y > 0.5) {
        return scene_light.model[3].rgb;
    }
    return scene_light.sun_diffuse.rgb;
}

// Ambient light on lit clouds: the model's mean sky radiance when a model shows, else the bitmaps'.
fn cloud_ambient() -> vec3<f32> {
    if (scene_light.source.y > 0.5) {
        return scene_light.model[2].rgb;
    }
    return scene_light.sun_ambient.rgb;
}
const PI: f32 = 3.14159265358979;

