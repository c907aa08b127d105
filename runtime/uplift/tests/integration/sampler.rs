//! The sampling decoder shipped in runtime/weights/decoder.safetensors (uplift_neural::sampler):
//! at the encoder's latents of every training class, its mixtures sample their own pdf (χ² at
//! views down to grazing); f̂·cos/q averaged over its samples gives the decoder's albedo (against
//! an estimate from the stack's sampler and the cosine lobe, within 0.01); and a neural render
//! sampled by it has less error at equal samples per pixel than one sampling the non-diffuse part
//! by the cosine lobe, and converges to the image the stack's sampler converges to (within the
//! FLIP noise floor of two renders by one sampler).

use super::common::stack_params;
use std::path::Path;
use uplift_engines::cpu_engine::CpuEngine;
use uplift_engines::stack::Stack;
use uplift_neural::datagen::{ClassMix, DataGenerator};
use uplift_neural::evaluate::{decode, encode};
use uplift_neural::features::direction_features;
use uplift_neural::mlp::Mlp;
use uplift_neural::sampler::{chi_square, mixtures, reference_views, Mixture, SAMPLER_OUTPUTS};
use uplift_neural::weights::{load_model, load_sampler, SHIPPED_DECODER};
use uplift_render::environment::Environment;
use uplift_render::integrator::{render, RenderOptions};
use uplift_render::metrics::{default_pixels_per_degree, flip_ldr};
use uplift_render::scene::Sphere;
use uplift_render::shading::{Model, Shading};
use uplift_render::surface::SurfaceTextures;
use uplift_render::tonemap::to_display;
use uplift_base::rng::{mix64, unit_from_key as unit};

fn shipped_sampler() -> Mlp<f32> {
    load_sampler(Path::new(SHIPPED_DECODER)).unwrap().expect("the shipped decoder file has a sampling decoder (uplift train-sampler)")
}

fn view(mu: f32) -> [f32; 3] {
    [(1.0 - mu * mu).sqrt(), 0.0, mu]
}

/// Rows of each training class: (class, parameters, encoded latents).
fn class_rows(rows: usize) -> Vec<(String, DataGenerator, Vec<f32>, Vec<f32>)> {
    let stack = Stack::builtin();
    let model = load_model(Path::new(SHIPPED_DECODER), &stack).unwrap();
    let names: Vec<String> = DataGenerator::new(CpuEngine::new().unwrap(), &stack, ClassMix::All, 3).unwrap().classes().names().into_iter().map(String::from).collect();
    names
        .into_iter()
        .map(|name| {
            let g = DataGenerator::new(CpuEngine::new().unwrap(), &stack, ClassMix::Only(name.clone()), 3).unwrap();
            let b = g.batch(7, rows).unwrap();
            let z = encode(&model, &b.encoded);
            (name, g, b.params, z)
        })
        .collect()
}

#[test]
fn its_mixtures_sample_their_own_pdf_per_class() {
    let sampler = shipped_sampler();
    let latent = sampler.shape.inputs() - 1;
    for (class, _, _, z) in class_rows(2) {
        for &mu in &[0.95f32, 0.5, 0.12] {
            for r in 0..2 {
                let m = mixtures(&sampler, &z[r * latent..(r + 1) * latent], &[mu])[0];
                let t = chi_square(&m, view(mu), 100_000, 11 + r as u64);
                eprintln!("{class} row {r} μv {mu}: {m:?}: χ² {:.1} over {} bins, ∫pdf {:.4} (kept {:.4})", t.chi2, t.bins, t.integral, t.kept);
                assert!(t.passes(), "{class} row {r} μv {mu}: {m:?}: {t:?}");
            }
        }
    }
}

#[test]
fn the_estimator_over_its_samples_gives_the_decoder_albedo() {
    let sampler = shipped_sampler();
    let model = load_model(Path::new(SHIPPED_DECODER), &Stack::builtin()).unwrap();
    let latent = model.latent();
    let n = 65536;
    let mut worst = 0.0f32;
    for (class, g, params, z) in class_rows(2) {
        let np = g.stack().len();
        for &mu in &[0.9f32, 0.1] {
            for r in 0..2 {
                let zr = &z[r * latent..(r + 1) * latent];
                let wv = view(mu);
                // Over the sampler's samples: f̂·μl / q (a lost sample counts 0).
                let m = mixtures(&sampler, zr, &[mu])[0];
                let drawn: Vec<Option<[f32; 3]>> = (0..n).map(|k| {
                    let key = mix64(0x5a ^ mix64(k as u64 + 1000 * r as u64));
                    m.sample(wv, [unit(key), unit(key ^ 1), unit(key ^ 2)])
                }).collect();
                let wl: Vec<[f32; 3]> = drawn.iter().map(|d| d.unwrap_or([0.0, 0.0, 1.0])).collect();
                let f = decode_at(&model, zr, wv, &wl);
                let mut by_sampler = [0.0f64; 3];
                for (k, d) in drawn.iter().enumerate() {
                    if let Some(l) = d {
                        let q = m.pdf(wv, *l) as f64;
                        for c in 0..3 {
                            by_sampler[c] += f[k * 7 + c] as f64 * l[2] as f64 / q / n as f64;
                        }
                    }
                }
                // Over the stack's sampler and the cosine lobe (balance heuristic), 2× the samples.
                let v = &reference_views(&g, &params[r * np..(r + 1) * np], &[wv], 2 * n, 0xbeef + r as u64).unwrap()[0];
                let f = decode_at(&model, zr, wv, &v.wl);
                let mut by_reference = [0.0f64; 3];
                for (k, (l, &d)) in v.wl.iter().zip(&v.density).enumerate() {
                    if d > 0.0 {
                        for c in 0..3 {
                            by_reference[c] += f[k * 7 + c] as f64 * l[2] as f64 / d as f64 / v.wl.len() as f64;
                        }
                    }
                }
                for c in 0..3 {
                    let e = (by_sampler[c] - by_reference[c]).abs() as f32;
                    worst = worst.max(e);
                    assert!(e <= 0.01, "{class} row {r} μv {mu} channel {c}: {:.4} by the sampler, {:.4} by the stack's sampler ({m:?})", by_sampler[c], by_reference[c]);
                }
            }
        }
    }
    eprintln!("largest |albedo by the sampling decoder − by the stack's sampler|: {worst:.4}");
}

