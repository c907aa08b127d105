//! A dense multilayer perceptron with hand-written forward and backward passes on
//! `matrixmultiply` GEMMs (single-threaded; callers parallelise over batch slices). Generic over
//! the float type so the gradient check runs the same code in f64. Parameters live in one flat
//! vector (per layer: the weights, row-major `out × in`, then the biases), which Adam updates
//! and safetensors stores as one tensor per layer. Activations are rows (`batch × width`).

use uplift_base::rng::SplitMix64;
use crate::dense::{self, Epilogue, PackedNetwork};
use std::ops::{Add, AddAssign, Div, Mul, Neg, Sub};

/// The float types the network runs in.
pub trait Real:
    Copy + Default + PartialOrd + Send + Sync + std::fmt::Debug + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self> + Neg<Output = Self> + AddAssign + 'static
{
    fn from_f64(v: f64) -> Self;
    fn to_f64(self) -> f64;
    fn exp(self) -> Self;
    fn ln_1p(self) -> Self;
    /// C (m×n) = alpha·A (m×k)·B (k×n) + beta·C, each matrix given by its row and column strides.
    #[allow(clippy::too_many_arguments)]
    fn gemm(m: usize, k: usize, n: usize, alpha: Self, a: &[Self], rsa: isize, csa: isize, b: &[Self], rsb: isize, csb: isize, beta: Self, c: &mut [Self], rsc: isize, csc: isize);
    /// The slice as f32 when the type is f32 (the fused kernels' path, dense.rs); `None` otherwise.
    fn as_f32(_s: &[Self]) -> Option<&[f32]> {
        None
    }
    fn as_f32_mut(_s: &mut [Self]) -> Option<&mut [f32]> {
        None
    }
}

/// Checks that a strided matrix lies inside its slice (the GEMM reads raw pointers).
fn assert_fits(len: usize, rows: usize, cols: usize, rs: isize, cs: isize) {
    if rows > 0 && cols > 0 {
        let last = (rows - 1) as isize * rs + (cols - 1) as isize * cs;
        assert!(rs >= 0 && cs >= 0 && (last as usize) < len, "matrix {rows}×{cols} (strides {rs}, {cs}) exceeds its buffer of {len}");
    }
}

macro_rules! real_impl {
    ($t:ty, $gemm:ident $(, { $($extra:tt)* })?) => {
        impl Real for $t {
            fn from_f64(v: f64) -> Self {
                v as $t
            }
            fn to_f64(self) -> f64 {
                self as f64
            }
            fn exp(self) -> Self {
                <$t>::exp(self)
            }
            fn ln_1p(self) -> Self {
                <$t>::ln_1p(self)
            }
            fn gemm(m: usize, k: usize, n: usize, alpha: Self, a: &[Self], rsa: isize, csa: isize, b: &[Self], rsb: isize, csb: isize, beta: Self, c: &mut [Self], rsc: isize, csc: isize) {
                assert_fits(a.len(), m, k, rsa, csa);
                assert_fits(b.len(), k, n, rsb, csb);
                assert_fits(c.len(), m, n, rsc, csc);
                // SAFETY: the three matrices lie inside their slices (checked above), and `c`
                // is borrowed mutably, so it aliases neither input.
                unsafe { matrixmultiply::$gemm(m, k, n, alpha, a.as_ptr(), rsa, csa, b.as_ptr(), rsb, csb, beta, c.as_mut_ptr(), rsc, csc) }
            }
            $($($extra)*)?
        }
    };
}
real_impl!(
    f32,
    sgemm,
    {
        fn as_f32(s: &[f32]) -> Option<&[f32]> {
            Some(s)
        }
        fn as_f32_mut(s: &mut [f32]) -> Option<&mut [f32]> {
            Some(s)
        }
    }
);
real_impl!(f64, dgemm);

/// A layer's activation function.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Activation {
    Identity,
    /// max(x, slope·x).
    LeakyRelu { slope: f64 },
    /// 1 / (1 + e^−x).
    Sigmoid,
    /// exp(min(x, clamp) − shift): positive, starts small (e^−shift at x = 0), and can never
    /// overflow (at most e^(clamp − shift)); its gradient is zero above the clamp.
    ExpHead { shift: f64, clamp: f64 },
}

impl Activation {
    /// The decoder's output head: exp(min(x, 30) − 3) ≤ e²⁷ ≈ 5·10¹¹, finite in f32 and f16-free.
    pub const EXP_HEAD: Activation = Activation::ExpHead { shift: 3.0, clamp: 30.0 };
    pub const LEAKY_RELU: Activation = Activation::LeakyRelu { slope: 0.01 };

