//! A material's per-texel data as the renderer reads it: the `uplift_stack` parameters and
//! the diffuse colour c (from `uplift enhance`'s params.exr), and optionally the fitted latents
//! (`uplift fit`'s latent.exr: the decoder's latent width, 6 for the paper's). Lookups are bilinear, repeating in u and clamped in v; v = 1 is
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
use uplift_engines::stack::{Stack, MAX_PARAMETERS};
use std::path::Path;
use uplift_material::MaterialFolder;
use uplift_neural::model::MAX_LATENT;

pub use uplift_material::NormalSpace;

/// Per-texel material data, row-major (row 0 at the top): per texel the stack's parameters,
/// the diffuse colour and the latents ([`SurfaceTextures::stride`] floats).
pub struct SurfaceTextures {
    pub width: usize,
    pub height: usize,
    /// The stack's parameters per texel.
    pub parameters: usize,
    pub values: Vec<f32>,
    pub has_latents: bool,
    /// Latent values per texel (0 without latents).
    pub latents: usize,
    /// Baked shading normals per texel (empty: no normal map) and their frame.
    pub normals: Vec<[f32; 3]>,
    pub normal_space: NormalSpace,
    /// The material's glints (meta.json), applied to its non-diffuse part.
    pub glint: Option<uplift_material::GlintRecord>,
}

/// The data at one surface point (the first `count` of `params` are the stack's, the first
/// `latents` of `latent` the fitted latent).
#[derive(Clone, Copy)]
pub struct SurfaceSample {
    pub params: [f32; MAX_PARAMETERS],
    pub count: usize,
    pub diffuse: [f32; 3],
    pub latent: [f32; MAX_LATENT],
    pub latents: usize,
}

impl SurfaceSample {
    /// The stack's parameters.
    pub fn parameters(&self) -> &[f32] {
        &self.params[..self.count]
    }

    /// The fitted latent (empty without one).
    pub fn latent(&self) -> &[f32] {
        &self.latent[..self.latents]
    }
}

impl SurfaceTextures {
    /// One texel everywhere (`params`: one row of the stack's parameters).
    pub fn uniform(params: &[f32], diffuse: [f32; 3], latent: Option<&[f32]>) -> SurfaceTextures {
        assert!(params.len() <= MAX_PARAMETERS, "a stack has at most {MAX_PARAMETERS} parameters");
        let latent = latent.unwrap_or(&[]);
        assert!(latent.len() <= MAX_LATENT, "a latent has at most {MAX_LATENT} values");
        let mut values = params.to_vec();
        values.extend_from_slice(&diffuse);
        values.extend_from_slice(latent);
        SurfaceTextures { width: 1, height: 1, parameters: params.len(), values, has_latents: !latent.is_empty(), latents: latent.len(), normals: Vec::new(), normal_space: NormalSpace::Plane, glint: None }
    }

    /// Floats per texel: parameters, diffuse colour, latents.
    pub fn stride(&self) -> usize {
        self.parameters + 3 + self.latents
    }

    /// An enhanced material's folder: params.exr (`stack`'s parameters and the diffuse colour)
    /// and, if `latents`, latent.exr of the same size.
    pub fn load(dir: &Path, stack: &Stack, latents: bool) -> Result<SurfaceTextures, String> {
        let folder = MaterialFolder::open(dir)?;
        let p = folder.read_params(stack)?;
        let (w, h) = (p.width, p.height);
        let n = w * h;
        let np = stack.len();
        let lat = if latents { Some(folder.read_latents()?) } else { None };
        let k = lat.as_ref().map_or(0, |l| l.channels);
        if k > MAX_LATENT {
            return Err(format!("{}: {k} latent values per texel (at most {MAX_LATENT})", folder.latent_path().display()));
        }
        let stride = np + 3 + k;
        let diffuse = p.diffuse.ok_or_else(|| format!("{}: no channel `diffuse_color.R/G/B` (written by `uplift enhance`; re-run it if the folder predates the diffuse_color channels)", folder.params_path().display()))?;
        let mut values = vec![0.0f32; n * stride];
        for t in 0..n {
            let v = &mut values[t * stride..(t + 1) * stride];
            v[..np].copy_from_slice(&p.params[t * np..(t + 1) * np]);
            v[np..np + 3].copy_from_slice(&diffuse[t * 3..t * 3 + 3]);
        }
        if let Some(lat) = lat {
            if (lat.width, lat.height) != (w, h) {
                return Err(format!("{}: {}×{} texels, but params.exr has {w}×{h}", folder.latent_path().display(), lat.width, lat.height));
            }
            for t in 0..n {
                values[t * stride + np + 3..(t + 1) * stride].copy_from_slice(&lat.latents[t * k..(t + 1) * k]);
            }
        }
        let meta = folder.read_meta_if_any()?;
        let normal_space = meta.as_ref().map_or(NormalSpace::Plane, |m| m.normal_space);
        let glint = meta.and_then(|m| m.glint);
        Ok(SurfaceTextures { width: w, height: h, parameters: np, values, has_latents: latents, latents: k, normals: p.normals.unwrap_or_default(), normal_space, glint })
    }

    /// The data of texel `t` (row-major index).
    pub fn texel(&self, t: usize) -> SurfaceSample {
        let stride = self.stride();
        self.split(&self.values[t * stride..(t + 1) * stride])
    }

    fn split(&self, v: &[f32]) -> SurfaceSample {
        let np = self.parameters;
        let k = self.latents;
        let mut s = SurfaceSample { params: [0.0; MAX_PARAMETERS], count: np, diffuse: [0.0; 3], latent: [0.0; MAX_LATENT], latents: k };
        s.params[..np].copy_from_slice(&v[..np]);
        s.diffuse.copy_from_slice(&v[np..np + 3]);
        s.latent[..k].copy_from_slice(&v[np + 3..np + 3 + k]);
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
        let stride = self.stride();
        let mut acc = [0.0f32; MAX_PARAMETERS + 3 + MAX_LATENT];
        for (t, wgt) in self.taps(uv) {
            for (a, v) in acc.iter_mut().zip(&self.values[t * stride..(t + 1) * stride]) {
                *a += wgt * v;
            }
        }
        self.split(&acc[..stride])
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
