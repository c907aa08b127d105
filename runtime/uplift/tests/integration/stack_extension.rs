//! The stack as data, end to end (issue 26, deliverable 5): a decorator lobe added in a
//! temporary library folder — a nodedef and its WGSL function, `uplift_stack` redefined with the
//! lobe layered on top (two optional inputs), a training class that turns it on — and a rule
//! written from scratch that uses it, run through `enhance`, `datagen`, a short `train`, `fit`,
//! `render` and `furnace` with `--stack DIR` and no Rust change. The outputs are checked against
//! the lobe: params.exr carries its channels with the rule's values, the written document
//! validates with MaterialX's validator, the data generator's rows turn the lobe on only in the
//! new class, a decoder file records the 26-parameter signature and is refused by the builtin
//! stack, and the lobe changes the rendered image.

use super::common::cli::{repo, s, temp_dir, uplift_with};
use std::path::{Path, PathBuf};

/// The new lobe: a tinted sheen (pbrlib's sheen with a colour), as a nodedef and WGSL.
const LOBE_DEFS: &str = r#"<?xml version="1.0"?>
<materialx version="1.39">
  <nodedef name="ND_proof_tinted_sheen_bsdf" node="proof_tinted_sheen" nodegroup="pbr" doc="A tinted sheen lobe (a test's decorator).">
    <input name="weight" type="float" value="0.0" />
    <input name="color" type="color3" value="1, 1, 1" />
    <input name="roughness" type="float" value="0.3" />
    <input name="normal" type="vector3" defaultgeomprop="Nworld" />
    <output name="out" type="BSDF" />
  </nodedef>
</materialx>
"#;

const LOBE_WGSL: &str = "// The tinted sheen: pbrlib's Conty-Kulla sheen with a colour.
fn mx_proof_tinted_sheen_bsdf(cl: mx_closure, weight: f32, color: vec3<f32>, roughness: f32, normal: vec3<f32>) -> BSDF {
    return mx_sheen_bsdf(cl, weight, color, roughness, normal, 0);
}
";

/// The inputs the lobe adds to `uplift_stack` (optional: the builtin rules leave them out).
const STACK_INPUTS: &str = r#"    <input name="tint_weight" type="float" value="0.0" uimin="0.0" uimax="1.0" uplift_optional="true" doc="Weight of the tinted sheen on top." />
    <input name="tint_color" type="color3" value="1, 1, 1" uimin="0,0,0" uimax="1,1,1" uplift_optional="true" doc="Colour of the tinted sheen." />
"#;

/// The stack's nodegraph tail: the tinted sheen layered over the builtin stack's result.
const STACK_TOP: &str = r#"    <proof_tinted_sheen name="tinted" type="BSDF">
      <input name="weight" type="float" interfacename="tint_weight" />
      <input name="color" type="color3" interfacename="tint_color" />
      <input name="roughness" type="float" value="0.3" />
      <input name="normal" type="vector3" interfacename="normal" />
    </proof_tinted_sheen>
    <layer name="tinted_layer" type="BSDF">
      <input name="top" type="BSDF" nodename="tinted" />
      <input name="base" type="BSDF" nodename="out_layer" />
    </layer>
    <output name="out" type="BSDF" nodename="tinted_layer" />
"#;

/// A training class for the lobe: a dielectric with the tinted sheen on.
const CLASS: &str = r#"<?xml version="1.0"?>
<materialx version="1.39" colorspace="lin_rec709">
  <nodegraph name="uplift_class" uplift_share="1">
    <input name="weight" type="float" value="0.3" uimin="0.3" uimax="1.0" uplift_scope="tile" />
    <input name="red" type="float" value="0.2" uimin="0.2" uimax="1.0" uplift_scope="tile" />
    <input name="roughness" type="float" value="0.05" uimin="0.05" uimax="0.6" uplift_scope="cell" />
    <combine3 name="tint" type="color3">
      <input name="in1" type="float" interfacename="red" />
      <input name="in2" type="float" value="0.4" />
      <input name="in3" type="float" value="0.1" />
    </combine3>
    <constant name="weight_value" type="float">
      <input name="value" type="float" interfacename="weight" />
    </constant>
    <constant name="core" type="float">
      <input name="value" type="float" interfacename="roughness" />
    </constant>
    <output name="tint_weight_out" type="float" nodename="weight_value" />
    <output name="tint_color_out" type="color3" nodename="tint" />
    <output name="core_roughness_out" type="float" nodename="core" />
  </nodegraph>
</materialx>
"#;

