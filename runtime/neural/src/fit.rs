//! Per-material latent fitting (paper §4.3, lobes.md §4.4): the latent textures of an
//! enhanced material (the decoder's latent width: two RGB textures for the paper's 6) are optimised against the frozen decoder with Eq. 3 (and the ±0.005
//! jitter), starting from the encoder's latents.
//!
//! Texels are grouped by their parameter vector quantised to `levels` steps per encoded channel
//! (`levels` = 0: exact vectors), so identical — or, quantised, nearly identical — texels are
//! fitted once: each group gets a latent z_g, initialised from the encoder at the group's mean
//! parameters and fitted on direction pairs drawn afresh at every step like the training data
//! (cosine views; lights half uniform, half from the stack's sampler) with targets from the
//! compiled kernels (a fixed set lets six numbers overfit a few dozen directions of a sharp
//! lobe: measured, the fitted latents then lost to the encoder's on other directions). A texel's latent is then clamp(Enc(p_texel) + (z_g − Enc(p̄_g)), 0, 1): the
//! group's fitted correction on top of the encoder's own per-texel variation. Latents are
//! clamped to [0, 1] after every Adam step. The report compares the encoder-only and the fitted
//! latents on other directions at sampled texels with their own (unquantised) parameters.

use uplift_material::fit_record::{round_to, FIT_FORMAT};
use uplift_material::{EnergyRecord, FitRecord, LatentImage, LossRecord};
use crate::adam::{cosine_lr, Adam};
use crate::datagen::{DataGenerator, TrainingBatch};
use crate::energy_bound::{enforce_energy_bound, EnergyOptions, EnergyReport};
use crate::evaluate::{decode, encode};
use crate::loss::{eq3_loss, LossParts, LossWeights, OUTPUTS};
use crate::mlp::Mlp;
use crate::model::{latent_slice, latent_width, ModelWorkspace, NeuralModel, Slice};
use crate::wgpu_fit::DeviceFit;
use uplift_engines::stack_kernel::Engine;
use crate::trainer::jitter;
use uplift_base::rng::mix64;
use std::collections::HashMap;

/// How to fit.
#[derive(Clone, Debug)]
pub struct FitOptions {
    pub steps: u64,
    /// Direction pairs per group and step (drawn afresh every step).
    pub directions: usize,
    /// Quantisation steps per encoded channel for grouping texels (0: exact).
    pub levels: u32,
    pub lr_start: f64,
    pub lr_end: f64,
    pub jitter: f32,
    pub seed: u64,
    pub threads: usize,
    /// Texels and directions per texel of the before/after report.
    pub check_texels: usize,
    pub check_directions: usize,
    /// The energy bound after the Eq. 3 fit (energy_bound.rs); `None` skips it.
    pub energy: Option<EnergyOptions>,
}

impl Default for FitOptions {
    fn default() -> Self {
        FitOptions {
            steps: 200,
            directions: 8,
            levels: 16,
            lr_start: 5e-3,
            lr_end: 1e-4,
            jitter: 0.005,
            seed: 1,
            threads: std::thread::available_parallelism().map_or(1, |n| n.get()),
            check_texels: 2048,
            check_directions: 64,
            energy: Some(EnergyOptions::default()),
        }
    }
}

/// Adam over rows of latents, and per-thread workspaces.
#[derive(Default)]
pub struct FitBuffers {
    workspaces: Vec<ModelWorkspace<f32>>,
    adam: Option<Adam>,
    jitter: Vec<f32>,
}

