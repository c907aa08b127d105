//! Runs the Rust written from tests/wgsl/semantics.wgsl (tests/out/rs_wgsl/semantics.rs) and
//! checks the WGSL semantics that differ from Rust's defaults.

use glam::{IVec3, Mat3, Vec2, Vec3, Vec4};
use uplift_rs_snapshots::wgsl_semantics as s;

#[test]
fn integer_arithmetic_wraps() {
    assert_eq!(s::add_i32_(i32::MAX, 1), i32::MIN);
    assert_eq!(s::sub_i32_(i32::MIN, 1), i32::MAX);
    assert_eq!(s::mul_i32_(i32::MAX, 2), -2);
    assert_eq!(s::neg_i32_(i32::MIN), i32::MIN);
    assert_eq!(s::add_u32_(u32::MAX, 2), 1);
    assert_eq!(s::add_ivec3_scalar(IVec3::new(i32::MAX, 0, -1), 1), IVec3::new(i32::MIN, 1, 0));
}

#[test]
fn integer_division_by_zero_is_defined() {
    // WGSL: x / 0 = x, x % 0 = 0; MIN / -1 = MIN, MIN % -1 = 0.
    assert_eq!(s::div_i32_(7, 0), 7);
    assert_eq!(s::rem_i32_(7, 0), 0);
    assert_eq!(s::div_i32_(i32::MIN, -1), i32::MIN);
    assert_eq!(s::rem_i32_(i32::MIN, -1), 0);
    assert_eq!(s::div_i32_(-7, 2), -3);
    assert_eq!(s::rem_i32_(-7, 2), -1);
    assert_eq!(s::div_u32_(9, 0), 9);
    assert_eq!(s::rem_u32_(9, 0), 0);
    assert_eq!(s::div_ivec3_(IVec3::new(6, 5, -9), IVec3::new(3, 0, 2)), IVec3::new(2, 5, -4));
}

#[test]
fn shifts_take_the_amount_modulo_32() {
    assert_eq!(s::shl_u32_(1, 33), 2);
    assert_eq!(s::shr_i32_(-8, 1), -4);
    assert_eq!(s::shr_i32_(-8, 34), -2);
}

#[test]
fn float_remainder_truncates() {
    // WGSL: a % b = a - b * trunc(a / b) (the sign of a).
    assert_eq!(s::rem_f32_(5.5, 2.0), 1.5);
    assert_eq!(s::rem_f32_(-5.5, 2.0), -1.5);
    assert_eq!(s::rem_f32_(5.5, -2.0), 1.5);
    assert_eq!(s::rem_vec3_(Vec3::new(-1.25, 3.0, 0.5), 1.0), Vec3::new(-0.25, 0.0, 0.5));
}

#[test]
fn rounding_and_decomposition() {
    assert_eq!(s::round_f32_(2.5), 2.0);
    assert_eq!(s::round_f32_(3.5), 4.0);
    assert_eq!(s::round_f32_(-2.5), -2.0);
    assert_eq!(s::round_f32_(-0.6), -1.0);
    assert_eq!(s::round_vec2_(Vec2::new(0.5, 1.5)), Vec2::new(0.0, 2.0));
    // fract(x) = x - floor(x), so fract(-0.25) = 0.75 (Rust's f32::fract gives -0.25).
    assert_eq!(s::fract_f32_(-0.25), 0.75);
    assert_eq!(s::fract_f32_(1.75), 0.75);
    assert_eq!(s::sign_f32_(0.0), 0.0);
    assert_eq!(s::sign_f32_(-3.0), -1.0);
    assert_eq!(s::sign_f32_(2.0), 1.0);
}

