//! Training data from the compiled `uplift_stack` kernels (runtime/kernels/graphs/bsdf/uplift_stack.mtlx,
//! shipped in the eval, albedo and sample contexts). A batch is a pure function of (seed, batch
//! index, size): each row draws its class (by the classes' shares, or one class), tile and cell
//! from a counter-based hash, its parameters from the class's graph (`classes`), its view cosine-weighted (θv ≤ 87°) and
//! its light from a mixture — half uniform on the hemisphere, half from the stack's own
//! `sample` (falling back to uniform where a sample leaves the hemisphere). No importance weights:
//! the mixture itself is the regression weighting (lobes.md §4.3). Targets: f·μl (RGB) from
//! `eval` (or `sample`, whose response is the same), T (RGB) and R = Y(albedo) from `albedo`.

use crate::classes::{TrainingClasses, TILE};
use crate::features::{cosine_view, direction_features, uniform_cosine_view, uniform_hemisphere, FEATURES};
use crate::loss::OUTPUTS;
use uplift_engines::stack::Stack;
use std::sync::Arc;
use uplift_engines::prepared_kernel::AnyEngine;
use uplift_engines::stack_kernel::{usable_sample, Engine, StackKernel};
use uplift_base::rng::{mix64, unit_from_key as unit};
use rayon::prelude::*;
use uplift_compiler::ClosureContext;

/// Base materials (tiles) per themed class.
pub const TILES_PER_CLASS: u64 = 1 << 16;

/// Which classes a generator draws.
#[derive(Clone, Debug, PartialEq)]
pub enum ClassMix {
    /// Every class in proportion to its share (the builtin five: 1/5 each; paper §4.2:
    /// infill ≈ 20 %).
    All,
    /// One class, by name.
    Only(String),
    /// Every class, the named ones' shares multiplied by their factors (`dust=2,inner=2`:
    /// twice the dust and inner rows of `all`, relative to the others).
    Weighted(Vec<(String, f64)>),
}

impl ClassMix {
    /// `all`, a class name, or `name=factor,…` (names checked against the classes when a batch
    /// is drawn).
    pub fn parse(text: &str) -> Result<ClassMix, String> {
        if text == "all" {
            Ok(ClassMix::All)
        } else if text.contains('=') {
            let mut v = Vec::new();
            for part in text.split(',') {
                let (name, factor) = part.split_once('=').ok_or_else(|| format!("`{part}` is not name=factor"))?;
                let f = factor.trim().parse::<f64>().ok().filter(|f| f.is_finite() && *f >= 0.0).ok_or_else(|| format!("`{factor}` (class {name}) is not a factor ≥ 0"))?;
                if name.trim().is_empty() {
                    return Err(format!("`{part}` names no class"));
                }
                v.push((name.trim().to_string(), f));
            }
            Ok(ClassMix::Weighted(v))
        } else if text.is_empty() {
            Err("an empty class name".into())
        } else {
            Ok(ClassMix::Only(text.to_string()))
        }
    }
    /// The mix as `parse` reads it.
    pub fn name(&self) -> String {
        match self {
            ClassMix::All => "all".into(),
            ClassMix::Only(c) => c.clone(),
            ClassMix::Weighted(w) => w.iter().map(|(n, f)| format!("{n}={f}")).collect::<Vec<_>>().join(","),
        }
    }
}

/// A batch of training rows.
#[derive(Clone, Debug, Default)]
pub struct TrainingBatch {
    pub rows: usize,
    pub class: Vec<u8>,
    /// rows × the stack's parameters (physical values).
    pub params: Vec<f32>,
    /// rows × the stack's encoder inputs.
    pub encoded: Vec<f32>,
    pub wv: Vec<[f32; 3]>,
    pub wl: Vec<[f32; 3]>,
    /// rows × 9 direction features.
    pub features: Vec<f32>,
    pub mu_l: Vec<f32>,
    /// rows × 7: f·μl RGB, T RGB, R.
    pub target: Vec<f32>,
}

/// One group's draws ([`DataGenerator::picks`]): its class, tile and cell.
pub(crate) type GroupPick = (usize, u64, u64);

