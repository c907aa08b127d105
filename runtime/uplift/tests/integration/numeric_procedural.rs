//! Procedural nodes (constant, ramplr, ramptb, splitlr, splittb) and geometric nodes
//! (position, normal, tangent, bitangent in model/object/world space; texcoord vector2/vector3),
//! every type variant: compiled, run on wgpu for 256 seeded points, compared with closed forms.
//!
//! Conventions checked (see `stdlib/wgsl/procedural.wgsl`):
//! * ramplr = mix(valuel, valuer, clamp(u, 0, 1)); ramptb = mix(valueb, valuet, clamp(v, 0, 1))
//!   (the spec and MaterialX ≥ 1.39.5: valueb at the bottom, v = 0; valuet at v = 1).
//! * splitlr = u >= center ? valuer : valuel; splittb = v >= center ? valuet : valueb (a hard
//!   step: compute kernels have no derivatives for MaterialX's antialiased `mx_aastep`).
//! * Geometry: object space == world space; "model" is an alias of "object"; normal, tangent and
//!   bitangent are normalized, bitangent = normalize(cross(N, T)); a zero vector stays zero.
//!
//! Tolerance 1e-5 absolute (arithmetic only; values in [-2, 2]); normalization 1e-5.

use crate::common;
use crate::graph_kit;

use common::*;
use graph_kit::*;
use uplift_engines::batch::Geometry;


const TYPES: [&str; 6] = ["float", "color3", "color4", "vector2", "vector3", "vector4"];

fn random(rng: &mut Rng, n: usize, lo: f32, hi: f32) -> Vec<f32> {
    (0..n).map(|_| rng.range(lo, hi)).collect()
}

fn lerp(a: &[f32], b: &[f32], t: f32) -> Vec<f32> {
    a.iter().zip(b).map(|(x, y)| x * (1.0 - t) + y * t).collect()
}

// ---- constant --------------------------------------------------------------------------------

#[test]
fn constant_all_types() {
    let all = ["float", "color3", "color4", "vector2", "vector3", "vector4", "integer", "boolean", "matrix33", "matrix44"];
    let mut nodes = Vec::new();
    let mut outs = Vec::new();
    let mut inputs = Vec::new();
    let mut rng = Rng::new(0xc0);
    let mut literals = Vec::new();
    for t in all {
        let iname = format!("in_{t}");
        let nname = format!("c_{t}");
        nodes.push(node("constant", &nname, t, &[("value", t, Src::I(&iname))]));
        outs.push((nname.clone(), t.to_string(), nname.clone()));
        inputs.push((iname, t));
        // A literal value too.
        let lit: Vec<f32> = match t {
            "integer" => vec![-7.0],
            "boolean" => vec![1.0],
            _ => random(&mut rng, comps(t), -10.0, 10.0),
        };
        let text = match t {
            "integer" => "-7".to_string(),
            "boolean" => "true".to_string(),
            _ => val(&lit),
        };
        let lname = format!("l_{t}");
        nodes.push(node("constant", &lname, t, &[("value", t, Src::V(&text))]));
        outs.push((lname.clone(), t.to_string(), lname));
        literals.push((t, lit));
    }
    let inputs_ref: Vec<(&str, &str)> = inputs.iter().map(|(n, t)| (n.as_str(), *t)).collect();
    let k = compile(&graph_doc(&inputs_ref, &nodes, &outs));
    let n = 256;
    let mut rows = Vec::new();
    let mut given = Vec::new();
    for _ in 0..n {
        let vals: Vec<(String, Vec<f32>)> = all
            .iter()
            .map(|t| {
                let v = match *t {
                    "integer" => vec![rng.range(-1000.0, 1000.0).round()],
                    "boolean" => vec![(rng.next_u64() % 2) as f32],
                    _ => random(&mut rng, comps(t), -100.0, 100.0),
                };
                (format!("in_{t}"), v)
            })
            .collect();
        let named: Vec<(&str, Vec<f32>)> = vals.iter().map(|(n, v)| (n.as_str(), v.clone())).collect();
        rows.push(input_row(&k, &named));
        given.push(vals);
    }
    let got = run(&k, &vec![Geometry::default(); n], &rows, vec![]);
    for i in 0..n {
        for (j, t) in all.iter().enumerate() {
            // A pass-through: exact (matrices are MaterialX row-major lists in and out).
            assert_close(&format!("constant {t} (interface), point {i}"), out(&k, &got[i], &format!("c_{t}")), &given[i][j].1, 0.0);
            assert_close(&format!("constant {t} (literal), point {i}"), out(&k, &got[i], &format!("l_{t}")), &literals[j].1, 0.0);
        }
    }
}

