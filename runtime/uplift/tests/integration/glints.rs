//! Glints (mtlx/libraries/uplift/wgsl/glint.wgsl; paper §5.3, Eq. 6) on wgpu: the pattern N is
//! energy-neutral (its mean over 10⁶ surface points is 1 ± 0.01 per channel for fixed
//! directions), tied to the surface (a function of position and half vector: the same under a
//! camera move that keeps the half vector, constant within a flake's cell), and the glint
//! closure multiplies a BSDF's response by exactly N while its albedo stays the BSDF's — so a
//! white Lambertian with glints still integrates to 1 over the surface (the white furnace).

use crate::common;
use common::*;
use uplift_compiler::{ClosureContext, OutputSelection, PatternKernel};
use uplift_engines::batch::Geometry;

const PARAMS: &str = r#"<input name="density" type="float" value="0.05"/><input name="size" type="float" value="0.01"/><input name="angle" type="float" value="0.1"/><input name="spread" type="float" value="0.5"/><input name="strength" type="float" value="0.5"/><input name="seed" type="float" value="7"/>"#;

fn factor_kernel() -> PatternKernel {
    compile(&format!(
        r#"<materialx version="1.39"><nodegraph name="g"><input name="wv" type="vector3" value="0,0,1"/><input name="wl" type="vector3" value="0,0,1"/>
        <uplift_glint_factor name="n" type="color3">{PARAMS}<input name="wv" type="vector3" interfacename="wv"/><input name="wl" type="vector3" interfacename="wl"/></uplift_glint_factor>
        <output name="out" type="color3" nodename="n"/></nodegraph></materialx>"#
    ))
}

fn unit(v: [f32; 3]) -> [f32; 3] {
    let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    v.map(|x| x / l)
}

fn positions(rng: &mut Rng, n: usize) -> Vec<Geometry> {
    (0..n).map(|_| Geometry { position: [rng.range(-40.0, 40.0), rng.range(-40.0, 40.0), rng.range(-40.0, 40.0)], ..Default::default() }).collect()
}

#[test]
fn the_glint_pattern_is_energy_neutral_and_tied_to_the_surface() {
    let k = factor_kernel();
    let (wv, wl) = (unit([0.3, 0.1, 0.95]), unit([-0.2, 0.4, 0.89]));
    let mut rng = Rng::new(17);
    let n = 1_000_000;
    let geom = positions(&mut rng, n);
    let rows: Vec<Vec<f32>> = (0..n).map(|_| [wv, wl].concat()).collect();
    let out = run(&k, &geom, &rows, vec![]);
    let mut sum = [0.0f64; 3];
    let mut sparkling = 0usize;
    for o in &out {
        for c in 0..3 {
            sum[c] += o[c] as f64;
        }
        sparkling += usize::from(o[0] > 1.0);
    }
    let mean = sum.map(|s| s / n as f64);
    eprintln!("glint mean over {n} points: {mean:?}; {sparkling} sparkle");
    for c in 0..3 {
        assert!((mean[c] - 1.0).abs() <= 0.01, "channel {c}: mean {}", mean[c]);
    }
    assert!(sparkling > n / 100 && sparkling < n / 5, "{sparkling} of {n} points sparkle");
    // A camera move that keeps the half vector (both directions turned 90° about it) and the
    // swap of view and light leave every point's N unchanged.
    let h = unit([wv[0] + wl[0], wv[1] + wl[1], wv[2] + wl[2]]);
    let turn = |v: [f32; 3]| {
        // Rodrigues, 90° about h: v·cos + (h × v)·sin + h (h·v)(1 − cos).
        let hv = h[0] * v[0] + h[1] * v[1] + h[2] * v[2];
        let cross = [h[1] * v[2] - h[2] * v[1], h[2] * v[0] - h[0] * v[2], h[0] * v[1] - h[1] * v[0]];
        [0, 1, 2].map(|c| cross[c] + h[c] * hv)
    };
    let some = &geom[..4096];
    let base = &out[..4096];
    for (wv2, wl2) in [(turn(wv), turn(wl)), (wl, wv)] {
        assert!(wv2[2] > 0.0 && wl2[2] > 0.0);
        let rows: Vec<Vec<f32>> = (0..some.len()).map(|_| [wv2, wl2].concat()).collect();
        let moved = run(&k, some, &rows, vec![]);
        let same = moved.iter().zip(base).filter(|(a, b)| a.iter().zip(b.iter()).all(|(x, y)| (x - y).abs() <= 1e-4 * y.abs().max(1.0))).count();
        assert!(same * 1000 >= some.len() * 998, "only {same} of {} points keep their N when the camera moves", some.len());
    }
    // Constant within a cell (edge 0.01): points 0.002 apart inside one cell.
    let inside: Vec<Geometry> = some.iter().map(|g| Geometry { position: g.position.map(|x| (x / 0.01).floor() * 0.01 + 0.004), ..*g }).collect();
    let shifted: Vec<Geometry> = inside.iter().map(|g| Geometry { position: g.position.map(|x| x + 0.002), ..*g }).collect();
    let rows: Vec<Vec<f32>> = (0..some.len()).map(|_| [wv, wl].concat()).collect();
    let (a, b) = (run(&k, &inside, &rows, vec![]), run(&k, &shifted, &rows, vec![]));
    let differ = a.iter().zip(&b).filter(|(x, y)| x != y).count();
    assert!(differ * 200 <= some.len(), "{differ} of {} points change N inside their cell", some.len());
}

