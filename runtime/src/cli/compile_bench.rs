//! `uplift compile --bench FILES|DIRS…`: the compiler's speed figures. Prints the time to load
//! the libraries, then for every document the median of repeated compilations with the
//! library already loaded, and the median over documents. Run it from a release build.

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
    println!("{:>10}  {:>10}  document", "median ms", "outputs");
    let mut medians = Vec::new();
    for f in &files {
        let first = compiler.compile_file(f, &OutputSelection::AllNumeric);
        let Some(k) = &first.kernel else {
            println!("{:>10}  {:>10}  {} (does not compile)", "-", "-", f.display());
            continue;
        };
        let outputs = k.outputs.len();
        let mut times = Vec::new();
        for _ in 0..15 {
            let t = Instant::now();
            let c = compiler.compile_file(f, &OutputSelection::AllNumeric);
            times.push(t.elapsed().as_secs_f64() * 1e3);
            assert!(c.kernel.is_some());
        }
        let m = median(&mut times);
        medians.push(m);
        println!("{m:>10.3}  {outputs:>10}  {}", f.display());
    }
    println!("median over {} compiled documents: {:.3} ms per document (target ≤ 1 ms)", medians.len(), median(&mut medians));
    Ok(())
}
