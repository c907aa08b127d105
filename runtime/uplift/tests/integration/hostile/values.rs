//! Hostile inputs: values (issue 46). Every number is checked where it enters — a rule's ranges
//! and distributions, a glTF's transforms, positions and factors, a document's PBR inputs, an
//! eval CSV's cells — with a positioned error; no output holds a non-finite number or a `null`;
//! fractal noise stays finite for any octave count on both engines.

use crate::common::cli::{repo, s, temp_dir, uplift};
use std::path::{Path, PathBuf};

const SCOPE: &str = "hostile-values";

fn copper() -> PathBuf {
    repo().join("tests/hostile/outputs/copper.mtlx")
}

fn enhance(input: &Path, out: &Path, extra: &[&str]) -> (i32, String) {
    let mut args = vec!["enhance", s(input), "--resolution", "8x8", "--mask-size", "16", "-o", s(out)];
    args.extend_from_slice(extra);
    let (code, _, stderr) = uplift(&args);
    (code, stderr)
}

/// examples/rules/wet.mtlx with `from` replaced by `to` (once), written as `dir/wet.mtlx`.
fn wet_with(dir: &Path, from: &str, to: &str) -> PathBuf {
    let wet = std::fs::read_to_string(repo().join("examples/rules/wet.mtlx")).unwrap();
    assert!(wet.contains(from), "wet.mtlx has no `{from}`");
    let path = dir.join("wet.mtlx");
    std::fs::write(&path, wet.replacen(from, to, 1)).unwrap();
    path
}

#[test]
fn rule_ranges_and_distributions_are_checked_where_the_rule_is_read() {
    let root = temp_dir(SCOPE, "rules");
    let cases = [
        ("uimin=\"0.4\" uimax=\"1.0\"", "uimin=\"0.4\" uimax=\"1e39\"", "uimax `1e39`, outside ±1e6"),
        ("uimin=\"0.4\" uimax=\"1.0\"", "uimin=\"-1e30\" uimax=\"1e30\"", "uimin `-1e30`, outside ±1e6"),
        ("uplift_distribution=\"normal(1.5, 0.08)\"", "uplift_distribution=\"normal(nan, 0.08)\"", "is not `normal(MEAN, SD)`"),
    ];
    for (from, to, want) in cases {
        let rule = wet_with(&root, from, to);
        let out = root.join("out");
        let (code, stderr) = enhance(&copper(), &out, &["--rule", s(&rule)]);
        assert_eq!(code, 1, "{to}: {stderr}");
        assert!(stderr.contains(&format!("{}:", rule.display())) && stderr.contains(want), "{to}: expected `{want}` at the rule's line: {stderr}");
        assert!(!out.exists(), "{to}: an output was written");
    }
    std::fs::remove_dir_all(&root).unwrap();
}

/// A glTF of one triangle (positions from `mesh.bin`, which the test writes), node `node`.
fn triangle_gltf(node: &str, material: &str) -> String {
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{node}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"TEXCOORD_0":1}},"material":0}}]}}],
"materials":[{material}],
"buffers":[{{"uri":"mesh.bin","byteLength":60}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":24}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3"}},{{"bufferView":1,"componentType":5126,"count":3,"type":"VEC2"}}]}}"#
    )
}

fn mesh(positions: [f32; 9]) -> Vec<u8> {
    mesh_with(positions, [0.0, 0.0, 1.0, 0.0, 0.0, 1.0])
}

fn mesh_with(positions: [f32; 9], uvs: [f32; 6]) -> Vec<u8> {
    positions.iter().chain(&uvs).flat_map(|x| x.to_le_bytes()).collect()
}

