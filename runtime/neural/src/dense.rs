//! Fused f32 dense-layer kernels for the networks' narrow layers (≤ 64 wide), on AVX-512 (16
//! lanes) and on AVX2 with FMA (8 lanes): `y = epilogue(x · M + bias)` for a block of rows,
//! where M (k × n) is the layer's weights laid out with its output columns contiguous and padded
//! to whole 16-lane vectors (one layout for both). The weights stay in L1, a block of rows × n
//! accumulators stays in registers (on AVX2, with its 16 registers, in panels of 32 columns), the
//! rows are read in place (no packing, unlike a general GEMM) and the bias and activation are
//! applied before the single store. The forward pass uses M = Wᵀ (k = inputs); the input
//! gradient uses M = W (k = outputs) with the previous layer's LeakyReLU derivative as the
//! epilogue. The weight gradient dW (outputs × inputs) += dzᵀ · x ([`weight_gradient`]) keeps a
//! block of dW in registers while the batch rows stream by, as sums of outer products.
//!
//! [`isa`] says which kernels this CPU runs (the widest it has; `UPLIFT_DENSE=avx2|avx512|gemm`
//! chooses, so an AVX-512 machine can measure the AVX2 kernels); callers fall back to the GEMM
//! path (`mlp.rs`) without one, and the tests compare the kernels with a plain loop and the two
//! paths with each other.

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

/// An instruction set the fused kernels are written for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Isa {
    /// AVX-512F: 16 lanes, 32 registers, masked loads and stores.
    Avx512,
    /// AVX2 with FMA: 8 lanes, 16 registers.
    Avx2,
}

