//! Training data and training, against independent references:
//! - every generated row's targets equal the shipped `uplift_stack` kernels run directly
//!   (through the closure tests' harness) at the row's parameters and directions: f·μl from
//!   `eval` (also for lights drawn by `sample`), T and R = Y(albedo) from `albedo`; batches are
//!   deterministic, classes come in equal proportions, and half the lights come from the sampler;
//! - a short training run lowers the loss, and a run stopped halfway and resumed from its
//!   checkpoint ends with bit-identical weights;
//! - the weights file is read by Python's `safetensors` and numpy reproduces the encoder →
//!   decoder forward pass (skipped, saying so, without python3, safetensors and numpy; .ci/run
//!   installs them).

use crate::common;

use common::bsdf::{bsdf, Params};
use std::path::Path;
use uplift_engines::cpu_engine::CpuEngine;
use uplift_neural::datagen::{ClassMix, DataGenerator};
use uplift_neural::evaluate::{decode, encode};
use uplift_engines::stack::Stack;
use uplift_neural::trainer::{checkpoint_path, train, TrainOptions};
use uplift_neural::weights::TensorFile;
use uplift_compiler::ClosureContext;

fn generator(mix: ClassMix, seed: u64) -> DataGenerator {
    DataGenerator::new(CpuEngine::new().unwrap(), &uplift_engines::stack::Stack::builtin(), mix, seed).unwrap()
}

#[test]
fn generated_targets_equal_the_stack_kernels() {
    let g = generator(ClassMix::All, 5);
    let b = g.batch(3, 4000).unwrap();
    let again = g.batch(3, 4000).unwrap();
    assert_eq!(b.target, again.target, "a batch is a function of (seed, index)");
    assert_eq!(b.params, again.params);
    // Rows are drawn in parallel: on one thread they are the same.
    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap().install(|| g.batch(3, 4000).unwrap());
    assert!(one.params == b.params && one.wv == b.wv && one.wl == b.wl && one.target == b.target && one.class == b.class, "a batch depends on the thread count");
    assert_ne!(b.params, g.batch(4, 4000).unwrap().params);
    // Class proportions: 1/5 each (binomial sd ≈ 0.0063 at 4000 rows).
    assert_eq!(g.classes().len(), 5);
    for (index, c) in g.classes().iter().enumerate() {
        let share = b.class.iter().filter(|&&k| k as usize == index).count() as f64 / b.rows as f64;
        assert!((share - 0.2).abs() < 0.03, "{}: {share}", c.name);
    }
    // A weighted mix (`train --class dust=2,inner=0`): shares 1, 2, 1, 0, 1 of 5.
    let w = generator(ClassMix::parse("dust=2,inner=0").unwrap(), 5).batch(3, 4000).unwrap();
    for (index, c) in g.classes().iter().enumerate() {
        let want = match c.name.as_str() { "dust" => 0.4, "inner" => 0.0, _ => 0.2 };
        let share = w.class.iter().filter(|&&k| k as usize == index).count() as f64 / w.rows as f64;
        assert!((share - want).abs() < 0.03, "weighted {}: {share}, expected {want}", c.name);
    }
    assert!(ClassMix::parse("dust=x").is_err() && ClassMix::parse("dust=-1").is_err());
    match generator(ClassMix::parse("no-such=2").unwrap(), 5).batch(0, 64) {
        Err(e) => assert!(e.contains("no-such"), "{e}"),
        Ok(_) => panic!("a weighted mix naming an unknown class drew a batch"),
    }
    let eval = bsdf("uplift_stack", ClosureContext::Eval);
    let albedo = bsdf("uplift_stack", ClosureContext::Albedo);
    // Params names inputs by `&'static str`: the process's builtin stack lives that long.
    let stack: &'static Stack = Box::leak(Box::new(Stack::builtin()));
    let np = stack.len();
    let row_params = |r: usize| -> Params {
        let mut p = Params::new();
        for (k, spec) in stack.parameters().iter().enumerate() {
            p.entry(spec.input.as_str()).or_insert_with(Vec::new).push(b.params[r * np + k]);
        }
        p
    };
    let params: Vec<Params> = (0..b.rows).map(row_params).collect();
    let ranges: Vec<(std::ops::Range<usize>, &Params)> = params.iter().enumerate().map(|(r, p)| (r..r + 1, p)).collect();
    let e = eval.run(&[b.wv.clone(), b.wl.clone()], &ranges);
    let a = albedo.run(&[b.wv.clone()], &ranges);
    let mut worst = 0.0f32;
    let mut peaked = 0;
    for r in 0..b.rows {
        let t = &b.target[r * 7..(r + 1) * 7];
        for c in 0..3 {
            let want = eval.column(&e, "response", c)[r].max(0.0);
            let err = (t[c] - want).abs() / want.abs().max(1.0);
            worst = worst.max(err);
            assert!(err <= 3e-4, "row {r} channel {c}: target f·μl {} vs eval {want}", t[c]);
            assert_eq!(t[3 + c], albedo.column(&a, "throughput", c)[r], "row {r}: T");
        }
        let y = 0.2126 * albedo.column(&a, "albedo", 0)[r] + 0.7152 * albedo.column(&a, "albedo", 1)[r] + 0.0722 * albedo.column(&a, "albedo", 2)[r];
        assert!((t[6] - y).abs() <= 1e-6, "row {r}: R {} vs Y(albedo) {y}", t[6]);
        assert!(b.wv[r][2] >= 0.05 && b.wl[r][2] > 0.0, "row {r}: directions {:?} {:?}", b.wv[r], b.wl[r]);
        // Lights near the mirror direction: the sampler's share.
        let refl = [-b.wv[r][0], -b.wv[r][1], b.wv[r][2]];
        if refl.iter().zip(&b.wl[r]).map(|(x, y)| x * y).sum::<f32>() > 0.95 {
            peaked += 1;
        }
    }
    // Uniform lights put ≈ (1 − 0.95)/1 = 5 % of the hemisphere within that cone; the sampled
    // half concentrates on specular lobes.
    let share = peaked as f64 / b.rows as f64;
    assert!(share > 0.12, "only {share:.3} of the lights lie near the mirror direction: is the sampler used?");
    eprintln!("worst |target − eval| {worst:.1e}; {:.1} % of lights within 18° of the mirror direction", 100.0 * share);
}

