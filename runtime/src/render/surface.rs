//! A material's per-texel data as the renderer reads it: the 22 `uplift_stack` parameters and
//! the diffuse colour c (from `uplift enhance`'s params.exr), and optionally the 6 fitted latents
//! (`uplift fit`'s latent.exr). Lookups are bilinear, repeating in u and clamped in v; v = 1 is
//! the image's top row (MaterialX's texcoord convention, as `uplift enhance` bakes).

use crate::exr;
use crate::neural::model::LATENT;
use crate::neural::params::{PARAMETERS, PARAMETER_TABLE};
use std::path::Path;

/// Diffuse colour channels of params.exr.
pub const DIFFUSE_CHANNELS: [&str; 3] = ["diffuse_color.R", "diffuse_color.G", "diffuse_color.B"];

/// The latent channels of latent.exr.
pub const LATENT_CHANNELS: [&str; LATENT] = ["latent0.R", "latent0.G", "latent0.B", "latent1.R", "latent1.G", "latent1.B"];

/// Values per texel: parameters, diffuse colour, latents.
pub const TEXEL_VALUES: usize = PARAMETERS + 3 + LATENT;

/// Per-texel material data, row-major (row 0 at the top), `TEXEL_VALUES` floats per texel.
pub struct SurfaceTextures {
    pub width: usize,
    pub height: usize,
    pub values: Vec<f32>,
    pub has_latents: bool,
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
        SurfaceTextures { width: 1, height: 1, values, has_latents: latent.is_some() }
    }

    /// An enhanced material's folder: params.exr (parameters and diffuse colour) and, if
    /// `latents`, latent.exr of the same size.
    pub fn load(dir: &Path, latents: bool) -> Result<SurfaceTextures, String> {
        let path = dir.join("params.exr");
        let img = exr::read(&path)?;
        let (w, h) = (img.width, img.height);
        let n = w * h;
        let mut values = vec![0.0f32; n * TEXEL_VALUES];
        let names = PARAMETER_TABLE.iter().map(|p| p.channel).chain(DIFFUSE_CHANNELS);
        for (k, name) in names.enumerate() {
            let ch = img.channel(name).ok_or_else(|| format!("{}: no channel `{name}` (written by `uplift enhance`; re-run it if the folder predates the diffuse_color channels)", path.display()))?;
            for t in 0..n {
                values[t * TEXEL_VALUES + k] = ch[t];
            }
        }
        if latents {
            let path = dir.join("latent.exr");
            let lat = exr::read(&path)?;
            if (lat.width, lat.height) != (w, h) {
                return Err(format!("{}: {}×{} texels, but params.exr has {w}×{h}", path.display(), lat.width, lat.height));
            }
            for (k, name) in LATENT_CHANNELS.iter().enumerate() {
                let ch = lat.channel(name).ok_or_else(|| format!("{}: no channel `{name}` (written by `uplift fit`)", path.display()))?;
                for t in 0..n {
                    values[t * TEXEL_VALUES + PARAMETERS + 3 + k] = ch[t];
                }
            }
        }
        if let Some(i) = values.iter().position(|x| !x.is_finite()) {
            let t = i / TEXEL_VALUES;
            return Err(format!("{}: texel ({}, {}) holds a non-finite value", dir.display(), t % w, t / w));
        }
        Ok(SurfaceTextures { width: w, height: h, values, has_latents: latents })
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

    /// Bilinear lookup at texture coordinates (u, v).
    pub fn lookup(&self, uv: [f32; 2]) -> SurfaceSample {
        let (w, h) = (self.width, self.height);
        let x = uv[0] * w as f32 - 0.5;
        let y = (1.0 - uv[1]) * h as f32 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let xi = |k: f32| (k as i64).rem_euclid(w as i64) as usize;
        let yi = |k: f32| (k.max(0.0) as usize).min(h - 1);
        let mut acc = [0.0f32; TEXEL_VALUES];
        for (tx, ty, wgt) in [(x0, y0, (1.0 - fx) * (1.0 - fy)), (x0 + 1.0, y0, fx * (1.0 - fy)), (x0, y0 + 1.0, (1.0 - fx) * fy), (x0 + 1.0, y0 + 1.0, fx * fy)] {
            let t = yi(ty) * w + xi(tx);
            for (a, v) in acc.iter_mut().zip(&self.values[t * TEXEL_VALUES..(t + 1) * TEXEL_VALUES]) {
                *a += wgt * v;
            }
        }
        Self::split(&acc)
    }
}
