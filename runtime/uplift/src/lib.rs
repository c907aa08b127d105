//! The `uplift` package: the command line (`src/main.rs` and its `cli` modules, one per
//! subcommand, private to the binary) and, as this library, the demo — the main job — which
//! drives every layer of the runtime (enhance, fit, render, furnace, report), and the export of
//! fitted materials as intrinsic videos for generative models (`export`), their WebDataset
//! shards (`pack`) and generated views projected back into a material (`project`); and the
//! shard contract of the batch commands (`shard`) with the Slurm job arrays that run them
//! (`slurm`).
//!
//! Nothing imports the CLI: commands are thin wrappers over the runtime's library crates, and
//! tests and benches use those crates (or run the binary).

pub mod demo;
pub mod export;
pub mod pack;
pub mod project;
pub mod seams;
pub mod shard;
pub mod slurm;
pub mod video;
