//! The neural material model (lobes.md §4): the encoder (the stack's encoded parameters → 64 → 64 → 64
//! → latent, LeakyReLU hidden, sigmoid out, so latents are image-like values in (0, 1)) and the
//! universal decoder (latent + 9 direction features → 4 × 64 LeakyReLU → 7, exp head:
//! f RGB, T RGB, R). The latent width is the model's (the paper's 6 by default: two RGB
//! textures; `uplift train --latent N`), read back from a decoder's input width. One training slice runs encoder → jitter → decoder → Eq. 3 → back again;
//! latent fitting runs the frozen decoder alone and returns ∂loss/∂latent.

use crate::features::FEATURES;
use crate::loss::{eq3_loss, LossParts, LossWeights, OUTPUTS};
use crate::mlp::{Activation, Mlp, MlpShape, Real, Workspace};

/// The paper's latent width: two RGB textures (latent.exr's default).
pub const LATENT: usize = uplift_material::folder::LATENTS;

/// The widest latent a model may have: the widest latent.exr holds (and the renderer's
/// per-point storage).
pub const MAX_LATENT: usize = uplift_material::folder::MAX_LATENTS;

/// The encoder's shape for a stack of `parameters` parameters and `latent` latent values (lobes.md §4.2).
pub fn encoder_shape(parameters: usize, latent: usize) -> MlpShape {
    MlpShape { widths: vec![parameters, 64, 64, 64, latent], hidden: Activation::LEAKY_RELU, output: Activation::Sigmoid }
}

/// The decoder's shape for `latent` latent values (paper §4.1: 4 hidden layers of 64).
pub fn decoder_shape(latent: usize) -> MlpShape {
    MlpShape { widths: vec![latent + FEATURES, 64, 64, 64, 64, OUTPUTS], hidden: Activation::LEAKY_RELU, output: Activation::EXP_HEAD }
}

/// The latent width a decoder reads (its inputs less the direction features).
pub fn latent_width<T: Real>(decoder: &Mlp<T>) -> usize {
    decoder.shape.widths[0].saturating_sub(FEATURES)
}

/// Encoder and decoder.
#[derive(Clone, Debug)]
pub struct NeuralModel<T: Real> {
    pub encoder: Mlp<T>,
    pub decoder: Mlp<T>,
}

/// Per-thread buffers for one slice of a batch.
pub struct ModelWorkspace<T: Real> {
    pub enc: Workspace<T>,
    pub dec: Workspace<T>,
    pub dec_in: Vec<T>,
    pub d_out: Vec<T>,
    pub d_latent: Vec<T>,
}

/// One slice of a batch: the rows the loss sees.
pub struct Slice<'a, T> {
    /// Encoded parameters (rows × the stack's parameters) for training, or latents (rows × the latent width) for fitting.
    pub input: &'a [T],
    /// Added to the latent (rows × the latent width): the ±0.005 jitter.
    pub jitter: &'a [T],
    /// Direction features (rows × 9).
    pub features: &'a [T],
    /// f·μl RGB, T RGB, R (rows × 7).
    pub target: &'a [f32],
    pub mu_l: &'a [f32],
    /// Rows in the whole batch (the loss is a mean over it).
    pub batch: usize,
}

/// Rows per block of a slice: every layer's activations of a block (64 wide) take 128 KB, so a
/// block's forward and backward passes stay in a core's L2 cache.
pub const BLOCK_ROWS: usize = 512;

impl<'a, T> Slice<'a, T> {
    /// The slice in consecutive blocks of at most [`BLOCK_ROWS`] rows (same `batch`).
    pub fn blocks(&self) -> impl Iterator<Item = Slice<'a, T>> + '_ {
        let rows = self.mu_l.len();
        let per_row = |v: usize| v / rows.max(1);
        let (ni, nj, nf) = (per_row(self.input.len()), per_row(self.jitter.len()), per_row(self.features.len()));
        (0..rows).step_by(BLOCK_ROWS).map(move |a| {
            let b = (a + BLOCK_ROWS).min(rows);
            Slice {
                input: &self.input[a * ni..b * ni],
                jitter: &self.jitter[a * nj..b * nj],
                features: &self.features[a * nf..b * nf],
                target: &self.target[a * OUTPUTS..b * OUTPUTS],
                mu_l: &self.mu_l[a..b],
                batch: self.batch,
            }
        })
    }
}

impl<T: Real> Default for ModelWorkspace<T> {
    fn default() -> Self {
        // The encoder's input gradient (∂loss/∂parameters) is never needed.
        ModelWorkspace { enc: Workspace::without_input_gradient(), dec: Workspace::default(), dec_in: Vec::new(), d_out: Vec::new(), d_latent: Vec::new() }
    }
}

impl<T: Real> NeuralModel<T> {
    /// Xavier-uniform weights; the decoder's T and R output biases start at exp(b − 3) = ½, the
    /// middle of their range (from e⁻³ ≈ 0.05, the exp head's rate of change in log space would
    /// take thousands of steps at their small loss weights to get there).
    /// `parameters`: the stack's parameter count (the encoder's input width); `latent`: the
    /// latent width.
    pub fn new(parameters: usize, latent: usize, seed: u64) -> NeuralModel<T> {
        let mut decoder = Mlp::new(decoder_shape(latent), seed.wrapping_add(1));
        let last = decoder.shape.layers() - 1;
        let (_, b) = decoder.shape.offsets(last);
        for k in 3..OUTPUTS {
            decoder.params[b + k] = T::from_f64(3.0 + 0.5f64.ln());
        }
        NeuralModel { encoder: Mlp::new(encoder_shape(parameters, latent), seed), decoder }
    }