    pub fn apply<T: Real>(self, x: T) -> T {
        match self {
            Activation::Identity => x,
            Activation::LeakyRelu { slope } => {
                if x > T::default() {
                    x
                } else {
                    x * T::from_f64(slope)
                }
            }
            Activation::Sigmoid => T::from_f64(1.0) / (T::from_f64(1.0) + (-x).exp()),
            Activation::ExpHead { shift, clamp } => {
                let c = T::from_f64(clamp);
                (if x < c { x } else { c } - T::from_f64(shift)).exp()
            }
        }
    }

    /// d activation / dx, from the activation's output `a` alone.
    pub fn derivative_from_output<T: Real>(self, a: T) -> T {
        match self {
            Activation::Identity => T::from_f64(1.0),
            Activation::LeakyRelu { slope } => {
                if a > T::default() {
                    T::from_f64(1.0)
                } else {
                    T::from_f64(slope)
                }
            }
            Activation::Sigmoid => a * (T::from_f64(1.0) - a),
            Activation::ExpHead { shift, clamp } => {
                if a.to_f64() < (clamp - shift).exp() {
                    a
                } else {
                    T::default()
                }
            }
        }
    }

    /// Applies the activation to every value (one `match`, then a loop LLVM vectorises).
    pub fn apply_slice<T: Real>(self, values: &mut [T]) {
        match self {
            Activation::Identity => {}
            Activation::LeakyRelu { slope } => {
                let s = T::from_f64(slope);
                let zero = T::default();
                for v in values.iter_mut() {
                    *v = if *v > zero { *v } else { *v * s };
                }
            }
            _ => values.iter_mut().for_each(|v| *v = self.apply(*v)),
        }
    }

    /// grad ⊙= activation′, from the activation's outputs (one `match`, then a loop).
    pub fn scale_by_derivative<T: Real>(self, grad: &mut [T], outputs: &[T]) {
        match self {
            Activation::Identity => {}
            Activation::LeakyRelu { slope } => {
                let s = T::from_f64(slope);
                let zero = T::default();
                for (g, a) in grad.iter_mut().zip(outputs) {
                    *g = if *a > zero { *g } else { *g * s };
                }
            }
            _ => grad.iter_mut().zip(outputs).for_each(|(g, a)| *g = *g * self.derivative_from_output(*a)),
        }
    }

    pub fn name(self) -> String {
        match self {
            Activation::Identity => "identity".into(),
            Activation::LeakyRelu { slope } => format!("leaky_relu({slope})"),
            Activation::Sigmoid => "sigmoid".into(),
            Activation::ExpHead { shift, clamp } => format!("exp(min(x, {clamp}) - {shift})"),
        }
    }

    /// Parses [`Activation::name`]'s text.
    pub fn parse(text: &str) -> Option<Activation> {
        let args = |s: &str| -> Option<Vec<f64>> { s.split(',').map(|v| v.trim().parse().ok()).collect() };
        match text {
            "identity" => Some(Activation::Identity),
            "sigmoid" => Some(Activation::Sigmoid),
            t if t.starts_with("leaky_relu(") && t.ends_with(')') => Some(Activation::LeakyRelu { slope: args(&t[11..t.len() - 1])?[0] }),
            t if t.starts_with("exp(min(x, ") && t.ends_with(')') => {
                let inner = t[11..t.len() - 1].replace(") -", ",");
                let v = args(&inner)?;
                (v.len() == 2).then(|| Activation::ExpHead { clamp: v[0], shift: v[1] })
            }
            _ => None,
        }
    }
}

/// The shape of a network: layer widths (input first) and activations.
#[derive(Clone, Debug, PartialEq)]
pub struct MlpShape {
    pub widths: Vec<usize>,
    pub hidden: Activation,
    pub output: Activation,
}

