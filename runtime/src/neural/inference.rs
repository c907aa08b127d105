//! Decoder inference on the CPU from the trainer's own forward pass: rows of [latent, direction
//! features] → rows of (f RGB, T RGB, R), split over threads in contiguous slices, each slice in
//! blocks so the activations stay in cache.

use super::loss::OUTPUTS;
use super::mlp::{Mlp, Workspace};
use super::model::DECODER_INPUTS;

/// Rows per block of one thread.
const BLOCK: usize = 1024;

/// Decodes `dec_in` (rows × 15) into `out` (rows × 7) on `threads` threads.
pub fn decode_parallel(decoder: &Mlp<f32>, dec_in: &[f32], out: &mut [f32], threads: usize) {
    let rows = dec_in.len() / DECODER_INPUTS;
    assert_eq!(out.len(), rows * OUTPUTS, "output rows");
    let threads = threads.clamp(1, rows.div_ceil(BLOCK).max(1));
    let per = rows.div_ceil(threads);
    std::thread::scope(|scope| {
        for (t, chunk) in out.chunks_mut(per * OUTPUTS).enumerate() {
            let input = &dec_in[t * per * DECODER_INPUTS..(t * per + chunk.len() / OUTPUTS) * DECODER_INPUTS];
            scope.spawn(move || {
                let mut ws = Workspace::default();
                for (i, o) in input.chunks(BLOCK * DECODER_INPUTS).zip(chunk.chunks_mut(BLOCK * OUTPUTS)) {
                    o.copy_from_slice(decoder.forward(i, i.len() / DECODER_INPUTS, &mut ws));
                }
            });
        }
    });
}
