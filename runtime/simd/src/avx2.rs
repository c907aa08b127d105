//! The AVX2 level (8 lanes, with FMA): [`Avx2`] and its packets over `__m256`/`__m256i`.
//!
//! Safety: every value of these types was made through an [`Avx2`] token, and the token is
//! only made by [`entry`], which [`crate::Level::dispatch`] calls after detecting AVX2 and FMA.
//! So the intrinsics called below (all `#[inline(always)]`, inlined into `entry`'s
//! `#[target_feature]` context) only run on a machine that has them: the `avx!` blocks rely on
//! that alone. Loads, stores and gathers also take pointers; their blocks say why each access
//! is in bounds.

use crate::level::WithSimd;
use crate::packets::{F32s, I32s, M32s, Simd, U32s};
use std::arch::x86_64::*;
use std::ops::{Add, BitAnd, BitOr, BitXor, Div, Mul, Neg, Not, Sub};

/// The AVX2 + FMA token.
#[derive(Clone, Copy, Debug)]
pub struct Avx2 {
    _private: (),
}

#[derive(Clone, Copy, Debug)]
pub struct F32x8(__m256);
#[derive(Clone, Copy, Debug)]
pub struct I32x8(__m256i);
#[derive(Clone, Copy, Debug)]
pub struct U32x8(__m256i);
/// All-ones or all-zeros 32-bit lanes.
#[derive(Clone, Copy, Debug)]
pub struct M32x8(__m256i);

/// Runs `op` at the AVX2 level.
///
/// # Safety
/// The machine must have AVX2 and FMA.
#[target_feature(enable = "avx2,fma")]
pub(crate) unsafe fn entry<Op: WithSimd>(op: Op) -> Op::Output {
    op.with_simd(Avx2 { _private: () })
}

/// An intrinsic call: sound because an AVX2 token exists (module doc).
macro_rules! avx {
    ($e:expr) => {
        unsafe { $e }
    };
}

const SIGN: i32 = i32::MIN;

#[inline(always)]
fn ps(m: __m256i) -> __m256 {
    avx!(_mm256_castsi256_ps(m))
}
#[inline(always)]
fn si(m: __m256) -> __m256i {
    avx!(_mm256_castps_si256(m))
}
#[inline(always)]
fn splat_si(x: i32) -> __m256i {
    avx!(_mm256_set1_epi32(x))
}

macro_rules! float_binary {
    ($($tr:ident $m:ident $intr:ident;)*) => {$(
        impl $tr for F32x8 {
            type Output = Self;
            #[inline(always)]
            fn $m(self, o: Self) -> Self {
                F32x8(avx!($intr(self.0, o.0)))
            }
        }
    )*};
}
float_binary!(Add add _mm256_add_ps; Sub sub _mm256_sub_ps; Mul mul _mm256_mul_ps; Div div _mm256_div_ps;);

macro_rules! int_binary {
    ($ty:ident, $($tr:ident $m:ident $intr:ident;)*) => {$(
        impl $tr for $ty {
            type Output = Self;
            #[inline(always)]
            fn $m(self, o: Self) -> Self {
                $ty(avx!($intr(self.0, o.0)))
            }
        }
    )*};
}
int_binary!(I32x8, Add add _mm256_add_epi32; Sub sub _mm256_sub_epi32; Mul mul _mm256_mullo_epi32;
    BitAnd bitand _mm256_and_si256; BitOr bitor _mm256_or_si256; BitXor bitxor _mm256_xor_si256;);
int_binary!(U32x8, Add add _mm256_add_epi32; Sub sub _mm256_sub_epi32; Mul mul _mm256_mullo_epi32;
    BitAnd bitand _mm256_and_si256; BitOr bitor _mm256_or_si256; BitXor bitxor _mm256_xor_si256;);
int_binary!(M32x8, BitAnd bitand _mm256_and_si256; BitOr bitor _mm256_or_si256; BitXor bitxor _mm256_xor_si256;);

