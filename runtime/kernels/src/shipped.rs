//! The CPU kernels built into the runtime: every shipped graph (`runtime/kernels/graphs/*.mtlx`,
//! `examples/marble.mtlx`, the uplift rules) compiled by `uplift_compiler::build_api` into
//! `generated/` with the table re-exported here (committed; `compiler/tests/snapshots.rs` keeps
//! it current). The CPU engine finds a kernel by the fingerprint of its generated Rust, so a
//! document that compiles to the same code runs in-process.

use crate::driver::BatchFn;
use crate::KernelShape;

/// One shipped kernel.
#[derive(Clone, Copy)]
pub struct BuiltinKernel {
    /// The generated module's name (the document's stem).
    pub name: &'static str,
    /// The document, relative to the repository root.
    pub source: &'static str,
    /// The closure context (`eval`, `albedo`, `sample`) of a BSDF graph's kernel.
    pub context: Option<&'static str>,
    /// `uplift_compiler::build_api::kernel_fingerprint` of its generated Rust (with its own
    /// albedo tables, as a runtime compiling the same document writes it).
    pub fingerprint: u64,
    pub shape: KernelShape,
    /// The kernel behind runtime CPU dispatch: its packet form (`packet_batch_fn!`) where it
    /// ships one, else `mx_pattern_batch` (`cpu_batch_fn!`).
    pub batch: BatchFn,
    /// Where `batch` is a packet kernel: the scalar writer's kernel (`cpu_batch_fn!`), its
    /// oracle and its fallback without SIMD (the same function, compiled once).
    pub scalar: Option<BatchFn>,
    /// The dependence-split form of a packet BSDF kernel (`uplift_compiler::packet_split`),
    /// for batches whose points come in groups sharing everything but the light direction or
    /// the sample's random numbers.
    pub grouped: Option<Grouped>,
}

/// A packet kernel's grouped batch entry (`mx_pattern_grouped_batch_simd` of
/// `templates/packet_kernel.rs`): `run(geom, inputs, outputs, k)` evaluates groups of `k`
/// points, reading the input columns in `point_columns` per point and every other column per
/// group (`n / k` values) or per batch (1); `false`, having done nothing, without AVX-512 or
/// AVX2.
/// A grouped kernel's entry: point columns, group columns, output columns, group size.
pub type GroupedRun = fn(&[&[f32]], &[&[f32]], &mut [&mut [f32]], usize) -> bool;

#[derive(Clone, Copy)]
pub struct Grouped {
    pub run: GroupedRun,
    pub point_columns: &'static [usize],
}

impl BuiltinKernel {
    /// Whether `batch` is a packet kernel (it takes uniform columns as one value,
    /// `driver::run_column_blocks`).
    pub fn is_packet(&self) -> bool {
        self.scalar.is_some()
    }

    /// The scalar writer's kernel: `scalar` for a packet kernel, else `batch` itself.
    pub fn scalar_batch(&self) -> BatchFn {
        self.scalar.unwrap_or(self.batch)
    }
}

/// The `uplift_stack` closure graph (source path, text): the stack every enhanced material
/// shades with, shipped in every closure context.
pub const UPLIFT_STACK_GRAPH: (&str, &str) = ("runtime/kernels/graphs/bsdf/uplift_stack.mtlx", include_str!("../graphs/bsdf/uplift_stack.mtlx"));

/// The glint pattern graph (source path, text) the renderer evaluates at its hits.
pub const GLINT_FACTOR_GRAPH: (&str, &str) = ("runtime/kernels/graphs/glint_factor.mtlx", include_str!("../graphs/glint_factor.mtlx"));

pub use crate::generated::BUILTIN_KERNELS;

/// The shipped kernel whose generated Rust has this fingerprint.
pub fn find(fingerprint: u64) -> Option<&'static BuiltinKernel> {
    BUILTIN_KERNELS.iter().find(|k| k.fingerprint == fingerprint)
}

/// The shipped kernel named `name` (a document stem).
pub fn by_name(name: &str) -> Option<&'static BuiltinKernel> {
    BUILTIN_KERNELS.iter().find(|k| k.name == name)
}
