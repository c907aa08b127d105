//! The trainer's analytic gradients against central finite differences, in f64, on random small
//! networks of the model's structure (encoder → jitter → decoder → Eq. 3): every weight and
//! bias of both networks, the encoder's inputs and the direction features agree within 1e-4
//! relative (relative to the larger of the two values, with a floor of 1e-5 of the largest
//! gradient so that near-zero entries compare absolutely). Latents of the paper's width (6) and
//! a wider one (8).

use crate::common;

use common::Rng;
use uplift_neural::loss::LossWeights;
use uplift_neural::mlp::{Activation, Mlp, MlpShape};
use uplift_neural::features::FEATURES;
use uplift_neural::model::{latent_slice, ModelWorkspace, NeuralModel, Slice, LATENT};

const ROWS: usize = 7;

struct Case {
    input: Vec<f64>,
    jitter: Vec<f64>,
    features: Vec<f64>,
    target: Vec<f32>,
    mu_l: Vec<f32>,
}

fn random_case(rng: &mut Rng, inputs: usize, latent: usize) -> Case {
    let v = |rng: &mut Rng, n: usize, lo: f32, hi: f32| (0..n).map(|_| rng.range(lo, hi) as f64).collect::<Vec<f64>>();
    Case {
        input: v(rng, ROWS * inputs, -1.0, 1.0),
        jitter: v(rng, ROWS * latent, -0.005, 0.005),
        features: v(rng, ROWS * FEATURES, -1.0, 1.0),
        target: (0..ROWS * 7).map(|k| if k % 7 < 3 { rng.range(0.0, 3.0) } else { rng.range(0.0, 1.0) }).collect(),
        mu_l: (0..ROWS).map(|_| rng.range(0.1, 1.0)).collect(),
    }
}

fn random_model(rng: &mut Rng, inputs: usize, latent: usize) -> NeuralModel<f64> {
    let mut net = |widths: Vec<usize>, output: Activation| {
        let mut m = Mlp::<f64>::new(MlpShape { widths, hidden: Activation::LEAKY_RELU, output }, rng.next_u64());
        // Non-zero biases, so no unit sits exactly at a kink.
        for p in m.params.iter_mut() {
            *p += rng.range(-0.3, 0.3) as f64;
        }
        m
    };
    let encoder = net(vec![inputs, 9, 8, latent], Activation::Sigmoid);
    let decoder = net(vec![latent + FEATURES, 10, 8, 7], Activation::EXP_HEAD);
    NeuralModel { encoder, decoder }
}

fn slice<'a>(c: &'a Case) -> Slice<'a, f64> {
    Slice { input: &c.input, jitter: &c.jitter, features: &c.features, target: &c.target, mu_l: &c.mu_l, batch: ROWS }
}

fn loss(model: &NeuralModel<f64>, c: &Case) -> f64 {
    let mut ws = ModelWorkspace::default();
    let mut ge = vec![0.0; model.encoder.params.len()];
    let mut gd = vec![0.0; model.decoder.params.len()];
    model.train_slice(&slice(c), LossWeights::PAPER, &mut ws, &mut ge, &mut gd).total
}

fn compare(what: &str, analytic: &[f64], numeric: &[f64]) -> f64 {
    let scale = analytic.iter().chain(numeric).fold(0.0f64, |m, x| m.max(x.abs()));
    assert!(scale > 0.0, "{what}: all gradients are zero");
    let mut worst = 0.0f64;
    for (k, (a, n)) in analytic.iter().zip(numeric).enumerate() {
        let rel = (a - n).abs() / a.abs().max(n.abs()).max(1e-5 * scale);
        worst = worst.max(rel);
        assert!(rel <= 1e-4, "{what}[{k}]: analytic {a:e}, central difference {n:e} (relative {rel:.2e})");
    }
    worst
}

fn central(mut f: impl FnMut(f64) -> f64, x: f64) -> f64 {
    let h = 1e-4 * x.abs().max(1.0);
    (f(x + h) - f(x - h)) / (2.0 * h)
}

