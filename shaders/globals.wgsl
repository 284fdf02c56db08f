// Per-frame globals, bind group 0, shared by every pass.
// Keep in sync with `Globals` in src/render/frame/globals.rs.
struct Globals {
    clip_from_world: mat4x4<f32>,      // main-scene camera
    clip_from_sky: mat4x4<f32>,        // rotation-only camera: sky objects sit at the dome centre
    celestial_from_world: mat4x4<f32>, // rotating star frame
    towards_sun: vec4<f32>,            // xyz unit vector, w unused
    fog_color: vec4<f32>,
    sun_ambient: vec4<f32>,
    sun_diffuse: vec4<f32>,
    time: vec4<f32>,                   // hour, hours_per_day, weather, game_hours
    viewport: vec4<f32>,               // width, height, 1/width, 1/height (pixels)
    camera_position: vec4<f32>,        // world position of the main-scene camera, m
    output: vec4<f32>,                 // x: 1 when drawing exposed linear radiance into the HDR target (0: display values), y: tone mapper, z: 1 on a display-referred physical frame matched to the HDR picture
    cloud_sun: vec4<f32>,              // sun light on lit clouds, display values (the sky model's, else sun_diffuse)
    cloud_ambient: vec4<f32>,          // ambient light on lit clouds, display values (the sky model's, else sun_ambient)
};
@group(0) @binding(0) var<uniform> globals: Globals;
const PI: f32 = 3.14159265358979;

