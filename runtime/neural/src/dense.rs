//! Fused f32 dense-layer kernels for the networks' narrow layers (≤ 64 wide), on AVX-512:
//! `y = epilogue(x · M + bias)` for a block of rows, where M (k × n) is the layer's weights laid
//! out with its output columns contiguous and padded to whole 16-lane vectors. The weights stay
//! in L1, a block of rows × n accumulators stays in registers, the rows are read in place (no
//! packing, unlike a general GEMM) and the bias and activation are applied before the single
//! store. The forward pass uses M = Wᵀ (k = inputs); the input gradient uses M = W (k = outputs)
//! with the previous layer's LeakyReLU derivative as the epilogue.
//!
//! [`available`] says whether this CPU runs them; callers fall back to the GEMM path
//! (`mlp.rs`) otherwise, and the tests compare the two.

/// What is applied to `x · M + bias` before it is stored.
#[derive(Clone, Copy, Debug)]
pub enum Epilogue<'a> {
    None,
    /// max(v, slope·v) (0 ≤ slope ≤ 1).
    LeakyRelu { slope: f32 },
    /// exp(min(v, clamp) − shift), the decoder's output head (a degree-6 polynomial for e^r on
    /// |r| ≤ ln 2 / 2 and an exact power of two: relative error ≤ 2·10⁻⁷; NaN stays NaN).
    ExpHead { shift: f32, clamp: f32 },
    /// v · (a > 0 ? 1 : slope): the gradient through a LeakyReLU whose outputs are the rows of
    /// `a` (same shape as the result).
    LeakyReluGradient { slope: f32, a: &'a [f32] },
}

/// Whether this CPU runs the fused kernels.
pub fn available() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::is_x86_feature_detected!("avx512f")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// Lanes per vector.
const LANES: usize = 16;

/// The widest layer the kernels take (four vectors of accumulators per row).
pub const MAX_WIDTH: usize = 4 * LANES;

/// `n` rounded up to whole vectors.
pub fn padded(n: usize) -> usize {
    n.div_ceil(LANES) * LANES
}

/// Lays out M (k × n, element (i, j) = `at(i, j)`) with rows padded to whole vectors, zeros in
/// the padding, into `out`.
pub fn pack(k: usize, n: usize, at: impl Fn(usize, usize) -> f32, out: &mut Vec<f32>) {
    let np = padded(n);
    out.clear();
    out.resize(k * np, 0.0);
    for i in 0..k {
        for j in 0..n {
            out[i * np + j] = at(i, j);
        }
    }
}

/// A network's layers packed for the forward pass (M = Wᵀ) and the input gradient (M = W),
/// remembered with the parameters they came from, so a frozen network is packed once.
#[derive(Default)]
pub struct PackedNetwork {
    source: Vec<u32>,
    forward: Vec<Vec<f32>>,
    backward: Vec<Vec<f32>>,
}

impl PackedNetwork {
    /// Packs the layers — (inputs, outputs, weights row-major outputs × inputs) — of the network
    /// whose flat parameters are `params`, unless they are bit for bit those of the last call.
    /// A layer wider than [`MAX_WIDTH`] on the side a kernel produces gets an empty matrix.
    pub fn update<'a>(&mut self, params: &[f32], layers: impl Iterator<Item = (usize, usize, &'a [f32])>) {
        let bits: &[u32] = bytemuck::cast_slice(params);
        if self.source == bits {
            return;
        }
        self.source.clear();
        self.source.extend_from_slice(bits);
        self.forward.clear();
        self.backward.clear();
        for (n_in, n_out, w) in layers {
            let mut f = Vec::new();
            if n_out <= MAX_WIDTH {
                pack(n_in, n_out, |i, j| w[j * n_in + i], &mut f);
            }
            let mut b = Vec::new();
            if n_in <= MAX_WIDTH {
                pack(n_out, n_in, |i, j| w[i * n_in + j], &mut b);
            }
            self.forward.push(f);
            self.backward.push(b);
        }
    }

    /// Layer `l`'s Wᵀ (inputs × padded outputs).
    pub fn forward(&self, l: usize) -> &[f32] {
        &self.forward[l]
    }

    /// Layer `l`'s W (outputs × padded inputs).
    pub fn backward(&self, l: usize) -> &[f32] {
        &self.backward[l]
    }
}

