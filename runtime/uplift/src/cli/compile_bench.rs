//! `uplift compile --bench FILES|DIRS…`: the compiler's speed figures. Prints the time to load
//! the libraries, then for every document the median of repeated compilations with the
//! library already loaded — read and compiled to WGSL, compiled from a read document, and
//! compiled from a read document to WGSL and Rust (the CPU kernel's source), the same with the
//! library's text parsed into every kernel (the reference path, `LowerOptions`) — and the
//! medians over documents; `--context` compiles BSDF outputs in that closure context. Run it
//! from a release build.

use std::path::{Path, PathBuf};
use std::time::Instant;
use uplift_compiler::lower::LowerOptions;
use uplift_compiler::{ClosureContext, Compiler, OutputSelection};

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

pub fn run(paths: &[PathBuf], library: &[PathBuf], context: Option<ClosureContext>) -> Result<(), String> {
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
    // The reference path: every library function's text parsed into each kernel again.
    let mut parsing = Compiler::new(library);
    parsing.lower_options = LowerOptions { import_library: false, ..LowerOptions::default() };
    println!("library load: median {:.2} ms over {} runs ({} nodedefs, {} WGSL items)", median(&mut loads), loads.len(), compiler.library.defs.nodedefs.len(), compiler.library.wgsl.items.len());
    println!("{:>12}  {:>12}  {:>12}  {:>12}  {:>7}  document", "read+compile", "compile only", "WGSL + Rust", "text parsed", "outputs");
    let [mut medians, mut compile_medians, mut rust_medians, mut parsed_medians] = [(); 4].map(|_| Vec::new());
    for f in &files {
        let first = compiler.compile_file_in(f, &OutputSelection::AllNumeric, context);
        let Some(k) = &first.kernel else {
            println!("{:>12}  {:>12}  {:>12}  {:>12}  {:>7}  {} (does not compile)", "-", "-", "-", "-", "-", f.display());
            continue;
        };
        let outputs = k.outputs.len();
        let [mut times, mut compile_times, mut rust_times, mut parsed_times] = [(); 4].map(|_| Vec::new());
        let source = f.display().to_string();
        // Compiled from a read document (XML parsing and upgrades excluded) to WGSL and Rust.
        let to_rust = |c: &Compiler| -> Result<f64, String> {
            let (doc, diags) = mtlx::read_file(f);
            let t = Instant::now();
            let c = c.compile_document_in(doc, diags, &source, &OutputSelection::AllNumeric, context);
            let rust = c.kernel.as_ref().map(uplift_compiler::backend_rust::write_rust_kernel);
            let ms = t.elapsed().as_secs_f64() * 1e3;
            match rust {
                Some(Ok(_)) => Ok(ms),
                Some(Err(e)) => Err(format!("{}: the Rust writer failed: {e}", f.display())),
                None => Err(format!("{}: compiled once, then not", f.display())),
            }
        };
        for _ in 0..15 {
            let t = Instant::now();
            let c = compiler.compile_file_in(f, &OutputSelection::AllNumeric, context);
            times.push(t.elapsed().as_secs_f64() * 1e3);
            assert!(c.kernel.is_some());
            let (doc, diags) = mtlx::read_file(f);
            let t = Instant::now();
            let c = compiler.compile_document_in(doc, diags, &source, &OutputSelection::AllNumeric, context);
            compile_times.push(t.elapsed().as_secs_f64() * 1e3);
            assert!(c.kernel.is_some());
            rust_times.push(to_rust(&compiler)?);
            parsed_times.push(to_rust(&parsing)?);
        }
        let row = [median(&mut times), median(&mut compile_times), median(&mut rust_times), median(&mut parsed_times)];
        for (all, m) in [&mut medians, &mut compile_medians, &mut rust_medians, &mut parsed_medians].into_iter().zip(row) {
            all.push(m);
        }
        println!("{:>12.3}  {:>12.3}  {:>12.3}  {:>12.3}  {outputs:>7}  {}", row[0], row[1], row[2], row[3], f.display());
    }
    println!(
        "median over {} compiled documents: {:.3} ms per document read and compiled, {:.3} ms compiled from a read document, {:.3} ms compiled from a read document to WGSL and Rust (target ≤ 0.5 ms; {:.3} ms with the library's text parsed into every kernel)",
        medians.len(),
        median(&mut medians),
        median(&mut compile_medians),
        median(&mut rust_medians),
        median(&mut parsed_medians)
    );
    Ok(())
}