fn small_options(steps: u64) -> TrainOptions {
    TrainOptions { steps, batch: 1024, seed: 3, lr_start: 3e-3, lr_end: 1e-4, threads: 2, checkpoint_every: 1000, log_every: 5, ..Default::default() }
}

#[test]
fn training_lowers_the_loss_and_resumes_bit_identically() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("neural_training");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let g = generator(ClassMix::All, 3);
    let straight = dir.join("straight.safetensors");
    let s = train(&g, &small_options(60), &straight, &[], false).unwrap();
    let (first, last) = (s.history.first().unwrap().loss.total, s.history.last().unwrap().loss.total);
    assert!(last < 0.7 * first, "60 steps: loss {first:.4} → {last:.4}");
    let resumed = dir.join("resumed.safetensors");
    let half = TrainOptions { stop_after: Some(25), ..small_options(60) };
    let stopped = train(&g, &half, &resumed, &[], false).unwrap();
    assert_eq!(stopped.step, 25);
    assert!(!resumed.exists() && checkpoint_path(&resumed).exists(), "a stopped run leaves only its checkpoint");
    let r = train(&g, &small_options(60), &resumed, &[], false).unwrap();
    assert!(!checkpoint_path(&resumed).exists(), "the checkpoint is removed at the end");
    let (a, b) = (TensorFile::read(&straight).unwrap(), TensorFile::read(&resumed).unwrap());
    for net in ["encoder", "decoder"] {
        assert_eq!(a.mlp(net).unwrap().params, b.mlp(net).unwrap().params, "{net}: resumed run differs");
    }
    assert_eq!(r.history.len(), s.history.len());
    // Options must match to resume.
    let other = dir.join("other.safetensors");
    train(&g, &TrainOptions { stop_after: Some(5), ..small_options(60) }, &other, &[], false).unwrap();
    let err = train(&g, &small_options(61), &other, &[], false).unwrap_err();
    assert!(err.contains("other options"), "{err}");
    eprintln!("loss {first:.4} → {last:.4} in 60 steps of 1024");
}

