//! Every subcommand of the `uplift` binary as a user meets it on a bad day: `--help` exits 0 and
//! names the command; an unknown flag exits 2 with clap's message; a missing input file or
//! folder, a folder that is not an enhanced material, or an output that cannot be written exits
//! 1 with a message naming the path — never a panic (exit 101) or a signal.

use std::path::PathBuf;

use crate::common::cli::{s, uplift};

const SUBCOMMANDS: [&str; 15] = ["check", "compile", "eval", "tables", "enhance", "masks", "datagen", "train", "fit", "emit-decoder", "render", "furnace", "eval-fit", "demo", "flip"];

#[test]
fn every_subcommand_has_help_and_rejects_unknown_flags() {
    let (code, stdout, _) = uplift(&["--help"]);
    assert_eq!(code, 0);
    for sub in SUBCOMMANDS {
        assert!(stdout.contains(sub), "`uplift --help` does not list `{sub}`:\n{stdout}");
        let (code, stdout, stderr) = uplift(&[sub, "--help"]);
        assert_eq!(code, 0, "uplift {sub} --help: {stderr}");
        assert!(stdout.contains(&format!("Usage: uplift {sub}")), "uplift {sub} --help:\n{stdout}");
        let (code, _, stderr) = uplift(&[sub, "--no-such-flag"]);
        assert_eq!(code, 2, "uplift {sub} --no-such-flag: {stderr}");
        assert!(stderr.contains("--no-such-flag"), "uplift {sub} --no-such-flag:\n{stderr}");
    }
    let (code, _, stderr) = uplift(&["no-such-command"]);
    assert_eq!(code, 2, "{stderr}");
}

fn temp_dir(name: &str) -> PathBuf {
    crate::common::cli::temp_dir("cli-coverage", name)
}

/// Each command's main error paths: (arguments, a fragment the message must contain).
#[test]
fn every_subcommand_reports_missing_and_foreign_inputs_with_exit_1() {
    let dir = temp_dir("errors");
    let missing_mtlx = dir.join("missing.mtlx");
    let missing_dir = dir.join("missing_material");
    let foreign = dir.join("not_a_material");
    std::fs::create_dir_all(&foreign).unwrap();
    std::fs::write(foreign.join("notes.txt"), "not a material").unwrap();
    let missing_png = dir.join("missing.png");
    let missing_weights = dir.join("missing.safetensors");
    // An output below a regular file cannot be created.
    let blocker = dir.join("a_file");
    std::fs::write(&blocker, "x").unwrap();
    let unwritable = blocker.join("out");
    let csv = dir.join("in.csv");
    std::fs::write(&csv, "x\n1\n").unwrap();
    let out = dir.join("out");
    let (weights_out, decoder_rs, render_png) = (dir.join("w.safetensors"), dir.join("d.rs"), dir.join("r.png"));
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["check", s(&missing_mtlx)], "missing.mtlx"),
        (vec!["compile", s(&missing_mtlx), "-o", s(&out)], "missing.mtlx"),
        (vec!["eval", s(&missing_mtlx), "--output", "out", "--input", s(&csv), "-o", s(&out)], "missing.mtlx"),
        (vec!["tables", "-o", s(&unwritable)], "a_file"),
        (vec!["enhance", s(&missing_mtlx), "-o", s(&out)], "missing.mtlx"),
        (vec!["enhance", s(&foreign), "-o", s(&out)], "not_a_material"),
        (vec!["masks", "-o", s(&unwritable)], "a_file"),
        (vec!["datagen", "--class", "no-such-class", "--count", "1", "-o", s(&out)], "no-such-class"),
        (vec!["train", "--steps", "1", "--init", s(&missing_weights), "-o", s(&weights_out)], "missing.safetensors"),
        (vec!["fit", s(&missing_dir)], "missing_material"),
        (vec!["fit", s(&foreign)], "not_a_material"),
        (vec!["fit", s(&foreign), "--decoder", s(&missing_weights)], "missing.safetensors"),
        (vec!["emit-decoder", "--decoder", s(&missing_weights), "--rust", s(&decoder_rs)], "missing.safetensors"),
        (vec!["render", s(&missing_dir), "-o", s(&render_png)], "missing_material"),
        (vec!["render", s(&foreign), "-o", s(&render_png)], "not_a_material"),
        (vec!["furnace", s(&missing_dir)], "missing_material"),
        (vec!["furnace", s(&foreign)], "not_a_material"),
        (vec!["eval-fit", s(&missing_dir)], "missing_material"),
        (vec!["eval-fit", s(&foreign)], "not_a_material"),
        (vec!["demo", "-o", s(&unwritable), "--per-type", "1"], "a_file"),
        (vec!["flip", s(&missing_png), s(&missing_png)], "missing.png"),
    ];
    let mut covered: Vec<&str> = Vec::new();
    for (args, fragment) in &cases {
        let (code, _, stderr) = uplift(args);
        assert_eq!(code, 1, "uplift {args:?}: exit {code} (want 1)\n{stderr}");
        assert!(stderr.contains(fragment), "uplift {args:?}: the message does not name `{fragment}`:\n{stderr}");
        assert!(!stderr.contains("panicked"), "uplift {args:?} panicked:\n{stderr}");
        covered.push(args[0]);
    }
    for sub in SUBCOMMANDS {
        assert!(covered.contains(&sub), "no error path of `{sub}` is tested");
    }
    // Nothing was written for a failed command.
    assert!(!out.exists() || std::fs::read_dir(&out).unwrap().next().is_none(), "a failed command left files in {}", out.display());
}

