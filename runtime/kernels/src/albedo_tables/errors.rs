//! Measures each table's error: brute-force integration (a fresh point set, 4× the table's
//! samples) at the centre of every grid cell, where interpolation error peaks, against the
//! table's own interpolation. The report is docs/albedo-tables.md's error column.

use super::*;

/// Largest and mean absolute error of one table.
#[derive(Clone, Copy, Debug, Default)]
pub struct TableError {
    pub max: f64,
    pub mean: f64,
    /// Where the largest error sits: (μ, second axis, third axis or 0).
    pub worst_at: (f64, f64, f64),
}

/// The view angles the closure tests cover (μ ≥ 0.02); the error report gives both ranges.
pub const TESTED_MU: f64 = 0.02;

/// One measured cell: error and where (μ, axis 2, axis 3).
pub type CellError = (f64, (f64, f64, f64));

/// Summary over the cells with μ ≥ `mu_floor`.
pub fn summarize(errs: &[CellError], mu_floor: f64) -> TableError {
    let mut e = TableError::default();
    let errs: Vec<&CellError> = errs.iter().filter(|(_, at)| at.0 >= mu_floor).collect();
    for (x, at) in errs.iter().copied() {
        if *x > e.max {
            e.max = *x;
            e.worst_at = *at;
        }
        e.mean += x;
    }
    e.mean /= errs.len().max(1) as f64;
    e
}

/// Brute-force GGX albedo for a conductor (one channel) with `n` Hammersley points.
pub fn conductor_albedo(mu: f64, alpha: f64, n_ior: f64, k: f64, n: u32) -> f64 {
    ggx_with(mu, alpha, n, |c| fresnel_conductor(c, n_ior, k))
}

/// Brute-force GGX albedo for a dielectric with `n` Hammersley points.
pub fn dielectric_albedo(mu: f64, alpha: f64, eta: f64, n: u32) -> f64 {
    ggx_with(mu, alpha, n, |c| fresnel_dielectric(c, eta))
}

fn ggx_with(mu: f64, alpha: f64, n: u32, f: impl Fn(f64) -> f64) -> f64 {
    let v = view(mu);
    (0..n)
        .map(|k| {
            let (u1, u2) = qmc::hammersley(k, n);
            let (c, w) = ggx_albedo_sample(v, alpha, u1, u2);
            w * f(c)
        })
        .sum::<f64>()
        / n as f64
}

fn centre(i: usize, n: usize) -> f64 {
    (i as f64 + 0.5) / (n - 1) as f64
}

/// Errors of the GGX tables at cell centres of (μ, ᾱ) (dielectric: also of q): E_ss, the
/// moments, the dielectric outside (η ≥ 1) and inside (η ≤ 1, the third coordinate is η).
pub fn ggx_errors(t: &Tables) -> [Vec<CellError>; 4] {
    let cells: Vec<(usize, usize)> = (0..ROUGHNESS_NODES - 1).flat_map(|j| (0..VIEW_NODES - 1).map(move |i| (j, i))).collect();
    type Cell = (f64, f64, Vec<f64>, Vec<f64>, (f64, f64));
    let per: Vec<Cell> = cells
        .par_iter()
        .map(|&(j, i)| {
            let (mu, alpha) = (view_mu(GGX_VIEW, centre(i, VIEW_NODES)), ggx_alpha(centre(j, ROUGHNESS_NODES)));
            let exact = integrate_ggx(mu, alpha, 4 * GGX_SAMPLES);
            let e_ess = (t.ess(mu, alpha) - exact.ess).abs();
            // Moments checked through a conductor curve (gold, red channel).
            let n = 4 * GGX_SAMPLES;
            let gold_exact = conductor_albedo(mu, alpha, 0.183, 3.424, n);
            let e_mom = (t.with_fresnel(mu, alpha, |c| fresnel_conductor(c, 0.183, 3.424)) - gold_exact).abs();
            // Dielectric at IOR cell centres, outside (η) and inside (1/η).
            let dielectric_error = |eta: f64| (t.dielectric(mu, alpha, eta) - dielectric_albedo(mu, alpha, eta, n)).abs();
            let e_die: Vec<f64> = (0..IOR_NODES - 1).map(|k| dielectric_error(ior_eta(centre(k, IOR_NODES)))).collect();
            let e_inside: Vec<f64> = (0..IOR_NODES - 1).map(|k| dielectric_error(1.0 / ior_eta(centre(k, IOR_NODES)))).collect();
            (e_ess, e_mom, e_die, e_inside, (mu, alpha))
        })
        .collect();
    let ess = per.iter().map(|p| (p.0, (p.4 .0, p.4 .1, 0.0))).collect();
    let mom = per.iter().map(|p| (p.1, (p.4 .0, p.4 .1, 0.0))).collect();
    let die = per.iter().flat_map(|p| p.2.iter().enumerate().map(move |(k, e)| (*e, (p.4 .0, p.4 .1, ior_eta(centre(k, IOR_NODES)))))).collect();
    let inside = per.iter().flat_map(|p| p.3.iter().enumerate().map(move |(k, e)| (*e, (p.4 .0, p.4 .1, 1.0 / ior_eta(centre(k, IOR_NODES)))))).collect();
    [ess, mom, die, inside]
}

