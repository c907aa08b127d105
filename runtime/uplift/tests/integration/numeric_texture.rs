//! Texture nodes: `image` (all 6 types × every uaddressmode × vaddressmode in
//! constant/clamp/periodic/mirror × filtertype closest/linear, plus the defaults and `cubic`),
//! `tiledimage` (all 6 types), `triplanarprojection` (all 6 types with the default blend and
//! upaxis; upaxis X/Y and a softer blend for one type), and a missing file (every node returns
//! its `default`). Compiled, run on wgpu for 256 seeded points, compared with sampling
//! computed here from the TextureData the test uploads.
//!
//! Reference sampling (MaterialX's GL sampler semantics, as `stdlib/wgsl/texture.wgsl` states):
//! * UV origin at the image's lower-left; TextureData row 0 is the top, so texel space is
//!   st = (u · width, (1 − v) · height), texel centres at (i + 0.5).
//! * closest: texel floor(st); linear: bilinear between the four texel centres around st.
//! * address modes on texel indices: clamp = clamp to edge; periodic = repeat; mirror =
//!   mirrored repeat (period 2n); constant = `default` outside [0, 1] on that axis (inside,
//!   edge texels clamp).
//! * channels: float ← r, vector2 ← rg, color3/vector3 ← rgb, color4/vector4 ← rgba.
//!
//! Tolerances: image 1e-5 (arithmetic). tiledimage and triplanarprojection compute their UVs and
//! weights with division, normalize and power (device precision of a few ulp), so 1e-4; for
//! `closest` there, points within 1e-3 texel of a texel edge are not compared (a one-ulp UV
//! difference may pick the neighbour).

use crate::common;
use crate::graph_kit;

use common::*;
use graph_kit::*;
use std::path::PathBuf;
use uplift_engines::batch::{Geometry, TextureData};
use uplift_compiler::PatternKernel;


const TYPES: [&str; 6] = ["float", "color3", "color4", "vector2", "vector3", "vector4"];
const MODES: [&str; 4] = ["constant", "clamp", "periodic", "mirror"];
const FILTERS: [&str; 2] = ["closest", "linear"];

/// A placeholder file for a texture (the compiler only checks that it exists; the test supplies
/// the pixels). Returns its absolute path. One fixed folder, so runs leave nothing new behind.
fn placeholder(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join("uplift_numeric_texture");
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, b"placeholder: pixels are supplied by the test").unwrap();
    p
}

fn random_texture(rng: &mut Rng, width: u32, height: u32) -> TextureData {
    TextureData { width, height, rgba: (0..width * height * 4).map(|_| rng.range(-1.0, 2.0)).collect() }
}

/// The kernel's textures in binding order, looked up by file.
fn bind(k: &PatternKernel, files: &[(&PathBuf, &TextureData)]) -> Vec<TextureData> {
    k.textures
        .iter()
        .map(|t| files.iter().find(|(p, _)| **p == t.path).unwrap_or_else(|| panic!("unexpected texture {:?}", t.path)).1.clone())
        .collect()
}

fn mode_index(m: &str) -> usize {
    MODES.iter().position(|x| *x == m).unwrap()
}

/// Texel index `i` on an axis of `n` texels under address mode `mode` (index into MODES).
fn address(i: i64, n: i64, mode: usize) -> i64 {
    match mode {
        0 | 1 => i.clamp(0, n - 1),
        2 => i.rem_euclid(n),
        _ => {
            let m = i.rem_euclid(2 * n);
            if m >= n {
                2 * n - 1 - m
            } else {
                m
            }
        }
    }
}

fn texel(t: &TextureData, x: i64, y: i64, um: usize, vm: usize) -> [f32; 4] {
    let (w, h) = (t.width as i64, t.height as i64);
    let (x, y) = (address(x, w, um), address(y, h, vm));
    let k = ((y * w + x) * 4) as usize;
    [t.rgba[k], t.rgba[k + 1], t.rgba[k + 2], t.rgba[k + 3]]
}