impl MlpShape {
    pub fn layers(&self) -> usize {
        self.widths.len() - 1
    }
    pub fn inputs(&self) -> usize {
        self.widths[0]
    }
    pub fn outputs(&self) -> usize {
        *self.widths.last().unwrap()
    }
    /// Where layer `l`'s weights and biases start in the flat parameter vector.
    pub fn offsets(&self, l: usize) -> (usize, usize) {
        let mut at = 0;
        for k in 0..l {
            at += (self.widths[k] + 1) * self.widths[k + 1];
        }
        (at, at + self.widths[l] * self.widths[l + 1])
    }
    pub fn parameter_count(&self) -> usize {
        self.widths.windows(2).map(|w| (w[0] + 1) * w[1]).sum()
    }
    pub fn activation(&self, l: usize) -> Activation {
        if l + 1 == self.layers() {
            self.output
        } else {
            self.hidden
        }
    }
    /// Multiply–adds per forward evaluation of one row.
    pub fn macs(&self) -> usize {
        self.widths.windows(2).map(|w| w[0] * w[1]).sum()
    }
}

/// A network: its shape and flat parameters.
#[derive(Clone, Debug)]
pub struct Mlp<T: Real> {
    pub shape: MlpShape,
    pub params: Vec<T>,
}

/// The activations of one forward pass (kept for the backward pass), and scratch space.
pub struct Workspace<T: Real> {
    /// Post-activation rows of every layer (layer 0's input is not copied).
    acts: Vec<Vec<T>>,
    /// Gradients with respect to a layer's output and input (swapped while walking back).
    grad: Vec<T>,
    grad_prev: Vec<T>,
    rows: usize,
    /// Whether [`Mlp::backward`] computes ∂loss/∂input (the first layer's dx GEMM).
    pub want_input_gradient: bool,
    /// The layers packed for the fused kernels (dense.rs).
    packed: PackedNetwork,
}

impl<T: Real> Workspace<T> {
    /// ∂loss/∂input rows of the last backward pass (when `want_input_gradient`).
    pub fn input_gradient(&self) -> &[T] {
        &self.grad
    }

    /// A workspace whose backward pass stops at the first layer's weights (no input gradient).
    pub fn without_input_gradient() -> Workspace<T> {
        Workspace { want_input_gradient: false, ..Default::default() }
    }
}

impl<T: Real> Default for Workspace<T> {
    fn default() -> Self {
        Workspace { acts: Vec::new(), grad: Vec::new(), grad_prev: Vec::new(), rows: 0, want_input_gradient: true, packed: PackedNetwork::default() }
    }
}

/// Whether a layer `n` wide runs through the fused kernels on this CPU (for f32 networks).
fn fused(n: usize) -> bool {
    n <= dense::MAX_WIDTH && dense::available()
}

/// A LeakyReLU's slope when the fused kernels can apply it (0 ≤ slope ≤ 1).
fn leaky_slope(a: Activation) -> Option<f32> {
    match a {
        Activation::LeakyRelu { slope } if (0.0..=1.0).contains(&slope) => Some(slope as f32),
        _ => None,
    }
}

impl<T: Real> Mlp<T> {
    /// Xavier-uniform weights, zero biases, from `seed`.
    pub fn new(shape: MlpShape, seed: u64) -> Mlp<T> {
        let mut params = vec![T::default(); shape.parameter_count()];
        let mut rng = SplitMix64::new(seed ^ 0x6d6c_705f_696e_6974);
        for l in 0..shape.layers() {
            let (w, _) = shape.offsets(l);
            let (fan_in, fan_out) = (shape.widths[l], shape.widths[l + 1]);
            let bound = (6.0 / (fan_in + fan_out) as f64).sqrt();
            for p in &mut params[w..w + fan_in * fan_out] {
                *p = T::from_f64((2.0 * rng.unit_f64() - 1.0) * bound);
            }
        }
        Mlp { shape, params }
    }

    pub fn from_params(shape: MlpShape, params: Vec<T>) -> Result<Mlp<T>, String> {
        if params.len() != shape.parameter_count() {
            return Err(format!("{} parameters for a network of {:?} that has {}", params.len(), shape.widths, shape.parameter_count()));
        }
        Ok(Mlp { shape, params })
    }

    /// Layer `l`'s weights (row-major `out × in`) and biases.
    pub fn layer(&self, l: usize) -> (&[T], &[T]) {
        let (w, b) = self.shape.offsets(l);
        let out = self.shape.widths[l + 1];
        (&self.params[w..b], &self.params[b..b + out])
    }

    /// Packs the layers for the fused kernels (a no-op while the parameters are unchanged, or
    /// without the kernels).
    fn pack(&self, packed: &mut PackedNetwork) {
        if let (true, Some(params)) = (dense::available(), T::as_f32(&self.params)) {
            let s = &self.shape;
            packed.update(params, (0..s.layers()).map(|l| {
                let (w, _) = s.offsets(l);
                (s.widths[l], s.widths[l + 1], &params[w..w + s.widths[l] * s.widths[l + 1]])
            }));
        }
    }

