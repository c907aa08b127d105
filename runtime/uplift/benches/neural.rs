//! Benchmark of the neural-material networks on one generated batch (16,384 rows by default),
//! in samples per second and as a fraction of the machine's fp32 peak:
//! - training: one full step (encoder → jitter → decoder → Eq. 3 → backward → Adam), data-
//!   parallel over the threads (the data generation is timed separately);
//! - latent fitting: the frozen decoder's forward and backward to the latents (no weight
//!   gradients), plus the latents' Adam update;
//! - inference: the decoder's forward pass;
//! - data generation: rows per second of the training-data generator (three closure kernels),
//!   with one light direction per (parameter set, view) and with 32 (`directions_per_view`);
//! - the wgpu engine (`--only wgpu`, not in the default run): a training step on a host batch
//!   (`wgpu_train::WgpuTrainer`), a fitting step's forward, Eq. 3 and backward
//!   (`wgpu_fit::WgpuLatentGradients`), a whole fitting step as `uplift fit --engine wgpu` runs
//!   it (`wgpu_fit::DeviceFit`), data generation read back to the host, and a whole training step
//!   as `uplift train --engine wgpu` runs it (the batch assembled on the device, `wgpu_batch`),
//!   on whatever adapter wgpu opens (lavapipe without a GPU), its name printed.
//!
//! **Anchor.** PyTorch (CPU, the same threads) runs the same networks, batch and work per sample
//! in the same run (`benches/torch/setup.sh` installs it from PyPI into `target/torch-venv`,
//! `mlp_rate.py` measures); each line prints uplift's ratio to it. `--no-torch` skips it; when
//! it cannot be installed the benchmark says so and goes on. With `UPLIFT_DENSE=avx2` PyTorch is
//! held to AVX2 as well (ATen, oneDNN and MKL each have a switch).
//!
//! `cargo bench -p uplift --bench neural` (options after `--`: `--rows N`, `--seconds S`,
//! `--threads T`, `--peak-gflops G`, `--only train|fit|infer|data`, `--no-torch`). The peak is measured: cores
//! × one core's rate of independent FMAs in registers on the fused kernels' vectors
//! (`dense::fma_peak`: AVX-512 or AVX2), the most any fp32 code can reach with them; the
//! large-GEMM rate (matrixmultiply, 1024³) is printed beside it. `UPLIFT_DENSE=avx2` measures
//! the AVX2 kernels on an AVX-512 machine (`gemm`: the GEMM path). Each figure is the median of
//! seven windows: the machine is a shared VM.
use std::time::Instant;
use uplift_engines::cpu_engine::CpuEngine;
use uplift_neural::datagen::{ClassMix, DataGenerator};
use uplift_neural::fit::{fit_step_rows, FitBuffers};
use uplift_neural::model::{decoder_shape, encoder_shape, LATENT};
use uplift_neural::mlp::Real;
use uplift_neural::trainer::{train_step, StepBuffers, TrainOptions, TrainState};

struct Options {
    rows: usize,
    seconds: f64,
    threads: usize,
    peak_gflops: Option<f64>,
    /// Only this measurement (`train`, `fit`, `infer`, `data`), e.g. under a profiler.
    only: Option<String>,
    /// Measure PyTorch beside uplift (the default).
    torch: bool,
}

fn options() -> Options {
    let mut o = Options { rows: 16384, seconds: 3.0, threads: std::thread::available_parallelism().map_or(1, |n| n.get()), peak_gflops: None, only: None, torch: true };
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut i = 0;
    while i < args.len() {
        let value = |i: usize| args.get(i + 1).unwrap_or_else(|| panic!("{} needs a value", args[i])).clone();
        match args[i].as_str() {
            "--rows" => o.rows = value(i).parse().expect("--rows N"),
            "--seconds" => o.seconds = value(i).parse().expect("--seconds S"),
            "--threads" => o.threads = value(i).parse().expect("--threads T"),
            "--peak-gflops" => o.peak_gflops = Some(value(i).parse().expect("--peak-gflops G")),
            "--only" => o.only = Some(value(i)),
            "--no-torch" => {
                o.torch = false;
                i += 1;
                continue;
            }
            "--bench" => {
                i += 1;
                continue;
            }
            other => panic!("unknown option {other}"),
        }
        i += 2;
    }
    o
}

