//! Every subcommand of the `uplift` binary as a user meets it on a bad day: `--help` exits 0 and
//! names the command; an unknown flag exits 2 with clap's message; a missing input file or
//! folder, a folder that is not an enhanced material, or an output that cannot be written exits
//! 1 with a message naming the path — never a panic (exit 101) or a signal.

use std::path::PathBuf;

use crate::common::cli::{s, uplift};

const SUBCOMMANDS: [&str; 22] = ["check", "compile", "eval", "tables", "enhance", "masks", "datagen", "train", "train-sampler", "fit", "emit-decoder", "render", "gallery", "furnace", "eval-fit", "demo", "flip", "export", "pack", "project", "shards", "slurm"];

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
    let missing_mesh = dir.join("m.glb");
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
        (vec!["train-sampler", "--decoder", s(&missing_weights), "-o", s(&weights_out)], "missing.safetensors"),
        (vec!["fit", s(&missing_dir)], "missing_material"),
        (vec!["fit", s(&foreign)], "not_a_material"),
        (vec!["fit", s(&foreign), "--decoder", s(&missing_weights)], "missing.safetensors"),
        (vec!["emit-decoder", "--decoder", s(&missing_weights), "--rust", s(&decoder_rs)], "missing.safetensors"),
        (vec!["render", s(&missing_dir), "-o", s(&render_png)], "missing_material"),
        (vec!["pack", s(&missing_dir), "-o", s(&out)], "missing_material"),
        (vec!["project", s(&missing_dir), "--mesh", s(&missing_mesh), "-o", s(&out)], "m.glb"),
        (vec!["export", s(&missing_dir), "--mesh", s(&missing_mesh), "-o", s(&out)], "m.glb"),
        (vec!["render", s(&foreign), "-o", s(&render_png)], "not_a_material"),
        (vec!["render", s(&missing_mtlx), "-o", s(&render_png)], "missing.mtlx"),
        (vec!["gallery", s(&missing_dir), "-o", s(&out)], "missing_material"),
        (vec!["gallery", s(&foreign), "-o", s(&out)], "no MaterialX documents"),
        (vec!["furnace", s(&missing_dir)], "missing_material"),
        (vec!["furnace", s(&foreign)], "not_a_material"),
        (vec!["eval-fit", s(&missing_dir)], "missing_material"),
        (vec!["eval-fit", s(&foreign)], "not_a_material"),
        (vec!["demo", "-o", s(&unwritable), "--per-type", "1"], "a_file"),
        (vec!["flip", s(&missing_png), s(&missing_png)], "missing.png"),
        (vec!["shards", s(&missing_dir)], "missing_material"),
        (vec!["slurm", "status", s(&missing_dir)], "missing_material"),
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
            "lies outside the input's folder",
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

/// Runs the binary and requires exit 0; its stdout and stderr together.
fn ok(args: &[&str]) -> String {
    let (code, stdout, stderr) = uplift(args);
    assert_eq!(code, 0, "uplift {}: {stdout}{stderr}", args.join(" "));
    stdout + &stderr
}

