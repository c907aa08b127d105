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
    /// Let the document name files anywhere; by default a file it names (a texture) must lie
    /// in the document's folder or a library search path.
    #[arg(long = "allow-any-path")]
    pub allow_any_path: bool,
    /// Library folders loaded before the builtin one (a redefined `uplift_stack` with new lobes,
    /// as for `enhance`; repeatable), so that a rule using them can be checked.
    #[arg(long = "stack", value_name = "DIR")]
    pub stack: Vec<PathBuf>,
}

pub fn run(args: CheckArgs) -> Result<(), String> {
    let mut compiler = Compiler::layered(&args.stack, &args.library);
    if args.allow_any_path {
        compiler = compiler.allow_any_path();
    }
    let mut diags = compiler.library.diagnostics.clone();
    diags.extend(compiler.check_file(&args.file));
    if super::report(&diags) {
        return Err(String::new());
    }
    println!("{}: ok", args.file.display());
    Ok(())
}
