//! Hostile inputs: paths (issue 46). No reader follows a name out of the input's folder without
//! `--allow-any-path`: glTF image and buffer URIs (relative, absolute, percent-encoded),
//! `xi:include`s of `check` and of `enhance`'s rules, MaterialX textures and `fileprefix`. The
//! message for a name outside is the same whether or not a file is there (tested with one that
//! exists and one that does not), and no message holds a byte of the file.

use crate::common::cli::{repo, s, temp_dir, uplift};
use std::path::{Path, PathBuf};

const SCOPE: &str = "hostile-paths";

/// A folder `input/` for the user's files beside `outside/`, which holds a secret image, a
/// secret buffer and a secret document.
fn folders(name: &str) -> (PathBuf, PathBuf, PathBuf) {
    let root = temp_dir(SCOPE, name);
    let (input, outside) = (root.join("input"), root.join("outside"));
    std::fs::create_dir_all(&input).unwrap();
    std::fs::create_dir_all(&outside).unwrap();
    std::fs::copy(repo().join("tests/hostile/paths/secret.png"), outside.join("secret.png")).unwrap();
    std::fs::write(outside.join("secret.bin"), mesh_bytes()).unwrap();
    std::fs::write(outside.join("secret.mtlx"), "<?xml version=\"1.0\"?>\n<materialx version=\"1.39\">\n  <!-- SECRET-DOCUMENT-TEXT -->\n</materialx>\n").unwrap();
    (root, input, outside)
}

/// One triangle: 3 positions then 3 texture coordinates, little-endian f32.
fn mesh_bytes() -> Vec<u8> {
    let v: [f32; 15] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0];
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// A glTF of one textured triangle whose buffer is `buffer_uri` and base colour image `image_uri`.
fn gltf(buffer_uri: &str, image_uri: &str) -> String {
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"TEXCOORD_0":1}},"material":0}}]}}],
"materials":[{{"name":"m","pbrMetallicRoughness":{{"baseColorTexture":{{"index":0}}}}}}],
"textures":[{{"source":0}}],"images":[{{"uri":"{image_uri}"}}],
"buffers":[{{"uri":"{buffer_uri}","byteLength":60}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":24}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,0,1]}},{{"bufferView":1,"componentType":5126,"count":3,"type":"VEC2"}}]}}"#
    )
}

fn enhance(input: &Path, out: &Path, extra: &[&str]) -> (i32, String) {
    let mut args = vec!["enhance", s(input), "--type", "0", "--resolution", "8x8", "--mask-size", "16", "-o", s(out)];
    args.extend_from_slice(extra);
    let (code, _, stderr) = uplift(&args);
    (code, stderr)
}

/// The error with the test's folders written as placeholders, so that two errors about two
/// names can be compared.
fn shape(stderr: &str, root: &Path, names: &[&str]) -> String {
    let mut t = stderr.replace(&root.display().to_string(), "ROOT");
    for n in names {
        t = t.replace(n, "NAME");
    }
    t
}

