//! The χ² goodness-of-fit test the sampling tests share (closures.rs, materials.rs): bins with
//! expectations below 5 pooled, smallest first, and the upper tail by Wilson–Hilferty.

/// χ² of `observed` against `expected` over the bins `cells`, and its number of cells after
/// pooling the bins expected below 5 (smallest first, until each pool reaches 5).
pub fn pooled(observed: &[f64], expected: &[f64], cells: impl Iterator<Item = usize>) -> (f64, usize) {
    let (mut chi2, mut df, mut pool_o, mut pool_e) = (0.0, 0usize, 0.0, 0.0);
    let mut order: Vec<usize> = cells.collect();
    order.sort_by(|a, b| expected[*a].partial_cmp(&expected[*b]).unwrap());
    for &b in &order {
        if expected[b] < 5.0 || pool_e > 0.0 && pool_e < 5.0 {
            pool_o += observed[b];
            pool_e += expected[b];
            if pool_e >= 5.0 {
                chi2 += (pool_o - pool_e) * (pool_o - pool_e) / pool_e;
                df += 1;
                pool_o = 0.0;
                pool_e = 0.0;
            }
            continue;
        }
        chi2 += (observed[b] - expected[b]) * (observed[b] - expected[b]) / expected[b];
        df += 1;
    }
    (chi2, df)
}

/// Wilson–Hilferty upper tail of χ² with `df` degrees of freedom.
pub fn p_value(x: f64, df: f64) -> f64 {
    let z = ((x / df).powf(1.0 / 3.0) - (1.0 - 2.0 / (9.0 * df))) / (2.0 / (9.0 * df)).sqrt();
    0.5 * erfc(z / std::f64::consts::SQRT_2)
}

fn erfc(x: f64) -> f64 {
    // Numerical Recipes' erfc (Chebyshev fit), relative error < 1.2e-7.
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let r = t * (-z * z - 1.26551223 + t * (1.00002368 + t * (0.37409196 + t * (0.09678418 + t * (-0.18628806 + t * (0.27886807 + t * (-1.13520398 + t * (1.48851587 + t * (-0.82215223 + t * 0.17087277))))))))).exp();
    if x >= 0.0 {
        r
    } else {
        2.0 - r
    }
}