#[test]
fn trainer_gradients_match_central_differences() {
    let mut rng = Rng::new(0x9_4ad);
    let mut worst = 0.0f64;
    for trial in 0..6 {
        let inputs = 3 + trial % 4;
        let latent = if trial % 2 == 0 { LATENT } else { 8 };
        let model = random_model(&mut rng, inputs, latent);
        let case = random_case(&mut rng, inputs, latent);
        let mut ws = ModelWorkspace::default();
        ws.enc.want_input_gradient = true;
        let mut ge = vec![0.0; model.encoder.params.len()];
        let mut gd = vec![0.0; model.decoder.params.len()];
        model.train_slice(&slice(&case), LossWeights::PAPER, &mut ws, &mut ge, &mut gd);
        let d_input = ws.enc.input_gradient().to_vec();
        let d_features: Vec<f64> = (0..ROWS).flat_map(|r| ws.d_latent[r * (latent + FEATURES) + latent..(r + 1) * (latent + FEATURES)].to_vec()).collect();

        let numeric_enc: Vec<f64> = (0..ge.len())
            .map(|k| {
                let mut m = model.clone();
                central(|x| { m.encoder.params[k] = x; loss(&m, &case) }, model.encoder.params[k])
            })
            .collect();
        let numeric_dec: Vec<f64> = (0..gd.len())
            .map(|k| {
                let mut m = model.clone();
                central(|x| { m.decoder.params[k] = x; loss(&m, &case) }, model.decoder.params[k])
            })
            .collect();
        let numeric_input: Vec<f64> = (0..case.input.len())
            .map(|k| {
                let mut c = Case { input: case.input.clone(), jitter: case.jitter.clone(), features: case.features.clone(), target: case.target.clone(), mu_l: case.mu_l.clone() };
                central(|x| { c.input[k] = x; loss(&model, &c) }, case.input[k])
            })
            .collect();
        let numeric_features: Vec<f64> = (0..case.features.len())
            .map(|k| {
                let mut c = Case { input: case.input.clone(), jitter: case.jitter.clone(), features: case.features.clone(), target: case.target.clone(), mu_l: case.mu_l.clone() };
                central(|x| { c.features[k] = x; loss(&model, &c) }, case.features[k])
            })
            .collect();
        worst = worst.max(compare(&format!("trial {trial} encoder weights"), &ge, &numeric_enc));
        worst = worst.max(compare(&format!("trial {trial} decoder weights"), &gd, &numeric_dec));
        worst = worst.max(compare(&format!("trial {trial} encoder inputs"), &d_input, &numeric_input));
        worst = worst.max(compare(&format!("trial {trial} direction features"), &d_features, &numeric_features));
    }
    eprintln!("worst relative gradient error {worst:.2e}");
}

#[test]
fn latent_gradients_match_central_differences() {
    // Latent fitting: the frozen decoder's ∂loss/∂latent.
    let mut rng = Rng::new(0x1a7e);
    for latent in [LATENT, 8] {
        let model = random_model(&mut rng, 4, latent);
        let mut case = random_case(&mut rng, latent, latent);
        for z in case.input.iter_mut() {
            *z = 0.5 + 0.5 * *z;
        }
        let run = |c: &Case| latent_slice(&model.decoder, &slice(c), LossWeights::PAPER, &mut ModelWorkspace::default());
        let (_, analytic) = run(&case);
        assert_eq!(analytic.len(), ROWS * latent);
        let numeric: Vec<f64> = (0..case.input.len())
            .map(|k| {
                let mut c = Case { input: case.input.clone(), jitter: case.jitter.clone(), features: case.features.clone(), target: case.target.clone(), mu_l: case.mu_l.clone() };
                central(|x| { c.input[k] = x; run(&c).0.total }, case.input[k])
            })
            .collect();
        let worst = compare(&format!("latents ({latent})"), &analytic, &numeric);
        eprintln!("latent width {latent}: worst relative latent-gradient error {worst:.2e}");
    }
}
