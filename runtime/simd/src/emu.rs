//! The emulated level [`Emu<N>`]: N lanes as plain arrays, each operation a lane loop in
//! scalar Rust. `Emu<1>` is the scalar fallback; `Emu<16>` runs 16-lane code (masks, tails,
//! divergence) on any machine. These lane formulas are also the reference the hardware levels
//! are tested against.

use crate::packets::{F32s, I32s, M32s, Simd, U32s};
use std::ops::{Add, BitAnd, BitOr, BitXor, Div, Mul, Neg, Not, Sub};

/// N lanes emulated with arrays.
#[derive(Clone, Copy, Debug, Default)]
pub struct Emu<const N: usize>;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmuF32<const N: usize>(pub [f32; N]);
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EmuI32<const N: usize>(pub [i32; N]);
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EmuU32<const N: usize>(pub [u32; N]);
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EmuM32<const N: usize>(pub [bool; N]);

fn lanes<T: Copy, R, const N: usize>(a: [T; N], f: impl Fn(T) -> R) -> [R; N] {
    std::array::from_fn(|k| f(a[k]))
}
fn lanes2<T: Copy, R, const N: usize>(a: [T; N], b: [T; N], f: impl Fn(T, T) -> R) -> [R; N] {
    std::array::from_fn(|k| f(a[k], b[k]))
}

macro_rules! binary_ops {
    ($ty:ident, $($tr:ident $m:ident $f:expr;)*) => {$(
        impl<const N: usize> $tr for $ty<N> {
            type Output = Self;
            #[inline(always)]
            fn $m(self, o: Self) -> Self {
                $ty(lanes2(self.0, o.0, $f))
            }
        }
    )*};
}

binary_ops!(EmuF32, Add add |a, b| a + b; Sub sub |a, b| a - b; Mul mul |a, b| a * b; Div div |a, b| a / b;);
binary_ops!(EmuI32, Add add i32::wrapping_add; Sub sub i32::wrapping_sub; Mul mul i32::wrapping_mul;
    BitAnd bitand |a, b| a & b; BitOr bitor |a, b| a | b; BitXor bitxor |a, b| a ^ b;);
binary_ops!(EmuU32, Add add u32::wrapping_add; Sub sub u32::wrapping_sub; Mul mul u32::wrapping_mul;
    BitAnd bitand |a, b| a & b; BitOr bitor |a, b| a | b; BitXor bitxor |a, b| a ^ b;);
binary_ops!(EmuM32, BitAnd bitand |a, b| a & b; BitOr bitor |a, b| a | b; BitXor bitxor |a, b| a ^ b;);

impl<const N: usize> Neg for EmuF32<N> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        EmuF32(lanes(self.0, |a| -a))
    }
}
impl<const N: usize> Neg for EmuI32<N> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        EmuI32(lanes(self.0, i32::wrapping_neg))
    }
}
impl<const N: usize> Not for EmuI32<N> {
    type Output = Self;
    #[inline(always)]
    fn not(self) -> Self {
        EmuI32(lanes(self.0, |a| !a))
    }
}
impl<const N: usize> Not for EmuU32<N> {
    type Output = Self;
    #[inline(always)]
    fn not(self) -> Self {
        EmuU32(lanes(self.0, |a| !a))
    }
}
impl<const N: usize> Not for EmuM32<N> {
    type Output = Self;
    #[inline(always)]
    fn not(self) -> Self {
        EmuM32(lanes(self.0, |a| !a))
    }
}

impl<const N: usize> Simd for Emu<N> {
    const LANES: usize = N;
    const NAME: &'static str = match N {
        1 => "scalar",
        16 => "emu16",
        _ => "emu",
    };

    #[inline(always)]
    fn outline<R>(self, f: impl FnOnce() -> R) -> R {
        f()
    }
    type F = EmuF32<N>;
    type I = EmuI32<N>;
    type U = EmuU32<N>;
    type M = EmuM32<N>;

    #[inline(always)]
    fn splat(self, x: f32) -> EmuF32<N> {
        EmuF32([x; N])
    }
    #[inline(always)]
    fn splat_i(self, x: i32) -> EmuI32<N> {
        EmuI32([x; N])
    }
    #[inline(always)]
    fn splat_u(self, x: u32) -> EmuU32<N> {
        EmuU32([x; N])
    }
    #[inline(always)]
    fn first_lanes(self, n: usize) -> EmuM32<N> {
        EmuM32(std::array::from_fn(|k| k < n))
    }
    #[inline(always)]
    fn lane_index(self) -> EmuI32<N> {
        EmuI32(std::array::from_fn(|k| k as i32))
    }
    #[inline(always)]
    fn load(self, s: &[f32]) -> EmuF32<N> {
        EmuF32(s[..N].try_into().unwrap())
    }
    #[inline(always)]
    fn load_partial(self, s: &[f32]) -> EmuF32<N> {
        EmuF32(std::array::from_fn(|k| s.get(k).copied().unwrap_or(0.0)))
    }
    #[inline(always)]
    fn load_i(self, s: &[i32]) -> EmuI32<N> {
        EmuI32(s[..N].try_into().unwrap())
    }
    #[inline(always)]
    fn load_u(self, s: &[u32]) -> EmuU32<N> {
        EmuU32(s[..N].try_into().unwrap())
    }
    #[inline(always)]
    fn store(self, v: EmuF32<N>, out: &mut [f32]) {
        out[..N].copy_from_slice(&v.0);
    }
    #[inline(always)]
    fn store_partial(self, v: EmuF32<N>, out: &mut [f32]) {
        let n = out.len().min(N);
        out[..n].copy_from_slice(&v.0[..n]);
    }
    #[inline(always)]
    fn store_i(self, v: EmuI32<N>, out: &mut [i32]) {
        out[..N].copy_from_slice(&v.0);
    }
    #[inline(always)]
    fn store_u(self, v: EmuU32<N>, out: &mut [u32]) {
        out[..N].copy_from_slice(&v.0);
    }
    #[inline(always)]
    fn gather(self, table: &[f32], idx: EmuI32<N>) -> EmuF32<N> {
        assert!(!table.is_empty() && table.len() <= i32::MAX as usize, "gather from a table of {} values", table.len());
        let last = table.len() as i32 - 1;
        EmuF32(lanes(idx.0, |i| table[i.clamp(0, last) as usize]))
    }
}