/// The large-GEMM rate: a single-threaded 1024³ sgemm (matrixmultiply, the trainer's weight-
/// gradient GEMM) per second, times the cores, in GFLOP/s.
fn sgemm_rate(cores: usize) -> f64 {
    let n = 1024;
    let a: Vec<f32> = (0..n * n).map(|k| (k % 7) as f32 * 0.1).collect();
    let mut c = vec![0.0f32; n * n];
    let mut run = || <f32 as Real>::gemm(n, n, n, 1.0, &a, n as isize, 1, &a, n as isize, 1, 0.0, &mut c, n as isize, 1);
    run();
    let start = Instant::now();
    let mut reps = 0;
    while start.elapsed().as_secs_f64() < 1.0 {
        run();
        reps += 1;
    }
    cores as f64 * reps as f64 * 2.0 * (n * n * n) as f64 / start.elapsed().as_secs_f64() / 1e9
}

/// Rows per second of `f` (one pass over `rows`), in seven windows of `seconds` / 7 (each at
/// least two passes): the median, and the slowest and fastest window. The machine is a shared
/// VM whose windows vary by ±15 %; the median is the figure reported.
fn rate(rows: usize, seconds: f64, mut f: impl FnMut()) -> Rate {
    f();
    let mut windows: Vec<f64> = (0..7)
        .map(|_| {
            let start = Instant::now();
            let mut n = 0usize;
            while start.elapsed().as_secs_f64() < seconds / 7.0 || n < 2 {
                f();
                n += 1;
            }
            (n * rows) as f64 / start.elapsed().as_secs_f64()
        })
        .collect();
    windows.sort_by(f64::total_cmp);
    Rate { median: windows[3], low: windows[0], high: windows[6] }
}

