//! `uplift compile FILE.mtlx [--output NAME] --target wgsl -o DIR`: writes the pattern kernel
//! (`DIR/<stem>.wgsl`) and, with `--dump-ir`, the graph IR (`DIR/<stem>.ir`). With `--bench`
//! it instead times library loading and repeated compilation and prints the figures.

use crate::atomic_write::write_atomically;
use std::path::PathBuf;
use uplift_compiler::{Compiler, OutputSelection};

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Target {
    Wgsl,
}

#[derive(clap::Args)]
pub struct CompileArgs {
    /// The MaterialX document(s). With --bench, every .mtlx under the given folders too.
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
    /// Output to compile (`graph/output` or `output`; repeatable). Default: every numeric output.
    #[arg(long)]
    pub output: Vec<String>,
    #[arg(long, value_enum, default_value = "wgsl")]
    pub target: Target,
    /// Output folder.
    #[arg(short = 'o', long = "out-dir", default_value = ".")]
    pub out_dir: PathBuf,
    /// Also write the graph IR dump.
    #[arg(long)]
    pub dump_ir: bool,
    /// Extra library folder (repeatable); MATERIALX_SEARCH_PATH is read too.
    #[arg(long = "library")]
    pub library: Vec<PathBuf>,
    /// Time library loading and per-document compilation instead of writing files.
    #[arg(long)]
    pub bench: bool,
}

pub fn run(args: CompileArgs) -> Result<(), String> {
    if args.bench {
        return crate::cli::compile_bench::run(&args.files, &args.library);
    }
    let compiler = Compiler::new(&args.library);
    if super::report(&compiler.library.diagnostics) {
        return Err("errors in the node library".into());
    }
    let selection = if args.output.is_empty() { OutputSelection::AllNumeric } else { OutputSelection::Named(args.output.clone()) };
    let mut failed = false;
    for file in &args.files {
        let c = compiler.compile_file(file, &selection);
        failed |= super::report(&c.diagnostics);
        let Some(kernel) = c.kernel else { continue };
        let stem = file.file_stem().map(|s| s.to_string_lossy().to_string()).unwrap_or_else(|| "kernel".into());
        std::fs::create_dir_all(&args.out_dir).map_err(|e| format!("{}: cannot create folder: {e}", args.out_dir.display()))?;
        let path = args.out_dir.join(format!("{stem}.wgsl"));
        write_atomically(&path, kernel.wgsl.as_bytes()).map_err(|e| format!("{}: {e}", path.display()))?;
        println!("wrote {}", path.display());
        if args.dump_ir {
            let path = args.out_dir.join(format!("{stem}.ir"));
            write_atomically(&path, kernel.graph.dump().as_bytes()).map_err(|e| format!("{}: {e}", path.display()))?;
        }
    }
    if failed {
        Err(String::new())
    } else {
        Ok(())
    }
}