/// Writes the library folder: the lobe, the redefined stack (the builtin one's nodedef and
/// nodegraph with the lobe added), the class.
fn library(dir: &Path) -> PathBuf {
    let lib = dir.join("lib");
    std::fs::create_dir_all(lib.join("wgsl")).unwrap();
    std::fs::create_dir_all(lib.join("classes")).unwrap();
    std::fs::write(lib.join("proof_lobe.mtlx"), LOBE_DEFS).unwrap();
    std::fs::write(lib.join("wgsl/proof_lobe.wgsl"), LOBE_WGSL).unwrap();
    std::fs::write(lib.join("classes/tinted.mtlx"), CLASS).unwrap();
    let root = repo();
    let element = |file: &str, open: &str, close: &str| -> String {
        let text = std::fs::read_to_string(root.join(file)).unwrap();
        let a = text.find(open).unwrap_or_else(|| panic!("{file}: no {open}"));
        let b = a + text[a..].find(close).unwrap() + close.len();
        text[a..b].to_string()
    };
    let nodedef = element("mtlx/libraries/uplift/uplift_defs.mtlx", "<nodedef name=\"ND_uplift_stack\"", "</nodedef>");
    let normal_at = nodedef.find("    <input name=\"normal\"").unwrap();
    let nodedef = format!("{}{STACK_INPUTS}{}", &nodedef[..normal_at], &nodedef[normal_at..]);
    let graph = element("mtlx/libraries/uplift/uplift_ng.mtlx", "<nodegraph name=\"NG_uplift_stack\"", "</nodegraph>");
    let out = "    <output name=\"out\" type=\"BSDF\" nodename=\"out_layer\" />\n";
    assert!(graph.contains(out), "the builtin stack's output changed");
    let graph = graph.replace(out, STACK_TOP);
    std::fs::write(lib.join("stack.mtlx"), format!("<?xml version=\"1.0\"?>\n<materialx version=\"1.39\">\n  {nodedef}\n  {graph}\n</materialx>\n")).unwrap();
    lib
}