impl<const N: usize> F32s<Emu<N>> for EmuF32<N> {
    #[inline(always)]
    fn mul_add(self, a: Self, b: Self) -> Self {
        EmuF32(std::array::from_fn(|k| self.0[k] * a.0[k] + b.0[k]))
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        EmuF32(lanes2(self.0, o.0, f32::min))
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        EmuF32(lanes2(self.0, o.0, f32::max))
    }
    #[inline(always)]
    fn abs(self) -> Self {
        EmuF32(lanes(self.0, f32::abs))
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        EmuF32(lanes(self.0, f32::sqrt))
    }
    #[inline(always)]
    fn floor(self) -> Self {
        EmuF32(lanes(self.0, f32::floor))
    }
    #[inline(always)]
    fn ceil(self) -> Self {
        EmuF32(lanes(self.0, f32::ceil))
    }
    #[inline(always)]
    fn trunc(self) -> Self {
        EmuF32(lanes(self.0, f32::trunc))
    }
    #[inline(always)]
    fn round(self) -> Self {
        EmuF32(lanes(self.0, f32::round_ties_even))
    }
    #[inline(always)]
    fn fract(self) -> Self {
        EmuF32(lanes(self.0, |a| a - a.floor()))
    }
    #[inline(always)]
    fn rcp(self) -> Self {
        EmuF32(lanes(self.0, |a| 1.0 / a))
    }
    #[inline(always)]
    fn rsqrt(self) -> Self {
        EmuF32(lanes(self.0, |a| 1.0 / a.sqrt()))
    }
    #[inline(always)]
    fn eq(self, o: Self) -> EmuM32<N> {
        EmuM32(lanes2(self.0, o.0, |a, b| a == b))
    }
    #[inline(always)]
    fn ne(self, o: Self) -> EmuM32<N> {
        EmuM32(lanes2(self.0, o.0, |a, b| a != b))
    }
    #[inline(always)]
    fn lt(self, o: Self) -> EmuM32<N> {
        EmuM32(lanes2(self.0, o.0, |a, b| a < b))
    }
    #[inline(always)]
    fn le(self, o: Self) -> EmuM32<N> {
        EmuM32(lanes2(self.0, o.0, |a, b| a <= b))
    }
    #[inline(always)]
    fn gt(self, o: Self) -> EmuM32<N> {
        EmuM32(lanes2(self.0, o.0, |a, b| a > b))
    }
    #[inline(always)]
    fn ge(self, o: Self) -> EmuM32<N> {
        EmuM32(lanes2(self.0, o.0, |a, b| a >= b))
    }
    #[inline(always)]
    fn is_nan(self) -> EmuM32<N> {
        EmuM32(lanes(self.0, f32::is_nan))
    }
    #[inline(always)]
    fn to_i32(self) -> EmuI32<N> {
        EmuI32(lanes(self.0, |a| a as i32))
    }
    #[inline(always)]
    fn to_u32(self) -> EmuU32<N> {
        EmuU32(lanes(self.0, |a| a as u32))
    }
    #[inline(always)]
    fn to_bits(self) -> EmuU32<N> {
        EmuU32(lanes(self.0, f32::to_bits))
    }
    #[inline(always)]
    fn write_to(self, out: &mut [f32]) {
        out.copy_from_slice(&self.0);
    }
    #[inline(always)]
    fn map(self, f: impl Fn(f32) -> f32) -> Self {
        EmuF32(lanes(self.0, f))
    }
}

