//! `uplift eval` and `uplift compile --target spirv|msl|glsl|hlsl|rust` as a user meets them: CSV
//! rows in (geometric columns and interface inputs, missing columns at their defaults), CSV out
//! with exact values; bad CSV, closure outputs, textures (PNG decoded, sRGB converted, missing
//! files an error unless allowed), both engines writing the same CSV, and naga's other backends
//! writing files. Errors exit 1 with a message naming the file, the line and the column, never a
//! panic.

use std::path::{Path, PathBuf};

use crate::common::cli::{repo, s, uplift};

fn temp_dir(name: &str) -> PathBuf {
    crate::common::cli::temp_dir("cli-eval", name)
}

/// A graph with interface inputs (`scale` float, `tint` color3) and geometric reads. Values
/// are chosen so every product is exact in f32.
const GRAPH: &str = r#"<materialx version="1.39">
  <nodegraph name="g">
    <input name="scale" type="float" value="2" />
    <input name="tint" type="color3" value="0.25, 0.5, 1" />
    <position name="p" type="vector3" />
    <texcoord name="uv" type="vector2" />
    <normal name="n" type="vector3" />
    <tangent name="t" type="vector3" />
    <multiply name="ps" type="vector3">
      <input name="in1" type="vector3" nodename="p" />
      <input name="in2" type="float" interfacename="scale" />
    </multiply>
    <extract name="u" type="float">
      <input name="in" type="vector2" nodename="uv" />
      <input name="index" type="integer" value="0" />
    </extract>
    <extract name="v" type="float">
      <input name="in" type="vector2" nodename="uv" />
      <input name="index" type="integer" value="1" />
    </extract>
    <multiply name="tu" type="color3">
      <input name="in1" type="color3" interfacename="tint" />
      <input name="in2" type="float" nodename="u" />
    </multiply>
    <add name="sv" type="float">
      <input name="in1" type="float" interfacename="scale" />
      <input name="in2" type="float" nodename="v" />
    </add>
    <output name="pos_out" type="vector3" nodename="ps" />
    <output name="col" type="color3" nodename="tu" />
    <output name="sum" type="float" nodename="sv" />
    <output name="n_out" type="vector3" nodename="n" />
    <output name="t_out" type="vector3" nodename="t" />
  </nodegraph>
</materialx>
"#;

/// Writes GRAPH and `csv` into a fresh folder; returns (document, inputs, output path).
fn setup(name: &str, csv: &str) -> (PathBuf, PathBuf, PathBuf) {
    let dir = temp_dir(name);
    let doc = dir.join("graph.mtlx");
    std::fs::write(&doc, GRAPH).unwrap();
    let input = dir.join("inputs.csv");
    std::fs::write(&input, csv).unwrap();
    (doc, input, dir.join("out.csv"))
}

/// Runs `eval` and returns the output CSV (header, rows), asserting success.
fn eval_ok(doc: &Path, output: &str, input: &Path, out: &Path) -> (Vec<String>, Vec<Vec<f32>>) {
    let (code, stdout, stderr) = uplift(&["eval", s(doc), "--output", output, "--engine", "wgpu", "--input", s(input), "-o", s(out)]);
    assert_eq!(code, 0, "{stderr}");
    assert!(stdout.contains("out.csv"), "{stdout}");
    read_csv(out)
}

fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<f32>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines.map(|l| l.split(',').map(|c| c.parse().unwrap_or_else(|_| panic!("{c:?} in {text}"))).collect()).collect();
    (header, rows)
}

