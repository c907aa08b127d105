//! A material's per-texel data as the renderer reads it: the 22 `uplift_stack` parameters and
//! the diffuse colour c (from `uplift enhance`'s params.exr), and optionally the 6 fitted latents
//! (`uplift fit`'s latent.exr). Lookups are bilinear, repeating in u and clamped in v; v = 1 is
//! the image's top row (MaterialX's texcoord convention, as `uplift enhance` bakes).
//!
//! Normal maps (applied unchanged, as the paper does): params.exr's `normal.X/Y/Z` is the rule's
//! `normal_out`, the input's normal map already applied to the bake's geometry. meta.json's
//! `normal_space` says which geometry: `plane` (texture inputs: the unit square facing +Y with
//! tangent +X and bitangent −Z, so the tangent-space normal is (X, −Z, Y) and it can be applied
//! on any surface's frame) or `world` (a glTF material: world-space normals of that asset,
//! applied when rendering its mesh and ignored on the preview ball). Folders without the
//! channels or the field render without a normal map (or as `plane`).

use crate::scene::Hit;
use uplift_engines::stack_params::PARAMETERS;
use std::path::Path;
use uplift_material::MaterialFolder;
use uplift_neural::model::LATENT;

pub use uplift_material::NormalSpace;

/// Values per texel: parameters, diffuse colour, latents.
pub const TEXEL_VALUES: usize = PARAMETERS + 3 + LATENT;

/// Per-texel material data, row-major (row 0 at the top), `TEXEL_VALUES` floats per texel.
pub struct SurfaceTextures {
    pub width: usize,
    pub height: usize,
    pub values: Vec<f32>,
    pub has_latents: bool,
    /// Baked shading normals per texel (empty: no normal map) and their frame.
    pub normals: Vec<[f32; 3]>,
    pub normal_space: NormalSpace,
    /// The material's glints (meta.json), applied to its non-diffuse part.
    pub glint: Option<uplift_material::GlintRecord>,
}

/// The data at one surface point.
#[derive(Clone, Copy)]
pub struct SurfaceSample {
    pub params: [f32; PARAMETERS],
    pub diffuse: [f32; 3],
    pub latent: [f32; LATENT],
}

impl SurfaceTextures {
    /// One texel everywhere.
    pub fn uniform(params: [f32; PARAMETERS], diffuse: [f32; 3], latent: Option<[f32; LATENT]>) -> SurfaceTextures {
        let mut values = params.to_vec();
        values.extend_from_slice(&diffuse);
        values.extend_from_slice(&latent.unwrap_or([0.0; LATENT]));
        SurfaceTextures { width: 1, height: 1, values, has_latents: latent.is_some(), normals: Vec::new(), normal_space: NormalSpace::Plane, glint: None }
    }

    /// An enhanced material's folder: params.exr (parameters and diffuse colour) and, if
    /// `latents`, latent.exr of the same size.
    pub fn load(dir: &Path, latents: bool) -> Result<SurfaceTextures, String> {
        let folder = MaterialFolder::open(dir)?;
        let p = folder.read_params()?;
        let (w, h) = (p.width, p.height);
        let n = w * h;
        let diffuse = p.diffuse.ok_or_else(|| format!("{}: no channel `diffuse_color.R/G/B` (written by `uplift enhance`; re-run it if the folder predates the diffuse_color channels)", folder.params_path().display()))?;
        let mut values = vec![0.0f32; n * TEXEL_VALUES];
        for t in 0..n {
            let v = &mut values[t * TEXEL_VALUES..(t + 1) * TEXEL_VALUES];
            v[..PARAMETERS].copy_from_slice(&p.params[t * PARAMETERS..(t + 1) * PARAMETERS]);
            v[PARAMETERS..PARAMETERS + 3].copy_from_slice(&diffuse[t * 3..t * 3 + 3]);
        }
        if latents {
            let lat = folder.read_latents()?;
            if (lat.width, lat.height) != (w, h) {
                return Err(format!("{}: {}×{} texels, but params.exr has {w}×{h}", folder.latent_path().display(), lat.width, lat.height));
            }
            for t in 0..n {
                values[t * TEXEL_VALUES + PARAMETERS + 3..(t + 1) * TEXEL_VALUES].copy_from_slice(&lat.latents[t * LATENT..(t + 1) * LATENT]);
            }
        }
        let meta = folder.read_meta_if_any()?;
        let normal_space = meta.as_ref().map_or(NormalSpace::Plane, |m| m.normal_space);
        let glint = meta.and_then(|m| m.glint);
        Ok(SurfaceTextures { width: w, height: h, values, has_latents: latents, normals: p.normals.unwrap_or_default(), normal_space, glint })
    }

