//! The runtime's integration tests, one test binary: every module below was once its own file
//! under tests/, and each such file linked the whole runtime (wgpu, naga, the shipped kernels)
//! into a binary of its own — 21 links of ~100 MB on every cold build. One binary links once,
//! shares the wgpu device and the compiled library between tests, and lets the test harness
//! run slow and fast tests side by side. Run one module with a filter:
//! `cargo test -p uplift --test integration closures::`.

mod common;
mod graph_kit;
mod nodedef_harness;

mod albedo_tables;
mod cli;
mod cli_coverage;
mod cli_eval;
mod closures;
mod cpu_engine;
mod datagen_engines;
mod demo_report;
mod enhance;
mod export;
mod fuzz_enhance;
mod glints;
mod grazing_views;
mod hostile;
mod iridescence;
mod kill_resume;
mod layering;
mod materials;
mod neural_decoder;
mod neural_fit_wgpu;
mod neural_train_wgpu;
mod neural_gradients;
mod neural_inference;
mod neural_training;
mod numeric_channel_conditional;
mod numeric_compositing_adjustment;
mod numeric_math;
mod numeric_noise;
mod numeric_procedural;
mod numeric_smoke;
mod pack;
mod project;
mod numeric_texture;
mod random_graphs;
mod render;
mod sampler;
mod shard;
mod specialisation;
mod stack_extension;
mod uplift_stack;
