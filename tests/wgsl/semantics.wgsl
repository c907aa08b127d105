// WGSL semantics the Rust writer must keep (compiler/src/backend_rust.rs), written to
// tests/out/rs_wgsl/semantics.rs by compiler/tests/snapshots.rs and run by
// tests/rs_compile/tests/integration/semantics.rs. Functions only: no entry point.

struct Pair {
    a: f32,
    b: i32,
}

const HALF: f32 = 0.5;

fn add_i32(a: i32, b: i32) -> i32 { return a + b; }
fn sub_i32(a: i32, b: i32) -> i32 { return a - b; }
fn mul_i32(a: i32, b: i32) -> i32 { return a * b; }
fn neg_i32(a: i32) -> i32 { return -a; }
fn div_i32(a: i32, b: i32) -> i32 { return a / b; }
fn rem_i32(a: i32, b: i32) -> i32 { return a % b; }
fn add_u32(a: u32, b: u32) -> u32 { return a + b; }
fn div_u32(a: u32, b: u32) -> u32 { return a / b; }
fn rem_u32(a: u32, b: u32) -> u32 { return a % b; }
fn shl_u32(a: u32, b: u32) -> u32 { return a << b; }
fn shr_i32(a: i32, b: u32) -> i32 { return a >> b; }
fn rem_f32(a: f32, b: f32) -> f32 { return a % b; }
fn rem_vec3(a: vec3<f32>, b: f32) -> vec3<f32> { return a % b; }
fn div_ivec3(a: vec3<i32>, b: vec3<i32>) -> vec3<i32> { return a / b; }
fn add_ivec3_scalar(a: vec3<i32>, b: i32) -> vec3<i32> { return a + b; }
fn scale_vec3(a: vec3<f32>, s: f32) -> vec3<f32> { return s * a - a / s; }

fn round_f32(a: f32) -> f32 { return round(a); }
fn round_vec2(a: vec2<f32>) -> vec2<f32> { return round(a); }
fn fract_f32(a: f32) -> f32 { return fract(a); }
fn sign_f32(a: f32) -> f32 { return sign(a); }
fn clamp_f32(x: f32, lo: f32, hi: f32) -> f32 { return clamp(x, lo, hi); }
fn mix_vec3(a: vec3<f32>, b: vec3<f32>, t: f32) -> vec3<f32> { return mix(a, b, t); }
fn smooth_step(x: f32) -> f32 { return smoothstep(0.0, 2.0, x); }
fn step_vec2(edge: vec2<f32>, x: vec2<f32>) -> vec2<f32> { return step(edge, x); }
fn inv_sqrt(x: f32) -> f32 { return inverseSqrt(x); }
fn select_max(a: vec3<f32>, b: vec3<f32>) -> vec3<f32> { return select(a, b, a < b); }
// vec4<f32> compares and selects (glam's SIMD Vec4 masks are BVec4A, not BVec4).
fn select_vec4_masks(a: vec4<f32>, b: vec4<f32>) -> vec4<f32> { return select(b, a, (a < b) & (b > vec4(0.0))); }
fn equal_vec4(a: vec4<f32>, b: vec4<f32>) -> vec4<bool> { return a == b; }
fn count_bits(a: u32) -> u32 { return countOneBits(a); }
fn row_times_matrix(v: vec3<f32>, m: mat3x3<f32>) -> vec3<f32> { return v * m; }
fn any_all(v: vec3<f32>) -> vec2<bool> { return vec2<bool>(any(v > vec3(0.0)), all(v > vec3(0.0))); }
fn swizzle(v: vec4<f32>) -> vec3<f32> { return (v + v).wzx; }

fn f32_to_i32(a: f32) -> i32 { return i32(a); }
fn f32_to_u32(a: f32) -> u32 { return u32(a); }
fn i32_to_u32(a: i32) -> u32 { return u32(a); }
fn bits_f32(a: f32) -> u32 { return bitcast<u32>(a); }
fn from_bits_i32(a: i32) -> f32 { return bitcast<f32>(a); }
fn bool_to_f32(b: bool) -> f32 { return f32(b); }
fn vec_to_ivec(a: vec3<f32>) -> vec3<i32> { return vec3<i32>(a); }

fn index_vec3(v: vec3<f32>, i: i32) -> f32 { return v[i]; }
fn index_store(i: i32) -> vec3<f32> {
    var v = vec3<f32>(1.0, 2.0, 3.0);
    v[i] = 9.0;
    return v;
}
fn make_pair(x: f32) -> Pair { return Pair(x * HALF, i32(x)); }

fn sum_loop(n: i32) -> i32 {
    var s = 0;
    for (var i = 0; i < n; i++) {
        if (i == 3) {
            continue;
        }
        s += i;
    }
    return s;
}

fn loop_break_if(n: i32) -> i32 {
    var i = 0;
    loop {
        i += 2;
        continuing {
            break if i >= n;
        }
    }
    return i;
}

fn classify(x: i32) -> i32 {
    switch x {
        case 0, 1: { return 10; }
        case 2: { return 20; }
        default: { return -1; }
    }
}

// `break` in a switch leaves the switch; `continue` in a switch runs the loop's continuing.
fn switch_in_loop(n: i32) -> i32 {
    var s = 0;
    for (var i = 0; i < n; i++) {
        switch i % 3 {
            case 0: {
                if (i > 4) {
                    break;
                }
                s += 100;
            }
            default: {
                if (i == 7) {
                    continue;
                }
                s += 1;
            }
        }
    }
    return s;
}
