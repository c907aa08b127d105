// Math nodes of the MaterialX standard library (nodegroup "math"): arithmetic, trigonometry,
// vector and matrix operations, rotate2d/rotate3d, normalmap, and the space transforms.
// One `mx_<x>` function per atomic nodedef `ND_<x>` (see ../../README.md).
// Semantics follow MaterialX's reference GLSL implementation (libraries/stdlib/genglsl);
// deviations are noted on the function.

// 3x3 inverse by cofactors (GLSL inverse()). inverse(transpose(M)) == transpose(inverse(M)), so this
// matches GLSL on the same column layout. A singular matrix gives inf/NaN, as in GLSL.
fn mx_math_inverse3(m: mat3x3<f32>) -> mat3x3<f32> {
    let a = m[0];
    let b = m[1];
    let c = m[2];
    let r0 = cross(b, c);
    let r1 = cross(c, a);
    let r2 = cross(a, b);
    let inv_det = 1.0 / dot(a, r0);
    return transpose(mat3x3<f32>(r0, r1, r2)) * inv_det;
}

// 4x4 inverse by cofactors (GLSL inverse()).
fn mx_math_inverse4(m: mat4x4<f32>) -> mat4x4<f32> {
    let a00 = m[0][0]; let a01 = m[0][1]; let a02 = m[0][2]; let a03 = m[0][3];
    let a10 = m[1][0]; let a11 = m[1][1]; let a12 = m[1][2]; let a13 = m[1][3];
    let a20 = m[2][0]; let a21 = m[2][1]; let a22 = m[2][2]; let a23 = m[2][3];
    let a30 = m[3][0]; let a31 = m[3][1]; let a32 = m[3][2]; let a33 = m[3][3];

    let b00 = a00 * a11 - a01 * a10;
    let b01 = a00 * a12 - a02 * a10;
    let b02 = a00 * a13 - a03 * a10;
    let b03 = a01 * a12 - a02 * a11;
    let b04 = a01 * a13 - a03 * a11;
    let b05 = a02 * a13 - a03 * a12;
    let b06 = a20 * a31 - a21 * a30;
    let b07 = a20 * a32 - a22 * a30;
    let b08 = a20 * a33 - a23 * a30;
    let b09 = a21 * a32 - a22 * a31;
    let b10 = a21 * a33 - a23 * a31;
    let b11 = a22 * a33 - a23 * a32;

    let det = b00 * b11 - b01 * b10 + b02 * b09 + b03 * b08 - b04 * b07 + b05 * b06;
    let inv_det = 1.0 / det;

    return mat4x4<f32>(
        vec4<f32>(a11 * b11 - a12 * b10 + a13 * b09,
                  a02 * b10 - a01 * b11 - a03 * b09,
                  a31 * b05 - a32 * b04 + a33 * b03,
                  a22 * b04 - a21 * b05 - a23 * b03) * inv_det,
        vec4<f32>(a12 * b08 - a10 * b11 - a13 * b07,
                  a00 * b11 - a02 * b08 + a03 * b07,
                  a32 * b02 - a30 * b05 - a33 * b01,
                  a20 * b05 - a22 * b02 + a23 * b01) * inv_det,
        vec4<f32>(a10 * b10 - a11 * b08 + a13 * b06,
                  a01 * b08 - a00 * b10 - a03 * b06,
                  a30 * b04 - a31 * b02 + a33 * b00,
                  a21 * b02 - a20 * b04 - a23 * b00) * inv_det,
        vec4<f32>(a11 * b07 - a10 * b09 - a12 * b06,
                  a00 * b09 - a01 * b07 + a02 * b06,
                  a31 * b01 - a30 * b03 - a32 * b00,
                  a20 * b03 - a21 * b01 + a22 * b00) * inv_det);
}

// Rotation by `angle` radians about `axis`: MaterialX GLSL mx_rotationMatrix, whose mat4 is
// written with the same value list (its fourth row/column is the identity, so for
// `(m * vec4(v, 1.0)).xyz` a mat3x3 gives the same result).
fn mx_math_rotation_matrix(axis_in: vec3<f32>, angle: f32) -> mat3x3<f32> {
    let axis = normalize(axis_in);
    let s = sin(angle);
    let c = cos(angle);
    let oc = 1.0 - c;
    return mat3x3<f32>(
        oc * axis.x * axis.x + c, oc * axis.x * axis.y - axis.z * s, oc * axis.z * axis.x + axis.y * s,
        oc * axis.x * axis.y + axis.z * s, oc * axis.y * axis.y + c, oc * axis.y * axis.z - axis.x * s,
        oc * axis.z * axis.x - axis.y * s, oc * axis.y * axis.z + axis.x * s, oc * axis.z * axis.z + c);
}

// ---- add ----

fn mx_add_float(in1: f32, in2: f32) -> f32 {
    return in1 + in2;
}

fn mx_add_integer(in1: i32, in2: i32) -> i32 {
    return in1 + in2;
}

fn mx_add_color3(in1: vec3<f32>, in2: vec3<f32>) -> vec3<f32> {
    return in1 + in2;
}

fn mx_add_color4(in1: vec4<f32>, in2: vec4<f32>) -> vec4<f32> {
    return in1 + in2;
}

fn mx_add_vector2(in1: vec2<f32>, in2: vec2<f32>) -> vec2<f32> {
    return in1 + in2;
}

fn mx_add_vector3(in1: vec3<f32>, in2: vec3<f32>) -> vec3<f32> {
    return in1 + in2;
}

fn mx_add_vector4(in1: vec4<f32>, in2: vec4<f32>) -> vec4<f32> {
    return in1 + in2;
}

