// Channel nodes of the MaterialX standard library (nodegroup "channel"): the atomic convert
// variants, combine2/3/4 and extract. (The other convert/separate variants are nodegraphs.)
// Semantics follow MaterialX's reference GLSL implementation (libraries/stdlib/genglsl).

// ---- convert ----

fn mx_convert_boolean_float(in: bool) -> f32 {
    return select(0.0, 1.0, in);
}

fn mx_convert_integer_float(in: i32) -> f32 {
    return f32(in);
}

// ---- combine2 ----

fn mx_combine2_vector2(in1: f32, in2: f32) -> vec2<f32> {
    return vec2<f32>(in1, in2);
}

fn mx_combine2_color4CF(in1: vec3<f32>, in2: f32) -> vec4<f32> {
    return vec4<f32>(in1, in2);
}

fn mx_combine2_vector4VF(in1: vec3<f32>, in2: f32) -> vec4<f32> {
    return vec4<f32>(in1, in2);
}

fn mx_combine2_vector4VV(in1: vec2<f32>, in2: vec2<f32>) -> vec4<f32> {
    return vec4<f32>(in1, in2);
}

// ---- combine3 ----

fn mx_combine3_color3(in1: f32, in2: f32, in3: f32) -> vec3<f32> {
    return vec3<f32>(in1, in2, in3);
}

fn mx_combine3_vector3(in1: f32, in2: f32, in3: f32) -> vec3<f32> {
    return vec3<f32>(in1, in2, in3);
}

// ---- combine4 ----

fn mx_combine4_color4(in1: f32, in2: f32, in3: f32, in4: f32) -> vec4<f32> {
    return vec4<f32>(in1, in2, in3, in4);
}

fn mx_combine4_vector4(in1: f32, in2: f32, in3: f32, in4: f32) -> vec4<f32> {
    return vec4<f32>(in1, in2, in3, in4);
}

// ---- extract ----

fn mx_extract_color3(in: vec3<f32>, index: i32) -> f32 {
    // Out-of-range indices are clamped (GLSL leaves them undefined).
    return in[clamp(index, 0, 2)];
}

fn mx_extract_color4(in: vec4<f32>, index: i32) -> f32 {
    // Out-of-range indices are clamped (GLSL leaves them undefined).
    return in[clamp(index, 0, 3)];
}

fn mx_extract_vector2(in: vec2<f32>, index: i32) -> f32 {
    // Out-of-range indices are clamped (GLSL leaves them undefined).
    return in[clamp(index, 0, 1)];
}

fn mx_extract_vector3(in: vec3<f32>, index: i32) -> f32 {
    // Out-of-range indices are clamped (GLSL leaves them undefined).
    return in[clamp(index, 0, 2)];
}

fn mx_extract_vector4(in: vec4<f32>, index: i32) -> f32 {
    // Out-of-range indices are clamped (GLSL leaves them undefined).
    return in[clamp(index, 0, 3)];
}

fn mx_extract_matrix33(in: mat3x3<f32>, index: i32) -> vec3<f32> {
    // Out-of-range indices are clamped (GLSL leaves them undefined).
    return in[clamp(index, 0, 2)];
}

fn mx_extract_matrix44(in: mat4x4<f32>, index: i32) -> vec4<f32> {
    // Out-of-range indices are clamped (GLSL leaves them undefined).
    return in[clamp(index, 0, 3)];
}
