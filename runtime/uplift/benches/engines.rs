//! Benchmark of the two engines on the representative pattern graph
//! (`runtime/kernels/graphs/triplanar_mask.mtlx`: a fractal3d-driven triplanar mask, 30 nodes, 4 output
//! columns), in evaluations (points) per second:
//! - CPU engine, the shipped in-process kernel (runtime CPU dispatch), on 1 thread and on all;
//! - CPU engine, the same kernel's runner built normally and built with LLVM's vectorisers off
//!   (`-C no-vectorize-loops -C no-vectorize-slp`), 1 thread each: their ratio is what
//!   vectorisation of the batch loop gains;
//! - wgpu engine (lavapipe without a GPU), upload + dispatch + read-back per batch, with the
//!   driver's threads on all cores and on one (`LP_NUM_THREADS=1`, in a child process).
//!
//! `cargo bench -p uplift --bench engines` (options after `--`: `--points N`, `--seconds S`,
//! `--graph FILE.mtlx` to measure another document's numeric outputs; a graph the runtime does
//! not ship has no in-process figures; `--context eval|albedo|sample|pdf` for a BSDF graph's
//! closure kernel, on random direction pairs in the local frame). The closure library's
//! figures (paths relative to runtime/uplift/, where cargo runs benchmarks): `--graph
//! ../kernels/graphs/bsdf/bsdf_conductor.mtlx --context eval` (one conductor)
//! and `--graph ../kernels/graphs/bsdf/bsdf_stack.mtlx --context eval` (the layered stack).

use std::path::{Path, PathBuf};
use std::time::Instant;
use uplift_engines::batch::{Geometry, PatternBatch};
use uplift_engines::cpu_engine::driver::evals_per_second as rate;
use uplift_engines::cpu_engine::external::{self, RunnerOptions};
use uplift_engines::cpu_engine::{CpuEngine, CpuKernel};
use uplift_engines::wgpu_engine::WgpuEngine;
use uplift_compiler::{ClosureContext, Compiler, OutputSelection, PatternKernel};

struct Options {
    graph: Option<PathBuf>,
    context: Option<ClosureContext>,
    points: usize,
    seconds: f64,
    wgpu_child: bool,
}

fn options() -> Options {
    let mut o = Options { graph: None, context: None, points: 1 << 20, seconds: 2.0, wgpu_child: false };
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut i = 0;
    while i < args.len() {
        match args[i].as_str() {
            "--points" => {
                i += 1;
                o.points = args[i].parse().expect("--points N");
            }
            "--seconds" => {
                i += 1;
                o.seconds = args[i].parse().expect("--seconds S");
            }
            "--graph" => {
                i += 1;
                o.graph = Some(PathBuf::from(&args[i]));
            }
            "--context" => {
                i += 1;
                o.context = Some(ClosureContext::from_name(&args[i]).expect("--context eval|albedo|sample|pdf"));
            }
            "--wgpu-child" => o.wgpu_child = true,
            _ => {} // `--bench` and libtest's options
        }
        i += 1;
    }
    o
}

/// Seeded points on a sphere of radius 3 (world position, normal, tangent) with the documented
/// interface inputs.
fn batch(kernel: &PatternKernel, n: usize) -> PatternBatch {
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 40) as f32 / (1u64 << 24) as f32
    };
    let points: Vec<Geometry> = (0..n)
        .map(|_| {
            let z = 2.0 * next() - 1.0;
            let phi = std::f32::consts::TAU * next();
            let r = (1.0 - z * z).max(0.0).sqrt();
            let normal = [r * phi.cos(), r * phi.sin(), z];
            Geometry { texcoord: [next(), next()], position: normal.map(|c| 3.0 * c), normal, tangent: [-phi.sin(), phi.cos(), 0.0] }
        })
        .collect();
    let defaults: Vec<f32> = kernel.inputs.iter().flat_map(|i| i.input.default.clone()).collect();
    let mut rows: Vec<f32> = (0..n).flat_map(|_| defaults.iter().copied()).collect();
    let Some(context) = kernel.context else {
        return PatternBatch::from_rows(&points, &rows, kernel.input_stride, vec![]);
    };
    // Closure kernels: the local frame, and random upper-hemisphere directions (uniforms for
    // the sample context's `u`).
    let local = Geometry { texcoord: [0.0; 2], position: [0.0; 3], normal: [0.0, 0.0, 1.0], tangent: [1.0, 0.0, 0.0] };
    let directions = context.direction_inputs().len();
    for row in rows.chunks_mut(kernel.input_stride) {
        for d in 0..directions {
            let (u1, u2) = (next(), next());
            let v = if kernel.inputs[d].input.name == "u" {
                [u1, u2, next()]
            } else {
                let r = u1.sqrt();
                let phi = std::f32::consts::TAU * u2;
                [r * phi.cos(), r * phi.sin(), (1.0 - u1).max(0.0).sqrt()]
            };
            row[kernel.inputs[d].offset..kernel.inputs[d].offset + 3].copy_from_slice(&v);
        }
    }
    PatternBatch::from_rows(&vec![local; n], &rows, kernel.input_stride, vec![])
}

fn mega(r: f64) -> String {
    format!("{:8.2} M evals/s", r / 1e6)
}