/// y (rows × n) = epilogue(x (rows × k) · M + bias), M packed by [`pack`]; `bias` is n long or
/// empty (zero). Panics when the shapes disagree or n > [`MAX_WIDTH`]; must only be called
/// when [`available`].
#[allow(clippy::too_many_arguments)]
pub fn dense(x: &[f32], rows: usize, k: usize, m: &[f32], n: usize, bias: &[f32], epilogue: Epilogue<'_>, y: &mut [f32]) {
    assert!(available(), "the fused dense kernels need AVX-512");
    assert!(n > 0 && n <= MAX_WIDTH, "layer width {n} is not in 1..={MAX_WIDTH}");
    assert_eq!(x.len(), rows * k, "input rows");
    assert_eq!(y.len(), rows * n, "output rows");
    assert_eq!(m.len(), k * padded(n), "packed weights");
    assert!(bias.is_empty() || bias.len() == n, "bias length");
    if let Epilogue::LeakyReluGradient { a, .. } = epilogue {
        assert_eq!(a.len(), rows * n, "activation rows");
    }
    #[cfg(target_arch = "x86_64")]
    {
        let mut b = [0.0f32; MAX_WIDTH];
        b[..bias.len()].copy_from_slice(bias);
        // SAFETY: AVX-512F is present (asserted), and every pointer the kernels form lies in
        // its slice: x rows × k, m k × padded(n), y and a rows × n with masked access beyond n.
        unsafe {
            match padded(n) / LANES {
                1 => avx512::rows::<1, 12>(x, rows, k, m, n, &b, epilogue, y),
                2 => avx512::rows::<2, 8>(x, rows, k, m, n, &b, epilogue, y),
                3 => avx512::rows::<3, 6>(x, rows, k, m, n, &b, epilogue, y),
                _ => avx512::rows::<4, 6>(x, rows, k, m, n, &b, epilogue, y),
            }
        }
    }
}

/// One core's fp32 peak in FLOP/s, measured: twelve independent chains of AVX-512 fused
/// multiply–adds held in registers, for about `seconds` (the best of ten windows, so a
/// neighbour's burst on a shared machine does not lower it). `None` without AVX-512.
pub fn fma_peak(seconds: f64) -> Option<f64> {
    if !available() {
        return None;
    }
    #[cfg(target_arch = "x86_64")]
    {
        let mut best = 0.0f64;
        let mut sink = 0.0f32;
        for _ in 0..10 {
            let start = std::time::Instant::now();
            let mut rounds = 0u64;
            while start.elapsed().as_secs_f64() < seconds / 10.0 {
                // SAFETY: AVX-512F is present (checked above).
                sink += unsafe { avx512::fma_chains(1 << 16) };
                rounds += 1;
            }
            // 12 chains × 16 lanes × 2 FLOP per round of the inner loop.
            best = best.max((rounds << 16) as f64 * 12.0 * 16.0 * 2.0 / start.elapsed().as_secs_f64());
        }
        std::hint::black_box(sink);
        Some(best)
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        None
    }
}

#[cfg(target_arch = "x86_64")]
mod avx512 {
    use super::{Epilogue, LANES};
    use std::arch::x86_64::*;

    /// e^x for every lane: 2ⁿ·e^r with n = round(x·log₂e), r = x − n·ln 2 (ln 2 in two parts),
    /// e^r by its Taylor polynomial of degree 6 (truncation ≤ 1.2·10⁻⁷ relative on |r| ≤ 0.347).
    /// x is first held to [−104, 89] (e^x is 0 or ∞ in f32 beyond), with NaN passed through.
    #[target_feature(enable = "avx512f")]
    #[inline]
    unsafe fn exp(x: __m512) -> __m512 {
        // MAXPS/MINPS return their second operand when either is NaN: x goes second.
        let x = _mm512_min_ps(_mm512_set1_ps(89.0), _mm512_max_ps(_mm512_set1_ps(-104.0), x));
        let n = _mm512_roundscale_ps::<{ _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC }>(_mm512_mul_ps(x, _mm512_set1_ps(std::f32::consts::LOG2_E)));
        let r = _mm512_fnmadd_ps(n, _mm512_set1_ps(0.693_359_4), x);
        let r = _mm512_fnmadd_ps(n, _mm512_set1_ps(-2.121_944_4e-4), r);
        let mut p = _mm512_set1_ps(1.0 / 720.0);
        for c in [1.0 / 120.0, 1.0 / 24.0, 1.0 / 6.0, 0.5, 1.0, 1.0] {
            p = _mm512_fmadd_ps(p, r, _mm512_set1_ps(c));
        }
        _mm512_scalef_ps(p, n)
    }

