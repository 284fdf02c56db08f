//! requires: sky_objects/material, sky_objects/placement, sky_objects/pairs, sky_objects/texels
// Sky objects: procedural shapes with a NeL-style material of up to 4 texture stages.
// The material is a sum of terms: an `add` stage starts a term (texture x constant), a
// `modulate` stage multiplies the current term; the result times the diffuse colour.
//
// (globals.wgsl is prepended by the loader.)
//
// The module's parts (shaders/sky_objects/): draw.wgsl (bindings and the vertex), signature.wgsl
// (specialisation), material.wgsl (stages and terms), placement.wgsl (where on the frame),
// pairs.wgsl (two layers at once) and texels.wgsl (a sparse stage texel by texel). This file
// holds the plain draw's entry points.

@vertex
fn vs_main(@location(0) position: vec3<f32>, @location(1) uv: vec2<f32>) -> VertexOut {
    return sky_vertex(position, uv);
}

// One triangle over the frame, for a draw that maps nothing from its shape (the background
// where its sparse stage is drawn texel by texel: the runs' colour at the pixel), scissored to
// where the shape covers the frame. No vertex buffer; nothing but the position is meant to be read.
@vertex
fn vs_fullscreen(@builtin(vertex_index) vi: u32) -> VertexOut {
    let p = vec2<f32>(f32((vi << 1u) & 2u), f32(vi & 2u));
    var out: VertexOut;
    // Inside the sky's depth range, as `sky_vertex`.
    out.clip = vec4<f32>(p * 2.0 - vec2<f32>(1.0), 0.5, 1.0);
    out.uv = vec2<f32>(0.0);
    out.world_dir = vec3<f32>(0.0, 1.0, 0.0);
    out.mesh_uv01 = vec4<f32>(0.0);
    out.mesh_uv23 = vec4<f32>(0.0);
    return out;
}

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    let at = Place(in.world_dir, in.mesh_uv01, in.mesh_uv23);
    var color = material(LAYER_OWN, draw, tex0, tex1, tex2, tex3, samp0, samp1, samp2, samp3, sky_view, sky_view_sampler, at);
    // What scales the colour's radiance where it is matched to the HDR picture (there the moon's
    // shading applies to radiance, as on the HDR target, not to display values).
    var shade = 1.0;
    if lighting(LAYER_OWN, draw) == 1u {
        // Moon: a lit sphere seen from the dome centre; the sun side is bright, so phases show.
        let p = in.uv * 2.0 - vec2<f32>(1.0);
        let r2 = dot(p, p);
        let right = normalize(draw.object_from_local[0].xyz);
        let up = normalize(draw.object_from_local[1].xyz);
        let towards_viewer = -normalize(draw.object_from_local[2].xyz);
        let n = normalize(p.x * right - p.y * up + sqrt(max(1.0 - r2, 0.0)) * towards_viewer);
        let lit = max(dot(n, globals.towards_sun.xyz), 0.0);
        // The unlit side is dark but also transparent: in daylight the sky shows through it.
        let coverage = mix(0.35, 1.0, smoothstep(0.0, 0.25, lit));
        shade = 0.04 + 0.96 * lit;
        var rgb = color.rgb;
        if !OVER_MODEL_SKY { rgb *= shade; }
        color = vec4<f32>(rgb, color.a * coverage * step(r2, 1.0));
    }
    // Over the seed, what lies under the layer is known: blended in radiance over it. Where
    // clear, left to `over_seed` below, as `over_model_sky` leaves a clear colour.
    if OVER_MODEL_SKY && OVER_SEED && BLEND_KIND == 1u && color.a >= 1e-3 {
        return over_seed_in_radiance(color.a * shade * exposed_from_display(color.rgb), 1.0 - color.a, run_radiance_at_seeded(in.clip.xy));
    }
    if OVER_MODEL_SKY {
        color = over_model_sky(color, shade, in.world_dir, sky_view, sky_view_sampler);
    }
    if UNDER_RUN {
        color = under_run(color, in.clip.xy);
    }
    if BACKGROUND != 0u {
        color = as_background(color, in.clip.xy);
    }
    if OVER_SEED {
        color = over_seed(color, in.clip.xy);
    }
    return color;
}