fn mx_add_matrix33(in1: mat3x3<f32>, in2: mat3x3<f32>) -> mat3x3<f32> {
    return in1 + in2;
}

fn mx_add_matrix44(in1: mat4x4<f32>, in2: mat4x4<f32>) -> mat4x4<f32> {
    return in1 + in2;
}

fn mx_add_color3FA(in1: vec3<f32>, in2: f32) -> vec3<f32> {
    return in1 + in2;
}

fn mx_add_color4FA(in1: vec4<f32>, in2: f32) -> vec4<f32> {
    return in1 + in2;
}

fn mx_add_vector2FA(in1: vec2<f32>, in2: f32) -> vec2<f32> {
    return in1 + in2;
}

fn mx_add_vector3FA(in1: vec3<f32>, in2: f32) -> vec3<f32> {
    return in1 + in2;
}

fn mx_add_vector4FA(in1: vec4<f32>, in2: f32) -> vec4<f32> {
    return in1 + in2;
}

fn mx_add_matrix33FA(in1: mat3x3<f32>, in2: f32) -> mat3x3<f32> {
    // GLSL `mat + float` is component-wise.
    return in1 + mat3x3<f32>(vec3<f32>(in2), vec3<f32>(in2), vec3<f32>(in2));
}

fn mx_add_matrix44FA(in1: mat4x4<f32>, in2: f32) -> mat4x4<f32> {
    // GLSL `mat + float` is component-wise.
    return in1 + mat4x4<f32>(vec4<f32>(in2), vec4<f32>(in2), vec4<f32>(in2), vec4<f32>(in2));
}

// ---- subtract ----

fn mx_subtract_float(in1: f32, in2: f32) -> f32 {
    return in1 - in2;
}

fn mx_subtract_integer(in1: i32, in2: i32) -> i32 {
    return in1 - in2;
}

fn mx_subtract_color3(in1: vec3<f32>, in2: vec3<f32>) -> vec3<f32> {
    return in1 - in2;
}

fn mx_subtract_color4(in1: vec4<f32>, in2: vec4<f32>) -> vec4<f32> {
    return in1 - in2;
}

fn mx_subtract_vector2(in1: vec2<f32>, in2: vec2<f32>) -> vec2<f32> {
    return in1 - in2;
}

fn mx_subtract_vector3(in1: vec3<f32>, in2: vec3<f32>) -> vec3<f32> {
    return in1 - in2;
}

fn mx_subtract_vector4(in1: vec4<f32>, in2: vec4<f32>) -> vec4<f32> {
    return in1 - in2;
}

fn mx_subtract_matrix33(in1: mat3x3<f32>, in2: mat3x3<f32>) -> mat3x3<f32> {
    return in1 - in2;
}

fn mx_subtract_matrix44(in1: mat4x4<f32>, in2: mat4x4<f32>) -> mat4x4<f32> {
    return in1 - in2;
}

fn mx_subtract_color3FA(in1: vec3<f32>, in2: f32) -> vec3<f32> {
    return in1 - in2;
}

fn mx_subtract_color4FA(in1: vec4<f32>, in2: f32) -> vec4<f32> {
    return in1 - in2;
}

fn mx_subtract_vector2FA(in1: vec2<f32>, in2: f32) -> vec2<f32> {
    return in1 - in2;
}

fn mx_subtract_vector3FA(in1: vec3<f32>, in2: f32) -> vec3<f32> {
    return in1 - in2;
}

fn mx_subtract_vector4FA(in1: vec4<f32>, in2: f32) -> vec4<f32> {
    return in1 - in2;
}

fn mx_subtract_matrix33FA(in1: mat3x3<f32>, in2: f32) -> mat3x3<f32> {
    // GLSL `mat - float` is component-wise.
    return in1 - mat3x3<f32>(vec3<f32>(in2), vec3<f32>(in2), vec3<f32>(in2));
}

fn mx_subtract_matrix44FA(in1: mat4x4<f32>, in2: f32) -> mat4x4<f32> {
    // GLSL `mat - float` is component-wise.
    return in1 - mat4x4<f32>(vec4<f32>(in2), vec4<f32>(in2), vec4<f32>(in2), vec4<f32>(in2));
}

// ---- multiply ----

fn mx_multiply_float(in1: f32, in2: f32) -> f32 {
    return in1 * in2;
}

fn mx_multiply_color3(in1: vec3<f32>, in2: vec3<f32>) -> vec3<f32> {
    return in1 * in2;
}

fn mx_multiply_color4(in1: vec4<f32>, in2: vec4<f32>) -> vec4<f32> {
    return in1 * in2;
}

fn mx_multiply_vector2(in1: vec2<f32>, in2: vec2<f32>) -> vec2<f32> {
    return in1 * in2;
}

fn mx_multiply_vector3(in1: vec3<f32>, in2: vec3<f32>) -> vec3<f32> {
    return in1 * in2;
}

fn mx_multiply_vector4(in1: vec4<f32>, in2: vec4<f32>) -> vec4<f32> {
    return in1 * in2;
}

fn mx_multiply_matrix33(in1: mat3x3<f32>, in2: mat3x3<f32>) -> mat3x3<f32> {
    return in1 * in2;
}

fn mx_multiply_matrix44(in1: mat4x4<f32>, in2: mat4x4<f32>) -> mat4x4<f32> {
    return in1 * in2;
}

fn mx_multiply_color3FA(in1: vec3<f32>, in2: f32) -> vec3<f32> {
    return in1 * in2;
}

fn mx_multiply_color4FA(in1: vec4<f32>, in2: f32) -> vec4<f32> {
    return in1 * in2;
}

fn mx_multiply_vector2FA(in1: vec2<f32>, in2: f32) -> vec2<f32> {
    return in1 * in2;
}

