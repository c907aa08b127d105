//! The AVX-512 level (16 lanes; F, BW, DQ, VL with FMA): [`Avx512`] and its packets over
//! `__m512`/`__m512i`, masks as `__mmask16`.
//!
//! Safety: as in `avx2.rs` — every value of these types was made through an [`Avx512`]
//! token, made only by [`entry`] after [`crate::Level::dispatch`] detected the features, so
//! the `avx!` intrinsic calls run only where they exist; the pointer-taking ones say why each
//! access is in bounds.

use crate::level::WithSimd;
use crate::packets::{F32s, I32s, M32s, Simd, U32s};
use std::arch::x86_64::*;
use std::ops::{Add, BitAnd, BitOr, BitXor, Div, Mul, Neg, Not, Sub};

/// The AVX-512 token.
#[derive(Clone, Copy, Debug)]
pub struct Avx512 {
    _private: (),
}

#[derive(Clone, Copy, Debug)]
pub struct F32x16(__m512);
#[derive(Clone, Copy, Debug)]
pub struct I32x16(__m512i);
#[derive(Clone, Copy, Debug)]
pub struct U32x16(__m512i);
/// One bit per lane.
#[derive(Clone, Copy, Debug)]
pub struct M32x16(__mmask16);

/// Runs `op` at the AVX-512 level.
///
/// # Safety
/// The machine must have AVX-512 F, BW, DQ and VL, AVX2 and FMA.
#[target_feature(enable = "avx512f,avx512bw,avx512dq,avx512vl,avx2,fma")]
pub(crate) unsafe fn entry<Op: WithSimd>(op: Op) -> Op::Output {
    op.with_simd(Avx512 { _private: () })
}

/// An intrinsic call: sound because an AVX-512 token exists (module doc).
macro_rules! avx {
    ($e:expr) => {
        unsafe { $e }
    };
}

#[inline(always)]
fn splat_si(x: i32) -> __m512i {
    avx!(_mm512_set1_epi32(x))
}
#[inline(always)]
fn ps(m: __m512i) -> __m512 {
    avx!(_mm512_castsi512_ps(m))
}
#[inline(always)]
fn si(m: __m512) -> __m512i {
    avx!(_mm512_castps_si512(m))
}

macro_rules! float_binary {
    ($($tr:ident $m:ident $intr:ident;)*) => {$(
        impl $tr for F32x16 {
            type Output = Self;
            #[inline(always)]
            fn $m(self, o: Self) -> Self {
                F32x16(avx!($intr(self.0, o.0)))
            }
        }
    )*};
}
float_binary!(Add add _mm512_add_ps; Sub sub _mm512_sub_ps; Mul mul _mm512_mul_ps; Div div _mm512_div_ps;);

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
int_binary!(I32x16, Add add _mm512_add_epi32; Sub sub _mm512_sub_epi32; Mul mul _mm512_mullo_epi32;
    BitAnd bitand _mm512_and_si512; BitOr bitor _mm512_or_si512; BitXor bitxor _mm512_xor_si512;);
int_binary!(U32x16, Add add _mm512_add_epi32; Sub sub _mm512_sub_epi32; Mul mul _mm512_mullo_epi32;
    BitAnd bitand _mm512_and_si512; BitOr bitor _mm512_or_si512; BitXor bitxor _mm512_xor_si512;);

impl BitAnd for M32x16 {
    type Output = Self;
    #[inline(always)]
    fn bitand(self, o: Self) -> Self {
        M32x16(self.0 & o.0)
    }
}
impl BitOr for M32x16 {
    type Output = Self;
    #[inline(always)]
    fn bitor(self, o: Self) -> Self {
        M32x16(self.0 | o.0)
    }
}
impl BitXor for M32x16 {
    type Output = Self;
    #[inline(always)]
    fn bitxor(self, o: Self) -> Self {
        M32x16(self.0 ^ o.0)
    }
}
impl Not for M32x16 {
    type Output = Self;
    #[inline(always)]
    fn not(self) -> Self {
        M32x16(!self.0)
    }
}
impl Not for I32x16 {
    type Output = Self;
    #[inline(always)]
    fn not(self) -> Self {
        I32x16(avx!(_mm512_xor_si512(self.0, splat_si(-1))))
    }
}
impl Not for U32x16 {
    type Output = Self;
    #[inline(always)]
    fn not(self) -> Self {
        U32x16(avx!(_mm512_xor_si512(self.0, splat_si(-1))))
    }
}
impl Neg for F32x16 {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        F32x16(ps(avx!(_mm512_xor_si512(si(self.0), splat_si(i32::MIN)))))
    }
}
impl Neg for I32x16 {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        I32x16(avx!(_mm512_sub_epi32(_mm512_setzero_si512(), self.0)))
    }
}

