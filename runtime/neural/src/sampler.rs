//! The sampling decoder (paper §4.1, following Zeltner et al. 2024; lobes.md §4.5): a small MLP
//! from a texel's latent and the view cosine μv to an analytic mixture over light directions —
//! two GGX visible-normal lobes (their weights and roughnesses) and a cosine lobe — with which
//! the renderer importance-samples the neural non-diffuse part, and whose pdf it uses for MIS.
//!
//! Trained once, after the evaluation decoder, by maximum likelihood: the forward KL from the
//! reference stack's normalised f·cos to the mixture, −Σ_j ŵ_j log q(ωl_j), over direction sets
//! drawn half from the stack's own `sample` kernel and half cosine-weighted (ŵ_j ∝ Y(f·cos)/p_j
//! with p the two halves' mixture pdf, normalised per view), at the frozen encoder's latents of
//! the training classes' parameters. Stored in the weights file beside the networks it serves
//! (`sampler.*`).

use crate::adam::{cosine_lr, Adam};
use crate::datagen::DataGenerator;
use crate::features::cosine_hemisphere;
use crate::mlp::{Activation, Mlp, MlpShape, Workspace};
use crate::model::NeuralModel;
use std::f32::consts::{FRAC_1_PI, PI};
use uplift_base::rng::{mix64, unit_from_key as unit};
use uplift_engines::stack_kernel::{usable_sample, vec3_at};

/// Raw outputs: three lobe logits, then two roughness pre-activations.
pub const SAMPLER_OUTPUTS: usize = 5;

/// The smallest GGX roughness the mixture uses (sharper lobes are sampled as this one).
pub const ALPHA_MIN: f32 = 0.02;

/// The cosine lobe's least weight (defensive sampling: wherever the decoder reflects something
/// the mixture lost track of, f̂·cos/q stays bounded by π·f̂/ε). Measured: without it, a hazy
/// dielectric's mixture put 97 % on its sharpest lobe and the albedo estimate over 16,384
/// samples missed by 0.010.
pub const COSINE_FLOOR: f32 = 0.1;

/// The sampler's shape for a latent of `latent` values: (latent, μv) → 3 × 32 → 5.
pub fn sampler_shape(latent: usize) -> MlpShape {
    MlpShape { widths: vec![latent + 1, 32, 32, 32, SAMPLER_OUTPUTS], hidden: Activation::LEAKY_RELU, output: Activation::Identity }
}

/// The sampler's input row: the latent, then μv.
pub fn sampler_input(latent: &[f32], mu_v: f32, row: &mut Vec<f32>) {
    row.extend_from_slice(latent);
    row.push(mu_v);
}

/// A mixture over light directions at one view: weights of (GGX A, GGX B, cosine) and the two
/// GGX roughnesses.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mixture {
    pub weight: [f32; 3],
    pub alpha: [f32; 2],
}

fn sigmoid(x: f32) -> f32 {
    1.0 / (1.0 + (-x).exp())
}

/// Softmax of the three logits.
fn softmax(o: &[f32]) -> [f32; 3] {
    let m = o[0].max(o[1]).max(o[2]);
    let e = [0, 1, 2].map(|k| (o[k] - m).exp());
    let s = e[0] + e[1] + e[2];
    e.map(|x| x / s)
}

impl Mixture {
    /// From the sampler's raw outputs: weights ε·cosine + (1 − ε)·softmax (ε =
    /// [`COSINE_FLOOR`]), α = α_min + (1 − α_min)·σ(o).
    pub fn from_outputs(o: &[f32]) -> Mixture {
        let s = softmax(o);
        let mut weight = s.map(|x| (1.0 - COSINE_FLOOR) * x);
        weight[2] += COSINE_FLOOR;
        Mixture { weight, alpha: [sigmoid(o[3]), sigmoid(o[4])].map(|g| ALPHA_MIN + (1.0 - ALPHA_MIN) * g) }
    }

    /// The lobes' pdfs at wl (solid angle; local frame, normal +z): GGX A, GGX B, cosine.
    pub fn lobe_pdfs(&self, wv: [f32; 3], wl: [f32; 3]) -> [f32; 3] {
        if wl[2] <= 0.0 || wv[2] <= 0.0 {
            return [0.0; 3];
        }
        [vndf_pdf(wv, wl, self.alpha[0]), vndf_pdf(wv, wl, self.alpha[1]), wl[2] * FRAC_1_PI]
    }

