//! Kernels the runtime was not built with (any document, any `--library`): the CPU engine
//! writes the kernel's generated Rust into a small crate — the runner, `kernel_runner/main.rs`,
//! with this engine's `driver.rs` and `runner_protocol.rs` — builds it once with cargo into a
//! cache folder, and runs it as a child process that reads a batch on stdin and writes the
//! output columns on stdout. Runners are keyed by a fingerprint of everything they are built
//! from, so a cached one is reused until the kernel, the runner or its dependencies change.
//! A runner may hold many kernels (`build_bundle`: one cargo build for all of them, the albedo
//! tables once instead of once per kernel); the runner's first argument picks one.

use super::runner_protocol::{decode_floats, encode_request, Request};
use crate::batch::{Columns, KernelShape, PatternBatch};
use std::borrow::Cow;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use uplift_compiler::build_api::{fnv1a, FNV1A_START};

const RUNNER_MAIN: &str = include_str!("../../kernel_runner/main.rs");
const DRIVER: &str = uplift_kernels::DRIVER_SOURCE;
const PROTOCOL: &str = include_str!("runner_protocol.rs");

/// LLVM's options for kernel code, passed as `-C llvm-args=…` (the workspace's
/// `.cargo/config.toml` passes the same to the crates it builds, a test checks):
/// - `-unroll-threshold=6000` (LLVM's default at -O3 is 300). Library loops with a trip count
///   that is constant once inlined, such as fractal noise's octaves, must be unrolled fully for
///   the batch loop around them to vectorise: measured on `runtime/kernels/graphs/triplanar_mask.mtlx`
///   (three 3-octave fractal3d), one thread, AVX2: 0.79 M evals/s at the default, 0.80 at 1000,
///   6.8 at 3000, 10.9 at 6000.
/// - `-alias-set-saturation-threshold=10000` (default 250). Past that many pointers in one
///   alias set LLVM's alias-set tracker gives up and treats every access as aliasing every
///   other, so the loop vectoriser cannot prove the batch loop safe; a layered BSDF reads its
///   albedo tables at a few hundred places (`runtime/kernels/graphs/bsdf/bsdf_stack.mtlx`, eval
///   context: 59 bilinear lookups). Measured on that graph, one thread, AVX-512: 1.2 M evals/s
///   at the default (scalar), 6.1 M at 10000.
pub const KERNEL_LLVM_ARGS: [&str; 2] = ["-unroll-threshold=6000", "-alias-set-saturation-threshold=10000"];

/// Where runners are built and how.
#[derive(Clone, Debug)]
pub struct RunnerOptions {
    /// Cache folder (runner crates in `kernels/`, their shared cargo target folders beside).
    pub cache_dir: PathBuf,
    /// `false` builds with LLVM's loop and SLP vectorisers off (`-C no-vectorize-loops -C
    /// no-vectorize-slp`): the benchmark's reference for what vectorisation gains.
    pub vectorize: bool,
    /// `true` builds at opt-level 0 without [`KERNEL_LLVM_ARGS`]: for one-off kernels of
    /// thousands of nodes in differential tests, whose optimised build takes LLVM tens of
    /// minutes (and whose speed does not matter). The default is `true` when the environment
    /// sets `UPLIFT_RUNNER_QUICK=1` (tests that run the binary on kernels it does not ship).
    pub quick: bool,
}

impl Default for RunnerOptions {
    fn default() -> Self {
        RunnerOptions { cache_dir: default_cache_dir(), vectorize: true, quick: std::env::var_os("UPLIFT_RUNNER_QUICK").is_some_and(|v| v == "1") }
    }
}

/// `$UPLIFT_CACHE_DIR`, else `$XDG_CACHE_HOME/uplift`, else `~/.cache/uplift`, else a folder in
/// the system's temporary directory.
pub fn default_cache_dir() -> PathBuf {
    if let Some(d) = std::env::var_os("UPLIFT_CACHE_DIR").filter(|d| !d.is_empty()) {
        return PathBuf::from(d);
    }
    if let Some(d) = std::env::var_os("XDG_CACHE_HOME").filter(|d| !d.is_empty()) {
        return PathBuf::from(d).join("uplift");
    }
    if let Some(h) = std::env::var_os("HOME").filter(|d| !d.is_empty()) {
        return PathBuf::from(h).join(".cache/uplift");
    }
    std::env::temp_dir().join("uplift-cache")
}