/// Per-lane scalar fallback over two integer packets.
#[inline(always)]
fn int_lanes(a: __m512i, b: __m512i, f: impl Fn(i32, i32) -> i32) -> __m512i {
    let (mut x, mut y) = ([0i32; 16], [0i32; 16]);
    // SAFETY: `x` and `y` are 16 i32 = 64 bytes, the width of the unaligned stores.
    avx!(_mm512_storeu_si512(x.as_mut_ptr().cast(), a));
    avx!(_mm512_storeu_si512(y.as_mut_ptr().cast(), b));
    let r: [i32; 16] = std::array::from_fn(|k| f(x[k], y[k]));
    // SAFETY: `r` is 64 bytes, the width of the unaligned load.
    avx!(_mm512_loadu_si512(r.as_ptr().cast()))
}

const LANE_INDEX: [i32; 16] = [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15];

impl Simd for Avx512 {
    const LANES: usize = 16;
    const NAME: &'static str = "avx512";
    type F = F32x16;
    type I = I32x16;
    type U = U32x16;
    type M = M32x16;

    #[inline(always)]
    fn outline<R>(self, f: impl FnOnce() -> R) -> R {
        /// A function of its own, compiled for AVX-512, `f` inlined into it.
        #[target_feature(enable = "avx512f,avx512bw,avx512dq,avx512vl,avx2,fma")]
        #[inline(never)]
        fn part<R>(f: impl FnOnce() -> R) -> R {
            f()
        }
        // SAFETY: the token exists, so the features were detected (module doc).
        unsafe { part(f) }
    }

    #[inline(always)]
    fn splat(self, x: f32) -> F32x16 {
        F32x16(avx!(_mm512_set1_ps(x)))
    }
    #[inline(always)]
    fn splat_i(self, x: i32) -> I32x16 {
        I32x16(splat_si(x))
    }
    #[inline(always)]
    fn splat_u(self, x: u32) -> U32x16 {
        U32x16(splat_si(x as i32))
    }
    #[inline(always)]
    fn first_lanes(self, n: usize) -> M32x16 {
        M32x16(if n >= 16 { 0xFFFF } else { ((1u32 << n) - 1) as u16 })
    }
    #[inline(always)]
    fn lane_index(self) -> I32x16 {
        self.load_i(&LANE_INDEX)
    }
    #[inline(always)]
    fn load(self, s: &[f32]) -> F32x16 {
        let s = &s[..16];
        // SAFETY: `s` holds 16 f32, the width of the unaligned load.
        F32x16(avx!(_mm512_loadu_ps(s.as_ptr())))
    }
    #[inline(always)]
    fn load_partial(self, s: &[f32]) -> F32x16 {
        let n = s.len().min(16);
        // SAFETY: the load is masked to the first `n` lanes, which lie inside `s`; masked-off
        // lanes are not accessed (and read as zero).
        F32x16(avx!(_mm512_maskz_loadu_ps(self.first_lanes(n).0, s.as_ptr())))
    }
    #[inline(always)]
    fn load_i(self, s: &[i32]) -> I32x16 {
        let s = &s[..16];
        // SAFETY: `s` holds 16 i32 = 64 bytes, the width of the unaligned load.
        I32x16(avx!(_mm512_loadu_si512(s.as_ptr().cast())))
    }
    #[inline(always)]
    fn load_u(self, s: &[u32]) -> U32x16 {
        let s = &s[..16];
        // SAFETY: `s` holds 16 u32 = 64 bytes, the width of the unaligned load.
        U32x16(avx!(_mm512_loadu_si512(s.as_ptr().cast())))
    }
    #[inline(always)]
    fn store(self, v: F32x16, out: &mut [f32]) {
        let out = &mut out[..16];
        // SAFETY: `out` holds 16 f32, the width of the unaligned store.
        avx!(_mm512_storeu_ps(out.as_mut_ptr(), v.0))
    }
    #[inline(always)]
    fn store_partial(self, v: F32x16, out: &mut [f32]) {
        let n = out.len().min(16);
        // SAFETY: the store is masked to the first `n` lanes, which lie inside `out`.
        avx!(_mm512_mask_storeu_ps(out.as_mut_ptr(), self.first_lanes(n).0, v.0))
    }
    #[inline(always)]
    fn store_i(self, v: I32x16, out: &mut [i32]) {
        let out = &mut out[..16];
        // SAFETY: `out` holds 16 i32 = 64 bytes, the width of the unaligned store.
        avx!(_mm512_storeu_si512(out.as_mut_ptr().cast(), v.0))
    }
    #[inline(always)]
    fn store_u(self, v: U32x16, out: &mut [u32]) {
        let out = &mut out[..16];
        // SAFETY: `out` holds 16 u32 = 64 bytes, the width of the unaligned store.
        avx!(_mm512_storeu_si512(out.as_mut_ptr().cast(), v.0))
    }
    #[inline(always)]
    fn gather(self, table: &[f32], idx: I32x16) -> F32x16 {
        assert!(!table.is_empty() && table.len() <= i32::MAX as usize, "gather from a table of {} values", table.len());
        let clamped = avx!(_mm512_min_epi32(_mm512_max_epi32(idx.0, _mm512_setzero_si512()), splat_si(table.len() as i32 - 1)));
        // SAFETY: every lane's index lies in [0, table.len() − 1] after the clamp, so each
        // 4-byte load is inside `table`.
        F32x16(avx!(_mm512_i32gather_ps::<4>(clamped, table.as_ptr())))
    }
}