    /// The data of texel `t` (row-major index).
    pub fn texel(&self, t: usize) -> SurfaceSample {
        Self::split(&self.values[t * TEXEL_VALUES..(t + 1) * TEXEL_VALUES])
    }

    fn split(v: &[f32]) -> SurfaceSample {
        let mut s = SurfaceSample { params: [0.0; PARAMETERS], diffuse: [0.0; 3], latent: [0.0; LATENT] };
        s.params.copy_from_slice(&v[..PARAMETERS]);
        s.diffuse.copy_from_slice(&v[PARAMETERS..PARAMETERS + 3]);
        s.latent.copy_from_slice(&v[PARAMETERS + 3..]);
        s
    }

    /// The four texels and weights of a bilinear lookup at texture coordinates (u, v).
    fn taps(&self, uv: [f32; 2]) -> [(usize, f32); 4] {
        let (w, h) = (self.width, self.height);
        let x = uv[0] * w as f32 - 0.5;
        let y = (1.0 - uv[1]) * h as f32 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let xi = |k: f32| (k as i64).rem_euclid(w as i64) as usize;
        let yi = |k: f32| (k.max(0.0) as usize).min(h - 1);
        [(x0, y0, (1.0 - fx) * (1.0 - fy)), (x0 + 1.0, y0, fx * (1.0 - fy)), (x0, y0 + 1.0, (1.0 - fx) * fy), (x0 + 1.0, y0 + 1.0, fx * fy)].map(|(tx, ty, wgt)| (yi(ty) * w + xi(tx), wgt))
    }

    /// Bilinear lookup at texture coordinates (u, v).
    pub fn lookup(&self, uv: [f32; 2]) -> SurfaceSample {
        let mut acc = [0.0f32; TEXEL_VALUES];
        for (t, wgt) in self.taps(uv) {
            for (a, v) in acc.iter_mut().zip(&self.values[t * TEXEL_VALUES..(t + 1) * TEXEL_VALUES]) {
                *a += wgt * v;
            }
        }
        Self::split(&acc)
    }

    /// The baked normal at (u, v), bilinear and renormalised, in `normal_space` (None without
    /// a normal map).
    pub fn normal_at(&self, uv: [f32; 2]) -> Option<[f32; 3]> {
        if self.normals.is_empty() {
            return None;
        }
        let mut n = [0.0f32; 3];
        for (t, wgt) in self.taps(uv) {
            for c in 0..3 {
                n[c] += wgt * self.normals[t][c];
            }
        }
        let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        (l > 1e-6).then(|| n.map(|x| x / l))
    }

    /// The shading frame at `hit` with the normal map applied: a `plane` normal as tangent-space
    /// (X, −Z, Y) on the hit's frame, a `world` normal as is where the scene is the mesh it
    /// was baked on (`world_normals`); the hit unchanged otherwise.
    pub fn normal_mapped(&self, hit: &Hit, world_normals: bool) -> Hit {
        match (self.normal_at(hit.uv), self.normal_space) {
            (Some(n), NormalSpace::Plane) => hit.with_shading_normal(hit.to_world([n[0], -n[2], n[1]])),
            (Some(n), NormalSpace::World) if world_normals => hit.with_shading_normal(n),
            _ => *hit,
        }
    }
}
