//! The path tracer: wavefront passes (one sample per pixel per pass, every pixel's paths
//! shaded together so the material kernels run in large batches), distant environment lighting,
//! direct lighting by environment sampling and BSDF sampling combined with the power heuristic
//! (or either strategy alone), and a configurable number of bounces.
//!
//! The material is a `SurfaceModel` (surface_model.rs): an enhanced material (f = f_nd + T·c/π,
//! `material.rs`, its normal map replacing each hit's shading frame, surface.rs) or a MaterialX
//! material's own closure kernels (mtlx_material.rs), whose emission every hit adds.
//!
//! Every random number is a hash of (seed, pixel, pass, depth, dimension), so a render is a
//! pure function of its inputs, samples are independent (the per-pixel variance is an honest
//! error estimate), and the same seed gives reference and neural renders the same light
//! samples. (A low-discrepancy sequence was tried: with this many dimensions it gave more FLIP
//! noise, not less.)

use crate::environment::Environment;
use crate::scene::{dot, Camera, Hit, Scene, Vec3};
use crate::shading::Shading;
use crate::surface::SurfaceTextures;
use crate::surface_model::{EnhancedMaterial, SurfaceModel};
use uplift_base::rng::{mix64, unit_from_key as unit};
use indicatif::ProgressBar;
use rayon::prelude::*;

/// How direct lighting is estimated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Strategy {
    /// Environment and BSDF sampling, combined by the power heuristic.
    Mis,
    /// BSDF sampling only.
    Bsdf,
    /// Environment sampling only (BSDF sampling still continues paths for bounces).
    Light,
}

impl Strategy {
    pub fn parse(s: &str) -> Result<Strategy, String> {
        match s {
            "mis" => Ok(Strategy::Mis),
            "bsdf" => Ok(Strategy::Bsdf),
            "light" => Ok(Strategy::Light),
            _ => Err(format!("--strategy: `{s}` is not one of mis, bsdf, light")),
        }
    }
}

#[derive(Clone, Debug)]
pub struct RenderOptions {
    pub width: usize,
    pub height: usize,
    /// Samples (paths) per pixel.
    pub spp: usize,
    /// Surface interactions after the first (0: direct lighting only).
    pub bounces: usize,
    pub seed: u64,
    pub strategy: Strategy,
    /// Jitter the sample position inside the pixel (off: every path through the pixel centre).
    pub jitter: bool,
    pub fov_degrees: f32,
    pub camera_distance: f32,
    /// The camera (None: the preview camera of `fov_degrees` at `camera_distance` on +z).
    pub camera: Option<Camera>,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions { width: 256, height: 256, spp: 64, bounces: 2, seed: 1, strategy: Strategy::Mis, jitter: true, fov_degrees: 30.0, camera_distance: 4.8, camera: None }
    }
}

/// A rendered image: per pixel the mean radiance, its sample variance per channel and the
/// fraction of primary rays that hit the object.
pub struct Rendering {
    pub width: usize,
    pub height: usize,
    pub radiance: Vec<[f32; 3]>,
    /// Variance of the pixel mean (sample variance / spp), per channel.
    pub variance: Vec<[f32; 3]>,
    pub coverage: Vec<f32>,
}

impl Rendering {
    /// Pixels the object covers (at least half of the primary rays hit it).
    pub fn object_mask(&self) -> Vec<bool> {
        self.coverage.iter().map(|&c| c >= 0.5).collect()
    }
}

#[derive(Clone, Copy)]
struct PathState {
    pixel: u32,
    origin: Vec3,
    dir: Vec3,
    beta: [f32; 3],
    /// The BSDF pdf the current direction was drawn with (for MIS when it escapes).
    pdf_prev: f32,
}

/// The random stream of one pixel.
fn path_key(seed: u64, pixel: u32) -> u64 {
    mix64(mix64(seed ^ 0x7265_6e64) ^ pixel as u64)
}

/// Uniform `dim` of path depth `depth` in sample `pass` of the pixel whose stream is `key`.
fn rand(key: u64, pass: usize, depth: usize, dim: u64) -> f32 {
    unit(mix64(key ^ pass as u64) ^ ((depth as u64 * 16 + dim + 1).wrapping_mul(uplift_base::rng::GOLDEN_GAMMA)))
}