#[test]
fn python_reproduces_the_forward_pass_from_the_weights_file() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("neural_python");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let ok = std::process::Command::new("python3").args(["-c", "import safetensors.numpy, numpy"]).output().is_ok_and(|o| o.status.success());
    if !ok {
        return uplift_base::test_env::skip("python_reproduces_the_forward_pass_from_the_weights_file", "needs python3 with the `safetensors` and `numpy` packages (pip install safetensors numpy; .ci/run installs them)");
    }
    let g = generator(ClassMix::All, 9);
    let weights = dir.join("w.safetensors");
    let state = train(&g, &TrainOptions { steps: 5, ..small_options(5) }, &weights, &[], false).unwrap();
    let b = g.batch(77, 500).unwrap();
    let z = encode(&state.model, &b.encoded);
    let out = decode(&state.model, &z, &b.features);
    let mut inputs = TensorFile::default();
    inputs.put("encoded", vec![b.rows, Stack::builtin().len()], b.encoded.clone());
    inputs.put("features", vec![b.rows, 9], b.features.clone());
    inputs.write(&dir.join("inputs.safetensors")).unwrap();
    let script = r#"
import sys, numpy as np
from safetensors import safe_open
from safetensors.numpy import load_file, save_file
w = load_file(sys.argv[1]); meta = safe_open(sys.argv[1], "np").metadata()
x = load_file(sys.argv[2])
def act(name, v):
    if name.startswith("leaky_relu("): s = float(name[11:-1]); return np.where(v > 0, v, s * v)
    if name == "sigmoid": return 1 / (1 + np.exp(-v))
    if name.startswith("exp(min(x, "): c, b = name[11:-1].split(") - "); return np.exp(np.minimum(v, float(c)) - float(b))
    if name == "identity": return v
    raise SystemExit("unknown activation " + name)
def net(prefix, v):
    layers = len(meta[prefix + ".widths"].split(",")) - 1
    for l in range(layers):
        v = v.astype(np.float64) @ w[f"{prefix}.layers.{l}.weight"].T.astype(np.float64) + w[f"{prefix}.layers.{l}.bias"]
        v = act(meta[prefix + (".output" if l == layers - 1 else ".hidden")], v)
    return v
z = net("encoder", x["encoded"])
out = net("decoder", np.concatenate([z, x["features"]], axis=1))
save_file({"out": out.astype(np.float32)}, sys.argv[3])
"#;
    std::fs::write(dir.join("forward.py"), script).unwrap();
    let o = std::process::Command::new("python3").arg(dir.join("forward.py")).arg(&weights).arg(dir.join("inputs.safetensors")).arg(dir.join("out.safetensors")).output().unwrap();
    assert!(o.status.success(), "python: {}", String::from_utf8_lossy(&o.stderr));
    let py = TensorFile::read(&dir.join("out.safetensors")).unwrap();
    let (shape, values) = py.get("out").unwrap();
    assert_eq!(shape, &vec![b.rows, 7]);
    let mut worst = 0.0f32;
    for (k, (a, p)) in out.iter().zip(values).enumerate() {
        let rel = (a - p).abs() / a.abs().max(p.abs()).max(1e-6);
        worst = worst.max(rel);
        assert!(rel <= 1e-4, "output {k}: Rust {a} vs numpy {p}");
    }
    eprintln!("numpy forward pass: worst relative difference {worst:.1e}");
}
