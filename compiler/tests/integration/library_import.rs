//! Library import (compiler/src/naga_import.rs) against the reference path: every snapshot
//! input, the uplift rules and every shipped kernel graph (BSDF graphs in every closure context)
//! compiled with the library's functions imported pre-parsed — with the text fallback off, so
//! the import is the path taken — and with the full text parsed. The two must write the same
//! WGSL (GPU kernel and CPU module) and the same Rust. With `UPLIFT_MTLX_DATA` set, MaterialX's
//! own TestSuite documents are compared too.

use std::path::{Path, PathBuf};
use uplift_compiler::lower::LowerOptions;
use uplift_compiler::{ClosureContext, Compiler, OutputSelection, PatternKernel};

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap().to_path_buf()
}

fn mtlx_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir).into_iter().flatten().filter_map(|e| e.ok().map(|e| e.path())).collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            mtlx_files(&p, out);
        } else if p.extension().is_some_and(|e| e == "mtlx") {
            out.push(p);
        }
    }
}

/// Everything a kernel's text output depends on: the GPU WGSL, the CPU module's WGSL and the
/// Rust kernel.
fn outputs(k: &PatternKernel) -> (String, Option<String>, String) {
    let cpu = k.cpu_module.as_ref().map(|(m, info)| naga::back::wgsl::write_string(m, info, naga::back::wgsl::WriterFlags::empty()).unwrap());
    let rust = uplift_compiler::backend_rust::write_rust_kernel(k).map_err(|e| e.to_string()).unwrap_or_else(|e| format!("error: {e}"));
    (k.wgsl.clone(), cpu, rust)
}

#[test]
fn imported_library_functions_give_the_kernels_of_parsed_ones() {
    let root = repo_root();
    let mut imported = Compiler::builtin();
    imported.lower_options = LowerOptions { import_library: true, fall_back_to_text: false };
    let mut parsed = Compiler::builtin();
    parsed.lower_options = LowerOptions { import_library: false, fall_back_to_text: true };
    let mut jobs: Vec<(PathBuf, Option<ClosureContext>)> = Vec::new();
    let mut files = Vec::new();
    mtlx_files(&root.join("tests/in"), &mut files);
    mtlx_files(&root.join("mtlx/rules"), &mut files);
    mtlx_files(&root.join("runtime/kernels/graphs"), &mut files);
    if let Some(data) = std::env::var_os("UPLIFT_MTLX_DATA") {
        mtlx_files(&Path::new(&data).join("Materials/TestSuite/stdlib"), &mut files);
    } else {
        eprintln!("UPLIFT_MTLX_DATA is not set: MaterialX's TestSuite documents are not compared");
    }
    for f in files.into_iter().filter(|f| !f.components().any(|c| c.as_os_str() == "include" || c.as_os_str() == "images")) {
        if f.components().any(|c| c.as_os_str() == "bsdf") {
            jobs.extend(ClosureContext::ALL.into_iter().map(|c| (f.clone(), Some(c))));
        } else {
            jobs.push((f, None));
        }
    }
    let mut compared = 0;
    for (path, context) in &jobs {
        let reference = parsed.compile_file_in(path, &OutputSelection::AllNumeric, *context);
        let Some(reference) = reference.kernel else { continue };
        let c = imported.compile_file_in(path, &OutputSelection::AllNumeric, *context);
        let what = format!("{} ({})", path.display(), context.map_or("pattern", |c| c.name()));
        let kernel = c.kernel.unwrap_or_else(|| panic!("{what}: compiles from text but not with the library imported: {:?}", c.diagnostics.iter().map(|d| d.to_string()).collect::<Vec<_>>()));
        let (a, b) = (outputs(&kernel), outputs(&reference));
        assert!(a.0 == b.0, "{what}: the WGSL kernels differ");
        assert!(a.1 == b.1, "{what}: the CPU modules differ");
        assert!(a.2 == b.2, "{what}: the Rust kernels differ");
        compared += 1;
    }
    eprintln!("{compared} kernels identical with the library imported and parsed");
    assert!(compared >= 80, "only {compared} kernels compared");
}
