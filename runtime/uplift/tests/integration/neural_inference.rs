//! The emitted inference kernels against the trainer's forward pass (`NeuralModel` /
//! `Mlp::forward`), on 4,096 generated rows with the shipped decoder's weights:
//! - the committed Rust module runtime/neural/src/shipped_decoder.rs is what the template writes
//!   for runtime/weights/decoder.safetensors today, and its outputs agree within 1e-4 relative;
//! - the WGSL shader, run by wgpu (lavapipe without a GPU), agrees within 1e-4 relative.
//! - the same for the sampling decoder's network (`shipped_sampler.rs`, its WGSL), on rows of
//!   (encoder latent, μv) with μv down to grazing.

use crate::common;

use std::path::Path;
use uplift_neural::weights::source_name;
use uplift_neural::weights::{load_model, SHIPPED_DECODER};
use uplift_engines::cpu_engine::CpuEngine;
use uplift_neural::datagen::{ClassMix, DataGenerator};
use uplift_neural::evaluate::{decode, encode};
use uplift_neural::inference::{decoder_spec, WgpuDecoder};
use uplift_neural::model::LATENT;
use uplift_neural::shipped_decoder;
use uplift_neural::shipped_sampler;
use uplift_neural::weights::load_sampler;
use uplift_neural::mlp::Workspace;
use uplift_compiler::backend_neural::write_rust_decoder;

/// Rows of [latent, features] and the trainer's outputs for them.
fn rows() -> (Vec<f32>, Vec<f32>) {
    let model = load_model(Path::new(SHIPPED_DECODER), &uplift_engines::stack::Stack::builtin()).unwrap();
    let g = DataGenerator::new(CpuEngine::new().unwrap(), &uplift_engines::stack::Stack::builtin(), ClassMix::All, 51).unwrap();
    let b = g.batch(0, 4096).unwrap();
    let z = encode(&model, &b.encoded);
    let out = decode(&model, &z, &b.features);
    let dec_in = (0..b.rows).flat_map(|r| z[r * LATENT..(r + 1) * LATENT].iter().chain(&b.features[r * 9..(r + 1) * 9]).copied().collect::<Vec<_>>()).collect();
    (dec_in, out)
}

fn assert_agree(what: &str, got: &[f32], want: &[f32]) {
    assert_agree_above(what, got, want, 1e-6);
}

/// Relative agreement within 1e-4 of values at least `floor` in magnitude (below it, absolute
/// 1e-4·floor: the sampling decoder's logits cross zero, where a relative figure means nothing).
fn assert_agree_above(what: &str, got: &[f32], want: &[f32], floor: f32) {
    assert_eq!(got.len(), want.len(), "{what}: output count");
    let mut worst = 0.0f32;
    for (k, (g, w)) in got.iter().zip(want).enumerate() {
        let rel = (g - w).abs() / g.abs().max(w.abs()).max(floor);
        worst = worst.max(rel);
        assert!(rel <= 1e-4, "{what} output {k}: {g} vs the trainer's {w}");
    }
    eprintln!("{what}: worst relative difference to the trainer's forward pass {worst:.1e}");
}

#[test]
fn committed_rust_decoder_is_current_and_agrees() {
    let model = load_model(Path::new(SHIPPED_DECODER), &uplift_engines::stack::Stack::builtin()).unwrap();
    let text = write_rust_decoder(&decoder_spec(&model.decoder, &source_name(Path::new(SHIPPED_DECODER)))).unwrap();
    let committed = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../neural/src/shipped_decoder.rs")).unwrap();
    assert!(text == committed, "runtime/neural/src/shipped_decoder.rs is stale: run `cargo run --release -p uplift -- emit-decoder --rust runtime/neural/src/shipped_decoder.rs`");
    let (dec_in, want) = rows();
    assert_eq!(shipped_decoder::INPUTS, model.decoder.shape.inputs());
    assert_eq!(model.latent(), LATENT, "the shipped decoder has the paper's latent width");
    let mut got = vec![0.0f32; want.len()];
    shipped_decoder::decode_rows(&dec_in, &mut got);
    assert_agree("Rust (shipped_decoder.rs)", &got, &want);
}

#[test]
fn wgsl_decoder_agrees() {
    let model = load_model(Path::new(SHIPPED_DECODER), &uplift_engines::stack::Stack::builtin()).unwrap();
    let engine = common::engine();
    let d = WgpuDecoder::new(engine, &model.decoder, "runtime/weights/decoder.safetensors").unwrap();
    let (dec_in, want) = rows();
    let got = d.decode(engine, &dec_in).unwrap();
    assert_agree(&format!("WGSL on {}", engine.adapter_info.name), &got, &want);
}

/// Rows of (latent, μv) for the shipped sampling decoder and its forward pass on them.
fn sampler_rows() -> (uplift_neural::mlp::Mlp<f32>, Vec<f32>, Vec<f32>) {
    let model = load_model(Path::new(SHIPPED_DECODER), &uplift_engines::stack::Stack::builtin()).unwrap();
    let net = load_sampler(Path::new(SHIPPED_DECODER)).unwrap().expect("the shipped file holds a sampling decoder");
    let g = DataGenerator::new(CpuEngine::new().unwrap(), &uplift_engines::stack::Stack::builtin(), ClassMix::All, 52).unwrap();
    let b = g.batch(0, 2048).unwrap();
    let z = encode(&model, &b.encoded);
    let mut input = Vec::new();
    for r in 0..b.rows {
        let mu = 0.02 + 0.98 * (r % 64) as f32 / 63.0;
        uplift_neural::sampler::sampler_input(&z[r * LATENT..(r + 1) * LATENT], mu, &mut input);
    }
    let want = net.forward(&input, b.rows, &mut Workspace::without_input_gradient()).to_vec();
    (net, input, want)
}

#[test]
fn committed_rust_sampler_is_current_and_agrees() {
    let (net, input, want) = sampler_rows();
    let text = write_rust_decoder(&decoder_spec(&net, &format!("{} (sampling decoder)", source_name(Path::new(SHIPPED_DECODER))))).unwrap();
    let committed = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../neural/src/shipped_sampler.rs")).unwrap();
    assert!(text == committed, "runtime/neural/src/shipped_sampler.rs is stale: run `cargo run --release -p uplift -- emit-decoder --sampler --rust runtime/neural/src/shipped_sampler.rs`");
    assert_eq!((shipped_sampler::INPUTS, shipped_sampler::OUTPUTS), (net.shape.inputs(), net.shape.outputs()));
    let mut got = vec![0.0f32; want.len()];
    shipped_sampler::decode_rows(&input, &mut got);
    assert_agree_above("Rust (shipped_sampler.rs)", &got, &want, 0.01);
}

#[test]
fn wgsl_sampler_agrees() {
    let (net, input, want) = sampler_rows();
    let engine = common::engine();
    let d = WgpuDecoder::new(engine, &net, "runtime/weights/decoder.safetensors (sampling decoder)").unwrap();
    let got = d.decode(engine, &input).unwrap();
    assert_agree_above(&format!("sampler WGSL on {}", engine.adapter_info.name), &got, &want, 0.01);
}
