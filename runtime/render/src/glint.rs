//! Glints at render time (paper §5.3, Eq. 6): the pattern N of `uplift_glint` evaluated at a
//! batch of hits through the shipped `glint_factor` kernel (runtime/kernels/graphs/, in-process
//! on the CPU engine, or its WGSL on wgpu), with the material's glint inputs (meta.json) and
//! world-space directions, so N is the same function of surface position and half vector as
//! the glint node in the material's document. The renderer multiplies the non-diffuse part by it
//! — the reference stack and the neural material alike (f_nd · N, material.rs).

use crate::scene::{Hit, Vec3};
use crate::shading::ShadingEngine;
use uplift_compiler::{Compiler, OutputSelection};
use uplift_engines::batch::{Columns, Geometry, PatternBatch};
use uplift_engines::prepared_kernel::PreparedKernel;
use uplift_material::GlintRecord;

/// The glint kernel, prepared on an engine.
pub struct GlintKernel {
    prepared: PreparedKernel,
}

impl GlintKernel {
    pub fn new(engine: &ShadingEngine) -> Result<GlintKernel, String> {
        let (source, text) = uplift_kernels::shipped::GLINT_FACTOR_GRAPH;
        let (doc, diags) = mtlx::read_str(text, source);
        let c = Compiler::builtin().compile_document(doc, diags, source, &OutputSelection::AllNumeric);
        let kernel = c.kernel.ok_or_else(|| c.diagnostics.iter().map(|d| d.to_string()).collect::<Vec<_>>().join("\n"))?;
        Ok(GlintKernel { prepared: PreparedKernel::new(engine.as_engine(), kernel)? })
    }

    /// N (RGB) per hit for local directions wv, wl (the hit's shading frame).
    pub fn factors(&self, engine: &ShadingEngine, glint: &GlintRecord, hits: &[Hit], wv: &[Vec3], wl: &[Vec3]) -> Result<Vec<[f32; 3]>, String> {
        let n = hits.len();
        if n == 0 {
            return Ok(Vec::new());
        }
        let kernel = &self.prepared.kernel;
        let mut inputs = Columns::zeros(n, kernel.input_stride);
        for inp in &kernel.inputs {
            let name = inp.input.name.as_str();
            if let Some((_, v)) = glint.inputs().into_iter().find(|(g, _)| *g == name) {
                inputs.column_mut(inp.offset).fill(v);
                continue;
            }
            let dirs = match name {
                "wv" => wv,
                "wl" => wl,
                other => return Err(format!("glint kernel: unexpected input `{other}`")),
            };
            for c in 0..3 {
                let col = inputs.column_mut(inp.offset + c);
                for (k, x) in col.iter_mut().enumerate() {
                    *x = hits[k].to_world(dirs[k])[c];
                }
            }
        }
        inputs.mark_uniform_columns();
        let geometry: Vec<Geometry> = hits.iter().map(|h| Geometry { texcoord: h.uv, position: h.position, normal: h.frame[2], tangent: h.frame[0] }).collect();
        let batch = PatternBatch { geometry: Geometry::columns(&geometry), inputs, textures: vec![], points_per_group: 1 };
        let out = self.prepared.run(engine.as_engine(), &batch)?;
        Ok((0..n).map(|k| [0, 1, 2].map(|c| out.column(c)[k]).map(|x| if x.is_finite() { x.max(0.0) } else { 0.0 })).collect())
    }
}
