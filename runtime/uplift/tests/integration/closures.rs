//! The pbrlib closure library against independent references, on the shipped CPU kernels
//! (runtime/kernels/graphs/bsdf, found in-process by fingerprint):
//! - every lobe and the layered stack: the albedo context equals a brute-force Monte Carlo
//!   integral of the eval context (16,384 stratified directions, 40 random parameter sets and
//!   12 anisotropic ones, 8 view angles from μ = 0.02 to 1) within the albedo tables' documented
//!   error plus four standard errors of the estimate, per channel;
//! - white furnace: a white, non-absorbing stack over white Lambert has albedo 1 ± 2e-3, every
//!   transmitting lobe alone has albedo + throughput = 1 ± 2e-3; a conductor of reflectivity 0.99
//!   and edge colour 1 keeps albedo ≥ 0.97; no configuration exceeds 1 + 2e-3;
//! - the sample context: response/pdf averages to the albedo within its error budget, its response and pdf
//!   equal the eval and pdf contexts at the drawn direction, and a χ² test over direction bins
//!   accepts the drawn directions for every lobe;
//! - degenerate inputs (μ = 0 or 1, roughness 0 and 1, ior 1, weight 0 and 1, NaN and negative
//!   parameters) never give NaN or Inf, in any context, on either engine.

use crate::common;

use common::bsdf::{bsdf, local_frame, view, Params};
use common::Rng;
use std::f64::consts::PI;
use uplift_engines::batch::{Columns, PatternBatch, PatternEngine};
use uplift_compiler::ClosureContext;


/// The lobes under test: graph, a name, and a parameter generator (weight included).
struct Lobe {
    graph: &'static str,
    name: &'static str,
    /// GGX alphas of the lobe's specular parts for the Monte Carlo sampler (empty: none).
    alpha: fn(&Params) -> Vec<f64>,
    random: fn(&mut Rng) -> Params,
}

fn c3(rng: &mut Rng, lo: f32, hi: f32) -> Vec<f32> {
    vec![rng.range(lo, hi), rng.range(lo, hi), rng.range(lo, hi)]
}

/// Isotropic roughness (α, α), α in [0.02, 1] log-uniform.
fn roughness(rng: &mut Rng) -> Vec<f32> {
    let a = (0.02f32.ln() + rng.range(0.0, 1.0) * (1.0f32.ln() - 0.02f32.ln())).exp();
    vec![a, a]
}

/// Random isotropic parameter sets per lobe in the albedo test.
const ISOTROPIC_SETS: usize = 40;

/// Anisotropic roughness (aspect ratio up to 1.5): the albedo tables are indexed by MaterialX's
/// ᾱ = √(αx αy), exact for isotropic lobes only (docs/albedo-tables.md).
const ANISOTROPIC_SETS: usize = 12;

/// Thin films: the albedo sums the Airy curve over 32 hat functions of v·h, which a thick film's
/// oscillation with angle outruns for narrow lobes (docs/albedo-tables.md); fewer sets, because
/// the Airy sum keeps LLVM from vectorising these kernels (0.08 M evals/s).
const FILM_SETS: usize = 6;

fn is_film(lobe: &Lobe) -> bool {
    lobe.name.ends_with("thin film")
}

/// Chiang hair: its albedo is a 256-direction quadrature of its eval (no table), checked on
/// fewer sets (its kernels call asin, atan2, exp and log per lane and stay scalar) for
/// longitudinal variances ≥ 0.15, which the quadrature resolves.
const HAIR_SETS: usize = 20;

/// The albedo context's own error budget, independent of this test: the largest error of any
/// albedo table in the tested domain (μ ≥ 0.02, η ≥ 1.1, sheen roughness ≥ 0.05), measured by
/// `uplift tables --errors` against brute-force integration at every grid cell's centre
/// (docs/albedo-tables.md: ggx_dielectric 3.08e-3, the largest), scaled by the lobe's weight
/// and colour (≤ 1) — so it is an absolute bound on the lobe's albedo.
const TABLE_ERROR: f64 = 3.1e-3;

/// The thin films' extra quadrature error: the Airy curve through 32 hat functions against the
/// curve itself, measured by `uplift tables --errors`-style brute force in
/// runtime/uplift/tests/integration/albedo_tables.rs as the film moments' error (≤ 8e-4 through a
/// smooth curve) — but a film up to 1,000 nm oscillates faster than the nodes under narrow
/// lobes. Bounded relative to the albedo: a quadrature of N nodes over a curve of at most
/// K = 2·thickness·film_ior/λ ≈ 5 oscillations per unit of v·h misses at most ~K/N of it.
const FILM_RELATIVE_ERROR: f64 = 0.15;

