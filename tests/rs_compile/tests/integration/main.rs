//! The Rust snapshots' tests, one test binary (each module below was once a file of its own
//! under tests/, linking the snapshots, naga and wgpu into a binary of its own). Run one module
//! with a filter: `cargo test -p uplift_rs_snapshots --test integration semantics::`.

mod cpu_vs_wgpu;
mod kernels;
mod oracle_naga_rust_back;
mod packet_vs_scalar;
mod semantics;