    /// Runs `rows` input rows (`rows × inputs`) forward; returns the output rows, which stay
    /// in `ws` for [`Mlp::backward`].
    pub fn forward<'w>(&self, input: &[T], rows: usize, ws: &'w mut Workspace<T>) -> &'w [T] {
        let s = &self.shape;
        assert_eq!(input.len(), rows * s.inputs(), "input rows");
        ws.rows = rows;
        ws.acts.resize_with(s.layers(), Vec::new);
        self.pack(&mut ws.packed);
        for l in 0..s.layers() {
            let (n_in, n_out) = (s.widths[l], s.widths[l + 1]);
            let (w, b) = self.layer(l);
            let (before, after) = ws.acts.split_at_mut(l);
            let x: &[T] = if l == 0 { input } else { &before[l - 1] };
            let y = &mut after[0];
            y.resize(rows * n_out, T::default());
            let activation = s.activation(l);
            let fast = if fused(n_out) { T::as_f32(x).zip(T::as_f32(b)) } else { None };
            if let (Some((x, b)), Some(y)) = (fast, T::as_f32_mut(y)) {
                // y = act(x · Wᵀ + b), one pass (dense.rs).
                let epilogue = match activation {
                    Activation::ExpHead { shift, clamp } => Epilogue::ExpHead { shift: shift as f32, clamp: clamp as f32 },
                    a => leaky_slope(a).map_or(Epilogue::None, |slope| Epilogue::LeakyRelu { slope }),
                };
                dense::dense(x, rows, n_in, ws.packed.forward(l), n_out, b, epilogue, y);
                if matches!(epilogue, Epilogue::None) {
                    activation.apply_slice(y);
                }
                continue;
            }
            for r in 0..rows {
                y[r * n_out..(r + 1) * n_out].copy_from_slice(b);
            }
            // y (rows × out) += x (rows × in) · Wᵀ (in × out).
            T::gemm(rows, n_in, n_out, T::from_f64(1.0), x, n_in as isize, 1, w, 1, n_in as isize, T::from_f64(1.0), y, n_out as isize, 1);
            activation.apply_slice(y);
        }
        &ws.acts[s.layers() - 1]
    }

    /// Back-propagates `d_output` (∂loss/∂output rows) through the last forward pass in `ws`:
    /// adds ∂loss/∂parameters into `grads` (skipped when `None`: a frozen network) and returns
    /// ∂loss/∂input rows.
    pub fn backward<'w>(&self, input: &[T], d_output: &[T], ws: &'w mut Workspace<T>, mut grads: Option<&mut [T]>) -> &'w [T] {
        let s = &self.shape;
        let rows = ws.rows;
        assert_eq!(d_output.len(), rows * s.outputs(), "output gradient rows");
        if let Some(g) = &grads {
            assert_eq!(g.len(), self.params.len(), "gradient length");
        }
        ws.grad.clear();
        ws.grad.extend_from_slice(d_output);
        // Whether ws.grad already holds dz (the fused dx kernel applied act′).
        let mut scaled = false;
        self.pack(&mut ws.packed);
        for l in (0..s.layers()).rev() {
            let (n_in, n_out) = (s.widths[l], s.widths[l + 1]);
            // dz = d_out ⊙ act'(z), from the activations.
            if !std::mem::take(&mut scaled) {
                s.activation(l).scale_by_derivative(&mut ws.grad, &ws.acts[l]);
            }
            if let Some(grads) = grads.as_deref_mut() {
                let x: &[T] = if l == 0 { input } else { &ws.acts[l - 1] };
                let (w_at, b_at) = s.offsets(l);
                let (gw, gb) = grads[w_at..b_at + n_out].split_at_mut(b_at - w_at);
                // dW (out × in) += dzᵀ (out × rows) · x (rows × in).
                let isa = if n_in <= dense::MAX_WIDTH { dense::isa() } else { None };
                match (isa, T::as_f32(&ws.grad), T::as_f32(x)) {
                    (Some(isa), Some(dz), Some(x32)) if T::as_f32(gw).is_some() => {
                        let gw = T::as_f32_mut(gw).expect("an f32 network");
                        dense::weight_gradient(isa, dz, x32, rows, n_out, n_in, gw);
                    }
                    _ => T::gemm(n_out, rows, n_in, T::from_f64(1.0), &ws.grad, 1, n_out as isize, x, n_in as isize, 1, T::from_f64(1.0), gw, n_in as isize, 1),
                }
                for r in 0..rows {
                    for (b, g) in gb.iter_mut().zip(&ws.grad[r * n_out..(r + 1) * n_out]) {
                        *b += *g;
                    }
                }
            }
            if l == 0 && !ws.want_input_gradient {
                break;
            }
            // dx (rows × in) = dz (rows × out) · W (out × in).
            let (w, _) = self.layer(l);
            ws.grad_prev.resize(rows * n_in, T::default());
            let below = if l > 0 { T::as_f32(&ws.acts[l - 1]).zip(leaky_slope(s.activation(l - 1))) } else { None };
            if let (true, Some(dz), Some(dx)) = (fused(n_in), T::as_f32(&ws.grad), T::as_f32_mut(&mut ws.grad_prev)) {
                // With the layer below's LeakyReLU derivative applied: dx is its dz (dense.rs).
                let epilogue = below.map_or(Epilogue::None, |(a, slope)| Epilogue::LeakyReluGradient { slope, a });
                dense::dense(dz, rows, n_out, ws.packed.backward(l), n_in, &[], epilogue, dx);
                scaled = below.is_some();
                std::mem::swap(&mut ws.grad, &mut ws.grad_prev);
                continue;
            }
            T::gemm(rows, n_out, n_in, T::from_f64(1.0), &ws.grad, n_out as isize, 1, w, n_in as isize, 1, T::default(), &mut ws.grad_prev, n_in as isize, 1);
            std::mem::swap(&mut ws.grad, &mut ws.grad_prev);
        }
        &ws.grad
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn activation_names_round_trip() {
        for a in [Activation::Identity, Activation::Sigmoid, Activation::LEAKY_RELU, Activation::EXP_HEAD] {
            assert_eq!(Activation::parse(&a.name()), Some(a), "{}", a.name());
        }
    }

    /// The f32 network (the fused kernels of dense.rs, where this CPU has them) against the
    /// same network in f64 (the GEMM path): outputs, input and weight gradients.
    #[test]
    fn f32_layers_agree_with_the_f64_gemm_path() {
        let mut rng = SplitMix64::new(11);
        for (widths, output) in [(vec![15, 64, 64, 33, 7], Activation::EXP_HEAD), (vec![22, 64, 64, 6], Activation::Sigmoid), (vec![9, 80, 16], Activation::Identity)] {
            let shape = MlpShape { widths, hidden: Activation::LEAKY_RELU, output };
            let wide: Mlp<f64> = Mlp::new(shape.clone(), 3);
            let narrow: Mlp<f32> = Mlp::from_params(shape.clone(), wide.params.iter().map(|p| *p as f32).collect()).unwrap();
            let rows = 37;
            let x: Vec<f64> = (0..rows * shape.inputs()).map(|_| 2.0 * rng.unit_f64() - 1.0).collect();
            let d: Vec<f64> = (0..rows * shape.outputs()).map(|_| 2.0 * rng.unit_f64() - 1.0).collect();
            let (mut w64, mut w32) = (Workspace::default(), Workspace::default());
            let y64 = wide.forward(&x, rows, &mut w64).to_vec();
            let x32: Vec<f32> = x.iter().map(|v| *v as f32).collect();
            let y32 = narrow.forward(&x32, rows, &mut w32).to_vec();
            let (mut g64, mut g32) = (vec![0.0f64; wide.params.len()], vec![0.0f32; narrow.params.len()]);
            let dx64 = wide.backward(&x, &d, &mut w64, Some(&mut g64)).to_vec();
            let d32: Vec<f32> = d.iter().map(|v| *v as f32).collect();
            let dx32 = narrow.backward(&x32, &d32, &mut w32, Some(&mut g32)).to_vec();
            for (what, a, b) in [("output", &y64, &y32), ("input gradient", &dx64, &dx32), ("weight gradient", &g64, &g32)] {
                let scale = a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                let worst = a.iter().zip(b.iter()).fold(0.0f64, |m, (p, q)| m.max((p - *q as f64).abs()));
                assert!(worst <= 2e-5 * scale.max(1e-3), "{:?} {what}: worst |Δ| {worst} at scale {scale}", shape.widths);
            }
        }
    }

    #[test]
    fn exp_head_never_overflows_f32() {
        for x in [0.0f32, 29.0, 30.0, 1e6, f32::MAX] {
            assert!(Activation::EXP_HEAD.apply(x).is_finite(), "{x}");
        }
    }
}