/// Anisotropic lobes read the isotropic tables at MaterialX's ᾱ = √(αx αy) (microfacet.wgsl):
/// the test asserts exactly that — the albedo of an anisotropic set equals that of the isotropic
/// set at ᾱ, whose albedo the isotropic sets check against Monte Carlo — and reports, without
/// asserting, how far that approximation lies from the Monte Carlo integral of the anisotropic
/// eval (an approximation of the model, measured in docs/albedo-tables.md, not a tolerance).
/// Standard errors of the Monte Carlo estimate allowed on top of the budgets above.
const MC_SIGMAS: f64 = 4.0;

/// (isotropic sets, anisotropic sets) of the albedo test for a lobe.
fn albedo_sets(lobe: &Lobe) -> (usize, usize) {
    if is_film(lobe) {
        (FILM_SETS, 0)
    } else if lobe.graph == "bsdf_hair" {
        (HAIR_SETS, 0)
    } else {
        (ISOTROPIC_SETS, ANISOTROPIC_SETS)
    }
}

fn alpha_of(key: &'static str) -> impl Fn(&Params) -> Vec<f64> {
    move |p| p.get(key).map(|r| ((r[0] * r[1]) as f64).sqrt()).into_iter().collect()
}

fn lobes() -> Vec<Lobe> {
    vec![
        Lobe {
            graph: "bsdf_transparent_lobes",
            name: "dielectric_bsdf",
            alpha: |p| alpha_of("d_roughness")(p),
            random: |r| Params::from([("d_weight", vec![r.range(0.3, 1.0)]), ("d_tint", c3(r, 0.2, 1.0)), ("d_ior", vec![r.range(1.1, 2.8)]), ("d_roughness", roughness(r))]),
        },
        Lobe {
            graph: "bsdf_transparent_lobes",
            name: "generalized_schlick_bsdf",
            alpha: |p| alpha_of("s_roughness")(p),
            random: |r| {
                Params::from([
                    ("s_weight", vec![r.range(0.3, 1.0)]),
                    ("s_color0", c3(r, 0.02, 0.9)),
                    ("s_color82", c3(r, 0.5, 1.0)),
                    ("s_color90", c3(r, 0.7, 1.0)),
                    ("s_exponent", vec![r.range(3.0, 7.0)]),
                    ("s_roughness", roughness(r)),
                ])
            },
        },
        Lobe {
            graph: "bsdf_transparent_lobes",
            name: "sheen_bsdf conty_kulla",
            alpha: |_| Vec::new(),
            random: |r| Params::from([("k_weight", vec![r.range(0.3, 1.0)]), ("k_color", c3(r, 0.2, 1.0)), ("k_roughness", vec![r.range(0.1, 1.0)])]),
        },
        Lobe {
            graph: "bsdf_transparent_lobes",
            name: "sheen_bsdf zeltner",
            alpha: |_| Vec::new(),
            random: |r| Params::from([("z_weight", vec![r.range(0.3, 1.0)]), ("z_color", c3(r, 0.2, 1.0)), ("z_roughness", vec![r.range(0.1, 1.0)])]),
        },
        Lobe {
            graph: "bsdf_opaque_lobes",
            name: "conductor_bsdf",
            alpha: |p| alpha_of("c_roughness")(p),
            random: |r| Params::from([("c_weight", vec![r.range(0.3, 1.0)]), ("c_ior", c3(r, 0.1, 2.5)), ("c_extinction", c3(r, 0.5, 5.0)), ("c_roughness", roughness(r))]),
        },
        Lobe {
            graph: "bsdf_opaque_lobes",
            name: "oren_nayar_diffuse_bsdf",
            alpha: |_| Vec::new(),
            random: |r| Params::from([("o_weight", vec![r.range(0.3, 1.0)]), ("o_color", c3(r, 0.2, 1.0)), ("o_roughness", vec![r.range(0.0, 1.0)])]),
        },
        Lobe {
            graph: "bsdf_opaque_lobes",
            name: "burley_diffuse_bsdf",
            alpha: |_| Vec::new(),
            random: |r| Params::from([("b_weight", vec![r.range(0.3, 1.0)]), ("b_color", c3(r, 0.2, 1.0)), ("b_roughness", vec![r.range(0.0, 1.0)])]),
        },
        Lobe {
            graph: "bsdf_opaque_lobes",
            name: "subsurface_bsdf",
            alpha: |_| Vec::new(),
            random: |r| Params::from([("u_weight", vec![r.range(0.3, 1.0)]), ("u_color", c3(r, 0.2, 1.0)), ("u_radius", c3(r, 0.01, 5.0))]),
        },
        Lobe {
            graph: "bsdf_opaque_lobes",
            name: "translucent_bsdf",
            alpha: |_| Vec::new(),
            random: |r| Params::from([("t_weight", vec![r.range(0.3, 1.0)]), ("t_color", c3(r, 0.2, 1.0))]),
        },
        Lobe {
            graph: "bsdf_thin_film",
            name: "dielectric_bsdf thin film",
            alpha: |p| alpha_of("d_roughness")(p),
            random: |r| Params::from([("d_weight", vec![r.range(0.3, 1.0)]), ("d_ior", vec![r.range(1.1, 2.8)]), ("d_roughness", roughness(r)), ("d_film_thickness", vec![r.range(50.0, 1000.0)]), ("d_film_ior", vec![r.range(1.1, 2.5)])]),
        },
        Lobe {
            graph: "bsdf_thin_film",
            name: "conductor_bsdf thin film",
            alpha: |p| alpha_of("c_roughness")(p),
            random: |r| {
                Params::from([
                    ("c_weight", vec![r.range(0.3, 1.0)]),
                    ("c_ior", c3(r, 0.1, 2.5)),
                    ("c_extinction", c3(r, 0.5, 5.0)),
                    ("c_roughness", roughness(r)),
                    ("c_film_thickness", vec![r.range(50.0, 1000.0)]),
                    ("c_film_ior", vec![r.range(1.1, 2.5)]),
                ])
            },
        },
        Lobe {
            graph: "bsdf_thin_film",
            name: "generalized_schlick_bsdf thin film",
            alpha: |p| alpha_of("s_roughness")(p),
            random: |r| {
                Params::from([
                    ("s_weight", vec![r.range(0.3, 1.0)]),
                    ("s_color0", c3(r, 0.02, 0.9)),
                    ("s_color82", c3(r, 0.5, 1.0)),
                    ("s_color90", c3(r, 0.7, 1.0)),
                    ("s_exponent", vec![r.range(3.0, 7.0)]),
                    ("s_roughness", roughness(r)),
                    ("s_film_thickness", vec![r.range(50.0, 1000.0)]),
                    ("s_film_ior", vec![r.range(1.1, 2.5)]),
                ])
            },
        },
        Lobe {
            graph: "bsdf_hair",
            name: "chiang_hair_bsdf",
            alpha: |_| Vec::new(),
            random: |r| {
                let rough = |r: &mut Rng, lo: f32| vec![r.range(lo, 1.0), r.range(0.2, 1.0)];
                Params::from([
                    ("tint_r", c3(r, 0.2, 1.0)),
                    ("tint_tt", c3(r, 0.2, 1.0)),
                    ("tint_trt", c3(r, 0.2, 1.0)),
                    ("ior", vec![r.range(1.3, 1.8)]),
                    ("roughness_r", rough(r, 0.15)),
                    ("roughness_tt", rough(r, 0.15)),
                    ("roughness_trt", rough(r, 0.15)),
                    ("cuticle_angle", vec![r.range(0.3, 0.7)]),
                    ("absorption", c3(r, 0.0, 2.0)),
                ])
            },
        },
        Lobe {
            graph: "bsdf_stack",
            name: "layered stack (layer, mix, artistic_ior, sheen, dielectric, conductor, oren_nayar)",
            alpha: |p| ["core_roughness", "haze_roughness", "coat_roughness"].iter().flat_map(|k| alpha_of(k)(p)).collect(),
            random: random_stack,
        },
    ]
}