/// Is st within `eps` texels of a texel edge on either axis? (For `closest` with computed UVs.)
fn near_edge(t: &TextureData, uv: [f32; 2], eps: f32) -> bool {
    let st = [uv[0] * t.width as f32, (1.0 - uv[1]) * t.height as f32];
    st.iter().any(|s| {
        let f = s - s.floor();
        f < eps || f > 1.0 - eps
    })
}

/// Samples all four channels of `t` at `uv`; `None` where the constant address mode applies
/// the node's default.
fn sample(t: &TextureData, uv: [f32; 2], um: usize, vm: usize, linear: bool) -> Option<[f32; 4]> {
    let (u, v) = (uv[0], uv[1]);
    if (um == 0 && !(0.0..=1.0).contains(&u)) || (vm == 0 && !(0.0..=1.0).contains(&v)) {
        return None;
    }
    let st = [u * t.width as f32, (1.0 - v) * t.height as f32];
    if !linear {
        return Some(texel(t, st[0].floor() as i64, st[1].floor() as i64, um, vm));
    }
    let p = [st[0] - 0.5, st[1] - 0.5];
    let (x0, y0) = (p[0].floor(), p[1].floor());
    let (fx, fy) = (p[0] - x0, p[1] - y0);
    let (x0, y0) = (x0 as i64, y0 as i64);
    let c00 = texel(t, x0, y0, um, vm);
    let c10 = texel(t, x0 + 1, y0, um, vm);
    let c01 = texel(t, x0, y0 + 1, um, vm);
    let c11 = texel(t, x0 + 1, y0 + 1, um, vm);
    Some(std::array::from_fn(|c| {
        let top = c00[c] * (1.0 - fx) + c10[c] * fx;
        let bottom = c01[c] * (1.0 - fx) + c11[c] * fx;
        top * (1.0 - fy) + bottom * fy
    }))
}

/// The node's value: the sample's first `comps(ty)` channels, or `default`.
fn image_value(t: &TextureData, ty: &str, default: &[f32], uv: [f32; 2], um: usize, vm: usize, linear: bool) -> Vec<f32> {
    match sample(t, uv, um, vm, linear) {
        Some(c) => c[..comps(ty)].to_vec(),
        None => default.to_vec(),
    }
}

fn random(rng: &mut Rng, n: usize, lo: f32, hi: f32) -> Vec<f32> {
    (0..n).map(|_| rng.range(lo, hi)).collect()
}

/// Interface inputs `def_<type>` for the six types.
fn default_inputs() -> Vec<(String, &'static str)> {
    TYPES.iter().map(|t| (format!("def_{t}"), *t)).collect()
}

fn default_values(rng: &mut Rng) -> Vec<(String, Vec<f32>)> {
    TYPES.iter().map(|t| (format!("def_{t}"), random(rng, comps(t), -5.0, -3.0))).collect()
}

fn lookup<'a>(vals: &'a [(String, Vec<f32>)], name: &str) -> &'a [f32] {
    &vals.iter().find(|(n, _)| n == name).unwrap_or_else(|| panic!("no value {name}")).1
}

fn named(vals: &[(String, Vec<f32>)]) -> Vec<(&str, Vec<f32>)> {
    vals.iter().map(|(n, v)| (n.as_str(), v.clone())).collect()
}

// ---- image ---------------------------------------------------------------------------------