/// ∂(Eq. 3)/∂latent for rows of latents (rows × the latent width, jitter added), over `threads` slices.
fn latent_gradients(decoder: &Mlp<f32>, latents: &[f32], jit: &[f32], features: &[f32], target: &[f32], mu_l: &[f32], threads: usize, ws: &mut Vec<ModelWorkspace<f32>>) -> (LossParts, Vec<f32>) {
    let rows = mu_l.len();
    let latent = latent_width(decoder);
    let threads = threads.clamp(1, rows.max(1));
    ws.resize_with(threads, ModelWorkspace::default);
    let per = rows.div_ceil(threads);
    let parts: Vec<(LossParts, Vec<f32>)> = std::thread::scope(|scope| {
        let handles: Vec<_> = ws
            .iter_mut()
            .enumerate()
            .map(|(t, w)| {
                let (a, b) = ((t * per).min(rows), ((t + 1) * per).min(rows));
                scope.spawn(move || {
                    if a == b {
                        return (LossParts::default(), Vec::new());
                    }
                    let s = Slice { input: &latents[a * latent..b * latent], jitter: &jit[a * latent..b * latent], features: &features[a * 9..b * 9], target: &target[a * 7..b * 7], mu_l: &mu_l[a..b], batch: rows };
                    latent_slice(decoder, &s, LossWeights::PAPER, w)
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().expect("a fitting thread panicked")).collect()
    });
    let mut loss = LossParts::default();
    let mut grad = Vec::with_capacity(rows * latent);
    for (p, g) in parts {
        loss.add(&p);
        grad.extend_from_slice(&g);
    }
    (loss, grad)
}

/// One Adam step on latents, then the clamp to [0, 1].
fn adam_clamped(adam: &mut Adam, z: &mut [f32], g: &[f32], lr: f32) {
    adam.step(z, g, lr);
    z.iter_mut().for_each(|x| *x = x.clamp(0.0, 1.0));
}

/// One fitting step in which every row has its own latent (the benchmark's unit of work; the
/// material fit shares a latent over a group's rows).
#[allow(clippy::too_many_arguments)]
pub fn fit_step_rows(decoder: &Mlp<f32>, latents: &mut [f32], features: &[f32], target: &[f32], mu_l: &[f32], step: u64, lr: f32, threads: usize, buf: &mut FitBuffers) -> LossParts {
    let rows = mu_l.len();
    jitter(0, step, rows * latent_width(decoder), 0.005, &mut buf.jitter);
    let (loss, g) = latent_gradients(decoder, latents, &buf.jitter, features, target, mu_l, threads, &mut buf.workspaces);
    let adam = buf.adam.get_or_insert_with(|| Adam::new(latents.len()));
    adam_clamped(adam, latents, &g, lr);
    loss
}

/// The result of fitting one material.
#[derive(Clone, Debug)]
pub struct FitResult {
    pub width: usize,
    pub height: usize,
    /// texels × `latent`.
    pub latents: Vec<f32>,
    /// Latent values per texel (the decoder's latent width).
    pub latent: usize,
    pub groups: usize,
    /// Eq. 3 at the check texels: encoder-only latents, fitted latents (after the energy bound),
    /// and the Eq. 3 fit before the bound moved it (equal to `after` without the bound).
    pub before: LossParts,
    pub after: LossParts,
    pub after_unbounded: LossParts,
    /// Loss over the step's directions at the first and last step.
    pub first_step: LossParts,
    pub last_step: LossParts,
    /// What the energy bound did (when it ran).
    pub energy: Option<EnergyReport>,
    pub seconds: f64,
}

/// Fits the latents of a material whose texels have parameters `params` (texels × the
/// generator's stack's parameters) and
/// diffuse colour `diffuse` (texels × 3; the energy bound assumes c = 1 when it is `None`).
#[allow(clippy::too_many_arguments)]
pub fn fit_material(model: &NeuralModel<f32>, generator: &DataGenerator, params: &[f32], diffuse: Option<&[f32]>, width: usize, height: usize, o: &FitOptions, progress: bool) -> Result<FitResult, String> {
    let start = std::time::Instant::now();
    let n = width * height;
    let stack = generator.stack();
    let model_width = model.encoder.shape.widths[0];
    if model_width != stack.len() {
        return Err(format!("the decoder's encoder reads {model_width} parameters; the stack has {}", stack.len()));
    }
    let np = stack.len();
    let latent = model.latent();
    if params.len() != n * np {
        return Err(format!("{} parameter values for {width}×{height} texels", params.len()));
    }
    if let Some(d) = diffuse {
        if d.len() != n * 3 {
            return Err(format!("{} diffuse colour values for {width}×{height} texels", d.len()));
        }
        if let Some(k) = d.iter().position(|x| !x.is_finite()) {
            return Err(format!("texel {} diffuse colour channel {} is not finite", k / 3, k % 3));
        }
    }
    if let Some(k) = params.iter().position(|x| !x.is_finite()) {
        return Err(format!("texel {} parameter {} is not finite", k / np, k % np));
    }
    let mut encoded = vec![0.0; params.len()];
    stack.encode_rows(params, &mut encoded);
    // Groups of texels by quantised encoded parameters.
    let mut group_of = vec![0u32; n];
    let mut index: HashMap<Vec<u32>, u32> = HashMap::new();
    let mut sums: Vec<(Vec<f64>, usize)> = Vec::new();
    for t in 0..n {
        let e = &encoded[t * np..(t + 1) * np];
        let key: Vec<u32> = if o.levels == 0 { e.iter().map(|x| x.to_bits()).collect() } else { e.iter().map(|x| (x.clamp(0.0, 1.0) * o.levels as f32).round() as u32).collect() };
        let next = sums.len() as u32;
        let g = *index.entry(key).or_insert(next);
        if g == next {
            sums.push((vec![0.0; np], 0));
        }
        let s = &mut sums[g as usize];
        for (a, x) in s.0.iter_mut().zip(&params[t * np..(t + 1) * np]) {
            *a += *x as f64;
        }
        s.1 += 1;
        group_of[t] = g;
    }
    let groups = sums.len();
    let mean: Vec<f32> = sums.iter().flat_map(|(s, c)| s.iter().map(move |x| (x / *c as f64) as f32)).collect();
    let mut mean_encoded = vec![0.0; mean.len()];
    stack.encode_rows(&mean, &mut mean_encoded);
    let z0 = encode(model, &mean_encoded);
    // Each step draws fresh direction pairs for every group (a fixed set lets six latent
    // numbers overfit a few dozen directions of a sharp lobe).
    let d = o.directions.max(1);
    let rows = groups * d;
    let rows_params: Vec<f32> = (0..rows).flat_map(|r| mean[(r / d) * np..(r / d + 1) * np].to_vec()).collect();
    let mut z = z0.clone();
    let mut adam = Adam::new(z.len());
    let mut ws = Vec::new();
    let mut jit = Vec::new();
    let bar = if progress { indicatif::ProgressBar::new(o.steps) } else { indicatif::ProgressBar::hidden() };
    bar.set_style(indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} steps, eta {eta} · {msg}").unwrap());
    let (mut first_step, mut last_step) = (LossParts::default(), LossParts::default());
    let mut row_latents = vec![0.0f32; rows * latent];
    // A generator on the wgpu engine fits there too (wgpu_fit.rs): each step's rows assembled
    // on the device from the groups' parameters by the same kernels, Eq. 3 and its gradient,
    // Adam on the groups' latents — only the draws go up and the loss comes down.
    let mut on_wgpu = match generator.engine() {
        Engine::Wgpu(e) => Some((e, DeviceFit::new(e, generator, &model.decoder, latent, &rows_params, d, &z)?)),
        Engine::Cpu(_) => None,
    };
    for step in 0..o.steps {
        let key = mix64(o.seed ^ 0x6669_74) ^ mix64(step);
        jitter(o.seed, step, rows * latent, o.jitter, &mut jit);
        let lr = cosine_lr(step, o.steps, o.lr_start, o.lr_end);
        let loss = match &mut on_wgpu {
            Some((e, fit)) => fit.step(e, generator, key, &jit, lr, LossWeights::PAPER)?,
            None => {
                let data: TrainingBatch = generator.evaluate(rows_params.clone(), key)?;
                for r in 0..rows {
                    row_latents[r * latent..(r + 1) * latent].copy_from_slice(&z[(r / d) * latent..(r / d + 1) * latent]);
                }
                let (loss, g) = latent_gradients(&model.decoder, &row_latents, &jit, &data.features, &data.target, &data.mu_l, o.threads, &mut ws);
                let mut gz = vec![0.0f32; z.len()];
                for r in 0..rows {
                    for k in 0..latent {
                        gz[(r / d) * latent + k] += g[r * latent + k];
                    }
                }
                adam_clamped(&mut adam, &mut z, &gz, lr);
                loss
            }
        };
        if step == 0 {
            first_step = loss;
        }
        last_step = loss;
        bar.inc(1);
        bar.set_message(format!("loss {:.4}", loss.total));
    }
    if let Some((e, fit)) = &on_wgpu {
        z = fit.latents(e)?;
    }
    bar.finish_and_clear();
    let z_unbounded = z.clone();
    let energy = match &o.energy {
        Some(e) => {
            // The bound holds for the brightest diffuse colour of each group.
            let mut c = vec![0.0f32; groups * 3];
            for t in 0..n {
                let g = group_of[t] as usize;
                for k in 0..3 {
                    c[g * 3 + k] = c[g * 3 + k].max(diffuse.map_or(1.0, |d| d[t * 3 + k]));
                }
            }
            Some(enforce_energy_bound(&model.decoder, generator, &mean, &c, &mut z, o.threads, &EnergyOptions { seed: o.seed, ..e.clone() })?)
        }
        None => None,
    };
    // Texel latents: the encoder's, moved by the group's correction.
    let enc = encode(model, &encoded);
    let texel_latents = |z: &[f32]| -> Vec<f32> {
        let mut latents = vec![0.0f32; n * latent];
        for t in 0..n {
            let g = group_of[t] as usize;
            for k in 0..latent {
                latents[t * latent + k] = (enc[t * latent + k] + z[g * latent + k] - z0[g * latent + k]).clamp(0.0, 1.0);
            }
        }
        latents
    };
    let latents = texel_latents(&z);
    // Before/after at sampled texels, on other directions, with their own parameters.
    let checks: Vec<usize> = (0..o.check_texels.min(n).max(1)).map(|k| if o.check_texels >= n { k } else { (mix64(o.seed ^ 0x636b ^ k as u64) % n as u64) as usize }).collect();
    let cd = o.check_directions.max(1);
    let check_params: Vec<f32> = checks.iter().flat_map(|&t| (0..cd).flat_map(move |_| params[t * np..(t + 1) * np].to_vec())).collect();
    let check = generator.evaluate(check_params, mix64(o.seed ^ 0x6368_6563_6b))?;
    let lat = |src: &[f32]| -> Vec<f32> { checks.iter().flat_map(|&t| (0..cd).flat_map(move |_| src[t * latent..(t + 1) * latent].to_vec())).collect() };
    let loss_of = |z: &[f32]| {
        let out = decode(model, z, &check.features);
        let mut d = vec![0.0f32; out.len()];
        eq3_loss(&out, &check.target, &check.mu_l, check.rows, LossWeights::PAPER, &mut d)
    };
    let before = loss_of(&lat(&enc));
    let after = loss_of(&lat(&latents));
    let after_unbounded = if energy.is_some() { loss_of(&lat(&texel_latents(&z_unbounded))) } else { after };
    debug_assert_eq!(OUTPUTS, 7);
    Ok(FitResult { width, height, latents, latent, groups, before, after, after_unbounded, first_step, last_step, energy, seconds: start.elapsed().as_secs_f64() })
}

impl FitResult {
    /// The fit's record for the material folder's fit.json (`decoder` names the weights it was
    /// fitted against; losses to 6 decimals, time to 0.01 s).
    pub fn record(&self, decoder: &std::path::Path, o: &FitOptions) -> FitRecord {
        let loss = |p: &LossParts| LossRecord::new(p.total, p.f, p.t, p.r);
        FitRecord {
            format: FIT_FORMAT,
            decoder: decoder.display().to_string(),
            texels: self.width * self.height,
            groups: self.groups,
            steps: o.steps,
            directions: o.directions,
            levels: o.levels,
            seconds: round_to(self.seconds, 2),
            eq3_encoder_only: loss(&self.before),
            eq3_fitted: loss(&self.after),
            eq3_fitted_before_energy_bound: loss(&self.after_unbounded),
            fitting_loss_first_step: loss(&self.first_step),
            fitting_loss_last_step: loss(&self.last_step),
            energy_bound: self.energy.as_ref().map(|e| EnergyRecord::new(e.groups, e.over_before, e.over_after, e.worst_before.into(), e.worst_after.into(), e.steps)),
        }
    }

    /// The fitted latents as latent.exr holds them.
    pub fn latent_image(&self) -> LatentImage {
        LatentImage { width: self.width, height: self.height, channels: self.latent, latents: self.latents.clone() }
    }
}
