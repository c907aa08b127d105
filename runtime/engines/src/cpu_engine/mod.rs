//! The CPU engine: generated Rust kernels, parallel over blocks of points with rayon, each batch
//! loop compiled for several CPU levels with runtime dispatch (`uplift_kernels::driver`). A
//! kernel the runtime ships (`uplift_kernels::shipped`, generated in `runtime/kernels/src/generated/`)
//! runs in-process; any other kernel is built once with cargo into a cached runner and run as a
//! child process (`external.rs`). Both paths run the same generated `mx_pattern_batch` through
//! the same driver.

pub use uplift_kernels::{driver, grouped, shipped};
pub mod external;
pub mod runner_protocol;

use crate::batch::{Columns, KernelShape, PatternBatch, PatternEngine};
use driver::{TextureImage, TextureSet};
use external::{ExternalKernel, RunnerOptions};
use uplift_compiler::backend_rust::{write_albedo_table_static, write_rust_kernel, write_rust_kernel_with, RustOptions};
use uplift_compiler::build_api::kernel_fingerprint;
use uplift_compiler::kernel::GEOMETRY_STRIDE;
use uplift_compiler::PatternKernel;

/// A kernel ready to run on the CPU.
pub enum CpuKernel {
    /// Shipped with the runtime: runs in-process.
    Builtin(&'static shipped::BuiltinKernel),
    /// Built on demand: runs in a cached runner process.
    External(ExternalKernel),
}

impl CpuKernel {
    pub fn shape(&self) -> &KernelShape {
        match self {
            CpuKernel::Builtin(k) => &k.shape,
            CpuKernel::External(k) => &k.shape,
        }
    }

    /// Where the kernel's code comes from.
    pub fn describe(&self) -> String {
        match self {
            CpuKernel::Builtin(k) => format!("built-in kernel `{}` ({})", k.name, k.source),
            CpuKernel::External(k) => format!("kernel runner {}", k.exe.display()),
        }
    }
}

/// The CPU engine: a rayon pool and where to build runners.
pub struct CpuEngine {
    pool: rayon::ThreadPool,
    threads: usize,
    runner: RunnerOptions,
}

impl CpuEngine {
    /// An engine on every available core.
    pub fn new() -> Result<CpuEngine, String> {
        Self::with_threads(std::thread::available_parallelism().map_or(1, |n| n.get()))
    }

    /// An engine on `threads` threads (at least one).
    pub fn with_threads(threads: usize) -> Result<CpuEngine, String> {
        let threads = threads.max(1);
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().map_err(|e| format!("cannot start the CPU engine's threads: {e}"))?;
        Ok(CpuEngine { pool, threads, runner: RunnerOptions::default() })
    }

    /// Builds kernel runners under `dir` instead of the default cache folder.
    pub fn with_cache_dir(mut self, dir: impl Into<std::path::PathBuf>) -> CpuEngine {
        self.runner.cache_dir = dir.into();
        self
    }

    pub fn threads(&self) -> usize {
        self.threads
    }

    /// The CPU level the batch loops dispatch to on this machine.
    pub fn cpu_level(&self) -> &'static str {
        driver::cpu_level()
    }

    /// Whether `kernel` is one the runtime ships (runs in-process, no runner to build).
    pub fn is_shipped(kernel: &PatternKernel) -> bool {
        rust_of(kernel).is_ok_and(|rust| shipped::find(kernel_fingerprint(&rust)).is_some())
    }

    /// Finds `kernel` among the shipped ones (by the fingerprint of its generated Rust), or
    /// builds its runner (the first time for a given kernel: a cargo build).
    pub fn prepare(&self, kernel: &PatternKernel) -> Result<CpuKernel, String> {
        let rust = rust_of(kernel)?;
        match shipped::find(kernel_fingerprint(&rust)) {
            Some(k) => Ok(CpuKernel::Builtin(k)),
            None => {
                crate::batch::check_build_size(kernel)?;
                external::build(&rust, crate::batch::kernel_shape(kernel), &self.runner).map(CpuKernel::External)
            }
        }
    }

    /// Prepares several kernels: the shipped ones in-process, the others built together in one
    /// runner (one cargo build instead of one each; `albedo_tables`: the library's table data,
    /// when a kernel reads it).
    pub fn prepare_all(&self, kernels: &[&PatternKernel], albedo_tables: Option<&[f32]>) -> Result<Vec<CpuKernel>, String> {
        let mut out: Vec<Option<CpuKernel>> = Vec::with_capacity(kernels.len());
        let mut missing = Vec::new();
        for (k, kernel) in kernels.iter().enumerate() {
            match shipped::find(kernel_fingerprint(&rust_of(kernel)?)) {
                Some(s) => out.push(Some(CpuKernel::Builtin(s))),
                None => {
                    out.push(None);
                    missing.push(k);
                }
            }
        }
        if !missing.is_empty() {
            let built = self.prepare_bundle(&missing.iter().map(|&k| kernels[k]).collect::<Vec<_>>(), albedo_tables, &self.runner)?;
            for (k, b) in missing.into_iter().zip(built) {
                out[k] = Some(b);
            }
        }
        Ok(out.into_iter().map(|k| k.expect("every kernel prepared")).collect())
    }