#[test]
fn gltf_image_uris_outside_are_refused_alike_whether_or_not_the_file_exists() {
    let (root, input, outside) = folders("gltf-image");
    std::fs::write(input.join("mesh.bin"), mesh_bytes()).unwrap();
    let secret = outside.join("secret.png");
    let absolute = secret.display().to_string();
    let missing_absolute = outside.join("missing.png").display().to_string();
    let cases: [(&str, &str); 4] = [
        ("../outside/secret.png", "../outside/missing.png"),
        (&absolute, &missing_absolute),
        ("..%2Foutside%2Fsecret.png", "..%2Foutside%2Fmissing.png"),
        ("%2E%2E/outside/secret.png", "%2E%2E/outside/missing.png"),
    ];
    for (k, (exists, missing)) in cases.iter().enumerate() {
        let mut shapes = Vec::new();
        for uri in [exists, missing] {
            let file = input.join(format!("a{k}.gltf"));
            std::fs::write(&file, gltf("mesh.bin", uri)).unwrap();
            let out = root.join(format!("out{k}"));
            let (code, stderr) = enhance(&file, &out, &[]);
            assert_eq!(code, 1, "{uri}: {stderr}");
            assert!(stderr.contains("outside the input's folder") && stderr.contains("--allow-any-path"), "{uri}: {stderr}");
            assert!(!out.exists(), "{uri}: an output was written");
            shapes.push(shape(&stderr, &root, &[exists, missing, "secret.png", "missing.png"]));
        }
        assert_eq!(shapes[0], shapes[1], "the message tells whether {exists} exists");
    }
    // With --allow-any-path the image outside is read: its one pixel is the base colour.
    let file = input.join("allowed.gltf");
    std::fs::write(&file, gltf("mesh.bin", "../outside/secret.png")).unwrap();
    let (code, stderr) = enhance(&file, &root.join("allowed"), &["--allow-any-path"]);
    assert_eq!(code, 0, "{stderr}");
    assert!(root.join("allowed/textures").is_dir());
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn gltf_buffer_uris_outside_are_refused_and_no_bytes_reach_the_message() {
    let (root, input, outside) = folders("gltf-buffer");
    std::fs::copy(repo().join("tests/hostile/paths/secret.png"), input.join("albedo.png")).unwrap();
    let secret = outside.join("secret.bin").display().to_string();
    for uri in ["/etc/passwd", "../outside/secret.bin", secret.as_str(), "..%2Foutside%2Fsecret.bin", "../outside/missing.bin"] {
        let file = input.join("b.gltf");
        std::fs::write(&file, gltf(uri, "albedo.png")).unwrap();
        let (code, stderr) = enhance(&file, &root.join("out"), &[]);
        assert_eq!(code, 1, "{uri}: {stderr}");
        assert!(stderr.contains("buffer 0") && stderr.contains("outside the input's folder"), "{uri}: {stderr}");
        assert!(!stderr.contains("root:") && !stderr.contains("out of range"), "{uri}: the message shows the file's bytes: {stderr}");
    }
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn includes_outside_are_refused_by_check_and_by_enhance_rules() {
    let (root, input, outside) = folders("include");
    let secret = outside.join("secret.mtlx").display().to_string();
    for href in ["../outside/secret.mtlx", "/etc/passwd", secret.as_str(), "../outside/missing.mtlx"] {
        let doc = input.join("doc.mtlx");
        std::fs::write(&doc, format!("<?xml version=\"1.0\"?>\n<materialx version=\"1.39\" xmlns:xi=\"http://www.w3.org/2001/XInclude\">\n  <xi:include href=\"{href}\" />\n</materialx>\n")).unwrap();
        let (code, _, stderr) = uplift(&["check", s(&doc)]);
        assert_eq!(code, 1, "{href}: {stderr}");
        assert!(stderr.contains("doc.mtlx:3:") && stderr.contains("outside the input's folder"), "{href}: {stderr}");
        assert!(!stderr.contains("SECRET-DOCUMENT-TEXT") && !stderr.contains("root:"), "{href}: {stderr}");
    }
    // A rule that includes a document outside: enhance refuses it at the rule's line.
    let wet = std::fs::read_to_string(repo().join("examples/rules/wet.mtlx")).unwrap();
    let library = "<xi:include href=\"../../mtlx/libraries/uplift/uplift_defs.mtlx\" />";
    assert!(wet.contains(library));
    let hostile = wet.replacen(library, &format!("{library}\n  <xi:include href=\"../outside/secret.mtlx\" />"), 1);
    let rule = input.join("wet.mtlx");
    std::fs::write(&rule, &hostile).unwrap();
    let (code, _, stderr) = uplift(&["enhance", s(&repo().join("tests/hostile/outputs/copper.mtlx")), "--rule", s(&rule), "--resolution", "8x8", "--mask-size", "16", "-o", s(&root.join("out"))]);
    assert_eq!(code, 1, "{stderr}");
    assert!(stderr.contains("wet.mtlx:") && stderr.contains("outside the input's folder"), "{stderr}");
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn a_rule_copied_out_of_the_repository_checks_and_enhances_alike() {
    // wet.mtlx includes the uplift library by a relative path; from any folder, `check` reads
    // it from the builtin library as `enhance` does.
    let root = temp_dir(SCOPE, "wet-copy");
    let rule = root.join("wet.mtlx");
    std::fs::copy(repo().join("examples/rules/wet.mtlx"), &rule).unwrap();
    let (code, _, stderr) = uplift(&["check", s(&rule)]);
    assert_eq!(code, 0, "check of a copy of wet.mtlx: {stderr}");
    let (code, _, stderr) = uplift(&["enhance", s(&repo().join("tests/hostile/outputs/copper.mtlx")), "--rule", s(&rule), "--resolution", "8x8", "--mask-size", "16", "-o", s(&root.join("out"))]);
    assert_eq!(code, 0, "enhance with a copy of wet.mtlx: {stderr}");
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn mtlx_textures_outside_are_refused_alike_whether_or_not_the_file_exists() {
    let (root, input, _) = folders("texture");
    let mut shapes = Vec::new();
    for name in ["secret.png", "missing.png"] {
        let doc = input.join("m.mtlx");
        std::fs::write(
            &doc,
            format!(
                "<?xml version=\"1.0\"?>\n<materialx version=\"1.39\">\n  <image name=\"i\" type=\"color3\" fileprefix=\"../outside/\">\n    <input name=\"file\" type=\"filename\" value=\"{name}\" />\n  </image>\n  <gltf_pbr name=\"s\" type=\"surfaceshader\">\n    <input name=\"base_color\" type=\"color3\" nodename=\"i\" />\n  </gltf_pbr>\n  <surfacematerial name=\"m\" type=\"material\">\n    <input name=\"surfaceshader\" type=\"surfaceshader\" nodename=\"s\" />\n  </surfacematerial>\n</materialx>\n"
            ),
        )
        .unwrap();
        let (code, stderr) = enhance(&doc, &root.join("out"), &[]);
        assert_eq!(code, 1, "{name}: {stderr}");
        assert!(stderr.contains("m.mtlx:4:") && stderr.contains("outside the input's folder"), "{name}: {stderr}");
        let (code, _, check) = uplift(&["check", s(&doc)]);
        assert_eq!(code, 1, "check {name}: {check}");
        assert!(check.contains("outside the input's folder"), "check {name}: {check}");
        shapes.push((shape(&stderr, &root, &[name]), shape(&check, &root, &[name])));
    }
    assert_eq!(shapes[0], shapes[1], "the messages tell whether the texture exists");
    std::fs::remove_dir_all(&root).unwrap();
}
