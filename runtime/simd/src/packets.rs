//! The traits every level implements: [`Simd`] (the token: constructors, loads, stores,
//! gathers) and the packet types' operations [`F32s`], [`I32s`], [`U32s`], [`M32s`].
//! Arithmetic and bitwise operators are the `std::ops` traits, so generated code reads
//! `a * b + c`; everything else is a method.

use std::fmt::Debug;
use std::ops::{Add, BitAnd, BitOr, BitXor, Div, Mul, Neg, Not, Sub};

/// A SIMD level: a zero-sized token whose existence proves its instructions are available.
pub trait Simd: Copy + Send + Sync + Debug + 'static {
    /// Lanes per packet.
    const LANES: usize;
    /// The level's name (`avx512`, `avx2`, `emu16`, …).
    const NAME: &'static str;
    type F: F32s<Self>;
    type I: I32s<Self>;
    type U: U32s<Self>;
    type M: M32s<Self>;

    /// Runs `f` (an `#[inline(always)]` closure) in a function of its own compiled for this
    /// level, instead of inlined into its caller: the packet writer outlines the large parts of
    /// a kernel (its lobes) so that each is compiled once, not once per call site, and no
    /// function grows so large that LLVM's optimisation time explodes (a kernel is otherwise
    /// one function per level). `Emu` levels just call `f`.
    fn outline<R>(self, f: impl FnOnce() -> R) -> R;

    fn splat(self, x: f32) -> Self::F;
    fn splat_i(self, x: i32) -> Self::I;
    fn splat_u(self, x: u32) -> Self::U;
    /// The mask whose first `n` lanes are on (all lanes for `n ≥ LANES`).
    fn first_lanes(self, n: usize) -> Self::M;
    /// Lane indices 0, 1, …, LANES − 1.
    fn lane_index(self) -> Self::I;

    /// The first `LANES` values of `s` (panics if it is shorter).
    fn load(self, s: &[f32]) -> Self::F;
    /// `s` (shorter than a packet, or not) in the first lanes, zero in the rest.
    fn load_partial(self, s: &[f32]) -> Self::F;
    fn load_i(self, s: &[i32]) -> Self::I;
    fn load_u(self, s: &[u32]) -> Self::U;
    /// Writes all lanes to the first `LANES` values of `out` (panics if it is shorter).
    fn store(self, v: Self::F, out: &mut [f32]);
    /// Writes the first `min(out.len(), LANES)` lanes.
    fn store_partial(self, v: Self::F, out: &mut [f32]);
    fn store_i(self, v: Self::I, out: &mut [i32]);
    fn store_u(self, v: Self::U, out: &mut [u32]);

    /// `table[clamp(idx, 0, len − 1)]` per lane (panics on an empty table or one longer than
    /// `i32::MAX`): the clamp makes every lane's load in bounds, whatever its index.
    fn gather(self, table: &[f32], idx: Self::I) -> Self::F;
}

/// A packet of f32 lanes.
pub trait F32s<S: Simd>:
    Copy + Debug + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self> + Neg<Output = Self>
{
    /// `self · a + b`, fused where the level has FMA (module doc).
    fn mul_add(self, a: Self, b: Self) -> Self;
    fn min(self, o: Self) -> Self;
    fn max(self, o: Self) -> Self;
    fn abs(self) -> Self;
    fn sqrt(self) -> Self;
    fn floor(self) -> Self;
    fn ceil(self) -> Self;
    fn trunc(self) -> Self;
    /// Round half to even (WGSL `round`).
    fn round(self) -> Self;
    /// `self − floor(self)` (WGSL `fract`).
    fn fract(self) -> Self;
    /// `1/x` to 2 ulp (module doc).
    fn rcp(self) -> Self;
    /// `1/√x` to 2 ulp (module doc).
    fn rsqrt(self) -> Self;

    fn eq(self, o: Self) -> S::M;
    /// True where either is NaN.
    fn ne(self, o: Self) -> S::M;
    fn lt(self, o: Self) -> S::M;
    fn le(self, o: Self) -> S::M;
    fn gt(self, o: Self) -> S::M;
    fn ge(self, o: Self) -> S::M;
    fn is_nan(self) -> S::M;

    /// Saturating conversion, NaN → 0 (Rust's `as i32`).
    fn to_i32(self) -> S::I;
    /// Saturating conversion, NaN and negatives → 0 (Rust's `as u32`).
    fn to_u32(self) -> S::U;
    /// The bits (WGSL `bitcast<u32>`).
    fn to_bits(self) -> S::U;

    /// The lanes, in order (`out.len()` must be `LANES`).
    fn write_to(self, out: &mut [f32]);
    /// Applies `f` to every lane (the scalar fallback for operations the level lacks).
    fn map(self, f: impl Fn(f32) -> f32) -> Self;
}

