//! Subcommands of the `uplift` binary, one module each. Each `run` returns `Err(message)` for
//! a failure to print (already positioned as `file:line:col: …`); the binary exits 1.

pub mod check;
pub mod compile;
pub mod compile_bench;
pub mod eval;

use mtlx::Diagnostic;
use std::path::PathBuf;
use uplift_compiler::Compiler;

/// Prints diagnostics to stderr; returns true when any is an error.
pub fn report(diagnostics: &[Diagnostic]) -> bool {
    for d in diagnostics {
        eprintln!("{d}");
    }
    mtlx::has_errors(diagnostics)
}

/// A compiler over the builtin library and `library` folders; the library's diagnostics are
/// printed, and an error among them fails.
pub fn compiler(library: &[PathBuf]) -> Result<Compiler, String> {
    let compiler = Compiler::new(library);
    if report(&compiler.library.diagnostics) {
        return Err("errors in the node library".into());
    }
    Ok(compiler)
}
