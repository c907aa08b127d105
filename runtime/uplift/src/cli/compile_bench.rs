//! `uplift compile --bench FILES|DIRS…`: the compiler's speed figures. Prints the time to load
//! the libraries, then for every document the median of repeated compilations with the
//! library already loaded — read and compiled to WGSL, compiled from a read document, and
//! compiled from a read document to WGSL and Rust (the CPU kernel's source) — and the medians
//! over documents. Run it from a release build.

use std::path::{Path, PathBuf};
use std::time::Instant;
use uplift_compiler::{Compiler, OutputSelection};

fn collect(p: &Path, out: &mut Vec<PathBuf>) {
    if p.is_dir() {
        let mut v: Vec<PathBuf> = std::fs::read_dir(p).into_iter().flatten().filter_map(|e| e.ok().map(|e| e.path())).collect();
        v.sort();
        for c in v {
            collect(&c, out);
        }
    } else if p.extension().is_some_and(|e| e == "mtlx") {
        out.push(p.to_path_buf());
    }
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(|a, b| a.partial_cmp(b).unwrap());
    if v.is_empty() {
        0.0
    } else {
        v[v.len() / 2]
    }
}

pub fn run(paths: &[PathBuf], library: &[PathBuf]) -> Result<(), String> {
    let mut files = Vec::new();
    for p in paths {
        collect(p, &mut files);
    }
    let mut loads = Vec::new();
    for _ in 0..5 {
        let t = Instant::now();
        let c = Compiler::new(library);
        loads.push(t.elapsed().as_secs_f64() * 1e3);
        drop(c);
    }
    let compiler = Compiler::new(library);
    println!("library load: median {:.2} ms over {} runs ({} nodedefs, {} WGSL items)", median(&mut loads), loads.len(), compiler.library.defs.nodedefs.len(), compiler.library.wgsl.items.len());
    println!("{:>12}  {:>12}  {:>12}  {:>7}  document", "read+compile", "compile only", "WGSL + Rust", "outputs");
    let mut medians = Vec::new();
    let mut compile_medians = Vec::new();
    let mut rust_medians = Vec::new();
    for f in &files {
        let first = compiler.compile_file(f, &OutputSelection::AllNumeric);
        let Some(k) = &first.kernel else {
            println!("{:>12}  {:>12}  {:>12}  {:>7}  {} (does not compile)", "-", "-", "-", "-", f.display());
            continue;
        };
        let outputs = k.outputs.len();
        let mut times = Vec::new();
        let mut compile_times = Vec::new();
        let mut rust_times = Vec::new();
        let source = f.display().to_string();
        for _ in 0..15 {
            let t = Instant::now();
            let c = compiler.compile_file(f, &OutputSelection::AllNumeric);
            times.push(t.elapsed().as_secs_f64() * 1e3);
            assert!(c.kernel.is_some());
            // The same with the document already read (XML parsing and upgrades excluded).
            let (doc, diags) = mtlx::read_file(f);
            let t = Instant::now();
            let c = compiler.compile_document(doc, diags, &source, &OutputSelection::AllNumeric);
            compile_times.push(t.elapsed().as_secs_f64() * 1e3);
            assert!(c.kernel.is_some());
            // The same, then the Rust kernel written from its module.
            let (doc, diags) = mtlx::read_file(f);
            let t = Instant::now();
            let c = compiler.compile_document(doc, diags, &source, &OutputSelection::AllNumeric);
            let rust = c.kernel.as_ref().map(uplift_compiler::backend_rust::write_rust_kernel);
            rust_times.push(t.elapsed().as_secs_f64() * 1e3);
            if let Some(Err(e)) = rust {
                return Err(format!("{}: the Rust writer failed: {e}", f.display()));
            }
        }
        let m = median(&mut times);
        let mc = median(&mut compile_times);
        let mr = median(&mut rust_times);
        medians.push(m);
        compile_medians.push(mc);
        rust_medians.push(mr);
        println!("{m:>12.3}  {mc:>12.3}  {mr:>12.3}  {outputs:>7}  {}", f.display());
    }
    println!(
        "median over {} compiled documents: {:.3} ms per document read and compiled, {:.3} ms compiled from a read document, {:.3} ms compiled from a read document to WGSL and Rust (target ≤ 0.5 ms)",
        medians.len(),
        median(&mut medians),
        median(&mut compile_medians),
        median(&mut rust_medians)
    );
    Ok(())
}
