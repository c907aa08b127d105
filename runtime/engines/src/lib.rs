//! The engines: the batch API (`batch`) and its two implementations — the CPU engine
//! (`cpu_engine`: shipped kernels in-process, cargo-built runners for other documents) and the
//! wgpu engine (`wgpu_engine`: the same kernels as WGSL compute shaders) — texture loading for
//! pattern inputs (`texture_loader`), tables of points as batches (`table_batch`), and the `uplift_stack` closure kernels on either engine
//! (`stack_kernel`) with the stack itself, read from its nodedef at run time (`stack`).
//!
//! Must never: depend on enhancement, neural, render or the CLI; know what a material folder is.

pub mod batch;
pub mod cpu_engine;
pub mod prepared_kernel;
pub mod stack;
pub mod stack_kernel;
pub mod table_batch;
pub mod texture_loader;
pub mod wgpu_engine;