    /// The mixture pdf at wl.
    pub fn pdf(&self, wv: [f32; 3], wl: [f32; 3]) -> f32 {
        let p = self.lobe_pdfs(wv, wl);
        self.weight[0] * p[0] + self.weight[1] * p[1] + self.weight[2] * p[2]
    }

    /// A direction drawn from the mixture with three uniforms (`u[2]` picks the lobe); `None`
    /// when a GGX sample leaves the hemisphere.
    pub fn sample(&self, wv: [f32; 3], u: [f32; 3]) -> Option<[f32; 3]> {
        let wl = if u[2] < self.weight[0] {
            reflect(wv, vndf_sample(wv, self.alpha[0], u[0], u[1]))
        } else if u[2] < self.weight[0] + self.weight[1] {
            reflect(wv, vndf_sample(wv, self.alpha[1], u[0], u[1]))
        } else {
            cosine_hemisphere(u[0], u[1])
        };
        (wl[2] > 0.0 && wl.iter().all(|x| x.is_finite())).then_some(wl)
    }
}

fn normalize(v: [f32; 3]) -> [f32; 3] {
    let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    v.map(|x| x / l)
}

fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// wv reflected about h.
fn reflect(wv: [f32; 3], h: [f32; 3]) -> [f32; 3] {
    let d = 2.0 * dot(wv, h);
    [d * h[0] - wv[0], d * h[1] - wv[1], d * h[2] - wv[2]]
}

/// GGX's normal distribution at a half vector of cosine `c`.
fn ggx_d(c: f32, a: f32) -> f32 {
    let a2 = a * a;
    let t = c * c * (a2 - 1.0) + 1.0;
    a2 / (PI * t * t)
}

/// Smith's masking for GGX at cosine `mu`.
fn smith_g1(mu: f32, a: f32) -> f32 {
    2.0 * mu / (mu + (a * a * (1.0 - mu * mu) + mu * mu).sqrt())
}

/// The pdf of wl when h is drawn from GGX's visible normals at wv and wl = reflect(wv, h):
/// D_v(h) / (4 wv·h) = G1(wv)·D(h) / (4 μv).
fn vndf_pdf(wv: [f32; 3], wl: [f32; 3], a: f32) -> f32 {
    let h = normalize([wv[0] + wl[0], wv[1] + wl[1], wv[2] + wl[2]]);
    if h[2] <= 0.0 || dot(wv, h) <= 0.0 {
        return 0.0;
    }
    smith_g1(wv[2], a) * ggx_d(h[2], a) / (4.0 * wv[2])
}

/// ∂ ln vndf_pdf / ∂α at (wv, wl).
fn vndf_log_pdf_da(wv: [f32; 3], wl: [f32; 3], a: f32) -> f32 {
    let h = normalize([wv[0] + wl[0], wv[1] + wl[1], wv[2] + wl[2]]);
    let c2 = h[2] * h[2];
    let d = 2.0 / a - 4.0 * a * c2 / (c2 * (a * a - 1.0) + 1.0);
    let mu = wv[2];
    let s = (a * a * (1.0 - mu * mu) + mu * mu).sqrt();
    d - (a * (1.0 - mu * mu) / s) / (mu + s)
}

