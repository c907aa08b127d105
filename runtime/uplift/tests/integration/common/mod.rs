//! Shared helpers for numeric tests: compile a MaterialX snippet into a pattern kernel, run it
//! on the wgpu engine for random inputs, and compare with values computed in the test.
#![allow(dead_code)]

pub mod bsdf;
pub mod chi2;
pub mod cli;

use std::sync::OnceLock;
use uplift_engines::batch::{Geometry, PatternBatch, PatternEngine, TextureData};
use uplift_engines::wgpu_engine::WgpuEngine;
use uplift_compiler::{Compiler, OutputSelection, PatternKernel};

/// The builtin library; documents may name files anywhere (the numeric tests write their images
/// to a temporary folder; the path rules are tested in compiler/tests/integration/malformed.rs).
pub fn compiler() -> &'static Compiler {
    static C: OnceLock<Compiler> = OnceLock::new();
    C.get_or_init(|| Compiler::builtin().allow_any_path())
}

pub fn engine() -> &'static WgpuEngine {
    static E: OnceLock<WgpuEngine> = OnceLock::new();
    E.get_or_init(|| WgpuEngine::new().unwrap_or_else(|e| panic!("{e}")))
}

/// Compiles a document given as text; panics with the diagnostics on failure.
pub fn compile(text: &str) -> PatternKernel {
    let (doc, diags) = mtlx::read_str(text, "test.mtlx");
    let c = compiler().compile_document(doc, diags, "test.mtlx", &OutputSelection::AllNumeric);
    match c.kernel {
        Some(k) => k,
        None => panic!("does not compile:\n{}\n{text}", c.diagnostics.iter().map(|d| d.to_string()).collect::<Vec<_>>().join("\n")),
    }
}

/// The seeded generator every test draws from (the runtime's SplitMix64).
#[allow(unused_imports)]
pub use uplift_base::rng::SplitMix64 as Rng;

/// Runs `kernel` for the given per-point geometry and interface-input rows.
pub fn run(kernel: &PatternKernel, geometry: &[Geometry], inputs: &[Vec<f32>], textures: Vec<TextureData>) -> Vec<Vec<f32>> {
    let mut rows = Vec::new();
    for row in inputs {
        assert_eq!(row.len(), kernel.input_stride, "input row width");
        rows.extend_from_slice(row);
    }
    let batch = PatternBatch::from_rows(geometry, &rows, kernel.input_stride, textures);
    let out = engine().run_pattern(kernel, &batch).unwrap_or_else(|e| panic!("{e}"));
    out.to_rows().chunks(kernel.output_stride).map(|c| c.to_vec()).collect()
}

/// Asserts |got - want| ≤ tol componentwise, naming the case.
pub fn assert_close(what: &str, got: &[f32], want: &[f32], tol: f32) {
    assert_eq!(got.len(), want.len(), "{what}: component count");
    for (k, (g, w)) in got.iter().zip(want).enumerate() {
        let err = (g - w).abs();
        assert!(err <= tol || (g.is_nan() && w.is_nan()), "{what}: component {k}: got {g}, want {w} (|err| {err} > {tol})");
    }
}

/// A row of the builtin stack's parameters: its nodedef's values with `set` applied (by
/// params.exr channel name).
pub fn stack_params(set: &[(&str, f32)]) -> Vec<f32> {
    let stack = uplift_engines::stack::Stack::builtin();
    let mut p = stack.defaults();
    for (name, v) in set {
        p[stack.index_of(name).unwrap_or_else(|| panic!("no parameter {name}"))] = *v;
    }
    p
}