impl F32x16 {
    #[inline(always)]
    fn cmp<const P: i32>(self, o: Self) -> M32x16 {
        M32x16(avx!(_mm512_cmp_ps_mask::<P>(self.0, o.0)))
    }
    /// Lanes that are ±0 or ±∞: applied to an estimate, where a Newton step would turn it into
    /// NaN (exact inputs ±0 and ±∞, and subnormal inputs the estimate treats as zero).
    #[inline(always)]
    fn zero_or_inf(self) -> __mmask16 {
        avx!(_mm512_fpclass_ps_mask::<0x1E>(self.0))
    }
}

impl F32s<Avx512> for F32x16 {
    #[inline(always)]
    fn mul_add(self, a: Self, b: Self) -> Self {
        F32x16(avx!(_mm512_fmadd_ps(self.0, a.0, b.0)))
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        // minps gives its second operand when either is NaN: take `self` where `o` is NaN.
        let r = avx!(_mm512_min_ps(self.0, o.0));
        F32x16(avx!(_mm512_mask_blend_ps(_mm512_cmp_ps_mask::<_CMP_UNORD_Q>(o.0, o.0), r, self.0)))
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        let r = avx!(_mm512_max_ps(self.0, o.0));
        F32x16(avx!(_mm512_mask_blend_ps(_mm512_cmp_ps_mask::<_CMP_UNORD_Q>(o.0, o.0), r, self.0)))
    }
    #[inline(always)]
    fn abs(self) -> Self {
        F32x16(avx!(_mm512_abs_ps(self.0)))
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        F32x16(avx!(_mm512_sqrt_ps(self.0)))
    }
    #[inline(always)]
    fn floor(self) -> Self {
        F32x16(avx!(_mm512_roundscale_ps::<{ _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC }>(self.0)))
    }
    #[inline(always)]
    fn ceil(self) -> Self {
        F32x16(avx!(_mm512_roundscale_ps::<{ _MM_FROUND_TO_POS_INF | _MM_FROUND_NO_EXC }>(self.0)))
    }
    #[inline(always)]
    fn trunc(self) -> Self {
        F32x16(avx!(_mm512_roundscale_ps::<{ _MM_FROUND_TO_ZERO | _MM_FROUND_NO_EXC }>(self.0)))
    }
    #[inline(always)]
    fn round(self) -> Self {
        F32x16(avx!(_mm512_roundscale_ps::<{ _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC }>(self.0)))
    }
    #[inline(always)]
    fn fract(self) -> Self {
        self - self.floor()
    }
    #[inline(always)]
    fn rcp(self) -> Self {
        // rcp14 (relative error < 2⁻¹⁴) and one Newton step.
        let y = avx!(_mm512_rcp14_ps(self.0));
        let e = avx!(_mm512_fnmadd_ps(self.0, y, _mm512_set1_ps(1.0)));
        let r = avx!(_mm512_fmadd_ps(y, e, y));
        F32x16(avx!(_mm512_mask_blend_ps(F32x16(y).zero_or_inf(), r, y)))
    }
    #[inline(always)]
    fn rsqrt(self) -> Self {
        // y₁ = y₀ · (1.5 − (x·y₀)·0.5·y₀), x·y₀ first so that a tiny x does not underflow.
        let y = avx!(_mm512_rsqrt14_ps(self.0));
        let hxy = avx!(_mm512_mul_ps(_mm512_mul_ps(self.0, y), _mm512_set1_ps(0.5)));
        let t = avx!(_mm512_fnmadd_ps(hxy, y, _mm512_set1_ps(1.5)));
        let r = avx!(_mm512_mul_ps(y, t));
        F32x16(avx!(_mm512_mask_blend_ps(F32x16(y).zero_or_inf(), r, y)))
    }
    #[inline(always)]
    fn eq(self, o: Self) -> M32x16 {
        self.cmp::<_CMP_EQ_OQ>(o)
    }
    #[inline(always)]
    fn ne(self, o: Self) -> M32x16 {
        self.cmp::<_CMP_NEQ_UQ>(o)
    }
    #[inline(always)]
    fn lt(self, o: Self) -> M32x16 {
        self.cmp::<_CMP_LT_OQ>(o)
    }
    #[inline(always)]
    fn le(self, o: Self) -> M32x16 {
        self.cmp::<_CMP_LE_OQ>(o)
    }
    #[inline(always)]
    fn gt(self, o: Self) -> M32x16 {
        self.cmp::<_CMP_GT_OQ>(o)
    }
    #[inline(always)]
    fn ge(self, o: Self) -> M32x16 {
        self.cmp::<_CMP_GE_OQ>(o)
    }
    #[inline(always)]
    fn is_nan(self) -> M32x16 {
        self.cmp::<_CMP_UNORD_Q>(self)
    }
    #[inline(always)]
    fn to_i32(self) -> I32x16 {
        // cvttps gives i32::MIN for NaN and out of range: x ≥ 2³¹ → MAX, NaN → 0.
        let r = avx!(_mm512_cvttps_epi32(self.0));
        let big = self.cmp::<_CMP_GE_OQ>(avx!(F32x16(_mm512_set1_ps(2147483648.0))));
        let r = avx!(_mm512_mask_mov_epi32(r, big.0, splat_si(i32::MAX)));
        let ordered = self.cmp::<_CMP_ORD_Q>(self);
        I32x16(avx!(_mm512_maskz_mov_epi32(ordered.0, r)))
    }
    #[inline(always)]
    fn to_u32(self) -> U32x16 {
        // max(x, 0) maps NaN and negatives to 0; cvttps_epu32 gives u32::MAX for x ≥ 2³².
        let x = avx!(_mm512_max_ps(self.0, _mm512_setzero_ps()));
        U32x16(avx!(_mm512_cvttps_epu32(x)))
    }
    #[inline(always)]
    fn to_bits(self) -> U32x16 {
        U32x16(si(self.0))
    }
    #[inline(always)]
    fn write_to(self, out: &mut [f32]) {
        assert_eq!(out.len(), 16);
        Avx512 { _private: () }.store(self, out)
    }
    #[inline(always)]
    fn map(self, f: impl Fn(f32) -> f32) -> Self {
        let mut a = [0f32; 16];
        self.write_to(&mut a);
        Avx512 { _private: () }.load(&a.map(f))
    }
}

