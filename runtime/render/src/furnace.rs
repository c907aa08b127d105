//! The white furnace test, per texel (lobes.md §5.1, the deterministic form of the paper's §4.3
//! filter): for a convex object under a unit environment a one-bounce pixel equals the
//! material's total albedo A(wv) = ∫ f cos θl dωl = ∫ f_nd cos dωl + T·c, so if A ≤ 1 at every
//! texel and view no render of it can exceed 1.
//!
//! The neural material's A is estimated by Monte Carlo with a defensive mixture of the
//! material's two strategies (material.rs: the stack's sampler and cosine, half each), the
//! selector stratified so each strategy gets exactly its share, and a seeded
//! hash for the other dimensions — the same numbers every run; its standard error is the
//! tolerance (an estimate counts as above a threshold only when it is more than 3 standard
//! errors above). The reference material's A is exact, from the albedo kernel
//! (`exact_albedo`); the estimator is tested against it.
//!
//! Texels with identical data are checked once; at most `max_texels` distinct texels are
//! checked (a seeded subset when there are more), at `views` view cosines from 1 down to the
//! decoder's smallest (θv = 87°). A material fails if any channel of any (texel, view) exceeds
//! `limit` (1.02), or if more than `over_one_fraction` (1 %) of the pairs exceed `one` (1.002:
//! 1 plus the albedo tables' error, issue 4's tolerance).

use crate::material;
use crate::scene::Vec3;
use crate::shading::{Model, Shading};
use crate::surface::{SurfaceSample, SurfaceTextures};
use uplift_base::rng::{mix64, unit_from_key as unit};
use uplift_neural::features::view_direction;
use std::collections::HashMap;

#[derive(Clone, Debug)]
pub struct FurnaceOptions {
    pub views: usize,
    pub directions: usize,
    pub max_texels: usize,
    /// No pair may exceed this.
    pub limit: f32,
    /// What counts as above 1 (1 + the albedo tables' error).
    pub one: f32,
    /// At most this fraction of pairs may be above `one`.
    pub over_one_fraction: f64,
    /// Monte Carlo tolerance: a pair's estimate is lowered by this many standard errors before
    /// it is compared (the paper's "tolerating small Monte-Carlo violations").
    pub sigmas: f32,
    pub seed: u64,
}

impl Default for FurnaceOptions {
    fn default() -> Self {
        FurnaceOptions { views: 16, directions: 1024, max_texels: 256, limit: 1.02, one: 1.002, over_one_fraction: 0.01, sigmas: 3.0, seed: 1 }
    }
}

#[derive(Clone, Debug)]
pub struct FurnaceResult {
    /// Distinct texels in the material, and how many were checked.
    pub distinct_texels: usize,
    pub checked_texels: usize,
    /// (texel, view) pairs checked.
    pub pairs: usize,
    /// The largest channel of A over all pairs, with its texel (x, y) and view cosine.
    pub worst: f32,
    pub worst_texel: (usize, usize),
    pub worst_mu: f32,
    /// Pairs whose largest channel exceeds `one` beyond the Monte Carlo tolerance.
    pub over_one: usize,
    /// Some pair exceeds `limit` beyond the Monte Carlo tolerance.
    pub failed_hard: bool,
    pub passed: bool,
}

/// The view cosines checked.
pub use uplift_neural::features::view_cosines;

/// Monte Carlo estimate of A(wv) per (point, view), `directions` samples each.
pub fn estimated_albedo(shading: &Shading, points: &[SurfaceSample], wv: &[Vec3], directions: usize, seed: u64) -> Result<Vec<[f32; 3]>, String> {
    Ok(estimated_albedo_with_error(shading, points, wv, directions, seed)?.into_iter().map(|(a, _)| a).collect())
}