fn random_stack(r: &mut Rng) -> Params {
    let core = roughness(r);
    let scale = r.range(2.0, 8.0);
    let haze: Vec<f32> = core.iter().map(|a| (a * scale).min(1.0)).collect();
    Params::from([
        ("sheen_weight", vec![r.range(0.0, 1.0)]),
        ("sheen_color", c3(r, 0.3, 1.0)),
        ("sheen_roughness", vec![r.range(0.1, 1.0)]),
        ("coat_weight", vec![r.range(0.0, 1.0)]),
        ("coat_ior", vec![r.range(1.2, 2.0)]),
        ("coat_roughness", vec![0.05, 0.05]),
        ("metalness", vec![r.range(0.0, 1.0)]),
        ("reflectivity", c3(r, 0.2, 0.99)),
        ("edge_color", c3(r, 0.5, 1.0)),
        ("core_roughness", core),
        ("haze_roughness", haze),
        ("haze_weight", vec![r.range(0.0, 1.0)]),
        ("specular_ior", vec![r.range(1.2, 2.5)]),
        ("specular_tint", c3(r, 0.5, 1.0)),
        ("base_color", c3(r, 0.0, 1.0)),
        ("base_roughness", vec![r.range(0.0, 1.0)]),
    ])
}

/// The mean of `y` over `m` samples, one per stratum with neighbouring strata at 2q and 2q + 1,
/// and an upper bound on its standard error: the variance of the mean is at most Σ over the
/// disjoint pairs of (y_2q − y_2q+1)², over m² (E(y_a − y_b)² = Var_a + Var_b + (μ_a − μ_b)² ≥
/// Var_a + Var_b).
fn stratified_mean(m: usize, y: impl Fn(usize) -> f64) -> (f64, f64) {
    let mean = (0..m).map(&y).sum::<f64>() / m as f64;
    let pairs: f64 = (0..m / 2).map(|q| (y(2 * q) - y(2 * q + 1)).powi(2)).sum();
    (mean, pairs.sqrt() / m as f64)
}

