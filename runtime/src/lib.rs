//! uplift's runtime: the batch API (`batch`) and the two engines that implement it — the CPU
//! engine (generated Rust, `cpu_engine`) and the wgpu engine (generated WGSL, `wgpu_engine`) —
//! the neural materials (`neural`: training data, trainer, fitting), and the `uplift` CLI's
//! subcommands.

pub mod albedo_tables;
pub mod atomic_write;
pub mod batch;
pub mod cli;
pub mod cpu_engine;
pub mod demo;
pub mod enhance;
pub mod exr;
pub mod neural;
pub mod render;
pub mod stack_kernel;
pub mod csv_table;
pub mod texture_loader;
pub mod wgpu_engine;
