//! uplift's runtime: the engines that run compiled kernels (wgpu now; the CPU engine comes
//! with the Rust backend), and the `uplift` CLI's subcommands.

pub mod atomic_write;
pub mod cli;
pub mod wgpu_engine;