#[test]
fn image_all_types_address_modes_and_filters() {
    let file = placeholder("image_5x3.exr");
    let f = file.to_str().unwrap();
    let mut nodes = Vec::new();
    let mut outs = Vec::new();
    for t in TYPES {
        let def = format!("def_{t}");
        for um in MODES {
            for vm in MODES {
                for flt in FILTERS {
                    let name = format!("img_{t}_{um}_{vm}_{flt}");
                    nodes.push(node(
                        "image",
                        &name,
                        t,
                        &[
                            ("file", "filename", Src::V(f)),
                            ("default", t, Src::I(&def)),
                            ("uaddressmode", "string", Src::V(um)),
                            ("vaddressmode", "string", Src::V(vm)),
                            ("filtertype", "string", Src::V(flt)),
                        ],
                    ));
                    outs.push((name.clone(), t.to_string(), name));
                }
            }
        }
        // Nodedef defaults: periodic, periodic, linear.
        let name = format!("img_{t}_defaults");
        nodes.push(node("image", &name, t, &[("file", "filename", Src::V(f)), ("default", t, Src::I(&def))]));
        outs.push((name.clone(), t.to_string(), name));
        // cubic: no bicubic path (as MaterialX's GL renderer); sampled as linear.
        let name = format!("img_{t}_cubic");
        nodes.push(node("image", &name, t, &[("file", "filename", Src::V(f)), ("default", t, Src::I(&def)), ("filtertype", "string", Src::V("cubic"))]));
        outs.push((name.clone(), t.to_string(), name));
    }
    let inputs = default_inputs();
    let inputs_ref: Vec<(&str, &str)> = inputs.iter().map(|(n, t)| (n.as_str(), *t)).collect();
    let k = compile(&graph_doc(&inputs_ref, &nodes, &outs));
    assert_eq!(k.textures.len(), 1, "one file, one binding");

    let mut rng = Rng::new(0x1a6e);
    let tex = random_texture(&mut rng, 5, 3);
    let n = 256;
    let mut geom = Vec::new();
    let mut rows = Vec::new();
    let mut defs = Vec::new();
    for i in 0..n {
        let uv = match i % 8 {
            // Edges and corners of [0, 1]².
            0 => [[0.0, 1.0, 0.5][i / 8 % 3], [1.0, 0.0, 0.25][i / 24 % 3]],
            // Texel edges and centres (u = k/5 within one ulp, v = k/3 likewise).
            1 => [(i / 8 % 11) as f32 / 5.0 - 0.4, (i / 8 % 7) as f32 / 3.0 - 0.3],
            2 => [((i / 8 % 12) as f32 - 3.5) / 5.0, ((i / 8 % 9) as f32 - 2.5) / 3.0],
            _ => [rng.range(-1.5, 2.5), rng.range(-1.5, 2.5)],
        };
        geom.push(Geometry { texcoord: uv, ..Default::default() });
        let d = default_values(&mut rng);
        rows.push(input_row(&k, &named(&d)));
        defs.push(d);
    }
    let textures = bind(&k, &[(&file, &tex)]);
    let got = run(&k, &geom, &rows, textures);
    for i in 0..n {
        let uv = geom[i].texcoord;
        for t in TYPES {
            let d = lookup(&defs[i], &format!("def_{t}"));
            for um in MODES {
                for vm in MODES {
                    for flt in FILTERS {
                        let want = image_value(&tex, t, d, uv, mode_index(um), mode_index(vm), flt == "linear");
                        assert_close(&format!("image {t} u={um} v={vm} {flt}, point {i}, uv {uv:?}"), out(&k, &got[i], &format!("img_{t}_{um}_{vm}_{flt}")), &want, 1e-5);
                    }
                }
            }
            let want = image_value(&tex, t, d, uv, 2, 2, true);
            assert_close(&format!("image {t} defaults, point {i}, uv {uv:?}"), out(&k, &got[i], &format!("img_{t}_defaults")), &want, 1e-5);
            assert_close(&format!("image {t} cubic, point {i}, uv {uv:?}"), out(&k, &got[i], &format!("img_{t}_cubic")), &want, 1e-5);
        }
    }
}

// ---- tiledimage ------------------------------------------------------------------------------

