//! uplift's runtime: the engines that run compiled kernels (wgpu now; the CPU engine comes
//! with the Rust backend), and the `uplift` CLI's subcommands.

pub mod atomic_write;
pub mod cli;
pub mod csv_table;
pub mod texture_loader;
pub mod wgpu_engine;
