//! Shipped BSDF kernels (runtime/kernels/graphs/bsdf) for the closure tests: compile a graph in one
//! closure context, prepare it on the CPU engine (found in-process by fingerprint), and run it
//! on directions in the local frame with parameters by interface-input name.
#![allow(dead_code)]

use std::collections::HashMap;
use std::path::Path;
use uplift_engines::batch::{Columns, Geometry, PatternBatch};
use uplift_engines::cpu_engine::{CpuEngine, CpuKernel};
use uplift_compiler::{ClosureContext, OutputSelection, PatternKernel};

/// A shipped BSDF graph compiled in one context, prepared on the CPU engine.
pub struct Bsdf {
    pub kernel: PatternKernel,
    pub prepared: CpuKernel,
}

pub fn cpu_engine() -> &'static CpuEngine {
    static E: std::sync::OnceLock<CpuEngine> = std::sync::OnceLock::new();
    E.get_or_init(|| CpuEngine::new().unwrap().with_cache_dir(Path::new(env!("CARGO_TARGET_TMPDIR")).join("uplift-kernel-cache")))
}

pub fn bsdf(graph: &str, context: ClosureContext) -> Bsdf {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../kernels/graphs/bsdf").join(format!("{graph}.mtlx"));
    let c = super::compiler().compile_file_in(&path, &OutputSelection::AllNumeric, Some(context));
    let kernel = c.kernel.unwrap_or_else(|| panic!("{graph}: {:?}", c.diagnostics.iter().map(|d| d.to_string()).collect::<Vec<_>>()));
    let prepared = cpu_engine().prepare(&kernel).unwrap();
    assert!(matches!(prepared, CpuKernel::Builtin(_)), "{graph} ({}) is not a shipped kernel", context.name());
    Bsdf { kernel, prepared }
}

/// Parameters by interface-input name (missing ones take the document's values).
pub type Params = HashMap<&'static str, Vec<f32>>;

/// The local shading frame (normal +z, tangent +x) for every point.
pub fn local_frame(n: usize) -> Columns {
    Geometry { texcoord: [0.0; 2], position: [0.0; 3], normal: [0.0, 0.0, 1.0], tangent: [1.0, 0.0, 0.0] }.repeated(n)
}

impl Bsdf {
    /// Runs the kernel on `n` points: `directions[k]` fills the k-th direction input (wv, then
    /// wl or u) per point; `params` are the same for every point of `ranges[i]` = params i.
    pub fn run(&self, directions: &[Vec<[f32; 3]>], params: &[(std::ops::Range<usize>, &Params)]) -> Columns {
        let n = directions[0].len();
        let mut inputs = Columns::zeros(n, self.kernel.input_stride);
        for inp in &self.kernel.inputs {
            let d = self.kernel.context.unwrap().direction_inputs().iter().position(|x| *x == inp.input.name);
            for c in 0..inp.input.ty.components().unwrap() {
                let col = inputs.column_mut(inp.offset + c);
                match d {
                    Some(k) => col.iter_mut().zip(&directions[k]).for_each(|(x, v)| *x = v[c]),
                    None => {
                        for (range, p) in params {
                            let v = p.get(inp.input.name.as_str()).map_or(inp.input.default[c], |v| v[c]);
                            col[range.clone()].fill(v);
                        }
                    }
                }
            }
        }
        for (_, p) in params {
            for name in p.keys() {
                assert!(self.kernel.inputs.iter().any(|i| i.input.name == *name), "no input `{name}`");
            }
        }
        let batch = PatternBatch { geometry: local_frame(n), inputs, textures: vec![], points_per_group: 1 };
        cpu_engine().run_prepared(&self.prepared, &batch).unwrap()
    }

    pub fn column(&self, out: &Columns, name: &str, c: usize) -> Vec<f32> {
        let o = self.kernel.outputs.iter().find(|o| o.name == name).unwrap_or_else(|| panic!("no output {name}"));
        out.column(o.offset + c).to_vec()
    }
}

/// The direction at cosine μ in the x–z plane.
pub fn view(mu: f64) -> [f32; 3] {
    [(1.0 - mu * mu).max(0.0).sqrt() as f32, 0.0, mu as f32]
}

/// Gulbrandsen's artistic conductor IOR ("Artist Friendly Metallic Fresnel", 2014), per channel:
/// (n, k) from reflectivity r and edge colour g, written out independently of the library.
pub fn gulbrandsen(r: f32, g: f32) -> (f32, f32) {
    let r = r.clamp(0.0, 0.99);
    let n_min = (1.0 - r) / (1.0 + r);
    let n_max = (1.0 + r.sqrt()) / (1.0 - r.sqrt());
    let n = n_max + (n_min - n_max) * g;
    let k2 = ((n + 1.0) * (n + 1.0) * r - (n - 1.0) * (n - 1.0)) / (1.0 - r);
    (n, k2.max(0.0).sqrt())
}