/// A built runner and which of its kernels to run.
#[derive(Clone, Debug)]
pub struct ExternalKernel {
    pub exe: PathBuf,
    /// The kernel's index in its runner (`build_bundle`'s order; 0 for `build`).
    pub index: usize,
    pub shape: KernelShape,
}

/// The runner crate's manifest.
fn manifest(name: &str) -> String {
    format!(
        "# Written by uplift's CPU engine (runtime/engines/src/cpu_engine/external.rs): the runner of one kernel.\n\
         [package]\nname = \"{name}\"\nversion = \"0.0.0\"\nedition = \"2021\"\npublish = false\n\n\
         [dependencies]\n\
         glam = {{ version = \"{}\", default-features = false, features = [\"std\"] }}\n\
         rayon = \"{}\"\n\
         multiversion = \"{}\"\n\n\
         [profile.release]\ndebug = false\n\n\
         # Not part of any enclosing workspace.\n[workspace]\n",
        env!("UPLIFT_RUNNER_GLAM_VERSION"),
        env!("UPLIFT_RUNNER_RAYON_VERSION"),
        env!("UPLIFT_RUNNER_MULTIVERSION_VERSION"),
    )
}

/// Builds (or finds in the cache) the runner of the kernel whose generated Rust is `rust`.
pub fn build(rust: &str, shape: KernelShape, options: &RunnerOptions) -> Result<ExternalKernel, String> {
    let mut built = build_bundle(&[(rust.to_string(), shape)], None, options)?;
    Ok(built.remove(0))
}

/// The runner's `kernels.rs`: one module per kernel (`k{i}.rs`), the shared albedo tables, and
/// the table of their batch functions and shapes.
fn kernels_module(count: usize, shared_tables: bool) -> String {
    let mut s = String::from("// Written by uplift's CPU engine (runtime/engines/src/cpu_engine/external.rs): the runner's kernels.\n");
    if shared_tables {
        s.push_str("#[allow(dead_code)]\npub mod albedo_tables {\n    include!(\"albedo_tables.rs\");\n}\n");
    }
    s.push_str("use crate::driver::{BatchFn, TextureSet};\n\n");
    for i in 0..count {
        s.push_str(&format!("#[allow(clippy::all, dead_code, unused_imports)]\npub mod k{i} {{\n    include!(\"k{i}.rs\");\n}}\n"));
    }
    s.push_str("\n/// Kernel `index`'s batch function and (geometry, input, output columns, textures).\npub fn kernel(index: usize) -> Option<(BatchFn, (usize, usize, usize, usize))> {\n    match index {\n");
    for i in 0..count {
        s.push_str(&format!("        {i} => Some((cpu_batch_fn!(k{i}), (k{i}::GEOMETRY_COLUMNS, k{i}::INPUT_COLUMNS, k{i}::OUTPUT_COLUMNS, k{i}::TEXTURE_COUNT))),\n"));
    }
    s.push_str("        _ => None,\n    }\n}\n");
    s
}

/// The module path under which a bundle's kernels find the shared albedo tables (pass it as
/// `RustOptions::albedo_table_data` when writing them).
pub const BUNDLE_ALBEDO_TABLES: &str = "crate::kernels::albedo_tables::MX_ALBEDO_TABLE_DATA";