/// A packet of i32 lanes (wrapping arithmetic, WGSL shifts and division).
pub trait I32s<S: Simd>:
    Copy
    + Debug
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Neg<Output = Self>
    + BitAnd<Output = Self>
    + BitOr<Output = Self>
    + BitXor<Output = Self>
    + Not<Output = Self>
{
    /// `self << (n mod 32)` per lane.
    fn shl(self, n: Self) -> Self;
    /// Arithmetic `self >> (n mod 32)` per lane.
    fn shr(self, n: Self) -> Self;
    /// `self / d`, with `x / 0 = x` and `MIN / −1 = MIN`.
    fn div(self, d: Self) -> Self;
    /// `self % d`, with `x % 0 = 0` and `MIN % −1 = 0`.
    fn rem(self, d: Self) -> Self;
    fn min(self, o: Self) -> Self;
    fn max(self, o: Self) -> Self;
    /// Wrapping absolute value (`MIN` stays `MIN`).
    fn abs(self) -> Self;
    fn eq(self, o: Self) -> S::M;
    fn lt(self, o: Self) -> S::M;
    fn gt(self, o: Self) -> S::M;
    fn to_f32(self) -> S::F;
    fn to_u32_bits(self) -> S::U;
    fn write_to(self, out: &mut [i32]);
}

/// A packet of u32 lanes.
pub trait U32s<S: Simd>:
    Copy
    + Debug
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + BitAnd<Output = Self>
    + BitOr<Output = Self>
    + BitXor<Output = Self>
    + Not<Output = Self>
{
    /// `self << (n mod 32)` per lane.
    fn shl(self, n: Self) -> Self;
    /// Logical `self >> (n mod 32)` per lane.
    fn shr(self, n: Self) -> Self;
    /// `self / d`, with `x / 0 = x`.
    fn div(self, d: Self) -> Self;
    /// `self % d`, with `x % 0 = 0`.
    fn rem(self, d: Self) -> Self;
    fn min(self, o: Self) -> Self;
    fn max(self, o: Self) -> Self;
    fn eq(self, o: Self) -> S::M;
    fn lt(self, o: Self) -> S::M;
    fn gt(self, o: Self) -> S::M;
    /// Correctly rounded conversion.
    fn to_f32(self) -> S::F;
    /// The f32 with these bits (WGSL `bitcast<f32>`).
    fn to_f32_bits(self) -> S::F;
    fn to_i32_bits(self) -> S::I;
    fn write_to(self, out: &mut [u32]);
}

/// A lane mask: the result of comparisons, the condition of selects, the active lanes of
/// masked control flow.
pub trait M32s<S: Simd>: Copy + Debug + BitAnd<Output = Self> + BitOr<Output = Self> + BitXor<Output = Self> + Not<Output = Self> {
    /// Some lane is on.
    fn any(self) -> bool;
    /// Every lane is on.
    fn all(self) -> bool;
    /// Lane k on ⇔ bit k set.
    fn bitmask(self) -> u32;
    /// `on` where the lane is on, else `off`.
    fn select(self, on: S::F, off: S::F) -> S::F;
    fn select_i(self, on: S::I, off: S::I) -> S::I;
    fn select_u(self, on: S::U, off: S::U) -> S::U;
}