/// The happy path through the binary of every subcommand that the other binary tests
/// (cli, cli_eval, enhance, kill_resume) do not run to success: tables, masks, emit-decoder,
/// render (reference and neural), flip, furnace (reference and neural), eval-fit and demo, on
/// tiny inputs. Each output is checked against something independent of the command: the
/// committed tables and decoder code it regenerates, a second run, FLIP's zero on equal images.
#[test]
fn the_remaining_subcommands_succeed_through_the_binary() {
    let dir = temp_dir("happy");
    let repo = crate::common::cli::repo();

    // tables: the committed library tables are exactly this command's output.
    let tables = dir.join("tables");
    ok(&["tables", "-o", s(&tables)]);
    let committed = std::fs::read(repo.join("mtlx/libraries/pbrlib/wgsl/albedo_tables.wgsl")).unwrap();
    assert!(std::fs::read(tables.join("albedo_tables.wgsl")).unwrap() == committed, "`uplift tables` no longer writes the committed albedo_tables.wgsl");

    // masks: files written, and the same bytes for the same seed.
    let (m1, m2) = (dir.join("masks1"), dir.join("masks2"));
    for m in [&m1, &m2] {
        ok(&["masks", "--seed", "3", "--size", "32", "-o", s(m)]);
    }
    let mut names: Vec<_> = std::fs::read_dir(&m1).unwrap().map(|e| e.unwrap().file_name()).collect();
    names.sort();
    assert!(!names.is_empty(), "masks wrote nothing");
    for n in &names {
        assert!(std::fs::read(m1.join(n)).unwrap() == std::fs::read(m2.join(n)).unwrap(), "masks {n:?} differs between two runs with one seed");
    }

    // emit-decoder: the shipped decoder's committed Rust is this command's output.
    let (rust, wgsl) = (dir.join("decoder.rs"), dir.join("decoder.wgsl"));
    ok(&["emit-decoder", "--rust", s(&rust), "--wgsl", s(&wgsl)]);
    let shipped = std::fs::read_to_string(repo.join("runtime/neural/src/shipped_decoder.rs")).unwrap();
    assert_eq!(std::fs::read_to_string(&rust).unwrap(), shipped, "`uplift emit-decoder` no longer writes the committed shipped_decoder.rs");
    assert!(std::fs::read_to_string(&wgsl).unwrap().contains("fn "), "no WGSL decoder");
    let (rust, wgsl) = (dir.join("sampler.rs"), dir.join("sampler.wgsl"));
    ok(&["emit-decoder", "--sampler", "--rust", s(&rust), "--wgsl", s(&wgsl)]);
    let shipped = std::fs::read_to_string(repo.join("runtime/neural/src/shipped_sampler.rs")).unwrap();
    assert_eq!(std::fs::read_to_string(&rust).unwrap(), shipped, "`uplift emit-decoder --sampler` no longer writes the committed shipped_sampler.rs");
    assert!(std::fs::read_to_string(&wgsl).unwrap().contains("fn nd_main"), "no WGSL sampling decoder");

    // A fitted material: enhance one PBR set at 16², fit it briefly.
    let enhanced = dir.join("enhanced");
    ok(&["enhance", s(&repo.join("examples/pbr_materials.mtlx")), "--seed", "3", "--resolution", "16x16", "--mask-size", "32", "-o", s(&enhanced)]);
    let copper = enhanced.join("copper");
    ok(&["fit", s(&copper), "--steps", "20", "--threads", "2"]);
    // export: a short orbit of the fitted material on a UV sphere, every modality written.
    let sphere = crate::render::write_uv_sphere_gltf(&dir.join("sphere"), 16, 8);
    let exported = dir.join("exported");
    ok(&["export", s(&copper), "--mesh", s(&sphere), "-o", s(&exported), "--frames", "4", "--size", "48", "--spp", "1", "--bounces", "0", "--threads", "2"]);
    for (name, ext) in uplift::export::MODALITIES {
        assert!(uplift::export::frame_path(&exported, name, 1, ext).is_file(), "export wrote no {name}.{ext}");
    }
    // pack: the export as one WebDataset shard and its index.
    let shards = dir.join("shards");
    ok(&["pack", s(&exported), "-o", s(&shards)]);
    assert!(shards.join("shard-000000.tar").is_file() && shards.join("index.json").is_file(), "pack wrote no shard");
    // project: the export's own frames back into a material folder that render accepts.
    let projected = dir.join("projected");
    ok(&["project", s(&exported), "--mesh", s(&sphere), "-o", s(&projected), "--resolution", "32", "--fill", "diffuse"]);
    let (code, _, err) = uplift(&["project", s(&exported), "--mesh", s(&sphere), "-o", s(&dir.join("p3")), "--fill", "bogus"]);
    assert!(code == 1 && err.contains("--fill"), "{err}");
    ok(&["render", s(&projected), "--neural", "--sampler", "--mesh", s(&sphere), "-o", s(&dir.join("projected.png")), "--size", "16", "--spp", "1", "--threads", "2"]);
    let (code, _, err) = uplift(&["project", s(&copper), "--mesh", s(&sphere), "-o", s(&dir.join("p2"))]);
    assert!(code == 1 && err.contains("cameras.json"), "{err}");
    // --frames 0 is refused by the argument parser (docs/cli.md's bounds): exit 2.
    let (code, _, err) = uplift(&["export", s(&copper), "--mesh", s(&sphere), "-o", s(&exported), "--frames", "0"]);
    assert!(code == 2 && err.contains("--frames"), "{err}");

    // render (reference and neural) and flip between them; flip of an image with itself is 0.
    let (reference, neural) = (dir.join("reference.png"), dir.join("neural.png"));
    ok(&["render", s(&copper), "-o", s(&reference), "--size", "32", "--spp", "4", "--threads", "2"]);
    ok(&["render", s(&copper), "--neural", "-o", s(&neural), "--size", "32", "--spp", "4", "--threads", "2"]);
    // train-sampler, briefly, and a neural render sampled by it; a decoder file without one is
    // an error naming it.
    let sampled = dir.join("sampled.safetensors");
    ok(&["train-sampler", "--steps", "2", "--views", "16", "--directions", "8", "-o", s(&sampled)]);
    ok(&["render", s(&copper), "--neural", "--sampler", "--decoder", s(&sampled), "-o", s(&dir.join("sampled.png")), "--size", "24", "--spp", "2", "--threads", "2"]);
    let no_sampler = dir.join("no_sampler.safetensors");
    std::fs::copy(repo.join("runtime/weights/decoder.safetensors"), &no_sampler).unwrap();
    let mut f = uplift_neural::weights::TensorFile::read(&no_sampler).unwrap();
    f.tensors.retain(|k, _| !k.starts_with("sampler."));
    f.metadata.retain(|k, _| !k.starts_with("sampler."));
    f.write(&no_sampler).unwrap();
    let (code, _, err) = uplift(&["render", s(&copper), "--neural", "--sampler", "--decoder", s(&no_sampler), "-o", s(&dir.join("x.png"))]);
    assert!(code == 1 && err.contains("no_sampler.safetensors") && err.contains("no sampling decoder"), "{err}");
    let same = ok(&["flip", s(&reference), s(&reference)]);
    let flip_of = |text: &str| -> f64 {
        let at = text.find("FLIP").unwrap_or_else(|| panic!("no FLIP figure in: {text}"));
        text[at..].split(|c: char| !(c.is_ascii_digit() || c == '.')).find(|t| t.parse::<f64>().is_ok()).unwrap().parse().unwrap()
    };
    assert_eq!(flip_of(&same), 0.0, "FLIP of an image with itself: {same}");
    let map = dir.join("flip.png");
    let differ = ok(&["flip", s(&reference), s(&neural), "-o", s(&map)]);
    let f = flip_of(&differ);
    assert!(f > 0.0 && f < 1.0 && map.is_file(), "FLIP reference vs neural: {differ}");

    // furnace, reference and neural, on a few texels.
    for extra in [&[][..], &["--neural"][..]] {
        let mut args = vec!["furnace", s(&copper), "--max-texels", "8", "--directions", "64", "--views", "4", "--threads", "2"];
        args.extend_from_slice(extra);
        let out = ok(&args);
        assert!(out.contains("pass") || out.contains("PASS"), "furnace {extra:?}: {out}");
    }

    // eval-fit: the table and its images.
    let eval = dir.join("eval");
    ok(&["eval-fit", s(&copper), "-o", s(&eval), "--size", "32", "--spp", "4", "--threads", "2"]);
    let table = std::fs::read_to_string(eval.join("table.md")).unwrap();
    assert!(table.contains('|'), "eval-fit's table.md: {table}");

    // demo, the main job, at its smallest.
    let demo = dir.join("demo");
    ok(&["demo", "-o", s(&demo), "--per-type", "1", "--texture-size", "16", "--render-size", "24", "--spp", "2", "--fit-steps", "5", "--threads", "2", "--sampler-spp", "2", "--sampler-converged-spp", "16"]);
    // One material per Type, each fitted, and a report showing each one's four images; the
    // first of Types 0 and 1 again with glints (three images: no PBR input of their own).
    let all: Vec<String> = std::fs::read_dir(demo.join("materials")).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    let (glinty, materials): (Vec<String>, Vec<String>) = all.into_iter().partition(|m| m.ends_with("_glints"));
    let (iridescent, materials): (Vec<String>, Vec<String>) = materials.into_iter().partition(|m| m.ends_with("_iridescent"));
    assert_eq!((materials.len(), glinty.len(), iridescent.len()), (6, 2, 3), "{materials:?} {glinty:?} {iridescent:?}");
    let report = std::fs::read_to_string(demo.join("report/index.html")).unwrap();
    for m in &glinty {
        assert!(demo.join("materials").join(m).join("latent.exr").is_file(), "{m} has no latents");
        for kind in ["reference", "neural", "flip"] {
            let img = format!("img/{m}_{kind}.png");
            assert!(demo.join("report").join(&img).is_file() && report.contains(&img), "the report lacks {img}");
        }
    }
    for m in &materials {
        assert!(demo.join("materials").join(m).join("latent.exr").is_file(), "{m} was not fitted");
        for kind in ["pbr", "reference", "neural", "flip"] {
            let img = format!("img/{m}_{kind}.png");
            assert!(demo.join("report").join(&img).is_file() && report.contains(&img), "the report lacks {img}");
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
