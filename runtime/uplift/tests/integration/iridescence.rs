//! The iridescent clearcoat (issue 26, deliverable 3): `uplift_stack`'s clearcoat with a thin
//! film (`coat_film_thickness`, `coat_film_ior`) against an independent implementation of the
//! Airy reflectance written here in f64 (Belcour & Barla 2017 as MaterialX evaluates it: both
//! polarisations, the m = 0 term and two pairs of spectral Diracs against the Gaussian fits of
//! the CIE XYZ sensitivities, XYZ to RGB, clamped); the white furnace with films on; and the
//! `--iridescence` rule option's written material, which MaterialX's validator accepts.

use super::common::cli::{repo, s, temp_dir, uplift};
use super::common::stack_params;
use uplift_compiler::ClosureContext;
use uplift_engines::cpu_engine::CpuEngine;
use uplift_engines::stack::Stack;
use uplift_engines::stack_kernel::{vec3_at, StackKernel};

/// Dielectric Fresnel reflectances (p, s) of relative IOR `eta` ≥ its critical value at
/// incidence cosine `c` (no total internal reflection in these cases).
fn fresnel_polarized(c: f64, eta: f64) -> (f64, f64) {
    let ct = (eta * eta - (1.0 - c * c)).sqrt() / eta;
    let rs = (c - eta * ct) / (c + eta * ct);
    let rp = (eta * c - ct) / (eta * c + ct);
    (rp * rp, rs * rs)
}

/// The reflection phases (p, s) at the film–substrate interface in Belcour & Barla's
/// convention (their `fresnelPhaseExact`, which MaterialX uses): for a dielectric substrate of
/// IOR `eta3` under a film of IOR `eta2` at internal cosine `ct`, 0 or π.
fn substrate_phases(ct: f64, eta2: f64, eta3: f64) -> (f64, f64) {
    let c3 = (1.0 - (eta2 / eta3).powi(2) * (1.0 - ct * ct)).sqrt();
    let pi = std::f64::consts::PI;
    let phi_s = if eta3 * c3 > eta2 * ct { 0.0 } else { pi };
    let phi_p = if eta3 * ct > eta2 * c3 { 0.0 } else { pi };
    (phi_p, phi_s)
}

/// The CIE XYZ sensitivities' Fourier transform at optical path difference `opd` (m) with
/// phase `shift` (Belcour & Barla's Gaussian fits).
fn sensitivity(opd: f64, shift: f64) -> [f64; 3] {
    let phase = 2.0 * std::f64::consts::PI * opd;
    let val = [5.4856e-13, 4.4201e-13, 5.2481e-13];
    let pos = [1.6810e+06, 1.7953e+06, 2.2084e+06];
    let var = [4.3278e+09, 9.3046e+09, 6.6121e+09];
    let mut xyz = [0.0; 3];
    for k in 0..3 {
        xyz[k] = val[k] * (2.0 * std::f64::consts::PI * var[k]).sqrt() * (pos[k] * phase + shift).cos() * (-var[k] * phase * phase).exp();
    }
    xyz[0] += 9.7470e-14 * (2.0 * std::f64::consts::PI * 4.5282e+09f64).sqrt() * (2.2399e+06 * phase + shift).cos() * (-4.5282e+09 * phase * phase).exp();
    xyz.map(|x| x / 1.0685e-7)
}