const VIEWS: [f64; 8] = [0.02, 0.1, 0.25, 0.4, 0.55, 0.7, 0.85, 1.0];

/// GGX normal sample (distribution of normals × cos θh), isotropic alpha.
fn ggx_half(a: f64, u1: f64, u2: f64) -> [f64; 3] {
    let t2 = a * a * u1 / (1.0 - u1).max(1e-12);
    let ct = 1.0 / (1.0 + t2).sqrt();
    let st = (1.0 - ct * ct).max(0.0).sqrt();
    let phi = 2.0 * PI * u2;
    [st * phi.cos(), st * phi.sin(), ct]
}

fn ggx_d(h: [f64; 3], a: f64) -> f64 {
    let a2 = a * a;
    let t = h[2] * h[2] * (a2 - 1.0) + 1.0;
    a2 / (PI * t * t)
}

/// The brute-force sampler: a stratified mixture of three distributions — cosine-weighted,
/// uniform over the hemisphere (dense near the horizon, where grazing sheen lobes live), and,
/// for GGX lobes, the distribution of normals (D cos θh); returns directions and mixture pdfs.
fn mc_directions(v: [f32; 3], alphas: &[f64], side: usize, rng: &mut Rng) -> (Vec<[f32; 3]>, Vec<f64>) {
    let v = [v[0] as f64, v[1] as f64, v[2] as f64];
    let mut dirs = Vec::with_capacity(side * side);
    let mut pdfs = Vec::with_capacity(side * side);
    // Shares of the strata: GGX, uniform, cosine.
    let (ggx, uniform) = if alphas.is_empty() { (0.0, 0.5) } else { (0.5, 0.15) };
    let each = ggx / alphas.len().max(1) as f64;
    for i in 0..side {
        for j in 0..side {
            let u1 = (i as f64 + rng.range(0.0, 1.0) as f64) / side as f64;
            let u2 = (j as f64 + rng.range(0.0, 1.0) as f64) / side as f64;
            let phi = 2.0 * PI * u2;
            let l = if u1 < ggx {
                let k = ((u1 / each) as usize).min(alphas.len() - 1);
                let h = ggx_half(alphas[k], (u1 - k as f64 * each) / each, u2);
                let c = 2.0 * (v[0] * h[0] + v[1] * h[1] + v[2] * h[2]);
                [c * h[0] - v[0], c * h[1] - v[1], c * h[2] - v[2]]
            } else if u1 < ggx + uniform {
                let z = (u1 - ggx) / uniform;
                let s = (1.0 - z * z).max(0.0).sqrt();
                [s * phi.cos(), s * phi.sin(), z]
            } else {
                let uu = (u1 - ggx - uniform) / (1.0 - ggx - uniform);
                let r = uu.sqrt();
                [r * phi.cos(), r * phi.sin(), (1.0 - uu).max(0.0).sqrt()]
            };
            let mut pdf = if l[2] > 0.0 { (1.0 - ggx - uniform) * l[2] / PI + uniform / (2.0 * PI) } else { 0.0 };
            for &a in alphas {
                let h = [v[0] + l[0], v[1] + l[1], v[2] + l[2]];
                let n = (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]).sqrt();
                if n > 1e-12 {
                    let h = [h[0] / n, h[1] / n, h[2] / n];
                    let vh = v[0] * h[0] + v[1] * h[1] + v[2] * h[2];
                    if h[2] > 0.0 && vh > 0.0 {
                        pdf += each * ggx_d(h, a) * h[2] / (4.0 * vh);
                    }
                }
            }
            dirs.push([l[0] as f32, l[1] as f32, l[2] as f32]);
            pdfs.push(pdf);
        }
    }
    (dirs, pdfs)
}

