// Organization nodes of the MaterialX standard library (nodegroup "organization"): `dot`, which
// passes `in` through (its `note` string is metadata and is not passed).
// Semantics follow MaterialX's reference GLSL implementation (libraries/stdlib/genglsl).

// ---- dot ----

fn mx_dot_float(in: f32) -> f32 {
    return in;
}

fn mx_dot_color3(in: vec3<f32>) -> vec3<f32> {
    return in;
}

fn mx_dot_color4(in: vec4<f32>) -> vec4<f32> {
    return in;
}

fn mx_dot_vector2(in: vec2<f32>) -> vec2<f32> {
    return in;
}

fn mx_dot_vector3(in: vec3<f32>) -> vec3<f32> {
    return in;
}

fn mx_dot_vector4(in: vec4<f32>) -> vec4<f32> {
    return in;
}

fn mx_dot_boolean(in: bool) -> bool {
    return in;
}

fn mx_dot_integer(in: i32) -> i32 {
    return in;
}

fn mx_dot_matrix33(in: mat3x3<f32>) -> mat3x3<f32> {
    return in;
}

fn mx_dot_matrix44(in: mat4x4<f32>) -> mat4x4<f32> {
    return in;
}