impl I32s<Avx512> for I32x16 {
    #[inline(always)]
    fn shl(self, n: Self) -> Self {
        I32x16(avx!(_mm512_sllv_epi32(self.0, _mm512_and_si512(n.0, splat_si(31)))))
    }
    #[inline(always)]
    fn shr(self, n: Self) -> Self {
        I32x16(avx!(_mm512_srav_epi32(self.0, _mm512_and_si512(n.0, splat_si(31)))))
    }
    #[inline(always)]
    fn div(self, d: Self) -> Self {
        I32x16(int_lanes(self.0, d.0, |a, b| a.checked_div(b).unwrap_or(a)))
    }
    #[inline(always)]
    fn rem(self, d: Self) -> Self {
        I32x16(int_lanes(self.0, d.0, |a, b| a.checked_rem(b).unwrap_or(0)))
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        I32x16(avx!(_mm512_min_epi32(self.0, o.0)))
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        I32x16(avx!(_mm512_max_epi32(self.0, o.0)))
    }
    #[inline(always)]
    fn abs(self) -> Self {
        I32x16(avx!(_mm512_abs_epi32(self.0)))
    }
    #[inline(always)]
    fn eq(self, o: Self) -> M32x16 {
        M32x16(avx!(_mm512_cmpeq_epi32_mask(self.0, o.0)))
    }
    #[inline(always)]
    fn lt(self, o: Self) -> M32x16 {
        M32x16(avx!(_mm512_cmplt_epi32_mask(self.0, o.0)))
    }
    #[inline(always)]
    fn gt(self, o: Self) -> M32x16 {
        M32x16(avx!(_mm512_cmpgt_epi32_mask(self.0, o.0)))
    }
    #[inline(always)]
    fn to_f32(self) -> F32x16 {
        F32x16(avx!(_mm512_cvtepi32_ps(self.0)))
    }
    #[inline(always)]
    fn to_u32_bits(self) -> U32x16 {
        U32x16(self.0)
    }
    #[inline(always)]
    fn write_to(self, out: &mut [i32]) {
        assert_eq!(out.len(), 16);
        Avx512 { _private: () }.store_i(self, out)
    }
}