fn wgpu_rate(kernel: &PatternKernel, b: &PatternBatch, seconds: f64) -> Result<(f64, String), String> {
    let engine = WgpuEngine::new()?;
    let pipeline = engine.prepare(kernel);
    let r = rate(b.n(), seconds, || {
        engine.run_prepared(&pipeline, b).expect("wgpu run");
    });
    Ok((r, format!("{} ({:?})", engine.adapter_info.name, engine.adapter_info.backend)))
}

fn cache_dir() -> PathBuf {
    let target = std::env::var_os("CARGO_TARGET_DIR").map(PathBuf::from).unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../../target"));
    target.join("uplift-bench-cache")
}

fn main() {
    let o = options();
    let graph = o.graph.clone().unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../kernels/graphs/triplanar_mask.mtlx"));
    let compiler = Compiler::builtin();
    let c = compiler.compile_file_in(&graph, &OutputSelection::AllNumeric, o.context);
    let kernel = c.kernel.unwrap_or_else(|| panic!("{}: {:?}", graph.display(), c.diagnostics.iter().map(|d| d.to_string()).collect::<Vec<_>>()));
    let b = batch(&kernel, o.points);
    if o.wgpu_child {
        match wgpu_rate(&kernel, &b, o.seconds) {
            Ok((r, _)) => println!("rate={r}"),
            Err(e) => println!("error={e}"),
        }
        return;
    }
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let mut name = graph.file_stem().unwrap_or_default().to_string_lossy().to_string();
    if let Some(c) = o.context {
        name = format!("{name} ({} context)", c.name());
    }
    println!("{name}: {} IR values, {} points per batch, {} output columns", kernel.graph.values.len(), o.points, kernel.output_stride);

    // CPU, in-process (a shipped kernel).
    let all = CpuEngine::with_threads(threads).unwrap().with_cache_dir(cache_dir());
    let one = CpuEngine::with_threads(1).unwrap().with_cache_dir(cache_dir());
    println!("CPU level: {}", all.cpu_level());
    let prepared = all.prepare(&kernel).unwrap();
    let (cpu1, cpu_all) = match &prepared {
        CpuKernel::Builtin(_) => {
            let cpu1 = rate(o.points, o.seconds, || {
                one.run_prepared(&prepared, &b).unwrap();
            });
            let cpu_all = rate(o.points, o.seconds, || {
                all.run_prepared(&prepared, &b).unwrap();
            });
            println!("cpu  in-process   1 thread : {}", mega(cpu1));
            println!("cpu  in-process {threads:2} threads: {}  ({:.2}× one thread)", mega(cpu_all), cpu_all / cpu1);
            (cpu1, cpu_all)
        }
        CpuKernel::External(runner) => {
            let cpu1 = external::bench(runner, &b, 1, o.seconds).unwrap().0;
            let cpu_all = external::bench(runner, &b, threads, o.seconds).unwrap().0;
            println!("cpu  runner       1 thread : {}  (not shipped: no in-process kernel)", mega(cpu1));
            println!("cpu  runner     {threads:2} threads: {}  ({:.2}× one thread)", mega(cpu_all), cpu_all / cpu1);
            (cpu1, cpu_all)
        }
    };

    // CPU, runners with and without vectorisation (1 thread).
    let cache = cache_dir();
    let mut vectorised = None;
    for vectorize in [true, false] {
        let options = RunnerOptions { cache_dir: cache.clone(), vectorize, quick: false };
        let started = Instant::now();
        match one.prepare_runner(&kernel, &options) {
            Ok(runner) => {
                let built = started.elapsed().as_secs_f64();
                match external::bench(&runner, &b, 1, o.seconds) {
                    Ok((r, level)) => {
                        let label = if vectorize { "vectorised    " } else { "not vectorised" };
                        println!("cpu  runner {label} 1 thread : {}  (level {level}; build/cache {built:.1} s)", mega(r));
                        match vectorised {
                            None => vectorised = Some(r),
                            Some(v) => println!("vectorisation gain (runner, 1 thread): {:.2}×", v / r),
                        }
                    }
                    Err(e) => println!("cpu  runner: {e}"),
                }
            }
            Err(e) => println!("cpu  runner (vectorize={vectorize}) not built: {e}"),
        }
    }

    // wgpu, all driver threads here, one in a child process.
    match wgpu_rate(&kernel, &b, o.seconds) {
        Ok((r, adapter)) => println!("wgpu {adapter}, all threads: {}  ({:.3}× CPU all threads)", mega(r), r / cpu_all),
        Err(e) => println!("wgpu: {e}"),
    }
    let exe = std::env::current_exe().unwrap();
    let mut child_args = vec!["--wgpu-child".to_string(), "--points".into(), o.points.to_string(), "--seconds".into(), o.seconds.to_string(), "--graph".into(), graph.display().to_string()];
    if let Some(c) = o.context {
        child_args.extend(["--context".to_string(), c.name().to_string()]);
    }
    let child = std::process::Command::new(exe)
        .args(&child_args)
        .env("LP_NUM_THREADS", "1")
        .output();
    match child {
        Ok(out) => {
            let text = String::from_utf8_lossy(&out.stdout);
            match text.lines().find_map(|l| l.strip_prefix("rate=")).and_then(|r| r.parse::<f64>().ok()) {
                Some(r) => println!("wgpu LP_NUM_THREADS=1        : {}  ({:.3}× CPU 1 thread)", mega(r), r / cpu1),
                None => println!("wgpu single thread: {}{}", text.trim(), String::from_utf8_lossy(&out.stderr).trim()),
            }
        }
        Err(e) => println!("wgpu single thread: cannot start the child: {e}"),
    }
}