/// Airy reflectance (RGB) of a film of IOR `eta2` and `thickness` nm on a dielectric of IOR
/// `eta3`, in air, at incidence cosine `c`.
fn airy(c: f64, eta2: f64, eta3: f64, thickness: f64) -> [f64; 3] {
    let ct = (1.0 - (1.0 - c * c) / (eta2 * eta2)).sqrt();
    let (r12p, r12s) = fresnel_polarized(c, eta2);
    let (r23p, r23s) = fresnel_polarized(ct, eta3 / eta2);
    let (phi23p, phi23s) = substrate_phases(ct, eta2, eta3);
    let brewster = 1.0 / (1.0 + eta2 * eta2).sqrt();
    let phi21p = if c < brewster { 0.0 } else { std::f64::consts::PI };
    let opd = 2.0 * eta2 * ct * thickness * 1e-9;
    let polarization = |r12: f64, r23: f64, phi: f64| -> [f64; 3] {
        let t121 = 1.0 - r12;
        let rs = t121 * t121 * r23 / (1.0 - r12 * r23);
        let r123 = (r12 * r23).sqrt();
        let c1 = (rs - t121) * r123;
        let c2 = c1 * r123;
        let (s1, s2) = (sensitivity(opd, phi), sensitivity(2.0 * opd, 2.0 * phi));
        [0, 1, 2].map(|k| r12 + rs + 2.0 * c1 * s1[k] + 2.0 * c2 * s2[k])
    };
    let p = polarization(r12p, r23p, phi23p + phi21p);
    let s = polarization(r12s, r23s, phi23s + std::f64::consts::PI);
    let xyz = [0, 1, 2].map(|k| 0.5 * (p[k] + s[k]));
    let m = [[2.3706743, -0.9000405, -0.4706338], [-0.5138850, 1.4253036, 0.0885814], [0.0052982, -0.0146949, 1.0093968]];
    [0, 1, 2].map(|r| (m[r][0] * xyz[0] + m[r][1] * xyz[1] + m[r][2] * xyz[2]).clamp(0.0, 1.0))
}

/// Unpolarised dielectric Fresnel reflectance.
fn fresnel(c: f64, eta: f64) -> f64 {
    let (p, s) = fresnel_polarized(c, eta);
    0.5 * (p + s)
}

#[test]
fn the_coat_film_is_the_airy_reflectance() {
    // Only the clearcoat reflects: a black conductor base (reflectivity 0: n = 1, k = 0) under
    // it, no fuzz. At the mirror direction h = n, so v·h = μv, and the coat's response is
    // w·D·G·F·comp: the film's over the bare coat's is F_airy / F_dielectric (the energy
    // compensation of a GGX alpha of 0.01 differs from 1 by less than 1e-5).
    let stack = Stack::builtin();
    let engine = CpuEngine::with_threads(1).unwrap();
    let eval = StackKernel::new(&engine, &stack, ClosureContext::Eval).unwrap();
    let base = [("metalness", 1.0), ("reflectivity.R", 0.0), ("reflectivity.G", 0.0), ("reflectivity.B", 0.0), ("edge_color.R", 0.0), ("edge_color.G", 0.0), ("edge_color.B", 0.0), ("fuzz_weight", 0.0), ("coat_weight", 1.0), ("coat_ior", 1.5)];
    let mut rows = Vec::new();
    let mut cases = Vec::new();
    for thickness in [150.0f32, 400.0, 820.0] {
        for film_ior in [1.3f32, 1.8] {
            for mu in [0.97f32, 0.8, 0.6, 0.4] {
                let mut with = base.to_vec();
                with.extend([("coat_film_thickness", thickness), ("coat_film_ior", film_ior)]);
                rows.extend(stack_params(&with));
                rows.extend(stack_params(&base));
                cases.push((thickness, film_ior, mu));
            }
        }
    }
    let n = rows.len() / stack.len();
    let wv: Vec<[f32; 3]> = (0..n).map(|r| cases[r / 2].2).map(|mu| [(1.0 - mu * mu).sqrt(), 0.0, mu]).collect();
    let wl: Vec<[f32; 3]> = wv.iter().map(|v| [-v[0], -v[1], v[2]]).collect();
    let out = eval.run(&engine, &rows, &(0..n).collect::<Vec<_>>(), &[("wv", &wv), ("wl", &wl)]).unwrap();
    let at = eval.output_offset("response");
    let mut worst = 0.0f64;
    for (k, &(thickness, film_ior, mu)) in cases.iter().enumerate() {
        let (film, bare) = (vec3_at(&out, at, 2 * k), vec3_at(&out, at, 2 * k + 1));
        let f_d = fresnel(mu as f64, 1.5);
        let want = airy(mu as f64, film_ior as f64, 1.5, thickness as f64);
        for c in 0..3 {
            let got = film[c] as f64 / bare[c] as f64 * f_d;
            let rel = (got - want[c]).abs() / want[c].max(1e-3);
            worst = worst.max(rel);
            assert!(rel <= 1e-4, "film {thickness} nm, IOR {film_ior}, μ {mu}, channel {c}: {got:.6} against Airy {:.6} ({rel:.2e} relative)", want[c]);
        }
    }
    eprintln!("coat film against the Airy reflectance: worst relative difference {worst:.2e} over {} cases", cases.len() * 3);
}