#[test]
fn builtins() {
    // clamp = min(max(x, lo), hi): lo > hi gives hi, and never panics.
    assert_eq!(s::clamp_f32_(5.0, 0.0, 1.0), 1.0);
    assert_eq!(s::clamp_f32_(0.5, 1.0, 0.0), 0.0);
    assert_eq!(s::mix_vec3_(Vec3::ZERO, Vec3::new(2.0, 4.0, 8.0), 0.25), Vec3::new(0.5, 1.0, 2.0));
    assert_eq!(s::smooth_step(1.0), 0.5);
    assert_eq!(s::smooth_step(-1.0), 0.0);
    assert_eq!(s::smooth_step(3.0), 1.0);
    assert_eq!(s::step_vec2_(Vec2::new(0.5, 0.5), Vec2::new(0.5, 0.4)), Vec2::new(1.0, 0.0));
    assert_eq!(s::inv_sqrt(4.0), 0.5);
    assert_eq!(s::select_max(Vec3::new(1.0, 5.0, -2.0), Vec3::new(3.0, 2.0, -1.0)), Vec3::new(3.0, 5.0, -1.0));
    // Lanes: a < b and b > 0 → a; otherwise b.
    assert_eq!(s::select_vec4_masks(Vec4::new(1.0, 5.0, -3.0, -2.0), Vec4::new(3.0, 2.0, -1.0, 4.0)), Vec4::new(1.0, 2.0, -1.0, -2.0));
    assert_eq!(s::equal_vec4_(Vec4::new(1.0, 2.0, f32::NAN, 0.0), Vec4::new(1.0, 3.0, f32::NAN, -0.0)), glam::BVec4::new(true, false, false, true));
    assert_eq!(s::count_bits(0xF0F0), 8);
    let m = Mat3::from_cols(Vec3::new(1.0, 2.0, 3.0), Vec3::new(4.0, 5.0, 6.0), Vec3::new(7.0, 8.0, 9.0));
    // v * M (row vector): component j is dot(v, column j).
    assert_eq!(s::row_times_matrix(Vec3::new(1.0, 0.0, 1.0), m), Vec3::new(4.0, 10.0, 16.0));
    assert_eq!(s::any_all(Vec3::new(1.0, -1.0, 2.0)), glam::BVec2::new(true, false));
    assert_eq!(s::swizzle(Vec4::new(1.0, 2.0, 3.0, 4.0)), Vec3::new(8.0, 6.0, 2.0));
    assert_eq!(s::scale_vec3_(Vec3::new(2.0, 4.0, 8.0), 2.0), Vec3::new(3.0, 6.0, 12.0));
}

#[test]
fn conversions() {
    // f32 → integer truncates toward zero and saturates; NaN → 0.
    assert_eq!(s::f32_to_i32_(-2.7), -2);
    assert_eq!(s::f32_to_i32_(1e10), i32::MAX);
    assert_eq!(s::f32_to_i32_(-1e10), i32::MIN);
    assert_eq!(s::f32_to_i32_(f32::NAN), 0);
    assert_eq!(s::f32_to_u32_(-5.0), 0);
    assert_eq!(s::f32_to_u32_(7.9), 7);
    assert_eq!(s::i32_to_u32_(-1), u32::MAX);
    assert_eq!(s::bits_f32_(1.0), 0x3f80_0000);
    assert_eq!(s::from_bits_i32_(0x4000_0000), 2.0);
    assert_eq!(s::bool_to_f32_(true), 1.0);
    assert_eq!(s::vec_to_ivec(Vec3::new(1.9, -1.9, 0.2)), IVec3::new(1, -1, 0));
}

#[test]
fn runtime_indices_are_clamped() {
    let v = Vec3::new(1.0, 2.0, 3.0);
    assert_eq!(s::index_vec3_(v, 1), 2.0);
    assert_eq!(s::index_vec3_(v, 7), 3.0);
    assert_eq!(s::index_store(0), Vec3::new(9.0, 2.0, 3.0));
    assert_eq!(s::index_store(5), Vec3::new(1.0, 2.0, 9.0));
}

#[test]
fn structs_and_constants() {
    assert_eq!(s::make_pair(3.0), s::Pair { a: 1.5, b: 3 });
    assert_eq!(s::HALF, 0.5);
}

#[test]
fn control_flow() {
    assert_eq!(s::sum_loop(6), 0 + 1 + 2 + 4 + 5);
    assert_eq!(s::sum_loop(0), 0);
    assert_eq!(s::loop_break_if(5), 6);
    assert_eq!(s::loop_break_if(0), 2);
    assert_eq!([0, 1, 2, 3, -4].map(s::classify), [10, 10, 20, -1, -1]);
    // i % 3 == 0: +100 unless i > 4 (break leaves the switch); else +1 unless i == 7 (continue).
    assert_eq!(s::switch_in_loop(10), 100 + 1 + 1 + 100 + 1 + 1 + 1);
}
