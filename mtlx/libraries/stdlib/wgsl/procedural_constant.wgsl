// The `constant` node of the MaterialX standard library (nodegroup "procedural"): returns `value`.
// The string and filename variants have no WGSL function (a string without enum is not passed,
// and a texture cannot be returned).
// Semantics follow MaterialX's reference GLSL implementation (libraries/stdlib/genglsl).

// ---- constant ----

fn mx_constant_float(value: f32) -> f32 {
    return value;
}

fn mx_constant_color3(value: vec3<f32>) -> vec3<f32> {
    return value;
}

fn mx_constant_color4(value: vec4<f32>) -> vec4<f32> {
    return value;
}

fn mx_constant_vector2(value: vec2<f32>) -> vec2<f32> {
    return value;
}

fn mx_constant_vector3(value: vec3<f32>) -> vec3<f32> {
    return value;
}

fn mx_constant_vector4(value: vec4<f32>) -> vec4<f32> {
    return value;
}

fn mx_constant_boolean(value: bool) -> bool {
    return value;
}

fn mx_constant_integer(value: i32) -> i32 {
    return value;
}

fn mx_constant_matrix33(value: mat3x3<f32>) -> mat3x3<f32> {
    return value;
}

fn mx_constant_matrix44(value: mat4x4<f32>) -> mat4x4<f32> {
    return value;
}