fn mx_multiply_vector3FA(in1: vec3<f32>, in2: f32) -> vec3<f32> {
    return in1 * in2;
}

fn mx_multiply_vector4FA(in1: vec4<f32>, in2: f32) -> vec4<f32> {
    return in1 * in2;
}

// ---- divide ----

fn mx_divide_float(in1: f32, in2: f32) -> f32 {
    return in1 / in2;
}

fn mx_divide_color3(in1: vec3<f32>, in2: vec3<f32>) -> vec3<f32> {
    return in1 / in2;
}

fn mx_divide_color4(in1: vec4<f32>, in2: vec4<f32>) -> vec4<f32> {
    return in1 / in2;
}

fn mx_divide_vector2(in1: vec2<f32>, in2: vec2<f32>) -> vec2<f32> {
    return in1 / in2;
}

fn mx_divide_vector3(in1: vec3<f32>, in2: vec3<f32>) -> vec3<f32> {
    return in1 / in2;
}

fn mx_divide_vector4(in1: vec4<f32>, in2: vec4<f32>) -> vec4<f32> {
    return in1 / in2;
}

fn mx_divide_matrix33(in1: mat3x3<f32>, in2: mat3x3<f32>) -> mat3x3<f32> {
    // MaterialX GLSL writes `in1 / in2`, which GLSL evaluates component-wise (the spec says
    // in1 * inverse(in2); the GLSL wins, see README).
    return mat3x3<f32>(in1[0] / in2[0], in1[1] / in2[1], in1[2] / in2[2]);
}

fn mx_divide_matrix44(in1: mat4x4<f32>, in2: mat4x4<f32>) -> mat4x4<f32> {
    // MaterialX GLSL writes `in1 / in2`, which GLSL evaluates component-wise (the spec says
    // in1 * inverse(in2); the GLSL wins, see README).
    return mat4x4<f32>(in1[0] / in2[0], in1[1] / in2[1], in1[2] / in2[2], in1[3] / in2[3]);
}

fn mx_divide_color3FA(in1: vec3<f32>, in2: f32) -> vec3<f32> {
    return in1 / in2;
}

fn mx_divide_color4FA(in1: vec4<f32>, in2: f32) -> vec4<f32> {
    return in1 / in2;
}

fn mx_divide_vector2FA(in1: vec2<f32>, in2: f32) -> vec2<f32> {
    return in1 / in2;
}

fn mx_divide_vector3FA(in1: vec3<f32>, in2: f32) -> vec3<f32> {
    return in1 / in2;
}

fn mx_divide_vector4FA(in1: vec4<f32>, in2: f32) -> vec4<f32> {
    return in1 / in2;
}

// ---- modulo ----

fn mx_modulo_float(in1: f32, in2: f32) -> f32 {
    // GLSL mod(): x - y * floor(x / y).
    return in1 - in2 * floor(in1 / in2);
}

fn mx_modulo_color3(in1: vec3<f32>, in2: vec3<f32>) -> vec3<f32> {
    // GLSL mod(): x - y * floor(x / y).
    return in1 - in2 * floor(in1 / in2);
}

fn mx_modulo_color4(in1: vec4<f32>, in2: vec4<f32>) -> vec4<f32> {
    // GLSL mod(): x - y * floor(x / y).
    return in1 - in2 * floor(in1 / in2);
}

fn mx_modulo_vector2(in1: vec2<f32>, in2: vec2<f32>) -> vec2<f32> {
    // GLSL mod(): x - y * floor(x / y).
    return in1 - in2 * floor(in1 / in2);
}

fn mx_modulo_vector3(in1: vec3<f32>, in2: vec3<f32>) -> vec3<f32> {
    // GLSL mod(): x - y * floor(x / y).
    return in1 - in2 * floor(in1 / in2);
}

fn mx_modulo_vector4(in1: vec4<f32>, in2: vec4<f32>) -> vec4<f32> {
    // GLSL mod(): x - y * floor(x / y).
    return in1 - in2 * floor(in1 / in2);
}

fn mx_modulo_color3FA(in1: vec3<f32>, in2: f32) -> vec3<f32> {
    // GLSL mod(): x - y * floor(x / y).
    return in1 - in2 * floor(in1 / in2);
}

fn mx_modulo_color4FA(in1: vec4<f32>, in2: f32) -> vec4<f32> {
    // GLSL mod(): x - y * floor(x / y).
    return in1 - in2 * floor(in1 / in2);
}

fn mx_modulo_vector2FA(in1: vec2<f32>, in2: f32) -> vec2<f32> {
    // GLSL mod(): x - y * floor(x / y).
    return in1 - in2 * floor(in1 / in2);
}

fn mx_modulo_vector3FA(in1: vec3<f32>, in2: f32) -> vec3<f32> {
    // GLSL mod(): x - y * floor(x / y).
    return in1 - in2 * floor(in1 / in2);
}

fn mx_modulo_vector4FA(in1: vec4<f32>, in2: f32) -> vec4<f32> {
    // GLSL mod(): x - y * floor(x / y).
    return in1 - in2 * floor(in1 / in2);
}

// ---- fract ----

fn mx_fract_float(in: f32) -> f32 {
    return fract(in);
}

fn mx_fract_color3(in: vec3<f32>) -> vec3<f32> {
    return fract(in);
}

fn mx_fract_color4(in: vec4<f32>) -> vec4<f32> {
    return fract(in);
}

fn mx_fract_vector2(in: vec2<f32>) -> vec2<f32> {
    return fract(in);
}

fn mx_fract_vector3(in: vec3<f32>) -> vec3<f32> {
    return fract(in);
}

