//! The non-diffuse part of a material as the renderer evaluates it, in batches of surface points:
//! f·cos θl (RGB), the throughput T (RGB) that scales the Lambertian base, R = Y(albedo) of the
//! non-diffuse part, and the pdf of the non-diffuse sampling strategy.
//!
//! - `Reference`: the compiled `uplift_stack` kernels on the interpolated parameters (the
//!   `pdf` context returns response, throughput and pdf in one call; `albedo` gives R).
//! - `Neural`: the frozen decoder on the interpolated latents: its outputs are f (so f·cos θl
//!   is f̂·μl, as Eq. 3 compares it), T and R (paper Eq. 2).
//!
//! Both run on the CPU engine (generated Rust kernels, the trainer's forward pass) or on the
//! wgpu engine (generated WGSL kernels, the emitted WGSL decoder).
//!
//! Both sample the non-diffuse part with the stack's own `sample` kernel on the material's
//! parameters by default: any proposal keeps the estimator unbiased, and sharing it gives
//! reference and neural renders correlated noise, which lowers the FLIP noise floor. A neural
//! material given its sampling decoder (`with_sampler`, uplift_neural::sampler) samples with
//! that instead — the mixture it predicts from the latent alone, its pdf for MIS — as a neural
//! material without its parameters must. The integrator (integrator.rs) adds the diffuse base
//! and chooses between the parts by R.

use crate::scene::Vec3;
use crate::surface::SurfaceSample;
use uplift_engines::cpu_engine::CpuEngine;
use uplift_neural::features::{direction_features, FEATURES};
use uplift_neural::inference::decode_parallel;
use uplift_neural::loss::OUTPUTS;
use uplift_neural::mlp::Mlp;
use uplift_neural::model::{fill_decoder_input, latent_width};
use uplift_engines::stack::Stack;
use std::sync::Arc;
use uplift_neural::inference::WgpuDecoder;
use uplift_engines::stack_kernel::{usable_sample, vec3_at, Engine, StackKernel};
use uplift_engines::wgpu_engine::WgpuEngine;
use uplift_compiler::ClosureContext;

/// The non-diffuse part's values at one direction pair.
#[derive(Clone, Copy, Debug, Default)]
pub struct LobeValue {
    /// f·cos θl.
    pub fcos: [f32; 3],
    pub throughput: [f32; 3],
    /// Luminance of the non-diffuse albedo (only when asked for).
    pub reflectance: f32,
    /// Density of the non-diffuse sampling strategy at wl.
    pub pdf: f32,
}

/// Which evaluation of the non-diffuse part.
pub enum Model {
    Reference,
    Neural(Mlp<f32>),
}

/// Where the kernels run.
pub enum ShadingEngine {
    Cpu(CpuEngine),
    /// The wgpu engine: the stack's WGSL kernels and the emitted WGSL decoder.
    Wgpu(WgpuEngine),
}

impl ShadingEngine {
    /// The engine, borrowed, as prepared kernels take it.
    pub fn as_engine(&self) -> Engine<'_> {
        match self {
            ShadingEngine::Cpu(e) => Engine::Cpu(e),
            ShadingEngine::Wgpu(e) => Engine::Wgpu(e),
        }
    }
}

/// The stack's kernels and, for the neural model, the decoder.
pub struct Shading {
    engine: ShadingEngine,
    /// The glint pattern's kernel, prepared on first use (materials with glints).
    glint: std::sync::OnceLock<Result<crate::glint::GlintKernel, String>>,
    wgpu_decoder: Option<WgpuDecoder>,
    pdf: StackKernel,
    sample: StackKernel,
    albedo: StackKernel,
    pub model: Model,
    /// The neural model's sampling decoder, when it samples with one.
    sampler: Option<Mlp<f32>>,
    /// On the wgpu engine, the sampling decoder's emitted WGSL network.
    wgpu_sampler: Option<WgpuDecoder>,
    threads: usize,
}

fn params_of(points: &[SurfaceSample]) -> Vec<f32> {
    let mut p = Vec::with_capacity(points.len() * points.first().map_or(0, |s| s.count));
    for s in points {
        p.extend_from_slice(s.parameters());
    }
    p
}

fn finite3(v: [f32; 3]) -> [f32; 3] {
    v.map(|x| if x.is_finite() { x.max(0.0) } else { 0.0 })
}

