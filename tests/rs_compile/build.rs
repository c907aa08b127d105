//! Lists every Rust snapshot in `tests/out/rs/` and writes `$OUT_DIR/kernels.rs`: one module per
//! snapshot (`include!`d), an `MxTextures` impl of each module's trait for every
//! [`Textures`] type (such as `Checker`), and
//! `KERNELS`, a table that runs any kernel's `mx_pattern_batch` by name; and one module
//! `wgsl_<stem>` per `tests/out/rs_wgsl/<stem>.rs` (Rust written from plain WGSL modules that
//! pin down WGSL semantics). A new snapshot is picked up by the next build.

use std::fmt::Write as _;
use std::path::Path;

/// Sorted stems of the `.rs` files in `dir` (none when it is missing).
fn rust_stems(dir: &Path) -> Vec<String> {
    println!("cargo:rerun-if-changed={}", dir.display());
    let mut stems: Vec<String> = std::fs::read_dir(dir)
        .map(|entries| {
            entries
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|e| e == "rs"))
                .map(|p| p.file_stem().unwrap().to_string_lossy().to_string())
                .collect()
        })
        .unwrap_or_default();
    stems.sort();
    stems
}

fn main() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../out/rs");
    let stems = rust_stems(&dir);
    let mut out = String::new();
    let wgsl_dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../out/rs_wgsl");
    for stem in rust_stems(&wgsl_dir) {
        let path = wgsl_dir.join(format!("{stem}.rs"));
        let path = path.canonicalize().unwrap_or(path);
        let _ = writeln!(out, "/// `tests/out/rs_wgsl/{stem}.rs`.\npub mod wgsl_{stem} {{\n    include!({:?});\n}}\n", path.display().to_string());
    }
    for stem in &stems {
        let path = dir.join(format!("{stem}.rs"));
        let path = path.canonicalize().unwrap_or(path);
        let _ = writeln!(out, "/// `tests/out/rs/{stem}.rs`.\npub mod {stem} {{\n    include!({:?});\n}}\n", path.display().to_string());
        let _ = writeln!(
            out,
            "impl<T: Textures + ?Sized> {stem}::MxTextures for T {{\n    fn load(&self, texture: usize, x: i32, y: i32) -> glam::Vec4 {{\n        Textures::load(self, texture, x, y)\n    }}\n    fn dimensions(&self, texture: usize) -> glam::UVec2 {{\n        Textures::dimensions(self, texture)\n    }}\n}}\n"
        );
    }
    out.push_str("/// Every snapshot kernel: (name, input stride, output stride, batch function).\npub const KERNELS: &[Kernel] = &[\n");
    for stem in &stems {
        let _ = writeln!(
            out,
            "    Kernel {{ name: {stem:?}, input_stride: {stem}::INPUT_STRIDE, output_stride: {stem}::OUTPUT_STRIDE, batch: |g, i, o, t| {stem}::mx_pattern_batch(g, i, o, t), texture_count: {stem}::TEXTURE_COUNT, batch_with: |g, i, o, t| {stem}::mx_pattern_batch(g, i, o, t) }},"
        );
    }
    out.push_str("];\n");
    let dest = Path::new(&std::env::var("OUT_DIR").unwrap()).join("kernels.rs");
    std::fs::write(dest, out).unwrap();
}
