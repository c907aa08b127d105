//! Extreme grazing views: the shipped gold `conductor_bsdf` eval kernel (packet form and
//! scalar form) against an f64 reference down to μv = 0.003 — the height-correlated GGX lobe
//! with the exact conductor Fresnel, times MaterialX's energy compensation with E_ss integrated
//! by brute force at that very view (not read from the tables the kernel reads).

use uplift_kernels::albedo_tables::{integrate_ggx, reference};
use uplift_kernels::driver::TextureSet;
use uplift_kernels::generated::bsdf_conductor_eval as conductor;

/// Gold (n, k) per channel, as bsdf_conductor.mtlx's defaults.
const GOLD: [(f64, f64); 3] = [(0.183, 3.424), (0.421, 2.346), (1.373, 1.770)];

/// f·cos of the reference lobe for channel (n, k) at local directions v, l.
fn reference_f_cos(v: [f64; 3], l: [f64; 3], alpha: f64, (n, k): (f64, f64), ess: f64) -> f64 {
    let h = reference::normalize([v[0] + l[0], v[1] + l[1], v[2] + l[2]]);
    let smith = |w: [f64; 3]| (w[2] * w[2] + alpha * alpha * (w[0] * w[0] + w[1] * w[1])).sqrt();
    let lobe = reference::ggx_d(h, alpha) * l[2] / (2.0 * (l[2] * smith(v) + v[2] * smith(l)));
    let f1 = reference::fresnel_conductor(1.0, n, k);
    let favg = f1 + (1.0 - f1) / 21.0;
    lobe * reference::fresnel_conductor(reference::dot(v, h), n, k) * (1.0 + favg * (1.0 - ess) / ess)
}

#[test]
fn conductor_eval_matches_a_brute_force_reference_at_grazing_views() {
    assert_eq!((conductor::GEOMETRY_COLUMNS, conductor::INPUT_COLUMNS, conductor::OUTPUT_COLUMNS), (20, 15, 6), "bsdf_conductor_eval's column layout changed: update this test");
    let shipped = uplift_kernels::shipped::by_name("bsdf_conductor_eval").expect("bsdf_conductor_eval is shipped");
    const LIGHTS: usize = 64;
    let mut worst = (0.0f64, 0.0, 0.0);
    for alpha in [0.05f64, 0.3, 0.6] {
        for mu in [0.003f64, 0.004, 0.005, 0.007, 0.01, 0.02, 0.1] {
            let ess = integrate_ggx(mu, alpha, 1 << 16).ess;
            let v = [(1.0 - mu * mu).sqrt(), 0.0, mu];
            // Light directions: μl from 0.01 to 1, azimuths around the whole circle.
            let lights: Vec<[f64; 3]> = (0..LIGHTS)
                .map(|i| {
                    let (u1, u2) = uplift_kernels::albedo_tables::qmc::hammersley(i as u32, LIGHTS as u32);
                    let (ml, phi) = (0.01 + 0.99 * u1, std::f64::consts::TAU * u2);
                    let s = (1.0 - ml * ml).sqrt();
                    [s * phi.cos(), s * phi.sin(), ml]
                })
                .collect();
            // Columns: geometry (normal_world = z at 11..14, tangent_world = x at 17..20), inputs
            // wv 0..3, wl 3..6, weight 6, ior 7..10, extinction 10..13, roughness 13..15.
            let mut geometry = vec![vec![0.0f32; LIGHTS]; conductor::GEOMETRY_COLUMNS];
            geometry[13].fill(1.0);
            geometry[17].fill(1.0);
            let mut inputs = vec![vec![0.0f32; LIGHTS]; conductor::INPUT_COLUMNS];
            for (i, l) in lights.iter().enumerate() {
                inputs[0][i] = v[0] as f32;
                inputs[2][i] = v[2] as f32;
                for c in 0..3 {
                    inputs[3 + c][i] = l[c] as f32;
                    inputs[7 + c][i] = GOLD[c].0 as f32;
                    inputs[10 + c][i] = GOLD[c].1 as f32;
                }
            }
            inputs[6].fill(1.0);
            inputs[13].fill(alpha as f32);
            inputs[14].fill(alpha as f32);
            let geometry: Vec<&[f32]> = geometry.iter().map(|c| c.as_slice()).collect();
            let inputs: Vec<&[f32]> = inputs.iter().map(|c| c.as_slice()).collect();
            for (form, batch) in [("packet", shipped.batch), ("scalar", shipped.scalar_batch())] {
                let mut out = vec![vec![0.0f32; LIGHTS]; conductor::OUTPUT_COLUMNS];
                let mut cols: Vec<&mut [f32]> = out.iter_mut().map(|c| c.as_mut_slice()).collect();
                batch(&geometry, &inputs, &mut cols, &TextureSet::default());
                for (i, l) in lights.iter().enumerate() {
                    for (c, &gold) in GOLD.iter().enumerate() {
                        let want = reference_f_cos(v, *l, alpha, gold, ess);
                        let rel = (out[c][i] as f64 / want - 1.0).abs();
                        assert!(rel <= 3e-3, "{form} kernel, α {alpha}, μv {mu}, wl {l:?}, channel {c}: {} vs reference {want} (relative error {rel:.1e})", out[c][i]);
                        if rel > worst.0 {
                            worst = (rel, mu, alpha);
                        }
                    }
                }
            }
        }
    }
    eprintln!("worst relative error {:.2e} at μv {}, α {}", worst.0, worst.1, worst.2);
}
