// Compositing nodes of the MaterialX standard library (nodegroup "compositing"): mix, premult,
// unpremult and the blend/merge operators (plus, minus, difference, burn, dodge, screen, over,
// disjointover, in, out, mask, matte, inside, outside). Closure variants (mix of shaders) are
// not here: they are not numeric types.
// Semantics follow MaterialX's reference GLSL implementation (libraries/stdlib/genglsl):
// mix(fg, bg, m) = bg * (1 - m) + fg * m.

// M_FLOAT_EPS of MaterialX's GLSL (lib/mx_math.glsl).
const mx_compositing_float_eps: f32 = 1e-8;

// ---- premult ----

fn mx_premult_color4(in: vec4<f32>) -> vec4<f32> {
    return vec4<f32>(in.rgb * in.a, in.a);
}

// ---- unpremult ----

fn mx_unpremult_color4(in: vec4<f32>) -> vec4<f32> {
    return vec4<f32>(in.rgb / in.a, in.a);
}

// ---- plus ----

fn mx_plus_float(fg: f32, bg: f32, mix: f32) -> f32 {
    return mix * (bg + fg) + (1.0 - mix) * bg;
}

fn mx_plus_color3(fg: vec3<f32>, bg: vec3<f32>, mix: f32) -> vec3<f32> {
    return mix * (bg + fg) + (1.0 - mix) * bg;
}

fn mx_plus_color4(fg: vec4<f32>, bg: vec4<f32>, mix: f32) -> vec4<f32> {
    return mix * (bg + fg) + (1.0 - mix) * bg;
}

// ---- minus ----

fn mx_minus_float(fg: f32, bg: f32, mix: f32) -> f32 {
    return mix * (bg - fg) + (1.0 - mix) * bg;
}

fn mx_minus_color3(fg: vec3<f32>, bg: vec3<f32>, mix: f32) -> vec3<f32> {
    return mix * (bg - fg) + (1.0 - mix) * bg;
}

fn mx_minus_color4(fg: vec4<f32>, bg: vec4<f32>, mix: f32) -> vec4<f32> {
    return mix * (bg - fg) + (1.0 - mix) * bg;
}

// ---- difference ----

fn mx_difference_float(fg: f32, bg: f32, mix: f32) -> f32 {
    return mix * abs(bg - fg) + (1.0 - mix) * bg;
}

fn mx_difference_color3(fg: vec3<f32>, bg: vec3<f32>, mix: f32) -> vec3<f32> {
    return mix * abs(bg - fg) + (1.0 - mix) * bg;
}

fn mx_difference_color4(fg: vec4<f32>, bg: vec4<f32>, mix: f32) -> vec4<f32> {
    return mix * abs(bg - fg) + (1.0 - mix) * bg;
}

// ---- burn ----

fn mx_burn_float(fg: f32, bg: f32, mix: f32) -> f32 {
    if (abs(fg) < mx_compositing_float_eps) {
        return 0.0;
    }
    return mix * (1.0 - ((1.0 - bg) / fg)) + (1.0 - mix) * bg;
}

fn mx_burn_color3(fg: vec3<f32>, bg: vec3<f32>, mix: f32) -> vec3<f32> {
    // Per channel, as MaterialX GLSL.
    return vec3<f32>(mx_burn_float(fg.x, bg.x, mix), mx_burn_float(fg.y, bg.y, mix), mx_burn_float(fg.z, bg.z, mix));
}

fn mx_burn_color4(fg: vec4<f32>, bg: vec4<f32>, mix: f32) -> vec4<f32> {
    // Per channel (alpha included), as MaterialX GLSL.
    return vec4<f32>(mx_burn_float(fg.x, bg.x, mix), mx_burn_float(fg.y, bg.y, mix), mx_burn_float(fg.z, bg.z, mix), mx_burn_float(fg.w, bg.w, mix));
}

// ---- dodge ----

fn mx_dodge_float(fg: f32, bg: f32, mix: f32) -> f32 {
    if (abs(1.0 - fg) < mx_compositing_float_eps) {
        return 0.0;
    }
    return mix * (bg / (1.0 - fg)) + (1.0 - mix) * bg;
}

fn mx_dodge_color3(fg: vec3<f32>, bg: vec3<f32>, mix: f32) -> vec3<f32> {
    // Per channel, as MaterialX GLSL.
    return vec3<f32>(mx_dodge_float(fg.x, bg.x, mix), mx_dodge_float(fg.y, bg.y, mix), mx_dodge_float(fg.z, bg.z, mix));
}

fn mx_dodge_color4(fg: vec4<f32>, bg: vec4<f32>, mix: f32) -> vec4<f32> {
    // Per channel (alpha included), as MaterialX GLSL.
    return vec4<f32>(mx_dodge_float(fg.x, bg.x, mix), mx_dodge_float(fg.y, bg.y, mix), mx_dodge_float(fg.z, bg.z, mix), mx_dodge_float(fg.w, bg.w, mix));
}

// ---- screen ----

fn mx_screen_float(fg: f32, bg: f32, mix: f32) -> f32 {
    return mix * (1.0 - (1.0 - fg) * (1.0 - bg)) + (1.0 - mix) * bg;
}