// ---- ramps and splits ----------------------------------------------------------------------------

#[test]
fn ramps_and_splits_all_types() {
    // One node per (family, type); values and center are interface inputs, texcoord the UV0
    // stream (left unconnected) for half of the nodes and an interface input for the other half.
    let mut nodes = Vec::new();
    let mut outs = Vec::new();
    let mut inputs: Vec<(String, &str)> = vec![("center".into(), "float"), ("uv".into(), "vector2")];
    for t in TYPES {
        inputs.push((format!("a_{t}"), t));
        inputs.push((format!("b_{t}"), t));
        let (a, b) = (format!("a_{t}"), format!("b_{t}"));
        for (fam, first, second, split) in [("ramplr", "valuel", "valuer", false), ("ramptb", "valuet", "valueb", false), ("splitlr", "valuel", "valuer", true), ("splittb", "valuet", "valueb", true)] {
            for from_uv in [false, true] {
                let name = format!("{fam}_{t}{}", if from_uv { "_uv" } else { "" });
                let mut ins = vec![(first, t, Src::I(&a)), (second, t, Src::I(&b))];
                if split {
                    ins.push(("center", "float", Src::I("center")));
                }
                if from_uv {
                    ins.push(("texcoord", "vector2", Src::I("uv")));
                }
                nodes.push(node(fam, &name, t, &ins));
                outs.push((name.clone(), t.to_string(), name));
            }
        }
    }
    let inputs_ref: Vec<(&str, &str)> = inputs.iter().map(|(n, t)| (n.as_str(), *t)).collect();
    let k = compile(&graph_doc(&inputs_ref, &nodes, &outs));

    let mut rng = Rng::new(0x7a3b);
    let n = 256;
    let mut rows = Vec::new();
    let mut geom = Vec::new();
    let mut cases = Vec::new();
    for i in 0..n {
        // Coordinates beyond [0, 1] (clamping), exactly on the edges, and exactly on the center.
        let mut tc = [rng.range(-0.5, 1.5), rng.range(-0.5, 1.5)];
        let mut uv = [rng.range(-0.5, 1.5), rng.range(-0.5, 1.5)];
        let mut center = rng.range(-0.2, 1.2);
        match i % 8 {
            0 => center = tc[0],
            1 => center = tc[1],
            2 => {
                center = uv[0];
                uv[1] = center;
            }
            3 => tc = [[0.0, 1.0][i / 8 % 2], [0.0, 1.0][i / 16 % 2]],
            4 => uv = [[0.0, 1.0][i / 8 % 2], [1.0, 0.0][i / 16 % 2]],
            _ => {}
        }
        let mut vals: Vec<(String, Vec<f32>)> = vec![("center".into(), vec![center]), ("uv".into(), uv.to_vec())];
        for t in TYPES {
            vals.push((format!("a_{t}"), random(&mut rng, comps(t), -2.0, 2.0)));
            vals.push((format!("b_{t}"), random(&mut rng, comps(t), -2.0, 2.0)));
        }
        let named: Vec<(&str, Vec<f32>)> = vals.iter().map(|(n, v)| (n.as_str(), v.clone())).collect();
        rows.push(input_row(&k, &named));
        geom.push(Geometry { texcoord: tc, ..Default::default() });
        cases.push((tc, uv, center, vals));
    }
    let got = run(&k, &geom, &rows, vec![]);
    for i in 0..n {
        let (tc, uv, center, vals) = &cases[i];
        let get = |name: String| vals.iter().find(|(n, _)| *n == name).unwrap().1.clone();
        for t in TYPES {
            let (a, b) = (get(format!("a_{t}")), get(format!("b_{t}")));
            for (coords, suffix) in [(tc, ""), (uv, "_uv")] {
                let (u, v) = (coords[0], coords[1]);
                let ctx = format!("point {i}, texcoord ({u}, {v}), center {center}, first {a:?}, second {b:?}");
                // ramplr: valuel at u = 0, valuer at u = 1.
                let want = lerp(&a, &b, u.clamp(0.0, 1.0));
                assert_close(&format!("ramplr {t}{suffix}, {ctx}"), out(&k, &got[i], &format!("ramplr_{t}{suffix}")), &want, 1e-5);
                // ramptb: first input valuet at v = 1, second valueb at v = 0.
                let want = lerp(&b, &a, v.clamp(0.0, 1.0));
                assert_close(&format!("ramptb {t}{suffix}, {ctx}"), out(&k, &got[i], &format!("ramptb_{t}{suffix}")), &want, 1e-5);
                // splitlr: valuer where u >= center.
                let want = if u >= *center { &b } else { &a };
                assert_close(&format!("splitlr {t}{suffix}, {ctx}"), out(&k, &got[i], &format!("splitlr_{t}{suffix}")), want, 0.0);
                // splittb: valuet (first) where v >= center.
                let want = if v >= *center { &a } else { &b };
                assert_close(&format!("splittb {t}{suffix}, {ctx}"), out(&k, &got[i], &format!("splittb_{t}{suffix}")), want, 0.0);
            }
        }
    }
}

