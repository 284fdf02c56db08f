//! requires: sky_model/tone, reduced/run
// Point-star field: one screen-aligned sprite per star, rotating with the celestial frame.
// (globals.wgsl is prepended by the loader.)

// Keep in sync with `StarsUniform` in src/render/passes/stars.rs.
struct StarsParams {
    color: vec4<f32>,   // rgb tint, a = visibility
    size: vec4<f32>,    // x: size of a magnitude-0 star, pixels
};
@group(1) @binding(0) var<uniform> params: StarsParams;

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) local: vec2<f32>,
    @location(1) brightness: f32,
};

@vertex
fn vs_main(@builtin(vertex_index) vi: u32, @location(0) celestial_dir: vec3<f32>, @location(1) brightness: f32) -> VertexOut {
    var corners = array<vec2<f32>, 4>(vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, -1.0), vec2<f32>(-1.0, 1.0), vec2<f32>(1.0, 1.0));
    let corner = corners[vi];
    // celestial_from_world is a rotation: its transpose maps back to the world.
    let world = (transpose(globals.celestial_from_world) * vec4<f32>(celestial_dir, 0.0)).xyz;
    var clip = globals.clip_from_sky * vec4<f32>(world, 1.0);
    clip.z = clip.w * 0.5;
    let size_px = params.size.x * clamp(sqrt(brightness), 0.5, 2.0);
    clip = vec4<f32>(clip.xy + corner * size_px * globals.viewport.zw * clip.w, clip.zw);
    // Extinction near the horizon.
    let extinction = smoothstep(-0.02, 0.2, world.y);
    var out: VertexOut;
    out.clip = clip;
    out.local = corner;
    out.brightness = min(brightness, 1.5) * extinction;
    return out;
}

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    return star_color(in);
}

fn star_color(in: VertexOut) -> vec4<f32> {
    let falloff = exp(-dot(in.local, in.local) * 4.0);
    let a = clamp(falloff * in.brightness * params.color.a, 0.0, 1.0);
    // Premultiplied (additive blending weights by the source alpha): see glare.wgsl.
    return vec4<f32>(to_target(params.color.rgb * a), 1.0);
}

// Added light under the run above the stars (drawn after its composite: src/render/passes/stars.rs,
// `Placement::UnderRun`) shows through the run's transmittance.
@fragment
fn fs_under_run(in: VertexOut) -> @location(0) vec4<f32> {
    let transmittance = run_at(in.clip.xy).a;
    let c = star_color(in);
    return vec4<f32>(c.rgb * transmittance, c.a);
}
