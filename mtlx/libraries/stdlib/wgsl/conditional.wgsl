// Conditional nodes of the MaterialX standard library (nodegroup "conditional"): ifgreater,
// ifgreatereq, ifequal (float, integer `I` and boolean `B` comparands) and the logical and/or/not.
// Semantics follow MaterialX's reference GLSL implementation (libraries/stdlib/genglsl):
// ifgreater is strict `>`, ifgreatereq is `>=`, ifequal is `==`; true selects in1, false in2.

// ---- ifgreater ----

fn mx_ifgreater_float(value1: f32, value2: f32, in1: f32, in2: f32) -> f32 {
    if (value1 > value2) {
        return in1;
    }
    return in2;
}

fn mx_ifgreater_integer(value1: f32, value2: f32, in1: i32, in2: i32) -> i32 {
    if (value1 > value2) {
        return in1;
    }
    return in2;
}

fn mx_ifgreater_color3(value1: f32, value2: f32, in1: vec3<f32>, in2: vec3<f32>) -> vec3<f32> {
    if (value1 > value2) {
        return in1;
    }
    return in2;
}

fn mx_ifgreater_color4(value1: f32, value2: f32, in1: vec4<f32>, in2: vec4<f32>) -> vec4<f32> {
    if (value1 > value2) {
        return in1;
    }
    return in2;
}

fn mx_ifgreater_vector2(value1: f32, value2: f32, in1: vec2<f32>, in2: vec2<f32>) -> vec2<f32> {
    if (value1 > value2) {
        return in1;
    }
    return in2;
}

fn mx_ifgreater_vector3(value1: f32, value2: f32, in1: vec3<f32>, in2: vec3<f32>) -> vec3<f32> {
    if (value1 > value2) {
        return in1;
    }
    return in2;
}

fn mx_ifgreater_vector4(value1: f32, value2: f32, in1: vec4<f32>, in2: vec4<f32>) -> vec4<f32> {
    if (value1 > value2) {
        return in1;
    }
    return in2;
}

fn mx_ifgreater_matrix33(value1: f32, value2: f32, in1: mat3x3<f32>, in2: mat3x3<f32>) -> mat3x3<f32> {
    if (value1 > value2) {
        return in1;
    }
    return in2;
}

fn mx_ifgreater_matrix44(value1: f32, value2: f32, in1: mat4x4<f32>, in2: mat4x4<f32>) -> mat4x4<f32> {
    if (value1 > value2) {
        return in1;
    }
    return in2;
}

fn mx_ifgreater_boolean(value1: f32, value2: f32) -> bool {
    return value1 > value2;
}

fn mx_ifgreater_floatI(value1: i32, value2: i32, in1: f32, in2: f32) -> f32 {
    if (value1 > value2) {
        return in1;
    }
    return in2;
}

fn mx_ifgreater_integerI(value1: i32, value2: i32, in1: i32, in2: i32) -> i32 {
    if (value1 > value2) {
        return in1;
    }
    return in2;
}

fn mx_ifgreater_color3I(value1: i32, value2: i32, in1: vec3<f32>, in2: vec3<f32>) -> vec3<f32> {
    if (value1 > value2) {
        return in1;
    }
    return in2;
}

fn mx_ifgreater_color4I(value1: i32, value2: i32, in1: vec4<f32>, in2: vec4<f32>) -> vec4<f32> {
    if (value1 > value2) {
        return in1;
    }
    return in2;
}

fn mx_ifgreater_vector2I(value1: i32, value2: i32, in1: vec2<f32>, in2: vec2<f32>) -> vec2<f32> {
    if (value1 > value2) {
        return in1;
    }
    return in2;
}

fn mx_ifgreater_vector3I(value1: i32, value2: i32, in1: vec3<f32>, in2: vec3<f32>) -> vec3<f32> {
    if (value1 > value2) {
        return in1;
    }
    return in2;
}