#[test]
fn gltf_transforms_positions_and_factors_are_checked_where_the_asset_is_read() {
    let root = temp_dir(SCOPE, "gltf");
    let good = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0];
    let plain = r#"{"name":"m"}"#;
    let cases: Vec<([f32; 9], String, String, &str)> = vec![
        (good, r#"{"mesh":0,"scale":[1e30,1e30,1e30]}"#.into(), plain.into(), "after its node's transform, past ±1e9"),
        (good, r#"{"mesh":0,"matrix":[1e300,0,0,0,0,1,0,0,0,0,1,0,0,0,0,1]}"#.into(), plain.into(), "node 0: its transform is not finite"),
        ([f32::NAN, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0], r#"{"mesh":0}"#.into(), plain.into(), "POSITION of vertex 0 is not finite"),
        (good, r#"{"mesh":0}"#.into(), r#"{"name":"m","pbrMetallicRoughness":{"metallicFactor":-3}}"#.into(), "materials[0] (`m`): pbrMetallicRoughness.metallicFactor `-3` is outside 0..1"),
        (good, r#"{"mesh":0}"#.into(), r#"{"name":"m","pbrMetallicRoughness":{"baseColorFactor":[50,0.5,0.5,1]}}"#.into(), "pbrMetallicRoughness.baseColorFactor `50` is outside 0..1"),
    ];
    // A NaN texture coordinate (found by `cargo fuzz run gltf`: it reached the world triangles
    // the renderer and export read).
    let nan_uv = mesh_with(good, [0.0, 0.0, f32::NAN, 0.0, 0.0, 1.0]);
    let cases: Vec<(Vec<u8>, String, String, &str)> = cases
        .into_iter()
        .map(|(p, n, m, w)| (mesh(p), n, m, w))
        .chain([(nan_uv, r#"{"mesh":0}"#.to_string(), plain.to_string(), "TEXCOORD_0 of vertex 1 is not finite")])
        .collect();
    for (k, (bytes, node, material, want)) in cases.iter().enumerate() {
        let dir = root.join(format!("case{k}"));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("mesh.bin"), bytes).unwrap();
        let file = dir.join("a.gltf");
        std::fs::write(&file, triangle_gltf(node, material)).unwrap();
        let out = root.join(format!("out{k}"));
        let (code, stderr) = enhance(&file, &out, &[]);
        assert_eq!(code, 1, "{node} {material}: {stderr}");
        assert!(stderr.contains(&format!("{}:", file.display())) && stderr.contains(want), "expected `{want}`: {stderr}");
        assert!(!out.exists());
    }
    // The same triangle with sane values enhances, and meta.json holds a finite object size.
    let dir = root.join("sane");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("mesh.bin"), mesh(good)).unwrap();
    std::fs::write(dir.join("a.gltf"), triangle_gltf(r#"{"mesh":0,"scale":[1000,1000,1000]}"#, plain)).unwrap();
    let (code, stderr) = enhance(&dir.join("a.gltf"), &root.join("sane-out"), &[]);
    assert_eq!(code, 0, "{stderr}");
    let meta: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(root.join("sane-out/meta.json")).unwrap()).unwrap();
    let size = meta["object_size"].as_f64().unwrap();
    assert!((size - 1000.0 * 2f64.sqrt()).abs() < 1e-2, "object size {size}");
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn non_physical_pbr_inputs_are_refused_at_their_line() {
    let root = temp_dir(SCOPE, "pbr");
    let copper = std::fs::read_to_string(copper()).unwrap();
    let cases = [
        ("name=\"metallic\" type=\"float\" value=\"1.0\"", "name=\"metallic\" type=\"float\" value=\"-5\"", "m.mtlx:7:", "input `metallic` `-5` is outside 0..1"),
        ("value=\"0.955, 0.637, 0.538\"", "value=\"1e30, 0.637, 0.538\"", "m.mtlx:5:", "input `base_color` `1000000000000000000000000000000` is outside 0..1"),
        ("name=\"roughness\" type=\"float\" value=\"0.35\"", "name=\"roughness\" type=\"float\" value=\"1.5\"", "m.mtlx:6:", "`1.5` is outside 0..1"),
    ];
    for (from, to, at, want) in cases {
        assert!(copper.contains(from));
        let doc = root.join("m.mtlx");
        std::fs::write(&doc, copper.replacen(from, to, 1)).unwrap();
        let (code, stderr) = enhance(&doc, &root.join("out"), &[]);
        assert_eq!(code, 1, "{to}: {stderr}");
        assert!(stderr.contains(at) && stderr.contains(want), "{to}: expected `{at}` … `{want}`: {stderr}");
        assert!(!root.join("out").exists());
    }
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn eval_csv_cells_must_be_finite() {
    let root = temp_dir(SCOPE, "csv");
    let marble = repo().join("examples/marble.mtlx");
    for cell in ["nan", "inf", "-inf", "1e39"] {
        let csv = root.join("in.csv");
        std::fs::write(&csv, format!("scale\n4\n{cell}\n")).unwrap();
        let out = root.join("out.csv");
        let (code, _, stderr) = uplift(&["eval", s(&marble), "--output", "out_roughness", "--engine", "cpu", "--input", s(&csv), "-o", s(&out)]);
        assert_eq!(code, 1, "{cell}: {stderr}");
        assert!(stderr.contains(&format!("{}:3: column `scale`: `{cell}` is not a finite number", csv.display())), "{cell}: {stderr}");
        assert!(!out.exists());
    }
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn fractal3d_stays_finite_for_any_octave_count_on_both_engines() {
    let root = temp_dir(SCOPE, "fractal");
    let doc = root.join("f.mtlx");
    std::fs::write(
        &doc,
        "<?xml version=\"1.0\"?>\n<materialx version=\"1.39\">\n  <nodegraph name=\"g\">\n    <input name=\"octaves\" type=\"integer\" value=\"3\" />\n    <input name=\"p\" type=\"vector3\" value=\"0.3, 0.7, 1.1\" />\n    <fractal3d name=\"n\" type=\"float\">\n      <input name=\"octaves\" type=\"integer\" interfacename=\"octaves\" />\n      <input name=\"position\" type=\"vector3\" interfacename=\"p\" />\n    </fractal3d>\n    <output name=\"out\" type=\"float\" nodename=\"n\" />\n  </nodegraph>\n</materialx>\n",
    )
    .unwrap();
    let csv = root.join("in.csv");
    // 32 octaves: every coordinate is a lattice integer from octave 25 on here, so the sum is
    // converged; 34, 64 and 1000 octaves must give the same value (they were NaN).
    std::fs::write(&csv, "octaves\n32\n34\n64\n1000\n").unwrap();
    for engine in ["cpu", "wgpu"] {
        let out = root.join(format!("{engine}.csv"));
        let (code, _, stderr) = uplift(&["eval", s(&doc), "--output", "g/out", "--engine", engine, "--input", s(&csv), "-o", s(&out)]);
        assert_eq!(code, 0, "{engine}: {stderr}");
        let values: Vec<f32> = std::fs::read_to_string(&out).unwrap().lines().skip(1).map(|l| l.parse().unwrap()).collect();
        assert_eq!(values.len(), 4);
        assert!(values.iter().all(|v| v.is_finite() && v.abs() <= 2.0), "{engine}: {values:?}");
        assert!(values.iter().all(|v| (v - values[0]).abs() <= 1e-5), "{engine}: more octaves than 32 changed the converged sum: {values:?}");
    }
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn fit_never_writes_a_non_finite_fit() {
    // params.exr with a parameter far outside its range: the fit either stays finite (exit 0,
    // no `null` in fit.json) or fails saying so, with nothing written.
    let root = temp_dir(SCOPE, "fit");
    let out = root.join("copper");
    let (code, stderr) = enhance(&copper(), &out, &["--type", "0"]);
    assert_eq!(code, 0, "{stderr}");
    let mut img = uplift_base::exr::read(&out.join("params.exr")).unwrap();
    for c in img.channels.iter_mut().filter(|c| c.name.starts_with("base_color")) {
        c.data.iter_mut().for_each(|x| *x = 1e30);
    }
    uplift_base::exr::write(&out.join("params.exr"), &img, uplift_base::exr::Compression::Zip).unwrap();
    let (code, _, stderr) = uplift(&["fit", s(&out), "--steps", "5"]);
    match code {
        0 => {
            let fit = std::fs::read_to_string(out.join("fit.json")).unwrap();
            assert!(!fit.contains("null") && !fit.contains("NaN"), "{fit}");
        }
        _ => {
            assert!(stderr.contains("diverged") && stderr.contains("nothing written"), "{stderr}");
            assert!(!out.join("fit.json").exists() && !out.join("latent.exr").exists());
        }
    }
    std::fs::remove_dir_all(&root).unwrap();
}