macro_rules! int_not {
    ($($ty:ident)*) => {$(
        impl Not for $ty {
            type Output = Self;
            #[inline(always)]
            fn not(self) -> Self {
                $ty(avx!(_mm256_xor_si256(self.0, splat_si(-1))))
            }
        }
    )*};
}
int_not!(I32x8 U32x8 M32x8);

impl Neg for F32x8 {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        F32x8(ps(avx!(_mm256_xor_si256(si(self.0), splat_si(SIGN)))))
    }
}
impl Neg for I32x8 {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        I32x8(avx!(_mm256_sub_epi32(_mm256_setzero_si256(), self.0)))
    }
}

/// Per-lane scalar fallback over two integer packets.
#[inline(always)]
fn int_lanes(a: __m256i, b: __m256i, f: impl Fn(i32, i32) -> i32) -> __m256i {
    let (mut x, mut y) = ([0i32; 8], [0i32; 8]);
    // SAFETY: `x` and `y` are 8 i32 = 32 bytes, the width of the unaligned stores.
    avx!(_mm256_storeu_si256(x.as_mut_ptr().cast(), a));
    avx!(_mm256_storeu_si256(y.as_mut_ptr().cast(), b));
    let r: [i32; 8] = std::array::from_fn(|k| f(x[k], y[k]));
    // SAFETY: `r` is 32 bytes, the width of the unaligned load.
    avx!(_mm256_loadu_si256(r.as_ptr().cast()))
}

impl Simd for Avx2 {
    const LANES: usize = 8;
    const NAME: &'static str = "avx2";
    type F = F32x8;
    type I = I32x8;
    type U = U32x8;
    type M = M32x8;

    #[inline(always)]
    fn outline<R>(self, f: impl FnOnce() -> R) -> R {
        /// A function of its own, compiled for AVX2, `f` inlined into it.
        #[target_feature(enable = "avx2,fma")]
        #[inline(never)]
        fn part<R>(f: impl FnOnce() -> R) -> R {
            f()
        }
        // SAFETY: the token exists, so the features were detected (module doc).
        unsafe { part(f) }
    }