/// Albedo (albedo context) vs Monte Carlo of eval for random parameter sets × 8 views per lobe:
/// |albedo − MC| ≤ the albedo's own error budget (TABLE_ERROR; relative terms for films and
/// anisotropic roughness) + MC_SIGMAS standard errors of the estimate, which the test measures
/// from its own samples.
#[test]
fn albedo_matches_monte_carlo_integral_of_eval() {
    const SIDE: usize = 128; // 16,384 stratified directions per view
    let mut report = Vec::new();
    let mut checked = 0usize;
    for (li, lobe) in lobes().iter().enumerate() {
        let eval = bsdf(lobe.graph, ClosureContext::Eval);
        let albedo = bsdf(lobe.graph, ClosureContext::Albedo);
        let mut rng = Rng::new(0xa1bed0 ^ li as u64);
        // Worst (|albedo − MC| / bound, |albedo − MC|, relative error, where) per kind of set.
        let mut worst = [(0.0f64, 0.0f64, 0.0f64, String::new()), (0.0, 0.0, 0.0, String::new())];
        let (sets, anisotropic_sets) = albedo_sets(lobe);
        for set in 0..sets + anisotropic_sets {
            let mut p = (lobe.random)(&mut rng);
            if set >= sets {
                // Anisotropic roughness: the tables read one roughness (see microfacet.wgsl).
                for v in p.values_mut().filter(|v| v.len() == 2) {
                    v[1] = v[0] / rng.range(1.0, 1.5);
                }
            }
            // (Hair's vector2 roughnesses are two variances, not an anisotropic pair.)
            let anisotropic = lobe.graph != "bsdf_hair" && p.values().any(|v| v.len() == 2 && v[0] != v[1]);
            let alpha = (lobe.alpha)(&p);
            // One batch: every view's directions.
            let mut wv = Vec::new();
            let mut wl = Vec::new();
            let mut pdfs = Vec::new();
            for &mu in &VIEWS {
                let (d, pdf) = mc_directions(view(mu), &alpha, SIDE, &mut rng);
                wv.extend(std::iter::repeat_n(view(mu), d.len()));
                wl.extend(d);
                pdfs.extend(pdf);
            }
            let n = wv.len();
            let out = eval.run(&[wv, wl], &[(0..n, &p)]);
            let views: Vec<[f32; 3]> = VIEWS.iter().map(|&m| view(m)).collect();
            let a_out = albedo.run(&[views.clone()], &[(0..VIEWS.len(), &p)]);
            // An anisotropic set's albedo is that of the isotropic set at ᾱ = √(αx αy).
            if anisotropic {
                let mut q = p.clone();
                for v in q.values_mut().filter(|v| v.len() == 2) {
                    let a = (v[0] * v[1]).sqrt();
                    *v = vec![a, a];
                }
                let iso = albedo.run(&[views.clone()], &[(0..VIEWS.len(), &q)]);
                for c in 0..3 {
                    for (k, (a, b)) in albedo.column(&a_out, "albedo", c).iter().zip(albedo.column(&iso, "albedo", c)).enumerate() {
                        assert!((a - b).abs() <= 1e-5 * b.abs().max(1.0), "{}: set {set} μ {} channel {c}: anisotropic albedo {a} ≠ {b} at ᾱ (params {p:?})", lobe.name, VIEWS[k]);
                    }
                }
            }
            for c in 0..3 {
                let resp = eval.column(&out, "response", c);
                let alb = albedo.column(&a_out, "albedo", c);
                for (k, &mu) in VIEWS.iter().enumerate() {
                    let m = SIDE * SIDE;
                    let (mc, sigma) = stratified_mean(m, |j| if pdfs[k * m + j] > 0.0 { resp[k * m + j] as f64 / pdfs[k * m + j] } else { 0.0 });
                    let a = alb[k] as f64;
                    let err = (a - mc).abs();
                    let approximation = if is_film(lobe) { FILM_RELATIVE_ERROR * mc.abs() } else { 0.0 };
                    let bound = TABLE_ERROR + approximation + MC_SIGMAS * sigma;
                    assert!(
                        anisotropic || err <= bound,
                        "{}: set {set} μ {mu} channel {c}: albedo {a:.5} vs Monte Carlo {mc:.5} ± {sigma:.1e}: |error| {err:.2e} > bound {bound:.2e} (params {p:?})",
                        lobe.name
                    );
                    checked += 1;
                    let w = &mut worst[anisotropic as usize];
                    if err / bound > w.0 {
                        *w = (err / bound, err, err / mc.abs().max(1e-6), format!("set {set} μ {mu} channel {c} (albedo {a:.4}, σ {sigma:.1e})"));
                    }
                }
            }
        }
        for (w, kind) in worst.iter().zip(["isotropic", "anisotropic (not asserted)"]) {
            if !w.3.is_empty() {
                report.push(format!("{} ({kind}): worst |albedo − MC| at {:.0} % of the isotropic bound: {:.2e} ({:.1} % relative) at {}", lobe.name, w.0 * 100.0, w.1, w.2 * 100.0, w.3));
            }
        }
    }
    eprintln!("{}", report.join("\n"));
    assert!(checked > 10_000, "only {checked} comparisons");
}

