//! Any MaterialX material as the renderer shades it: one surfaceshader or material output of a
//! document, compiled in the `pdf` context (f·cos θl, the sampling pdf, and the emitted
//! radiance) and the `sample` context (wl drawn by the closure's own exponential race), run on
//! either engine with each hit's geometry — texture coordinate, position, shading normal and
//! tangent — and world-space directions (the closure kernels' convention: directions in the
//! space of the BSDF's `normal` and `tangent`, so the material's own normal maps apply).
//!
//! The renderer traces reflection only: a direction a transmissive lobe draws below the surface
//! ends the path (uplift's materials are opaque; glass shows its reflection).

use crate::material::MaterialValue;
use crate::scene::{Hit, Vec3};
use crate::shading::ShadingEngine;
use crate::surface_model::{Evaluation, SurfaceModel};
use std::path::Path;
use uplift_compiler::graph_builder::document_outputs;
use uplift_compiler::wgsl_types::is_scattering;
use uplift_compiler::{ClosureContext, Compiler, OutputSelection};
use uplift_engines::batch::{Columns, Geometry, PatternBatch, TextureData};
use uplift_engines::prepared_kernel::PreparedKernel;
use uplift_engines::texture_loader::load_texture;
use mtlx::DataType;

struct ClosureKernel {
    prepared: PreparedKernel,
    textures: Vec<TextureData>,
}

/// A document's material, compiled and prepared.
pub struct MtlxMaterial {
    /// The output rendered (a material node's name, or `graph/output`).
    pub name: String,
    /// The compiler's warnings (a texture file not found reads as its `default`, …), once each.
    pub warnings: Vec<String>,
    engine: ShadingEngine,
    pdf: ClosureKernel,
    sample: ClosureKernel,
}

/// The scattering outputs of a document, each with whether it is a material.
fn scattering_outputs(doc: &mtlx::Document) -> Vec<(String, bool)> {
    let material = DataType::Closure("material".into());
    document_outputs(doc).into_iter().filter(|o| is_scattering(&o.ty)).map(|o| (o.name, o.ty == material)).collect()
}

/// The scattering outputs of a document that `render` can show (material outputs first).
pub fn material_outputs(doc: &mtlx::Document) -> Vec<String> {
    let mut outs = scattering_outputs(doc);
    outs.sort_by_key(|(_, is_material)| !*is_material);
    outs.into_iter().map(|(n, _)| n).collect()
}

/// What a gallery shows of a document: its materials, else its surface shaders and BSDFs.
pub fn gallery_outputs(doc: &mtlx::Document) -> Vec<String> {
    let outs = scattering_outputs(doc);
    let any_material = outs.iter().any(|(_, m)| *m);
    outs.into_iter().filter(|(_, m)| *m || !any_material).map(|(n, _)| n).collect()
}

impl MtlxMaterial {
    /// Compiles output `name` of `path` (default: its first material, else its first surface
    /// shader or BSDF output) for `engine`. Errors name the file and position, or list the
    /// outputs when `name` is not one of them.
    pub fn compile(compiler: &Compiler, path: &Path, name: Option<&str>, engine: ShadingEngine) -> Result<MtlxMaterial, String> {
        let (doc, diags) = mtlx::read_file(path);
        if let Some(e) = diags.iter().find(|d| d.is_error()) {
            return Err(e.to_string());
        }
        let outputs = material_outputs(&doc);
        let name = match name {
            Some(n) if outputs.iter().any(|o| o == n) => n.to_string(),
            Some(n) => return Err(format!("{}: no material or surface shader `{n}`; the document has: {}", path.display(), if outputs.is_empty() { "none".into() } else { outputs.join(", ") })),
            None => outputs.first().cloned().ok_or_else(|| format!("{}: no material, surface shader or BSDF output to render", path.display()))?,
        };
        let mut warnings: Vec<String> = diags.iter().map(|d| d.to_string()).collect();
        let mut kernel = |c: ClosureContext| -> Result<ClosureKernel, String> {
            let r = compiler.compile_document_in(doc.clone(), Vec::new(), &path.display().to_string(), &OutputSelection::Named(vec![name.clone()]), Some(c));
            for d in r.diagnostics.iter().filter(|d| !d.is_error()) {
                let d = d.to_string();
                if !warnings.contains(&d) {
                    warnings.push(d);
                }
            }
            let errors: Vec<String> = r.diagnostics.iter().filter(|d| d.is_error()).map(|d| d.to_string()).collect();
            let kernel = match r.kernel {
                Some(k) if errors.is_empty() => k,
                _ => return Err(format!("`{name}` does not compile in the {} context:\n{}", c.name(), errors.join("\n"))),
            };
            let textures = kernel.textures.iter().map(|t| load_texture(&t.path, t.colorspace.as_deref())).collect::<Result<Vec<_>, _>>()?;
            Ok(ClosureKernel { prepared: PreparedKernel::new(engine.as_engine(), kernel)?, textures })
        };
        let (pdf, sample) = (kernel(ClosureContext::Pdf)?, kernel(ClosureContext::Sample)?);
        Ok(MtlxMaterial { name, warnings, engine, pdf, sample })
    }