fn mx_ifgreater_vector4I(value1: i32, value2: i32, in1: vec4<f32>, in2: vec4<f32>) -> vec4<f32> {
    if (value1 > value2) {
        return in1;
    }
    return in2;
}

fn mx_ifgreater_matrix33I(value1: i32, value2: i32, in1: mat3x3<f32>, in2: mat3x3<f32>) -> mat3x3<f32> {
    if (value1 > value2) {
        return in1;
    }
    return in2;
}

fn mx_ifgreater_matrix44I(value1: i32, value2: i32, in1: mat4x4<f32>, in2: mat4x4<f32>) -> mat4x4<f32> {
    if (value1 > value2) {
        return in1;
    }
    return in2;
}

fn mx_ifgreater_booleanI(value1: i32, value2: i32) -> bool {
    return value1 > value2;
}

// ---- ifgreatereq ----

fn mx_ifgreatereq_float(value1: f32, value2: f32, in1: f32, in2: f32) -> f32 {
    if (value1 >= value2) {
        return in1;
    }
    return in2;
}

fn mx_ifgreatereq_integer(value1: f32, value2: f32, in1: i32, in2: i32) -> i32 {
    if (value1 >= value2) {
        return in1;
    }
    return in2;
}

fn mx_ifgreatereq_color3(value1: f32, value2: f32, in1: vec3<f32>, in2: vec3<f32>) -> vec3<f32> {
    if (value1 >= value2) {
        return in1;
    }
    return in2;
}

fn mx_ifgreatereq_color4(value1: f32, value2: f32, in1: vec4<f32>, in2: vec4<f32>) -> vec4<f32> {
    if (value1 >= value2) {
        return in1;
    }
    return in2;
}

fn mx_ifgreatereq_vector2(value1: f32, value2: f32, in1: vec2<f32>, in2: vec2<f32>) -> vec2<f32> {
    if (value1 >= value2) {
        return in1;
    }
    return in2;
}

fn mx_ifgreatereq_vector3(value1: f32, value2: f32, in1: vec3<f32>, in2: vec3<f32>) -> vec3<f32> {
    if (value1 >= value2) {
        return in1;
    }
    return in2;
}

fn mx_ifgreatereq_vector4(value1: f32, value2: f32, in1: vec4<f32>, in2: vec4<f32>) -> vec4<f32> {
    if (value1 >= value2) {
        return in1;
    }
    return in2;
}

fn mx_ifgreatereq_matrix33(value1: f32, value2: f32, in1: mat3x3<f32>, in2: mat3x3<f32>) -> mat3x3<f32> {
    if (value1 >= value2) {
        return in1;
    }
    return in2;
}

fn mx_ifgreatereq_matrix44(value1: f32, value2: f32, in1: mat4x4<f32>, in2: mat4x4<f32>) -> mat4x4<f32> {
    if (value1 >= value2) {
        return in1;
    }
    return in2;
}

fn mx_ifgreatereq_boolean(value1: f32, value2: f32) -> bool {
    return value1 >= value2;
}

fn mx_ifgreatereq_floatI(value1: i32, value2: i32, in1: f32, in2: f32) -> f32 {
    if (value1 >= value2) {
        return in1;
    }
    return in2;
}

fn mx_ifgreatereq_integerI(value1: i32, value2: i32, in1: i32, in2: i32) -> i32 {
    if (value1 >= value2) {
        return in1;
    }
    return in2;
}

fn mx_ifgreatereq_color3I(value1: i32, value2: i32, in1: vec3<f32>, in2: vec3<f32>) -> vec3<f32> {
    if (value1 >= value2) {
        return in1;
    }
    return in2;
}

fn mx_ifgreatereq_color4I(value1: i32, value2: i32, in1: vec4<f32>, in2: vec4<f32>) -> vec4<f32> {
    if (value1 >= value2) {
        return in1;
    }
    return in2;
}

