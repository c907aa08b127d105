//! The `uplift` command line: `check` and `compile` (the compiler spine) and `eval` (run an
//! output over CSV rows); `enhance` and `masks` (uplift rules);
//! `datagen`, `train`, `fit` and `emit-decoder` (neural materials); `render`, `eval-fit`, `furnace` and `flip` (evaluation); `demo` (the main job); `export`, `pack`
//! and `project` (intrinsic videos for generative models, their WebDataset shards, and
//! generated views back into a material); `shards` and `slurm` (sharded batch runs).

mod cli;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

#[derive(Parser)]
#[command(name = "uplift", version, about = "MaterialX → naga compiler and runtime for uplifted materials")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Read a document, resolve every node, and report all diagnostics (exit 1 on error).
    Check(cli::check::CheckArgs),
    /// Compile a document's outputs to a pattern kernel.
    Compile(cli::compile::CompileArgs),
    /// Evaluate one output for every row of a CSV file of inputs; write a CSV of results.
    Eval(cli::eval::EvalArgs),
    /// Regenerate the pbrlib albedo tables by quasi-Monte-Carlo integration.
    Tables(cli::tables::TablesArgs),
    /// Enhance PBR materials into uplifted ones by an uplift rule (Types 0–5).
    Enhance(cli::enhance::EnhanceArgs),
    /// Write the uplift rules' procedural masks (dust, clearcoat damage) for a seed.
    Masks(cli::masks::MasksArgs),
    /// Write generated neural-material training data as safetensors shards.
    Datagen(cli::datagen::DatagenArgs),
    /// Train the universal encoder and decoder (paper §4.2) on generated data.
    Train(cli::train::TrainArgs),
    /// Train the sampling decoder for a trained decoder (docs/neural.md).
    TrainSampler(cli::train_sampler::TrainSamplerArgs),
    /// Fit an enhanced material's latent textures against the frozen decoder (paper §4.3).
    Fit(cli::fit::FitArgs),
    /// Write a trained decoder's inference code (Rust and WGSL).
    EmitDecoder(cli::emit_decoder::EmitDecoderArgs),
    /// Render an enhanced material (reference kernels or neural) or a MaterialX material.
    Render(cli::render::RenderArgs),
    /// Render every material of a folder of MaterialX documents; write a gallery page.
    Gallery(cli::gallery::GalleryArgs),
    /// The per-texel white furnace test of enhanced materials; --filter moves failures aside.
    Furnace(cli::furnace::FurnaceArgs),
    /// Render fitted materials reference vs neural; FLIP per Type in the paper's Table 1 format.
    EvalFit(cli::eval_fit::EvalFitArgs),
    /// The main job: enhance a procedural PBR set across all Types, fit, render, FLIP, furnace, report.
    Demo(cli::demo::DemoArgs),
    /// A fitted material on a mesh as a multi-view intrinsic video for generative models.
    Export(cli::export::ExportArgs),
    /// Exported assets as WebDataset tar shards with an index.
    Pack(cli::pack::PackArgs),
    /// Generated latent and base-colour views back into a fitted material's texture space.
    Project(cli::project::ProjectArgs),
    /// LDR-FLIP (and PSNR) of two images.
    Flip(cli::flip::FlipArgs),
    /// What the shards of sharded batch runs (`--shard i/N`) did: finished, missing, duplicated.
    Shards(cli::shards::ShardsArgs),
    /// Slurm job arrays of the batch stages (`--shard` per task), and their status.
    Slurm(cli::slurm::SlurmArgs),
}

fn main() -> ExitCode {
    uplift_engines::wgpu_engine::quiet_headless_vulkan();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Check(a) => cli::check::run(a),
        Command::Compile(a) => cli::compile::run(a),
        Command::Eval(a) => cli::eval::run(a),
        Command::Tables(a) => cli::tables::run(a),
        Command::Enhance(a) => cli::enhance::run(a),
        Command::Masks(a) => cli::masks::run(a),
        Command::Datagen(a) => cli::datagen::run(a),
        Command::Train(a) => cli::train::run(a),
        Command::TrainSampler(a) => cli::train_sampler::run(a),
        Command::Fit(a) => cli::fit::run(a),
        Command::EmitDecoder(a) => cli::emit_decoder::run(a),
        Command::Render(a) => cli::render::run(a),
        Command::Gallery(a) => cli::gallery::run(a),
        Command::Furnace(a) => cli::furnace::run(a),
        Command::Flip(a) => cli::flip::run(a),
        Command::Demo(a) => cli::demo::run(a),
        Command::EvalFit(a) => cli::eval_fit::run(a),
        Command::Export(a) => cli::export::run(a),
        Command::Pack(a) => cli::pack::run(a),
        Command::Project(a) => cli::project::run(a),
        Command::Shards(a) => cli::shards::run(a),
        Command::Slurm(a) => cli::slurm::run(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            if !message.is_empty() {
                eprintln!("{message}");
            }
            ExitCode::from(1)
        }
    }
}