/// A rule written from scratch: Type 0's haze mapping is not needed for the proof, so the rule
/// sets the stack's inputs directly (a lacquered, tinted-sheen dielectric) — every required
/// output, the lobe's two, and the full material.
fn rule(dir: &Path) -> PathBuf {
    let required = [
        ("reflectivity", "color3", "<constant name=\"reflectivity\" type=\"color3\"><input name=\"value\" type=\"color3\" value=\"0.04, 0.04, 0.04\" /></constant>"),
        ("edge_color", "color3", "<constant name=\"edge_color\" type=\"color3\"><input name=\"value\" type=\"color3\" value=\"1, 1, 1\" /></constant>"),
        ("metalness", "float", "<constant name=\"metalness\" type=\"float\"><input name=\"value\" type=\"float\" interfacename=\"metalness\" /></constant>"),
        ("core_roughness", "float", "<multiply name=\"core_roughness\" type=\"float\"><input name=\"in1\" type=\"float\" interfacename=\"roughness\" /><input name=\"in2\" type=\"float\" interfacename=\"roughness\" /></multiply>"),
        ("haze_roughness", "float", "<constant name=\"haze_roughness\" type=\"float\"><input name=\"value\" type=\"float\" value=\"0.4\" /></constant>"),
        ("haze_weight", "float", "<constant name=\"haze_weight\" type=\"float\"><input name=\"value\" type=\"float\" value=\"0.1\" /></constant>"),
        ("specular_ior", "float", "<constant name=\"specular_ior\" type=\"float\"><input name=\"value\" type=\"float\" value=\"1.5\" /></constant>"),
        ("fuzz_weight", "float", "<constant name=\"fuzz_weight\" type=\"float\"><input name=\"value\" type=\"float\" value=\"0.0\" /></constant>"),
        ("fuzz_thickness", "float", "<constant name=\"fuzz_thickness\" type=\"float\"><input name=\"value\" type=\"float\" value=\"0.5\" /></constant>"),
        ("coat_weight", "float", "<constant name=\"coat_weight\" type=\"float\"><input name=\"value\" type=\"float\" value=\"0.0\" /></constant>"),
        ("coat_ior", "float", "<constant name=\"coat_ior\" type=\"float\"><input name=\"value\" type=\"float\" value=\"1.5\" /></constant>"),
        ("inner_weight", "float", "<constant name=\"inner_weight\" type=\"float\"><input name=\"value\" type=\"float\" value=\"0.0\" /></constant>"),
        ("inner_thickness", "float", "<constant name=\"inner_thickness\" type=\"float\"><input name=\"value\" type=\"float\" value=\"0.5\" /></constant>"),
        ("scatter_color", "color3", "<constant name=\"scatter_color\" type=\"color3\"><input name=\"value\" type=\"color3\" interfacename=\"base_color\" /></constant>"),
        ("subcutaneous_weight", "float", "<constant name=\"subcutaneous_weight\" type=\"float\"><input name=\"value\" type=\"float\" value=\"0.0\" /></constant>"),
        ("subcutaneous_roughness", "float", "<constant name=\"subcutaneous_roughness\" type=\"float\"><input name=\"value\" type=\"float\" value=\"0.64\" /></constant>"),
        ("tint_weight", "float", "<constant name=\"tint_weight\" type=\"float\"><input name=\"value\" type=\"float\" interfacename=\"sheen_amount\" /></constant>"),
        ("tint_color", "color3", "<constant name=\"tint_color\" type=\"color3\"><input name=\"value\" type=\"color3\" value=\"0.9, 0.3, 0.1\" /></constant>"),
    ];
    let mut nodes = String::new();
    let mut stack_inputs = String::new();
    let mut outputs = String::new();
    for (name, ty, node) in required {
        // Nodes are `<input>_value` (an interface input may share the stack input's name).
        let node = node.replacen(&format!("name=\"{name}\""), &format!("name=\"{name}_value\""), 1);
        nodes += &format!("    {node}\n");
        stack_inputs += &format!("      <input name=\"{name}\" type=\"{ty}\" nodename=\"{name}_value\" />\n");
        outputs += &format!("    <output name=\"{name}_out\" type=\"{ty}\" nodename=\"{name}_value\" />\n");
    }
    let text = format!(
        r#"<?xml version="1.0"?>
<materialx version="1.39" colorspace="lin_rec709">
  <nodegraph name="uplift_rule" uplift_type="0">
    <input name="base_color" type="color3" value="0.5, 0.5, 0.5" />
    <input name="roughness" type="float" value="0.5" />
    <input name="metalness" type="float" value="0.0" />
    <input name="normal_map" type="vector3" value="0.5, 0.5, 1.0" />
    <input name="object_size" type="float" value="1.0" />
    <input name="sheen_amount" type="float" value="0.6" uimin="0.5" uimax="0.8" />
{nodes}    <uplift_stack name="stack" type="BSDF">
{stack_inputs}    </uplift_stack>
    <oren_nayar_diffuse_bsdf name="diffuse" type="BSDF">
      <input name="color" type="color3" interfacename="base_color" />
    </oren_nayar_diffuse_bsdf>
    <layer name="material" type="BSDF">
      <input name="top" type="BSDF" nodename="stack" />
      <input name="base" type="BSDF" nodename="diffuse" />
    </layer>
    <constant name="diffuse_color" type="color3"><input name="value" type="color3" interfacename="base_color" /></constant>
    <normalmap name="shading_normal" type="vector3"><input name="in" type="vector3" interfacename="normal_map" /></normalmap>
{outputs}    <output name="diffuse_color_out" type="color3" nodename="diffuse_color" />
    <output name="normal_out" type="vector3" nodename="shading_normal" />
    <output name="bsdf_out" type="BSDF" nodename="material" />
  </nodegraph>
</materialx>
"#
    );
    let path = dir.join("tinted_lacquer.mtlx");
    std::fs::write(&path, text).unwrap();
    path
}

/// Runs the binary with its kernel runners built quickly (opt-level 0: the stack's kernels
/// are not shipped for this library; their speed does not matter here).
fn uplift(args: &[&str]) -> (i32, String, String) {
    uplift_with(args, &[("UPLIFT_RUNNER_QUICK", "1")])
}

fn run(args: &[&str]) -> String {
    let (code, out, err) = uplift(args);
    assert_eq!(code, 0, "uplift {}\n{out}\n{err}", args.join(" "));
    format!("{out}{err}")
}

fn params_channel(dir: &Path, name: &str) -> Vec<f32> {
    let img = uplift_base::exr::read(&dir.join("params.exr")).unwrap();
    img.channel(name).unwrap_or_else(|| panic!("params.exr has no {name}")).to_vec()
}