fn mx_ifgreatereq_vector2I(value1: i32, value2: i32, in1: vec2<f32>, in2: vec2<f32>) -> vec2<f32> {
    if (value1 >= value2) {
        return in1;
    }
    return in2;
}

fn mx_ifgreatereq_vector3I(value1: i32, value2: i32, in1: vec3<f32>, in2: vec3<f32>) -> vec3<f32> {
    if (value1 >= value2) {
        return in1;
    }
    return in2;
}

fn mx_ifgreatereq_vector4I(value1: i32, value2: i32, in1: vec4<f32>, in2: vec4<f32>) -> vec4<f32> {
    if (value1 >= value2) {
        return in1;
    }
    return in2;
}

fn mx_ifgreatereq_matrix33I(value1: i32, value2: i32, in1: mat3x3<f32>, in2: mat3x3<f32>) -> mat3x3<f32> {
    if (value1 >= value2) {
        return in1;
    }
    return in2;
}

fn mx_ifgreatereq_matrix44I(value1: i32, value2: i32, in1: mat4x4<f32>, in2: mat4x4<f32>) -> mat4x4<f32> {
    if (value1 >= value2) {
        return in1;
    }
    return in2;
}

fn mx_ifgreatereq_booleanI(value1: i32, value2: i32) -> bool {
    return value1 >= value2;
}

// ---- ifequal ----

fn mx_ifequal_float(value1: f32, value2: f32, in1: f32, in2: f32) -> f32 {
    if (value1 == value2) {
        return in1;
    }
    return in2;
}

fn mx_ifequal_integer(value1: f32, value2: f32, in1: i32, in2: i32) -> i32 {
    if (value1 == value2) {
        return in1;
    }
    return in2;
}

fn mx_ifequal_color3(value1: f32, value2: f32, in1: vec3<f32>, in2: vec3<f32>) -> vec3<f32> {
    if (value1 == value2) {
        return in1;
    }
    return in2;
}

fn mx_ifequal_color4(value1: f32, value2: f32, in1: vec4<f32>, in2: vec4<f32>) -> vec4<f32> {
    if (value1 == value2) {
        return in1;
    }
    return in2;
}

fn mx_ifequal_vector2(value1: f32, value2: f32, in1: vec2<f32>, in2: vec2<f32>) -> vec2<f32> {
    if (value1 == value2) {
        return in1;
    }
    return in2;
}

fn mx_ifequal_vector3(value1: f32, value2: f32, in1: vec3<f32>, in2: vec3<f32>) -> vec3<f32> {
    if (value1 == value2) {
        return in1;
    }
    return in2;
}

fn mx_ifequal_vector4(value1: f32, value2: f32, in1: vec4<f32>, in2: vec4<f32>) -> vec4<f32> {
    if (value1 == value2) {
        return in1;
    }
    return in2;
}

fn mx_ifequal_matrix33(value1: f32, value2: f32, in1: mat3x3<f32>, in2: mat3x3<f32>) -> mat3x3<f32> {
    if (value1 == value2) {
        return in1;
    }
    return in2;
}

fn mx_ifequal_matrix44(value1: f32, value2: f32, in1: mat4x4<f32>, in2: mat4x4<f32>) -> mat4x4<f32> {
    if (value1 == value2) {
        return in1;
    }
    return in2;
}

fn mx_ifequal_boolean(value1: f32, value2: f32) -> bool {
    return value1 == value2;
}

fn mx_ifequal_floatI(value1: i32, value2: i32, in1: f32, in2: f32) -> f32 {
    if (value1 == value2) {
        return in1;
    }
    return in2;
}

fn mx_ifequal_integerI(value1: i32, value2: i32, in1: i32, in2: i32) -> i32 {
    if (value1 == value2) {
        return in1;
    }
    return in2;
}

fn mx_ifequal_color3I(value1: i32, value2: i32, in1: vec3<f32>, in2: vec3<f32>) -> vec3<f32> {
    if (value1 == value2) {
        return in1;
    }
    return in2;
}