/// Builds (or finds in the cache) one runner holding every kernel of `kernels` (generated Rust
/// and shape), in order. `albedo_tables` is the source of the `static` the kernels were
/// written to share ([`BUNDLE_ALBEDO_TABLES`]), if any. One cargo build for all of them.
pub fn build_bundle(kernels: &[(String, KernelShape)], albedo_tables: Option<&str>, options: &RunnerOptions) -> Result<Vec<ExternalKernel>, String> {
    let variant = match (options.vectorize, options.quick) {
        (_, true) => "-quick",
        (true, false) => "",
        (false, false) => "-novec",
    };
    let module = kernels_module(kernels.len(), albedo_tables.is_some());
    // One runner per distinct kernel code: each kernel's text is hashed without its first line,
    // which names the document it came from (uplift_compiler::build_api::kernel_fingerprint),
    // so one kernel read from another path, a staging copy or another material is one runner.
    let mut h = FNV1A_START;
    for part in kernels.iter().map(|k| k.0.split_once('\n').map_or("", |(_, body)| body)).chain([albedo_tables.unwrap_or(""), module.as_str(), RUNNER_MAIN, DRIVER, PROTOCOL, &manifest(""), &KERNEL_LLVM_ARGS.join(" ")]) {
        h = fnv1a(h, part.as_bytes());
        h = fnv1a(h, &[0]);
    }
    let name = format!("uplift-kernel-{h:016x}{variant}");
    let kernels_dir = options.cache_dir.join("kernels");
    let crate_dir = kernels_dir.join(&name);
    let target_dir = kernels_dir.join(format!("target{variant}"));
    let exe = target_dir.join("release").join(format!("{name}{}", std::env::consts::EXE_SUFFIX));
    let built: Vec<ExternalKernel> = kernels.iter().enumerate().map(|(index, k)| ExternalKernel { exe: exe.clone(), index, shape: k.1 }).collect();
    if exe.is_file() {
        return Ok(built);
    }
    let src = crate_dir.join("src");
    std::fs::create_dir_all(&src).map_err(|e| format!("{}: cannot create the kernel runner's folder: {e}", src.display()))?;
    let mut files = vec![
        (crate_dir.join("Cargo.toml"), manifest(&name)),
        (src.join("main.rs"), RUNNER_MAIN.to_string()),
        (src.join("driver.rs"), DRIVER.to_string()),
        (src.join("runner_protocol.rs"), PROTOCOL.to_string()),
        (src.join("kernels.rs"), module),
    ];
    files.extend(kernels.iter().enumerate().map(|(i, k)| (src.join(format!("k{i}.rs")), k.0.clone())));
    files.extend(albedo_tables.map(|t| (src.join("albedo_tables.rs"), t.to_string())));
    for (path, text) in files {
        uplift_base::atomic_write::write_atomically(&path, text.as_bytes()).map_err(|e| format!("{}: {e}", path.display()))?;
    }
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let run_cargo = |offline: bool| {
        let mut c = Command::new(&cargo);
        c.arg("build").arg("--release").arg("--quiet").arg("--manifest-path").arg(crate_dir.join("Cargo.toml"));
        if offline {
            c.arg("--offline");
        }
        // Flags are the runner's own: not the caller's RUSTFLAGS, nor a `.cargo/config.toml`
        // around the caller's working directory.
        let mut flags: Vec<String> = if options.quick { Vec::new() } else { KERNEL_LLVM_ARGS.iter().map(|a| format!("-Cllvm-args={a}")).collect() };
        if options.quick {
            c.env("CARGO_PROFILE_RELEASE_OPT_LEVEL", "0");
        }
        if !options.vectorize {
            flags.extend(["-Cno-vectorize-loops".to_string(), "-Cno-vectorize-slp".to_string()]);
        }
        c.current_dir(&crate_dir).env("CARGO_TARGET_DIR", &target_dir).env_remove("RUSTFLAGS").env_remove("CARGO_BUILD_RUSTFLAGS");
        c.env("CARGO_ENCODED_RUSTFLAGS", flags.join("\u{1f}"));
        uplift_base::child_process::tie_to_parent(&mut c).stdin(Stdio::null()).output()
    };
    let describe = |e: std::io::Error| format!("the CPU engine builds kernels it was not built with by running cargo ({}), which failed to start: {e}; install Rust (rustup) or use --engine wgpu", Path::new(&cargo).display());
    // Offline first (the dependencies are usually cached); online when they are not.
    eprintln!("uplift: building the CPU kernel runner {name} ({} kernel{}) with cargo (once; cached in {})", kernels.len(), if kernels.len() == 1 { "" } else { "s" }, kernels_dir.display());
    let mut out = run_cargo(true).map_err(describe)?;
    if !out.status.success() {
        out = run_cargo(false).map_err(describe)?;
    }
    if !out.status.success() {
        let stderr = String::from_utf8_lossy(&out.stderr);
        let tail: Vec<&str> = stderr.lines().rev().take(30).collect();
        return Err(format!(
            "building the CPU kernel runner in {} failed ({}):\n{}",
            crate_dir.display(),
            out.status,
            tail.into_iter().rev().collect::<Vec<_>>().join("\n")
        ));
    }
    if !exe.is_file() {
        return Err(format!("cargo built the kernel runner but {} does not exist", exe.display()));
    }
    Ok(built)
}

