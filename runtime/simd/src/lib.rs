//! The packet-SIMD layer (issue 24): the vocabulary the packet Rust writer emits, with WGSL's
//! semantics, on every level a CPU may have.
//!
//! A *level* is a zero-sized token type implementing [`Simd`]: [`Avx512`] (16 lanes),
//! [`Avx2`] (8 lanes, with FMA), and [`Emu<N>`] (N lanes as plain arrays, any machine:
//! `Emu<1>` is the scalar fallback, `Emu<16>` runs the 16-lane logic where AVX-512 is
//! missing). A level's packets — [`Simd::F`] (f32), [`Simd::I`] (i32), [`Simd::U`] (u32) and
//! [`Simd::M`] (a lane mask) — can only be made through its token, and the hardware tokens
//! only by [`Level::dispatch`] after run-time detection: holding a packet proves its
//! instructions exist. That is the whole safety argument of the `unsafe` blocks in `avx2.rs`
//! and `avx512.rs` (intrinsics called from `#[inline(always)]` code that is inlined into the
//! level's `#[target_feature]` entry), plus bounds for the few that take pointers (loads,
//! stores and gathers, each argued where it is). Nothing outside those two files is unsafe.
//!
//! Code is written once, generic over `S: Simd`, as a [`WithSimd`] operation, and run by
//! [`Level::dispatch`], which enters the level's `#[target_feature]` function so that the
//! generic code is compiled for it.
//!
//! **Semantics** (identical on every level; tested against scalar Rust in `tests/ops.rs`):
//! IEEE f32 arithmetic, `sqrt` and `/` correctly rounded; `min`/`max` return the other operand
//! when one is NaN (Rust's `f32::min`); `round` is ties-to-even (WGSL); `fract(x) = x −
//! floor(x)`; float → int conversions saturate and map NaN to 0 (Rust's `as`); integer
//! arithmetic wraps, shifts take the amount modulo 32, `x / 0 = x`, `x % 0 = 0`,
//! `MIN / −1 = MIN`, `MIN % −1 = 0` (WGSL); comparisons with NaN are false except `ne`.
//! `mul_add` is fused on AVX2 and AVX-512 and unfused (`a·b + c`) on `Emu`, so that a scalar
//! build never calls a software `fmaf`. The approximations [`F32s::rcp`] and [`F32s::rsqrt`]
//! are the hardware estimate refined by one Newton–Raphson step: within 2 ulp of `1/x` and
//! `1/√x` for normal finite x (WGSL allows 2.5 ulp for `1/x` and 2 ulp for `inverseSqrt`),
//! exact at ±0 and ±∞; subnormal inputs may be treated as zero (WGSL permits flushing).

#[cfg(target_arch = "x86_64")]
mod avx2;
#[cfg(target_arch = "x86_64")]
mod avx512;
mod emu;
mod level;
mod packets;
pub mod tape;
pub mod vector;

#[cfg(target_arch = "x86_64")]
pub use avx2::{Avx2, F32x8, I32x8, M32x8, U32x8};
#[cfg(target_arch = "x86_64")]
pub use avx512::{Avx512, F32x16, I32x16, M32x16, U32x16};
pub use emu::{Emu, EmuF32, EmuI32, EmuM32, EmuU32};
pub use level::{Level, WithSimd};
pub use packets::{F32s, I32s, M32s, Simd, U32s};