/// White furnace and energy bounds on the stack and on single transmitting lobes.
#[test]
fn white_furnace_and_energy_bounds() {
    let stack = bsdf("bsdf_stack", ClosureContext::Albedo);
    let views: Vec<[f32; 3]> = (0..64).map(|k| view(0.005 + 0.995 * k as f64 / 63.0)).collect();
    let mut rng = Rng::new(0xf0_4ace);
    let mut worst = 0.0f64;
    for _ in 0..200 {
        // White, non-absorbing: white sheen and tints, dielectric only, white Lambert base.
        let mut p = random_stack(&mut rng);
        for key in ["sheen_color", "specular_tint", "base_color"] {
            p.insert(key, vec![1.0, 1.0, 1.0]);
        }
        p.insert("metalness", vec![0.0]);
        p.insert("base_roughness", vec![0.0]);
        let out = stack.run(&[views.clone()], &[(0..views.len(), &p)]);
        for c in 0..3 {
            let a = stack.column(&out, "albedo", c);
            let t = stack.column(&out, "throughput", c);
            for k in 0..views.len() {
                let e = (a[k] + t[k] - 1.0).abs() as f64;
                worst = worst.max(e);
                assert!(e <= 2e-3, "white stack: μ {} albedo {} + throughput {} ≠ 1 ({p:?})", views[k][2], a[k], t[k]);
            }
        }
    }
    eprintln!("white stack: worst |albedo + throughput − 1| = {worst:.2e}");
    // Each transmitting lobe alone, white: albedo + throughput = 1.
    let lobes = bsdf("bsdf_transparent_lobes", ClosureContext::Albedo);
    let mut worst = 0.0f64;
    for which in 0..4 {
        for _ in 0..50 {
            let r = roughness(&mut rng);
            let w = rng.range(0.0, 1.0);
            let p: Params = match which {
                0 => Params::from([("d_weight", vec![w]), ("d_ior", vec![rng.range(1.05, 3.0)]), ("d_roughness", r)]),
                1 => Params::from([("s_weight", vec![w]), ("s_color0", vec![0.04; 3]), ("s_roughness", r)]),
                2 => Params::from([("k_weight", vec![w]), ("k_roughness", vec![rng.range(0.1, 1.0)])]),
                _ => Params::from([("z_weight", vec![w]), ("z_roughness", vec![rng.range(0.0, 1.0)])]),
            };
            let out = lobes.run(&[views.clone()], &[(0..views.len(), &p)]);
            for c in 0..3 {
                let a = lobes.column(&out, "albedo", c);
                let t = lobes.column(&out, "throughput", c);
                for k in 0..views.len() {
                    let e = (a[k] + t[k] - 1.0).abs() as f64;
                    worst = worst.max(e);
                    assert!(e <= 2e-3, "white lobe {which}: μ {} albedo {} + throughput {} ≠ 1 ({p:?})", views[k][2], a[k], t[k]);
                }
            }
        }
    }
    eprintln!("white single lobes: worst |albedo + throughput − 1| = {worst:.2e}");
    // A near-white conductor keeps its energy at every roughness.
    let mut lowest = f32::MAX;
    for k in 0..=40 {
        let a = 10f32.powf(-3.0 + 3.0 * k as f32 / 40.0);
        let p = Params::from([
            ("sheen_weight", vec![0.0]),
            ("coat_weight", vec![0.0]),
            ("metalness", vec![1.0]),
            ("reflectivity", vec![0.99; 3]),
            ("edge_color", vec![1.0; 3]),
            ("core_roughness", vec![a, a]),
            ("haze_roughness", vec![a, a]),
        ]);
        let out = stack.run(&[views.clone()], &[(0..views.len(), &p)]);
        for c in 0..3 {
            for (j, v) in stack.column(&out, "albedo", c).iter().enumerate() {
                lowest = lowest.min(*v);
                assert!(*v >= 0.97, "conductor reflectivity 0.99, α {a}, μ {}: albedo {v}", views[j][2]);
            }
        }
    }
    eprintln!("conductor reflectivity 0.99: lowest albedo {lowest:.4}");
    // Nothing exceeds 1 for colours ≤ 1.
    let mut highest = 0.0f32;
    for _ in 0..400 {
        let p = random_stack(&mut rng);
        let out = stack.run(&[views.clone()], &[(0..views.len(), &p)]);
        for c in 0..3 {
            for v in stack.column(&out, "albedo", c) {
                highest = highest.max(v);
                assert!(v <= 1.0 + 2e-3, "albedo {v} > 1 ({p:?})");
            }
        }
    }
    eprintln!("random stacks: highest albedo {highest:.4}");
}