impl Isa {
    /// Whether this CPU has it.
    pub fn supported(self) -> bool {
        #[cfg(target_arch = "x86_64")]
        {
            match self {
                Isa::Avx512 => std::is_x86_feature_detected!("avx512f"),
                Isa::Avx2 => std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("fma"),
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            false
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Isa::Avx512 => "AVX-512",
            Isa::Avx2 => "AVX2",
        }
    }
}

/// The kernels this process uses: `UPLIFT_DENSE` (`avx512`, `avx2`, or `gemm` for none) when set
/// and supported, else the widest this CPU has. Decided once.
pub fn isa() -> Option<Isa> {
    static CHOICE: std::sync::OnceLock<Option<Isa>> = std::sync::OnceLock::new();
    *CHOICE.get_or_init(|| {
        let widest = [Isa::Avx512, Isa::Avx2].into_iter().find(|i| i.supported());
        match std::env::var("UPLIFT_DENSE").as_deref() {
            Ok("gemm") => None,
            Ok("avx2") if Isa::Avx2.supported() => Some(Isa::Avx2),
            Ok("avx512") if Isa::Avx512.supported() => Some(Isa::Avx512),
            _ => widest,
        }
    })
}

/// Whether this process runs the fused kernels.
pub fn available() -> bool {
    isa().is_some()
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
/// empty (zero), on [`isa`]'s kernels. Panics when the shapes disagree or n > [`MAX_WIDTH`];
/// must only be called when [`available`].
#[allow(clippy::too_many_arguments)]
pub fn dense(x: &[f32], rows: usize, k: usize, m: &[f32], n: usize, bias: &[f32], epilogue: Epilogue<'_>, y: &mut [f32]) {
    dense_on(isa().expect("the fused dense kernels need AVX-512 or AVX2"), x, rows, k, m, n, bias, epilogue, y);
}

/// [`dense`] on the kernels of `isa` (which this CPU must support).
#[allow(clippy::too_many_arguments)]
pub fn dense_on(isa: Isa, x: &[f32], rows: usize, k: usize, m: &[f32], n: usize, bias: &[f32], epilogue: Epilogue<'_>, y: &mut [f32]) {
    assert!(isa.supported(), "this CPU lacks {}", isa.name());
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
        // SAFETY: the ISA is present (asserted), and every pointer the kernels form lies in
        // its slice: x rows × k, m k × padded(n), y and a rows × n with masked access beyond n.
        unsafe {
            match isa {
                Isa::Avx512 => match padded(n) / LANES {
                    1 => avx512::rows::<1, 12>(x, rows, k, m, n, &b, epilogue, y),
                    2 => avx512::rows::<2, 8>(x, rows, k, m, n, &b, epilogue, y),
                    3 => avx512::rows::<3, 6>(x, rows, k, m, n, &b, epilogue, y),
                    _ => avx512::rows::<4, 6>(x, rows, k, m, n, &b, epilogue, y),
                },
                Isa::Avx2 => avx2::dense(x, rows, k, m, n, &b, epilogue, y),
            }
        }
    }
}

/// dW (n_out × n_in, row-major) += dzᵀ · x for `rows` rows of dz (rows × n_out) and x
/// (rows × n_in), n_in ≤ [`MAX_WIDTH`], on `isa`'s kernels: a block of dW's rows × its columns
/// stays in registers while the batch rows stream by (per row, x's row as vectors and dz's
/// entries broadcast: outer products, no transposes), then is added to dW once.
pub fn weight_gradient(isa: Isa, dz: &[f32], x: &[f32], rows: usize, n_out: usize, n_in: usize, dw: &mut [f32]) {
    assert!(isa.supported(), "this CPU lacks {}", isa.name());
    assert!(n_in > 0 && n_in <= MAX_WIDTH, "layer input width {n_in} is not in 1..={MAX_WIDTH}");
    assert_eq!((dz.len(), x.len(), dw.len()), (rows * n_out, rows * n_in, n_out * n_in), "weight-gradient shapes");
    #[cfg(target_arch = "x86_64")]
    // SAFETY: the ISA is present (asserted); the kernels read dz and x and write dw within
    // their shapes (asserted), with masked access beyond n_in.
    unsafe {
        let (dz, x, dw) = (dz.as_ptr(), x.as_ptr(), dw.as_mut_ptr());
        match isa {
            Isa::Avx512 => match n_in.div_ceil(LANES) {
                1 => avx512::outer::<1, 16>(dz, x, rows, n_out, n_in, dw),
                2 => avx512::outer::<2, 12>(dz, x, rows, n_out, n_in, dw),
                3 => avx512::outer::<3, 8>(dz, x, rows, n_out, n_in, dw),
                _ => avx512::outer::<4, 6>(dz, x, rows, n_out, n_in, dw),
            },
            Isa::Avx2 => avx2::weight_gradient(dz, x, rows, n_out, n_in, dw),
        }
    }
}

/// One core's fp32 peak in FLOP/s on [`isa`]'s vectors, measured: twelve independent chains
/// of fused multiply–adds held in registers, for about `seconds` (the best of ten windows, so a
/// neighbour's burst on a shared machine does not lower it). `None` without fused kernels.
pub fn fma_peak(seconds: f64) -> Option<f64> {
    let isa = isa()?;
    #[cfg(target_arch = "x86_64")]
    {
        let mut best = 0.0f64;
        let mut sink = 0.0f32;
        let lanes = if isa == Isa::Avx512 { 16.0 } else { 8.0 };
        for _ in 0..10 {
            let start = std::time::Instant::now();
            let mut rounds = 0u64;
            while start.elapsed().as_secs_f64() < seconds / 10.0 {
                // SAFETY: the ISA is present (`isa` checks).
                sink += unsafe {
                    match isa {
                        Isa::Avx512 => avx512::fma_chains(1 << 16),
                        Isa::Avx2 => avx2::fma_chains(1 << 16),
                    }
                };
                rounds += 1;
            }
            // 12 chains × lanes × 2 FLOP per round of the inner loop.
            best = best.max((rounds << 16) as f64 * 12.0 * lanes * 2.0 / start.elapsed().as_secs_f64());
        }
        std::hint::black_box(sink);
        Some(best)
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let _ = isa;
        None
    }
}

#[cfg(target_arch = "x86_64")]
mod avx2 {
    use super::{padded, Epilogue};
    use std::arch::x86_64::*;

    /// Lanes per vector.
    const LANES: usize = 8;

    /// Columns per panel: the whole layer (up to 8 vectors; a block of one row then holds 8
    /// accumulators; measured faster than 32-column panels of 3 rows).
    const PANEL: usize = 64;