#[test]
fn films_keep_the_white_furnace() {
    // A white stack with every lobe on and a film on the coat: albedo + nothing absorbed ≤ 1
    // at every view (the layer's throughput uses the film's own albedo).
    let stack = Stack::builtin();
    let engine = CpuEngine::with_threads(1).unwrap();
    let albedo = StackKernel::new(&engine, &stack, ClosureContext::Albedo).unwrap();
    let mut rows = Vec::new();
    let mut wv = Vec::new();
    for thickness in [120.0f32, 350.0, 700.0, 1000.0] {
        for film_ior in [1.2f32, 1.6, 2.0] {
            for mu in [1.0f32, 0.7, 0.4, 0.15, 0.05] {
                rows.extend(stack_params(&[
                    ("metalness", 0.0),
                    ("coat_weight", 1.0),
                    ("coat_film_thickness", thickness),
                    ("coat_film_ior", film_ior),
                    ("fuzz_weight", 0.5),
                    ("inner_weight", 0.5),
                    ("subcutaneous_weight", 1.0),
                    ("scatter_color.R", 1.0),
                    ("scatter_color.G", 1.0),
                    ("scatter_color.B", 1.0),
                ]));
                wv.push([(1.0 - mu * mu).sqrt(), 0.0, mu]);
            }
        }
    }
    let n = wv.len();
    let out = albedo.run(&engine, &rows, &(0..n).collect::<Vec<_>>(), &[("wv", &wv)]).unwrap();
    let at = albedo.output_offset("albedo");
    let mut highest = 0.0f32;
    for k in 0..n {
        let a = vec3_at(&out, at, k);
        highest = highest.max(a[0].max(a[1]).max(a[2]));
    }
    eprintln!("highest albedo of a white stack with a coat film: {highest:.4}");
    assert!(highest <= 1.0 + 1e-4, "albedo {highest} above 1");
    assert!(highest > 0.2);
}

#[test]
fn the_iridescence_option_writes_valid_materials() {
    let dir = temp_dir("iridescence", "option");
    let out = dir.join("out");
    let (code, _, err) = uplift(&["enhance", s(&repo().join("examples/pbr_materials.mtlx")), "--type", "2", "--iridescence", "--resolution", "8x8", "--mask-size", "32", "-o", s(&out)]);
    assert_eq!(code, 0, "{err}");
    // Every material folder (not enhance's manifest beside them).
    for m in std::fs::read_dir(&out).unwrap().map(|e| e.unwrap().path()).filter(|p| p.is_dir()) {
        let img = uplift_base::exr::read(&m.join("params.exr")).unwrap();
        let t = img.channel("coat_film_thickness").unwrap();
        assert!(t.iter().all(|&x| (100.0..=1000.0).contains(&x) && x == t[0]), "{}: film thickness {}", m.display(), t[0]);
        let meta = std::fs::read_to_string(m.join("meta.json")).unwrap();
        assert!(meta.contains("film_thickness") && meta.contains("options/iridescence.mtlx"), "{meta}");
        match super::enhance::validate(&m.join("material.mtlx")) {
            Some(r) => r.unwrap(),
            None => super::enhance::say_validator_skipped(),
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
