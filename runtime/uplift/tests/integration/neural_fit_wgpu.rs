//! Latent fitting on the wgpu engine (runtime/neural/src/wgpu_fit.rs: the decoder's forward and
//! backward passes and Eq. 3 as WGSL emitted from templates/neural_fit.wgsl) against the CPU
//! path, its oracle: the same loss and latent gradients per step, and the same fit.

use std::path::Path;
use std::sync::Arc;
use uplift_engines::batch::TextureData;
use uplift_engines::cpu_engine::CpuEngine;
use uplift_engines::stack::Stack;
use uplift_engines::wgpu_engine::WgpuEngine;
use uplift_enhance::pbr_input::{PbrChannel, PbrMaterial, Surface};
use uplift_enhance::pipeline::{enhance, EnhanceOptions};
use uplift_enhance::rules::EnhancementType;
use uplift_material::ParamsImage;
use uplift_neural::datagen::{ClassMix, DataGenerator};
use uplift_neural::fit::{fit_material, FitOptions};
use uplift_neural::loss::LossWeights;
use uplift_neural::model::{fill_decoder_input, latent_slice, latent_width, ModelWorkspace, Slice};
use uplift_neural::weights::{load_model, SHIPPED_DECODER};
use uplift_neural::wgpu_fit::WgpuLatentGradients;

/// 16,384 rows of every class (the shipped decoder, the encoder's latents with jitter): Eq. 3
/// per term within 1e-5 relative, and ∂loss/∂latent within 1e-4 of the largest gradient, but
/// for rows whose f, T or R lands on its target within float rounding (the ℓ1 loss's sign
/// flips there): at most 0.1 % of them.
#[test]
fn wgpu_latent_gradients_equal_the_cpu_ones() {
    let stack = Stack::builtin();
    let model = load_model(Path::new(SHIPPED_DECODER), &stack).unwrap();
    let g = DataGenerator::new(CpuEngine::new().unwrap(), &stack, ClassMix::All, 21).unwrap();
    let rows = 16384;
    let b = g.batch(0, rows).unwrap();
    let latent = latent_width(&model.decoder);
    let z = uplift_neural::evaluate::encode(&model, &b.encoded);
    let jit: Vec<f32> = (0..rows * latent).map(|k| 0.005 * (((k * 7919) % 201) as f32 / 100.0 - 1.0)).collect();
    let mut ws = ModelWorkspace::default();
    let s = Slice { input: &z, jitter: &jit, features: &b.features, target: &b.target, mu_l: &b.mu_l, batch: rows };
    let (cpu_loss, cpu_grad) = latent_slice(&model.decoder, &s, LossWeights::PAPER, &mut ws);
    let engine = WgpuEngine::new().unwrap_or_else(|e| panic!("{e}"));
    let k = WgpuLatentGradients::new(&engine, &model.decoder, latent, "shipped").unwrap();
    let mut dec_in = Vec::new();
    fill_decoder_input(&z, &jit, &b.features, rows, latent, &mut dec_in);
    let (gpu_loss, gpu_grad) = k.run(&engine, &dec_in, &b.target, &b.mu_l, LossWeights::PAPER).unwrap();
    eprintln!("Eq. 3: CPU {:.6} (f {:.6}, T {:.6}, R {:.6}), wgpu {:.6} (f {:.6}, T {:.6}, R {:.6})", cpu_loss.total, cpu_loss.f, cpu_loss.t, cpu_loss.r, gpu_loss.total, gpu_loss.f, gpu_loss.t, gpu_loss.r);
    for (name, a, b) in [("total", cpu_loss.total, gpu_loss.total), ("f", cpu_loss.f, gpu_loss.f), ("T", cpu_loss.t, gpu_loss.t), ("R", cpu_loss.r, gpu_loss.r)] {
        assert!((a - b).abs() <= 1e-5 * a.abs(), "Eq. 3 {name}: CPU {a} vs wgpu {b}");
    }
    let largest = cpu_grad.iter().fold(0.0f32, |m, x| m.max(x.abs()));
    let bad: Vec<usize> = (0..rows).filter(|r| (0..latent).any(|c| (cpu_grad[r * latent + c] - gpu_grad[r * latent + c]).abs() > 1e-4 * largest)).collect();
    eprintln!("∂loss/∂latent: {} of {rows} rows differ by more than 1e-4 of the largest gradient {largest:.3e}", bad.len());
    assert!(bad.len() * 1000 <= rows, "{} rows of {rows} differ, e.g. row {:?}", bad.len(), bad.first());
}