impl Shading {
    /// Shading of `stack` on the CPU engine (generated Rust; the decoder is the trainer's
    /// forward pass).
    pub fn new(engine: CpuEngine, stack: &Arc<Stack>, model: Model) -> Result<Shading, String> {
        // The data generator's four contexts in its order (eval unused here): a stack whose
        // kernels are not shipped shares one built runner between training and rendering.
        let [_, albedo, sample, pdf]: [StackKernel; 4] = StackKernel::contexts(Engine::Cpu(&engine), stack, &[ClosureContext::Eval, ClosureContext::Albedo, ClosureContext::Sample, ClosureContext::Pdf])?
            .try_into()
            .map_err(|_| "four stack kernels".to_string())?;
        Ok(Shading {
            pdf,
            sample,
            albedo,
            threads: engine.threads(),
            engine: ShadingEngine::Cpu(engine),
            glint: Default::default(),
            wgpu_decoder: None,
            model,
            sampler: None,
            wgpu_sampler: None,
        })
    }

    /// Shading on the wgpu engine (the stack's WGSL kernels, the emitted WGSL decoder).
    pub fn new_wgpu(engine: WgpuEngine, stack: &Arc<Stack>, model: Model) -> Result<Shading, String> {
        let e = Engine::Wgpu(&engine);
        let wgpu_decoder = match &model {
            Model::Neural(d) => Some(WgpuDecoder::new(&engine, d, "render")?),
            Model::Reference => None,
        };
        Ok(Shading {
            pdf: StackKernel::on(e, stack, ClosureContext::Pdf)?,
            sample: StackKernel::on(e, stack, ClosureContext::Sample)?,
            albedo: StackKernel::on(e, stack, ClosureContext::Albedo)?,
            threads: 1,
            engine: ShadingEngine::Wgpu(engine),
            glint: Default::default(),
            wgpu_decoder,
            model,
            sampler: None,
            wgpu_sampler: None,
        })
    }

    /// The neural model sampling its non-diffuse part with `sampler` (uplift_neural::sampler):
    /// its network runs as the trainer's forward pass on the CPU engine and as its emitted WGSL
    /// on the wgpu engine (like the evaluation decoder); the mixture's closed forms run on the
    /// CPU. An error for the reference model or a sampler made for another latent width.
    pub fn with_sampler(mut self, sampler: Mlp<f32>) -> Result<Shading, String> {
        let Model::Neural(decoder) = &self.model else { return Err("a sampling decoder serves the neural model only".into()) };
        if sampler.shape.inputs() != latent_width(decoder) + 1 || sampler.shape.outputs() != uplift_neural::sampler::SAMPLER_OUTPUTS {
            return Err(format!("the sampling decoder reads {} inputs; this decoder's latent has {} values (+ μv)", sampler.shape.inputs(), latent_width(decoder)));
        }
        if let ShadingEngine::Wgpu(engine) = &self.engine {
            self.wgpu_sampler = Some(WgpuDecoder::new(engine, &sampler, "render sampler")?);
        }
        self.sampler = Some(sampler);
        Ok(self)
    }

    /// The sampling decoder's mixtures at the points' latents and views.
    fn mixtures(&self, sampler: &Mlp<f32>, points: &[SurfaceSample], wv: &[Vec3]) -> Result<Vec<uplift_neural::sampler::Mixture>, String> {
        let latents: Vec<f32> = points.iter().flat_map(|p| p.latent().iter().copied()).collect();
        let mu: Vec<f32> = wv.iter().map(|w| w[2]).collect();
        if let (ShadingEngine::Wgpu(engine), Some(net)) = (&self.engine, &self.wgpu_sampler) {
            let out = net.decode(engine, &uplift_neural::sampler::sampler_inputs(&latents, &mu, sampler.shape.inputs() - 1))?;
            return Ok(out.chunks(uplift_neural::sampler::SAMPLER_OUTPUTS).map(uplift_neural::sampler::Mixture::from_outputs).collect());
        }
        Ok(uplift_neural::sampler::mixtures(sampler, &latents, &mu))
    }

    /// The stack it shades.
    pub fn stack(&self) -> &Arc<Stack> {
        self.albedo.stack()
    }