fn mx_fract_vector4(in: vec4<f32>) -> vec4<f32> {
    return fract(in);
}

// ---- invert ----

fn mx_invert_float(in: f32, amount: f32) -> f32 {
    return amount - in;
}

fn mx_invert_color3(in: vec3<f32>, amount: vec3<f32>) -> vec3<f32> {
    return amount - in;
}

fn mx_invert_color4(in: vec4<f32>, amount: vec4<f32>) -> vec4<f32> {
    return amount - in;
}

fn mx_invert_vector2(in: vec2<f32>, amount: vec2<f32>) -> vec2<f32> {
    return amount - in;
}

fn mx_invert_vector3(in: vec3<f32>, amount: vec3<f32>) -> vec3<f32> {
    return amount - in;
}

fn mx_invert_vector4(in: vec4<f32>, amount: vec4<f32>) -> vec4<f32> {
    return amount - in;
}

fn mx_invert_color3FA(in: vec3<f32>, amount: f32) -> vec3<f32> {
    return amount - in;
}

fn mx_invert_color4FA(in: vec4<f32>, amount: f32) -> vec4<f32> {
    return amount - in;
}

fn mx_invert_vector2FA(in: vec2<f32>, amount: f32) -> vec2<f32> {
    return amount - in;
}

fn mx_invert_vector3FA(in: vec3<f32>, amount: f32) -> vec3<f32> {
    return amount - in;
}

fn mx_invert_vector4FA(in: vec4<f32>, amount: f32) -> vec4<f32> {
    return amount - in;
}

// ---- absval ----

fn mx_absval_float(in: f32) -> f32 {
    return abs(in);
}

fn mx_absval_color3(in: vec3<f32>) -> vec3<f32> {
    return abs(in);
}

fn mx_absval_color4(in: vec4<f32>) -> vec4<f32> {
    return abs(in);
}

fn mx_absval_vector2(in: vec2<f32>) -> vec2<f32> {
    return abs(in);
}

fn mx_absval_vector3(in: vec3<f32>) -> vec3<f32> {
    return abs(in);
}

fn mx_absval_vector4(in: vec4<f32>) -> vec4<f32> {
    return abs(in);
}

// ---- floor ----

fn mx_floor_float(in: f32) -> f32 {
    return floor(in);
}

fn mx_floor_color3(in: vec3<f32>) -> vec3<f32> {
    return floor(in);
}

fn mx_floor_color4(in: vec4<f32>) -> vec4<f32> {
    return floor(in);
}

fn mx_floor_vector2(in: vec2<f32>) -> vec2<f32> {
    return floor(in);
}

fn mx_floor_vector3(in: vec3<f32>) -> vec3<f32> {
    return floor(in);
}

fn mx_floor_vector4(in: vec4<f32>) -> vec4<f32> {
    return floor(in);
}

fn mx_floor_integer(in: f32) -> i32 {
    return i32(floor(in));
}

// ---- ceil ----

fn mx_ceil_float(in: f32) -> f32 {
    return ceil(in);
}

fn mx_ceil_color3(in: vec3<f32>) -> vec3<f32> {
    return ceil(in);
}

fn mx_ceil_color4(in: vec4<f32>) -> vec4<f32> {
    return ceil(in);
}

fn mx_ceil_vector2(in: vec2<f32>) -> vec2<f32> {
    return ceil(in);
}

fn mx_ceil_vector3(in: vec3<f32>) -> vec3<f32> {
    return ceil(in);
}

fn mx_ceil_vector4(in: vec4<f32>) -> vec4<f32> {
    return ceil(in);
}

fn mx_ceil_integer(in: f32) -> i32 {
    return i32(ceil(in));
}

// ---- round ----

fn mx_round_float(in: f32) -> f32 {
    // WGSL round() takes halves to even; GLSL leaves the direction of x.5 to the implementation.
    return round(in);
}

fn mx_round_color3(in: vec3<f32>) -> vec3<f32> {
    // WGSL round() takes halves to even; GLSL leaves the direction of x.5 to the implementation.
    return round(in);
}

fn mx_round_color4(in: vec4<f32>) -> vec4<f32> {
    // WGSL round() takes halves to even; GLSL leaves the direction of x.5 to the implementation.
    return round(in);
}

fn mx_round_vector2(in: vec2<f32>) -> vec2<f32> {
    // WGSL round() takes halves to even; GLSL leaves the direction of x.5 to the implementation.
    return round(in);
}

fn mx_round_vector3(in: vec3<f32>) -> vec3<f32> {
    // WGSL round() takes halves to even; GLSL leaves the direction of x.5 to the implementation.
    return round(in);
}

fn mx_round_vector4(in: vec4<f32>) -> vec4<f32> {
    // WGSL round() takes halves to even; GLSL leaves the direction of x.5 to the implementation.
    return round(in);
}

fn mx_round_integer(in: f32) -> i32 {
    // WGSL round() takes halves to even; GLSL leaves the direction of x.5 to the implementation.
    return i32(round(in));
}

// ---- power ----
// WGSL leaves pow(x, y) indeterminate for x < 0 and x = 0 (its accuracy is that of
// exp2(y·log2(x))): lavapipe gives NaN or 0 there, where C and Rust give numbers, so the CPU
// and GPU engines disagreed (found by the random-graph test). The library defines `power` on
// every input as OSL's pow does (OSL is the shading language of MaterialX's reference
// renders, `safe_pow`): pow(x, 0) = 1; pow(0, y) = 0 for every other y (negative ones too, where
// C gives infinity); for x < 0, |x|^y negated for odd integer y, and 0 for y not an integer.