fn power_heuristic(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 > 0.0 { a2 / (a2 + b2) } else { 0.0 }
}

/// Renders `scene` lit by `env` with an enhanced material (`surface` data, `shading` model).
pub fn render(scene: &dyn Scene, env: &Environment, surface: &SurfaceTextures, shading: &Shading, o: &RenderOptions, progress: Option<&ProgressBar>) -> Result<Rendering, String> {
    render_model(scene, env, &EnhancedMaterial { surface, shading }, o, progress)
}

/// Renders `scene` lit by `env` with any material model.
pub fn render_model(scene: &dyn Scene, env: &Environment, model: &dyn SurfaceModel, o: &RenderOptions, progress: Option<&ProgressBar>) -> Result<Rendering, String> {
    if o.width == 0 || o.height == 0 || o.spp == 0 {
        return Err(format!("render: width, height and spp must be at least 1 (got {}×{}, {} spp)", o.width, o.height, o.spp));
    }
    let camera = o.camera.unwrap_or_else(|| Camera::preview(o.fov_degrees, o.camera_distance));
    let n = o.width * o.height;
    let mut sum = vec![[0.0f64; 3]; n];
    let mut sum_sq = vec![[0.0f64; 3]; n];
    let mut hits_primary = vec![0u32; n];
    for pass in 0..o.spp {
        let mut value = vec![[0.0f32; 3]; n];
        let mut paths: Vec<PathState> = (0..n as u32)
            .into_par_iter()
            .map(|pixel| {
                let key = path_key(o.seed, pixel);
                let (jx, jy) = if o.jitter { (rand(key, pass, 0, 14), rand(key, pass, 0, 15)) } else { (0.5, 0.5) };
                let (x, y) = ((pixel as usize % o.width) as f32 + jx, (pixel as usize / o.width) as f32 + jy);
                let (origin, dir) = camera.ray(x, y, o.width, o.height);
                PathState { pixel, origin, dir, beta: [1.0; 3], pdf_prev: 0.0 }
            })
            .collect();
        for depth in 0.. {
            let hits: Vec<Option<Hit>> = paths.par_iter().map(|p| scene.intersect(p.origin, p.dir)).collect();
            let mut shade: Vec<(PathState, Hit)> = Vec::new();
            for (p, h) in paths.iter().zip(hits) {
                match h {
                    None => {
                        if depth > 0 {
                            let w = match o.strategy {
                                Strategy::Mis => power_heuristic(p.pdf_prev, env.pdf(p.dir)),
                                Strategy::Bsdf => 1.0,
                                Strategy::Light => 0.0,
                            };
                            let l = env.radiance(p.dir);
                            for c in 0..3 {
                                value[p.pixel as usize][c] += p.beta[c] * l[c] * w;
                            }
                        }
                    }
                    Some(h) => {
                        if depth == 0 {
                            hits_primary[p.pixel as usize] += 1;
                        }
                        if depth <= o.bounces {
                            shade.push((*p, h));
                        }
                    }
                }
            }
            if shade.is_empty() {
                break;
            }
            paths = shade_hits(&shade, env, scene, model, o, pass, depth, &mut value)?;
            if paths.is_empty() {
                break;
            }
        }
        for (i, v) in value.iter().enumerate() {
            for c in 0..3 {
                let x = if v[c].is_finite() { v[c] as f64 } else { 0.0 };
                sum[i][c] += x;
                sum_sq[i][c] += x * x;
            }
        }
        if let Some(p) = progress {
            p.inc(1);
        }
    }
    let spp = o.spp as f64;
    let radiance = sum.iter().map(|s| s.map(|x| (x / spp) as f32)).collect();
    let variance = sum
        .iter()
        .zip(&sum_sq)
        .map(|(s, q)| [0, 1, 2].map(|c| if o.spp > 1 { ((q[c] - s[c] * s[c] / spp) / (spp - 1.0) / spp).max(0.0) as f32 } else { 0.0 }))
        .collect();
    let coverage = hits_primary.iter().map(|&h| h as f32 / o.spp as f32).collect();
    Ok(Rendering { width: o.width, height: o.height, radiance, variance, coverage })
}

