//! Shared helpers for numeric tests: compile a MaterialX snippet into a pattern kernel, run it
//! on the wgpu engine for random inputs, and compare with values computed in the test.
#![allow(dead_code)]

pub mod bsdf;

use std::sync::OnceLock;
use uplift::batch::{Geometry, PatternBatch, PatternEngine, TextureData};
use uplift::wgpu_engine::WgpuEngine;
use uplift_compiler::{Compiler, OutputSelection, PatternKernel};

pub fn compiler() -> &'static Compiler {
    static C: OnceLock<Compiler> = OnceLock::new();
    C.get_or_init(Compiler::builtin)
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

/// A small deterministic generator (SplitMix64) so every test is seeded.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Rng {
        Rng(seed)
    }
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        let u = (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32;
        lo + (hi - lo) * u
    }
}

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