impl U32s<Avx512> for U32x16 {
    #[inline(always)]
    fn shl(self, n: Self) -> Self {
        U32x16(avx!(_mm512_sllv_epi32(self.0, _mm512_and_si512(n.0, splat_si(31)))))
    }
    #[inline(always)]
    fn shr(self, n: Self) -> Self {
        U32x16(avx!(_mm512_srlv_epi32(self.0, _mm512_and_si512(n.0, splat_si(31)))))
    }
    #[inline(always)]
    fn div(self, d: Self) -> Self {
        U32x16(int_lanes(self.0, d.0, |a, b| (a as u32).checked_div(b as u32).unwrap_or(a as u32) as i32))
    }
    #[inline(always)]
    fn rem(self, d: Self) -> Self {
        U32x16(int_lanes(self.0, d.0, |a, b| (a as u32).checked_rem(b as u32).unwrap_or(0) as i32))
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        U32x16(avx!(_mm512_min_epu32(self.0, o.0)))
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        U32x16(avx!(_mm512_max_epu32(self.0, o.0)))
    }
    #[inline(always)]
    fn eq(self, o: Self) -> M32x16 {
        M32x16(avx!(_mm512_cmpeq_epu32_mask(self.0, o.0)))
    }
    #[inline(always)]
    fn lt(self, o: Self) -> M32x16 {
        M32x16(avx!(_mm512_cmplt_epu32_mask(self.0, o.0)))
    }
    #[inline(always)]
    fn gt(self, o: Self) -> M32x16 {
        M32x16(avx!(_mm512_cmpgt_epu32_mask(self.0, o.0)))
    }
    #[inline(always)]
    fn to_f32(self) -> F32x16 {
        F32x16(avx!(_mm512_cvtepu32_ps(self.0)))
    }
    #[inline(always)]
    fn to_f32_bits(self) -> F32x16 {
        F32x16(ps(self.0))
    }
    #[inline(always)]
    fn to_i32_bits(self) -> I32x16 {
        I32x16(self.0)
    }
    #[inline(always)]
    fn write_to(self, out: &mut [u32]) {
        assert_eq!(out.len(), 16);
        Avx512 { _private: () }.store_u(self, out)
    }
}

impl M32s<Avx512> for M32x16 {
    #[inline(always)]
    fn any(self) -> bool {
        self.0 != 0
    }
    #[inline(always)]
    fn all(self) -> bool {
        self.0 == 0xFFFF
    }
    #[inline(always)]
    fn bitmask(self) -> u32 {
        self.0 as u32
    }
    #[inline(always)]
    fn select(self, on: F32x16, off: F32x16) -> F32x16 {
        F32x16(avx!(_mm512_mask_blend_ps(self.0, off.0, on.0)))
    }
    #[inline(always)]
    fn select_i(self, on: I32x16, off: I32x16) -> I32x16 {
        I32x16(avx!(_mm512_mask_blend_epi32(self.0, off.0, on.0)))
    }
    #[inline(always)]
    fn select_u(self, on: U32x16, off: U32x16) -> U32x16 {
        U32x16(avx!(_mm512_mask_blend_epi32(self.0, off.0, on.0)))
    }
}
