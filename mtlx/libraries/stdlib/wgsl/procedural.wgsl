// procedural.wgsl: UV ramps and splits (ramplr, ramptb, splitlr, splittb), all six types each
// (float, color3, color4, vector2, vector3, vector4).
//
// ramplr  = mix(valuel, valuer, clamp(u, 0, 1))
// ramptb  = mix(valueb, valuet, clamp(v, 0, 1))     valuet at the top edge (v = 1)
// splitlr = u >= center ? valuer : valuel
// splittb = v >= center ? valuet : valueb
//
// Deviations from MaterialX's GLSL, on purpose:
// * splitlr/splittb: the GLSL uses mx_aastep(center, x), a smoothstep over +-fwidth(x)/sqrt(2)
//   for antialiasing. Kernels here are compute shaders with no derivatives, so the split is a
//   hard step: exactly at x == center the right (splitlr) / top (splittb) value is returned.
// * ramptb/splittb: MaterialX GLSL/OSL up to 1.39.4 computed mix(valuet, valueb, ...), which
//   puts valuet at v = 0, contradicting the spec ("valuet: value at the top (V=1) edge").
//   MaterialX 1.39.5 fixed the GLSL (issue #1758, PR 2721); we follow the spec and 1.39.5:
//   valueb at v = 0, valuet at v = 1.

// ---- ramplr ----

fn mx_ramplr_float(valuel: f32, valuer: f32, texcoord: vec2<f32>) -> f32 {
    return mix(valuel, valuer, clamp(texcoord.x, 0.0, 1.0));
}

fn mx_ramplr_color3(valuel: vec3<f32>, valuer: vec3<f32>, texcoord: vec2<f32>) -> vec3<f32> {
    return mix(valuel, valuer, clamp(texcoord.x, 0.0, 1.0));
}

fn mx_ramplr_color4(valuel: vec4<f32>, valuer: vec4<f32>, texcoord: vec2<f32>) -> vec4<f32> {
    return mix(valuel, valuer, clamp(texcoord.x, 0.0, 1.0));
}

fn mx_ramplr_vector2(valuel: vec2<f32>, valuer: vec2<f32>, texcoord: vec2<f32>) -> vec2<f32> {
    return mix(valuel, valuer, clamp(texcoord.x, 0.0, 1.0));
}

fn mx_ramplr_vector3(valuel: vec3<f32>, valuer: vec3<f32>, texcoord: vec2<f32>) -> vec3<f32> {
    return mix(valuel, valuer, clamp(texcoord.x, 0.0, 1.0));
}

fn mx_ramplr_vector4(valuel: vec4<f32>, valuer: vec4<f32>, texcoord: vec2<f32>) -> vec4<f32> {
    return mix(valuel, valuer, clamp(texcoord.x, 0.0, 1.0));
}

// ---- ramptb ----

fn mx_ramptb_float(valuet: f32, valueb: f32, texcoord: vec2<f32>) -> f32 {
    return mix(valueb, valuet, clamp(texcoord.y, 0.0, 1.0));
}

fn mx_ramptb_color3(valuet: vec3<f32>, valueb: vec3<f32>, texcoord: vec2<f32>) -> vec3<f32> {
    return mix(valueb, valuet, clamp(texcoord.y, 0.0, 1.0));
}

fn mx_ramptb_color4(valuet: vec4<f32>, valueb: vec4<f32>, texcoord: vec2<f32>) -> vec4<f32> {
    return mix(valueb, valuet, clamp(texcoord.y, 0.0, 1.0));
}

fn mx_ramptb_vector2(valuet: vec2<f32>, valueb: vec2<f32>, texcoord: vec2<f32>) -> vec2<f32> {
    return mix(valueb, valuet, clamp(texcoord.y, 0.0, 1.0));
}

fn mx_ramptb_vector3(valuet: vec3<f32>, valueb: vec3<f32>, texcoord: vec2<f32>) -> vec3<f32> {
    return mix(valueb, valuet, clamp(texcoord.y, 0.0, 1.0));
}

fn mx_ramptb_vector4(valuet: vec4<f32>, valueb: vec4<f32>, texcoord: vec2<f32>) -> vec4<f32> {
    return mix(valueb, valuet, clamp(texcoord.y, 0.0, 1.0));
}

// ---- splitlr ----

fn mx_splitlr_float(valuel: f32, valuer: f32, center: f32, texcoord: vec2<f32>) -> f32 {
    return select(valuel, valuer, texcoord.x >= center);
}

fn mx_splitlr_color3(valuel: vec3<f32>, valuer: vec3<f32>, center: f32, texcoord: vec2<f32>) -> vec3<f32> {
    return select(valuel, valuer, texcoord.x >= center);
}

fn mx_splitlr_color4(valuel: vec4<f32>, valuer: vec4<f32>, center: f32, texcoord: vec2<f32>) -> vec4<f32> {
    return select(valuel, valuer, texcoord.x >= center);
}

fn mx_splitlr_vector2(valuel: vec2<f32>, valuer: vec2<f32>, center: f32, texcoord: vec2<f32>) -> vec2<f32> {
    return select(valuel, valuer, texcoord.x >= center);
}

fn mx_splitlr_vector3(valuel: vec3<f32>, valuer: vec3<f32>, center: f32, texcoord: vec2<f32>) -> vec3<f32> {
    return select(valuel, valuer, texcoord.x >= center);
}

fn mx_splitlr_vector4(valuel: vec4<f32>, valuer: vec4<f32>, center: f32, texcoord: vec2<f32>) -> vec4<f32> {
    return select(valuel, valuer, texcoord.x >= center);
}

// ---- splittb ----

fn mx_splittb_float(valuet: f32, valueb: f32, center: f32, texcoord: vec2<f32>) -> f32 {
    return select(valueb, valuet, texcoord.y >= center);
}

fn mx_splittb_color3(valuet: vec3<f32>, valueb: vec3<f32>, center: f32, texcoord: vec2<f32>) -> vec3<f32> {
    return select(valueb, valuet, texcoord.y >= center);
}

fn mx_splittb_color4(valuet: vec4<f32>, valueb: vec4<f32>, center: f32, texcoord: vec2<f32>) -> vec4<f32> {
    return select(valueb, valuet, texcoord.y >= center);
}

fn mx_splittb_vector2(valuet: vec2<f32>, valueb: vec2<f32>, center: f32, texcoord: vec2<f32>) -> vec2<f32> {
    return select(valueb, valuet, texcoord.y >= center);
}

fn mx_splittb_vector3(valuet: vec3<f32>, valueb: vec3<f32>, center: f32, texcoord: vec2<f32>) -> vec3<f32> {
    return select(valueb, valuet, texcoord.y >= center);
}

fn mx_splittb_vector4(valuet: vec4<f32>, valueb: vec4<f32>, center: f32, texcoord: vec2<f32>) -> vec4<f32> {
    return select(valueb, valuet, texcoord.y >= center);
}