    #[inline(always)]
    fn splat(self, x: f32) -> F32x8 {
        F32x8(avx!(_mm256_set1_ps(x)))
    }
    #[inline(always)]
    fn splat_i(self, x: i32) -> I32x8 {
        I32x8(splat_si(x))
    }
    #[inline(always)]
    fn splat_u(self, x: u32) -> U32x8 {
        U32x8(splat_si(x as i32))
    }
    #[inline(always)]
    fn first_lanes(self, n: usize) -> M32x8 {
        let n = n.min(8) as i32;
        M32x8(avx!(_mm256_cmpgt_epi32(splat_si(n), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7))))
    }
    #[inline(always)]
    fn lane_index(self) -> I32x8 {
        I32x8(avx!(_mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7)))
    }
    #[inline(always)]
    fn load(self, s: &[f32]) -> F32x8 {
        let s = &s[..8];
        // SAFETY: `s` holds 8 f32, the width of the unaligned load.
        F32x8(avx!(_mm256_loadu_ps(s.as_ptr())))
    }
    #[inline(always)]
    fn load_partial(self, s: &[f32]) -> F32x8 {
        let mut a = [0f32; 8];
        let n = s.len().min(8);
        a[..n].copy_from_slice(&s[..n]);
        self.load(&a)
    }
    #[inline(always)]
    fn load_i(self, s: &[i32]) -> I32x8 {
        let s = &s[..8];
        // SAFETY: `s` holds 8 i32 = 32 bytes, the width of the unaligned load.
        I32x8(avx!(_mm256_loadu_si256(s.as_ptr().cast())))
    }
    #[inline(always)]
    fn load_u(self, s: &[u32]) -> U32x8 {
        let s = &s[..8];
        // SAFETY: `s` holds 8 u32 = 32 bytes, the width of the unaligned load.
        U32x8(avx!(_mm256_loadu_si256(s.as_ptr().cast())))
    }
    #[inline(always)]
    fn store(self, v: F32x8, out: &mut [f32]) {
        let out = &mut out[..8];
        // SAFETY: `out` holds 8 f32, the width of the unaligned store.
        avx!(_mm256_storeu_ps(out.as_mut_ptr(), v.0))
    }
    #[inline(always)]
    fn store_partial(self, v: F32x8, out: &mut [f32]) {
        let mut a = [0f32; 8];
        self.store(v, &mut a);
        let n = out.len().min(8);
        out[..n].copy_from_slice(&a[..n]);
    }
    #[inline(always)]
    fn store_i(self, v: I32x8, out: &mut [i32]) {
        let out = &mut out[..8];
        // SAFETY: `out` holds 8 i32 = 32 bytes, the width of the unaligned store.
        avx!(_mm256_storeu_si256(out.as_mut_ptr().cast(), v.0))
    }
    #[inline(always)]
    fn store_u(self, v: U32x8, out: &mut [u32]) {
        let out = &mut out[..8];
        // SAFETY: `out` holds 8 u32 = 32 bytes, the width of the unaligned store.
        avx!(_mm256_storeu_si256(out.as_mut_ptr().cast(), v.0))
    }
    #[inline(always)]
    fn gather(self, table: &[f32], idx: I32x8) -> F32x8 {
        assert!(!table.is_empty() && table.len() <= i32::MAX as usize, "gather from a table of {} values", table.len());
        let clamped = avx!(_mm256_min_epi32(_mm256_max_epi32(idx.0, _mm256_setzero_si256()), splat_si(table.len() as i32 - 1)));
        // SAFETY: every lane's index lies in [0, table.len() − 1] after the clamp, so each
        // 4-byte load is inside `table`.
        F32x8(avx!(_mm256_i32gather_ps::<4>(table.as_ptr(), clamped)))
    }
}

impl F32x8 {
    #[inline(always)]
    fn cmp<const P: i32>(self, o: Self) -> M32x8 {
        M32x8(si(avx!(_mm256_cmp_ps::<P>(self.0, o.0))))
    }
    #[inline(always)]
    fn round_mode<const R: i32>(self) -> Self {
        F32x8(avx!(_mm256_round_ps::<R>(self.0)))
    }
    /// Where the lane is ±0 or ±∞: applied to an estimate, where a Newton step would turn it into
    /// NaN (exact inputs ±0 and ±∞, and subnormal inputs the estimate treats as zero).
    #[inline(always)]
    fn zero_or_inf(self) -> __m256 {
        let a = avx!(_mm256_and_ps(self.0, ps(splat_si(i32::MAX))));
        avx!(_mm256_or_ps(_mm256_cmp_ps::<_CMP_EQ_OQ>(a, _mm256_setzero_ps()), _mm256_cmp_ps::<_CMP_EQ_OQ>(a, _mm256_set1_ps(f32::INFINITY))))
    }
}