/// One row's direction draws ([`DataGenerator::draw_directions`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct RowDirections {
    pub wv: [f32; 3],
    /// The light when it is not sampled (or the sample is unusable).
    pub wl: [f32; 3],
    /// The stack sampler's uniforms.
    pub u: [f32; 3],
    pub sample: bool,
}

/// Generates training batches.
pub struct DataGenerator {
    engine: AnyEngine,
    stack: Arc<Stack>,
    classes: TrainingClasses,
    eval: StackKernel,
    albedo: StackKernel,
    sample: StackKernel,
    pdf: StackKernel,
    pub mix: ClassMix,
    pub seed: u64,
    pub views: ViewDistribution,
    /// K, light directions per (parameter set, view): a batch holds rows / K groups of K rows
    /// sharing their class, parameters and view, the first K/2 lit uniformly and the rest from
    /// the stack's sampler (1: every row its own parameters and view, the light's kind a coin
    /// flip). With K > 1 the albedo runs once per group and the eval through the stack's
    /// dependence-split kernel (issue 24).
    pub directions_per_view: usize,
}

/// How training views are drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ViewDistribution {
    /// Cosine-weighted, θv ≤ 87° (a sphere's pixels see views this way).
    Cosine,
    /// Half cosine-weighted, half with μv uniform: more grazing views.
    Mixed,
}

impl ViewDistribution {
    pub fn parse(s: &str) -> Result<ViewDistribution, String> {
        match s {
            "cosine" => Ok(ViewDistribution::Cosine),
            "mixed" => Ok(ViewDistribution::Mixed),
            _ => Err(format!("`{s}` is not cosine or mixed")),
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            ViewDistribution::Cosine => "cosine",
            ViewDistribution::Mixed => "mixed",
        }
    }
}

impl DataGenerator {
    /// A generator of `stack`'s training data on `engine` (the CPU engine, or the wgpu engine:
    /// the same kernels as WGSL).
    pub fn new(engine: impl Into<AnyEngine>, stack: &Arc<Stack>, mix: ClassMix, seed: u64) -> Result<DataGenerator, String> {
        let engine: AnyEngine = engine.into();
        let mut k = StackKernel::contexts(engine.engine(), stack, &[ClosureContext::Eval, ClosureContext::Albedo, ClosureContext::Sample, ClosureContext::Pdf])?.into_iter();
        let mut next = || k.next().expect("four contexts");
        Ok(DataGenerator {
            eval: next(),
            albedo: next(),
            sample: next(),
            pdf: next(),
            classes: TrainingClasses::load(stack, engine.engine())?,
            engine,
            stack: stack.clone(),
            mix,
            seed,
            views: ViewDistribution::Cosine,
            directions_per_view: 1,
        })
    }

    /// The stack whose data this generates.
    pub fn stack(&self) -> &Arc<Stack> {
        &self.stack
    }

    /// The training classes (`classes`).
    pub fn classes(&self) -> &TrainingClasses {
        &self.classes
    }