/// Errors of a cosine-sampled table at cell centres.
pub fn diffuse_errors(t: &Tables, which: DiffuseTable) -> Vec<CellError> {
    let cells: Vec<(usize, usize)> = (0..ROUGHNESS_NODES - 1).flat_map(|j| (0..VIEW_NODES - 1).map(move |i| (j, i))).collect();
    cells
        .par_iter()
        .map(|&(j, i)| {
            let mu = view_mu(which.view_axis(), centre(i, VIEW_NODES));
            let r = which.roughness_axis().value(centre(j, ROUGHNESS_NODES));
            ((t.diffuse(which, mu, r) - which.integrate(mu, r, 4 * COSINE_SAMPLES)).abs(), (mu, r, 0.0))
        })
        .collect()
}

/// The Markdown error report.
pub fn report(t: &Tables, progress: &(dyn Fn(&str) + Sync)) -> String {
    progress("GGX tables");
    let [ess, mom, die, inside] = ggx_errors(t);
    let mut rows = vec![
        ("ggx_ess", ess, "E_ss(μ, ᾱ), F = 1", (0.0, 0.0, f64::INFINITY)),
        ("ggx_moments", mom, "Σ W_j F(c_j) for gold (n 0.183, k 3.424, red channel)", (0.0, 0.0, f64::INFINITY)),
        ("ggx_dielectric", die, "E(μ, ᾱ, η), IOR cell centres too", (0.0, 1.1, f64::INFINITY)),
        ("ggx_dielectric_inside", inside, "E(μ, ᾱ, η), η < 1, IOR cell centres too", (0.0, 0.0, 1.0 / 1.1)),
    ];
    let mut diffuse = Vec::new();
    for w in DiffuseTable::ALL {
        progress(w.name());
        diffuse.push((w, diffuse_errors(t, w)));
    }
    for (w, e) in diffuse {
        let floor = if w == DiffuseTable::SheenContyKulla { 0.05 } else { 0.0 };
        rows.push((w.name(), e, "albedo(μ, roughness), white", (floor, 0.0, f64::INFINITY)));
    }
    let mut s = String::from("| table | range | max abs error | mean abs error | worst at (μ, axis 2, axis 3) | quantity |\n|---|---|---|---|---|---|\n");
    // The tested domain of each table: axis 2 ≥ floor2 and floor3 ≤ axis 3 ≤ ceiling3.
    for (name, cells, what, (floor2, floor3, ceiling3)) in &rows {
        let tested: Vec<CellError> = cells.iter().copied().filter(|(_, at)| at.1 >= *floor2 && at.2 >= *floor3 && at.2 <= *ceiling3).collect();
        let mut range = String::from("μ ≥ 0.02");
        if *floor2 > 0.0 {
            range += &format!(", roughness ≥ {floor2}");
        }
        if *floor3 > 0.0 {
            range += &format!(", η ≥ {floor3}");
        }
        if ceiling3.is_finite() {
            range += &format!(", η ≤ 1/{:.1}", 1.0 / ceiling3);
        }
        for (range, cells, floor) in [(range.as_str(), &tested, TESTED_MU), ("all", cells, 0.0)] {
            let e = summarize(cells, floor);
            let _ = writeln!(s, "| {name} | {range} | {:.2e} | {:.2e} | ({:.4}, {:.4}, {:.3}) | {what} |", e.max, e.mean, e.worst_at.0, e.worst_at.1, e.worst_at.2);
        }
    }
    s
}