/// The sample context against the albedo, eval and pdf contexts, and a χ² test of its
/// directions against its pdf, for every lobe and the stack.
#[test]
fn sampling_is_consistent_with_pdf_eval_and_albedo() {
    const N: usize = 1 << 16;
    const THETA_BINS: usize = 16;
    const PHI_BINS: usize = 32;
    for (li, lobe) in lobes().iter().enumerate() {
        let sample = bsdf(lobe.graph, ClosureContext::Sample);
        let pdf_k = bsdf(lobe.graph, ClosureContext::Pdf);
        let eval = bsdf(lobe.graph, ClosureContext::Eval);
        let albedo = bsdf(lobe.graph, ClosureContext::Albedo);
        let mut rng = Rng::new(0x5a_e1e ^ li as u64);
        for set in 0..if is_film(lobe) || lobe.graph == "bsdf_hair" { 1 } else { 4 } {
            let p = (lobe.random)(&mut rng);
            let mu = [0.15, 0.5, 0.8, 1.0][set];
            let v = view(mu);
            // Stratified u (256 × 256 grid in u.xy), u.z uniform.
            let side = 256;
            let u: Vec<[f32; 3]> = (0..N)
                .map(|k| {
                    let (i, j) = (k % side, k / side);
                    [(i as f32 + rng.range(0.0, 1.0)) / side as f32, (j as f32 + rng.range(0.0, 1.0)) / (N / side) as f32, rng.range(0.0, 1.0)]
                })
                .collect();
            let out = sample.run(&[vec![v; N], u], &[(0..N, &p)]);
            let wl: Vec<[f32; 3]> = (0..N).map(|k| [0, 1, 2].map(|c| out.column(sample.kernel.outputs[0].offset + c)[k])).collect();
            let pdf = sample.column(&out, "pdf", 0);
            let alb = albedo.run(&[vec![v]], &[(0..1, &p)]);
            // Estimator response/pdf vs the albedo: within the albedo's own error budget (the
            // albedo test's TABLE_ERROR, with FILM_RELATIVE_ERROR for films) plus MC_SIGMAS
            // standard errors (from pairs of neighbouring strata, as in the albedo test).
            for c in 0..3 {
                let resp = sample.column(&out, "response", c);
                let (est, sigma) = stratified_mean(N, |k| if pdf[k] > 0.0 { resp[k] as f64 / pdf[k] as f64 } else { 0.0 });
                let a = albedo.column(&alb, "albedo", c)[0] as f64;
                let bound = TABLE_ERROR + if is_film(lobe) { FILM_RELATIVE_ERROR * a } else { 0.0 } + MC_SIGMAS * sigma;
                assert!((est - a).abs() <= bound, "{} set {set} μ {mu} channel {c}: E[response/pdf] {est:.4} ± {sigma:.1e} vs albedo {a:.4}: beyond {bound:.1e} ({p:?})", lobe.name);
            }
            // Response and pdf at the drawn directions agree with the eval and pdf contexts.
            let check = 4096;
            let e = eval.run(&[vec![v; check], wl[..check].to_vec()], &[(0..check, &p)]);
            let q = pdf_k.run(&[vec![v; check], wl[..check].to_vec()], &[(0..check, &p)]);
            for k in 0..check {
                let r0 = sample.column(&out, "response", 0)[k];
                let r1 = eval.column(&e, "response", 0)[k];
                assert!((r0 - r1).abs() <= 1e-4 * r0.abs().max(1.0), "{}: sample response {r0} vs eval {r1}", lobe.name);
                let p1 = pdf_k.column(&q, "pdf", 0)[k];
                assert!((pdf[k] - p1).abs() <= 1e-4 * pdf[k].abs().max(1.0), "{}: sample pdf {} vs pdf context {p1}", lobe.name, pdf[k]);
            }
            // χ² over (cos θ ∈ [−1, 1], φ) bins; expected counts integrate the pdf context.
            let bin = |d: &[f32; 3]| {
                let t = (((d[2] as f64 + 1.0) * 0.5 * THETA_BINS as f64) as usize).min(THETA_BINS - 1);
                let phi = (d[1] as f64).atan2(d[0] as f64).rem_euclid(2.0 * PI);
                let f = ((phi / (2.0 * PI) * PHI_BINS as f64) as usize).min(PHI_BINS - 1);
                t * PHI_BINS + f
            };
            let mut observed = vec![0.0f64; THETA_BINS * PHI_BINS];
            for (k, d) in wl.iter().enumerate() {
                if pdf[k] > 0.0 {
                    observed[bin(d)] += 1.0;
                }
            }
            // Expected counts: the pdf context integrated over sub-cells, 16 per bin along φ and
            // along z = z_hi − Δz·s², s uniform (cells shrink towards each bin's upper edge, so
            // that the pole, where a narrow lobe at normal view sits within 0.05 rad, is
            // resolved: a uniform grid in z puts the first midpoint at 0.07 rad).
            let sub = 16;
            let (nt, np) = (THETA_BINS * sub, PHI_BINS * sub);
            let dz = 2.0 / THETA_BINS as f64;
            let mut dirs: Vec<[f32; 3]> = Vec::with_capacity(nt * np);
            let mut cells: Vec<f64> = Vec::with_capacity(nt * np);
            for k in 0..nt * np {
                let (t, f) = (k / np, k % np);
                let (tb, s) = (t / sub, ((t % sub) as f64 + 0.5) / sub as f64);
                let z_hi = -1.0 + dz * (tb + 1) as f64;
                let z = z_hi - dz * s * s;
                let phi = 2.0 * PI * (f as f64 + 0.5) / np as f64;
                let r = (1.0 - z * z).max(0.0).sqrt();
                dirs.push([(r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32]);
                cells.push(dz * 2.0 * s / sub as f64 * 2.0 * PI / np as f64);
            }
            let q = pdf_k.run(&[vec![v; dirs.len()], dirs.clone()], &[(0..dirs.len(), &p)]);
            let qpdf = pdf_k.column(&q, "pdf", 0);
            let mut expected = vec![0.0f64; THETA_BINS * PHI_BINS];
            for (k, d) in dirs.iter().enumerate() {
                expected[bin(d)] += qpdf[k] as f64 * cells[k] * N as f64;
            }
            // Pool bins with small expectations (χ² needs ≥ 5 per cell).
            let (chi2, df) = common::chi2::pooled(&observed, &expected, 0..expected.len());
            let pv = common::chi2::p_value(chi2, (df.max(2) - 1) as f64);
            eprintln!("{} set {set} μ {mu}: χ² {chi2:.1} over {df} cells, p = {pv:.3}", lobe.name);
            assert!(pv > 1e-4, "{} set {set} μ {mu}: χ² {chi2:.1} with {df} cells, p = {pv:.2e} ({p:?})", lobe.name);
        }
    }
}

/// Degenerate inputs never give NaN or Inf, in any context, on both engines.
#[test]
fn degenerate_inputs_stay_finite() {
    let gpu = common::engine();
    let specials = [0.0f32, 1.0, -1.0, f32::NAN, 1e-9, 1e9];
    let views = [[0.0f32, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.6, 0.0, -0.8], [f32::NAN, 0.0, 1.0]];
    for graph in ["bsdf_transparent_lobes", "bsdf_opaque_lobes", "bsdf_thin_film", "bsdf_hair", "bsdf_stack", "bsdf_conductor", "uplift_stack"] {
        for context in ClosureContext::ALL {
            let b = bsdf(graph, context);
            // Every input takes every special value in turn, the others their defaults or 1.
            let mut wv = Vec::new();
            let mut second = Vec::new();
            let mut sets: Vec<Params> = Vec::new();
            for inp in &b.kernel.inputs {
                if context.direction_inputs().contains(&inp.input.name.as_str()) {
                    continue;
                }
                for &s in &specials {
                    let mut p = Params::new();
                    let name: &'static str = Box::leak(inp.input.name.clone().into_boxed_str());
                    p.insert(name, vec![s; inp.input.ty.components().unwrap()]);
                    sets.push(p);
                }
            }
            sets.push(Params::new());
            let per = views.len() * views.len();
            let mut ranges = Vec::new();
            for (k, _) in sets.iter().enumerate() {
                for a in &views {
                    for l in &views {
                        wv.push(*a);
                        second.push(if context == ClosureContext::Sample { [0.5, 0.999999, 0.0] } else { *l });
                    }
                }
                ranges.push(k * per..(k + 1) * per);
            }
            let params: Vec<(std::ops::Range<usize>, &Params)> = ranges.into_iter().zip(sets.iter()).collect();
            let cpu_out = b.run(&[wv.clone(), second.clone()], &params);
            if let Some(k) = cpu_out.data().iter().position(|x| !x.is_finite()) {
                let point = k % wv.len();
                let set = params.iter().find(|(r, _)| r.contains(&point)).unwrap().1;
                panic!("{graph} {}: CPU gives {} for {set:?}, wv {:?}, second direction {:?}", context.name(), cpu_out.data()[k], wv[point], second[point]);
            }
            // The same batch on wgpu.
            let mut inputs = Columns::zeros(wv.len(), b.kernel.input_stride);
            for (k, src) in [&wv, &second].iter().enumerate().take(context.direction_inputs().len()) {
                for c in 0..3 {
                    inputs.column_mut(b.kernel.inputs[k].offset + c).iter_mut().zip(src.iter()).for_each(|(x, v)| *x = v[c]);
                }
            }
            for inp in b.kernel.inputs.iter().skip(context.direction_inputs().len()) {
                for c in 0..inp.input.ty.components().unwrap() {
                    let col = inputs.column_mut(inp.offset + c);
                    for (range, p) in &params {
                        col[range.clone()].fill(p.get(inp.input.name.as_str()).map_or(inp.input.default[c], |v| v[c]));
                    }
                }
            }
            let batch = PatternBatch { geometry: local_frame(wv.len()), inputs, textures: vec![], points_per_group: 1 };
            let gpu_out = gpu.run_pattern(&b.kernel, &batch).unwrap();
            assert!(gpu_out.data().iter().all(|x| x.is_finite()), "{graph} {}: wgpu gives NaN or Inf", context.name());
        }
    }
}