    /// e^x for every lane, as the AVX-512 kernel's (the same polynomial and range reduction);
    /// 2ⁿ (n in [−150, 128]) as the product of two powers of two built in the exponent field,
    /// each within the normal range. NaN stays NaN.
    #[target_feature(enable = "avx2,fma")]
    #[inline]
    unsafe fn exp(x: __m256) -> __m256 {
        // MAXPS/MINPS return their second operand when either is NaN: x goes second.
        let x = _mm256_min_ps(_mm256_set1_ps(89.0), _mm256_max_ps(_mm256_set1_ps(-104.0), x));
        let n = _mm256_round_ps::<{ _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC }>(_mm256_mul_ps(x, _mm256_set1_ps(std::f32::consts::LOG2_E)));
        let r = _mm256_fnmadd_ps(n, _mm256_set1_ps(0.693_359_4), x);
        let r = _mm256_fnmadd_ps(n, _mm256_set1_ps(-2.121_944_4e-4), r);
        let mut p = _mm256_set1_ps(1.0 / 720.0);
        for c in [1.0 / 120.0, 1.0 / 24.0, 1.0 / 6.0, 0.5, 1.0, 1.0] {
            p = _mm256_fmadd_ps(p, r, _mm256_set1_ps(c));
        }
        let ni = _mm256_cvtps_epi32(n);
        let half = _mm256_srai_epi32::<1>(ni);
        let rest = _mm256_sub_epi32(ni, half);
        let bias = _mm256_set1_epi32(127);
        let two_to = |e: __m256i| _mm256_castsi256_ps(_mm256_slli_epi32::<23>(_mm256_add_epi32(e, bias)));
        _mm256_mul_ps(_mm256_mul_ps(p, two_to(half)), two_to(rest))
    }

    /// `rounds` × 12 independent FMAs (the peak measurement); returns a lane so the work is kept.
    #[target_feature(enable = "avx2,fma")]
    pub unsafe fn fma_chains(rounds: u64) -> f32 {
        // Opaque operands and trip count: the chains cannot be folded at compile time.
        let (a, b) = (_mm256_set1_ps(std::hint::black_box(0.999_99)), _mm256_set1_ps(std::hint::black_box(1e-6)));
        let mut acc = [_mm256_set1_ps(std::hint::black_box(1.0)); 12];
        for _ in 0..std::hint::black_box(rounds) {
            for c in acc.iter_mut() {
                *c = _mm256_fmadd_ps(*c, a, b);
            }
        }
        let mut lanes = [0.0f32; 8];
        let sum = acc.iter().fold(_mm256_setzero_ps(), |s, c| _mm256_add_ps(s, *c));
        _mm256_storeu_ps(lanes.as_mut_ptr(), sum);
        lanes.iter().sum()
    }

    /// All rows, panel by panel of [`PANEL`] columns.
    #[target_feature(enable = "avx2,fma")]
    #[allow(clippy::too_many_arguments)]
    pub unsafe fn dense(x: &[f32], rows: usize, k: usize, m: &[f32], n: usize, bias: &[f32], epilogue: Epilogue<'_>, y: &mut [f32]) {
        let stride = padded(n);
        let mut c0 = 0;
        while c0 < n {
            let p = Panel { stride, n, c0, cols: (n - c0).min(PANEL) };
            // A panel's vectors stay within the padded row (its columns rounded up to 8 ≤ padded(n)).
            match p.cols.div_ceil(LANES) {
                1 => panel::<1, 12>(x, rows, k, m, bias, epilogue, &p, y),
                2 => panel::<2, 6>(x, rows, k, m, bias, epilogue, &p, y),
                3 => panel::<3, 4>(x, rows, k, m, bias, epilogue, &p, y),
                4 => panel::<4, 3>(x, rows, k, m, bias, epilogue, &p, y),
                5 | 6 => panel::<6, 2>(x, rows, k, m, bias, epilogue, &p, y),
                _ => panel::<8, 1>(x, rows, k, m, bias, epilogue, &p, y),
            }
            c0 += PANEL;
        }
    }

    /// Columns `c0..c0 + cols` of rows `n` wide, M's rows `stride` long.
    struct Panel {
        stride: usize,
        n: usize,
        c0: usize,
        cols: usize,
    }

    /// Columns per panel of the weight gradient: 2 vectors, so 6 rows of dW hold 12 accumulators.
    const GRADIENT_PANEL: usize = 16;

