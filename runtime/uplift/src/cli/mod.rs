//! Subcommands of the `uplift` binary, one module each. Each `run` returns `Err(message)` for
//! a failure to print (already positioned as `file:line:col: …`); the binary exits 1.

pub mod bounds;
pub mod check;
pub mod compile;
pub mod compile_bench;
pub mod datagen;
pub mod demo;
pub mod emit_decoder;
pub mod enhance;
pub mod eval;
pub mod eval_fit;
pub mod export;
pub mod fit;
pub mod flip;
pub mod furnace;
pub mod gallery;
pub mod masks;
pub mod pack;
pub mod project;
pub mod render;
pub mod shards;
pub mod slurm;
pub mod tables;
pub mod train;
pub mod train_sampler;

use mtlx::Diagnostic;
use std::path::PathBuf;
use uplift_compiler::Compiler;

/// The closure context of a BSDF-typed output on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ContextArg {
    /// f·cos θl and throughput for directions wv, wl.
    Eval,
    /// Directional albedo and throughput for direction wv.
    Albedo,
    /// A direction wl drawn for wv from three uniforms u, with its pdf, response and throughput.
    Sample,
    /// The pdf with which `sample` draws wl for wv, with response and throughput.
    Pdf,
}

impl ContextArg {
    pub fn context(self) -> uplift_compiler::ClosureContext {
        use uplift_compiler::ClosureContext as C;
        match self {
            ContextArg::Eval => C::Eval,
            ContextArg::Albedo => C::Albedo,
            ContextArg::Sample => C::Sample,
            ContextArg::Pdf => C::Pdf,
        }
    }
}

/// Claims the folder a command writes (`uplift_base::output_folder`) and creates it: a new or
/// empty folder or the command's own earlier output; one holding other files is refused (and
/// left untouched) unless `force`, which writes beside them.
pub fn claim_output(dir: &std::path::Path, command: &str, force: bool) -> Result<uplift_base::output_folder::OutputFolder, String> {
    let folder = uplift_base::output_folder::OutputFolder::claim(dir, command, force)?;
    folder.create()?;
    Ok(folder)
}

/// Prints diagnostics to stderr; returns true when any is an error.
pub fn report(diagnostics: &[Diagnostic]) -> bool {
    for d in diagnostics {
        eprintln!("{d}");
    }
    mtlx::has_errors(diagnostics)
}

/// A compiler over the builtin library and `library` folders (files named by documents anywhere
/// with `allow_any_path`, else in their folder or the search paths); the library's diagnostics are
/// printed, and an error among them fails.
pub fn compiler(library: &[PathBuf], allow_any_path: bool) -> Result<Compiler, String> {
    layered_compiler(&[], library, allow_any_path)
}

/// [`compiler`] with `stack` folders loaded before the builtin library (`--stack DIR`,
/// `Compiler::layered`).
pub fn layered_compiler(stack: &[PathBuf], library: &[PathBuf], allow_any_path: bool) -> Result<Compiler, String> {
    let mut compiler = Compiler::layered(stack, library);
    if allow_any_path {
        compiler = compiler.allow_any_path();
    }
    if report(&compiler.library.diagnostics) {
        return Err("errors in the node library".into());
    }
    Ok(compiler)
}

/// `--stack DIR`: the library folders of another `uplift_stack` (a redefined `ND_uplift_stack`
/// and nodegraph, with the lobes it adds), for every command that enhances, trains, fits or
/// renders enhanced materials.
#[derive(clap::Args, Clone, Debug, Default)]
pub struct StackArgs {
    /// A library folder whose definitions win over the builtin ones — a redefined
    /// `uplift_stack` with its lobes (repeatable). Materials, decoders and this command must
    /// agree on the stack: each records its signature.
    #[arg(long = "stack", value_name = "DIR")]
    pub stack: Vec<PathBuf>,
}

impl StackArgs {
    /// The stack: the builtin one, or the folders' (errors name the file and position).
    pub fn load(&self) -> Result<std::sync::Arc<uplift_engines::stack::Stack>, String> {
        uplift_engines::stack::Stack::load(&self.stack)
    }
}
