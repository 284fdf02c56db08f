//! requires: sky_objects/material, sky_objects/placement
// A pair of alpha-blended dome layers on the same mesh drawn at once into a reduced buffer
// (src/render/sky_objects/pairs.rs, `Placement::Pair`): each one's mesh coordinates.
struct PairOut {
    @builtin(position) clip: vec4<f32>,
    @location(1) world_dir: vec3<f32>,
    @location(2) mesh_uv01: vec4<f32>,
    @location(3) mesh_uv23: vec4<f32>,
    @location(4) upper_uv01: vec4<f32>,
    @location(5) upper_uv23: vec4<f32>,
};

@vertex
fn vs_pair(@location(0) position: vec3<f32>, @location(1) uv: vec2<f32>) -> PairOut {
    let own = sky_vertex(position, uv);
    var out: PairOut;
    out.clip = own.clip;
    out.world_dir = own.world_dir;
    out.mesh_uv01 = own.mesh_uv01;
    out.mesh_uv23 = own.mesh_uv23;
    out.upper_uv01 = vec4<f32>(scaled(upper, 0u, uv), scaled(upper, 1u, uv));
    out.upper_uv23 = vec4<f32>(scaled(upper, 2u, uv), scaled(upper, 3u, uv));
    return out;
}

// The upper layer over the draw's own, as the two alpha blends one after the other would leave
// them: premultiplied colour, and in alpha what the pair covers (the buffer's transmittance is
// multiplied by what it lets through: `PAIR_BLEND` in src/render/sky_objects/variants.rs). Over the seed
// (`OVER_SEED`), written as it is, with the transmittance left.
@fragment
fn fs_pair(in: PairOut) -> @location(0) vec4<f32> {
    let own = material(LAYER_OWN, draw, tex0, tex1, tex2, tex3, samp0, samp1, samp2, samp3, sky_view, sky_view_sampler, Place(in.world_dir, in.mesh_uv01, in.mesh_uv23));
    let up = material(
        LAYER_UPPER, upper, upper_tex0, upper_tex1, upper_tex2, upper_tex3, upper_samp0, upper_samp1, upper_samp2, upper_samp3, upper_sky_view, upper_sky_view_sampler,
        Place(in.world_dir, in.upper_uv01, in.upper_uv23),
    );
    var rgb = up.a * up.rgb + (1.0 - up.a) * own.a * own.rgb;
    var through = (1.0 - own.a) * (1.0 - up.a);
    // On a display-referred physical frame, where the pair covers anything (skipped first where
    // it is clear, as `over_model_sky` skips a clear layer): over the seed, what lies under the
    // pair is known, so the two blends are made in radiance over it (`over_seed_in_radiance`);
    // elsewhere the pair is matched as one layer over the model's sky: the HDR path's two blends
    // in radiance, tone-mapped once, as `over_model_sky` matches one layer (exact where the pair
    // lies on the bare sky; one map sample and one tone curve for the two).
    if OVER_MODEL_SKY && max(own.a, up.a) >= 1e-3 {
        let over = up.a * exposed_from_display(up.rgb) + (1.0 - up.a) * own.a * exposed_from_display(own.rgb);
        if OVER_SEED {
            return over_seed_in_radiance(over, through, run_radiance_at_seeded(in.clip.xy));
        }
        let sky = model_sky(in.world_dir, sky_view, sky_view_sampler);
        let matched = matched_alpha_blend(display_from_exposed(over + through * sky.radiance, frame_tone_mapper()), sky.display, 1.0 - through);
        rgb = matched.rgb * matched.a;
        through = 1.0 - matched.a;
    }
    if OVER_SEED {
        return vec4<f32>(rgb + through * run_at_seeded(in.clip.xy).rgb, through);
    }
    return vec4<f32>(rgb, 1.0 - through);
}
