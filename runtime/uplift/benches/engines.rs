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
//! and `--graph ../kernels/graphs/bsdf/bsdf_stack.mtlx --context eval` (the layered stack),
//! `--graph ../kernels/graphs/bsdf/uplift_stack.mtlx --context eval` (the 8-lobe stack).
//!
//! **Parameters.** Interface inputs take their document defaults, one material for the whole
//! batch, except: `--param NAME=V[,V…]` (repeatable) sets one; the `uplift_stack` graph runs
//! with every lobe live (metalness 0.5, fuzz 0.3, coat 0.5, inner 0.4, subcutaneous 0.5 — its
//! defaults leave 6 of the 8 lobes at weight 0) and the conductor graph at GGX α 0.3 (gold, as
//! Mitsuba's `roughconductor` below); `--random-params` draws every `uplift_stack` parameter
//! per row inside its range (uplift_engines::stack; weights at least 5 % of their range, so no lobe
//! is dead). Directions: `wv` and `wl` uniform on the upper hemisphere. `--per-view K`: the
//! grouped layout (`PatternBatch::points_per_group`): runs of K rows share their first row's
//! view and parameters, each row its own `wl` — a kernel with a dependence-split form runs its
//! per-view work once per K rows. `--set NAME=VALUE` (repeatable) binds an interface input at
//! compile time (`Compiler::constant_inputs`): a specialised kernel, not shipped, so measured
//! through its runner. Closure kernels: the
//! frame and every parameter not drawn per row are uniform columns (`Columns::mark_uniform`),
//! as Mitsuba's benchmark has one material and one frame. In-process runs write into one
//! output buffer reused from batch to batch (`CpuEngine::run_prepared_into`), as Dr.Jit's
//! caching allocator hands Mitsuba's outputs back without clearing them.
//!
//! **Anchor.** `--mitsuba roughconductor|principled` also measures Mitsuba 3.9.1's BSDF `eval`
//! (`llvm_ad_rgb`, all threads) on the same direction distribution in the same run
//! (`benches/mitsuba/setup.sh` installs it into `target/mitsuba-venv`, `bsdf_rate.py` measures)
//! and prints uplift's ratio to it. `--in-process` skips the runners and wgpu (the shipped
//! kernel's figures and Mitsuba's only).

use std::path::{Path, PathBuf};
use std::time::Instant;
use uplift_engines::batch::{Columns, Geometry, PatternBatch};
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
    params: Vec<(String, Vec<f32>)>,
    random_params: bool,
    mitsuba: Option<String>,
    in_process: bool,
    per_view: usize,
    /// `--set NAME=VALUE`: interface inputs bound at compile time (specialisation).
    set: Vec<(String, String)>,
}

fn options() -> Options {
    let mut o = Options { graph: None, context: None, points: 1 << 20, seconds: 2.0, wgpu_child: false, params: Vec::new(), random_params: false, mitsuba: None, in_process: false, per_view: 1, set: Vec::new() };
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
            "--param" => {
                i += 1;
                let (name, values) = args[i].split_once('=').expect("--param NAME=V[,V…]");
                let values = values.split(',').map(|v| v.trim().parse().expect("--param: numbers")).collect();
                o.params.push((name.to_string(), values));
            }
            "--random-params" => o.random_params = true,
            "--set" => {
                i += 1;
                let (name, value) = args[i].split_once('=').expect("--set NAME=VALUE");
                o.set.push((name.to_string(), value.to_string()));
            }
            "--per-view" => {
                i += 1;
                o.per_view = args[i].parse().ok().filter(|&k: &usize| k > 0).expect("--per-view K (K ≥ 1)");
            }
            "--in-process" => o.in_process = true,
            "--mitsuba" => {
                i += 1;
                o.mitsuba = Some(args[i].clone());
            }
            "--wgpu-child" => o.wgpu_child = true,
            _ => {} // `--bench` and libtest's options
        }
        i += 1;
    }
    o
}

/// The parameters the benchmark sets on top of a graph's defaults (module doc), then `--param`s.
fn parameters(graph: &Path, o: &Options) -> Vec<(String, Vec<f32>)> {
    let stem = graph.file_stem().unwrap_or_default().to_string_lossy();
    let mut params: Vec<(String, Vec<f32>)> = match stem.as_ref() {
        "uplift_stack" => [("metalness", 0.5), ("fuzz_weight", 0.3), ("coat_weight", 0.5), ("inner_weight", 0.4), ("subcutaneous_weight", 0.5)]
            .iter()
            .map(|(n, v)| (n.to_string(), vec![*v]))
            .collect(),
        "bsdf_conductor" => vec![("roughness".to_string(), vec![0.3, 0.3])],
        _ => Vec::new(),
    };
    params.extend(o.params.iter().cloned());
    // Inputs bound at compile time are no inputs of the kernel.
    params.retain(|(n, _)| !o.set.iter().any(|(s, _)| s == n));
    params
}

