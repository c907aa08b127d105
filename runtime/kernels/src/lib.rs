//! The CPU kernels the runtime ships, and the contract every CPU kernel runs under.
//!
//! - `driver`: the batch ABI of a generated kernel (`mx_pattern_batch` over column slices, its
//!   textures, [`driver::BatchFn`]), runtime CPU dispatch (`cpu_batch_fn!`) and the parallel
//!   block loop. The same file is copied into the kernel runners the CPU engine builds for other
//!   documents ([`DRIVER_SOURCE`]).
//! - `shipped`: the kernels compiled from `graphs/`, `examples/marble.mtlx` and the uplift
//!   rules, each with the fingerprint of its generated Rust; the code is in `generated/`,
//!   committed and kept current by `compiler/tests/snapshots.rs` (`UPLIFT_BLESS=1` rewrites it).
//! - `albedo_table_data`: the pbrlib albedo tables, once; every shipped kernel that reads them
//!   uses this one static instead of its own copy.
//! - `albedo_tables`: the quasi-Monte-Carlo integrator that computes those tables
//!   (`uplift tables`), with its brute-force error measurement.
//!
//! Must never: depend on an engine or any higher runtime crate (engines find their shipped
//! kernels here, not the other way round).

pub mod albedo_tables;
pub mod driver;
pub mod generated;
pub mod grouped;
pub mod shipped;

/// The pbrlib albedo tables as one static (generated from the node library).
pub use generated::albedo_table_data;

/// The text of `driver.rs`, which the CPU engine copies into every kernel runner it builds.
pub const DRIVER_SOURCE: &str = include_str!("driver.rs");

/// A kernel's interface as a batch meets it: its input and output columns and its textures.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct KernelShape {
    pub input_columns: usize,
    pub output_columns: usize,
    pub texture_count: usize,
}