    /// dW += dzᵀ · x (see `dense::weight_gradient`), panel by panel of dW's columns.
    #[target_feature(enable = "avx2,fma")]
    pub unsafe fn weight_gradient(dz: *const f32, x: *const f32, rows: usize, n_out: usize, n_in: usize, dw: *mut f32) {
        let mut c0 = 0;
        while c0 < n_in {
            let cols = (n_in - c0).min(GRADIENT_PANEL);
            let mut o = 0;
            if cols > LANES {
                while o + 6 <= n_out {
                    outer::<2, 6>(dz, x, rows, n_out, n_in, c0, cols, o, dw);
                    o += 6;
                }
            } else {
                while o + 12 <= n_out {
                    outer::<1, 12>(dz, x, rows, n_out, n_in, c0, cols, o, dw);
                    o += 12;
                }
            }
            while o < n_out {
                outer::<2, 1>(dz, x, rows, n_out, n_in, c0, cols, o, dw);
                o += 1;
            }
            c0 += GRADIENT_PANEL;
        }
    }

    /// Rows `o0..o0 + R` of dW, columns `c0..c0 + cols` (≤ V vectors): R × V accumulators
    /// summed over the batch rows.
    #[target_feature(enable = "avx2,fma")]
    #[inline]
    #[allow(clippy::too_many_arguments)]
    unsafe fn outer<const V: usize, const R: usize>(dz: *const f32, x: *const f32, rows: usize, n_out: usize, n_in: usize, c0: usize, cols: usize, o0: usize, dw: *mut f32) {
        let lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
        let mut mask = [_mm256_setzero_si256(); V];
        for (v, m) in mask.iter_mut().enumerate() {
            *m = _mm256_cmpgt_epi32(_mm256_set1_epi32(cols.saturating_sub(v * LANES).min(LANES) as i32), lane);
        }
        let mut acc = [[_mm256_setzero_ps(); V]; R];
        for b in 0..rows {
            let mut xv = [_mm256_setzero_ps(); V];
            for v in 0..V {
                let at = x.add(b * n_in + c0 + v * LANES);
                // VMASKMOVPS costs more than a plain load: only the panel's last vector needs it.
                xv[v] = if (v + 1) * LANES <= cols { _mm256_loadu_ps(at) } else { _mm256_maskload_ps(at, mask[v]) };
            }
            for (r, a) in acc.iter_mut().enumerate() {
                let d = _mm256_broadcast_ss(&*dz.add(b * n_out + o0 + r));
                for v in 0..V {
                    a[v] = _mm256_fmadd_ps(d, xv[v], a[v]);
                }
            }
        }
        for (r, a) in acc.iter().enumerate() {
            for v in 0..V {
                let at = dw.add((o0 + r) * n_in + c0 + v * LANES);
                _mm256_maskstore_ps(at, mask[v], _mm256_add_ps(a[v], _mm256_maskload_ps(at, mask[v])));
            }
        }
    }

    /// One panel for all rows: blocks of `R` rows, then the rest one at a time.
    #[target_feature(enable = "avx2,fma")]
    #[allow(clippy::too_many_arguments)]
    unsafe fn panel<const V: usize, const R: usize>(x: &[f32], rows: usize, k: usize, m: &[f32], bias: &[f32], epilogue: Epilogue<'_>, p: &Panel, y: &mut [f32]) {
        let mut r = 0;
        while r + R <= rows {
            block::<V, R>(x.as_ptr().add(r * k), k, m.as_ptr().add(p.c0), bias.as_ptr().add(p.c0), epilogue, r, p, y.as_mut_ptr().add(r * p.n + p.c0));
            r += R;
        }
        while r < rows {
            block::<V, 1>(x.as_ptr().add(r * k), k, m.as_ptr().add(p.c0), bias.as_ptr().add(p.c0), epilogue, r, p, y.as_mut_ptr().add(r * p.n + p.c0));
            r += 1;
        }
    }