fn mx_pow(x: f32, y: f32) -> f32 {
    let m = select(pow(abs(x), y), 0.0, x == 0.0);
    let integer = trunc(y) == y;
    let odd = integer & (abs(y) < 16777216.0) & ((i32(y) & 1) != 0);
    let negative = select(select(0.0, m, integer), -m, odd);
    return select(select(m, negative, x < 0.0), 1.0, y == 0.0);
}

fn mx_power_float(in1: f32, in2: f32) -> f32 {
    return mx_pow(in1, in2);
}

fn mx_power_color3(in1: vec3<f32>, in2: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(mx_pow(in1.x, in2.x), mx_pow(in1.y, in2.y), mx_pow(in1.z, in2.z));
}

fn mx_power_color4(in1: vec4<f32>, in2: vec4<f32>) -> vec4<f32> {
    return vec4<f32>(mx_pow(in1.x, in2.x), mx_pow(in1.y, in2.y), mx_pow(in1.z, in2.z), mx_pow(in1.w, in2.w));
}

fn mx_power_vector2(in1: vec2<f32>, in2: vec2<f32>) -> vec2<f32> {
    return vec2<f32>(mx_pow(in1.x, in2.x), mx_pow(in1.y, in2.y));
}

fn mx_power_vector3(in1: vec3<f32>, in2: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(mx_pow(in1.x, in2.x), mx_pow(in1.y, in2.y), mx_pow(in1.z, in2.z));
}

fn mx_power_vector4(in1: vec4<f32>, in2: vec4<f32>) -> vec4<f32> {
    return vec4<f32>(mx_pow(in1.x, in2.x), mx_pow(in1.y, in2.y), mx_pow(in1.z, in2.z), mx_pow(in1.w, in2.w));
}

fn mx_power_color3FA(in1: vec3<f32>, in2: f32) -> vec3<f32> {
    return vec3<f32>(mx_pow(in1.x, in2), mx_pow(in1.y, in2), mx_pow(in1.z, in2));
}

fn mx_power_color4FA(in1: vec4<f32>, in2: f32) -> vec4<f32> {
    return vec4<f32>(mx_pow(in1.x, in2), mx_pow(in1.y, in2), mx_pow(in1.z, in2), mx_pow(in1.w, in2));
}

fn mx_power_vector2FA(in1: vec2<f32>, in2: f32) -> vec2<f32> {
    return vec2<f32>(mx_pow(in1.x, in2), mx_pow(in1.y, in2));
}

fn mx_power_vector3FA(in1: vec3<f32>, in2: f32) -> vec3<f32> {
    return vec3<f32>(mx_pow(in1.x, in2), mx_pow(in1.y, in2), mx_pow(in1.z, in2));
}

fn mx_power_vector4FA(in1: vec4<f32>, in2: f32) -> vec4<f32> {
    return vec4<f32>(mx_pow(in1.x, in2), mx_pow(in1.y, in2), mx_pow(in1.z, in2), mx_pow(in1.w, in2));
}

// ---- sin ----

fn mx_sin_float(in: f32) -> f32 {
    return sin(in);
}

// ---- cos ----

fn mx_cos_float(in: f32) -> f32 {
    return cos(in);
}

// ---- tan ----

fn mx_tan_float(in: f32) -> f32 {
    return tan(in);
}

// ---- asin ----

fn mx_asin_float(in: f32) -> f32 {
    // Written with atan2: Vulkan lets asin/acos inherit atan2's 4096-ULP bound from
    // atan2(x, sqrt(1 - x*x)), and lavapipe's asin is off by up to 4e-4 (atan2 by ~3e-6).
    // Same values as GLSL asin on [-1, 1]; NaN outside, as sqrt of a negative.
    return atan2(in, sqrt((1.0 - in) * (1.0 + in)));
}

// ---- acos ----

fn mx_acos_float(in: f32) -> f32 {
    // With atan2, for precision: see mx_asin_float.
    return atan2(sqrt((1.0 - in) * (1.0 + in)), in);
}

// ---- atan2 ----
// WGSL leaves atan2(0, 0) indeterminate (lavapipe gives 3π/4, Rust 0; found by the random-graph
// test). The library defines it as C does for +0, +0: 0.

fn mx_atan2_float(iny: f32, inx: f32) -> f32 {
    return select(atan2(iny, inx), 0.0, (iny == 0.0) & (inx == 0.0));
}

// ---- sin ----

fn mx_sin_vector2(in: vec2<f32>) -> vec2<f32> {
    return sin(in);
}

// ---- cos ----

fn mx_cos_vector2(in: vec2<f32>) -> vec2<f32> {
    return cos(in);
}

// ---- tan ----

fn mx_tan_vector2(in: vec2<f32>) -> vec2<f32> {
    return tan(in);
}

// ---- asin ----

fn mx_asin_vector2(in: vec2<f32>) -> vec2<f32> {
    // Written with atan2: Vulkan lets asin/acos inherit atan2's 4096-ULP bound from
    // atan2(x, sqrt(1 - x*x)), and lavapipe's asin is off by up to 4e-4 (atan2 by ~3e-6).
    // Same values as GLSL asin on [-1, 1]; NaN outside, as sqrt of a negative.
    return atan2(in, sqrt((1.0 - in) * (1.0 + in)));
}

// ---- acos ----

fn mx_acos_vector2(in: vec2<f32>) -> vec2<f32> {
    // With atan2, for precision: see mx_asin_vector2.
    return atan2(sqrt((1.0 - in) * (1.0 + in)), in);
}

// ---- atan2 ----

