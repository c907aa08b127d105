//! MaterialX's Examples materials ($UPLIFT_MTLX_DATA/Materials/Examples: standard_surface and
//! gltf_pbr documents, each `surfacematerial` on its own) as closure kernels, with the shading
//! models of the builtin library (mtlx/libraries/bxdf) and no `--library`:
//! - every material compiles in the four closure contexts (eval, albedo, sample, pdf), runs on
//!   the wgpu engine, and runs on the CPU engine (all kernels in one runner, `prepare_bundle`)
//!   with the wgpu engine's values (5e-3 relative, PDF_TOLERANCE);
//! - at 8 views (μ = 0.1 … 1), for every non-emissive material: albedo + throughput ≤ 1 + 2e-3 (a passive
//!   surface returns at most what arrives) per channel where the albedo is grey (a white base),
//!   for the channels' mean otherwise (MaterialX's generalized_schlick_bsdf passes
//!   1 − mean(albedo) below itself whatever its colour);
//! - at 8 views (μ = 0.1 … 1): the albedo context equals an integral of the eval context over
//!   the hemisphere within 0.005 (within the documented bound of the library's albedo
//!   approximation where the material asks for one: anisotropic GGX, thin films) — 2 × 16,384 directions per view, drawn from a stratified cosine/uniform mix
//!   and from the material's own sample context, weighted by the sum of both densities
//!   (the balance heuristic: a defensive mixture, since Examples lobes as sharp as roughness
//!   0.01 defeat any sampler that does not know them; the pdf the mixture uses is the pdf
//!   context, checked against the sample context below);
//! - at 8 views (μ = 0.1 … 1): the sample context's weight response/pdf equals the eval and pdf contexts' at
//!   the drawn directions (and its pdf the pdf context's, where the pdf is below 10⁴: a
//!   near-specular lobe's pdf at a direction rounded to f32 is not a number to compare), and a χ² test over (cos θ, φ) bins accepts the drawn directions against
//!   the pdf context's integral over each bin. Bins the angular grid cannot integrate (a
//!   near-specular peak inside them: refining the grid changes the bin's mass by more than
//!   1 %) leave the test together with the draws that fell in them, and the rest is tested as
//!   the conditional distribution it is.
//!   docs/conformance.md's "Materials" section is written from this test.

use crate::common;

use common::Rng;
use std::f64::consts::PI;
use std::fmt::Write;
use std::path::{Path, PathBuf};
use uplift_compiler::graph_builder::document_outputs;
use uplift_compiler::{ClosureContext, Compiler, OutputSelection, PatternKernel};
use uplift_engines::batch::{Columns, Geometry, PatternBatch, TextureData};
use uplift_engines::cpu_engine::external::RunnerOptions;
use uplift_engines::cpu_engine::CpuKernel;
use uplift_engines::texture_loader::load_texture;
use uplift_engines::wgpu_engine::WgpuPipeline;

const VIEWS: [f64; 8] = [0.1, 0.2, 0.3, 0.45, 0.6, 0.75, 0.9, 1.0];

/// The widest texture side the test keeps. Its checks sample one surface point, and every
/// batch carries its textures (cloned, uploaded to wgpu, sent to the CPU runner): the chess
/// set's 2048² maps, five per material, made the engines' agreement check alone take 100 s.
const TEXTURE_SIDE: u32 = 256;

/// `t` box-filtered to at most [`TEXTURE_SIDE`] texels a side (the mean of each block of
/// source texels; blocks at the far edges may be partial).
fn shrunk(t: TextureData) -> TextureData {
    let f = (t.width.max(t.height).div_ceil(TEXTURE_SIDE)).max(1);
    if f == 1 {
        return t;
    }
    let (w, h) = (t.width.div_ceil(f), t.height.div_ceil(f));
    let mut rgba = vec![0.0f32; (w * h * 4) as usize];
    for y in 0..h {
        for x in 0..w {
            let mut sum = [0.0f64; 4];
            let mut n = 0.0;
            for sy in y * f..((y + 1) * f).min(t.height) {
                for sx in x * f..((x + 1) * f).min(t.width) {
                    let i = ((sy * t.width + sx) * 4) as usize;
                    for c in 0..4 {
                        sum[c] += t.rgba[i + c] as f64;
                    }
                    n += 1.0;
                }
            }
            let o = ((y * w + x) * 4) as usize;
            for c in 0..4 {
                rgba[o + c] = (sum[c] / n) as f32;
            }
        }
    }
    TextureData { width: w, height: h, rgba }
}

