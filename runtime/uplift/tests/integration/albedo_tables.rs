//! The albedo tables (docs/albedo-tables.md): regenerating them gives the checked-in file byte
//! for byte, and at random points (not grid nodes) every table matches brute-force integration
//! within its documented error.

use crate::common;

use common::Rng;
use uplift_kernels::albedo_tables::reference::fresnel_conductor;
use uplift_kernels::albedo_tables::{integrate_ggx, DiffuseTable, Tables};

const CHECKED_IN: &str = include_str!("../../../../mtlx/libraries/pbrlib/wgsl/albedo_tables.wgsl");

#[test]
fn regeneration_is_byte_identical_and_tables_match_brute_force() {
    let tables = Tables::compute(&|_| {});
    let text = tables.to_wgsl();
    assert!(text == CHECKED_IN, "`uplift tables` output differs from mtlx/libraries/pbrlib/wgsl/albedo_tables.wgsl (regenerate with `uplift tables -o mtlx/libraries/pbrlib/wgsl`)");
    // The file is read once per process (the library) and compiled into one Rust static.
    assert!(text.len() <= 5 << 18, "tables exceed 1.25 MiB");

    // Documented maximum errors in the tested domain (docs/albedo-tables.md), rounded up.
    // sup over v·h ∈ [0, 1] of |I·F − F| for the gold curve through each node set.
    let gold = |c: f64| fresnel_conductor(c, 0.183, 3.424);
    let interpolation_error = |hats: fn(f64) -> [(usize, f64); 2], node: fn(usize) -> f64| {
        (0..=100_000).map(|i| i as f64 / 100_000.0).map(|c| (hats(c).iter().map(|&(m, w)| w * gold(node(m))).sum::<f64>() - gold(c)).abs()).fold(0.0, f64::max)
    };
    let sup_moments = interpolation_error(uplift_kernels::albedo_tables::fresnel_hats, uplift_kernels::albedo_tables::fresnel_node);
    let sup_film = interpolation_error(uplift_kernels::albedo_tables::film_fresnel_hats, uplift_kernels::albedo_tables::film_fresnel_node);
    let mut rng = Rng::new(0x7ab1e5);
    let mut worst = [0.0f64; 8];
    let mut quadrature = [0.0f64; 2];
    for _ in 0..60 {
        let mu = rng.range(0.02, 1.0) as f64;
        let alpha = (rng.range(0.001f32.ln(), 0.0)).exp() as f64;
        let eta = rng.range(1.1, 3.0) as f64;
        let exact = integrate_ggx(mu, alpha, 1 << 15);
        let e = (tables.ess(mu, alpha) - exact.ess).abs();
        worst[0] = worst[0].max(e);
        assert!(e <= 2.5e-3, "ggx_ess at μ {mu} α {alpha}: {} vs {}", tables.ess(mu, alpha), exact.ess);
        // Moments through a conductor curve (gold, red), checked in two independent halves:
        // (1) the table interpolates the moments: the table's Σ W_j F(c_j) against the same sum
        //     over moments integrated at this very point (`brute`), within the documented
        //     interpolation error (docs/albedo-tables.md: 1.80e-3 for ggx_moments), rounded up;
        // (2) the moments represent the curve: `brute` integrates the piecewise-linear
        //     interpolant I·F of the curve through the nodes with the same samples (and weights
        //     w ≥ 0) that `direct` uses for F itself, so |brute − direct| ≤ sup |I·F − F| · E_ss,
        //     with the sup taken on a fine grid above (`interpolation_error`).
        let direct = uplift_kernels::albedo_tables::errors::conductor_albedo(mu, alpha, 0.183, 3.424, 1 << 15);
        let brute: f64 = exact.moments.iter().enumerate().map(|(j, w)| w * gold(uplift_kernels::albedo_tables::fresnel_node(j))).sum();
        let e = (tables.with_fresnel(mu, alpha, gold) - brute).abs();
        worst[1] = worst[1].max(e);
        assert!(e <= 2.5e-3, "ggx_moments (gold) at μ {mu} α {alpha}: table {} vs the moments at this point {brute}", tables.with_fresnel(mu, alpha, gold));
        let q = (brute - direct).abs();
        quadrature[0] = quadrature[0].max(q);
        assert!(q <= sup_moments * exact.ess + 1e-9, "ggx_moments (gold) at μ {mu} α {alpha}: Σ W_j F(c_j) {brute} vs the integral with the true curve {direct}");
        // The thin-film moments through the same curve.
        let brute: f64 = exact.film_moments.iter().enumerate().map(|(j, w)| w * gold(uplift_kernels::albedo_tables::film_fresnel_node(j))).sum();
        let e = (tables.with_film_fresnel(mu, alpha, gold) - brute).abs();
        worst[6] = worst[6].max(e);
        assert!(e <= 2.5e-3, "ggx_film_moments (gold) at μ {mu} α {alpha}: table {} vs the moments at this point {brute}", tables.with_film_fresnel(mu, alpha, gold));
        let q = (brute - direct).abs();
        quadrature[1] = quadrature[1].max(q);
        assert!(q <= sup_film * exact.ess + 1e-9, "ggx_film_moments (gold) at μ {mu} α {alpha}: Σ W_j F(c_j) {brute} vs the integral with the true curve {direct}");
        let d = uplift_kernels::albedo_tables::errors::dielectric_albedo(mu, alpha, eta, 1 << 15);
        let e = (tables.dielectric(mu, alpha, eta) - d).abs();
        worst[2] = worst[2].max(e);
        assert!(e <= 4e-3, "ggx_dielectric at μ {mu} α {alpha} η {eta}: {} vs {d}", tables.dielectric(mu, alpha, eta));
    }
    // Inside (η < 1): total internal reflection makes the albedo of a smooth lobe a step in μ at
    // the critical cosine √(1 − η²), which no interpolation on a regular grid resolves (next to
    // the step a point errs by up to its height): bounded pointwise where roughness smooths the
    // step (docs/albedo-tables.md: 0.091 from ᾱ ≥ 0.2 at cell centres), and on average
    // everywhere — below the former method's mean error at the same points (the Fresnel-moment
    // sum over the moments table, which smears the step over the Fresnel nodes).
    let (mut inside_sum, mut moments_sum) = (0.0, 0.0);
    const INSIDE_POINTS: usize = 400;
    for _ in 0..INSIDE_POINTS {
        let mu = rng.range(0.02, 1.0) as f64;
        let alpha = (rng.range(0.001f32.ln(), 0.0)).exp() as f64;
        let eta = 1.0 / rng.range(1.1, 3.0) as f64;
        let d = uplift_kernels::albedo_tables::errors::dielectric_albedo(mu, alpha, eta, 1 << 14);
        let e = (tables.dielectric(mu, alpha, eta) - d).abs();
        worst[7] = worst[7].max(e);
        inside_sum += e;
        moments_sum += (tables.with_fresnel(mu, alpha, |c| uplift_kernels::albedo_tables::reference::fresnel_dielectric(c, eta)) - d).abs();
        assert!(alpha < 0.2 || e <= 0.1, "ggx_dielectric_inside at μ {mu} α {alpha} η {eta}: {} vs {d}", tables.dielectric(mu, alpha, eta));
    }
    let (inside_mean, moments_mean) = (inside_sum / INSIDE_POINTS as f64, moments_sum / INSIDE_POINTS as f64);
    assert!(inside_mean < moments_mean && inside_mean <= 2.5e-2, "ggx_dielectric_inside: mean error {inside_mean:.2e} at random points (the Fresnel moments: {moments_mean:.2e})");
    for (k, which) in DiffuseTable::ALL.into_iter().enumerate() {
        let bound = match which {
            DiffuseTable::SheenContyKulla => 3e-3,
            DiffuseTable::OrenNayar => 1e-3,
            DiffuseTable::Burley => 3.5e-3,
        };
        for _ in 0..60 {
            let mu = rng.range(0.02, 1.0) as f64;
            let r = rng.range(0.05, 1.0) as f64;
            let exact = which.integrate(mu, r, 1 << 16);
            let e = (tables.diffuse(which, mu, r) - exact).abs();
            worst[3 + k] = worst[3 + k].max(e);
            assert!(e <= bound, "{} at μ {mu} r {r}: {} vs {exact}", which.name(), tables.diffuse(which, mu, r));
        }
    }
    eprintln!("worst errors at random points: ess {:.1e}, moments {:.1e}, film moments {:.1e}, dielectric {:.1e} (inside {:.1e}, mean {:.1e} against {:.1e} through the moments), sheen {:.1e}, oren_nayar {:.1e}, burley {:.1e}; the moments' quadrature of the gold curve {:.1e} (films {:.1e})", worst[0], worst[1], worst[6], worst[2], worst[7], inside_mean, moments_mean, worst[3], worst[4], worst[5], quadrature[0], quadrature[1]);
    eprintln!("sup |I·F − F| of the gold curve: {sup_moments:.1e} over the 16 squared nodes, {sup_film:.1e} over the 32 film nodes");
}