fn mx_atan2_vector2(iny: vec2<f32>, inx: vec2<f32>) -> vec2<f32> {
    // atan2(0, 0) = 0: see mx_atan2_float.
    return select(atan2(iny, inx), vec2<f32>(0.0), (iny == vec2<f32>(0.0)) & (inx == vec2<f32>(0.0)));
}

// ---- sin ----

fn mx_sin_vector3(in: vec3<f32>) -> vec3<f32> {
    return sin(in);
}

// ---- cos ----

fn mx_cos_vector3(in: vec3<f32>) -> vec3<f32> {
    return cos(in);
}

// ---- tan ----

fn mx_tan_vector3(in: vec3<f32>) -> vec3<f32> {
    return tan(in);
}

// ---- asin ----

fn mx_asin_vector3(in: vec3<f32>) -> vec3<f32> {
    // Written with atan2: Vulkan lets asin/acos inherit atan2's 4096-ULP bound from
    // atan2(x, sqrt(1 - x*x)), and lavapipe's asin is off by up to 4e-4 (atan2 by ~3e-6).
    // Same values as GLSL asin on [-1, 1]; NaN outside, as sqrt of a negative.
    return atan2(in, sqrt((1.0 - in) * (1.0 + in)));
}

// ---- acos ----

fn mx_acos_vector3(in: vec3<f32>) -> vec3<f32> {
    // With atan2, for precision: see mx_asin_vector3.
    return atan2(sqrt((1.0 - in) * (1.0 + in)), in);
}

// ---- atan2 ----

fn mx_atan2_vector3(iny: vec3<f32>, inx: vec3<f32>) -> vec3<f32> {
    // atan2(0, 0) = 0: see mx_atan2_float.
    return select(atan2(iny, inx), vec3<f32>(0.0), (iny == vec3<f32>(0.0)) & (inx == vec3<f32>(0.0)));
}

// ---- sin ----

fn mx_sin_vector4(in: vec4<f32>) -> vec4<f32> {
    return sin(in);
}

// ---- cos ----

fn mx_cos_vector4(in: vec4<f32>) -> vec4<f32> {
    return cos(in);
}

// ---- tan ----

fn mx_tan_vector4(in: vec4<f32>) -> vec4<f32> {
    return tan(in);
}

// ---- asin ----

fn mx_asin_vector4(in: vec4<f32>) -> vec4<f32> {
    // Written with atan2: Vulkan lets asin/acos inherit atan2's 4096-ULP bound from
    // atan2(x, sqrt(1 - x*x)), and lavapipe's asin is off by up to 4e-4 (atan2 by ~3e-6).
    // Same values as GLSL asin on [-1, 1]; NaN outside, as sqrt of a negative.
    return atan2(in, sqrt((1.0 - in) * (1.0 + in)));
}

// ---- acos ----

fn mx_acos_vector4(in: vec4<f32>) -> vec4<f32> {
    // With atan2, for precision: see mx_asin_vector4.
    return atan2(sqrt((1.0 - in) * (1.0 + in)), in);
}

// ---- atan2 ----

fn mx_atan2_vector4(iny: vec4<f32>, inx: vec4<f32>) -> vec4<f32> {
    // atan2(0, 0) = 0: see mx_atan2_float.
    return select(atan2(iny, inx), vec4<f32>(0.0), (iny == vec4<f32>(0.0)) & (inx == vec4<f32>(0.0)));
}

// ---- sqrt ----

fn mx_sqrt_float(in: f32) -> f32 {
    return sqrt(in);
}

// ---- ln ----

fn mx_ln_float(in: f32) -> f32 {
    return log(in);
}

// ---- exp ----

fn mx_exp_float(in: f32) -> f32 {
    return exp(in);
}

// ---- sqrt ----

fn mx_sqrt_vector2(in: vec2<f32>) -> vec2<f32> {
    return sqrt(in);
}

// ---- ln ----

fn mx_ln_vector2(in: vec2<f32>) -> vec2<f32> {
    return log(in);
}

// ---- exp ----

fn mx_exp_vector2(in: vec2<f32>) -> vec2<f32> {
    return exp(in);
}

// ---- sqrt ----

fn mx_sqrt_vector3(in: vec3<f32>) -> vec3<f32> {
    return sqrt(in);
}

// ---- ln ----

fn mx_ln_vector3(in: vec3<f32>) -> vec3<f32> {
    return log(in);
}

// ---- exp ----

fn mx_exp_vector3(in: vec3<f32>) -> vec3<f32> {
    return exp(in);
}

// ---- sqrt ----

fn mx_sqrt_vector4(in: vec4<f32>) -> vec4<f32> {
    return sqrt(in);
}

// ---- ln ----

fn mx_ln_vector4(in: vec4<f32>) -> vec4<f32> {
    return log(in);
}

// ---- exp ----

fn mx_exp_vector4(in: vec4<f32>) -> vec4<f32> {
    return exp(in);
}

// ---- sign ----

fn mx_sign_float(in: f32) -> f32 {
    return sign(in);
}

fn mx_sign_color3(in: vec3<f32>) -> vec3<f32> {
    return sign(in);
}

fn mx_sign_color4(in: vec4<f32>) -> vec4<f32> {
    return sign(in);
}

fn mx_sign_vector2(in: vec2<f32>) -> vec2<f32> {
    return sign(in);
}

fn mx_sign_vector3(in: vec3<f32>) -> vec3<f32> {
    return sign(in);
}

fn mx_sign_vector4(in: vec4<f32>) -> vec4<f32> {
    return sign(in);
}

// ---- clamp ----

fn mx_clamp_float(in: f32, low: f32, high: f32) -> f32 {
    return clamp(in, low, high);
}

fn mx_clamp_color3(in: vec3<f32>, low: vec3<f32>, high: vec3<f32>) -> vec3<f32> {
    return clamp(in, low, high);
}

