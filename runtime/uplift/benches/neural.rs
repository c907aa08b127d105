//! Benchmark of the neural-material networks on one generated batch (16,384 rows by default),
//! in samples per second and as a fraction of the machine's fp32 peak:
//! - training: one full step (encoder → jitter → decoder → Eq. 3 → backward → Adam), data-
//!   parallel over the threads (the data generation is timed separately);
//! - latent fitting: the frozen decoder's forward and backward to the latents (no weight
//!   gradients), plus the latents' Adam update;
//! - inference: the decoder's forward pass;
//! - data generation: rows per second of the training-data generator (three closure kernels),
//!   with one light direction per (parameter set, view) and with 32 (`directions_per_view`).
//!
//! `cargo bench -p uplift --bench neural` (options after `--`: `--rows N`, `--seconds S`,
//! `--threads T`, `--peak-gflops G`, `--only train|fit|infer|data`). The peak is measured: cores
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
}

fn options() -> Options {
    let mut o = Options { rows: 16384, seconds: 3.0, threads: std::thread::available_parallelism().map_or(1, |n| n.get()), peak_gflops: None, only: None };
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
    println!("samples/s: the median of 7 windows (slowest–fastest window in brackets)");
    let report = |what: &str, r: Rate, flop: f64| {
        let gflops = r.median * flop / 1e9;
        println!(
            "{what:<28} {:>10.0} samples/s  [{:.0}–{:.0}]  ({:.0} kflop/sample, {gflops:.1} GFLOP/s, {:.1} % of peak)",
            r.median,
            r.low,
            r.high,
            flop / 1e3,
            100.0 * gflops / peak
        );
    };

    let wants = |what: &str| o.only.as_deref().is_none_or(|w| w == what);
    let opts = TrainOptions { threads: o.threads, batch: o.rows, steps: 1 << 40, ..Default::default() };
    let mut state = TrainState::new(np, LATENT, 1);
    let mut buf = StepBuffers::default();
    if wants("train") {
        report("training step", rate(o.rows, o.seconds, || {
            train_step(&mut state, &batch, &opts, &mut buf);
        }), flop_train);
    }

    let decoder = state.model.decoder.clone();
    let mut latents = vec![0.5f32; o.rows * LATENT];
    let mut fb = FitBuffers::default();
    let mut step = 0u64;
    if wants("fit") {
        report("latent fitting step", rate(o.rows, o.seconds, || {
            fit_step_rows(&decoder, &mut latents, &batch.features, &batch.target, &batch.mu_l, step, 1e-3, o.threads, &mut fb);
            step += 1;
        }), flop_fit);
    }

    let dec_in: Vec<f32> = (0..o.rows).flat_map(|r| latents[r * LATENT..(r + 1) * LATENT].iter().chain(&batch.features[r * 9..(r + 1) * 9]).copied().collect::<Vec<_>>()).collect();
    assert_eq!(dec_in.len(), o.rows * dec.inputs());
    let mut out = vec![0.0f32; o.rows * 7];
    let mut workspaces = Vec::new();
    if wants("infer") {
        report("inference (decoder forward)", rate(o.rows, o.seconds, || {
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
