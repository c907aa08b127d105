//! The enhanced-material folder, read and written in one place. `uplift enhance` creates it,
//! `uplift fit` adds the latents, and every command that reads a material (fit, render,
//! furnace, eval-fit, the demo) opens it through [`MaterialFolder`]:
//!
//! ```text
//! OUT/material.mtlx      the standalone uplifted MaterialX document
//! OUT/params.exr         per texel: the uplift_stack parameters, diffuse_color.R/G/B, normal.X/Y/Z
//! OUT/meta.json          what made it (format, Type, rule, seed, source, scalars, masks): `Meta`
//! OUT/masks/, textures/  the rule's procedural masks and the PBR input's textures
//! OUT/latent.exr         the fitted latents latent0.R/G/B, latent1.R/G/B (`uplift fit`; a
//!                        decoder with a wider latent adds latent2.R, …)
//! OUT/latent0.png, latent1.png, …   the same quantised to 8 bits
//! OUT/fit.json           the fit's record (Eq. 3 before and after, groups, time): `FitRecord`
//! ```
//!
//! `folder` owns the paths, the checks (a missing folder, a folder that is not an enhanced
//! material, a format newer than this build) and the EXR layouts; `meta` and `fit_record` are
//! the typed JSON files (serde), each with a `format` version. Folders written before the
//! version field existed read as format 0.
//!
//! Must never: run kernels, fit or render (it is data, below enhance, neural and render).

pub mod fit_record;
pub mod folder;
pub mod meta;

pub use fit_record::{EnergyRecord, FitRecord, LossRecord};
pub use folder::{LatentImage, MaterialFolder, ParamsImage};
pub use meta::{GlintRecord, MaskRecord, Meta, NormalSpace};
