//! How well a model reproduces its reference: per class, on held-out batches (a generator seed
//! the training never draws), the relative L1 error of f·cos — Σ|f̂·μl − f·μl| / Σ|f·μl| over
//! rows and channels — and the mean absolute errors of T and R. Also the plain forward pass
//! (encoder → decoder, no jitter) that evaluation, fitting initialisation and inference share.

use crate::datagen::{ClassMix, DataGenerator, TrainingBatch};
use crate::features::FEATURES;
use crate::loss::OUTPUTS;
use crate::mlp::Workspace;
use crate::model::{fill_decoder_input, NeuralModel};

/// The seed offset of held-out data: training seeds never reach it.
pub const HOLDOUT_SEED: u64 = 0x686f_6c64_6f75_7400;

/// Errors of a model on one class.
#[derive(Clone, Debug)]
pub struct ClassError {
    /// The class's name.
    pub class: String,
    pub rows: usize,
    /// Σ|f̂·μl − f·μl| / Σ|f·μl|.
    pub fcos_relative_l1: f64,
    /// Mean |T̂ − T| and |R̂ − R|.
    pub t_l1: f64,
    pub r_l1: f64,
}

/// Latents of rows of encoded parameters.
pub fn encode(model: &NeuralModel<f32>, encoded: &[f32]) -> Vec<f32> {
    let rows = encoded.len() / model.encoder.shape.widths[0];
    model.encoder.forward(encoded, rows, &mut Workspace::without_input_gradient()).to_vec()
}

/// Decoder outputs (rows × 7) for latents (rows × the latent width) and features (rows × 9).
pub fn decode(model: &NeuralModel<f32>, latents: &[f32], features: &[f32]) -> Vec<f32> {
    let rows = features.len() / FEATURES;
    let mut dec_in = Vec::new();
    fill_decoder_input(latents, &vec![0.0; latents.len()], features, rows, model.latent(), &mut dec_in);
    model.decoder.forward(&dec_in, rows, &mut Workspace::default()).to_vec()
}

/// The errors of `outputs` (rows × 7) against a batch's targets.
pub fn batch_errors(class: &str, batch: &TrainingBatch, outputs: &[f32]) -> ClassError {
    let (mut num, mut den, mut t, mut r) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for k in 0..batch.rows {
        let (o, g) = (&outputs[k * OUTPUTS..(k + 1) * OUTPUTS], &batch.target[k * OUTPUTS..(k + 1) * OUTPUTS]);
        let mu = batch.mu_l[k] as f64;
        for c in 0..3 {
            num += (o[c] as f64 * mu - g[c] as f64).abs();
            den += (g[c] as f64).abs();
            t += (o[3 + c] as f64 - g[3 + c] as f64).abs() / 3.0;
        }
        r += (o[6] as f64 - g[6] as f64).abs();
    }
    let n = batch.rows.max(1) as f64;
    ClassError { class: class.to_string(), rows: batch.rows, fcos_relative_l1: num / den.max(1e-30), t_l1: t / n, r_l1: r / n }
}

/// The model's errors on `rows` held-out rows of every class (generated with `seed` +
/// [`HOLDOUT_SEED`]).
pub fn holdout_errors(model: &NeuralModel<f32>, generator: &mut DataGenerator, seed: u64, rows: usize) -> Result<Vec<ClassError>, String> {
    let (mix, s) = (generator.mix.clone(), generator.seed);
    let names: Vec<String> = generator.classes().names().iter().map(|n| n.to_string()).collect();
    let mut out = Vec::new();
    for class in &names {
        generator.mix = ClassMix::Only(class.clone());
        generator.seed = seed.wrapping_add(HOLDOUT_SEED);
        let batch = generator.batch(0, rows);
        generator.mix = mix.clone();
        generator.seed = s;
        let batch = batch?;
        let z = encode(model, &batch.encoded);
        out.push(batch_errors(class, &batch, &decode(model, &z, &batch.features)));
    }
    Ok(out)
}