fn eval_err(doc: &Path, output: &str, input: &Path, out: &Path) -> String {
    let _ = std::fs::remove_file(out);
    let (code, _, stderr) = uplift(&["eval", s(doc), "--output", output, "--input", s(input), "-o", s(out)]);
    assert_eq!(code, 1, "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(!out.exists(), "no output file on error");
    stderr
}

#[test]
fn interface_inputs_and_geometry_columns() {
    let rows: [[f32; 9]; 3] = [
        // texcoord_x, texcoord_y, position_x, position_y, position_z, scale, tint_r, tint_g, tint_b
        [0.5, 0.25, 1.0, 2.0, 3.0, 0.5, 1.0, 2.0, 4.0],
        [0.75, 0.125, -1.5, 0.0, 8.0, 3.0, 0.5, 0.25, 0.125],
        [0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    ];
    let mut csv = String::from("texcoord_x, texcoord_y,position_x,position_y,position_z,scale,tint_r,tint_g,tint_b\n");
    for r in &rows {
        csv.push_str(&r.iter().map(|v| v.to_string()).collect::<Vec<_>>().join(","));
        csv.push('\n');
    }
    let (doc, input, out) = setup("values", &csv);

    let (header, got) = eval_ok(&doc, "pos_out", &input, &out);
    assert_eq!(header, ["g/pos_out_x", "g/pos_out_y", "g/pos_out_z"]);
    let want: Vec<Vec<f32>> = rows.iter().map(|r| vec![r[2] * r[5], r[3] * r[5], r[4] * r[5]]).collect();
    assert_eq!(got, want);

    let (header, got) = eval_ok(&doc, "g/col", &input, &out);
    assert_eq!(header, ["g/col_r", "g/col_g", "g/col_b"]);
    let want: Vec<Vec<f32>> = rows.iter().map(|r| vec![r[6] * r[0], r[7] * r[0], r[8] * r[0]]).collect();
    assert_eq!(got, want);

    let (header, got) = eval_ok(&doc, "sum", &input, &out);
    assert_eq!(header, ["g/sum"], "a float output is just its name");
    let want: Vec<Vec<f32>> = rows.iter().map(|r| vec![r[5] + r[1]]).collect();
    assert_eq!(got, want);
}

#[test]
fn missing_columns_take_defaults() {
    let (doc, input, out) = setup("defaults", "position_x\n1.5\n-2\n");
    let (_, got) = eval_ok(&doc, "pos_out", &input, &out);
    assert_eq!(got, vec![vec![3.0, 0.0, 0.0], vec![-4.0, 0.0, 0.0]], "scale defaults to 2, position y/z to 0");
    let (_, got) = eval_ok(&doc, "col", &input, &out);
    assert_eq!(got, vec![vec![0.0; 3]; 2], "texcoord defaults to (0, 0)");
    let (_, got) = eval_ok(&doc, "sum", &input, &out);
    assert_eq!(got, vec![vec![2.0]; 2]);
    let (_, got) = eval_ok(&doc, "n_out", &input, &out);
    assert_eq!(got, vec![vec![0.0, 0.0, 1.0]; 2], "normal defaults to +z");
    let (_, got) = eval_ok(&doc, "t_out", &input, &out);
    assert_eq!(got, vec![vec![1.0, 0.0, 0.0]; 2], "tangent defaults to +x");

    // The tint default with a texcoord given, and an empty table (header only).
    std::fs::write(&input, "texcoord_x\n0.5\n").unwrap();
    let (_, got) = eval_ok(&doc, "col", &input, &out);
    assert_eq!(got, vec![vec![0.125, 0.25, 0.5]]);
    std::fs::write(&input, "texcoord_x\n").unwrap();
    let (header, got) = eval_ok(&doc, "col", &input, &out);
    assert_eq!((header.len(), got.len()), (3, 0));
}

#[test]
fn bad_csv_is_a_positioned_error() {
    let (doc, input, out) = setup("bad", "position_x,bogus\n1,2\n");
    let e = eval_err(&doc, "pos_out", &input, &out);
    assert!(e.contains("inputs.csv:1: unknown column `bogus`") && e.contains("scale, tint_b, tint_g, tint_r"), "{e}");

    std::fs::write(&input, "position_x,scale\n1,2\n3,abc\n").unwrap();
    let e = eval_err(&doc, "pos_out", &input, &out);
    assert!(e.contains("inputs.csv:3: column `scale`: `abc` is not a number"), "{e}");

    std::fs::write(&input, "position_x,scale\n1,2\n\n3\n").unwrap();
    let e = eval_err(&doc, "pos_out", &input, &out);
    assert!(e.contains("inputs.csv:4: 1 fields, but the header has 2 columns: column `scale` has no value"), "{e}");

    std::fs::write(&input, "position_x,scale\n1,2,7\n").unwrap();
    let e = eval_err(&doc, "pos_out", &input, &out);
    assert!(e.contains("inputs.csv:2: 3 fields") && e.contains("after column `scale`"), "{e}");

    // A suffix that does not fit the input's type is an unknown column too.
    std::fs::write(&input, "tint_x\n1\n").unwrap();
    let e = eval_err(&doc, "pos_out", &input, &out);
    assert!(e.contains("inputs.csv:1: unknown column `tint_x`"), "{e}");

    let e = eval_err(&doc, "pos_out", &input.with_file_name("absent.csv"), &out);
    assert!(e.contains("absent.csv: cannot read"), "{e}");
}

#[test]
fn closure_outputs_are_clear_errors_on_both_engines() {
    let dir = temp_dir("closure");
    let doc = dir.join("shader.mtlx");
    std::fs::write(
        &doc,
        r#"<materialx version="1.39">
  <nodegraph name="g">
    <constant name="c" type="float"><input name="value" type="float" value="1" /></constant>
    <output name="shader" type="surfaceshader" />
    <output name="f" type="float" nodename="c" />
  </nodegraph>
</materialx>
"#,
    )
    .unwrap();
    let input = dir.join("in.csv");
    std::fs::write(&input, "position_x\n1\n").unwrap();
    let out = dir.join("out.csv");
    let e = eval_err(&doc, "shader", &input, &out);
    assert!(e.contains("output `g/shader` is surfaceshader, not a pattern value"), "{e}");
    assert!(e.contains("cannot evaluate output `shader`"), "{e}");

    let (code, _, stderr) = uplift(&["eval", s(&doc), "--output", "shader", "--engine", "cpu", "--input", s(&input), "-o", s(&out)]);
    assert_eq!(code, 1);
    assert!(stderr.contains("output `g/shader` is surfaceshader, not a pattern value"), "{stderr}");
    assert!(!out.exists(), "no output file on error");
}

/// The sRGB EOTF, written out here independently of the runtime.
fn srgb(v: f64) -> f64 {
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

fn image_doc(file: &str, colorspace: Option<&str>) -> String {
    let cs = colorspace.map(|c| format!(" colorspace=\"{c}\"")).unwrap_or_default();
    format!(
        r#"<materialx version="1.39">
  <nodegraph name="g">
    <image name="im" type="color4">
      <input name="file" type="filename" value="{file}"{cs} />
      <input name="default" type="color4" value="0.125, 0.25, 0.5, 0.75" />
    </image>
    <output name="out" type="color4" nodename="im" />
  </nodegraph>
</materialx>
"#
    )
}

#[test]
fn image_textures_are_loaded_and_converted() {
    let dir = temp_dir("image");
    // 3 × 2 texels, row 0 at the top.
    let (w, h) = (3u32, 2u32);
    let px = |x: u32, y: u32| [(40 * x + 10) as u8, (100 * y + 30) as u8, (17 * (x + 3 * y) + 5) as u8, (255 - 50 * x - 20 * y) as u8];
    let img = image::RgbaImage::from_fn(w, h, |x, y| image::Rgba(px(x, y)));
    img.save(dir.join("tex.png")).unwrap();
    // One row per texel centre: uv origin at the lower left.
    let mut csv = String::from("texcoord_x,texcoord_y\n");
    let mut texels = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let u = (x as f32 + 0.5) / w as f32;
            let v = 1.0 - (y as f32 + 0.5) / h as f32;
            csv.push_str(&format!("{u},{v}\n"));
            texels.push(px(x, y));
        }
    }
    let input = dir.join("uv.csv");
    std::fs::write(&input, csv).unwrap();
    let out = dir.join("out.csv");
    for colorspace in [None, Some("lin_rec709"), Some("srgb_texture")] {
        let doc = dir.join("img.mtlx");
        std::fs::write(&doc, image_doc("tex.png", colorspace)).unwrap();
        let (header, got) = eval_ok(&doc, "out", &input, &out);
        assert_eq!(header, ["g/out_r", "g/out_g", "g/out_b", "g/out_a"]);
        assert_eq!(got.len(), texels.len());
        for (row, texel) in got.iter().zip(&texels) {
            for c in 0..4 {
                let encoded = texel[c] as f64 / 255.0;
                let want = if colorspace == Some("srgb_texture") && c < 3 { srgb(encoded) } else { encoded };
                assert!((row[c] as f64 - want).abs() < 1e-6, "{colorspace:?} channel {c}: got {row:?}, texel {texel:?}");
            }
        }
    }

    // A texture whose file is not an image: a clear error naming the file.
    std::fs::write(dir.join("broken.png"), b"not a png").unwrap();
    let doc = dir.join("broken.mtlx");
    std::fs::write(&doc, image_doc("broken.png", None)).unwrap();
    let e = eval_err(&doc, "out", &input, &out);
    assert!(e.contains("broken.png: cannot decode texture"), "{e}");

    // A missing file is an error naming it and its place...
    let doc = dir.join("missing.mtlx");
    std::fs::write(&doc, image_doc("nowhere.png", Some("srgb_texture"))).unwrap();
    let e = eval_err(&doc, "out", &input, &out);
    assert!(e.contains("missing.mtlx:") && e.contains("texture file `nowhere.png` not found") && e.contains("--allow-missing-textures"), "{e}");
    // ...unless asked for MaterialX's behaviour: the node returns its `default`.
    let (code, _, stderr) = uplift(&["eval", s(&doc), "--output", "out", "--allow-missing-textures", "--input", s(&input), "-o", s(&out)]);
    assert_eq!(code, 0, "{stderr}");
    let (_, got) = read_csv(&out);
    assert_eq!(got, vec![vec![0.125, 0.25, 0.5, 0.75]; texels.len()]);
    // An output that does not read the missing file evaluates as usual.
    let doc = dir.join("missing_elsewhere.mtlx");
    let text = image_doc("nowhere.png", None).replace(
        "  </nodegraph>",
        "    <constant name=\"c\" type=\"float\"><input name=\"value\" type=\"float\" value=\"2.5\" /></constant>\n    <output name=\"f\" type=\"float\" nodename=\"c\" />\n  </nodegraph>",
    );
    std::fs::write(&doc, text).unwrap();
    let (_, got) = eval_ok(&doc, "f", &input, &out);
    assert_eq!(got, vec![vec![2.5]; texels.len()]);
}

#[test]
fn naga_backends_write_files() {
    let dir = temp_dir("targets");
    let example = repo().join("examples/marble.mtlx");
    for (target, file) in [("spirv", "marble.spv"), ("msl", "marble.metal"), ("glsl", "marble.comp.glsl"), ("hlsl", "marble.hlsl"), ("rust", "marble.rs")] {
        let (code, stdout, stderr) = uplift(&["compile", s(&example), "--target", target, "-o", s(&dir)]);
        assert_eq!(code, 0, "{target}: {stderr}");
        assert!(stdout.contains(file), "{stdout}");
        let bytes = std::fs::read(dir.join(file)).unwrap();
        assert!(!bytes.is_empty(), "{target}");
        match target {
            "spirv" => {
                assert_eq!(bytes.len() % 4, 0);
                assert_eq!(u32::from_le_bytes(bytes[..4].try_into().unwrap()), 0x0723_0203, "SPIR-V magic");
            }
            "msl" => assert!(String::from_utf8(bytes).unwrap().contains("kernel void mx_main("), "{target}"),
            "rust" => {
                let text = String::from_utf8(bytes).unwrap();
                assert!(text.starts_with("// Generated by uplift (template: templates/pattern_kernel.rs;") && text.contains("pub fn mx_pattern_batch("), "{text}");
            }
            "glsl" => {
                let text = String::from_utf8(bytes).unwrap();
                assert!(text.starts_with("#version 450 core") && text.contains("layout(local_size_x = 64"), "{text}");
            }
            _ => assert!(String::from_utf8(bytes).unwrap().contains("[numthreads(64, 1, 1)]"), "{target}"),
        }
    }
}

/// Batches larger than one dispatch are split; the chunks together give the unsplit result.
#[test]
fn large_batches_run_in_chunks() {
    use uplift_engines::batch::PatternEngine;
    use uplift_engines::table_batch::{batch_from_table, graph_inputs};
    let (doc, input, _) = setup("chunks", "");
    let mut csv = String::from("position_x,position_y,texcoord_y,scale\n");
    for i in 0..300 {
        csv.push_str(&format!("{},{},{},{}\n", i, -i, i as f32 / 512.0, 0.5 + (i % 7) as f32));
    }
    std::fs::write(&input, &csv).unwrap();
    let table = uplift_base::csv_table::parse("inputs.csv", &csv).unwrap();
    let compiler = uplift_compiler::Compiler::builtin();
    let engine = uplift_engines::wgpu_engine::WgpuEngine::new().unwrap();
    for output in ["pos_out", "sum"] {
        let kernel = compiler.compile_file(&doc, &uplift_compiler::OutputSelection::Named(vec![output.into()])).kernel.unwrap();
        let batch = batch_from_table(&kernel, &graph_inputs(&doc, output), &table, "inputs.csv").unwrap();
        let whole = engine.run_pattern(&kernel, &batch).unwrap();
        assert_eq!((whole.n(), whole.width()), (300, kernel.output_stride));
        let pipeline = engine.prepare(&kernel);
        for chunk in [1, 64, 100, 299] {
            let parts = engine.run_chunked(&pipeline, &batch, chunk).unwrap();
            assert_eq!(parts, whole, "{output}, chunks of {chunk}");
        }
    }
}

/// `--engine cpu` and `--engine wgpu` write the same CSV (within 1e-4 relative, 1e-6 absolute):
/// for a shipped graph's output (a runner, since one output is a different kernel from the
/// shipped all-outputs one) and for the example's.
#[test]
fn both_engines_write_the_same_csv() {
    let dir = temp_dir("engines");
    let input = dir.join("in.csv");
    let mut csv = String::from("position_x,position_y,position_z,normal_x,normal_y,normal_z,texcoord_x,texcoord_y,scale\n");
    for i in 0..500 {
        let t = i as f32 * 0.137;
        let n = [t.sin(), t.cos(), (0.3 * t).sin()];
        let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        csv.push_str(&format!("{},{},{},{},{},{},{},{},{}\n", t.sin() * 3.0, t.cos() * 2.0, t * 0.1, n[0] / l, n[1] / l, n[2] / l, (t * 0.31).fract(), (t * 0.17).fract(), 2.0 + (i % 5) as f32));
    }
    std::fs::write(&input, csv).unwrap();
    for (doc, output) in [(repo().join("runtime/kernels/graphs/triplanar_mask.mtlx"), "triplanar_mask/color"), (repo().join("examples/marble.mtlx"), "out_color")] {
        let mut tables = Vec::new();
        for engine in ["cpu", "wgpu"] {
            let out = dir.join(format!("{engine}.csv"));
            let (code, _, stderr) = uplift(&["eval", s(&doc), "--output", output, "--engine", engine, "--input", s(&input), "-o", s(&out)]);
            assert_eq!(code, 0, "{engine}: {stderr}");
            tables.push(read_csv(&out));
        }
        let [(cpu_header, cpu), (gpu_header, gpu)] = [tables.remove(0), tables.remove(0)];
        assert_eq!(cpu_header, gpu_header);
        assert_eq!(cpu.len(), 500);
        for (i, (a, b)) in cpu.iter().zip(&gpu).enumerate() {
            for (x, y) in a.iter().zip(b) {
                assert!((x - y).abs() <= (1e-4 * x.abs().max(y.abs())).max(1e-6), "{output} row {i}: cpu {a:?} wgpu {b:?}");
            }
        }
    }
}