    /// `R` rows starting at row `row`, one panel: R × V vectors of accumulators.
    #[target_feature(enable = "avx2,fma")]
    #[inline]
    #[allow(clippy::too_many_arguments)]
    unsafe fn block<const V: usize, const R: usize>(x: *const f32, k: usize, m: *const f32, bias: *const f32, epilogue: Epilogue<'_>, row: usize, p: &Panel, y: *mut f32) {
        let mut acc = [[_mm256_setzero_ps(); V]; R];
        for v in 0..V {
            let b = _mm256_loadu_ps(bias.add(v * LANES));
            for a in acc.iter_mut() {
                a[v] = b;
            }
        }
        for i in 0..k {
            let mut w = [_mm256_setzero_ps(); V];
            for (v, wv) in w.iter_mut().enumerate() {
                *wv = _mm256_loadu_ps(m.add(i * p.stride + v * LANES));
            }
            for (r, a) in acc.iter_mut().enumerate() {
                let xb = _mm256_broadcast_ss(&*x.add(r * k + i));
                for v in 0..V {
                    a[v] = _mm256_fmadd_ps(xb, w[v], a[v]);
                }
            }
        }
        let lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
        for (r, a) in acc.iter().enumerate() {
            for (v, &value) in a.iter().enumerate() {
                let first = v * LANES;
                if first >= p.cols {
                    break;
                }
                let mask = _mm256_cmpgt_epi32(_mm256_set1_epi32((p.cols - first).min(LANES) as i32), lane);
                let out = match epilogue {
                    Epilogue::None => value,
                    Epilogue::LeakyRelu { slope } => _mm256_max_ps(value, _mm256_mul_ps(value, _mm256_set1_ps(slope))),
                    Epilogue::ExpHead { shift, clamp } => exp(_mm256_sub_ps(_mm256_min_ps(_mm256_set1_ps(clamp), value), _mm256_set1_ps(shift))),
                    Epilogue::LeakyReluGradient { slope, a } => {
                        let act = _mm256_maskload_ps(a.as_ptr().add((row + r) * p.n + p.c0 + first), mask);
                        let positive = _mm256_cmp_ps::<_CMP_GT_OQ>(act, _mm256_setzero_ps());
                        _mm256_blendv_ps(_mm256_mul_ps(value, _mm256_set1_ps(slope)), value, positive)
                    }
                };
                _mm256_maskstore_ps(y.add(r * p.n + first), mask, out);
            }
        }
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

    /// dW += dzᵀ · x (see `dense::weight_gradient`): blocks of `R` rows of dW, then the rest
    /// one at a time.
    #[target_feature(enable = "avx512f")]
    pub unsafe fn outer<const V: usize, const R: usize>(dz: *const f32, x: *const f32, rows: usize, n_out: usize, n_in: usize, dw: *mut f32) {
        let mut o = 0;
        while o + R <= n_out {
            outer_block::<V, R>(dz, x, rows, n_out, n_in, o, dw);
            o += R;
        }
        while o < n_out {
            outer_block::<V, 1>(dz, x, rows, n_out, n_in, o, dw);
            o += 1;
        }
    }

    /// Rows `o0..o0 + R` of dW: R × V accumulators summed over the batch rows.
    #[target_feature(enable = "avx512f")]
    #[inline]
    unsafe fn outer_block<const V: usize, const R: usize>(dz: *const f32, x: *const f32, rows: usize, n_out: usize, n_in: usize, o0: usize, dw: *mut f32) {
        let mut mask = [0 as __mmask16; V];
        for (v, m) in mask.iter_mut().enumerate() {
            let first = v * LANES;
            *m = if first + LANES <= n_in { 0xffff } else { ((1u32 << (n_in - first)) - 1) as __mmask16 };
        }
        let mut acc = [[_mm512_setzero_ps(); V]; R];
        for b in 0..rows {
            let mut xv = [_mm512_setzero_ps(); V];
            for v in 0..V {
                xv[v] = _mm512_maskz_loadu_ps(mask[v], x.add(b * n_in + v * LANES));
            }
            for (r, a) in acc.iter_mut().enumerate() {
                let d = _mm512_set1_ps(*dz.add(b * n_out + o0 + r));
                for v in 0..V {
                    a[v] = _mm512_fmadd_ps(d, xv[v], a[v]);
                }
            }
        }
        for (r, a) in acc.iter().enumerate() {
            for v in 0..V {
                let at = dw.add((o0 + r) * n_in + v * LANES);
                _mm512_mask_storeu_ps(at, mask[v], _mm512_add_ps(a[v], _mm512_maskz_loadu_ps(mask[v], at)));
            }
        }
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

    /// The kernels this CPU can run (both on an AVX-512 machine), saying which it cannot.
    fn testable(test: &str) -> Vec<Isa> {
        let all = [Isa::Avx512, Isa::Avx2];
        for isa in all.iter().filter(|i| !i.supported()) {
            eprintln!("NOT TESTED HERE: {test} on {}, which this CPU lacks", isa.name());
        }
        all.into_iter().filter(|i| i.supported()).collect()
    }

    /// e^x over f32's range against f64, and its limits.
    #[test]
    fn vector_exp_is_accurate() {
        for isa in testable("vector_exp_is_accurate") {
            vector_exp_on(isa);
        }
    }

    fn vector_exp_on(isa: Isa) {
        let mut worst = 0.0f64;
        let mut x = -87.0f32;
        while x < 88.0 {
            let xs: Vec<f32> = (0..16).map(|k| x + k as f32 * 1e-3).collect();
            let mut y = vec![0.0f32; 16];
            // exp(min(v, 100) − 0) = e^v through the epilogue, with M = 1 (k = 1).
            dense_on(isa, &xs, 16, 1, &{ let mut m = Vec::new(); pack(1, 1, |_, _| 1.0, &mut m); m }, 1, &[], Epilogue::ExpHead { shift: 0.0, clamp: 100.0 }, &mut y);
            for (a, b) in xs.iter().zip(&y) {
                let want = (*a as f64).exp();
                worst = worst.max(((*b as f64) - want).abs() / want);
            }
            x += 0.37;
        }
        assert!(worst < 4e-7, "{}: worst relative error {worst}", isa.name());
        let xs = [f32::NAN, -1e6, 1e6, 0.0];
        let mut y = [0.0f32; 4];
        let mut m = Vec::new();
        pack(1, 1, |_, _| 1.0, &mut m);
        dense_on(isa, &xs, 4, 1, &m, 1, &[], Epilogue::ExpHead { shift: 0.0, clamp: f32::INFINITY }, &mut y);
        assert!(y[0].is_nan() && y[1] == 0.0 && y[2] == f32::INFINITY && y[3] == 1.0, "{}: {y:?}", isa.name());
    }

    /// The weight gradient dW += dzᵀ·x against an f64 loop, for layer shapes of the networks and
    /// odd ones (row counts that leave tails, widths across the AVX2 panels).
    #[test]
    fn weight_gradient_matches_a_plain_loop() {
        for isa in testable("weight_gradient_matches_a_plain_loop") {
            let mut s = 3u64;
            for (rows, n_out, n_in) in [(512, 64, 64), (37, 7, 64), (100, 64, 15), (13, 6, 24), (70, 41, 33), (5, 1, 1)] {
                let dz: Vec<f32> = (0..rows * n_out).map(|_| lcg(&mut s)).collect();
                let x: Vec<f32> = (0..rows * n_in).map(|_| lcg(&mut s)).collect();
                let before: Vec<f32> = (0..n_out * n_in).map(|_| lcg(&mut s)).collect();
                let mut dw = before.clone();
                weight_gradient(isa, &dz, &x, rows, n_out, n_in, &mut dw);
                for o in 0..n_out {
                    for i in 0..n_in {
                        let want = before[o * n_in + i] as f64 + (0..rows).map(|r| dz[r * n_out + o] as f64 * x[r * n_in + i] as f64).sum::<f64>();
                        let got = dw[o * n_in + i] as f64;
                        assert!((got - want).abs() <= 1e-5 * (rows as f64).sqrt() * (1.0 + want.abs()), "{}: {rows}×{n_out}×{n_in} dW[{o}][{i}] {got} vs {want}", isa.name());
                    }
                }
            }
        }
    }

    /// Every width 1..=64, row counts that leave tails, each epilogue: against an f64 loop.
    #[test]
    fn fused_kernel_matches_a_plain_loop() {
        for isa in testable("fused_kernel_matches_a_plain_loop") {
            fused_kernel_on(isa);
        }
    }

    fn fused_kernel_on(isa: Isa) {
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
                    dense_on(isa, &x, rows, k, &m, n, b, epilogue, &mut y);
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
                            assert!(error <= 1e-5, "{}: n {n} k {k} row {r} col {j} epilogue {e}: {got} vs {want}", isa.name());
                        }
                    }
                }
            }
        }
    }
}