/// Seeded points on a sphere of radius 3 (world position, normal, tangent) with the documented
/// interface inputs.
fn batch(kernel: &PatternKernel, n: usize, params: &[(String, Vec<f32>)], random_params: bool, per_view: usize) -> PatternBatch {
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
    let mut defaults: Vec<f32> = kernel.inputs.iter().flat_map(|i| i.input.default.clone()).collect();
    for (name, values) in params {
        let input = kernel.inputs.iter().find(|i| &i.input.name == name).unwrap_or_else(|| panic!("--param {name}: the graph has no such input"));
        assert_eq!(values.len(), input.input.ty.components().unwrap_or(0), "--param {name}: wrong number of components");
        defaults[input.offset..input.offset + values.len()].copy_from_slice(values);
    }
    let mut rows: Vec<f32> = (0..n).flat_map(|_| defaults.iter().copied()).collect();
    if random_params {
        // Every uplift_stack parameter per row, inside its range (weights ≥ 5 % of it); each
        // parameter's column found once.
        let stack = uplift_engines::stack::Stack::builtin();
        // (Inputs a specialised kernel no longer has are skipped.)
        let columns: Vec<(usize, &uplift_engines::stack::Parameter)> = stack
            .parameters()
            .iter()
            .filter_map(|p| kernel.inputs.iter().find(|i| i.input.name == p.input).map(|input| (input.offset + p.component, p)))
            .collect();
        assert!(!columns.is_empty(), "--random-params: the graph has none of uplift_stack's inputs");
        for row in rows.chunks_mut(kernel.input_stride) {
            for &(c, p) in &columns {
                row[c] = p.lo + (p.hi - p.lo) * (0.05 + 0.95 * next());
            }
        }
    }
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
                // Uniform on the upper hemisphere (as bsdf_rate.py draws Mitsuba's).
                let r = (1.0 - u1 * u1).max(0.0).sqrt();
                let phi = std::f32::consts::TAU * u2;
                [r * phi.cos(), r * phi.sin(), u1]
            };
            row[kernel.inputs[d].offset..kernel.inputs[d].offset + 3].copy_from_slice(&v);
        }
    }
    // Groups of `per_view` rows share the first one's view and parameters (the grouped layout).
    if per_view > 1 {
        assert!(n % per_view == 0, "--per-view {per_view} does not divide --points {n}");
        let stride = kernel.input_stride;
        let shared: Vec<usize> = kernel.inputs.iter().filter(|i| !["wl", "u"].contains(&i.input.name.as_str())).flat_map(|i| i.offset..i.offset + i.input.ty.components().unwrap_or(1)).collect();
        for r in 0..n {
            let leader = r - r % per_view;
            for &c in &shared {
                rows[r * stride + c] = rows[leader * stride + c];
            }
        }
    }
    // One frame and (without --random-params) one material for the whole batch, as Mitsuba's
    // benchmark has them: those columns are marked uniform, so the CPU engine does not stream
    // them from memory.
    let mut b = PatternBatch::from_rows(&vec![local; n], &rows, kernel.input_stride, vec![]);
    b.geometry.mark_uniform_columns();
    b.inputs.mark_uniform_columns();
    b.points_per_group = per_view;
    b
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
    let mut compiler = Compiler::builtin();
    compiler.constant_inputs = o.set.clone();
    let c = compiler.compile_file_in(&graph, &OutputSelection::AllNumeric, o.context);
    let kernel = c.kernel.unwrap_or_else(|| panic!("{}: {:?}", graph.display(), c.diagnostics.iter().map(|d| d.to_string()).collect::<Vec<_>>()));
    let params = parameters(&graph, &o);
    let b = batch(&kernel, o.points, &params, o.random_params, o.per_view);
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
    println!("CPU level: {} (SIMD level {})", all.cpu_level(), uplift_simd::Level::detect().name());
    if !params.is_empty() || o.random_params {
        let set: Vec<String> = params.iter().map(|(n, v)| format!("{n}={}", v.iter().map(|x| x.to_string()).collect::<Vec<_>>().join(","))).collect();
        println!("parameters: {}{}", set.join(" "), if o.random_params { " (then every uplift_stack parameter random per row)" } else { "" });
    }
    let prepared = all.prepare(&kernel).unwrap();
    // Outputs go into one reused buffer, as Mitsuba's (Dr.Jit's caching allocator hands back
    // memory without clearing it): what is timed is evaluation, not allocation.
    let mut out = Columns::zeros(0, 0);
    let (cpu1, cpu_all) = match &prepared {
        CpuKernel::Builtin(_) => {
            let cpu1 = rate(o.points, o.seconds, || {
                one.run_prepared_into(&prepared, &b, &mut out).unwrap();
            });
            let cpu_all = rate(o.points, o.seconds, || {
                all.run_prepared_into(&prepared, &b, &mut out).unwrap();
            });
            let form = match &prepared {
                CpuKernel::Builtin(k) if k.grouped.is_some() && o.per_view >= uplift_engines::cpu_engine::GROUPED_MIN_POINTS && uplift_kernels::grouped::preferred() => {
                    format!("dependence-split packet kernel, {} points per view, {}", o.per_view, uplift_simd::Level::current().name())
                }
                CpuKernel::Builtin(k) if k.is_packet() && uplift_simd::Level::current() == uplift_simd::Level::Avx512 => format!("packet kernel, {}", uplift_simd::Level::current().name()),
                _ => "scalar kernel".to_string(),
            };
            println!("cpu  in-process   1 thread : {}  ({form})", mega(cpu1));
            println!("cpu  in-process {threads:2} threads: {}  ({:.2}× one thread)", mega(cpu_all), cpu_all / cpu1);
            // A kernel shipped in packet form: the scalar writer's kernel too (what it replaces).
            if let CpuKernel::Builtin(k) = &prepared {
                if let Some(scalar) = k.scalar {
                    let scalar = CpuKernel::Builtin(Box::leak(Box::new(uplift_kernels::shipped::BuiltinKernel { batch: scalar, scalar: None, grouped: None, ..**k })));
                    let s1 = rate(o.points, o.seconds, || {
                        one.run_prepared_into(&scalar, &b, &mut out).unwrap();
                    });
                    let s_all = rate(o.points, o.seconds, || {
                        all.run_prepared_into(&scalar, &b, &mut out).unwrap();
                    });
                    println!("cpu  in-process   1 thread : {}  (scalar kernel; packet {:.2}×)", mega(s1), cpu1 / s1);
                    println!("cpu  in-process {threads:2} threads: {}  (scalar kernel; packet {:.2}×)", mega(s_all), cpu_all / s_all);
                }
            }
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

    if o.in_process {
        print_mitsuba(&o, threads, cpu_all);
        return;
    }

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
    for (n, v) in &o.params {
        child_args.extend(["--param".to_string(), format!("{n}={}", v.iter().map(|x| x.to_string()).collect::<Vec<_>>().join(","))]);
    }
    if o.random_params {
        child_args.push("--random-params".into());
    }
    if o.per_view > 1 {
        child_args.extend(["--per-view".to_string(), o.per_view.to_string()]);
    }
    for (n, v) in &o.set {
        child_args.extend(["--set".to_string(), format!("{n}={v}")]);
    }
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

    print_mitsuba(&o, threads, cpu_all);
}

/// Mitsuba's figure and uplift's ratio to it (`--mitsuba`).
fn print_mitsuba(o: &Options, threads: usize, cpu_all: f64) {
    if let Some(bsdf) = &o.mitsuba {
        match mitsuba_rate(bsdf, o, threads) {
            Ok((r, line)) => println!("mitsuba {line}: {}  (uplift CPU {threads} threads / mitsuba = {:.3}×)", mega(r), cpu_all / r),
            Err(e) => println!("mitsuba: {e}"),
        }
    }
}

/// Mitsuba's rate for `bsdf` on `threads` threads (benches/mitsuba/), and a line naming it.
fn mitsuba_rate(bsdf: &str, o: &Options, threads: usize) -> Result<(f64, String), String> {
    let here = Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/mitsuba");
    let venv = cache_dir().with_file_name("mitsuba-venv");
    let setup = std::process::Command::new("bash").arg(here.join("setup.sh")).arg(&venv).output().map_err(|e| format!("cannot run setup.sh: {e}"))?;
    if !setup.status.success() {
        return Err(format!("setup.sh failed: {}{}", String::from_utf8_lossy(&setup.stdout), String::from_utf8_lossy(&setup.stderr)));
    }
    let out = std::process::Command::new(venv.join("bin/python"))
        .arg(here.join("bsdf_rate.py"))
        .args(["--bsdf", bsdf, "--points", &o.points.to_string(), "--seconds", &o.seconds.to_string(), "--threads", &threads.to_string()])
        .output()
        .map_err(|e| format!("cannot run bsdf_rate.py: {e}"))?;
    let text = String::from_utf8_lossy(&out.stdout);
    let line = text.lines().last().unwrap_or_default();
    let json: serde_json::Value = serde_json::from_str(line).map_err(|_| format!("bsdf_rate.py said: {text}{}", String::from_utf8_lossy(&out.stderr)))?;
    let rate = json["rate"].as_f64().ok_or("bsdf_rate.py gave no rate")?;
    Ok((rate, format!("{} {} `{bsdf}`, {threads} threads", json["mitsuba"].as_str().unwrap_or("?"), json["variant"].as_str().unwrap_or("?"))))
}