    /// `rounds` × 12 independent FMAs (the peak measurement); returns a lane so the work is kept.
    #[target_feature(enable = "avx512f")]
    pub unsafe fn fma_chains(rounds: u64) -> f32 {
        let (a, b) = (_mm512_set1_ps(0.999_99), _mm512_set1_ps(1e-6));
        let mut acc = [_mm512_set1_ps(1.0); 12];
        for _ in 0..rounds {
            for c in acc.iter_mut() {
                *c = _mm512_fmadd_ps(*c, a, b);
            }
        }
        acc.iter().fold(0.0, |s, c| s + _mm512_reduce_add_ps(*c))
    }

    /// All rows: blocks of `R` rows, then the rest one at a time.
    #[target_feature(enable = "avx512f")]
    #[allow(clippy::too_many_arguments)]
    pub unsafe fn rows<const V: usize, const R: usize>(x: &[f32], rows: usize, k: usize, m: &[f32], n: usize, bias: &[f32], epilogue: Epilogue<'_>, y: &mut [f32]) {
        let mut r = 0;
        while r + R <= rows {
            block::<V, R>(x.as_ptr().add(r * k), k, m.as_ptr(), n, bias.as_ptr(), epilogue, r, y.as_mut_ptr().add(r * n));
            r += R;
        }
        while r < rows {
            block::<V, 1>(x.as_ptr().add(r * k), k, m.as_ptr(), n, bias.as_ptr(), epilogue, r, y.as_mut_ptr().add(r * n));
            r += 1;
        }
    }