/// A visible normal of GGX (isotropic α) at wv, from two uniforms (Heitz 2018).
fn vndf_sample(wv: [f32; 3], a: f32, u1: f32, u2: f32) -> [f32; 3] {
    let vh = normalize([a * wv[0], a * wv[1], wv[2]]);
    let lensq = vh[0] * vh[0] + vh[1] * vh[1];
    let t1 = if lensq > 0.0 { [-vh[1] / lensq.sqrt(), vh[0] / lensq.sqrt(), 0.0] } else { [1.0, 0.0, 0.0] };
    let t2 = [vh[1] * t1[2] - vh[2] * t1[1], vh[2] * t1[0] - vh[0] * t1[2], vh[0] * t1[1] - vh[1] * t1[0]];
    let r = u1.sqrt();
    let phi = 2.0 * PI * u2;
    let (p1, mut p2) = (r * phi.cos(), r * phi.sin());
    let s = 0.5 * (1.0 + vh[2]);
    p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * p2;
    let p3 = (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt();
    let nh = [0, 1, 2].map(|k| p1 * t1[k] + p2 * t2[k] + p3 * vh[k]);
    normalize([a * nh[0], a * nh[1], nh[2].max(1e-7)])
}

/// One view's reference directions: wl per row, the density it was drawn with (½ p_stack +
/// ½ μl/π; 0 for a failed sample) and its normalised weight ŵ (Σ ŵ = 1 over the view's rows;
/// all 0 when the reference reflects nothing there).
pub struct ReferenceView {
    pub wv: [f32; 3],
    pub wl: Vec<[f32; 3]>,
    pub density: Vec<f32>,
    pub weight: Vec<f32>,
}

/// `m` reference directions for each parameter row (rows × the stack's parameters) at its view
/// `wv`: the first half from the stack's sampler, the rest cosine-weighted, each weighted by
/// Y(f·cos) over the two halves' mixture pdf (½ p_stack + ½ μl/π), normalised per row.
pub fn reference_views(generator: &DataGenerator, params: &[f32], wv: &[[f32; 3]], m: usize, key: u64) -> Result<Vec<ReferenceView>, String> {
    let n = generator.stack().len();
    let groups = wv.len();
    let half = (m / 2).max(1);
    let m = 2 * half;
    let rows = groups * m;
    let mut row_params = Vec::with_capacity(rows * n);
    let (mut row_wv, mut row_wl, mut u) = (Vec::with_capacity(rows), vec![[0.0f32, 0.0, 1.0]; rows], vec![[0.0f32; 3]; rows]);
    let (mut sampled, mut cosine) = (Vec::new(), Vec::new());
    for r in 0..rows {
        let (g, j) = (r / m, r % m);
        row_params.extend_from_slice(&params[g * n..(g + 1) * n]);
        row_wv.push(wv[g]);
        let k = mix64(key ^ mix64(r as u64));
        if j < half {
            u[r] = [unit(k), unit(k ^ 1), unit(k ^ 2)];
            sampled.push(r);
        } else {
            row_wl[r] = cosine_hemisphere(unit(k ^ 3), unit(k ^ 4));
            cosine.push(r);
        }
    }
    let engine = generator.engine();
    // Per row: (the stack's pdf at wl, luminance of f·cos); None: no usable direction.
    let mut at: Vec<Option<(f32, f32)>> = vec![None; rows];
    let luminance = |c: [f32; 3]| 0.2126 * c[0].max(0.0) + 0.7152 * c[1].max(0.0) + 0.0722 * c[2].max(0.0);
    let sample = generator.sample_kernel();
    let out = sample.run(engine, &row_params, &sampled, &[("wv", &row_wv), ("u", &u)])?;
    let (wl_at, pdf_at, resp_at) = (sample.output_offset("wl"), sample.output_offset("pdf"), sample.output_offset("response"));
    for (k, &r) in sampled.iter().enumerate() {
        let resp = vec3_at(&out, resp_at, k);
        let pdf = out.column(pdf_at)[k];
        if let Some(d) = usable_sample(vec3_at(&out, wl_at, k), pdf, 1e-4).filter(|_| resp.iter().all(|x| x.is_finite())) {
            row_wl[r] = d;
            at[r] = Some((pdf, luminance(resp)));
        }
    }
    let pdf_kernel = generator.pdf_kernel();
    let out = pdf_kernel.run(engine, &row_params, &cosine, &[("wv", &row_wv), ("wl", &row_wl)])?;
    let (pdf_at, resp_at) = (pdf_kernel.output_offset("pdf"), pdf_kernel.output_offset("response"));
    for (k, &r) in cosine.iter().enumerate() {
        let resp = vec3_at(&out, resp_at, k);
        let pdf = out.column(pdf_at)[k];
        if pdf.is_finite() && resp.iter().all(|x| x.is_finite()) {
            at[r] = Some((pdf.max(0.0), luminance(resp)));
        }
    }
    Ok((0..groups)
        .map(|g| {
            let range = g * m..(g + 1) * m;
            let density: Vec<f32> = range
                .clone()
                .map(|r| match at[r] {
                    Some((p, _)) if row_wl[r][2] > 0.0 => (0.5 * p + 0.5 * row_wl[r][2] * FRAC_1_PI).max(1e-12),
                    _ => 0.0,
                })
                .collect();
            let mut weight: Vec<f32> = range.clone().zip(&density).map(|(r, &d)| if d > 0.0 { at[r].map_or(0.0, |(_, y)| y) / d } else { 0.0 }).collect();
            let sum: f32 = weight.iter().sum();
            if sum > 0.0 && sum.is_finite() {
                weight.iter_mut().for_each(|w| *w /= sum);
            } else {
                weight.iter_mut().for_each(|w| *w = 0.0);
            }
            ReferenceView { wv: wv[g], wl: row_wl[range].to_vec(), density, weight }
        })
        .collect())
}

/// −Σ_j ŵ_j ln q(wl_j) of one view for raw outputs `o`, and ∂/∂o (added into `d`, scaled by
/// `scale`).
pub fn view_loss(o: &[f32], view: &ReferenceView, scale: f32, d: &mut [f32]) -> f32 {
    let mix = Mixture::from_outputs(o);
    let mut loss = 0.0f32;
    for (wl, &w) in view.wl.iter().zip(&view.weight) {
        if w <= 0.0 {
            continue;
        }
        let p = mix.lobe_pdfs(view.wv, *wl);
        let q = (mix.weight[0] * p[0] + mix.weight[1] * p[1] + mix.weight[2] * p[2]).max(1e-12);
        loss -= w * q.ln();
        // q = ε p_cos + (1 − ε) Σ s_k p_k: ∂ ln q/∂ logit_k = (1 − ε) s_k (p_k − Σ s p) / q.
        let s = softmax(o);
        let mean = s[0] * p[0] + s[1] * p[1] + s[2] * p[2];
        for k in 0..3 {
            d[k] -= scale * w * (1.0 - COSINE_FLOOR) * s[k] * (p[k] - mean) / q;
        }
        // ∂ ln q/∂ o_{3+k} = w_k p_k ∂ln p_k/∂α · ∂α/∂o.
        for k in 0..2 {
            if p[k] > 0.0 {
                let g = sigmoid(o[3 + k]);
                let da = (1.0 - ALPHA_MIN) * g * (1.0 - g);
                d[3 + k] -= scale * w * mix.weight[k] * p[k] / q * vndf_log_pdf_da(view.wv, *wl, mix.alpha[k]) * da;
            }
        }
    }
    loss
}

/// How to train the sampler.
#[derive(Clone, Debug)]
pub struct SamplerOptions {
    pub steps: u64,
    /// Views (parameter rows) per step.
    pub views: usize,
    /// Reference directions per view.
    pub directions: usize,
    pub lr_start: f64,
    pub lr_end: f64,
    pub seed: u64,
}

impl Default for SamplerOptions {
    fn default() -> Self {
        SamplerOptions { steps: 1500, views: 512, directions: 32, lr_start: 3e-3, lr_end: 1e-4, seed: 1 }
    }
}

/// The result of training: the network and its loss per step, averaged over windows of 50.
pub struct TrainedSampler {
    pub net: Mlp<f32>,
    pub history: Vec<(u64, f32)>,
    pub seconds: f64,
}

/// Trains the sampler for `model` (frozen) on `generator`'s classes.
pub fn train_sampler(model: &NeuralModel<f32>, generator: &DataGenerator, o: &SamplerOptions, progress: bool) -> Result<TrainedSampler, String> {
    let start = std::time::Instant::now();
    let latent = model.latent();
    let mut net = Mlp::<f32>::new(sampler_shape(latent), o.seed ^ 0x73616d70);
    // Start as mostly cosine with two mid-rough lobes: logits (0, 0, 1), α ≈ 0.3 and 0.6.
    let last = net.shape.layers() - 1;
    let (_, b) = net.shape.offsets(last);
    net.params[b + 2] = 1.0;
    net.params[b + 3] = -1.0;
    net.params[b + 4] = 0.5;
    let mut adam = Adam::new(net.params.len());
    let mut ws = Workspace::without_input_gradient();
    let mut history = Vec::new();
    let (mut window, mut count) = (0.0f32, 0u32);
    let bar = if progress { indicatif::ProgressBar::new(o.steps) } else { indicatif::ProgressBar::hidden() };
    bar.set_style(indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} steps, eta {eta} · {msg}").unwrap());
    for step in 0..o.steps {
        let batch = generator.batch(mix64(o.seed ^ 0x7361_6d70_6c65) ^ step, o.views)?;
        let z = crate::evaluate::encode(model, &batch.encoded);
        let views = reference_views(generator, &batch.params, &batch.wv, o.directions, mix64(o.seed) ^ mix64(step.wrapping_add(1)))?;
        let mut input = Vec::with_capacity(o.views * (latent + 1));
        for (g, v) in views.iter().enumerate() {
            sampler_input(&z[g * latent..(g + 1) * latent], v.wv[2], &mut input);
        }
        let out = net.forward(&input, o.views, &mut ws).to_vec();
        let mut d = vec![0.0f32; out.len()];
        let scale = 1.0 / o.views as f32;
        let mut loss = 0.0;
        for (g, v) in views.iter().enumerate() {
            loss += scale * view_loss(&out[g * SAMPLER_OUTPUTS..(g + 1) * SAMPLER_OUTPUTS], v, scale, &mut d[g * SAMPLER_OUTPUTS..(g + 1) * SAMPLER_OUTPUTS]);
        }
        if !loss.is_finite() {
            return Err(format!("the sampler's loss became {loss} at step {step}"));
        }
        let mut grads = vec![0.0f32; net.params.len()];
        net.backward(&input, &d, &mut ws, Some(&mut grads));
        adam.step(&mut net.params, &grads, cosine_lr(step, o.steps, o.lr_start, o.lr_end));
        window += loss;
        count += 1;
        if count == 50 || step + 1 == o.steps {
            history.push((step + 1, window / count as f32));
            bar.set_message(format!("loss {:.4}", window / count as f32));
            (window, count) = (0.0, 0);
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    Ok(TrainedSampler { net, history, seconds: start.elapsed().as_secs_f64() })
}

/// A sampling decoder for a latent of `latent` values that always answers the cosine lobe (its
/// last layer's weights 0, the cosine logit's bias far above the others): the baseline the
/// sampling decoder is measured against.
pub fn cosine_only(latent: usize) -> Mlp<f32> {
    let shape = sampler_shape(latent);
    let mut params = vec![0.0; shape.parameter_count()];
    let (_, b) = shape.offsets(shape.layers() - 1);
    params[b..b + SAMPLER_OUTPUTS].copy_from_slice(&[-40.0, -40.0, 40.0, 0.0, 0.0]);
    Mlp::from_params(shape, params).expect("the sampler's shape")
}

/// The input rows of (latent, μv) for latents of `latent` values each.
pub fn sampler_inputs(latents: &[f32], mu_v: &[f32], latent: usize) -> Vec<f32> {
    let mut input = Vec::with_capacity(mu_v.len() * (latent + 1));
    for (r, &mu) in mu_v.iter().enumerate() {
        sampler_input(&latents[r * latent..(r + 1) * latent], mu, &mut input);
    }
    input
}

/// The mixtures of rows of (latent, μv).
pub fn mixtures(net: &Mlp<f32>, latents: &[f32], mu_v: &[f32]) -> Vec<Mixture> {
    let input = sampler_inputs(latents, mu_v, net.shape.inputs() - 1);
    let out = net.forward(&input, mu_v.len(), &mut Workspace::without_input_gradient()).to_vec();
    out.chunks(SAMPLER_OUTPUTS).map(Mixture::from_outputs).collect()
}

/// A χ² test of a mixture's sampler against its own pdf at one view.
#[derive(Clone, Debug)]
pub struct ChiSquare {
    pub chi2: f64,
    /// Bins with an expected count over 20 (those the statistic sums).
    pub bins: usize,
    /// The pdf integrated over the hemisphere, and the fraction of samples kept (a GGX sample
    /// reflected below the horizon is lost, so the two agree, not 1).
    pub integral: f64,
    pub kept: f64,
}

impl ChiSquare {
    /// χ² within 5 standard deviations of its mean (the bin count), and the pdf's integral
    /// within 0.01 of the kept fraction.
    pub fn passes(&self) -> bool {
        self.chi2 < self.bins as f64 + 5.0 * (2.0 * self.bins as f64).sqrt() && (self.integral - self.kept).abs() < 0.01
    }
}

/// Draws `n` directions from `mix` at `wv` (seeded) into 12 × 16 bins of (cos θl, φl), and
/// compares the counts with the pdf integrated over each bin (a 96² midpoint grid per bin).
pub fn chi_square(mix: &Mixture, wv: [f32; 3], n: usize, seed: u64) -> ChiSquare {
    let (nt, np, sub) = (12usize, 16usize, 96usize);
    let mut counts = vec![0f64; nt * np];
    let mut kept = 0usize;
    for k in 0..n {
        let key = mix64(seed ^ mix64(k as u64));
        if let Some(wl) = mix.sample(wv, [unit(key), unit(key ^ 1), unit(key ^ 2)]) {
            let t = ((1.0 - wl[2]) * nt as f32).min(nt as f32 - 1.0) as usize;
            let phi = wl[1].atan2(wl[0]).rem_euclid(2.0 * PI);
            counts[t * np + ((phi / (2.0 * PI) * np as f32) as usize).min(np - 1)] += 1.0;
            kept += 1;
        }
    }
    let (mut chi2, mut integral, mut bins) = (0.0, 0.0, 0);
    for t in 0..nt {
        for p in 0..np {
            let mut e = 0.0f64;
            for a in 0..sub {
                for b in 0..sub {
                    let c = 1.0 - (t as f32 + (a as f32 + 0.5) / sub as f32) / nt as f32;
                    let phi = 2.0 * PI * (p as f32 + (b as f32 + 0.5) / sub as f32) / np as f32;
                    let s = (1.0 - c * c).max(0.0).sqrt();
                    e += mix.pdf(wv, [s * phi.cos(), s * phi.sin(), c]) as f64;
                }
            }
            // (cos θ, φ) measure is the solid angle.
            e *= (1.0 / nt as f64) * (2.0 * std::f64::consts::PI / np as f64) / (sub * sub) as f64;
            integral += e;
            let expected = e * n as f64;
            if expected > 20.0 {
                chi2 += (counts[t * np + p] - expected).powi(2) / expected;
                bins += 1;
            }
        }
    }
    ChiSquare { chi2, bins, integral, kept: kept as f64 / n as f64 }
}

#[cfg(test)]
mod tests {
    use super::*;
    use uplift_base::rng::SplitMix64;

    /// The mixture's sampler draws from its own pdf: a χ² test over (cos θl, φl) bins at several
    /// views (grazing included) and mixtures (sharp, rough, cosine-heavy).
    #[test]
    fn mixture_samples_follow_its_pdf() {
        for &mu_v in &[0.95f32, 0.5, 0.08] {
            let wv = [(1.0 - mu_v * mu_v).sqrt(), 0.0, mu_v];
            for mix in [Mixture { weight: [0.6, 0.3, 0.1], alpha: [0.08, 0.4] }, Mixture { weight: [0.2, 0.2, 0.6], alpha: [0.3, 0.9] }] {
                let t = chi_square(&mix, wv, 200_000, 5);
                assert!(t.passes(), "μv {mu_v} {mix:?}: {t:?}");
            }
        }
    }

    /// The loss's analytic gradient against central differences.
    #[test]
    fn view_loss_gradient_matches_central_differences() {
        let mut rng = SplitMix64::new(9);
        let wv = [0.6, 0.0, 0.8];
        let wl: Vec<[f32; 3]> = (0..16).map(|_| cosine_hemisphere(rng.unit(), rng.unit())).collect();
        let mut weight: Vec<f32> = (0..16).map(|_| rng.unit()).collect();
        let s: f32 = weight.iter().sum();
        weight.iter_mut().for_each(|w| *w /= s);
        let view = ReferenceView { wv, wl, density: vec![1.0; 16], weight };
        let o = [0.3f32, -0.2, 0.1, -0.5, 0.7];
        let mut d = [0.0f32; 5];
        view_loss(&o, &view, 1.0, &mut d);
        for k in 0..5 {
            let h = 1e-2f32;
            let (mut a, mut b) = (o, o);
            a[k] += h;
            b[k] -= h;
            let numeric = (view_loss(&a, &view, 1.0, &mut [0.0; 5]) - view_loss(&b, &view, 1.0, &mut [0.0; 5])) / (2.0 * h);
            assert!((numeric - d[k]).abs() <= 2e-3 * (1.0 + numeric.abs()), "output {k}: analytic {} vs central {numeric}", d[k]);
        }
    }
}