#[test]
fn a_lobe_added_as_graph_nodes_runs_through_every_stage() {
    let dir = temp_dir("stack_extension", "proof");
    let lib = library(&dir);
    let rule = rule(&dir);
    let (lib_s, rule_s) = (s(&lib).to_string(), s(&rule).to_string());

    // The stack as the runtime reads it from the folder: the builtin parameters plus the lobe's.
    let stack = uplift_engines::stack::Stack::load(std::slice::from_ref(&lib)).unwrap();
    let builtin = uplift_engines::stack::Stack::builtin();
    assert_eq!(stack.len(), builtin.len() + 4);
    assert!(stack.signature().starts_with(&builtin.signature()));
    assert!(stack.signature().ends_with("tint_weight[0.0,1.0]linear tint_color.R[0.0,1.0]linear tint_color.G[0.0,1.0]linear tint_color.B[0.0,1.0]linear"), "{}", stack.signature());

    // check and compile take the same --stack (issue 46): the rule, which uses the new lobe,
    // checks with it and not without it.
    run(&["check", "--stack", &lib_s, &rule_s]);
    let (code, _, stderr) = uplift(&["check", &rule_s]);
    assert_eq!(code, 1, "a rule using the new lobe checks without its --stack: {stderr}");
    run(&["compile", "--stack", &lib_s, &rule_s, "--target", "wgsl", "-o", s(&dir.join("compiled"))]);

    // enhance: the user's rule, and a builtin Type (which leaves the lobe out: weight 0).
    let material = repo().join("examples/pbr_materials.mtlx");
    let enhanced = dir.join("enhanced");
    run(&["enhance", s(&material), "--stack", &lib_s, "--rule", &rule_s, "--resolution", "16x16", "--mask-size", "32", "--seed", "2", "-o", s(&enhanced)]);
    let builtin_type = dir.join("builtin_type");
    run(&["enhance", s(&material), "--stack", &lib_s, "--type", "0", "--resolution", "16x16", "--mask-size", "32", "-o", s(&builtin_type)]);
    let first = |d: &Path| -> PathBuf {
        let mut v: Vec<PathBuf> = std::fs::read_dir(d).unwrap().map(|e| e.unwrap().path()).filter(|p| p.join("meta.json").exists()).collect();
        v.sort();
        v.remove(0)
    };
    let m = first(&enhanced);
    let weight = params_channel(&m, "tint_weight");
    assert!(weight.iter().all(|&w| (0.5..=0.8).contains(&w) && w == weight[0]), "the rule's drawn sheen amount: {:?}", &weight[..4]);
    assert!(params_channel(&m, "tint_color.R").iter().all(|&r| (r - 0.9).abs() < 1e-6));
    assert!(params_channel(&first(&builtin_type), "tint_weight").iter().all(|&w| w == 0.0), "a rule that leaves an optional input out bakes its nodedef value");
    let doc = std::fs::read_to_string(m.join("material.mtlx")).unwrap();
    assert!(doc.contains("ND_proof_tinted_sheen_bsdf") && doc.contains("tint_weight"), "the written material defines the stack it uses");
    match super::enhance::validate(&m.join("material.mtlx")) {
        Some(r) => r.unwrap(),
        None => super::enhance::say_validator_skipped(),
    }
    // Without --stack the material is refused, the difference named.
    let (code, _, err) = uplift(&["furnace", s(&m)]);
    assert_eq!(code, 1);
    assert!(err.contains("another uplift_stack") && err.contains("tint_weight"), "{err}");

    // datagen: the new class turns the lobe on; the builtin ones leave it off.
    let data = dir.join("data");
    run(&["datagen", "--stack", &lib_s, "--count", "16384", "-o", s(&data)]);
    let shard = uplift_neural::weights::TensorFile::read(&data.join("all-00000.safetensors")).unwrap();
    let (shape, params) = shard.get("params").unwrap();
    let classes = &shard.get("class").unwrap().1;
    assert_eq!(shape[1], stack.len());
    let names = shard.meta("class").unwrap().to_string();
    let tinted = names.split(", ").position(|c| c.ends_with(" tinted")).expect("the tinted class") as f32;
    let w = stack.index_of("tint_weight").unwrap();
    let infill = names.split(", ").position(|c| c.ends_with(" infill")).unwrap() as f32;
    let (mut on, mut rows_tinted) = (0, 0);
    for (r, c) in classes.iter().enumerate() {
        let x = params[r * stack.len() + w];
        if *c == tinted {
            rows_tinted += 1;
            on += (x >= 0.3) as usize;
        } else if *c != infill {
            assert_eq!(x, 0.0, "a builtin class turned the new lobe on");
        }
    }
    assert!(rows_tinted > 4000 && on == rows_tinted, "{on} of {rows_tinted} rows of the new class have the lobe on");

    // train: a short run records the new signature; the builtin stack refuses it. It widens the
    // latent too (8 values: latent.exr gains a third texture through fit and render).
    let decoder = dir.join("decoder.safetensors");
    let log = run(&["train", "--stack", &lib_s, "--init", s(&repo().join("runtime/weights/decoder.safetensors")), "--latent", "8", "--steps", "6", "--batch", "2048", "--holdout", "512", "-o", s(&decoder)]);
    assert!(log.contains("widened") && log.contains("tinted") && log.contains("widened to 8"), "{log}");
    let file = uplift_neural::weights::TensorFile::read(&decoder).unwrap();
    assert_eq!(file.meta(uplift_neural::weights::STACK_KEY).unwrap(), stack.signature());
    let (code, _, err) = uplift(&["fit", s(&m), "--decoder", s(&decoder), "--steps", "2"]);
    assert_eq!(code, 1, "{err}");

    // fit and render with the new stack; the lobe shows in the image.
    run(&["fit", s(&m), "--stack", &lib_s, "--decoder", s(&decoder), "--steps", "4", "--directions", "8"]);
    let latents = uplift_material::MaterialFolder::open(&m).unwrap().read_latents().unwrap();
    assert_eq!(latents.channels, 8);
    assert!(m.join("latent2.png").exists());
    let reference = dir.join("reference.exr");
    run(&["render", s(&m), "--stack", &lib_s, "--size", "32", "--spp", "8", "-o", s(&reference)]);
    run(&["render", s(&m), "--stack", &lib_s, "--neural", "--decoder", s(&decoder), "--size", "32", "--spp", "4", "-o", s(&dir.join("neural.png"))]);
    let furnace = run(&["furnace", s(&m), "--stack", &lib_s]);
    assert!(furnace.contains("1 of 1 materials pass"), "{furnace}");
    // The same material without the lobe (the builtin Type's) renders differently: redder at
    // grazing angles, where the sheen is.
    let plain = dir.join("plain.exr");
    run(&["render", s(&first(&builtin_type)), "--stack", &lib_s, "--size", "32", "--spp", "8", "-o", s(&plain)]);
    let red = |p: &Path| -> f64 {
        let img = uplift_base::exr::read(p).unwrap();
        let (r, g) = (img.channel("R").unwrap(), img.channel("G").unwrap());
        r.iter().zip(g).map(|(r, g)| (*r - *g) as f64).sum::<f64>()
    };
    assert!(red(&reference) > red(&plain) + 1e-3, "the tinted sheen does not show: {} vs {}", red(&reference), red(&plain));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_broken_stack_folder_is_an_error_naming_the_place() {
    let dir = temp_dir("stack_extension", "broken");
    // Not a folder.
    let (code, _, err) = uplift(&["datagen", "--stack", s(&dir.join("missing")), "--count", "8", "-o", s(&dir.join("out"))]);
    assert_eq!(code, 1);
    assert!(err.contains("--stack") && err.contains("missing") && err.contains("not a folder"), "{err}");
    // A stack input without its range: the nodedef's file, line and column.
    let lib = library(&dir);
    let stack = std::fs::read_to_string(lib.join("stack.mtlx")).unwrap();
    std::fs::write(lib.join("stack.mtlx"), stack.replace("uplift_optional=\"true\" doc=\"Weight of the tinted sheen on top.\"", "doc=\"Weight of the tinted sheen on top.\"").replace("<input name=\"tint_weight\" type=\"float\" value=\"0.0\" uimin=\"0.0\" uimax=\"1.0\"", "<input name=\"tint_weight\" type=\"float\" value=\"0.0\"")).unwrap();
    let (code, _, err) = uplift(&["datagen", "--stack", s(&lib), "--count", "8", "-o", s(&dir.join("out"))]);
    assert_eq!(code, 1);
    assert!(err.contains("stack.mtlx:") && err.contains("`tint_weight` has neither `uisoftmin` nor `uimin`"), "{err}");
    std::fs::write(lib.join("stack.mtlx"), stack).unwrap();
    // A class output that is not a stack input, and a random scalar without its scope.
    let class = lib.join("classes/tinted.mtlx");
    std::fs::write(&class, CLASS.replace("tint_weight_out", "tint_wieght_out")).unwrap();
    let (code, _, err) = uplift(&["datagen", "--stack", s(&lib), "--count", "8", "-o", s(&dir.join("out"))]);
    assert_eq!(code, 1);
    assert!(err.contains("tinted.mtlx:") && err.contains("`tint_wieght_out` is not `<input>_out` of an uplift_stack input"), "{err}");
    std::fs::write(&class, CLASS.replace(" uplift_scope=\"cell\"", "")).unwrap();
    let (code, _, err) = uplift(&["datagen", "--stack", s(&lib), "--count", "8", "-o", s(&dir.join("out"))]);
    assert_eq!(code, 1);
    assert!(err.contains("tinted.mtlx:") && err.contains("`roughness` has no uplift_scope"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}
