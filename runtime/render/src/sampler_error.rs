//! What the sampling decoder (uplift_neural::sampler) buys on a material: direct-lighting
//! renders of its preview ball (MIS with the environment) at equal samples per pixel, the neural
//! non-diffuse part sampled by the sampling decoder or by the cosine lobe alone, each compared
//! with a converged render (the stack's own sampler at many samples per pixel). The ratio of the
//! two mean squared errors is the variance reduction at equal cost in samples.

use crate::environment::Environment;
use crate::integrator::{render, RenderOptions};
use crate::scene::Sphere;
use crate::shading::{Model, Shading};
use crate::surface::SurfaceTextures;
use std::sync::Arc;
use uplift_engines::cpu_engine::CpuEngine;
use uplift_engines::stack::Stack;
use uplift_neural::mlp::Mlp;

/// The three ways of shading one neural model that the comparison needs.
pub struct SamplerShadings {
    /// Sampled by the sampling decoder.
    pub sampled: Shading,
    /// Sampled by the cosine lobe alone.
    pub cosine: Shading,
    /// Sampled by the stack's own sampler (the converged render's).
    pub stack: Shading,
}

impl SamplerShadings {
    pub fn new(stack: &Arc<Stack>, decoder: &Mlp<f32>, sampler: &Mlp<f32>, threads: usize) -> Result<SamplerShadings, String> {
        let neural = || -> Result<Shading, String> { Shading::new(CpuEngine::with_threads(threads)?, stack, Model::Neural(decoder.clone())) };
        let latent = sampler.shape.inputs() - 1;
        Ok(SamplerShadings { sampled: neural()?.with_sampler(sampler.clone())?, cosine: neural()?.with_sampler(uplift_neural::sampler::cosine_only(latent))?, stack: neural()? })
    }
}

/// The comparison's settings.
#[derive(Clone, Copy, Debug)]
pub struct SamplerErrorOptions {
    /// Image width and height.
    pub size: usize,
    /// Samples per pixel of the two compared renders.
    pub spp: usize,
    /// Samples per pixel of the converged render.
    pub converged_spp: usize,
    pub seed: u64,
}

impl Default for SamplerErrorOptions {
    fn default() -> Self {
        SamplerErrorOptions { size: 24, spp: 16, converged_spp: 1024, seed: 1 }
    }
}

/// Mean squared error (per pixel, summed over RGB) of each strategy's render against the
/// converged one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SamplerError {
    pub sampler: f64,
    pub cosine: f64,
}

impl SamplerError {
    /// cosine / sampler: how many times less variance the sampling decoder leaves.
    pub fn ratio(&self) -> f64 {
        self.cosine / self.sampler
    }
}

/// Measures [`SamplerError`] for one material.
pub fn sampler_error(surface: &SurfaceTextures, env: &Environment, s: &SamplerShadings, o: &SamplerErrorOptions) -> Result<SamplerError, String> {
    if o.size == 0 || o.spp == 0 || o.converged_spp <= o.spp {
        return Err(format!("sampler error: size and spp must be at least 1 and the converged render's spp above {} (got size {}, spp {}, converged {})", o.spp, o.size, o.spp, o.converged_spp));
    }
    let ro = |spp, seed| RenderOptions { width: o.size, height: o.size, spp, bounces: 0, seed, ..Default::default() };
    let scene = Sphere::preview();
    let converged = render(&scene, env, surface, &s.stack, &ro(o.converged_spp, o.seed ^ 0x5eed), None)?;
    let mse = |shading: &Shading| -> Result<f64, String> {
        let img = render(&scene, env, surface, shading, &ro(o.spp, o.seed), None)?;
        Ok(img.radiance.iter().zip(&converged.radiance).map(|(a, b)| (0..3).map(|c| ((a[c] - b[c]) as f64).powi(2)).sum::<f64>()).sum::<f64>() / img.radiance.len() as f64)
    };
    Ok(SamplerError { sampler: mse(&s.sampled)?, cosine: mse(&s.cosine)? })
}

/// Per Type: the materials, and the lowest, median and highest ratio of [`SamplerError`].
#[derive(Clone, Debug, PartialEq)]
pub struct SamplerRow {
    pub kind: usize,
    pub count: usize,
    pub ratio: (f64, f64, f64),
}

/// The per-Type rows of (Type, error) pairs.
pub fn per_type_ratios(errors: &[(usize, SamplerError)]) -> Vec<SamplerRow> {
    (0..6)
        .filter_map(|k| {
            let mut r: Vec<f64> = errors.iter().filter(|(t, e)| *t == k && e.ratio().is_finite()).map(|(_, e)| e.ratio()).collect();
            if r.is_empty() {
                return None;
            }
            r.sort_by(f64::total_cmp);
            let n = r.len();
            let median = if n % 2 == 1 { r[n / 2] } else { 0.5 * (r[n / 2 - 1] + r[n / 2]) };
            Some(SamplerRow { kind: k, count: n, ratio: (r[0], median, r[n - 1]) })
        })
        .collect()
}