/// The glint closure over a white Lambertian: eval = Lambert × N at each point; albedo = 1;
/// the surface average of ∫ f·N cos dωl (one uniform direction per point, 10⁶ points) is 1.
#[test]
fn the_glint_closure_multiplies_the_response_and_keeps_the_albedo() {
    let doc = format!(
        r#"<materialx version="1.39"><oren_nayar_diffuse_bsdf name="white" type="BSDF"><input name="color" type="color3" value="1, 1, 1"/><input name="roughness" type="float" value="0"/></oren_nayar_diffuse_bsdf>
        <uplift_glint name="glinty" type="BSDF"><input name="in" type="BSDF" nodename="white"/>{PARAMS}</uplift_glint>
        <output name="out" type="BSDF" nodename="glinty"/></materialx>"#
    );
    let closure = |c: ClosureContext| {
        let (d, diags) = mtlx::read_str(&doc, "glint.mtlx");
        let r = compiler().compile_document_in(d, diags, "glint.mtlx", &OutputSelection::Named(vec!["out".into()]), Some(c));
        r.kernel.unwrap_or_else(|| panic!("{:?}", r.diagnostics))
    };
    let (eval, albedo, factor) = (closure(ClosureContext::Eval), closure(ClosureContext::Albedo), factor_kernel());
    let mut rng = Rng::new(23);
    let n = 1_000_000;
    let geom = positions(&mut rng, n);
    let wv = unit([0.2, -0.3, 0.93]);
    let wl: Vec<[f32; 3]> = (0..n)
        .map(|_| {
            let (z, phi) = (rng.range(0.0, 1.0), rng.range(0.0, std::f32::consts::TAU));
            let r = (1.0 - z * z).max(0.0).sqrt();
            [r * phi.cos(), r * phi.sin(), z]
        })
        .collect();
    let rows: Vec<Vec<f32>> = wl.iter().map(|l| [wv, *l].concat()).collect();
    let (f, nn) = (run(&eval, &geom, &rows, vec![]), run(&factor, &geom, &rows, vec![]));
    let mut sum = 0.0f64;
    for i in 0..n {
        let lambert = wl[i][2] / std::f32::consts::PI;
        for c in 0..3 {
            assert!((f[i][c] - lambert * nn[i][c]).abs() <= 1e-5 * (lambert * nn[i][c]).max(1.0), "row {i}: eval {:?}, Lambert × N {:?}", &f[i][..3], nn[i]);
        }
        sum += (f[i][0] + f[i][1] + f[i][2]) as f64 / 3.0 * std::f64::consts::TAU;
    }
    let furnace = sum / n as f64;
    eprintln!("white Lambertian with glints: surface-average albedo {furnace:.4}");
    assert!((furnace - 1.0).abs() <= 0.01, "surface-average albedo {furnace}");
    let a = run(&albedo, &geom[..256], &vec![wv.to_vec(); 256], vec![]);
    for row in &a {
        assert!(row[..3].iter().all(|x| (x - 1.0).abs() < 2e-3), "albedo {:?}", &row[..3]);
    }
}