#[test]
fn tiledimage_all_types() {
    let file = placeholder("tiled_4x3.exr");
    let f = file.to_str().unwrap();
    let mut nodes = Vec::new();
    let mut outs = Vec::new();
    let params = ["uvtiling", "uvoffset", "realworldimagesize", "realworldtilesize"];
    for t in TYPES {
        let def = format!("def_{t}");
        for flt in ["closest", "linear", ""] {
            let name = format!("tiled_{t}_{}", if flt.is_empty() { "default" } else { flt });
            let mut ins = vec![("file", "filename", Src::V(f)), ("default", t, Src::I(&def))];
            for p in params {
                ins.push((p, "vector2", Src::I(p)));
            }
            if !flt.is_empty() {
                ins.push(("filtertype", "string", Src::V(flt)));
            }
            nodes.push(node("tiledimage", &name, t, &ins));
            outs.push((name.clone(), t.to_string(), name));
        }
    }
    let mut inputs = default_inputs();
    for p in params {
        inputs.push((p.to_string(), "vector2"));
    }
    let inputs_ref: Vec<(&str, &str)> = inputs.iter().map(|(n, t)| (n.as_str(), *t)).collect();
    let k = compile(&graph_doc(&inputs_ref, &nodes, &outs));

    let mut rng = Rng::new(0x711e);
    let tex = random_texture(&mut rng, 4, 3);
    let n = 256;
    let mut geom = Vec::new();
    let mut rows = Vec::new();
    let mut cases = Vec::new();
    for _ in 0..n {
        let tc = [rng.range(-1.0, 2.0), rng.range(-1.0, 2.0)];
        geom.push(Geometry { texcoord: tc, ..Default::default() });
        let mut vals = default_values(&mut rng);
        let tiling = random(&mut rng, 2, 0.5, 3.0);
        let offset = random(&mut rng, 2, -1.0, 1.0);
        let rwis = random(&mut rng, 2, 0.5, 2.0);
        let rwts = random(&mut rng, 2, 0.5, 2.0);
        vals.push(("uvtiling".into(), tiling.clone()));
        vals.push(("uvoffset".into(), offset.clone()));
        vals.push(("realworldimagesize".into(), rwis.clone()));
        vals.push(("realworldtilesize".into(), rwts.clone()));
        rows.push(input_row(&k, &named(&vals)));
        // The nodegraph: ((texcoord · uvtiling − uvoffset) / realworldimagesize) · realworldtilesize.
        let uv: [f32; 2] = std::array::from_fn(|c| ((tc[c] * tiling[c] - offset[c]) / rwis[c]) * rwts[c]);
        cases.push((vals, uv));
    }
    let got = run(&k, &geom, &rows, bind(&k, &[(&file, &tex)]));
    let mut skipped = 0;
    for i in 0..n {
        let (vals, uv) = &cases[i];
        for t in TYPES {
            let d = lookup(vals, &format!("def_{t}"));
            let ctx = format!("point {i}, texcoord {:?}, uv {uv:?}", geom[i].texcoord);
            let want = image_value(&tex, t, d, *uv, 2, 2, true);
            assert_close(&format!("tiledimage {t} linear, {ctx}"), out(&k, &got[i], &format!("tiled_{t}_linear")), &want, 1e-4);
            assert_close(&format!("tiledimage {t} (default filter), {ctx}"), out(&k, &got[i], &format!("tiled_{t}_default")), &want, 1e-4);
            if near_edge(&tex, *uv, 1e-3) {
                skipped += 1;
            } else {
                let want = image_value(&tex, t, d, *uv, 2, 2, false);
                assert_close(&format!("tiledimage {t} closest, {ctx}"), out(&k, &got[i], &format!("tiled_{t}_closest")), &want, 1e-5);
            }
        }
    }
    assert!(skipped < 6 * 16, "too many closest samples skipped: {skipped}");
}

// ---- triplanarprojection ------------------------------------------------------------------------