fn mx_clamp_color4(in: vec4<f32>, low: vec4<f32>, high: vec4<f32>) -> vec4<f32> {
    return clamp(in, low, high);
}

fn mx_clamp_vector2(in: vec2<f32>, low: vec2<f32>, high: vec2<f32>) -> vec2<f32> {
    return clamp(in, low, high);
}

fn mx_clamp_vector3(in: vec3<f32>, low: vec3<f32>, high: vec3<f32>) -> vec3<f32> {
    return clamp(in, low, high);
}

fn mx_clamp_vector4(in: vec4<f32>, low: vec4<f32>, high: vec4<f32>) -> vec4<f32> {
    return clamp(in, low, high);
}

fn mx_clamp_color3FA(in: vec3<f32>, low: f32, high: f32) -> vec3<f32> {
    return clamp(in, vec3<f32>(low), vec3<f32>(high));
}

fn mx_clamp_color4FA(in: vec4<f32>, low: f32, high: f32) -> vec4<f32> {
    return clamp(in, vec4<f32>(low), vec4<f32>(high));
}

fn mx_clamp_vector2FA(in: vec2<f32>, low: f32, high: f32) -> vec2<f32> {
    return clamp(in, vec2<f32>(low), vec2<f32>(high));
}

fn mx_clamp_vector3FA(in: vec3<f32>, low: f32, high: f32) -> vec3<f32> {
    return clamp(in, vec3<f32>(low), vec3<f32>(high));
}

fn mx_clamp_vector4FA(in: vec4<f32>, low: f32, high: f32) -> vec4<f32> {
    return clamp(in, vec4<f32>(low), vec4<f32>(high));
}

// ---- min ----

fn mx_min_float(in1: f32, in2: f32) -> f32 {
    return min(in1, in2);
}

fn mx_min_color3(in1: vec3<f32>, in2: vec3<f32>) -> vec3<f32> {
    return min(in1, in2);
}

fn mx_min_color4(in1: vec4<f32>, in2: vec4<f32>) -> vec4<f32> {
    return min(in1, in2);
}

fn mx_min_vector2(in1: vec2<f32>, in2: vec2<f32>) -> vec2<f32> {
    return min(in1, in2);
}

fn mx_min_vector3(in1: vec3<f32>, in2: vec3<f32>) -> vec3<f32> {
    return min(in1, in2);
}

fn mx_min_vector4(in1: vec4<f32>, in2: vec4<f32>) -> vec4<f32> {
    return min(in1, in2);
}

fn mx_min_color3FA(in1: vec3<f32>, in2: f32) -> vec3<f32> {
    return min(in1, vec3<f32>(in2));
}

fn mx_min_color4FA(in1: vec4<f32>, in2: f32) -> vec4<f32> {
    return min(in1, vec4<f32>(in2));
}

fn mx_min_vector2FA(in1: vec2<f32>, in2: f32) -> vec2<f32> {
    return min(in1, vec2<f32>(in2));
}

fn mx_min_vector3FA(in1: vec3<f32>, in2: f32) -> vec3<f32> {
    return min(in1, vec3<f32>(in2));
}

fn mx_min_vector4FA(in1: vec4<f32>, in2: f32) -> vec4<f32> {
    return min(in1, vec4<f32>(in2));
}

// ---- max ----

fn mx_max_float(in1: f32, in2: f32) -> f32 {
    return max(in1, in2);
}

fn mx_max_color3(in1: vec3<f32>, in2: vec3<f32>) -> vec3<f32> {
    return max(in1, in2);
}

fn mx_max_color4(in1: vec4<f32>, in2: vec4<f32>) -> vec4<f32> {
    return max(in1, in2);
}

fn mx_max_vector2(in1: vec2<f32>, in2: vec2<f32>) -> vec2<f32> {
    return max(in1, in2);
}

fn mx_max_vector3(in1: vec3<f32>, in2: vec3<f32>) -> vec3<f32> {
    return max(in1, in2);
}

fn mx_max_vector4(in1: vec4<f32>, in2: vec4<f32>) -> vec4<f32> {
    return max(in1, in2);
}

fn mx_max_color3FA(in1: vec3<f32>, in2: f32) -> vec3<f32> {
    return max(in1, vec3<f32>(in2));
}

fn mx_max_color4FA(in1: vec4<f32>, in2: f32) -> vec4<f32> {
    return max(in1, vec4<f32>(in2));
}

fn mx_max_vector2FA(in1: vec2<f32>, in2: f32) -> vec2<f32> {
    return max(in1, vec2<f32>(in2));
}

fn mx_max_vector3FA(in1: vec3<f32>, in2: f32) -> vec3<f32> {
    return max(in1, vec3<f32>(in2));
}

fn mx_max_vector4FA(in1: vec4<f32>, in2: f32) -> vec4<f32> {
    return max(in1, vec4<f32>(in2));
}

// ---- normalize ----

fn mx_normalize_vector2(in: vec2<f32>) -> vec2<f32> {
    return normalize(in);
}

fn mx_normalize_vector3(in: vec3<f32>) -> vec3<f32> {
    return normalize(in);
}

fn mx_normalize_vector4(in: vec4<f32>) -> vec4<f32> {
    return normalize(in);
}

// ---- magnitude ----

fn mx_magnitude_vector2(in: vec2<f32>) -> f32 {
    return length(in);
}

fn mx_magnitude_vector3(in: vec3<f32>) -> f32 {
    return length(in);
}

fn mx_magnitude_vector4(in: vec4<f32>) -> f32 {
    return length(in);
}

// ---- dotproduct ----