/// The kernels read the inside table for η < 1: the shipped dielectric_bsdf albedo kernel (a
/// white lobe of weight 1, so albedo = compensation · E) against the f64 lookup of the same
/// table (`Tables::dielectric`, the checked-in values, see above) with E_ss from `Tables::ess`.
#[test]
fn dielectric_albedo_below_ior_1_reads_the_inside_table() {
    use common::bsdf::{bsdf, view, Params};
    use uplift_compiler::ClosureContext;
    let tables = tables_from_checked_in_file();
    let albedo = bsdf("bsdf_transparent_lobes", ClosureContext::Albedo);
    let mut rng = Rng::new(0x1e5a);
    let mut worst = 0.0f64;
    for _ in 0..40 {
        let eta = rng.range(0.34, 0.99);
        let a = (rng.range(0.02f32.ln(), 0.0)).exp();
        let p = Params::from([("d_weight", vec![1.0]), ("d_ior", vec![eta]), ("d_roughness", vec![a, a])]);
        let mus = [0.02f64, 0.1, 0.3, 0.5, 0.7, 0.9, 1.0];
        let views: Vec<[f32; 3]> = mus.iter().map(|&m| view(m)).collect();
        let out = albedo.run(&[views], &[(0..mus.len(), &p)]);
        for (k, &mu) in mus.iter().enumerate() {
            let (alpha, eta) = (a as f64, eta as f64);
            let f1 = uplift_kernels::albedo_tables::reference::fresnel_dielectric(1.0, eta);
            let favg = f1 + (1.0 - f1) / 21.0;
            let ess = tables.ess(mu, alpha).max(1e-4);
            let want = (1.0 + favg * (1.0 - ess) / ess) * tables.dielectric(mu, alpha, eta);
            let got = albedo.column(&out, "albedo", 0)[k] as f64;
            worst = worst.max((got - want).abs());
            assert!((got - want).abs() <= 2e-4 * want.max(1.0), "η {eta} α {alpha} μ {mu}: kernel albedo {got} vs the inside table {want}");
        }
    }
    eprintln!("dielectric albedo below IOR 1: worst |kernel − f64 lookup| {worst:.1e}");
}

/// The tables as the checked-in file holds them (computing them takes a minute).
fn tables_from_checked_in_file() -> Tables {
    Tables::from_wgsl(CHECKED_IN).expect("the checked-in albedo tables parse")
}