/// Decoder outputs (rows × 7) at one latent and view for each wl.
fn decode_at(model: &uplift_neural::model::NeuralModel<f32>, z: &[f32], wv: [f32; 3], wl: &[[f32; 3]]) -> Vec<f32> {
    let latents: Vec<f32> = wl.iter().flat_map(|_| z.iter().copied()).collect();
    let features: Vec<f32> = wl.iter().flat_map(|l| direction_features(wv, *l)).collect();
    decode(model, &latents, &features)
}

/// The library's cosine-lobe-only sampler: its mixture is the cosine lobe.
fn cosine_only(latent: usize) -> Mlp<f32> {
    let net = uplift_neural::sampler::cosine_only(latent);
    let (_, b) = net.shape.offsets(net.shape.layers() - 1);
    assert!(Mixture::from_outputs(&net.params[b..b + SAMPLER_OUTPUTS]).weight[2] > 0.9999);
    net
}

#[test]
fn renders_sampled_by_it_have_less_error_and_converge() {
    let stack = Stack::builtin();
    let model = load_model(Path::new(SHIPPED_DECODER), &stack).unwrap();
    let sampler = shipped_sampler();
    let env = Environment::studio();
    let shading = |s: Option<Mlp<f32>>| {
        let sh = Shading::new(CpuEngine::new().unwrap(), &stack, Model::Neural(model.decoder.clone())).unwrap();
        match s {
            Some(s) => sh.with_sampler(s).unwrap(),
            None => sh,
        }
    };
    let (by_sampler, by_cosine, by_stack) = (shading(Some(sampler.clone())), shading(Some(cosine_only(model.latent()))), shading(None));
    let materials = [
        ("glossy metal", stack_params(&[("metalness", 1.0), ("core_roughness", 0.12)])),
        ("hazy dielectric", stack_params(&[("core_roughness", 0.08), ("haze_weight", 0.4), ("haze_roughness", 0.35)])),
    ];
    for (name, p) in materials {
        let mut enc = vec![0.0; p.len()];
        stack.encode_rows(&p, &mut enc);
        let z = encode(&model, &enc);
        let surface = SurfaceTextures::uniform(&p, [0.3, 0.3, 0.3], Some(&z));
        // Direct lighting (MIS with the environment), where the non-diffuse sampler matters.
        let o = |spp, seed| RenderOptions { width: 24, height: 24, spp, bounces: 0, seed, ..Default::default() };
        let converged = render(&Sphere::preview(), &env, &surface, &by_stack, &o(4096, 1), None).unwrap();
        let mse = |shading: &Shading| -> f64 {
            let img = render(&Sphere::preview(), &env, &surface, shading, &o(16, 2), None).unwrap();
            img.radiance.iter().zip(&converged.radiance).map(|(a, b)| (0..3).map(|c| ((a[c] - b[c]) as f64).powi(2)).sum::<f64>()).sum::<f64>() / img.radiance.len() as f64
        };
        let (e_sampler, e_cosine) = (mse(&by_sampler), mse(&by_cosine));
        let high = render(&Sphere::preview(), &env, &surface, &by_sampler, &o(4096, 3), None).unwrap();
        let flip_to = |img: &uplift_render::integrator::Rendering| flip_ldr(&to_display(&converged.radiance, 1.0), &to_display(&img.radiance, 1.0), 24, 24, default_pixels_per_degree()).unwrap().mean();
        let flip = flip_to(&high);
        eprintln!("{name}: 16 spp squared error, sampling decoder {e_sampler:.3e}, cosine {e_cosine:.3e} (ratio {:.2}); at 4096 spp FLIP to the stack sampler's image {flip:.4}", e_cosine / e_sampler);
        assert!(e_sampler < e_cosine, "{name}: the sampling decoder's error {e_sampler:.3e} is not below the cosine lobe's {e_cosine:.3e}");
        // At 24² under the studio's small bright lights, two 4,096-spp renders by the stack's
        // own sampler at two seeds differ by FLIP 0.0113–0.0114 (measured on both materials): the
        // noise floor. The sampling decoder's render converges to the same image when it lies
        // within 1.3× that floor (measured 0.0107 and 0.0112; a render that converged elsewhere lies
        // far beyond).
        assert!(flip <= 0.015, "{name}: at 4096 spp the sampling decoder's render is FLIP {flip:.4} from the stack sampler's (noise floor 0.0113)");
    }
}