impl<const N: usize> I32s<Emu<N>> for EmuI32<N> {
    #[inline(always)]
    fn shl(self, n: Self) -> Self {
        EmuI32(lanes2(self.0, n.0, |a, b| a.wrapping_shl(b as u32)))
    }
    #[inline(always)]
    fn shr(self, n: Self) -> Self {
        EmuI32(lanes2(self.0, n.0, |a, b| a.wrapping_shr(b as u32)))
    }
    #[inline(always)]
    fn div(self, d: Self) -> Self {
        EmuI32(lanes2(self.0, d.0, |a, b| a.checked_div(b).unwrap_or(a)))
    }
    #[inline(always)]
    fn rem(self, d: Self) -> Self {
        EmuI32(lanes2(self.0, d.0, |a, b| a.checked_rem(b).unwrap_or(0)))
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        EmuI32(lanes2(self.0, o.0, Ord::min))
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        EmuI32(lanes2(self.0, o.0, Ord::max))
    }
    #[inline(always)]
    fn abs(self) -> Self {
        EmuI32(lanes(self.0, i32::wrapping_abs))
    }
    #[inline(always)]
    fn eq(self, o: Self) -> EmuM32<N> {
        EmuM32(lanes2(self.0, o.0, |a, b| a == b))
    }
    #[inline(always)]
    fn lt(self, o: Self) -> EmuM32<N> {
        EmuM32(lanes2(self.0, o.0, |a, b| a < b))
    }
    #[inline(always)]
    fn gt(self, o: Self) -> EmuM32<N> {
        EmuM32(lanes2(self.0, o.0, |a, b| a > b))
    }
    #[inline(always)]
    fn to_f32(self) -> EmuF32<N> {
        EmuF32(lanes(self.0, |a| a as f32))
    }
    #[inline(always)]
    fn to_u32_bits(self) -> EmuU32<N> {
        EmuU32(lanes(self.0, |a| a as u32))
    }
    #[inline(always)]
    fn write_to(self, out: &mut [i32]) {
        out.copy_from_slice(&self.0);
    }
}

impl<const N: usize> U32s<Emu<N>> for EmuU32<N> {
    #[inline(always)]
    fn shl(self, n: Self) -> Self {
        EmuU32(lanes2(self.0, n.0, u32::wrapping_shl))
    }
    #[inline(always)]
    fn shr(self, n: Self) -> Self {
        EmuU32(lanes2(self.0, n.0, u32::wrapping_shr))
    }
    #[inline(always)]
    fn div(self, d: Self) -> Self {
        EmuU32(lanes2(self.0, d.0, |a, b| a.checked_div(b).unwrap_or(a)))
    }
    #[inline(always)]
    fn rem(self, d: Self) -> Self {
        EmuU32(lanes2(self.0, d.0, |a, b| a.checked_rem(b).unwrap_or(0)))
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        EmuU32(lanes2(self.0, o.0, Ord::min))
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        EmuU32(lanes2(self.0, o.0, Ord::max))
    }
    #[inline(always)]
    fn eq(self, o: Self) -> EmuM32<N> {
        EmuM32(lanes2(self.0, o.0, |a, b| a == b))
    }
    #[inline(always)]
    fn lt(self, o: Self) -> EmuM32<N> {
        EmuM32(lanes2(self.0, o.0, |a, b| a < b))
    }
    #[inline(always)]
    fn gt(self, o: Self) -> EmuM32<N> {
        EmuM32(lanes2(self.0, o.0, |a, b| a > b))
    }
    #[inline(always)]
    fn to_f32(self) -> EmuF32<N> {
        EmuF32(lanes(self.0, |a| a as f32))
    }
    #[inline(always)]
    fn to_f32_bits(self) -> EmuF32<N> {
        EmuF32(lanes(self.0, f32::from_bits))
    }
    #[inline(always)]
    fn to_i32_bits(self) -> EmuI32<N> {
        EmuI32(lanes(self.0, |a| a as i32))
    }
    #[inline(always)]
    fn write_to(self, out: &mut [u32]) {
        out.copy_from_slice(&self.0);
    }
}

impl<const N: usize> M32s<Emu<N>> for EmuM32<N> {
    #[inline(always)]
    fn any(self) -> bool {
        self.0.iter().any(|&b| b)
    }
    #[inline(always)]
    fn all(self) -> bool {
        self.0.iter().all(|&b| b)
    }
    #[inline(always)]
    fn bitmask(self) -> u32 {
        self.0.iter().enumerate().fold(0, |m, (k, &b)| m | ((b as u32) << k))
    }
    #[inline(always)]
    fn select(self, on: EmuF32<N>, off: EmuF32<N>) -> EmuF32<N> {
        EmuF32(std::array::from_fn(|k| if self.0[k] { on.0[k] } else { off.0[k] }))
    }
    #[inline(always)]
    fn select_i(self, on: EmuI32<N>, off: EmuI32<N>) -> EmuI32<N> {
        EmuI32(std::array::from_fn(|k| if self.0[k] { on.0[k] } else { off.0[k] }))
    }
    #[inline(always)]
    fn select_u(self, on: EmuU32<N>, off: EmuU32<N>) -> EmuU32<N> {
        EmuU32(std::array::from_fn(|k| if self.0[k] { on.0[k] } else { off.0[k] }))
    }
}
