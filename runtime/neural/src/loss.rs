//! The paper's loss (Eq. 3): L = λf·‖φ(f̂) − φ(f)‖₁ + λt·‖T̂ − T‖₁ + λr·‖R̂ − R‖₁, each term the
//! mean over the batch and its channels, with λ = (0.95, 0.04, 0.01). f is compared in
//! cosine-weighted log space, φ(f) = ln(1 + μl·f) (lobes.md §4.3: plain ℓ1 on f is dominated by
//! the D ≈ 2·10⁴ peaks of α = 0.004 lobes). The reference arrives as f·μl (the `eval` kernel's
//! response), so φ(f_ref) = ln(1 + response). Outputs and targets are rows of [`OUTPUTS`]:
//! f RGB, T RGB, R.

use crate::mlp::Real;

/// Decoder outputs (and targets) per row: f (RGB), T (RGB), R.
pub const OUTPUTS: usize = 7;

/// The weights of Eq. 3.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LossWeights {
    pub f: f64,
    pub t: f64,
    pub r: f64,
}

impl LossWeights {
    pub const PAPER: LossWeights = LossWeights { f: 0.95, t: 0.04, r: 0.01 };
}

/// The loss of a batch and its three terms (unweighted means).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LossParts {
    pub total: f64,
    pub f: f64,
    pub t: f64,
    pub r: f64,
}

impl LossParts {
    /// Sums parts of slices of one batch (each already normalised by the whole batch).
    pub fn add(&mut self, o: &LossParts) {
        self.total += o.total;
        self.f += o.f;
        self.t += o.t;
        self.r += o.r;
    }
}

/// The loss of `out` (rows × 7) against `target` (rows × 7: f·μl RGB, T RGB, R) at light
/// cosines `mu_l`, normalised as if the batch had `batch` rows (so slices of one batch add up);
/// writes ∂loss/∂out into `d_out`.
pub fn eq3_loss<T: Real>(out: &[T], target: &[f32], mu_l: &[f32], batch: usize, w: LossWeights, d_out: &mut [T]) -> LossParts {
    let rows = mu_l.len();
    assert_eq!(out.len(), rows * OUTPUTS);
    assert_eq!(target.len(), rows * OUTPUTS);
    assert_eq!(d_out.len(), rows * OUTPUTS);
    let (nf, nt, nr) = (3.0 * batch as f64, 3.0 * batch as f64, batch as f64);
    let mut parts = LossParts::default();
    let sign = |x: f64| if x > 0.0 { 1.0 } else if x < 0.0 { -1.0 } else { 0.0 };
    for r in 0..rows {
        let (o, t, d) = (&out[r * OUTPUTS..][..OUTPUTS], &target[r * OUTPUTS..][..OUTPUTS], &mut d_out[r * OUTPUTS..][..OUTPUTS]);
        let mu = mu_l[r] as f64;
        for c in 0..3 {
            let f = o[c].to_f64();
            let diff = (mu * f).ln_1p() - (t[c] as f64).max(0.0).ln_1p();
            parts.f += diff.abs() / nf;
            d[c] = T::from_f64(w.f / nf * sign(diff) * mu / (1.0 + mu * f));
        }
        for c in 3..6 {
            let diff = o[c].to_f64() - t[c] as f64;
            parts.t += diff.abs() / nt;
            d[c] = T::from_f64(w.t / nt * sign(diff));
        }
        let diff = o[6].to_f64() - t[6] as f64;
        parts.r += diff.abs() / nr;
        d[6] = T::from_f64(w.r / nr * sign(diff));
    }
    parts.total = w.f * parts.f + w.t * parts.t + w.r * parts.r;
    parts
}