/// One material compiled in every context.
struct Material {
    /// Document path relative to Materials/Examples.
    doc: String,
    name: String,
    /// eval, albedo, sample, pdf.
    kernels: Vec<PatternKernel>,
    textures: Vec<TextureData>,
    /// The albedo approximation the material's lobes use, if any (`approximation`).
    approximation: Option<Approximation>,
    /// The kernels' wgpu pipelines, built on first use.
    pipelines: [std::sync::OnceLock<WgpuPipeline>; 4],
}

impl Material {
    fn kernel(&self, c: ClosureContext) -> &PatternKernel {
        &self.kernels[ClosureContext::ALL.iter().position(|x| *x == c).unwrap()]
    }

    /// A batch of `directions` (one list per direction input, wv first) at one surface point:
    /// the local frame (normal +z, tangent +x), texture coordinate (0.37, 0.61).
    fn batch(&self, c: ClosureContext, directions: &[&[[f32; 3]]]) -> PatternBatch {
        let k = self.kernel(c);
        let n = directions[0].len();
        let mut inputs = Columns::zeros(n, k.input_stride);
        for inp in &k.inputs {
            let d = c
                .direction_inputs()
                .iter()
                .position(|x| *x == inp.input.name);
            for ch in 0..inp.input.ty.components().unwrap() {
                let col = inputs.column_mut(inp.offset + ch);
                match d {
                    Some(j) => col
                        .iter_mut()
                        .zip(directions[j])
                        .for_each(|(x, v)| *x = v[ch]),
                    None => col.fill(inp.input.default[ch]),
                }
            }
        }
        let geometry = Geometry {
            texcoord: [0.37, 0.61],
            position: [0.0; 3],
            normal: [0.0, 0.0, 1.0],
            tangent: [1.0, 0.0, 0.0],
        }
        .repeated(n);
        PatternBatch {
            geometry,
            inputs,
            textures: self.textures.clone(),
            points_per_group: 1,
        }
    }

    fn run(&self, c: ClosureContext, directions: &[&[[f32; 3]]]) -> Outputs<'_> {
        let i = ClosureContext::ALL.iter().position(|x| *x == c).unwrap();
        let k = &self.kernels[i];
        let p = self.pipelines[i].get_or_init(|| common::engine().prepare(k));
        let out = common::engine()
            .run_chunked(p, &self.batch(c, directions), 1 << 16)
            .unwrap_or_else(|e| panic!("{} {}: {e}", self.doc, self.name));
        Outputs { kernel: k, out }
    }

    fn label(&self) -> String {
        format!("{} / {}", self.doc, self.name)
    }
}

struct Outputs<'a> {
    kernel: &'a PatternKernel,
    out: Columns,
}

impl Outputs<'_> {
    fn col(&self, name: &str, c: usize) -> &[f32] {
        let o = self
            .kernel
            .outputs
            .iter()
            .find(|o| o.name == name)
            .unwrap_or_else(|| panic!("no output {name}"));
        self.out.column(o.offset + c)
    }

    fn dir(&self, name: &str, k: usize) -> [f32; 3] {
        [0, 1, 2].map(|c| self.col(name, c)[k])
    }
}

fn mtlx_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    v.sort();
    for p in v {
        if p.is_dir() {
            mtlx_files(&p, out);
        } else if p.extension().is_some_and(|e| e == "mtlx") {
            out.push(p);
        }
    }
}

fn view(mu: f64) -> [f32; 3] {
    [(1.0 - mu * mu).max(0.0).sqrt() as f32, 0.0, mu as f32]
}

/// Albedo approximations of the library (docs/albedo-tables.md), with the bound the albedo is
/// held to against the integral of eval instead of 0.005: an anisotropic GGX lobe's albedo is
/// that of the isotropic lobe at ᾱ = √(αx αy) (exact at normal view, off by up to 0.052 at
/// μ = 0.1 on these materials), a thin film's is its Fresnel moments' (off by up to 0.012).
#[derive(Clone, Copy, Debug)]
enum Approximation {
    Anisotropic,
    ThinFilm,
}

