//! What the path tracer asks of a material, in batches of hits (local shading-frame directions,
//! normal +z): the hit as shaded (normal map applied), the BSDF's f·cos θl and sampling pdf at
//! (wv, wl) with the radiance the surface emits towards wv, and directions drawn from its
//! sampling strategy. Two materials implement it: an enhanced material folder shaded by the
//! stack kernels or the decoder (`EnhancedMaterial`, here), and any MaterialX material shaded
//! by its own compiled closure kernels (`mtlx_material.rs`).

use crate::material::{self, MaterialValue};
use crate::scene::{Hit, Vec3};
use crate::shading::Shading;
use crate::surface::{SurfaceSample, SurfaceTextures};

/// The material's values at a batch of hits.
pub struct Evaluation {
    pub values: Vec<MaterialValue>,
    /// Per hit, what `sample` needs from the evaluation (the enhanced material's selection
    /// probability between its parts); opaque to the integrator.
    pub select: Vec<f32>,
    /// Radiance emitted towards wv.
    pub emission: Vec<[f32; 3]>,
}

pub trait SurfaceModel: Sync {
    /// The hit as it is shaded (a normal map replaces its shading frame); `world_normals`: the
    /// scene's normals are an asset's world-space normals (a mesh), not the preview ball's.
    fn shading_hit(&self, hit: &Hit, world_normals: bool) -> Hit;
    /// Values at (wv, wl) per hit, both in the hit's shading frame.
    fn evaluate(&self, hits: &[Hit], wv: &[Vec3], wl: &[Vec3]) -> Result<Evaluation, String>;
    /// Draws wl per hit with six uniforms; returns wl (shading frame) and the values there. A
    /// failed sample has pdf 0.
    fn sample(&self, hits: &[Hit], wv: &[Vec3], select: &[f32], u: &[[f32; 6]]) -> Result<Vec<(Vec3, MaterialValue)>, String>;
}

/// An enhanced material: its per-texel data and the model that shades it (paper Eq. 2,
/// `material.rs`), with its glints when it has them (glint.rs). It emits nothing.
pub struct EnhancedMaterial<'a> {
    pub surface: &'a SurfaceTextures,
    pub shading: &'a Shading,
}

impl EnhancedMaterial<'_> {
    fn lookups(&self, hits: &[Hit]) -> Vec<SurfaceSample> {
        hits.iter().map(|h| self.surface.lookup(h.uv)).collect()
    }

    /// The glint pattern N at these hits as a function of wl, when the material has glints.
    fn glints<'s>(&'s self, hits: &'s [Hit], wv: &'s [Vec3]) -> Option<impl Fn(&[Vec3]) -> Result<Vec<[f32; 3]>, String> + 's> {
        let glint = self.surface.glint.as_ref()?;
        Some(move |wl: &[Vec3]| self.shading.glint_factors(glint, hits, wv, wl))
    }
}

impl SurfaceModel for EnhancedMaterial<'_> {
    fn shading_hit(&self, hit: &Hit, world_normals: bool) -> Hit {
        self.surface.normal_mapped(hit, world_normals)
    }

    fn evaluate(&self, hits: &[Hit], wv: &[Vec3], wl: &[Vec3]) -> Result<Evaluation, String> {
        let glints = self.glints(hits, wv);
        let by = glints.as_ref().map(|g| g as material::Modulation);
        let (values, select) = material::evaluate(self.shading, &self.lookups(hits), wv, wl, by)?;
        Ok(Evaluation { values, select, emission: vec![[0.0; 3]; hits.len()] })
    }

    fn sample(&self, hits: &[Hit], wv: &[Vec3], select: &[f32], u: &[[f32; 6]]) -> Result<Vec<(Vec3, MaterialValue)>, String> {
        let glints = self.glints(hits, wv);
        let by = glints.as_ref().map(|g| g as material::Modulation);
        material::sample(self.shading, &self.lookups(hits), wv, select, u, by)
    }
}