/// A MaterialX document with one standard_surface material; `inputs` go inside the shader,
/// `nodes` at the top level.
fn surface_doc(inputs: &str, nodes: &str) -> String {
    format!("<?xml version=\"1.0\"?>\n<materialx version=\"1.39\">\n  <standard_surface name=\"s\" type=\"surfaceshader\">\n{inputs}\n  </standard_surface>\n{nodes}\n  <surfacematerial name=\"m\" type=\"material\">\n    <input name=\"surfaceshader\" type=\"surfaceshader\" nodename=\"s\" />\n  </surfacematerial>\n</materialx>\n")
}

/// Every input error of `uplift enhance` (runtime/enhance/src/pbr_input.rs), triggered once
/// through the binary: exit 1, the message's own words, and the file or position it names.
#[test]
fn enhance_reports_every_input_error() {
    let dir = temp_dir("enhance-inputs");
    let png = dir.join("tex.png");
    image::RgbImage::from_pixel(4, 4, image::Rgb([128, 128, 128])).save(&png).unwrap();
    let write = |name: &str, text: &str| {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    };
    let shader_doc = |name: &str, category: &str| write(name, &surface_doc("", "").replace("standard_surface name=\"s\"", &format!("{category} name=\"s\"")).replace("</standard_surface>", &format!("</{category}>")));
    // A texture beside the folder of `sub/escapes.mtlx`, which names it through fileprefix="../".
    std::fs::create_dir_all(dir.join("sub")).unwrap();
    std::fs::copy(&png, dir.join("outside.png")).unwrap();
    let twins = dir.join("twins");
    std::fs::create_dir_all(&twins).unwrap();
    for n in ["wood_basecolor.png", "wood_albedo.png"] {
        std::fs::copy(&png, twins.join(n)).unwrap();
    }
    let cases: Vec<(Vec<String>, &str)> = vec![
        (vec!["--base-color".into(), dir.join("none.png").display().to_string(), "--roughness".into(), png.display().to_string(), "--metalness".into(), png.display().to_string()], "no such texture file"),
        (vec![twins.display().to_string()], "look like the base_color texture"),
        (vec![write("empty.gltf", r#"{"asset":{"version":"2.0"}}"#).display().to_string()], "the asset has no materials"),
        (vec![shader_doc("unlit.mtlx", "surface_unlit").display().to_string()], "uses `surface_unlit`; supported shaders"),
        (vec![write("nomaterial.mtlx", "<?xml version=\"1.0\"?>\n<materialx version=\"1.39\">\n</materialx>\n").display().to_string()], "no surfacematerial with a supported PBR shader"),
        (vec![write("constnormal.mtlx", &surface_doc("    <input name=\"normal\" type=\"vector3\" value=\"0, 0, 1\" />", "")).display().to_string()], "a constant normal is not a normal map"),
        (vec![write("novalue.mtlx", &surface_doc("    <input name=\"base_color\" type=\"color3\" />", "")).display().to_string()], "has neither a value nor a connection"),
        (vec![write("notnumbers.mtlx", &surface_doc("    <input name=\"metalness\" type=\"float\" value=\"half\" />", "")).display().to_string()], "`half` is not a float value"),
        (vec![write("nan.mtlx", &surface_doc("    <input name=\"metalness\" type=\"float\" value=\"nan\" />", "")).display().to_string()], "`nan` is not a finite number"),
        (
            vec![write("sub/escapes.mtlx", &surface_doc("    <input name=\"base_color\" type=\"color3\" nodename=\"i\" />", "  <image name=\"i\" type=\"color3\" fileprefix=\"../\">\n    <input name=\"file\" type=\"filename\" value=\"outside.png\" />\n  </image>")).display().to_string()],
            "outside the document's folder",
        ),
        (vec![write("dangling.mtlx", &surface_doc("    <input name=\"base_color\" type=\"color3\" nodename=\"nowhere\" />", "")).display().to_string()], "the node it connects to is not in the document"),
        (
            vec![write("badnormalmap.mtlx", &surface_doc("    <input name=\"normal\" type=\"vector3\" nodename=\"nm\" />", "  <normalmap name=\"nm\" type=\"vector3\" />")).display().to_string()],
            "normalmap without an image on `in`",
        ),
        (
            vec![write("noise.mtlx", &surface_doc("    <input name=\"base_color\" type=\"color3\" nodename=\"n\" />", "  <noise2d name=\"n\" type=\"color3\" />")).display().to_string()],
            "connected to a `noise2d` node",
        ),
        (
            vec![write("nofile.mtlx", &surface_doc("    <input name=\"base_color\" type=\"color3\" nodename=\"i\" />", "  <image name=\"i\" type=\"color3\" />")).display().to_string()],
            "has no `file` input",
        ),
        (
            vec![write("missingtex.mtlx", &surface_doc("    <input name=\"base_color\" type=\"color3\" nodename=\"i\" />", "  <image name=\"i\" type=\"color3\">\n    <input name=\"file\" type=\"filename\" value=\"gone.png\" />\n  </image>")).display().to_string()],
            "gone.png` not found",
        ),
        (vec![write("notes.txt", "x").display().to_string()], "not a .gltf, .glb or .mtlx file"),
        (vec![dir.join("nothing_here").display().to_string()], "no such file or folder"),
    ];
    let out = dir.join("out");
    for (inputs, fragment) in &cases {
        let mut args: Vec<&str> = vec!["enhance"];
        args.extend(inputs.iter().map(String::as_str));
        args.extend(["-o", s(&out)]);
        let (code, _, stderr) = uplift(&args);
        assert_eq!(code, 1, "uplift {args:?}: exit {code}\n{stderr}");
        assert!(stderr.contains(fragment), "uplift {args:?}: want `{fragment}` in:\n{stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
    }
    assert!(!out.exists() || std::fs::read_dir(&out).unwrap().next().is_none(), "a failed enhance left files");
}