/// A 32² Type 2 material (textured base colour and roughness) fitted on both engines for 40
/// steps — on wgpu every step's data, the latents and Adam on the device (`DeviceFit`): the
/// first and last steps' losses within 0.1 %, the fitted latents' Eq. 3 (on the check texels)
/// within 1 % — the bound — and the latents themselves within 1e-3.
#[test]
fn a_material_fitted_on_wgpu_matches_the_cpu_fit() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("neural_fit_wgpu");
    let _ = std::fs::remove_dir_all(&dir);
    let texture = |seed: u64, lo: f32, hi: f32| {
        let mut rng = crate::common::Rng::new(seed);
        let px: Vec<f32> = (0..16).flat_map(|_| {
            let v = rng.range(lo, hi);
            [v, v * 0.8, v * 0.6, 1.0]
        }).collect();
        PbrChannel::Pixels(Arc::new(TextureData { width: 4, height: 4, rgba: px }))
    };
    let material = PbrMaterial { name: "m".into(), source: "test".into(), base_color: texture(1, 0.1, 0.8), roughness: texture(2, 0.2, 0.7), metalness: PbrChannel::Constant(vec![0.0]), normal_map: None, surface: Surface::Plane };
    let out = dir.join("m");
    let stack = Stack::builtin();
    let options = EnhanceOptions { kind: Some(EnhancementType::new(2).unwrap()), rules: Vec::new(), seed: 5, resolution: Some((32, 32)), mask_size: 64, glints: false, stack: stack.clone(), rule_options: Vec::new() };
    enhance(&material, &options, &out, &CpuEngine::new().unwrap()).unwrap();
    let ParamsImage { width: w, height: h, params, diffuse, .. } = uplift_material::MaterialFolder::open(&out).unwrap().read_params(&stack).unwrap();
    let model = load_model(Path::new(SHIPPED_DECODER), &stack).unwrap();
    let o = FitOptions { steps: 40, threads: 2, ..Default::default() };
    let fit = |engine: uplift_engines::prepared_kernel::AnyEngine| {
        let g = DataGenerator::new(engine, &stack, ClassMix::All, 3).unwrap();
        fit_material(&model, &g, &params, diffuse.as_deref(), w, h, &o, false).unwrap()
    };
    let cpu = fit(CpuEngine::new().unwrap().into());
    let gpu = fit(WgpuEngine::new().unwrap_or_else(|e| panic!("{e}")).into());
    eprintln!(
        "{} groups; Eq. 3 encoder only {:.5}; fitted on the CPU {:.5} ({:.1} s), on wgpu {:.5} ({:.1} s)",
        cpu.groups, cpu.before.total, cpu.after_unbounded.total, cpu.seconds, gpu.after_unbounded.total, gpu.seconds
    );
    // The step losses: the device's first step sees the CPU's latents on data the device
    // assembled (the same kernels, within float rounding), its last one its own latents.
    for (name, a, b) in [("first", cpu.first_step.total, gpu.first_step.total), ("last", cpu.last_step.total, gpu.last_step.total)] {
        eprintln!("Eq. 3 over the {name} step's rows: CPU {a:.6}, wgpu {b:.6}");
        assert!((a - b).abs() <= 1e-3 * a, "the {name} step's loss: CPU {a} vs wgpu {b}");
    }
    // (Whether 40 steps lower Eq. 3 is the CPU fitter's business: neural_decoder.rs.)
    let moved = cpu.latents.iter().zip(&gpu.latents).fold(0.0f32, |m, (a, b)| m.max((a - b).abs()));
    eprintln!("largest |latent on wgpu − on the CPU| over {} texel latents: {moved:.2e}", cpu.latents.len());
    assert!(moved <= 1e-3, "the engines' fitted latents differ by {moved:.2e}");
    let rel = (gpu.after_unbounded.total - cpu.after_unbounded.total).abs() / cpu.after_unbounded.total;
    assert!(rel <= 0.01, "fitted Eq. 3: wgpu {:.6} vs CPU {:.6} ({:.2} %)", gpu.after_unbounded.total, cpu.after_unbounded.total, 100.0 * rel);
    std::fs::remove_dir_all(&dir).unwrap();
}