    /// `R` rows starting at row `row`: R × V vectors of accumulators.
    #[target_feature(enable = "avx512f")]
    #[inline]
    #[allow(clippy::too_many_arguments)]
    unsafe fn block<const V: usize, const R: usize>(x: *const f32, k: usize, m: *const f32, n: usize, bias: *const f32, epilogue: Epilogue<'_>, row: usize, y: *mut f32) {
        let stride = V * LANES;
        let mut acc = [[_mm512_setzero_ps(); V]; R];
        for v in 0..V {
            let b = _mm512_loadu_ps(bias.add(v * LANES));
            for a in acc.iter_mut() {
                a[v] = b;
            }
        }
        for i in 0..k {
            let mut w = [_mm512_setzero_ps(); V];
            for (v, wv) in w.iter_mut().enumerate() {
                *wv = _mm512_loadu_ps(m.add(i * stride + v * LANES));
            }
            for (r, a) in acc.iter_mut().enumerate() {
                let xb = _mm512_set1_ps(*x.add(r * k + i));
                for v in 0..V {
                    a[v] = _mm512_fmadd_ps(xb, w[v], a[v]);
                }
            }
        }
        for (r, a) in acc.iter().enumerate() {
            for (v, &value) in a.iter().enumerate() {
                let first = v * LANES;
                let mask: __mmask16 = if first + LANES <= n { 0xffff } else { ((1u32 << (n - first)) - 1) as __mmask16 };
                let out = match epilogue {
                    Epilogue::None => value,
                    Epilogue::LeakyRelu { slope } => _mm512_max_ps(value, _mm512_mul_ps(value, _mm512_set1_ps(slope))),
                    Epilogue::ExpHead { shift, clamp } => exp(_mm512_sub_ps(_mm512_min_ps(_mm512_set1_ps(clamp), value), _mm512_set1_ps(shift))),
                    Epilogue::LeakyReluGradient { slope, a } => {
                        let act = _mm512_maskz_loadu_ps(mask, a.as_ptr().add((row + r) * n + first));
                        let positive = _mm512_cmp_ps_mask::<_CMP_GT_OQ>(act, _mm512_setzero_ps());
                        _mm512_mask_mov_ps(_mm512_mul_ps(value, _mm512_set1_ps(slope)), positive, value)
                    }
                };
                _mm512_mask_storeu_ps(y.add(r * n + first), mask, out);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lcg(state: &mut u64) -> f32 {
        *state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((*state >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0
    }

    /// e^x over f32's range against f64, and its limits.
    #[test]
    fn vector_exp_is_accurate() {
        if !available() {
            eprintln!("NOT TESTED HERE: vector_exp_is_accurate needs AVX-512F, which this CPU lacks; the fused kernels are untested on this machine (the GEMM path runs instead)");
            return;
        }
        let mut worst = 0.0f64;
        let mut x = -87.0f32;
        while x < 88.0 {
            let xs: Vec<f32> = (0..16).map(|k| x + k as f32 * 1e-3).collect();
            let mut y = vec![0.0f32; 16];
            // exp(min(v, 100) − 0) = e^v through the epilogue, with M = 1 (k = 1).
            dense(&xs, 16, 1, &{ let mut m = Vec::new(); pack(1, 1, |_, _| 1.0, &mut m); m }, 1, &[], Epilogue::ExpHead { shift: 0.0, clamp: 100.0 }, &mut y);
            for (a, b) in xs.iter().zip(&y) {
                let want = (*a as f64).exp();
                worst = worst.max(((*b as f64) - want).abs() / want);
            }
            x += 0.37;
        }
        assert!(worst < 4e-7, "worst relative error {worst}");
        let xs = [f32::NAN, -1e6, 1e6, 0.0];
        let mut y = [0.0f32; 4];
        let mut m = Vec::new();
        pack(1, 1, |_, _| 1.0, &mut m);
        dense(&xs, 4, 1, &m, 1, &[], Epilogue::ExpHead { shift: 0.0, clamp: f32::INFINITY }, &mut y);
        assert!(y[0].is_nan() && y[1] == 0.0 && y[2] == f32::INFINITY && y[3] == 1.0, "{y:?}");
    }

    /// Every width 1..=64, row counts that leave tails, each epilogue: against an f64 loop.
    #[test]
    fn fused_kernel_matches_a_plain_loop() {
        if !available() {
            eprintln!("NOT TESTED HERE: fused_kernel_matches_a_plain_loop needs AVX-512F, which this CPU lacks; the fused kernels are untested on this machine (the GEMM path runs instead)");
            return;
        }
        let mut s = 7u64;
        for n in 1..=MAX_WIDTH {
            for (k, rows) in [(15, 13), (64, 7), (7, 30)] {
                let x: Vec<f32> = (0..rows * k).map(|_| lcg(&mut s)).collect();
                let w: Vec<f32> = (0..k * n).map(|_| lcg(&mut s)).collect();
                let bias: Vec<f32> = (0..n).map(|_| lcg(&mut s)).collect();
                let a: Vec<f32> = (0..rows * n).map(|_| lcg(&mut s)).collect();
                let mut m = Vec::new();
                pack(k, n, |i, j| w[i * n + j], &mut m);
                for e in 0..4 {
                    let epilogue = match e {
                        0 => Epilogue::None,
                        1 => Epilogue::LeakyRelu { slope: 0.01 },
                        2 => Epilogue::LeakyReluGradient { slope: 0.01, a: &a },
                        _ => Epilogue::ExpHead { shift: 3.0, clamp: 1.5 },
                    };
                    let b: &[f32] = if e == 2 { &[] } else { &bias };
                    let mut y = vec![f32::NAN; rows * n];
                    dense(&x, rows, k, &m, n, b, epilogue, &mut y);
                    for r in 0..rows {
                        for j in 0..n {
                            let mut v = b.get(j).map_or(0.0, |b| *b as f64);
                            for i in 0..k {
                                v += x[r * k + i] as f64 * w[i * n + j] as f64;
                            }
                            let want = match e {
                                0 => v,
                                1 => v.max(0.01 * v),
                                2 => v * if a[r * n + j] > 0.0 { 1.0 } else { 0.01 },
                                _ => (v.min(1.5) - 3.0).exp(),
                            };
                            let got = y[r * n + j] as f64;
                            let error = if e == 3 { (got - want).abs() / want } else { (got - want).abs() / (1.0 + want.abs()) };
                            assert!(error <= 1e-5, "n {n} k {k} row {r} col {j} epilogue {e}: {got} vs {want}");
                        }
                    }
                }
            }
        }
    }
}