fn mx_dotproduct_vector2(in1: vec2<f32>, in2: vec2<f32>) -> f32 {
    return dot(in1, in2);
}

fn mx_dotproduct_vector3(in1: vec3<f32>, in2: vec3<f32>) -> f32 {
    return dot(in1, in2);
}

fn mx_dotproduct_vector4(in1: vec4<f32>, in2: vec4<f32>) -> f32 {
    return dot(in1, in2);
}

// ---- crossproduct ----

fn mx_crossproduct_vector3(in1: vec3<f32>, in2: vec3<f32>) -> vec3<f32> {
    return cross(in1, in2);
}

// ---- transformpoint ----

fn mx_transformpoint_vector3(in: vec3<f32>) -> vec3<f32> {
    // fromspace/tospace are strings without enum, so they are not passed. In uplift kernels
    // object space is world space (no model transform), so every space conversion is identity.
    return in;
}

// ---- transformvector ----

fn mx_transformvector_vector3(in: vec3<f32>) -> vec3<f32> {
    // fromspace/tospace are strings without enum, so they are not passed. In uplift kernels
    // object space is world space (no model transform), so every space conversion is identity.
    return in;
}

// ---- transformnormal ----

fn mx_transformnormal_vector3(in: vec3<f32>) -> vec3<f32> {
    // fromspace/tospace are strings without enum, so they are not passed. In uplift kernels
    // object space is world space (no model transform), so every space conversion is identity.
    return in;
}

// ---- transformmatrix ----

fn mx_transformmatrix_vector2M3(in: vec2<f32>, mat: mat3x3<f32>) -> vec2<f32> {
    return (mat * vec3<f32>(in, 1.0)).xy;
}

fn mx_transformmatrix_vector3(in: vec3<f32>, mat: mat3x3<f32>) -> vec3<f32> {
    return mat * in;
}

fn mx_transformmatrix_vector3M4(in: vec3<f32>, mat: mat4x4<f32>) -> vec3<f32> {
    return (mat * vec4<f32>(in, 1.0)).xyz;
}

fn mx_transformmatrix_vector4(in: vec4<f32>, mat: mat4x4<f32>) -> vec4<f32> {
    return mat * in;
}

// ---- normalmap ----

fn mx_normalmap_float(in: vec3<f32>, scale: f32, normal: vec3<f32>, tangent: vec3<f32>, bitangent: vec3<f32>) -> vec3<f32> {
    return mx_normalmap_vector2(in, vec2<f32>(scale), normal, tangent, bitangent);
}

fn mx_normalmap_vector2(in: vec3<f32>, scale: vec2<f32>, normal: vec3<f32>, tangent: vec3<f32>, bitangent: vec3<f32>) -> vec3<f32> {
    // Decode (an all-zero input means the flat normal), scale x/y, map through the T/B/N frame.
    var v = vec3<f32>(0.0, 0.0, 1.0);
    if (dot(in, in) != 0.0) {
        v = in * 2.0 - 1.0;
    }
    return normalize(tangent * v.x * scale.x + bitangent * v.y * scale.y + normal * v.z);
}

// ---- transpose ----

fn mx_transpose_matrix33(in: mat3x3<f32>) -> mat3x3<f32> {
    return transpose(in);
}

fn mx_transpose_matrix44(in: mat4x4<f32>) -> mat4x4<f32> {
    return transpose(in);
}

// ---- determinant ----

fn mx_determinant_matrix33(in: mat3x3<f32>) -> f32 {
    return determinant(in);
}

fn mx_determinant_matrix44(in: mat4x4<f32>) -> f32 {
    return determinant(in);
}

// ---- invertmatrix ----

fn mx_invertmatrix_matrix33(in: mat3x3<f32>) -> mat3x3<f32> {
    return mx_math_inverse3(in);
}

fn mx_invertmatrix_matrix44(in: mat4x4<f32>) -> mat4x4<f32> {
    return mx_math_inverse4(in);
}

// ---- rotate2d ----

fn mx_rotate2d_vector2(in: vec2<f32>, amount: f32) -> vec2<f32> {
    // amount is in degrees. As MaterialX GLSL: (1, 0) rotated by +90 gives (0, -1).
    let r = radians(amount);
    let sa = sin(r);
    let ca = cos(r);
    return vec2<f32>(ca * in.x + sa * in.y, -sa * in.x + ca * in.y);
}

// ---- rotate3d ----

fn mx_rotate3d_vector3(in: vec3<f32>, amount: f32, axis: vec3<f32>) -> vec3<f32> {
    // amount is in degrees; rotation about `axis` (normalized), as MaterialX GLSL mx_rotationMatrix
    // (same handedness as rotate2d: (1, 0, 0) rotated by +90 about +z gives (0, -1, 0)).
    return mx_math_rotation_matrix(axis, radians(amount)) * in;
}

// ---- creatematrix ----

fn mx_creatematrix_vector3_matrix33(in1: vec3<f32>, in2: vec3<f32>, in3: vec3<f32>) -> mat3x3<f32> {
    return mat3x3<f32>(in1, in2, in3);
}

fn mx_creatematrix_vector3_matrix44(in1: vec3<f32>, in2: vec3<f32>, in3: vec3<f32>, in4: vec3<f32>) -> mat4x4<f32> {
    return mat4x4<f32>(vec4<f32>(in1, 0.0), vec4<f32>(in2, 0.0), vec4<f32>(in3, 0.0), vec4<f32>(in4, 1.0));
}

fn mx_creatematrix_vector4_matrix44(in1: vec4<f32>, in2: vec4<f32>, in3: vec4<f32>, in4: vec4<f32>) -> mat4x4<f32> {
    return mat4x4<f32>(in1, in2, in3, in4);
}