/// Direct lighting at every hit and the continuation paths.
#[allow(clippy::too_many_arguments)]
fn shade_hits(
    shade: &[(PathState, Hit)],
    env: &Environment,
    scene: &dyn Scene,
    model: &dyn SurfaceModel,
    o: &RenderOptions,
    pass: usize,
    depth: usize,
    value: &mut [[f32; 3]],
) -> Result<Vec<PathState>, String> {
    // Points whose view is above the shading surface.
    struct Point {
        path: PathState,
        hit: Hit,
        key: u64,
        wv: Vec3,
        // Environment sample: local direction, pdf, radiance, visible.
        nee: (Vec3, f32, [f32; 3], bool),
    }
    let world_normals = scene.world_space_normals();
    let points: Vec<Point> = shade
        .par_iter()
        .filter_map(|(path, hit)| {
            let hit = &model.shading_hit(hit, world_normals);
            let wv = hit.to_local([-path.dir[0], -path.dir[1], -path.dir[2]]);
            if wv[2] <= 1e-5 {
                return None;
            }
            let key = path_key(o.seed, path.pixel);
            let (d, pdf, l) = env.sample([rand(key, pass, depth, 0), rand(key, pass, depth, 1), rand(key, pass, depth, 2)]);
            let local = hit.to_local(d);
            let visible = pdf > 0.0 && local[2] > 1e-5 && dot(d, hit.geometric_normal) > 0.0 && !scene.occluded(hit.spawn(d), d);
            Some(Point { path: *path, hit: *hit, key, wv, nee: (if visible { local } else { [0.0, 0.0, 1.0] }, pdf, l, visible) })
        })
        .collect();
    let hits: Vec<Hit> = points.iter().map(|p| p.hit).collect();
    let wv: Vec<Vec3> = points.iter().map(|p| p.wv).collect();
    let wl_nee: Vec<Vec3> = points.iter().map(|p| p.nee.0).collect();
    let evaluation = model.evaluate(&hits, &wv, &wl_nee)?;
    let (at_nee, select) = (&evaluation.values, &evaluation.select);
    // Emitted radiance reaches the eye or the previous hit unweighted: nothing samples the
    // emitting surfaces as lights.
    for (p, e) in points.iter().zip(&evaluation.emission) {
        for c in 0..3 {
            value[p.path.pixel as usize][c] += p.path.beta[c] * e[c];
        }
    }
    if o.strategy != Strategy::Bsdf {
        for (p, m) in points.iter().zip(at_nee) {
            let (_, pdf_e, l, visible) = p.nee;
            if !visible {
                continue;
            }
            let w = if o.strategy == Strategy::Mis { power_heuristic(pdf_e, m.pdf) } else { 1.0 };
            for c in 0..3 {
                value[p.path.pixel as usize][c] += p.path.beta[c] * l[c] * m.fcos[c] / pdf_e * w;
            }
        }
    }
    // BSDF sampling continues the paths.
    let u: Vec<[f32; 6]> = points.iter().map(|p| [3, 4, 5, 6, 7, 8].map(|d| rand(p.key, pass, depth, d))).collect();
    let sampled = model.sample(&hits, &wv, select, &u)?;
    let mut next = Vec::with_capacity(points.len());
    for (p, (wl, m)) in points.iter().zip(sampled) {
        if !(m.pdf > 0.0) || wl[2] <= 1e-6 {
            continue;
        }
        let d = p.hit.to_world(wl);
        if dot(d, p.hit.geometric_normal) <= 0.0 {
            continue;
        }
        let beta = [0, 1, 2].map(|c| p.path.beta[c] * m.fcos[c] / m.pdf);
        if beta.iter().all(|&b| b <= 0.0) || beta.iter().any(|b| !b.is_finite()) {
            continue;
        }
        next.push(PathState { pixel: p.path.pixel, origin: p.hit.spawn(d), dir: d, beta, pdf_prev: m.pdf });
    }
    Ok(next)
}