    fn engine(&self) -> Engine<'_> {
        self.engine.as_engine()
    }

    /// The glint pattern N of `glint` per hit at local directions (glint.rs).
    pub fn glint_factors(&self, glint: &uplift_material::GlintRecord, hits: &[crate::scene::Hit], wv: &[Vec3], wl: &[Vec3]) -> Result<Vec<[f32; 3]>, String> {
        let kernel = self.glint.get_or_init(|| crate::glint::GlintKernel::new(&self.engine)).as_ref().map_err(|e| e.clone())?;
        kernel.factors(&self.engine, glint, hits, wv, wl)
    }

    /// Which engine, in words.
    pub fn engine_name(&self) -> &'static str {
        match self.engine {
            ShadingEngine::Cpu(_) => "CPU",
            ShadingEngine::Wgpu(_) => "wgpu",
        }
    }

    /// Decoder outputs (rows × 7) at (latent, wv, wl) per row.
    fn decode(&self, decoder: &Mlp<f32>, points: &[SurfaceSample], wv: &[Vec3], wl: &[Vec3]) -> Result<Vec<f32>, String> {
        let n = points.len();
        let latent = latent_width(decoder);
        if let Some(p) = points.iter().find(|p| p.latents != latent) {
            return Err(format!("the material's latent.exr has {} values per texel; the decoder reads {latent} (fit the material with this decoder)", p.latents));
        }
        let mut z = Vec::with_capacity(n * latent);
        let mut features = Vec::with_capacity(n * FEATURES);
        for r in 0..n {
            z.extend_from_slice(points[r].latent());
            features.extend_from_slice(&direction_features(wv[r], wl[r]));
        }
        let mut dec_in = Vec::new();
        fill_decoder_input(&z, &vec![0.0; z.len()], &features, n, latent, &mut dec_in);
        if let (ShadingEngine::Wgpu(e), Some(d)) = (&self.engine, &self.wgpu_decoder) {
            return d.decode(e, &dec_in);
        }
        let mut out = vec![0.0f32; n * OUTPUTS];
        decode_parallel(decoder, &dec_in, &mut out, self.threads);
        Ok(out)
    }

    /// The non-diffuse part at (wv, wl) per point (local frame, both above the surface).
    /// `reflectance` is filled only when `want_reflectance`.
    pub fn evaluate(&self, points: &[SurfaceSample], wv: &[Vec3], wl: &[Vec3], want_reflectance: bool) -> Result<Vec<LobeValue>, String> {
        let n = points.len();
        if n == 0 {
            return Ok(vec![]);
        }
        let params = params_of(points);
        let rows: Vec<usize> = (0..n).collect();
        let out = self.pdf.run_on(self.engine(), &params, &rows, &[("wv", wv), ("wl", wl)])?;
        let (resp_at, thr_at, pdf_at) = (self.pdf.output_offset("response"), self.pdf.output_offset("throughput"), self.pdf.output_offset("pdf"));
        let mut values: Vec<LobeValue> = (0..n)
            .map(|k| LobeValue {
                fcos: finite3(vec3_at(&out, resp_at, k)),
                throughput: finite3(vec3_at(&out, thr_at, k)),
                reflectance: 0.0,
                pdf: out.column(pdf_at)[k].max(0.0),
            })
            .collect();
        match &self.model {
            Model::Reference => {
                if want_reflectance {
                    for (v, (albedo, _)) in values.iter_mut().zip(self.reference_albedo(points, wv)?) {
                        v.reflectance = luminance(albedo);
                    }
                }
            }
            Model::Neural(decoder) => {
                let out = self.decode(decoder, points, wv, wl)?;
                for (k, v) in values.iter_mut().enumerate() {
                    let o = &out[k * OUTPUTS..(k + 1) * OUTPUTS];
                    set_from_decoder(v, o, wl[k][2]);
                    v.reflectance = if o[6].is_finite() { o[6].max(0.0) } else { 0.0 };
                }
                if let Some(sampler) = &self.sampler {
                    for (k, (v, m)) in values.iter_mut().zip(self.mixtures(sampler, points, wv)?).enumerate() {
                        v.pdf = m.pdf(wv[k], wl[k]);
                    }
                }
            }
        }
        Ok(values)
    }

    /// The reference non-diffuse part's directional albedo and throughput at wv per point (the
    /// stack's albedo kernel, whatever the model).
    pub fn reference_albedo(&self, points: &[SurfaceSample], wv: &[Vec3]) -> Result<Vec<([f32; 3], [f32; 3])>, String> {
        if points.is_empty() {
            return Ok(vec![]);
        }
        let params = params_of(points);
        let rows: Vec<usize> = (0..points.len()).collect();
        let a = self.albedo.run_on(self.engine(), &params, &rows, &[("wv", wv)])?;
        let (alb_at, thr_at) = (self.albedo.output_offset("albedo"), self.albedo.output_offset("throughput"));
        Ok((0..points.len()).map(|k| (finite3(vec3_at(&a, alb_at, k)), finite3(vec3_at(&a, thr_at, k)))).collect())
    }

    /// Draws wl from the non-diffuse strategy with three uniforms per point; returns wl and the
    /// part's values there (`reflectance` not filled). A failed sample has pdf 0.
    pub fn sample(&self, points: &[SurfaceSample], wv: &[Vec3], u: &[Vec3]) -> Result<Vec<(Vec3, LobeValue)>, String> {
        let n = points.len();
        if n == 0 {
            return Ok(vec![]);
        }
        if let (Model::Neural(decoder), Some(sampler)) = (&self.model, &self.sampler) {
            // The sampling decoder's mixture: a direction and its pdf, then the decoder there.
            let drawn: Vec<Option<(Vec3, f32)>> = self.mixtures(sampler, points, wv)?.iter().zip(wv).zip(u).map(|((m, v), u)| m.sample(*v, *u).map(|l| (l, m.pdf(*v, l))).filter(|(_, p)| *p > 0.0 && p.is_finite())).collect();
            let wl: Vec<Vec3> = drawn.iter().map(|d| d.map_or([0.0, 0.0, 1.0], |d| d.0)).collect();
            let dec = self.decode(decoder, points, wv, &wl)?;
            return Ok(drawn
                .iter()
                .enumerate()
                .map(|(k, d)| match d {
                    Some((l, pdf)) => {
                        let mut v = LobeValue { pdf: *pdf, ..Default::default() };
                        set_from_decoder(&mut v, &dec[k * OUTPUTS..(k + 1) * OUTPUTS], l[2]);
                        (*l, v)
                    }
                    None => ([0.0, 0.0, 1.0], LobeValue::default()),
                })
                .collect());
        }
        let params = params_of(points);
        let rows: Vec<usize> = (0..n).collect();
        let out = self.sample.run_on(self.engine(), &params, &rows, &[("wv", wv), ("u", u)])?;
        let (wl_at, pdf_at, resp_at, thr_at) =
            (self.sample.output_offset("wl"), self.sample.output_offset("pdf"), self.sample.output_offset("response"), self.sample.output_offset("throughput"));
        let mut result: Vec<(Vec3, LobeValue)> = (0..n)
            .map(|k| {
                let wl = vec3_at(&out, wl_at, k);
                let pdf = out.column(pdf_at)[k];
                let Some(wl) = usable_sample(wl, pdf, 1e-6) else { return ([0.0, 0.0, 1.0], LobeValue::default()) };
                (wl, LobeValue { fcos: finite3(vec3_at(&out, resp_at, k)), throughput: finite3(vec3_at(&out, thr_at, k)), reflectance: 0.0, pdf })
            })
            .collect();
        if let Model::Neural(decoder) = &self.model {
            let wl: Vec<Vec3> = result.iter().map(|r| r.0).collect();
            let dec = self.decode(decoder, points, wv, &wl)?;
            for (k, r) in result.iter_mut().enumerate() {
                set_from_decoder(&mut r.1, &dec[k * OUTPUTS..(k + 1) * OUTPUTS], r.0[2]);
            }
        }
        Ok(result)
    }
}

/// f·cos and T from a decoder output row at light cosine `mu_l`: the decoder predicts f, and
/// Eq. 3 compares μl·f̂ with the reference's f·cos.
fn set_from_decoder(v: &mut LobeValue, o: &[f32], mu_l: f32) {
    let mu = mu_l.max(0.0);
    v.fcos = finite3([o[0] * mu, o[1] * mu, o[2] * mu]);
    v.throughput = finite3([o[3], o[4], o[5]]);
}

pub fn luminance(c: [f32; 3]) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}
