//! Reference BSDF formulas in f64, written from the formulas in materialx-notes.md §1 rather
//! than from the WGSL library: the integrands of the albedo tables, and the independent side of
//! the tests that check the compiled kernels. Local frame: normal +z; `v` toward the viewer,
//! `l` toward the light.

use std::f64::consts::PI;

pub type V3 = [f64; 3];

pub fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

pub fn normalize(a: V3) -> V3 {
    let n = dot(a, a).sqrt();
    [a[0] / n, a[1] / n, a[2] / n]
}

/// The view direction at cosine `mu` (azimuth 0).
pub fn view(mu: f64) -> V3 {
    [(1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu]
}

/// GGX distribution of normals, isotropic alpha `a`.
pub fn ggx_d(h: V3, a: f64) -> f64 {
    let a2 = a * a;
    let t = h[2] * h[2] * (a2 - 1.0) + 1.0;
    a2 / (PI * t * t)
}

/// Smith Λ for isotropic GGX.
pub fn ggx_lambda(w: V3, a: f64) -> f64 {
    let mu = w[2].max(1e-8);
    let tan2 = (1.0 - mu * mu).max(0.0) / (mu * mu);
    0.5 * ((1.0 + a * a * tan2).sqrt() - 1.0)
}

/// f·cos θl of the GGX lobe with F = 1 and height-correlated G2: D G2 / (4 μv).
pub fn ggx_f_cos(v: V3, l: V3, a: f64) -> f64 {
    if l[2] <= 0.0 || v[2] <= 0.0 {
        return 0.0;
    }
    let h = normalize([v[0] + l[0], v[1] + l[1], v[2] + l[2]]);
    let g2 = 1.0 / (1.0 + ggx_lambda(v, a) + ggx_lambda(l, a));
    ggx_d(h, a) * g2 / (4.0 * v[2].max(1e-8))
}

/// Visible-normal sample of the microfacet normal (Heitz 2018, isotropic).
pub fn ggx_sample_vndf(v: V3, a: f64, u1: f64, u2: f64) -> V3 {
    let vh = normalize([a * v[0], a * v[1], v[2].max(1e-12)]);
    let lensq = vh[0] * vh[0] + vh[1] * vh[1];
    let t1 = if lensq > 0.0 { [-vh[1] / lensq.sqrt(), vh[0] / lensq.sqrt(), 0.0] } else { [1.0, 0.0, 0.0] };
    let t2 = [vh[1] * t1[2] - vh[2] * t1[1], vh[2] * t1[0] - vh[0] * t1[2], vh[0] * t1[1] - vh[1] * t1[0]];
    let r = u1.sqrt();
    let phi = 2.0 * PI * u2;
    let p1 = r * phi.cos();
    let s = 0.5 * (1.0 + vh[2]);
    let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * r * phi.sin();
    let p3 = (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt();
    let nh = [p1 * t1[0] + p2 * t2[0] + p3 * vh[0], p1 * t1[1] + p2 * t2[1] + p3 * vh[1], p1 * t1[2] + p2 * t2[2] + p3 * vh[2]];
    normalize([a * nh[0], a * nh[1], nh[2].max(0.0)])
}

pub fn reflect(v: V3, h: V3) -> V3 {
    let c = 2.0 * dot(v, h);
    [c * h[0] - v[0], c * h[1] - v[1], c * h[2] - v[2]]
}

/// One VNDF sample of the F = 1 albedo: (v·h, weight), weight = f cos / pdf = G2/G1(v).
pub fn ggx_albedo_sample(v: V3, a: f64, u1: f64, u2: f64) -> (f64, f64) {
    let h = ggx_sample_vndf(v, a, u1, u2);
    let l = reflect(v, h);
    if l[2] <= 0.0 {
        return (dot(v, h), 0.0);
    }
    let lv = ggx_lambda(v, a);
    let ll = ggx_lambda(l, a);
    (dot(v, h), (1.0 + lv) / (1.0 + lv + ll))
}

/// Exact unpolarised dielectric Fresnel (Walter et al. 2007 form); 1 under TIR; η ≤ 0 → 1.
pub fn fresnel_dielectric(c: f64, eta: f64) -> f64 {
    if eta <= 0.0 {
        return 1.0;
    }
    let c = c.clamp(0.0, 1.0);
    let g2 = eta * eta - 1.0 + c * c;
    if g2 < 0.0 {
        return 1.0;
    }
    let g = g2.sqrt();
    let a = (g - c) / (g + c);
    let b = (c * (g + c) - 1.0) / (c * (g - c) + 1.0);
    0.5 * a * a * (1.0 + b * b)
}

/// Exact conductor Fresnel for n + ik (one channel), from the s and p amplitudes.
pub fn fresnel_conductor(c: f64, n: f64, k: f64) -> f64 {
    let c = c.clamp(0.0, 1.0);
    // Complex arithmetic: eta = n + ik; cos_t = sqrt(1 - sin²/eta²).
    let s2 = 1.0 - c * c;
    let (er, ei) = (n * n - k * k, 2.0 * n * k); // eta²
    // z = eta² - sin²θ ; w = sqrt(z)  (= eta·cos_t)
    let (zr, zi) = (er - s2, ei);
    let m = (zr * zr + zi * zi).sqrt();
    let wr = ((m + zr) * 0.5).max(0.0).sqrt();
    let wi = if zi >= 0.0 { ((m - zr) * 0.5).max(0.0).sqrt() } else { -((m - zr) * 0.5).max(0.0).sqrt() };
    // r_s = (c - w)/(c + w)
    let rs = ((c - wr).powi(2) + wi * wi) / ((c + wr).powi(2) + wi * wi).max(1e-300);
    // r_p = (eta² c - w)/(eta² c + w)
    let (ar, ai) = (er * c - wr, ei * c - wi);
    let (br, bi) = (er * c + wr, ei * c + wi);
    let rp = (ar * ar + ai * ai) / (br * br + bi * bi).max(1e-300);
    0.5 * (rs + rp)
}

/// Hoffman's generalized Schlick with F82 multiplier, one channel.
pub fn fresnel_schlick_f82(c: f64, r0: f64, r82: f64, r90: f64, q: f64) -> f64 {
    let cbar: f64 = 1.0 / 7.0;
    let x = c.clamp(0.0, 1.0);
    let lerp = |t: f64| r0 + (r90 - r0) * t;
    let a = lerp((1.0 - cbar).powf(q)) * (1.0 - r82) / (cbar * (1.0 - cbar).powi(6));
    lerp((1.0 - x).powf(q)) - a * x * (1.0 - x).powi(6)
}

/// MaterialX's conty_kulla sheen: f·cos θl (colour 1).
pub fn sheen_conty_kulla_f_cos(v: V3, l: V3, r: f64) -> f64 {
    if l[2] <= 0.0 {
        return 0.0;
    }
    let mv = v[2].clamp(1e-8, 1.0);
    let h = normalize([v[0] + l[0], v[1] + l[1], v[2] + l[2]]);
    let inv_r = 1.0 / r.max(0.005);
    let d = (2.0 + inv_r) * (1.0 - h[2] * h[2]).max(0.0).powf(0.5 * inv_r) / (2.0 * PI);
    d * l[2] / (4.0 * (l[2] + mv - l[2] * mv))
}

/// MaterialX's Oren–Nayar (uncompensated): f·cos θl (colour 1).
pub fn oren_nayar_f_cos(v: V3, l: V3, sigma: f64) -> f64 {
    if l[2] <= 0.0 {
        return 0.0;
    }
    let mv = v[2].clamp(1e-8, 1.0);
    let s = dot(l, v) - l[2] * mv;
    let stinv = if s > 0.0 { s / l[2].max(mv) } else { 0.0 };
    let s2 = sigma * sigma;
    let a = 1.0 - 0.5 * s2 / (s2 + 0.33);
    let b = 0.45 * s2 / (s2 + 0.09);
    (a + b * stinv) * l[2] / PI
}

/// MaterialX's Burley diffuse: f·cos θl (colour 1).
pub fn burley_f_cos(v: V3, l: V3, r: f64) -> f64 {
    if l[2] <= 0.0 {
        return 0.0;
    }
    let h = normalize([v[0] + l[0], v[1] + l[1], v[2] + l[2]]);
    let ldoth = dot(l, h);
    let f90 = 0.5 + 2.0 * r * ldoth * ldoth;
    let schlick = |c: f64| 1.0 + (f90 - 1.0) * (1.0 - c.clamp(0.0, 1.0)).powi(5);
    schlick(l[2]) * schlick(v[2]) * l[2] / PI
}

/// Cosine-weighted hemisphere direction.
pub fn sample_cosine(u1: f64, u2: f64) -> V3 {
    let r = u1.sqrt();
    let phi = 2.0 * PI * u2;
    [r * phi.cos(), r * phi.sin(), (1.0 - u1).max(0.0).sqrt()]
}