// ---- geometric ---------------------------------------------------------------------------------

fn normalize(v: [f32; 3]) -> Vec<f32> {
    let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    if l > 0.0 {
        v.iter().map(|x| x / l).collect()
    } else {
        vec![0.0; 3]
    }
}

fn cross(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

#[test]
fn geometric_all_spaces() {
    let mut nodes = Vec::new();
    let mut outs = Vec::new();
    for tag in ["position", "normal", "tangent", "bitangent"] {
        for space in ["model", "object", "world", ""] {
            let name = format!("{tag}_{}", if space.is_empty() { "default" } else { space });
            let ins: Vec<(&str, &str, Src)> = if space.is_empty() { vec![] } else { vec![("space", "string", Src::V(space))] };
            nodes.push(node(tag, &name, "vector3", &ins));
            outs.push((name.clone(), "vector3".to_string(), name));
        }
    }
    nodes.push(node("texcoord", "tc2", "vector2", &[]));
    nodes.push(node("texcoord", "tc3", "vector3", &[]));
    nodes.push(node("texcoord", "tc2_index", "vector2", &[("index", "integer", Src::V("0"))]));
    outs.push(("tc2".into(), "vector2".into(), "tc2".into()));
    outs.push(("tc3".into(), "vector3".into(), "tc3".into()));
    outs.push(("tc2_index".into(), "vector2".into(), "tc2_index".into()));
    let k = compile(&graph_doc(&[], &nodes, &outs));

    let mut rng = Rng::new(0x6e0);
    let n = 256;
    let mut geom = Vec::new();
    for i in 0..n {
        let v3 = |rng: &mut Rng, lo: f32, hi: f32| [rng.range(lo, hi), rng.range(lo, hi), rng.range(lo, hi)];
        let mut g = Geometry {
            texcoord: [rng.range(-2.0, 3.0), rng.range(-2.0, 3.0)],
            position: v3(&mut rng, -100.0, 100.0),
            // Unnormalized streams: the nodes normalize.
            normal: v3(&mut rng, -3.0, 3.0),
            tangent: v3(&mut rng, -3.0, 3.0),
        };
        if i % 32 == 0 {
            // A missing tangent stream: tangent and bitangent are zero, not NaN.
            g.tangent = [0.0; 3];
        }
        geom.push(g);
    }
    let rows = vec![Vec::new(); n];
    let got = run(&k, &geom, &rows, vec![]);
    for i in 0..n {
        let g = &geom[i];
        let ctx = format!("point {i}, {g:?}");
        for space in ["model", "object", "world", "default"] {
            assert_close(&format!("position {space}, {ctx}"), out(&k, &got[i], &format!("position_{space}")), &g.position, 0.0);
            assert_close(&format!("normal {space}, {ctx}"), out(&k, &got[i], &format!("normal_{space}")), &normalize(g.normal), 1e-5);
            assert_close(&format!("tangent {space}, {ctx}"), out(&k, &got[i], &format!("tangent_{space}")), &normalize(g.tangent), 1e-5);
            let b = normalize(cross(normalize(g.normal).try_into().unwrap(), normalize(g.tangent).try_into().unwrap()));
            assert_close(&format!("bitangent {space}, {ctx}"), out(&k, &got[i], &format!("bitangent_{space}")), &b, 1e-5);
        }
        assert_close(&format!("texcoord vector2, {ctx}"), out(&k, &got[i], "tc2"), &g.texcoord, 0.0);
        assert_close(&format!("texcoord vector2 index 0, {ctx}"), out(&k, &got[i], "tc2_index"), &g.texcoord, 0.0);
        assert_close(&format!("texcoord vector3, {ctx}"), out(&k, &got[i], "tc3"), &[g.texcoord[0], g.texcoord[1], 0.0], 0.0);
    }
}


/// A port of MaterialX's `mx_flake` (stdlib genglsl lib/mx_flake.glsl) in f32, the reference
/// for `flake3d`: (id, rand, presence, flakenormal) with N = +z, T = +x, B = +y.
fn flake_reference(size: f32, roughness: f32, coverage: f32, position: [f32; 3]) -> (i32, f32, f32, [f32; 3]) {
    let hash = |seed: u32, i: u32| (i ^ seed).wrapping_mul(1075385539);
    let xorshift = |mut s: u32| {
        s ^= s << 13;
        s ^= s >> 17;
        s ^= s << 5;
        s
    };
    let to01 = |x: u32| x as f32 / 4294967295.0f32;
    let x = coverage.clamp(0.0, 1.0);
    let probability = (-26.19771808 * x * x + 26.39663835 * x) / (85.53857017 * x * x * x - 102.35069432 * x * x - 101.42634862 * x + 118.45082288);
    let d = 1.5 / 3f32.sqrt();
    let p = position.map(|c| c / size);
    let base = p.map(f32::floor);
    let (mut best, mut best_seed) = (0.0f32, 0u32);
    for i in -1..2i32 {
        for j in -1..2i32 {
            for k in -1..2i32 {
                let cell = [base[0] as i32 + i, base[1] as i32 + j, base[2] as i32 + k];
                let mut seed = xorshift(hash(hash(hash(0, cell[0] as u32), cell[1] as u32), cell[2] as u32));
                if to01(seed) > probability {
                    continue;
                }
                seed = xorshift(seed);
                let priority = to01(seed);
                let pp = [0, 1, 2].map(|c| p[c] - (base[c] + [i, j, k][c] as f32 + 0.5));
                if priority < best || pp.iter().map(|v| v * v).sum::<f32>() >= d * d * 4.0 {
                    continue;
                }
                let mut rot = [0.0f32; 3];
                for r in rot.iter_mut() {
                    seed = xorshift(seed);
                    *r = to01(seed);
                }
                let (theta, phi, z) = (std::f32::consts::TAU * rot[0], std::f32::consts::TAU * rot[1], rot[2] * 2.0);
                let (vx, vy, vz) = (phi.sin() * z.sqrt(), phi.cos() * z.sqrt(), (2.0 - z).sqrt());
                let (st, ct) = (theta.sin(), theta.cos());
                let (sx, sy) = (vx * st - vy * st, vx * ct + vy * ct);
                // Column-major, as GLSL's mat3(…) and WGSL's mat3x3(c0, c1, c2).
                let cols = [[vx * sx - st, vx * sy - st, vx * vz], [vy * sx + ct, vy * sy - ct, vy * vz], [vz * sx, vz * sy, 1.0 - z]];
                let r = [0, 1, 2].map(|row| cols[0][row] * pp[0] + cols[1][row] * pp[1] + cols[2][row] * pp[2]);
                if r.iter().all(|v| v.abs() <= d) {
                    best = priority;
                    best_seed = seed;
                }
            }
        }
    }
    if best <= 0.0 {
        return (0, 0.0, 0.0, [0.0, 0.0, 1.0]);
    }
    let xi0 = to01(best_seed);
    let s1 = xorshift(best_seed);
    let xi1 = to01(s1);
    let s2 = xorshift(s1);
    let phi = std::f32::consts::TAU * xi0;
    let tan_theta = roughness * roughness * xi1.sqrt() / (1.0 - xi1).sqrt();
    let sin_theta = tan_theta / (1.0 + tan_theta * tan_theta).sqrt();
    let cos_theta = (1.0 - sin_theta * sin_theta).sqrt();
    let n = [phi.cos() * sin_theta, phi.sin() * sin_theta, cos_theta];
    let len = n.iter().map(|v| v * v).sum::<f32>().sqrt();
    (s2 as i32, to01(s2), best, n.map(|v| v / len))
}

/// `flake3d` against the port of MaterialX's GLSL: the same flake (id, rand, presence) at
/// ≥ 99 % of 4,096 seeded points (the rest sit on a flake's edge, where f32 rounding of the
/// rotation may differ between the GPU and the port), its normal within 1e-4; and the covered
/// fraction rises with `coverage`, with no flake at coverage 0.
#[test]
fn flake3d_matches_materialx_flake_noise() {
    let k = compile(
        r#"<materialx version="1.39"><nodegraph name="g">
        <input name="size" type="float" value="0.1"/><input name="rough" type="float" value="0.1"/>
        <input name="cov" type="float" value="0.5"/><input name="p" type="vector3" value="0,0,0"/>
        <flake3d name="f" type="multioutput">
          <input name="size" type="float" interfacename="size"/><input name="roughness" type="float" interfacename="rough"/>
          <input name="coverage" type="float" interfacename="cov"/><input name="position" type="vector3" interfacename="p"/>
        </flake3d>
        <output name="id" type="integer" nodename="f" output="id"/><output name="rand" type="float" nodename="f" output="rand"/>
        <output name="presence" type="float" nodename="f" output="presence"/><output name="n" type="vector3" nodename="f" output="flakenormal"/>
        </nodegraph></materialx>"#,
    );
    let mut rng = Rng::new(21);
    let mut rows = Vec::new();
    for i in 0..4096 {
        let coverage = [0.0, 0.2, 0.5, 0.9][i % 4];
        rows.push(vec![rng.range(0.02, 0.3), rng.range(0.0, 1.0), coverage, rng.range(-3.0, 3.0), rng.range(-3.0, 3.0), rng.range(-3.0, 3.0)]);
    }
    let out = run(&k, &vec![Geometry::default(); rows.len()], &rows, vec![]);
    let (mut same, mut covered) = (0usize, [0usize; 4]);
    for (i, (o, r)) in out.iter().zip(&rows).enumerate() {
        let (id, rand, presence, n) = flake_reference(r[0], r[1], r[2], [r[3], r[4], r[5]]);
        if o[0] as i64 == id as i64 || (o[0] - id as f32).abs() <= (id as f32).abs() * 1e-7 {
            same += 1;
            let what = format!("point {i}: {r:?}");
            assert_close(&format!("{what}: rand, presence"), &o[1..3], &[rand, presence], 1e-6);
            assert_close(&format!("{what}: flakenormal"), &o[3..6], &n, 1e-4);
        }
        if o[2] > 0.0 {
            covered[i % 4] += 1;
        }
    }
    assert!(same * 100 >= out.len() * 99, "the same flake at only {same} of {} points", out.len());
    assert_eq!(covered[0], 0, "coverage 0 has no flakes");
    assert!(covered[1] > 0 && covered[1] < covered[2] && covered[2] < covered[3], "covered points per coverage 0, 0.2, 0.5, 0.9: {covered:?}");
}
