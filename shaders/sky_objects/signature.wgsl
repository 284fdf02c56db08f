//! requires: sky_objects/draw
// The material's signature as specialisation constants, and how a layer reads it: from the
// constants where the pipeline is specialised, from its uniform where not.

// Specialisation: a pipeline per material signature sets SPECIALISED and the constants below from
// the draw's uniform (src/render/sky_objects/variants.rs, `VariantKey`), so the compiler drops what the draw
// does not use. This matters on SIMD rasterisers such as lavapipe, which run both sides of every
// branch (a uniform condition included) under a lane mask and sample textures even in lanes that
// are off: every branch left on a uniform costs as if taken. The generic pipeline keeps the
// defaults and reads everything from the uniform.
override SPECIALISED: bool = false;
override STAGE_COUNT: u32 = 4u;
override UV_MODE_0: u32 = 0u;
override UV_MODE_1: u32 = 0u;
override UV_MODE_2: u32 = 0u;
override UV_MODE_3: u32 = 0u;
// Stage op (0 add, 1 modulate), constant index (4: none), live (0: its term is black this frame).
override OP_0: u32 = 0u;
override OP_1: u32 = 0u;
override OP_2: u32 = 0u;
override OP_3: u32 = 0u;
override CONSTANT_0: u32 = 4u;
override CONSTANT_1: u32 = 4u;
override CONSTANT_2: u32 = 4u;
override CONSTANT_3: u32 = 4u;
override LIVE_0: bool = true;
override LIVE_1: bool = true;
override LIVE_2: bool = true;
override LIVE_3: bool = true;
// The stage the sky-view map feeds (4: none) and the lighting (0 flat, 1 moon, 2 cloud). What
// the target holds comes with TARGET_KIND and TONE_KIND (tone.wgsl).
override VIEW_STAGE: u32 = 4u;
override LIGHTING: u32 = 0u;
// A blended layer (no map of its own) of a display-referred physical frame: its colour is turned
// into what the HDR path's blend over the model's sky would leave (`over_model_sky`).
override OVER_MODEL_SKY: bool = false;
// The upper layer of a pair (`fs_pair`, group 3), specialised as the draw's own constants above.
override UPPER_STAGE_COUNT: u32 = 0u;
override UPPER_UV_MODE_0: u32 = 0u;
override UPPER_UV_MODE_1: u32 = 0u;
override UPPER_UV_MODE_2: u32 = 0u;
override UPPER_UV_MODE_3: u32 = 0u;
override UPPER_OP_0: u32 = 0u;
override UPPER_OP_1: u32 = 0u;
override UPPER_OP_2: u32 = 0u;
override UPPER_OP_3: u32 = 0u;
override UPPER_CONSTANT_0: u32 = 4u;
override UPPER_CONSTANT_1: u32 = 4u;
override UPPER_CONSTANT_2: u32 = 4u;
override UPPER_CONSTANT_3: u32 = 4u;
override UPPER_LIVE_0: bool = true;
override UPPER_LIVE_1: bool = true;
override UPPER_LIVE_2: bool = true;
override UPPER_LIVE_3: bool = true;
override UPPER_VIEW_STAGE: u32 = 4u;
override UPPER_LIGHTING: u32 = 0u;

// Layers of a draw: its own (group 1), and the upper one of a pair (group 3). The functions below
// take the layer, constant where they are called, and its uniform: the upper layer is always
// specialised, the draw's own reads its uniform where not.
const LAYER_OWN: u32 = 0u;
const LAYER_UPPER: u32 = 1u;

fn stage_count(l: u32, d: Draw) -> u32 {
    if l == LAYER_UPPER {
        return UPPER_STAGE_COUNT;
    }
    if SPECIALISED {
        return STAGE_COUNT;
    }
    return d.misc.x;
}

// One of four per-stage constants by stage index.
fn pick_u32(i: u32, c: vec4<u32>) -> u32 {
    switch i {
        case 0u: { return c.x; }
        case 1u: { return c.y; }
        case 2u: { return c.z; }
        default: { return c.w; }
    }
}

// One of four per-stage flags by stage index.
fn pick_bool(i: u32, c0: bool, c1: bool, c2: bool, c3: bool) -> bool {
    switch i {
        case 0u: { return c0; }
        case 1u: { return c1; }
        case 2u: { return c2; }
        default: { return c3; }
    }
}

fn uv_mode(l: u32, d: Draw, i: u32) -> u32 {
    if l == LAYER_UPPER {
        return pick_u32(i, vec4<u32>(UPPER_UV_MODE_0, UPPER_UV_MODE_1, UPPER_UV_MODE_2, UPPER_UV_MODE_3));
    }
    if SPECIALISED {
        return pick_u32(i, vec4<u32>(UV_MODE_0, UV_MODE_1, UV_MODE_2, UV_MODE_3));
    }
    return d.stages[i].cfg.y;
}

fn stage_op(l: u32, d: Draw, i: u32) -> u32 {
    if l == LAYER_UPPER {
        return pick_u32(i, vec4<u32>(UPPER_OP_0, UPPER_OP_1, UPPER_OP_2, UPPER_OP_3));
    }
    if SPECIALISED {
        return pick_u32(i, vec4<u32>(OP_0, OP_1, OP_2, OP_3));
    }
    return d.stages[i].cfg.x;
}

fn stage_constant(l: u32, d: Draw, i: u32) -> u32 {
    if l == LAYER_UPPER {
        return pick_u32(i, vec4<u32>(UPPER_CONSTANT_0, UPPER_CONSTANT_1, UPPER_CONSTANT_2, UPPER_CONSTANT_3));
    }
    if SPECIALISED {
        return pick_u32(i, vec4<u32>(CONSTANT_0, CONSTANT_1, CONSTANT_2, CONSTANT_3));
    }
    return d.stages[i].cfg.z;
}

fn stage_live(l: u32, d: Draw, i: u32) -> bool {
    if l == LAYER_UPPER {
        return pick_bool(i, UPPER_LIVE_0, UPPER_LIVE_1, UPPER_LIVE_2, UPPER_LIVE_3);
    }
    if SPECIALISED {
        return pick_bool(i, LIVE_0, LIVE_1, LIVE_2, LIVE_3);
    }
    return d.stages[i].cfg.w != 0u;
}

fn view_stage(l: u32, d: Draw) -> u32 {
    if l == LAYER_UPPER {
        return UPPER_VIEW_STAGE;
    }
    if SPECIALISED {
        return VIEW_STAGE;
    }
    return d.misc.z;
}

fn lighting(l: u32, d: Draw) -> u32 {
    if l == LAYER_UPPER {
        return UPPER_LIGHTING;
    }
    if SPECIALISED {
        return LIGHTING;
    }
    return d.misc.y;
}
