//! The full material the renderer shades, f = f_nd + T·c/π (paper Eq. 2): the non-diffuse part
//! from `Shading` over a Lambertian base of colour c scaled by the non-diffuse throughput T —
//! its evaluation and its sampling, in batches of surface points.
//!
//! Sampling picks the non-diffuse strategy with probability P = R / (R + Y(T·c)) (R = Y of the
//! non-diffuse albedo, as the paper chooses between the parts), clamped to [0.05, 0.95] so each
//! strategy keeps some samples (0 when R = 0, 1 when the base is black), and a cosine-weighted
//! direction otherwise; the pdf is the
//! mixture P·pdf_nd + (1 − P)·cos/π. P depends on wv only (T and R do), so it is computed once
//! per point by `evaluate` and passed to `sample`.

use crate::scene::Vec3;
use crate::shading::{luminance, LobeValue, Shading};
use crate::surface::SurfaceSample;
use std::f32::consts::FRAC_1_PI;

/// The full material at one direction pair.
#[derive(Clone, Copy, Debug, Default)]
pub struct MaterialValue {
    /// f·cos θl (RGB).
    pub fcos: [f32; 3],
    /// The BSDF-sampling pdf of wl.
    pub pdf: f32,
}

/// The probability of sampling the non-diffuse part, from its values at any wl.
pub fn select_probability(v: &LobeValue, diffuse: [f32; 3]) -> f32 {
    let d = luminance([0, 1, 2].map(|c| v.throughput[c] * diffuse[c]));
    let r = v.reflectance;
    if r <= 1e-6 {
        // Nothing to sample in the non-diffuse part (its sampler would fail).
        return 0.0;
    }
    if d <= 1e-6 {
        return 1.0;
    }
    (r / (r + d)).clamp(0.05, 0.95)
}

/// The full material from its non-diffuse part at a direction with cosine `mu_l`.
pub fn combine(v: &LobeValue, diffuse: [f32; 3], select: f32, mu_l: f32) -> MaterialValue {
    let fcos = [0, 1, 2].map(|c| v.fcos[c] + v.throughput[c] * diffuse[c] * FRAC_1_PI * mu_l);
    MaterialValue { fcos, pdf: select * v.pdf + (1.0 - select) * mu_l * FRAC_1_PI }
}

pub use uplift_neural::features::cosine_hemisphere;

/// A modulation of the non-diffuse part's f·cos per point at light directions wl (glints:
/// f_nd · N, glint.rs); P and the pdf are unchanged (E[N] = 1).
pub type Modulation<'a> = &'a dyn Fn(&[Vec3]) -> Result<Vec<[f32; 3]>, String>;

fn modulate(lobes: &mut [LobeValue], by: Option<Modulation>, wl: &[Vec3]) -> Result<(), String> {
    if let Some(m) = by {
        for (v, n) in lobes.iter_mut().zip(m(wl)?) {
            v.fcos = [0, 1, 2].map(|c| v.fcos[c] * n[c]);
        }
    }
    Ok(())
}

/// Evaluates the material at (wv, wl) per point; returns the values and each point's selection
/// probability P.
pub fn evaluate(shading: &Shading, points: &[SurfaceSample], wv: &[Vec3], wl: &[Vec3], by: Option<Modulation>) -> Result<(Vec<MaterialValue>, Vec<f32>), String> {
    let mut lobes = shading.evaluate(points, wv, wl, true)?;
    modulate(&mut lobes, by, wl)?;
    let select: Vec<f32> = lobes.iter().zip(points).map(|(v, p)| select_probability(v, p.diffuse)).collect();
    let values = lobes.iter().zip(points).zip(wl).zip(&select).map(|(((v, p), l), &s)| combine(v, p.diffuse, s, l[2])).collect();
    Ok((values, select))
}

/// Draws wl per point from the mixture with uniforms u (u[0] picks the strategy, u[1..4] drive
/// the non-diffuse sampler, u[4..6] the cosine one). A failed sample has pdf 0.
pub fn sample(shading: &Shading, points: &[SurfaceSample], wv: &[Vec3], select: &[f32], u: &[[f32; 6]], by: Option<Modulation>) -> Result<Vec<(Vec3, MaterialValue)>, String> {
    let n = points.len();
    let lobe_rows: Vec<usize> = (0..n).filter(|&k| u[k][0] < select[k]).collect();
    let cos_rows: Vec<usize> = (0..n).filter(|&k| u[k][0] >= select[k]).collect();
    let mut drawn: Vec<(Vec3, LobeValue)> = vec![([0.0, 0.0, 1.0], LobeValue::default()); n];
    let gather = |rows: &[usize]| -> (Vec<SurfaceSample>, Vec<Vec3>) { (rows.iter().map(|&k| points[k]).collect(), rows.iter().map(|&k| wv[k]).collect()) };
    let (s, v) = gather(&lobe_rows);
    let uu: Vec<Vec3> = lobe_rows.iter().map(|&k| [u[k][1], u[k][2], u[k][3]]).collect();
    for (&k, r) in lobe_rows.iter().zip(shading.sample(&s, &v, &uu)?) {
        drawn[k] = r;
    }
    let (s, v) = gather(&cos_rows);
    let wl: Vec<Vec3> = cos_rows.iter().map(|&k| cosine_hemisphere(u[k][4], u[k][5])).collect();
    for ((&k, &l), r) in cos_rows.iter().zip(&wl).zip(shading.evaluate(&s, &v, &wl, false)?) {
        drawn[k] = (l, r);
    }
    if by.is_some() {
        let wl: Vec<Vec3> = drawn.iter().map(|d| d.0).collect();
        let mut lobes: Vec<LobeValue> = drawn.iter().map(|d| d.1).collect();
        modulate(&mut lobes, by, &wl)?;
        for (d, l) in drawn.iter_mut().zip(lobes) {
            d.1 = l;
        }
    }
    Ok(drawn
        .into_iter()
        .enumerate()
        .map(|(k, (wl, v))| {
            let lobe_failed = u[k][0] < select[k] && v.pdf <= 0.0;
            if lobe_failed || wl[2] <= 1e-6 {
                return (wl, MaterialValue::default());
            }
            (wl, combine(&v, points[k].diffuse, select[k], wl[2]))
        })
        .collect())
}