impl Approximation {
    fn bound(self) -> f64 {
        match self {
            Approximation::Anisotropic => 0.06,
            Approximation::ThinFilm => 0.015,
        }
    }

    fn name(self) -> &'static str {
        match self {
            Approximation::Anisotropic => "anisotropic GGX (albedo at √(αx αy))",
            Approximation::ThinFilm => "thin film (Fresnel moments)",
        }
    }
}

/// The approximation a material's shader node asks for: a nonzero `*anisotropy` input, or a
/// nonzero `thin_film_thickness` / `iridescence`.
fn approximation(doc: &mtlx::Document, material: mtlx::ElementId) -> Option<Approximation> {
    let shader = doc
        .children_of(material, "input")
        .find_map(|i| doc.get(i).attr("nodename").map(str::to_string))?;
    let node = doc
        .children(doc.root())
        .iter()
        .copied()
        .find(|&n| doc.get(n).name() == shader)?;
    let value = |suffix: &str| {
        doc.children_of(node, "input").any(|i| {
            let e = doc.get(i);
            e.name().ends_with(suffix)
                && e.attr("value")
                    .and_then(|v| v.trim().parse::<f32>().ok())
                    .is_some_and(|v| v != 0.0)
        })
    };
    if value("anisotropy") {
        Some(Approximation::Anisotropic)
    } else if value("thin_film_thickness") || value("iridescence") {
        Some(Approximation::ThinFilm)
    } else {
        None
    }
}

/// Every Examples material compiled in the four contexts (panics naming the first failure).
fn examples(data: &Path) -> Vec<Material> {
    let mut compiler = Compiler::builtin();
    // The data folder as a search path, as MATERIALX_SEARCH_PATH would be: the Examples name
    // their images as ../../../Images/….
    compiler.file_roots = Some(vec![data.to_path_buf()]);
    let root = data.join("Materials/Examples");
    let mut files = Vec::new();
    mtlx_files(&root, &mut files);
    let mut materials = Vec::new();
    let mut failures = Vec::new();
    for f in &files {
        let (doc, diags) = mtlx::read_file(f);
        assert!(
            !diags.iter().any(|d| d.is_error()),
            "{}: {diags:?}",
            f.display()
        );
        let rel = f.strip_prefix(&root).unwrap().display().to_string();
        for o in document_outputs(&doc)
            .into_iter()
            .filter(|o| uplift_compiler::wgsl_types::is_scattering(&o.ty))
        {
            let mut kernels = Vec::new();
            for c in ClosureContext::ALL {
                let r = compiler.compile_document_in(
                    doc.clone(),
                    Vec::new(),
                    &f.display().to_string(),
                    &OutputSelection::Named(vec![o.name.clone()]),
                    Some(c),
                );
                match r.kernel {
                    Some(k) if !r.diagnostics.iter().any(|d| d.is_error()) => kernels.push(k),
                    _ => failures.push(format!(
                        "{rel} / {} ({}): {}",
                        o.name,
                        c.name(),
                        r.diagnostics
                            .iter()
                            .map(|d| d.to_string())
                            .collect::<Vec<_>>()
                            .join("; ")
                    )),
                }
            }
            if kernels.len() == 4 {
                let textures = kernels[0]
                    .textures
                    .iter()
                    .map(|t| {
                        shrunk(
                            load_texture(&t.path, t.colorspace.as_deref())
                                .unwrap_or_else(|e| panic!("{e}")),
                        )
                    })
                    .collect();
                materials.push(Material {
                    doc: rel.clone(),
                    name: o.name.clone(),
                    kernels,
                    textures,
                    approximation: approximation(&doc, o.element),
                    pipelines: Default::default(),
                });
            }
        }
    }
    assert!(
        failures.is_empty(),
        "materials that do not compile:\n{}",
        failures.join("\n")
    );
    materials
}