impl F32s<Avx2> for F32x8 {
    #[inline(always)]
    fn mul_add(self, a: Self, b: Self) -> Self {
        F32x8(avx!(_mm256_fmadd_ps(self.0, a.0, b.0)))
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        // minps gives its second operand when either is NaN: take `self` where `o` is NaN.
        let r = avx!(_mm256_min_ps(self.0, o.0));
        F32x8(avx!(_mm256_blendv_ps(r, self.0, _mm256_cmp_ps::<_CMP_UNORD_Q>(o.0, o.0))))
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        let r = avx!(_mm256_max_ps(self.0, o.0));
        F32x8(avx!(_mm256_blendv_ps(r, self.0, _mm256_cmp_ps::<_CMP_UNORD_Q>(o.0, o.0))))
    }
    #[inline(always)]
    fn abs(self) -> Self {
        F32x8(avx!(_mm256_and_ps(self.0, ps(splat_si(i32::MAX)))))
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        F32x8(avx!(_mm256_sqrt_ps(self.0)))
    }
    #[inline(always)]
    fn floor(self) -> Self {
        self.round_mode::<{ _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC }>()
    }
    #[inline(always)]
    fn ceil(self) -> Self {
        self.round_mode::<{ _MM_FROUND_TO_POS_INF | _MM_FROUND_NO_EXC }>()
    }
    #[inline(always)]
    fn trunc(self) -> Self {
        self.round_mode::<{ _MM_FROUND_TO_ZERO | _MM_FROUND_NO_EXC }>()
    }
    #[inline(always)]
    fn round(self) -> Self {
        self.round_mode::<{ _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC }>()
    }
    #[inline(always)]
    fn fract(self) -> Self {
        self - self.floor()
    }
    #[inline(always)]
    fn rcp(self) -> Self {
        // y₁ = y₀ + y₀(1 − x·y₀): 12 bits → ≈ 23.
        let y = avx!(_mm256_rcp_ps(self.0));
        let e = avx!(_mm256_fnmadd_ps(self.0, y, _mm256_set1_ps(1.0)));
        let r = avx!(_mm256_fmadd_ps(y, e, y));
        F32x8(avx!(_mm256_blendv_ps(r, y, F32x8(y).zero_or_inf())))
    }
    #[inline(always)]
    fn rsqrt(self) -> Self {
        // y₁ = y₀ · (1.5 − (x·y₀)·0.5·y₀), x·y₀ first so that a tiny x does not underflow.
        let y = avx!(_mm256_rsqrt_ps(self.0));
        let hxy = avx!(_mm256_mul_ps(_mm256_mul_ps(self.0, y), _mm256_set1_ps(0.5)));
        let t = avx!(_mm256_fnmadd_ps(hxy, y, _mm256_set1_ps(1.5)));
        let r = avx!(_mm256_mul_ps(y, t));
        F32x8(avx!(_mm256_blendv_ps(r, y, F32x8(y).zero_or_inf())))
    }
    #[inline(always)]
    fn eq(self, o: Self) -> M32x8 {
        self.cmp::<_CMP_EQ_OQ>(o)
    }
    #[inline(always)]
    fn ne(self, o: Self) -> M32x8 {
        self.cmp::<_CMP_NEQ_UQ>(o)
    }
    #[inline(always)]
    fn lt(self, o: Self) -> M32x8 {
        self.cmp::<_CMP_LT_OQ>(o)
    }
    #[inline(always)]
    fn le(self, o: Self) -> M32x8 {
        self.cmp::<_CMP_LE_OQ>(o)
    }
    #[inline(always)]
    fn gt(self, o: Self) -> M32x8 {
        self.cmp::<_CMP_GT_OQ>(o)
    }
    #[inline(always)]
    fn ge(self, o: Self) -> M32x8 {
        self.cmp::<_CMP_GE_OQ>(o)
    }
    #[inline(always)]
    fn is_nan(self) -> M32x8 {
        self.cmp::<_CMP_UNORD_Q>(self)
    }
    #[inline(always)]
    fn to_i32(self) -> I32x8 {
        // cvttps gives i32::MIN for NaN and out of range: fix x ≥ 2³¹ to MAX and NaN to 0.
        let r = avx!(_mm256_cvttps_epi32(self.0));
        let big = avx!(_mm256_cmp_ps::<_CMP_GE_OQ>(self.0, _mm256_set1_ps(2147483648.0)));
        let r = avx!(_mm256_blendv_ps(ps(r), ps(splat_si(i32::MAX)), big));
        let ordered = avx!(_mm256_cmp_ps::<_CMP_ORD_Q>(self.0, self.0));
        I32x8(si(avx!(_mm256_and_ps(r, ordered))))
    }
    #[inline(always)]
    fn to_u32(self) -> U32x8 {
        // max(x, 0) also maps NaN to 0 (maxps returns its second operand for NaN).
        let x = avx!(_mm256_max_ps(self.0, _mm256_setzero_ps()));
        let two31 = avx!(_mm256_set1_ps(2147483648.0));
        let low = avx!(_mm256_cvttps_epi32(x));
        let high = avx!(_mm256_xor_si256(_mm256_cvttps_epi32(_mm256_sub_ps(x, two31)), splat_si(SIGN)));
        let r = avx!(_mm256_blendv_ps(ps(low), ps(high), _mm256_cmp_ps::<_CMP_GE_OQ>(x, two31)));
        let r = avx!(_mm256_blendv_ps(r, ps(splat_si(-1)), _mm256_cmp_ps::<_CMP_GE_OQ>(x, _mm256_set1_ps(4294967296.0))));
        U32x8(si(r))
    }
    #[inline(always)]
    fn to_bits(self) -> U32x8 {
        U32x8(si(self.0))
    }
    #[inline(always)]
    fn write_to(self, out: &mut [f32]) {
        assert_eq!(out.len(), 8);
        Avx2 { _private: () }.store(self, out)
    }
    #[inline(always)]
    fn map(self, f: impl Fn(f32) -> f32) -> Self {
        let mut a = [0f32; 8];
        self.write_to(&mut a);
        Avx2 { _private: () }.load(&a.map(f))
    }
}