/// PyTorch's rows/s for `train`, `fit` and `infer` (benches/torch/), and its version; or why not.
fn torch_rates(o: &Options, params: usize) -> Result<(serde_json::Value, String), String> {
    let here = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/torch");
    let target = std::env::var_os("CARGO_TARGET_DIR").map(std::path::PathBuf::from).unwrap_or_else(|| std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../target"));
    let venv = target.join("torch-venv");
    let setup = std::process::Command::new("bash").arg(here.join("setup.sh")).arg(&venv).output().map_err(|e| format!("cannot run setup.sh: {e}"))?;
    if !setup.status.success() {
        return Err(format!("setup.sh failed: {}{}", String::from_utf8_lossy(&setup.stdout), String::from_utf8_lossy(&setup.stderr)));
    }
    let mut cmd = std::process::Command::new(venv.join("bin/python"));
    cmd.arg(here.join("mlp_rate.py")).args(["--rows", &o.rows.to_string(), "--params", &params.to_string(), "--latent", &LATENT.to_string(), "--seconds", &o.seconds.to_string(), "--threads", &o.threads.to_string()]);
    if let Some(only) = &o.only {
        cmd.args(["--only", only]);
    }
    // Held to AVX2 (`UPLIFT_DENSE=avx2` on an AVX-512 machine): PyTorch's kernels too (ATen's
    // dispatch, oneDNN and MKL), so that both sides measure the AVX2 machine this stands for.
    if uplift_neural::dense::isa() == Some(uplift_neural::dense::Isa::Avx2) {
        cmd.env("ATEN_CPU_CAPABILITY", "avx2").env("ONEDNN_MAX_CPU_ISA", "AVX2").env("MKL_ENABLE_INSTRUCTIONS", "AVX2");
    }
    let out = cmd.output().map_err(|e| format!("cannot run mlp_rate.py: {e}"))?;
    let text = String::from_utf8_lossy(&out.stdout);
    let json: serde_json::Value = serde_json::from_str(text.lines().last().unwrap_or_default()).map_err(|_| format!("mlp_rate.py said: {text}{}", String::from_utf8_lossy(&out.stderr)))?;
    let version = json["torch"].as_str().unwrap_or("?").to_string();
    Ok((json, version))
}

struct Rate {
    median: f64,
    low: f64,
    high: f64,
}

fn main() {
    let o = options();
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    // The fp32 peak: cores × one core's FMA rate on the fused kernels' vectors (dense.rs
    // measures it); without fused kernels, the large-GEMM rate stands in.
    let sgemm = sgemm_rate(cores);
    let (peak, peak_source) = match (o.peak_gflops, uplift_neural::dense::fma_peak(1.0)) {
        (Some(p), _) => (p, "--peak-gflops"),
        (None, Some(f)) => (cores as f64 * f / 1e9, "cores × an FMA loop on the kernels' vectors"),
        (None, None) => (sgemm, "cores × a 1024³ sgemm"),
    };
    let generator = DataGenerator::new(CpuEngine::with_threads(o.threads).unwrap(), &uplift_engines::stack::Stack::builtin(), ClassMix::All, 1).unwrap();
    let batch = generator.batch(0, o.rows).unwrap();
    let np = generator.stack().len();
    let (enc, dec) = (encoder_shape(np, LATENT), decoder_shape(LATENT));
    // Multiply–adds per row: forward; training adds two GEMMs per layer backward (the
    // encoder's first layer skips its input gradient).
    let (mac_enc, mac_dec) = (enc.macs() as f64, dec.macs() as f64);
    let flop_train = 2.0 * (3.0 * mac_dec + 3.0 * mac_enc - (enc.widths[0] * enc.widths[1]) as f64);
    let flop_fit = 2.0 * 2.0 * mac_dec;
    let flop_infer = 2.0 * mac_dec;
    println!(
        "neural benchmark: {} rows per batch, {} thread(s), {} core(s), {}; fp32 peak {peak:.0} GFLOP/s ({peak_source}); a 1024³ sgemm (matrixmultiply) {sgemm:.0} GFLOP/s",
        o.rows,
        o.threads,
        cores,
        match uplift_neural::dense::isa() {
            Some(isa) => format!("fused {} layers", isa.name()),
            None => "GEMM layers (no fused kernels)".to_string(),
        }
    );
    let torch = if o.torch && o.only.as_deref() != Some("data") {
        match torch_rates(&o, np) {
            Ok((json, version)) => {
                println!("PyTorch {version} (CPU, {} threads, the same networks and batch): measured first, in this run", o.threads);
                Some(json)
            }
            Err(e) => {
                println!("PyTorch: could not measure it ({})", e.trim());
                None
            }
        }
    } else {
        None
    };
    println!("samples/s: the median of 7 windows (slowest–fastest window in brackets)");
    let report = |what: &str, key: &str, r: Rate, flop: f64| {
        let gflops = r.median * flop / 1e9;
        let versus = match torch.as_ref().and_then(|j| j[key].as_f64()) {
            Some(t) => format!("; PyTorch {t:.0} samples/s, uplift {:.2}×", r.median / t),
            None => String::new(),
        };
        println!(
            "{what:<28} {:>10.0} samples/s  [{:.0}–{:.0}]  ({:.0} kflop/sample, {gflops:.1} GFLOP/s, {:.1} % of peak{versus})",
            r.median,
            r.low,
            r.high,
            flop / 1e3,
            100.0 * gflops / peak
        );
    };

    let wants = |what: &str| o.only.as_deref().is_none_or(|w| w == what);
    if o.only.as_deref() == Some("wgpu") {
        return wgpu_rates(&o, &batch);
    }
    let opts = TrainOptions { threads: o.threads, batch: o.rows, steps: 1 << 40, ..Default::default() };
    let mut state = TrainState::new(np, LATENT, 1);
    let mut buf = StepBuffers::default();
    if wants("train") {
        report("training step", "train", rate(o.rows, o.seconds, || {
            train_step(&mut state, &batch, &opts, &mut buf);
        }), flop_train);
    }

    let decoder = state.model.decoder.clone();
    let mut latents = vec![0.5f32; o.rows * LATENT];
    let mut fb = FitBuffers::default();
    let mut step = 0u64;
    if wants("fit") {
        report("latent fitting step", "fit", rate(o.rows, o.seconds, || {
            fit_step_rows(&decoder, &mut latents, &batch.features, &batch.target, &batch.mu_l, step, 1e-3, o.threads, &mut fb);
            step += 1;
        }), flop_fit);
    }

    let dec_in: Vec<f32> = (0..o.rows).flat_map(|r| latents[r * LATENT..(r + 1) * LATENT].iter().chain(&batch.features[r * 9..(r + 1) * 9]).copied().collect::<Vec<_>>()).collect();
    assert_eq!(dec_in.len(), o.rows * dec.inputs());
    let mut out = vec![0.0f32; o.rows * 7];
    let mut workspaces = Vec::new();
    if wants("infer") {
        report("inference (decoder forward)", "infer", rate(o.rows, o.seconds, || {
            uplift_neural::inference::decode_parallel_in(&mut workspaces, &decoder, &dec_in, &mut out, o.threads);
        }), flop_infer);
    }
    if !wants("data") {
        return;
    }

    let mut k = 1u64;
    let r = rate(o.rows, o.seconds, || {
        generator.batch(k, o.rows).unwrap();
        k += 1;
    });
    println!("{:<28} {:>10.0} rows/s [{:.0}–{:.0}] (eval or sample, and albedo, of uplift_stack per row)", "data generation", r.median, r.low, r.high);
    // The grouped layout: 32 light directions per (parameter set, view) — 16 lit uniformly
    // through the eval, 16 sampled, each half a full group for the split kernels
    // (`GROUPED_MIN_POINTS`) — the albedo once per group.
    let mut grouped = DataGenerator::new(CpuEngine::with_threads(o.threads).unwrap(), &uplift_engines::stack::Stack::builtin(), ClassMix::All, 1).unwrap();
    grouped.directions_per_view = 32;
    let g = rate(o.rows, o.seconds, || {
        grouped.batch(k, o.rows).unwrap();
        k += 1;
    });
    println!("{:<28} {:>10.0} rows/s [{:.0}–{:.0}] ({:.2}× one direction per view)", "data generation, 32 per view", g.median, g.low, g.high, g.median / r.median);
}

/// `--only wgpu`: training, fitting and data generation on the wgpu engine.
fn wgpu_rates(o: &Options, batch: &uplift_neural::datagen::TrainingBatch) {
    let engine = match uplift_engines::wgpu_engine::WgpuEngine::new() {
        Ok(e) => e,
        Err(e) => return println!("wgpu: no adapter ({e})"),
    };
    println!("wgpu adapter: {} ({:?}, {:?})", engine.adapter_info.name, engine.adapter_info.device_type, engine.adapter_info.backend);
    let np = uplift_engines::stack::Stack::builtin().len();
    let state = TrainState::new(np, LATENT, 1);
    let mut trainer = uplift_neural::wgpu_train::WgpuTrainer::new(&engine, &state).unwrap();
    let mut jit = Vec::new();
    uplift_neural::trainer::jitter(1, 0, o.rows * LATENT, 0.005, &mut jit);
    let mut t = 0u64;
    let r = rate(o.rows, o.seconds, || {
        t += 1;
        trainer.step(&engine, &batch.encoded, &jit, &batch.features, &batch.target, &batch.mu_l, 1e-4, t, uplift_neural::loss::LossWeights::PAPER).unwrap();
    });
    println!("{:<28} {:>10.0} samples/s [{:.0}–{:.0}] (batch {}, weights and moments on the device)", "wgpu training step", r.median, r.low, r.high, o.rows);
    let fit = uplift_neural::wgpu_fit::WgpuLatentGradients::new(&engine, &state.model.decoder, LATENT, "bench").unwrap();
    let latents = vec![0.5f32; o.rows * LATENT];
    let mut dec_in = Vec::new();
    uplift_neural::model::fill_decoder_input(&latents, &jit, &batch.features, o.rows, LATENT, &mut dec_in);
    let r = rate(o.rows, o.seconds, || {
        fit.run(&engine, &dec_in, &batch.target, &batch.mu_l, uplift_neural::loss::LossWeights::PAPER).unwrap();
    });
    println!("{:<28} {:>10.0} samples/s [{:.0}–{:.0}] (forward, Eq. 3, backward to the latents; rows uploaded per step)", "wgpu latent gradients", r.median, r.low, r.high);
    let generator = DataGenerator::new(engine, &uplift_engines::stack::Stack::builtin(), ClassMix::All, 1).unwrap();
    {
        // A whole fitting step as `uplift fit --engine wgpu` runs it (DeviceFit): the rows
        // assembled on the device from the groups' parameters, Eq. 3 and its gradient, Adam.
        let uplift_engines::stack_kernel::Engine::Wgpu(engine) = generator.engine() else { unreachable!("made on the wgpu engine") };
        let per_group = 8;
        let stack = generator.stack();
        let params = stack.defaults().repeat(o.rows);
        let z0 = vec![0.5f32; o.rows / per_group * LATENT];
        let mut fit = uplift_neural::wgpu_fit::DeviceFit::new(engine, &generator, &state.model.decoder, LATENT, &params[..o.rows / per_group * per_group * stack.len()], per_group, &z0).unwrap();
        let rows = o.rows / per_group * per_group;
        let mut step = 0u64;
        let r = rate(rows, o.seconds, || {
            step += 1;
            fit.step(engine, &generator, step, &jit[..rows * LATENT], 1e-3, uplift_neural::loss::LossWeights::PAPER).unwrap();
        });
        println!("{:<28} {:>10.0} samples/s [{:.0}–{:.0}] (batch {rows}: data, Eq. 3, gradient and Adam on the device)", "wgpu fitting step", r.median, r.low, r.high);
    }
    let mut k = 1u64;
    let r = rate(o.rows, o.seconds, || {
        generator.batch(k, o.rows).unwrap();
        k += 1;
    });
    println!("{:<28} {:>10.0} rows/s [{:.0}–{:.0}] (host batches: kernel outputs read back)", "wgpu data generation", r.median, r.low, r.high);
    // A whole training step as `uplift train --engine wgpu` runs it: the batch assembled on the
    // device (wgpu_batch.rs) and the step on it, only draws and jitter uploaded.
    let uplift_engines::stack_kernel::Engine::Wgpu(engine) = generator.engine() else { unreachable!("made on the wgpu engine") };
    let mut batches = uplift_neural::wgpu_batch::DeviceBatches::new(engine, &generator, LATENT).unwrap();
    let mut t = 0u64;
    let r = rate(o.rows, o.seconds, || {
        t += 1;
        let index = t;
        trainer.step_on_device(engine, o.rows, 1e-4, t, uplift_neural::loss::LossWeights::PAPER, |encoder, rows| batches.record(engine, &generator, index, o.rows, &jit, encoder, rows)).unwrap();
    });
    println!("{:<28} {:>10.0} samples/s [{:.0}–{:.0}] (batch {}: data generation and the step, on the device)", "wgpu training, device data", r.median, r.low, r.high, o.rows);
}