/// Monte Carlo estimate of A(wv) per (point, view) and its standard error per channel.
pub fn estimated_albedo_with_error(shading: &Shading, points: &[SurfaceSample], wv: &[Vec3], directions: usize, seed: u64) -> Result<Vec<([f32; 3], [f32; 3])>, String> {
    let n = points.len();
    // A defensive mixture: half the directions from the stack's sampler, half cosine-weighted,
    // whatever the material's own choice — a decoder's lobe may reach where the stack's sampler
    // rarely goes, and the estimate must not miss that energy.
    let select = vec![0.5f32; n];
    let mut acc = vec![[0.0f64; 3]; n];
    let mut acc_sq = vec![[0.0f64; 3]; n];
    // Rows per kernel call: about 128 k.
    let per = (131_072 / directions.max(1)).max(1);
    for start in (0..n).step_by(per) {
        let end = (start + per).min(n);
        let mut p = Vec::with_capacity((end - start) * directions);
        let mut v = Vec::with_capacity(p.capacity());
        let mut s = Vec::with_capacity(p.capacity());
        let mut u = Vec::with_capacity(p.capacity());
        for r in start..end {
            let key = mix64(seed ^ mix64(r as u64 ^ 0x6675_726e));
            for j in 0..directions {
                let k = mix64(key ^ j as u64);
                let stratum = (j as f32 + unit(k)) / directions as f32;
                p.push(points[r]);
                v.push(wv[r]);
                s.push(select[r]);
                u.push([stratum, unit(k ^ 1), unit(k ^ 2), unit(k ^ 3), unit(k ^ 4), unit(k ^ 5)]);
            }
        }
        let drawn = material::sample(shading, &p, &v, &s, &u, None)?;
        for (i, (_, m)) in drawn.iter().enumerate() {
            if m.pdf > 0.0 {
                let r = start + i / directions;
                for c in 0..3 {
                    let x = (m.fcos[c] / m.pdf) as f64;
                    acc[r][c] += x;
                    acc_sq[r][c] += x * x;
                }
            }
        }
    }
    let n = directions as f64;
    Ok(acc
        .iter()
        .zip(&acc_sq)
        .map(|(a, q)| {
            let mean = a.map(|x| x / n);
            let se = [0, 1, 2].map(|c| if directions > 1 { (((q[c] - a[c] * mean[c]) / (n - 1.0)).max(0.0) / n).sqrt() as f32 } else { 0.0 });
            (mean.map(|x| x as f32), se)
        })
        .collect())
}

/// The reference material's A(wv) from the albedo kernel: albedo + T·c.
pub fn exact_albedo(shading: &Shading, points: &[SurfaceSample], wv: &[Vec3]) -> Result<Vec<[f32; 3]>, String> {
    let a = shading.reference_albedo(points, wv)?;
    Ok(a.iter().zip(points).map(|((alb, t), p)| [0, 1, 2].map(|c| alb[c] + t[c] * p.diffuse[c])).collect())
}

/// The distinct texels of a material (bitwise identical data counted once): their indices.
pub fn distinct_texels(surface: &SurfaceTextures) -> Vec<usize> {
    let mut seen: HashMap<Vec<u32>, usize> = HashMap::new();
    let mut order = Vec::new();
    for t in 0..surface.width * surface.height {
        let stride = surface.stride();
        let key: Vec<u32> = surface.values[t * stride..(t + 1) * stride].iter().map(|x| x.to_bits()).collect();
        if let std::collections::hash_map::Entry::Vacant(e) = seen.entry(key) {
            e.insert(t);
            order.push(t);
        }
    }
    order
}

/// The white furnace check of a material under `shading`.
pub fn white_furnace(surface: &SurfaceTextures, shading: &Shading, o: &FurnaceOptions) -> Result<FurnaceResult, String> {
    let distinct = distinct_texels(surface);
    let mut chosen = distinct.clone();
    if chosen.len() > o.max_texels {
        // A seeded subset: sort by a hash of the texel index and keep the first.
        chosen.sort_by_key(|&t| mix64(o.seed ^ mix64(t as u64)));
        chosen.truncate(o.max_texels);
        chosen.sort_unstable();
    }
    let mus = view_cosines(o.views);
    let mut points = Vec::new();
    let mut wv = Vec::new();
    for &t in &chosen {
        let s = surface.texel(t);
        for &mu in &mus {
            points.push(s);
            wv.push(view_direction(mu));
        }
    }
    // The reference's A is exact (albedo kernel); the neural one is estimated.
    let a: Vec<([f32; 3], [f32; 3])> = match shading.model {
        Model::Reference => exact_albedo(shading, &points, &wv)?.into_iter().map(|a| (a, [0.0; 3])).collect(),
        Model::Neural(_) => estimated_albedo_with_error(shading, &points, &wv, o.directions, o.seed)?,
    };
    let mut r = FurnaceResult { distinct_texels: distinct.len(), checked_texels: chosen.len(), pairs: a.len(), worst: 0.0, worst_texel: (0, 0), worst_mu: 1.0, over_one: 0, failed_hard: false, passed: true };
    for (i, (v, se)) in a.iter().enumerate() {
        let m = v[0].max(v[1]).max(v[2]);
        let m = if m.is_finite() { m } else { f32::INFINITY };
        let low = (0..3).map(|c| v[c] - o.sigmas * se[c]).fold(f32::MIN, f32::max);
        let low = if low.is_finite() { low } else { f32::INFINITY };
        if low > o.one {
            r.over_one += 1;
        }
        if low > o.limit {
            r.failed_hard = true;
        }
        if m > r.worst {
            let t = chosen[i / mus.len()];
            r.worst = m;
            r.worst_texel = (t % surface.width, t / surface.width);
            r.worst_mu = mus[i % mus.len()];
        }
    }
    r.passed = !r.failed_hard && (r.over_one as f64) <= o.over_one_fraction * r.pairs as f64;
    Ok(r)
}