/// The request for `batch` on `threads` threads.
fn request(k: &ExternalKernel, batch: &PatternBatch, threads: usize) -> Vec<u8> {
    encode_request(&Request {
        n: batch.n(),
        geometry_columns: batch.geometry.width(),
        input_columns: k.shape.input_columns,
        output_columns: k.shape.output_columns,
        threads,
        textures: batch.textures.iter().map(|t| (t.width, t.height, Cow::Borrowed(t.rgba.as_slice()))).collect(),
        geometry: Cow::Borrowed(batch.geometry.data()),
        inputs: Cow::Borrowed(batch.inputs.data()),
    })
}

/// Runs the runner with `args`, `input` on stdin; returns its stdout.
fn exchange(k: &ExternalKernel, args: &[&str], input: Vec<u8>) -> Result<Vec<u8>, String> {
    let mut child = uplift_base::child_process::tie_to_parent(&mut Command::new(&k.exe))
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| format!("{}: cannot start the kernel runner: {e}", k.exe.display()))?;
    let mut stdin = child.stdin.take().expect("piped stdin");
    let writer = std::thread::spawn(move || stdin.write_all(&input));
    let mut stdout = Vec::new();
    child.stdout.take().expect("piped stdout").read_to_end(&mut stdout).map_err(|e| format!("reading the kernel runner's output: {e}"))?;
    let mut stderr = String::new();
    let _ = child.stderr.take().expect("piped stderr").read_to_string(&mut stderr);
    let status = child.wait().map_err(|e| format!("waiting for the kernel runner: {e}"))?;
    let written = writer.join().map_err(|_| "the request writer panicked".to_string())?;
    if !status.success() {
        return Err(format!("the kernel runner {} failed ({status}): {}", k.exe.display(), stderr.trim()));
    }
    written.map_err(|e| format!("writing the request to the kernel runner: {e}"))?;
    Ok(stdout)
}

/// Evaluates `batch` with the runner, on `threads` threads.
pub fn run(k: &ExternalKernel, batch: &PatternBatch, threads: usize) -> Result<Columns, String> {
    let n = batch.n();
    if n == 0 {
        return Ok(Columns::zeros(0, k.shape.output_columns));
    }
    let out = exchange(k, &[&k.index.to_string()], request(k, batch, threads))?;
    Columns::from_column_major(n, k.shape.output_columns, decode_floats(&out)?).map_err(|e| format!("the kernel runner's output: {e}"))
}

/// Evaluations per second of the runner over `batch` on `threads` threads (at least `seconds`
/// of repeated runs after a warm-up), and the CPU level it dispatched to.
pub fn bench(k: &ExternalKernel, batch: &PatternBatch, threads: usize, seconds: f64) -> Result<(f64, String), String> {
    let out = exchange(k, &[&k.index.to_string(), "bench", &seconds.to_string()], request(k, batch, threads))?;
    let text = String::from_utf8_lossy(&out);
    let rate = text.split_whitespace().find_map(|w| w.strip_prefix("evals_per_second=")).and_then(|v| v.parse().ok());
    let level = text.split_once("level=").map(|(_, l)| l.trim().to_string());
    match (rate, level) {
        (Some(r), Some(l)) => Ok((r, l)),
        _ => Err(format!("unexpected benchmark output from the kernel runner: {text}")),
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_workspace_builds_kernels_with_the_runners_llvm_options() {
        let config = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../.cargo/config.toml")).expect(".cargo/config.toml");
        for arg in super::KERNEL_LLVM_ARGS {
            let flag = format!("\"-Cllvm-args={arg}\"");
            assert!(config.lines().any(|l| l.starts_with("rustflags") && l.contains(&flag)), "{flag} not in .cargo/config.toml");
        }
    }
}
