//! `uplift check FILE.mtlx`: read, resolve and build every output; print all diagnostics.

use std::path::PathBuf;
use uplift_compiler::Compiler;

#[derive(clap::Args)]
pub struct CheckArgs {
    /// The MaterialX document.
    pub file: PathBuf,
    /// Extra library folder (repeatable); MATERIALX_SEARCH_PATH is read too.
    #[arg(long = "library")]
    pub library: Vec<PathBuf>,
}

pub fn run(args: CheckArgs) -> Result<(), String> {
    let compiler = Compiler::new(&args.library);
    let mut diags = compiler.library.diagnostics.clone();
    diags.extend(compiler.check_file(&args.file));
    if super::report(&diags) {
        return Err(String::new());
    }
    println!("{}: ok", args.file.display());
    Ok(())
}
