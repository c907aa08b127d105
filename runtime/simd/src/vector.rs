//! WGSL's vector operations on structure-of-arrays packets: a `vecN<f32>` of a packet kernel is
//! `[S::F; N]` (lane k of component c is point k's component c), and these are the lane-wise
//! operations the packet Rust writer calls on them. Scalar operands are packets (the writer
//! splats uniform ones).

use crate::packets::{F32s, M32s, Simd};

// `map`, `zip` and the functions below loop over the components (LLVM unrolls the constant
// trip count) rather than calling `std::array::from_fn`: through `from_fn`'s iterator adapters a closure with a few
// intrinsics in it was left out of line, compiled without the level's target features, and
// every intrinsic in it became a call (measured: a kernel 2.5× slower).
#[inline(always)]
pub fn map<S: Simd, const N: usize>(a: [S::F; N], f: impl Fn(S::F) -> S::F) -> [S::F; N] {
    let mut out = a;
    for c in 0..N {
        out[c] = f(a[c]);
    }
    out
}

#[inline(always)]
pub fn zip<S: Simd, const N: usize>(a: [S::F; N], b: [S::F; N], f: impl Fn(S::F, S::F) -> S::F) -> [S::F; N] {
    let mut out = a;
    for c in 0..N {
        out[c] = f(a[c], b[c]);
    }
    out
}

#[inline(always)]
pub fn splat<S: Simd, const N: usize>(x: S::F) -> [S::F; N] {
    [x; N]
}

#[inline(always)]
pub fn add<S: Simd, const N: usize>(a: [S::F; N], b: [S::F; N]) -> [S::F; N] {
    zip::<S, N>(a, b, |x, y| x + y)
}

#[inline(always)]
pub fn sub<S: Simd, const N: usize>(a: [S::F; N], b: [S::F; N]) -> [S::F; N] {
    zip::<S, N>(a, b, |x, y| x - y)
}

#[inline(always)]
pub fn mul<S: Simd, const N: usize>(a: [S::F; N], b: [S::F; N]) -> [S::F; N] {
    zip::<S, N>(a, b, |x, y| x * y)
}

#[inline(always)]
pub fn div<S: Simd, const N: usize>(a: [S::F; N], b: [S::F; N]) -> [S::F; N] {
    zip::<S, N>(a, b, |x, y| x / y)
}

#[inline(always)]
pub fn neg<S: Simd, const N: usize>(a: [S::F; N]) -> [S::F; N] {
    map::<S, N>(a, |x| -x)
}

/// Σ aᵢbᵢ in component order, each further term by a fused multiply-add (`F32s::mul_add`,
/// unfused on the emulated levels, as the scalar writer's `dot`).
#[inline(always)]
pub fn dot<S: Simd, const N: usize>(a: [S::F; N], b: [S::F; N]) -> S::F {
    let mut acc = a[0] * b[0];
    for c in 1..N {
        acc = a[c].mul_add(b[c], acc);
    }
    acc
}

#[inline(always)]
pub fn length<S: Simd, const N: usize>(a: [S::F; N]) -> S::F {
    dot::<S, N>(a, a).sqrt()
}

#[inline(always)]
pub fn normalize<S: Simd, const N: usize>(a: [S::F; N]) -> [S::F; N] {
    let l = length::<S, N>(a);
    map::<S, N>(a, |x| x / l)
}

#[inline(always)]
pub fn cross<S: Simd>(a: [S::F; 3], b: [S::F; 3]) -> [S::F; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

/// WGSL `mix(a, b, t) = a·(1 − t) + b·t`, lane-wise, the second product fused.
#[inline(always)]
pub fn mix<S: Simd, const N: usize>(s: S, a: [S::F; N], b: [S::F; N], t: [S::F; N]) -> [S::F; N] {
    let one = s.splat(1.0);
    let mut out = a;
    for c in 0..N {
        out[c] = b[c].mul_add(t[c], a[c] * (one - t[c]));
    }
    out
}

/// Component-wise `select(off, on, m)` with one mask per component.
#[inline(always)]
pub fn select<S: Simd, const N: usize>(m: [S::M; N], on: [S::F; N], off: [S::F; N]) -> [S::F; N] {
    let mut out = off;
    for c in 0..N {
        out[c] = m[c].select(on[c], off[c]);
    }
    out
}

/// `select` with one mask for every component.
#[inline(always)]
pub fn select_all<S: Simd, const N: usize>(m: S::M, on: [S::F; N], off: [S::F; N]) -> [S::F; N] {
    zip::<S, N>(on, off, |x, y| m.select(x, y))
}
