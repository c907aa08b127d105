//! The runtime's bottom layer: what every other runtime crate may use and that depends on no
//! other uplift crate. Atomic output files (`atomic_write`), output folders that never destroy
//! what a command did not write (`output_folder`), seeded random numbers and stable
//! hashes (`rng`), colour-space transfer functions (`color`), and the file codecs the runtime
//! reads and writes (`exr`: OpenEXR; `csv_table`: `uplift eval`'s tables); `test_env` says how a test
//! skips when the machine lacks a tool (and fails instead under `UPLIFT_REQUIRE_ALL=1`).
//!
//! Must never: depend on the compiler, an engine or any higher runtime crate.

pub mod atomic_write;
pub mod child_process;
pub mod color;
pub mod csv_table;
pub mod exr;
pub mod output_folder;
pub mod random_scalar;
pub mod rng;
pub mod test_env;