/// The triplanar blend of three samples. `upaxis` 0/1/2 (X/Y/Z), `blend` in (0, 1].
fn triplanar([tx, ty_, tz]: [&TextureData; 3], ty: &str, default: &[f32], pos: [f32; 3], normal: [f32; 3], upaxis: i32, blend: f32) -> Vec<f32> {
    let [x, y, z] = pos;
    let uv_x = if upaxis == 2 { [y, z] } else { [z, y] };
    let uv_y = if upaxis == 0 { [z, x] } else { [x, z] };
    let uv_z = if upaxis == 0 { [-y, x] } else { [x, y] };
    let len = (normal.iter().map(|c| (*c as f64).powi(2)).sum::<f64>()).sqrt();
    let a: Vec<f64> = normal.iter().map(|c| (*c as f64 / len).abs()).collect();
    let s: f64 = a.iter().sum();
    let e = 1.0 / (blend.clamp(0.03, 1.0) as f64);
    let w: Vec<f64> = a.iter().map(|c| (c / s).powf(e)).collect();
    let ws: f64 = w.iter().sum();
    let w: Vec<f64> = w.iter().map(|c| c / ws).collect();
    let sx = image_value(tx, ty, default, uv_x, 2, 2, true);
    let sy = image_value(ty_, ty, default, uv_y, 2, 2, true);
    let sz = image_value(tz, ty, default, uv_z, 2, 2, true);
    (0..comps(ty)).map(|c| (sx[c] as f64 * w[0] + sy[c] as f64 * w[1] + sz[c] as f64 * w[2]) as f32).collect()
}

#[test]
fn triplanarprojection_all_types() {
    let (fx, fy, fz) = (placeholder("tri_x.exr"), placeholder("tri_y.exr"), placeholder("tri_z.exr"));
    let files = [("filex", fx.to_str().unwrap()), ("filey", fy.to_str().unwrap()), ("filez", fz.to_str().unwrap())];
    let mut nodes = Vec::new();
    let mut outs = Vec::new();
    for t in TYPES {
        let def = format!("def_{t}");
        let mut ins: Vec<(&str, &str, Src)> = files.iter().map(|(n, f)| (*n, "filename", Src::V(f))).collect();
        ins.push(("default", t, Src::I(&def)));
        let name = format!("tri_{t}");
        nodes.push(node("triplanarprojection", &name, t, &ins));
        outs.push((name.clone(), t.to_string(), name));
    }
    // Other up axes and a softer blend, on color3.
    for (suffix, upaxis, blend) in [("up_x", "0", None), ("up_y", "1", None), ("blend", "2", Some("blend"))] {
        let mut ins: Vec<(&str, &str, Src)> = files.iter().map(|(n, f)| (*n, "filename", Src::V(f))).collect();
        ins.push(("default", "color3", Src::I("def_color3")));
        ins.push(("upaxis", "integer", Src::V(upaxis)));
        if let Some(b) = blend {
            ins.push(("blend", "float", Src::I(b)));
        }
        let name = format!("tri_color3_{suffix}");
        nodes.push(node("triplanarprojection", &name, "color3", &ins));
        outs.push((name.clone(), "color3".to_string(), name));
    }
    let mut inputs = default_inputs();
    inputs.push(("blend".into(), "float"));
    let inputs_ref: Vec<(&str, &str)> = inputs.iter().map(|(n, t)| (n.as_str(), *t)).collect();
    let k = compile(&graph_doc(&inputs_ref, &nodes, &outs));
    assert_eq!(k.textures.len(), 3, "three files, three bindings");

    let mut rng = Rng::new(0x3a9e);
    // Different sizes, so a binding mix-up cannot go unnoticed.
    let (tx, ty, tz) = (random_texture(&mut rng, 5, 3), random_texture(&mut rng, 4, 4), random_texture(&mut rng, 3, 5));
    let n = 256;
    let mut geom = Vec::new();
    let mut rows = Vec::new();
    let mut cases = Vec::new();
    for _ in 0..n {
        let v3 = |rng: &mut Rng, lo: f32, hi: f32| [rng.range(lo, hi), rng.range(lo, hi), rng.range(lo, hi)];
        let g = Geometry { position: v3(&mut rng, -3.0, 3.0), normal: v3(&mut rng, -2.0, 2.0), ..Default::default() };
        geom.push(g);
        let mut vals = default_values(&mut rng);
        let blend = rng.range(0.2, 1.0);
        vals.push(("blend".into(), vec![blend]));
        rows.push(input_row(&k, &named(&vals)));
        cases.push((vals, blend));
    }
    let got = run(&k, &geom, &rows, bind(&k, &[(&fx, &tx), (&fy, &ty), (&fz, &tz)]));
    for i in 0..n {
        let (vals, blend) = &cases[i];
        let g = &geom[i];
        let ctx = format!("point {i}, position {:?}, normal {:?}", g.position, g.normal);
        for t in TYPES {
            let d = lookup(vals, &format!("def_{t}"));
            let want = triplanar([&tx, &ty, &tz], t, d, g.position, g.normal, 2, 1.0);
            assert_close(&format!("triplanarprojection {t}, {ctx}"), out(&k, &got[i], &format!("tri_{t}")), &want, 1e-4);
        }
        let d = lookup(vals, "def_color3");
        for (suffix, upaxis, b) in [("up_x", 0, 1.0), ("up_y", 1, 1.0), ("blend", 2, *blend)] {
            let want = triplanar([&tx, &ty, &tz], "color3", d, g.position, g.normal, upaxis, b);
            assert_close(&format!("triplanarprojection color3 {suffix} (blend {b}), {ctx}"), out(&k, &got[i], &format!("tri_color3_{suffix}")), &want, 1e-4);
        }
    }
}