fn mx_ifequal_color4I(value1: i32, value2: i32, in1: vec4<f32>, in2: vec4<f32>) -> vec4<f32> {
    if (value1 == value2) {
        return in1;
    }
    return in2;
}

fn mx_ifequal_vector2I(value1: i32, value2: i32, in1: vec2<f32>, in2: vec2<f32>) -> vec2<f32> {
    if (value1 == value2) {
        return in1;
    }
    return in2;
}

fn mx_ifequal_vector3I(value1: i32, value2: i32, in1: vec3<f32>, in2: vec3<f32>) -> vec3<f32> {
    if (value1 == value2) {
        return in1;
    }
    return in2;
}

fn mx_ifequal_vector4I(value1: i32, value2: i32, in1: vec4<f32>, in2: vec4<f32>) -> vec4<f32> {
    if (value1 == value2) {
        return in1;
    }
    return in2;
}

fn mx_ifequal_matrix33I(value1: i32, value2: i32, in1: mat3x3<f32>, in2: mat3x3<f32>) -> mat3x3<f32> {
    if (value1 == value2) {
        return in1;
    }
    return in2;
}

fn mx_ifequal_matrix44I(value1: i32, value2: i32, in1: mat4x4<f32>, in2: mat4x4<f32>) -> mat4x4<f32> {
    if (value1 == value2) {
        return in1;
    }
    return in2;
}

fn mx_ifequal_booleanI(value1: i32, value2: i32) -> bool {
    return value1 == value2;
}

fn mx_ifequal_floatB(value1: bool, value2: bool, in1: f32, in2: f32) -> f32 {
    if (value1 == value2) {
        return in1;
    }
    return in2;
}

fn mx_ifequal_integerB(value1: bool, value2: bool, in1: i32, in2: i32) -> i32 {
    if (value1 == value2) {
        return in1;
    }
    return in2;
}

fn mx_ifequal_color3B(value1: bool, value2: bool, in1: vec3<f32>, in2: vec3<f32>) -> vec3<f32> {
    if (value1 == value2) {
        return in1;
    }
    return in2;
}

fn mx_ifequal_color4B(value1: bool, value2: bool, in1: vec4<f32>, in2: vec4<f32>) -> vec4<f32> {
    if (value1 == value2) {
        return in1;
    }
    return in2;
}

fn mx_ifequal_vector2B(value1: bool, value2: bool, in1: vec2<f32>, in2: vec2<f32>) -> vec2<f32> {
    if (value1 == value2) {
        return in1;
    }
    return in2;
}

fn mx_ifequal_vector3B(value1: bool, value2: bool, in1: vec3<f32>, in2: vec3<f32>) -> vec3<f32> {
    if (value1 == value2) {
        return in1;
    }
    return in2;
}

fn mx_ifequal_vector4B(value1: bool, value2: bool, in1: vec4<f32>, in2: vec4<f32>) -> vec4<f32> {
    if (value1 == value2) {
        return in1;
    }
    return in2;
}

fn mx_ifequal_matrix33B(value1: bool, value2: bool, in1: mat3x3<f32>, in2: mat3x3<f32>) -> mat3x3<f32> {
    if (value1 == value2) {
        return in1;
    }
    return in2;
}

fn mx_ifequal_matrix44B(value1: bool, value2: bool, in1: mat4x4<f32>, in2: mat4x4<f32>) -> mat4x4<f32> {
    if (value1 == value2) {
        return in1;
    }
    return in2;
}

fn mx_ifequal_booleanB(value1: bool, value2: bool) -> bool {
    return value1 == value2;
}

// ---- and ----

fn mx_logical_and(in1: bool, in2: bool) -> bool {
    return in1 && in2;
}

// ---- or ----

fn mx_logical_or(in1: bool, in2: bool) -> bool {
    return in1 || in2;
}

// ---- not ----

fn mx_logical_not(in: bool) -> bool {
    return !in;
}