impl I32s<Avx2> for I32x8 {
    #[inline(always)]
    fn shl(self, n: Self) -> Self {
        I32x8(avx!(_mm256_sllv_epi32(self.0, _mm256_and_si256(n.0, splat_si(31)))))
    }
    #[inline(always)]
    fn shr(self, n: Self) -> Self {
        I32x8(avx!(_mm256_srav_epi32(self.0, _mm256_and_si256(n.0, splat_si(31)))))
    }
    #[inline(always)]
    fn div(self, d: Self) -> Self {
        I32x8(int_lanes(self.0, d.0, |a, b| a.checked_div(b).unwrap_or(a)))
    }
    #[inline(always)]
    fn rem(self, d: Self) -> Self {
        I32x8(int_lanes(self.0, d.0, |a, b| a.checked_rem(b).unwrap_or(0)))
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        I32x8(avx!(_mm256_min_epi32(self.0, o.0)))
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        I32x8(avx!(_mm256_max_epi32(self.0, o.0)))
    }
    #[inline(always)]
    fn abs(self) -> Self {
        I32x8(avx!(_mm256_abs_epi32(self.0)))
    }
    #[inline(always)]
    fn eq(self, o: Self) -> M32x8 {
        M32x8(avx!(_mm256_cmpeq_epi32(self.0, o.0)))
    }
    #[inline(always)]
    fn lt(self, o: Self) -> M32x8 {
        M32x8(avx!(_mm256_cmpgt_epi32(o.0, self.0)))
    }
    #[inline(always)]
    fn gt(self, o: Self) -> M32x8 {
        M32x8(avx!(_mm256_cmpgt_epi32(self.0, o.0)))
    }
    #[inline(always)]
    fn to_f32(self) -> F32x8 {
        F32x8(avx!(_mm256_cvtepi32_ps(self.0)))
    }
    #[inline(always)]
    fn to_u32_bits(self) -> U32x8 {
        U32x8(self.0)
    }
    #[inline(always)]
    fn write_to(self, out: &mut [i32]) {
        assert_eq!(out.len(), 8);
        Avx2 { _private: () }.store_i(self, out)
    }
}

impl U32x8 {
    /// The lanes with the sign bit flipped, so that signed compares order them as unsigned.
    #[inline(always)]
    fn biased(self) -> __m256i {
        avx!(_mm256_xor_si256(self.0, splat_si(SIGN)))
    }
}