/// Random numbers for the sample context: u.xy stratified on a `side` × (n / side) grid, u.z
/// uniform.
fn stratified_u(n: usize, side: usize, rng: &mut Rng) -> Vec<[f32; 3]> {
    (0..n)
        .map(|k| {
            let (i, j) = (k % side, k / side);
            [
                ((i as f32 + rng.range(0.0, 1.0)) / side as f32).min(0.9999999),
                ((j as f32 + rng.range(0.0, 1.0)) / (n / side) as f32).min(0.9999999),
                rng.range(0.0, 1.0),
            ]
        })
        .collect()
}

/// The χ² bins: cos θ ∈ [−1, 1] in 16, φ in 32.
const THETA_BINS: usize = 16;
const PHI_BINS: usize = 32;

fn bin(d: &[f32; 3]) -> usize {
    let t = (((d[2] as f64 + 1.0) * 0.5 * THETA_BINS as f64) as usize).min(THETA_BINS - 1);
    let phi = (d[1] as f64).atan2(d[0] as f64).rem_euclid(2.0 * PI);
    let f = ((phi / (2.0 * PI) * PHI_BINS as f64) as usize).min(PHI_BINS - 1);
    t * PHI_BINS + f
}

/// Each bin's probability under the pdf context at each of `views`, integrated on `sub` × `sub`
/// sub-cells per bin (z = z_hi − Δz·s², cells shrinking towards the bin's upper edge).
fn bin_masses(m: &Material, views: &[[f32; 3]], sub: usize) -> Vec<(Vec<f64>, Vec<f32>)> {
    let (nt, np) = (THETA_BINS * sub, PHI_BINS * sub);
    let dz = 2.0 / THETA_BINS as f64;
    let mut dirs = Vec::with_capacity(nt * np);
    let mut cells = Vec::with_capacity(nt * np);
    for k in 0..nt * np {
        let (t, f) = (k / np, k % np);
        let (tb, s) = (t / sub, ((t % sub) as f64 + 0.5) / sub as f64);
        let z = -1.0 + dz * (tb + 1) as f64 - dz * s * s;
        let phi = 2.0 * PI * (f as f64 + 0.5) / np as f64;
        let r = (1.0 - z * z).max(0.0).sqrt();
        dirs.push([(r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32]);
        cells.push(dz * 2.0 * s / sub as f64 * 2.0 * PI / np as f64);
    }
    let wv: Vec<[f32; 3]> = views
        .iter()
        .flat_map(|v| std::iter::repeat_n(*v, dirs.len()))
        .collect();
    let wl: Vec<[f32; 3]> = views.iter().flat_map(|_| dirs.iter().copied()).collect();
    let q = m.run(ClosureContext::Pdf, &[&wv, &wl]);
    let pdf = q.col("pdf", 0);
    (0..views.len())
        .map(|vi| {
            let mut mass = vec![0.0f64; THETA_BINS * PHI_BINS];
            let mut highest = vec![0.0f32; THETA_BINS * PHI_BINS];
            for (k, d) in dirs.iter().enumerate() {
                let p = pdf[vi * dirs.len() + k];
                mass[bin(d)] += p as f64 * cells[k];
                highest[bin(d)] = highest[bin(d)].max(p);
            }
            (mass, highest)
        })
        .collect()
}

/// The sample context's pdf and response against the pdf and eval contexts at the direction it
/// drew: relative. The direction is written as f32 and read back normalised, which a sharp lobe
/// at grazing view amplifies (1.1e-3 measured: gltf_pbr_boombox at μ = 0.05, pdf 59).
const PDF_TOLERANCE: f32 = 5e-3;

/// The estimator's weight response/pdf, sample context against eval/pdf contexts: relative.
const WEIGHT_TOLERANCE: f64 = 5e-3;

struct Verdict {
    highest_energy: f64,
    worst_integral: f64,
    worst_p: f64,
    excluded_bins: usize,
    emissive: bool,
}

/// The numeric checks of one material on the wgpu engine, all views in each batch (panics
/// naming the first failure).
fn check_material(m: &Material, seed: u64) -> Verdict {
    let label = m.label();
    let views: Vec<[f32; 3]> = VIEWS.iter().map(|&mu| view(mu)).collect();
    let albedo = m.run(ClosureContext::Albedo, &[&views]);
    let emissive = (0..3).any(|c| albedo.col("emission", c).iter().any(|&e| e != 0.0));
    let mut highest_energy = 0.0f64;
    for (k, mu) in VIEWS.iter().enumerate() {
        let a: [f64; 3] = [0, 1, 2].map(|c| albedo.col("albedo", c)[k] as f64);
        let t: [f64; 3] = [0, 1, 2].map(|c| albedo.col("throughput", c)[k] as f64);
        for c in 0..3 {
            assert!(
                a[c].is_finite() && t[c].is_finite() && a[c] >= -1e-5 && t[c] >= -1e-5,
                "{label}: μ {mu} channel {c}: albedo {}, throughput {}",
                a[c],
                t[c]
            );
        }
        if emissive {
            continue;
        }
        // Per channel where the albedo is grey (a white base); else the channels' mean, since
        // MaterialX's generalized_schlick_bsdf passes 1 − mean(albedo) to what lies below it,
        // whatever its colour (a gold lobe's red channel then sums to more than 1).
        let grey = (a[0] - a[1]).abs().max((a[1] - a[2]).abs()) <= 1e-4;
        let sums: Vec<f64> = if grey {
            (0..3).map(|c| a[c] + t[c]).collect()
        } else {
            vec![(0..3).map(|c| a[c] + t[c]).sum::<f64>() / 3.0]
        };
        for e in sums {
            highest_energy = highest_energy.max(e);
            assert!(
                e <= 1.0 + 2e-3,
                "{label}: μ {mu}: albedo {a:?} + throughput {t:?} = {e:.5} > 1 + 2e-3 ({})",
                if grey { "a channel" } else { "channel mean" }
            );
        }
    }
    let mut rng = Rng::new(seed);
    let mut worst_integral = 0.0f64;
    let mut worst_p = 1.0f64;
    let mut excluded_bins = 0;
    let n_log2: u32 = std::env::var("UPLIFT_MATERIALS_N_LOG2")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(14);
    let n: usize = 1 << n_log2;
    let nv = VIEWS.len();
    let wv: Vec<[f32; 3]> = views
        .iter()
        .flat_map(|v| std::iter::repeat_n(*v, n))
        .collect();
    // Draws of the sample context, n per view.
    let u: Vec<[f32; 3]> = (0..nv)
        .flat_map(|_| stratified_u(n, 1 << (n_log2 / 2), &mut rng))
        .collect();
    let s = m.run(ClosureContext::Sample, &[&wv, &u]);
    let wl: Vec<[f32; 3]> = (0..n * nv).map(|k| s.dir("wl", k)).collect();
    let spdf = s.col("pdf", 0);
    // The pdf and eval contexts at the drawn directions: the pdf where it is finite in f32
    // terms (a near-specular lobe's pdf at a direction rounded to f32 is not), and everywhere
    // the estimator's weight response/pdf, which is well conditioned.
    let q = m.run(ClosureContext::Pdf, &[&wv, &wl]);
    let e = m.run(ClosureContext::Eval, &[&wv, &wl]);
    for k in (0..n * nv).filter(|&k| spdf[k] > 0.0) {
        let mu = VIEWS[k / n];
        let (p0, p1) = (spdf[k], q.col("pdf", 0)[k]);
        if p0 < 1e4 {
            assert!(
                (p0 - p1).abs() <= PDF_TOLERANCE * p0.abs().max(1.0),
                "{label}: μ {mu}: sample pdf {p0} vs pdf context {p1} at {:?}",
                wl[k]
            );
        }
        for c in 0..3 {
            let (r0, r1) = (s.col("response", c)[k], e.col("response", c)[k]);
            let (w0, w1) = (
                r0 as f64 / p0 as f64,
                if p1 > 0.0 { r1 as f64 / p1 as f64 } else { 0.0 },
            );
            assert!((w0 - w1).abs() <= WEIGHT_TOLERANCE * w0.abs().max(1.0), "{label}: μ {mu}: sample response/pdf {w0} vs eval/pdf context {w1} at {:?} (pdf {p0}, {p1})", wl[k]);
        }
    }
    // The integral of eval: per view, n directions from a stratified cosine/uniform mix and the
    // n draws of the sample context, each weighted by the sum of both densities (the balance
    // heuristic for two samplers of n draws each: (1/n) Σ f / (p_def + p_material)).
    let side = 1 << (n_log2 / 2);
    let mut defensive: Vec<[f32; 3]> = Vec::with_capacity(n * nv);
    for _ in 0..nv {
        for k in 0..n {
            let (i, j) = (k % side, k / side);
            let u1 = (i as f64 + rng.range(0.0, 1.0) as f64) / side as f64;
            let u2 = (j as f64 + rng.range(0.0, 1.0) as f64) / (n / side) as f64;
            let phi = 2.0 * PI * u2;
            // ½ cosine + ½ uniform hemisphere.
            let z = if u1 < 0.5 {
                (2.0 * u1).sqrt()
            } else {
                2.0 * u1 - 1.0
            }
            .clamp(1e-6, 1.0);
            let r = (1.0 - z * z).max(0.0).sqrt();
            defensive.push([(r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32]);
        }
    }
    let qd = m.run(ClosureContext::Pdf, &[&wv, &defensive]);
    let ed = m.run(ClosureContext::Eval, &[&wv, &defensive]);
    let p_def = |d: [f32; 3]| {
        if d[2] > 0.0 {
            0.5 * d[2] as f64 / PI + 0.5 / (2.0 * PI)
        } else {
            0.0
        }
    };
    for (vi, &mu) in VIEWS.iter().enumerate() {
        for c in 0..3 {
            let mut sum = 0.0f64;
            for k in vi * n..(vi + 1) * n {
                let p = p_def(defensive[k]) + qd.col("pdf", 0)[k] as f64;
                if p > 0.0 {
                    sum += ed.col("response", c)[k] as f64 / p;
                }
                if spdf[k] > 0.0 {
                    sum +=
                        e.col("response", c)[k] as f64 / (p_def(wl[k]) + q.col("pdf", 0)[k] as f64);
                }
            }
            let integral = sum / n as f64;
            let a = albedo.col("albedo", c)[vi] as f64;
            let err = (integral - a).abs();
            worst_integral = worst_integral.max(err);
            let bound = m.approximation.map_or(0.005, Approximation::bound);
            assert!(err <= bound, "{label}: μ {mu} channel {c}: albedo {a:.5} vs the integral of eval {integral:.5}: |error| {err:.2e} > {bound}");
        }
    }
    // χ²: bins whose mass the grid resolves: 8 and 16 sub-cells per bin side agree within 1 %,
    // and no draw in the bin has a pdf above 4× the highest the grid saw there (else a peak
    // narrower than the grid lies inside it).
    let coarse = bin_masses(m, &views, 8);
    let fine = bin_masses(m, &views, 16);
    for (vi, &mu) in VIEWS.iter().enumerate() {
        let (coarse, (fine, grid_highest)) = (&coarse[vi].0, &fine[vi]);
        let mut observed = vec![0.0f64; THETA_BINS * PHI_BINS];
        let mut drawn_highest = vec![0.0f32; THETA_BINS * PHI_BINS];
        for k in (vi * n..(vi + 1) * n).filter(|&k| spdf[k] > 0.0) {
            observed[bin(&wl[k])] += 1.0;
            drawn_highest[bin(&wl[k])] = drawn_highest[bin(&wl[k])].max(spdf[k]);
        }
        let resolved: Vec<bool> = (0..fine.len())
            .map(|b| {
                (fine[b] - coarse[b]).abs() <= 0.01 * fine[b].max(1e-4)
                    && drawn_highest[b] <= 4.0 * grid_highest[b] + 1e-3
            })
            .collect();
        excluded_bins += resolved.iter().filter(|r| !**r).count();
        let kept_mass: f64 = (0..fine.len())
            .filter(|&b| resolved[b])
            .map(|b| fine[b])
            .sum();
        let kept_obs: f64 = (0..fine.len())
            .filter(|&b| resolved[b])
            .map(|b| observed[b])
            .sum();
        if kept_obs < 200.0 || kept_mass <= 0.0 {
            continue; // (nearly) everything in unresolvable peaks: checked by the weights above
        }
        let expected: Vec<f64> = (0..fine.len())
            .map(|b| {
                if resolved[b] {
                    fine[b] / kept_mass * kept_obs
                } else {
                    0.0
                }
            })
            .collect();
        let (chi2, df) = common::chi2::pooled(&observed, &expected, (0..expected.len()).filter(|&b| resolved[b]));
        let pv = common::chi2::p_value(chi2, (df.max(2) - 1) as f64);
        worst_p = worst_p.min(pv);
        assert!(
            pv > 1e-4,
            "{label}: μ {mu}: χ² {chi2:.1} over {df} cells, p = {pv:.2e}"
        );
    }
    Verdict {
        highest_energy,
        worst_integral,
        worst_p,
        excluded_bins,
        emissive,
    }
}

/// The CPU engine's values against the wgpu engine's on a few points per context.
fn cpu_agrees(materials: &[Material], prepared: &[CpuKernel]) {
    let mut rng = Rng::new(0xc9_0e);
    for (mi, m) in materials.iter().enumerate() {
        let t = std::time::Instant::now();
        for (ci, c) in ClosureContext::ALL.into_iter().enumerate() {
            let n = 64;
            let wv: Vec<[f32; 3]> = (0..n).map(|k| view(VIEWS[k % 8])).collect();
            let second: Vec<[f32; 3]> = match c {
                ClosureContext::Sample => stratified_u(n, 8, &mut rng),
                _ => (0..n)
                    .map(|_| {
                        let (z, phi) = (rng.range(0.0, 1.0) as f64, rng.range(0.0, std::f32::consts::TAU) as f64);
                        let r = (1.0 - z * z).sqrt();
                        [(r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32]
                    })
                    .collect(),
            };
            let dirs: Vec<&[[f32; 3]]> = if c == ClosureContext::Albedo {
                vec![&wv]
            } else {
                vec![&wv, &second]
            };
            let batch = m.batch(c, &dirs);
            let gpu = m.run(c, &dirs).out;
            let cpu = common::bsdf::cpu_engine()
                .run_prepared(&prepared[mi * 4 + ci], &batch)
                .unwrap_or_else(|e| panic!("{} ({}): {e}", m.label(), c.name()));
            for col in 0..gpu.width() {
                for k in 0..n {
                    let (a, b) = (gpu.column(col)[k], cpu.column(col)[k]);
                    assert!(
                        (a - b).abs() <= PDF_TOLERANCE * a.abs().max(1.0),
                        "{} ({}): output column {col} row {k}: wgpu {a} vs CPU {b}",
                        m.label(),
                        c.name()
                    );
                }
            }
        }
        eprintln!("{}: CPU agrees in {:.1} s", m.label(), t.elapsed().as_secs_f64());
    }
}

#[test]
fn examples_materials_compile_run_and_conserve_energy() {
    let Ok(data) = std::env::var("UPLIFT_MTLX_DATA") else {
        return uplift_base::test_env::skip(
            "examples_materials",
            "UPLIFT_MTLX_DATA is not set (set it to ../shared/data/materialx; .ci/run does)",
        );
    };
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let data = root.join(data);
    let t0 = std::time::Instant::now();
    let mut materials = examples(&data);
    assert!(
        materials.len() >= 28,
        "only {} Examples materials",
        materials.len()
    );
    if let Ok(only) = std::env::var("UPLIFT_MATERIALS_ONLY") {
        materials.retain(|m| m.label().contains(&only)); // (for working on one material)
    }
    eprintln!(
        "{} materials compiled in 4 contexts in {:.1} s",
        materials.len(),
        t0.elapsed().as_secs_f64()
    );
    // CPU: every kernel in one runner (opt-level 0: building ~170 kernels optimised takes LLVM
    // tens of minutes; the speed of these kernels is measured by the engines benchmark). The
    // runner builds (cargo, in a thread) while the wgpu checks run: on 2 cores the build and
    // lavapipe's pipeline compiles overlap.
    let all: Vec<&PatternKernel> = materials.iter().flat_map(|m| m.kernels.iter()).collect();
    let options = RunnerOptions {
        cache_dir: Path::new(env!("CARGO_TARGET_TMPDIR")).join("uplift-kernel-cache"),
        vectorize: true,
        quick: true,
    };
    let tables = common::compiler().library.albedo_table_data.clone();
    let mut rows = String::from("| document | material | contexts | engines | albedo + throughput (highest, 8 views) | worst \\|albedo − ∫eval\\| | worst χ² p | bins left to the pdf check | albedo approximation |\n|---|---|---|---|---|---|---|---|---|\n");
    let mut failed = Vec::new();
    let prepared = std::thread::scope(|scope| {
        let build = scope.spawn(|| {
            let t1 = std::time::Instant::now();
            let prepared = common::bsdf::cpu_engine().prepare_bundle(&all, tables.as_deref(), &options);
            eprintln!("CPU runner for {} kernels built in {:.1} s", all.len(), t1.elapsed().as_secs_f64());
            prepared
        });
        for (i, m) in materials.iter().enumerate() {
            let t = std::time::Instant::now();
            let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                check_material(m, 0x3a7e ^ i as u64)
            }));
            let Ok(v) = r else {
                failed.push(m.label());
                continue;
            };
            eprintln!(
                "{}: checked in {:.1} s",
                m.label(),
                t.elapsed().as_secs_f64()
            );
            let energy = if v.emissive {
                "emissive".to_string()
            } else {
                format!("{:.4}", v.highest_energy)
            };
            let approx = m.approximation.map_or("—".to_string(), |a| {
                format!("{} (bound {})", a.name(), a.bound())
            });
            let _ = writeln!(rows, "| {} | {} | eval, albedo, sample, pdf | wgpu, CPU | {energy} | {:.1e} | {:.3} | {} | {approx} |", m.doc, m.name, v.worst_integral, v.worst_p, v.excluded_bins);
        }
        build.join().unwrap_or_else(|_| panic!("the CPU runner's build panicked"))
    })
    .unwrap_or_else(|e| panic!("{e}"));
    let t2 = std::time::Instant::now();
    cpu_agrees(&materials, &prepared);
    eprintln!(
        "CPU and wgpu agree on every kernel ({:.1} s)",
        t2.elapsed().as_secs_f64()
    );
    let section = format!(
        "## Materials\n\nGenerated by `runtime/uplift/tests/integration/materials.rs` (with `UPLIFT_MTLX_DATA` set). Every `surfacematerial` of Materials/Examples, compiled with the builtin library alone (its `bxdf` shading models; no `--library`) in the four closure contexts, run on the wgpu engine and on the CPU engine (agreeing to 5e-3 relative: a near-specular lobe's pdf at a direction rounded to f32 moves by that much), and checked at 8 views (μ = 0.1 … 1): albedo + throughput ≤ 1 + 2e-3 (non-emissive materials; per channel where the albedo is grey, for the channels' mean otherwise, as MaterialX's generalized_schlick_bsdf passes 1 − mean(albedo) below itself), the albedo against an integral of eval (≤ 0.005, or the documented bound of the library's albedo approximation the material uses), and the sample context against the pdf and eval contexts and by a χ² test over 16 × 32 direction bins. Images the documents name but the data folder lacks read as the texture nodes' `default`, as in MaterialX; images wider than 256 texels are box-filtered to 256 (the checks sample one surface point, and every batch carries its textures).\n\n{} materials: all compile and pass.\n\n{rows}",
        materials.len()
    );
    assert!(
        failed.is_empty(),
        "materials failing the numeric checks (messages above):\n{}",
        failed.join("\n")
    );
    write_materials_section(&root.join("docs/conformance.md"), &section);
}

/// Replaces (or appends) the "## Materials" section of docs/conformance.md, which
/// compiler/tests/integration/conformance.rs writes the rest of.
fn write_materials_section(path: &Path, section: &str) {
    let text = std::fs::read_to_string(path).unwrap_or_default();
    let head = match text.find("\n## Materials\n") {
        Some(i) => &text[..i + 1],
        None => text.as_str(),
    };
    let mut out = head.trim_end().to_string();
    out.push_str("\n\n");
    out.push_str(section);
    uplift_base::atomic_write::write_atomically(path, out.as_bytes()).unwrap();
}