    /// The latent width.
    pub fn latent(&self) -> usize {
        latent_width(&self.decoder)
    }

    /// That the networks fit together: the encoder's output is the decoder's latent, of 1 to
    /// [`MAX_LATENT`] values, and the decoder has 7 outputs.
    pub fn check(&self) -> Result<(), String> {
        let (enc_out, dec_in) = (self.encoder.shape.outputs(), self.decoder.shape.inputs());
        if dec_in <= FEATURES || enc_out + FEATURES != dec_in {
            return Err(format!("the encoder's {enc_out} latent values do not fit the decoder's {dec_in} inputs ({FEATURES} of them direction features)"));
        }
        if enc_out > MAX_LATENT {
            return Err(format!("a latent of {enc_out} values (at most {MAX_LATENT})"));
        }
        if self.decoder.shape.outputs() != OUTPUTS {
            return Err(format!("the decoder has {} outputs, not {OUTPUTS}", self.decoder.shape.outputs()));
        }
        Ok(())
    }

    /// Encoder, jitter, decoder, Eq. 3 and back: adds the gradients of both networks. Runs in
    /// blocks of [`BLOCK_ROWS`] rows.
    pub fn train_slice(&self, s: &Slice<'_, T>, w: LossWeights, ws: &mut ModelWorkspace<T>, g_enc: &mut [T], g_dec: &mut [T]) -> LossParts {
        let mut parts = LossParts::default();
        for b in s.blocks() {
            parts.add(&self.train_block(&b, w, ws, g_enc, g_dec));
        }
        parts
    }

    fn train_block(&self, s: &Slice<'_, T>, w: LossWeights, ws: &mut ModelWorkspace<T>, g_enc: &mut [T], g_dec: &mut [T]) -> LossParts {
        let rows = s.mu_l.len();
        let latent = self.latent();
        let z = self.encoder.forward(s.input, rows, &mut ws.enc);
        fill_decoder_input(z, s.jitter, s.features, rows, latent, &mut ws.dec_in);
        let parts = decode_and_backward(&self.decoder, s, w, ws, Some(g_dec));
        let d_z = latent_gradient(&ws.d_latent, rows, latent);
        self.encoder.backward(s.input, &d_z, &mut ws.enc, Some(g_enc));
        parts
    }
}

/// Rows of [latent + jitter, features] (`latent` values per row of `z` and `jitter`).
pub fn fill_decoder_input<T: Real>(z: &[T], jitter: &[T], features: &[T], rows: usize, latent: usize, dec_in: &mut Vec<T>) {
    let inputs = latent + FEATURES;
    dec_in.resize(rows * inputs, T::default());
    for r in 0..rows {
        let row = &mut dec_in[r * inputs..(r + 1) * inputs];
        for k in 0..latent {
            row[k] = z[r * latent + k] + jitter[r * latent + k];
        }
        row[latent..].copy_from_slice(&features[r * FEATURES..(r + 1) * FEATURES]);
    }
}

/// The decoder forward on `ws.dec_in`, Eq. 3, and the decoder backward: adds the decoder's
/// gradient into `g_dec` and leaves ∂loss/∂(decoder input) in `ws.d_latent` (all its columns).
fn decode_and_backward<T: Real>(decoder: &Mlp<T>, s: &Slice<'_, T>, w: LossWeights, ws: &mut ModelWorkspace<T>, g_dec: Option<&mut [T]>) -> LossParts {
    let rows = s.mu_l.len();
    let out = decoder.forward(&ws.dec_in, rows, &mut ws.dec);
    ws.d_out.resize(rows * OUTPUTS, T::default());
    let parts = eq3_loss(out, s.target, s.mu_l, s.batch, w, &mut ws.d_out);
    let d_in = decoder.backward(&ws.dec_in, &ws.d_out, &mut ws.dec, g_dec);
    ws.d_latent.clear();
    ws.d_latent.extend_from_slice(d_in);
    parts
}

/// The latent columns of ∂loss/∂(decoder input).
fn latent_gradient<T: Real>(d_in: &[T], rows: usize, latent: usize) -> Vec<T> {
    let inputs = latent + FEATURES;
    (0..rows).flat_map(|r| d_in[r * inputs..r * inputs + latent].iter().copied()).collect()
}

/// Latent fitting against a frozen decoder: Eq. 3 of `decoder(latent + jitter, features)`;
/// returns the loss and ∂loss/∂latent (rows × the latent width). The decoder's weight gradients
/// are not computed.
pub fn latent_slice<T: Real>(decoder: &Mlp<T>, s: &Slice<'_, T>, w: LossWeights, ws: &mut ModelWorkspace<T>) -> (LossParts, Vec<T>) {
    let latent = latent_width(decoder);
    let mut parts = LossParts::default();
    let mut grad = Vec::with_capacity(s.mu_l.len() * latent);
    for b in s.blocks() {
        let rows = b.mu_l.len();
        fill_decoder_input(b.input, b.jitter, b.features, rows, latent, &mut ws.dec_in);
        parts.add(&decode_and_backward(decoder, &b, w, ws, None));
        grad.extend(latent_gradient(&ws.d_latent, rows, latent));
    }
    (parts, grad)
}

/// Decodes rows of [latent, features] into rows of 7 outputs.
pub fn decode<T: Real>(decoder: &Mlp<T>, dec_in: &[T], ws: &mut Workspace<T>) -> Vec<T> {
    let rows = dec_in.len() / decoder.shape.widths[0];
    decoder.forward(dec_in, rows, ws).to_vec()
}