    /// The engine the reference kernels run on.
    pub fn engine(&self) -> Engine<'_> {
        self.engine.engine()
    }

    /// The stack's `sample` kernel (wv, u → wl, pdf, response, throughput).
    pub fn sample_kernel(&self) -> &StackKernel {
        &self.sample
    }

    /// The stack's `eval` kernel (wv, wl → response, throughput).
    pub fn eval_kernel(&self) -> &StackKernel {
        &self.eval
    }

    /// The stack's `pdf` kernel (wv, wl → pdf, response, throughput).
    pub fn pdf_kernel(&self) -> &StackKernel {
        &self.pdf
    }

    /// The stack's `albedo` kernel (wv → albedo, throughput).
    pub fn albedo_kernel(&self) -> &StackKernel {
        &self.albedo
    }

    /// Where the stack's kernels come from (shipped or built).
    pub fn describe(&self) -> String {
        self.eval.describe()
    }

    /// Batch `index` of `rows` rows (a multiple of `directions_per_view`).
    pub fn batch(&self, index: u64, rows: usize) -> Result<TrainingBatch, String> {
        let (key, k, picks) = self.picks(index, rows)?;
        let groups = rows / k;
        let np = self.stack.len();
        let mut params = vec![0.0; rows * np];
        let mut classes = vec![0u8; rows];
        for c in 0..self.classes.len() {
            let members: Vec<usize> = (0..groups).filter(|&g| picks[g].0 == c).collect();
            if members.is_empty() {
                continue;
            }
            let tiles: Vec<u64> = members.iter().map(|&g| picks[g].1).collect();
            let cells: Vec<u64> = members.iter().map(|&g| picks[g].2).collect();
            let p = self.classes.parameters(self.engine.engine(), c, self.seed, &tiles, &cells)?;
            for (m, &g) in members.iter().enumerate() {
                for r in g * k..(g + 1) * k {
                    params[r * np..(r + 1) * np].copy_from_slice(&p[m * np..(m + 1) * np]);
                    classes[r] = c as u8;
                }
            }
        }
        let mut b = self.evaluate_grouped(params, key, k)?;
        b.class = classes;
        Ok(b)
    }

    /// Batch `index`'s key, the rows per group (`directions_per_view`), and per group its
    /// class, tile and cell, each group drawn from its own key.
    pub(crate) fn picks(&self, index: u64, rows: usize) -> Result<(u64, usize, Vec<GroupPick>), String> {
        let k = self.directions_per_view.max(1);
        if !rows.is_multiple_of(k) {
            return Err(format!("a batch of {rows} rows does not hold whole groups of {k} light directions per view (--directions-per-view)"));
        }
        let key = mix64(self.seed ^ 0x6461_7461) ^ mix64(index.wrapping_mul(uplift_base::rng::GOLDEN_GAMMA));
        let mut factors = vec![1.0; self.classes.len()];
        let only = match &self.mix {
            ClassMix::All => None,
            ClassMix::Only(name) => Some(self.classes.index_of(name)?),
            ClassMix::Weighted(w) => {
                for (name, f) in w {
                    factors[self.classes.index_of(name)?] = *f;
                }
                if factors.iter().all(|f| *f == 0.0) {
                    return Err("the class factors are all 0".into());
                }
                None
            }
        };
        // Each group of k rows draws its class, tile and cell from its own key; the classes'
        // kernels then run once per class on all of its groups.
        let groups = rows / k;
        let picks: Vec<GroupPick> = (0..groups)
            .map(|g| {
                let rk = mix64(key.wrapping_add(g as u64));
                let class = only.unwrap_or_else(|| self.classes.pick_weighted(unit(rk ^ 1) as f64, &factors));
                (class, mix64(rk ^ 2) % TILES_PER_CLASS, mix64(rk ^ 3) % (TILE * TILE))
            })
            .collect();
        Ok((key, k, picks))
    }

    /// Per row of a batch drawn from `key` in groups of `k`: the view, a uniform light, the
    /// sampler's three uniforms, and whether the light comes from the sampler. Rows are
    /// independent (each draws from its own key): drawn in parallel, the same rows whatever the
    /// thread count (on one thread this was a sixth of data generation).
    pub(crate) fn draw_directions(&self, key: u64, rows: usize, k: usize) -> Vec<RowDirections> {
        let mixed = self.views == ViewDistribution::Mixed;
        (0..rows)
            .into_par_iter()
            .map(|r| {
                let rk = mix64(key.wrapping_add(r as u64)) ^ 0x5eed;
                // The view from the group's first row's key.
                let vk = mix64(key.wrapping_add((r - r % k) as u64)) ^ 0x5eed;
                let grazing = mixed && unit(vk ^ 12) < 0.5;
                let wv = if grazing { uniform_cosine_view(unit(vk ^ 4), unit(vk ^ 5)) } else { cosine_view(unit(vk ^ 4), unit(vk ^ 5)) };
                let sample = if k == 1 { unit(rk ^ 11) < 0.5 } else { r % k >= k / 2 };
                RowDirections { wv, wl: uniform_hemisphere(unit(rk ^ 6), unit(rk ^ 7)), u: [unit(rk ^ 8), unit(rk ^ 9), unit(rk ^ 10)], sample }
            })
            .collect()
    }

    /// Directions and reference targets for given parameter rows (rows × the stack's
    /// parameters), drawn from `key`.
    pub fn evaluate(&self, params: Vec<f32>, key: u64) -> Result<TrainingBatch, String> {
        self.evaluate_grouped(params, key, 1)
    }

    /// [`evaluate`](Self::evaluate) for rows in groups of `k` sharing their parameters (the
    /// caller's promise): one view per group (`directions_per_view`).
    fn evaluate_grouped(&self, params: Vec<f32>, key: u64, k: usize) -> Result<TrainingBatch, String> {
        let rows = params.len() / self.stack.len();
        let mut b = TrainingBatch { rows, params, class: vec![0; rows], ..Default::default() };
        let mut sampled = Vec::new();
        let mut uniform = Vec::new();
        let mut u3 = vec![[0.0f32; 3]; rows];
        for (r, d) in self.draw_directions(key, rows, k).into_iter().enumerate() {
            b.wv.push(d.wv);
            b.wl.push(d.wl);
            u3[r] = d.u;
            if d.sample { sampled.push(r) } else { uniform.push(r) }
        }
        b.target = vec![0.0; rows * OUTPUTS];
        // Uniformly lit rows: with groups, the first k/2 of each group, contiguous in `uniform`
        // (the eval's grouped layout); failed samples join them below, evaluated ungrouped.
        let grouped_uniform = uniform.len();
        // Lights from the stack's sampler; rows whose sample fails fall back to uniform.
        if !sampled.is_empty() {
            // With groups, the last k − k/2 rows of each group: contiguous in `sampled`.
            let out = self.sample.run_grouped(self.engine.engine(), &b.params, &sampled, &[("wv", &b.wv), ("u", &u3)], if k == 1 { 1 } else { k - k / 2 })?;
            let (wl_at, pdf_at, resp_at) = (self.sample.output_offset("wl"), self.sample.output_offset("pdf"), self.sample.output_offset("response"));
            for (k, &r) in sampled.iter().enumerate() {
                let wl = [0, 1, 2].map(|c| out.column(wl_at + c)[k]);
                let pdf = out.column(pdf_at)[k];
                let resp = [0, 1, 2].map(|c| out.column(resp_at + c)[k]);
                if let Some(wl) = usable_sample(wl, pdf, 1e-4).filter(|_| resp.iter().all(|x| x.is_finite())) {
                    b.wl[r] = wl;
                    b.target[r * OUTPUTS..r * OUTPUTS + 3].copy_from_slice(&resp);
                } else {
                    uniform.push(r);
                }
            }
        }
        let resp_at = self.eval.output_offset("response");
        let (grouped, fallback) = uniform.split_at(grouped_uniform);
        for (part, per_group) in [(grouped, (k / 2).max(1)), (fallback, 1)] {
            if part.is_empty() {
                continue;
            }
            let out = self.eval.run_grouped(self.engine.engine(), &b.params, part, &[("wv", &b.wv), ("wl", &b.wl)], per_group)?;
            for (j, &r) in part.iter().enumerate() {
                for c in 0..3 {
                    b.target[r * OUTPUTS + c] = out.column(resp_at + c)[j];
                }
            }
        }
        // The albedo depends on the parameters and the view only: once per group.
        let leaders: Vec<usize> = (0..rows).step_by(k).collect();
        let out = self.albedo.run(self.engine.engine(), &b.params, &leaders, &[("wv", &b.wv)])?;
        let (alb_at, thr_at) = (self.albedo.output_offset("albedo"), self.albedo.output_offset("throughput"));
        for r in 0..rows {
            let g = r / k;
            let t = &mut b.target[r * OUTPUTS..(r + 1) * OUTPUTS];
            for c in 0..3 {
                t[c] = t[c].max(0.0);
                t[3 + c] = out.column(thr_at + c)[g];
            }
            let a = [0, 1, 2].map(|c| out.column(alb_at + c)[g]);
            t[6] = 0.2126 * a[0] + 0.7152 * a[1] + 0.0722 * a[2];
        }
        b.encoded = vec![0.0; rows * self.stack.len()];
        self.stack.encode_rows(&b.params, &mut b.encoded);
        b.features = Vec::with_capacity(rows * FEATURES);
        for r in 0..rows {
            b.features.extend_from_slice(&direction_features(b.wv[r], b.wl[r]));
            b.mu_l.push(b.wl[r][2]);
        }
        Ok(b)
    }
}