impl U32s<Avx2> for U32x8 {
    #[inline(always)]
    fn shl(self, n: Self) -> Self {
        U32x8(avx!(_mm256_sllv_epi32(self.0, _mm256_and_si256(n.0, splat_si(31)))))
    }
    #[inline(always)]
    fn shr(self, n: Self) -> Self {
        U32x8(avx!(_mm256_srlv_epi32(self.0, _mm256_and_si256(n.0, splat_si(31)))))
    }
    #[inline(always)]
    fn div(self, d: Self) -> Self {
        U32x8(int_lanes(self.0, d.0, |a, b| (a as u32).checked_div(b as u32).unwrap_or(a as u32) as i32))
    }
    #[inline(always)]
    fn rem(self, d: Self) -> Self {
        U32x8(int_lanes(self.0, d.0, |a, b| (a as u32).checked_rem(b as u32).unwrap_or(0) as i32))
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        U32x8(avx!(_mm256_min_epu32(self.0, o.0)))
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        U32x8(avx!(_mm256_max_epu32(self.0, o.0)))
    }
    #[inline(always)]
    fn eq(self, o: Self) -> M32x8 {
        M32x8(avx!(_mm256_cmpeq_epi32(self.0, o.0)))
    }
    #[inline(always)]
    fn lt(self, o: Self) -> M32x8 {
        M32x8(avx!(_mm256_cmpgt_epi32(o.biased(), self.biased())))
    }
    #[inline(always)]
    fn gt(self, o: Self) -> M32x8 {
        M32x8(avx!(_mm256_cmpgt_epi32(self.biased(), o.biased())))
    }
    #[inline(always)]
    fn to_f32(self) -> F32x8 {
        // hi·2¹⁶ and lo are exact in f32; their sum is rounded once: correctly rounded.
        let lo = avx!(_mm256_cvtepi32_ps(_mm256_and_si256(self.0, splat_si(0xFFFF))));
        let hi = avx!(_mm256_cvtepi32_ps(_mm256_srli_epi32::<16>(self.0)));
        F32x8(avx!(_mm256_fmadd_ps(hi, _mm256_set1_ps(65536.0), lo)))
    }
    #[inline(always)]
    fn to_f32_bits(self) -> F32x8 {
        F32x8(ps(self.0))
    }
    #[inline(always)]
    fn to_i32_bits(self) -> I32x8 {
        I32x8(self.0)
    }
    #[inline(always)]
    fn write_to(self, out: &mut [u32]) {
        assert_eq!(out.len(), 8);
        Avx2 { _private: () }.store_u(self, out)
    }
}

impl M32s<Avx2> for M32x8 {
    #[inline(always)]
    fn any(self) -> bool {
        avx!(_mm256_movemask_ps(ps(self.0))) != 0
    }
    #[inline(always)]
    fn all(self) -> bool {
        avx!(_mm256_movemask_ps(ps(self.0))) == 0xFF
    }
    #[inline(always)]
    fn bitmask(self) -> u32 {
        avx!(_mm256_movemask_ps(ps(self.0))) as u32
    }
    #[inline(always)]
    fn select(self, on: F32x8, off: F32x8) -> F32x8 {
        F32x8(avx!(_mm256_blendv_ps(off.0, on.0, ps(self.0))))
    }
    #[inline(always)]
    fn select_i(self, on: I32x8, off: I32x8) -> I32x8 {
        I32x8(si(avx!(_mm256_blendv_ps(ps(off.0), ps(on.0), ps(self.0)))))
    }
    #[inline(always)]
    fn select_u(self, on: U32x8, off: U32x8) -> U32x8 {
        U32x8(si(avx!(_mm256_blendv_ps(ps(off.0), ps(on.0), ps(self.0)))))
    }
}