    /// Builds `kernel`'s runner even when it is shipped, with `options` (the benchmark builds
    /// one with vectorisation off).
    pub fn prepare_runner(&self, kernel: &PatternKernel, options: &RunnerOptions) -> Result<ExternalKernel, String> {
        crate::batch::check_build_size(kernel)?;
        external::build(&rust_of(kernel)?, crate::batch::kernel_shape(kernel), options)
    }

    /// Builds one runner holding every kernel of `kernels` (one cargo build; shipped kernels
    /// are built too), with `options`. Kernels reading the albedo tables share one copy of
    /// `albedo_tables` (the library's `NodeLibrary::albedo_table_data`) when it is given. For
    /// many kernels at once: a conformance run over a folder of documents.
    pub fn prepare_bundle(&self, kernels: &[&PatternKernel], albedo_tables: Option<&[f32]>, options: &RunnerOptions) -> Result<Vec<CpuKernel>, String> {
        kernels.iter().try_for_each(|k| crate::batch::check_build_size(k))?;
        let rust_options = RustOptions { albedo_table_data: albedo_tables.map(|_| external::BUNDLE_ALBEDO_TABLES.to_string()), ..RustOptions::default() };
        let sources = kernels
            .iter()
            .map(|k| Ok((write_rust_kernel_with(k, &rust_options).map_err(|e| format!("the kernel cannot be written as Rust: {e}"))?, crate::batch::kernel_shape(k))))
            .collect::<Result<Vec<_>, String>>()?;
        let tables = albedo_tables.map(|t| write_albedo_table_static("MX_ALBEDO_TABLE_DATA", t));
        Ok(external::build_bundle(&sources, tables.as_deref(), options)?.into_iter().map(CpuKernel::External).collect())
    }

    /// Evaluates a prepared kernel for every point of `batch` (checked against its shape).
    pub fn run_prepared(&self, kernel: &CpuKernel, batch: &PatternBatch) -> Result<Columns, String> {
        let mut out = Columns::zeros(0, 0);
        self.run_prepared_into(kernel, batch, &mut out)?;
        Ok(out)
    }

    /// [`CpuEngine::run_prepared`] into `out`, reusing its memory when it already has the
    /// output's shape (a caller evaluating batch after batch then allocates and zeroes no
    /// output: for a 10⁶-point conductor batch that was an eighth of the time). Every value
    /// of `out` is overwritten.
    pub fn run_prepared_into(&self, kernel: &CpuKernel, batch: &PatternBatch, out: &mut Columns) -> Result<(), String> {
        let n = batch.check_shape(kernel.shape())?;
        match kernel {
            CpuKernel::Builtin(k) => {
                let textures = TextureSet(batch.textures.iter().map(|t| TextureImage { width: t.width, height: t.height, rgba: &t.rgba }).collect());
                let s = &k.shape;
                if out.n() != n || out.width() != s.output_columns {
                    *out = Columns::zeros(n, s.output_columns);
                }
                // Uniform columns (`Columns::mark_uniform`) go in as their one value.
                let geometry: Vec<&[f32]> = (0..GEOMETRY_STRIDE).map(|c| batch.geometry.column_or_uniform(c)).collect();
                let inputs: Vec<&[f32]> = (0..s.input_columns).map(|c| batch.inputs.column_or_uniform(c)).collect();
                // A grouped batch through the kernel's dependence-split form, where it ships one
                // and the groups fill its packets (smaller groups leave lanes idle).
                let grouped = match (&k.grouped, batch.points_per_group) {
                    // AVX-512 only: the split kernels' AVX2 code runs below the scalar kernel
                    // (0.79–0.92× measured with `UPLIFT_SIMD=avx2`).
                    (Some(g), per_group) if per_group >= GROUPED_MIN_POINTS && grouped::preferred() => {
                        self.pool.install(|| grouped::run_grouped_blocks(g, per_group, n, &geometry, &inputs, out.data_mut(), s.output_columns))
                    }
                    _ => false,
                };
                if !grouped {
                    self.pool.install(|| driver::run_column_blocks(k.batch, k.is_packet(), n, &geometry, &inputs, out.data_mut(), s.output_columns, &textures));
                }
                Ok(())
            }
            CpuKernel::External(k) => {
                *out = external::run(k, batch, self.threads)?;
                Ok(())
            }
        }
    }
}

/// The smallest group (points per group) the CPU engine runs through a kernel's grouped form:
/// below it the point pass's packets run part empty. Measured, `uplift_stack` eval, one thread,
/// Xeon (scalar kernel 17–18 M evals/s): AVX-512 code 7.6 / 15.3 / 27.5 M evals/s at 4 / 8 / 16
/// points per group, AVX2 code 6.1 / 12.1 / 15.1.
pub const GROUPED_MIN_POINTS: usize = 16;

/// The kernel's generated Rust (what both the shipped table and the runners are built from).
fn rust_of(kernel: &PatternKernel) -> Result<String, String> {
    write_rust_kernel(kernel).map_err(|e| format!("the kernel cannot be written as Rust: {e}"))
}

impl PatternEngine for CpuEngine {
    fn describe(&self) -> String {
        format!("CPU, {} thread(s), {}", self.threads, self.cpu_level())
    }

    fn run_pattern(&self, kernel: &PatternKernel, batch: &PatternBatch) -> Result<Columns, String> {
        batch.check(kernel)?;
        let k = self.prepare(kernel)?;
        self.run_prepared(&k, batch)
    }
}