    /// Runs `k` at the hits with its direction inputs (world space) per hit; other interface
    /// inputs take their defaults.
    fn run(&self, k: &ClosureKernel, hits: &[Hit], directions: &[(&str, Vec<Vec3>)]) -> Result<Columns, String> {
        let n = hits.len();
        let kernel = &k.prepared.kernel;
        let mut inputs = Columns::zeros(n, kernel.input_stride);
        for inp in &kernel.inputs {
            let given = directions.iter().find(|(name, _)| *name == inp.input.name);
            for ch in 0..inp.input.ty.components().unwrap_or(0) {
                let col = inputs.column_mut(inp.offset + ch);
                match given {
                    Some((_, d)) => col.iter_mut().zip(d).for_each(|(x, v)| *x = v[ch]),
                    None => col.fill(inp.input.default.get(ch).copied().unwrap_or(0.0)),
                }
            }
        }
        let geometry: Vec<Geometry> = hits.iter().map(|h| Geometry { texcoord: h.uv, position: h.position, normal: h.frame[2], tangent: h.frame[0] }).collect();
        let batch = PatternBatch { geometry: Geometry::columns(&geometry), inputs, textures: k.textures.clone(), points_per_group: 1 };
        k.prepared.run(self.engine.as_engine(), &batch)
    }
}

fn rgb(out: &Columns, at: usize, i: usize) -> [f32; 3] {
    [0, 1, 2].map(|c| out.column(at + c)[i]).map(|x| if x.is_finite() { x.max(0.0) } else { 0.0 })
}

impl SurfaceModel for MtlxMaterial {
    fn shading_hit(&self, hit: &Hit, _world_normals: bool) -> Hit {
        *hit
    }

    fn evaluate(&self, hits: &[Hit], wv: &[Vec3], wl: &[Vec3]) -> Result<Evaluation, String> {
        let world = |d: &[Vec3]| hits.iter().zip(d).map(|(h, l)| h.to_world(*l)).collect::<Vec<_>>();
        let out = self.run(&self.pdf, hits, &[("wv", world(wv)), ("wl", world(wl))])?;
        let k = &self.pdf.prepared;
        let (resp, pdf) = (k.output_offset("response").ok_or("pdf kernel without `response`")?, k.output_offset("pdf").ok_or("pdf kernel without `pdf`")?);
        let emission = k.output_offset("emission");
        let n = hits.len();
        Ok(Evaluation {
            values: (0..n).map(|i| MaterialValue { fcos: rgb(&out, resp, i), pdf: out.column(pdf)[i].max(0.0) }).collect(),
            select: vec![1.0; n],
            emission: (0..n).map(|i| emission.map_or([0.0; 3], |e| rgb(&out, e, i))).collect(),
        })
    }

    fn sample(&self, hits: &[Hit], wv: &[Vec3], _select: &[f32], u: &[[f32; 6]]) -> Result<Vec<(Vec3, MaterialValue)>, String> {
        let wv_world: Vec<Vec3> = hits.iter().zip(wv).map(|(h, l)| h.to_world(*l)).collect();
        let uu: Vec<Vec3> = u.iter().map(|x| [x[0], x[1], x[2]]).collect();
        let out = self.run(&self.sample, hits, &[("wv", wv_world), ("u", uu)])?;
        let k = &self.sample.prepared;
        let (wl, pdf, resp) = (k.output_offset("wl").ok_or("sample kernel without `wl`")?, k.output_offset("pdf").ok_or("sample kernel without `pdf`")?, k.output_offset("response").ok_or("sample kernel without `response`")?);
        Ok((0..hits.len())
            .map(|i| {
                let d = [0, 1, 2].map(|c| out.column(wl + c)[i]);
                let p = out.column(pdf)[i];
                if !(p > 0.0 && p.is_finite()) || !d.iter().all(|x| x.is_finite()) {
                    return ([0.0, 0.0, 1.0], MaterialValue::default());
                }
                (hits[i].to_local(d), MaterialValue { fcos: rgb(&out, resp, i), pdf: p })
            })
            .collect())
    }
}
