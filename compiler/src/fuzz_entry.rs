//! The fuzz targets' bodies, shared by the libFuzzer targets under `fuzz/` (`cargo +nightly fuzz
//! run read|check|compile`) and the stable-Rust runner in CI (`compiler/tests/integration/fuzz_stable.rs`):
//! each takes arbitrary bytes and must return without panicking, aborting or hanging, whatever
//! the bytes. A property that fails panics with a message saying which one.
//!
//! - [`read`]: the XML reader; a document it reads without errors is written back out and must
//!   read again without errors to the same content (`Document::same_content`).
//! - [`check`]: `uplift check` — reading, include resolution, nodegraph flattening and the
//!   graph builder over every output.
//! - [`compile`]: `uplift compile` — every pattern output and, in the eval context, the BSDF
//!   output; each kernel that compiles is also written as Rust (WGSL comes with the kernel).
//!
//! Documents are read from memory as `fuzz.mtlx` in the working folder; the compiler only
//! reaches files inside that folder (its default path rule), and only those the bytes name.

use crate::{ClosureContext, Compiler, OutputSelection};
use std::sync::OnceLock;

/// The source name fuzz inputs are read under.
pub const SOURCE_NAME: &str = "fuzz.mtlx";

fn compiler() -> &'static Compiler {
    static C: OnceLock<Compiler> = OnceLock::new();
    C.get_or_init(Compiler::builtin)
}

fn text(data: &[u8]) -> Option<&str> {
    std::str::from_utf8(data).ok()
}

/// The reader and the writer.
pub fn read(data: &[u8]) {
    let Some(text) = text(data) else { return };
    let (doc, diags) = mtlx::read_str(text, SOURCE_NAME);
    if mtlx::has_errors(&diags) {
        return;
    }
    let written = mtlx::write_string(&doc);
    let (again, diags2) = mtlx::read_str(&written, SOURCE_NAME);
    let errors: Vec<String> = diags2.iter().filter(|d| d.is_error()).map(|d| d.to_string()).collect();
    assert!(errors.is_empty(), "a document read without errors, once written, reads with errors: {errors:?}\n--- written:\n{written}");
    assert!(doc.same_content(&again), "a document written and read again differs from the one read\n--- written:\n{written}");
}

/// What `uplift check` does.
pub fn check(data: &[u8]) {
    let Some(text) = text(data) else { return };
    let (doc, diags) = mtlx::read_str(text, SOURCE_NAME);
    let _ = compiler().compile_document(doc, diags, SOURCE_NAME, &OutputSelection::AllNumeric);
}

/// What `uplift compile --target wgsl|rust` does, for pattern outputs and a BSDF output.
pub fn compile(data: &[u8]) {
    let Some(text) = text(data) else { return };
    for context in [None, Some(ClosureContext::Eval)] {
        let (doc, diags) = mtlx::read_str(text, SOURCE_NAME);
        let c = compiler().compile_document_in(doc, diags, SOURCE_NAME, &OutputSelection::AllNumeric, context);
        if let Some(kernel) = c.kernel {
            assert!(!kernel.wgsl.is_empty(), "a compiled kernel without WGSL");
            if let Err(e) = crate::backend_rust::write_rust_kernel(&kernel) {
                panic!("a kernel that naga validated cannot be written as Rust: {e:?}");
            }
        }
    }
}