/// A node tag and its inputs.
type NodeSpec<'a> = (&'a str, Vec<(&'a str, &'a str, Src<'a>)>);

// ---- missing file ------------------------------------------------------------------------------

#[test]
fn missing_file_returns_default() {
    let missing = std::env::temp_dir().join("uplift_numeric_texture/absent/none.exr");
    assert!(!missing.exists());
    let f = missing.to_str().unwrap();
    let mut nodes = Vec::new();
    let mut outs = Vec::new();
    for t in TYPES {
        let def = format!("def_{t}");
        let variants: [NodeSpec; 4] = [
            ("image", vec![("file", "filename", Src::V(f)), ("default", t, Src::I(&def))]),
            ("image", vec![("file", "filename", Src::V(f)), ("default", t, Src::I(&def)), ("uaddressmode", "string", Src::V("clamp")), ("filtertype", "string", Src::V("closest"))]),
            ("tiledimage", vec![("file", "filename", Src::V(f)), ("default", t, Src::I(&def))]),
            ("triplanarprojection", vec![("filex", "filename", Src::V(f)), ("filey", "filename", Src::V(f)), ("filez", "filename", Src::V(f)), ("default", t, Src::I(&def))]),
        ];
        for (j, (tag, ins)) in variants.into_iter().enumerate() {
            let name = format!("{tag}_{t}_{j}");
            nodes.push(node(tag, &name, t, &ins));
            outs.push((name.clone(), t.to_string(), name));
        }
    }
    let inputs = default_inputs();
    let inputs_ref: Vec<(&str, &str)> = inputs.iter().map(|(n, t)| (n.as_str(), *t)).collect();
    let k = compile(&graph_doc(&inputs_ref, &nodes, &outs));
    assert!(k.textures.is_empty(), "a missing file binds no texture");
    let mut rng = Rng::new(0x0);
    let n = 256;
    let mut geom = Vec::new();
    let mut rows = Vec::new();
    let mut defs = Vec::new();
    for _ in 0..n {
        geom.push(Geometry {
            texcoord: [rng.range(-2.0, 2.0), rng.range(-2.0, 2.0)],
            position: [rng.range(-2.0, 2.0), rng.range(-2.0, 2.0), rng.range(-2.0, 2.0)],
            normal: [rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(0.1, 1.0)],
            ..Default::default()
        });
        let d = default_values(&mut rng);
        rows.push(input_row(&k, &named(&d)));
        defs.push(d);
    }
    let got = run(&k, &geom, &rows, vec![]);
    for i in 0..n {
        for t in TYPES {
            let d = lookup(&defs[i], &format!("def_{t}"));
            for (j, tag) in ["image", "image", "tiledimage", "triplanarprojection"].iter().enumerate() {
                let name = format!("{tag}_{t}_{j}");
                // triplanar blends three defaults with weights summing to 1.
                let tol = if *tag == "triplanarprojection" { 1e-5 } else { 0.0 };
                assert_close(&format!("{name} (missing file), point {i}"), out(&k, &got[i], &name), d, tol);
            }
        }
    }
}

