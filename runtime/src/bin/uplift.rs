//! The `uplift` command line: `check` and `compile` (the compiler spine) and `eval` (run an
//! output over CSV rows); later stages add data generation, training and rendering commands.

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
    Check(uplift::cli::check::CheckArgs),
    /// Compile a document's outputs to a pattern kernel.
    Compile(uplift::cli::compile::CompileArgs),
    /// Evaluate one output for every row of a CSV file of inputs; write a CSV of results.
    Eval(uplift::cli::eval::EvalArgs),
    /// Regenerate the pbrlib albedo tables by quasi-Monte-Carlo integration.
    Tables(uplift::cli::tables::TablesArgs),
    /// Enhance PBR materials into uplifted ones by an uplift rule (Types 0–5).
    Enhance(uplift::cli::enhance::EnhanceArgs),
    /// Write the uplift rules' procedural masks (dust, clearcoat damage) for a seed.
    Masks(uplift::cli::masks::MasksArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Check(a) => uplift::cli::check::run(a),
        Command::Compile(a) => uplift::cli::compile::run(a),
        Command::Eval(a) => uplift::cli::eval::run(a),
        Command::Tables(a) => uplift::cli::tables::run(a),
        Command::Enhance(a) => uplift::cli::enhance::run(a),
        Command::Masks(a) => uplift::cli::masks::run(a),
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