fn mx_screen_color3(fg: vec3<f32>, bg: vec3<f32>, mix: f32) -> vec3<f32> {
    return mix * (1.0 - (1.0 - fg) * (1.0 - bg)) + (1.0 - mix) * bg;
}

fn mx_screen_color4(fg: vec4<f32>, bg: vec4<f32>, mix: f32) -> vec4<f32> {
    return mix * (1.0 - (1.0 - fg) * (1.0 - bg)) + (1.0 - mix) * bg;
}

// ---- disjointover ----

fn mx_disjointover_color4(fg: vec4<f32>, bg: vec4<f32>, mix: f32) -> vec4<f32> {
    let summed_alpha = fg.a + bg.a;
    var rgb = fg.rgb + bg.rgb;
    if (summed_alpha > 1.0) {
        if (abs(bg.a) < mx_compositing_float_eps) {
            rgb = vec3<f32>(0.0);
        } else {
            rgb = fg.rgb + bg.rgb * ((1.0 - fg.a) / bg.a);
        }
    }
    let a = min(summed_alpha, 1.0);
    return vec4<f32>(rgb * mix + (1.0 - mix) * bg.rgb, a * mix + (1.0 - mix) * bg.a);
}

// ---- in ----

fn mx_in_color4(fg: vec4<f32>, bg: vec4<f32>, mix: f32) -> vec4<f32> {
    return fg * bg.a * mix + bg * (1.0 - mix);
}

// ---- mask ----

fn mx_mask_color4(fg: vec4<f32>, bg: vec4<f32>, mix: f32) -> vec4<f32> {
    return bg * fg.a * mix + bg * (1.0 - mix);
}

// ---- matte ----

fn mx_matte_color4(fg: vec4<f32>, bg: vec4<f32>, mix: f32) -> vec4<f32> {
    let c = vec4<f32>(fg.rgb * fg.a + bg.rgb * (1.0 - fg.a), fg.a + bg.a * (1.0 - fg.a));
    return c * mix + bg * (1.0 - mix);
}

// ---- out ----

fn mx_out_color4(fg: vec4<f32>, bg: vec4<f32>, mix: f32) -> vec4<f32> {
    return fg * (1.0 - bg.a) * mix + bg * (1.0 - mix);
}

// ---- over ----

fn mx_over_color4(fg: vec4<f32>, bg: vec4<f32>, mix: f32) -> vec4<f32> {
    return (fg + bg * (1.0 - fg.a)) * mix + bg * (1.0 - mix);
}

// ---- inside ----

fn mx_inside_float(in: f32, mask: f32) -> f32 {
    return in * mask;
}

fn mx_inside_color3(in: vec3<f32>, mask: f32) -> vec3<f32> {
    return in * mask;
}

fn mx_inside_color4(in: vec4<f32>, mask: f32) -> vec4<f32> {
    return in * mask;
}

// ---- outside ----

fn mx_outside_float(in: f32, mask: f32) -> f32 {
    return in * (1.0 - mask);
}

fn mx_outside_color3(in: vec3<f32>, mask: f32) -> vec3<f32> {
    return in * (1.0 - mask);
}

fn mx_outside_color4(in: vec4<f32>, mask: f32) -> vec4<f32> {
    return in * (1.0 - mask);
}

// ---- mix ----

fn mx_mix_float(fg: f32, bg: f32, mix: f32) -> f32 {
    return bg * (1.0 - mix) + fg * mix;
}

fn mx_mix_color3(fg: vec3<f32>, bg: vec3<f32>, mix: f32) -> vec3<f32> {
    return bg * (1.0 - mix) + fg * mix;
}

fn mx_mix_color3_color3(fg: vec3<f32>, bg: vec3<f32>, mix: vec3<f32>) -> vec3<f32> {
    return bg * (1.0 - mix) + fg * mix;
}

fn mx_mix_color4(fg: vec4<f32>, bg: vec4<f32>, mix: f32) -> vec4<f32> {
    return bg * (1.0 - mix) + fg * mix;
}

fn mx_mix_color4_color4(fg: vec4<f32>, bg: vec4<f32>, mix: vec4<f32>) -> vec4<f32> {
    return bg * (1.0 - mix) + fg * mix;
}

fn mx_mix_vector2(fg: vec2<f32>, bg: vec2<f32>, mix: f32) -> vec2<f32> {
    return bg * (1.0 - mix) + fg * mix;
}

fn mx_mix_vector2_vector2(fg: vec2<f32>, bg: vec2<f32>, mix: vec2<f32>) -> vec2<f32> {
    return bg * (1.0 - mix) + fg * mix;
}

fn mx_mix_vector3(fg: vec3<f32>, bg: vec3<f32>, mix: f32) -> vec3<f32> {
    return bg * (1.0 - mix) + fg * mix;
}

fn mx_mix_vector3_vector3(fg: vec3<f32>, bg: vec3<f32>, mix: vec3<f32>) -> vec3<f32> {
    return bg * (1.0 - mix) + fg * mix;
}

fn mx_mix_vector4(fg: vec4<f32>, bg: vec4<f32>, mix: f32) -> vec4<f32> {
    return bg * (1.0 - mix) + fg * mix;
}

fn mx_mix_vector4_vector4(fg: vec4<f32>, bg: vec4<f32>, mix: vec4<f32>) -> vec4<f32> {
    return bg * (1.0 - mix) + fg * mix;
}
