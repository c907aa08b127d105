//! Hostile inputs: outputs (issue 46). A command that writes a folder never destroys what it
//! did not write (uplift_base::output_folder): a foreign non-empty folder or a file at the
//! output path is refused and left byte-identical; a rerun onto the command's own output works;
//! `--force` writes beside foreign files and keeps them. `shards` verifies the files its
//! manifests record; a batch `fit` with other settings than its finished fits' says so; errors
//! name the user's files, never a staging copy.

use crate::common::cli::{repo, s, temp_dir, uplift};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

const SCOPE: &str = "hostile-outputs";

fn copper() -> PathBuf {
    repo().join("tests/hostile/outputs/copper.mtlx")
}

/// Every file under `root` with its bytes, by relative path (hidden files included).
fn snapshot(root: &Path) -> BTreeMap<String, Vec<u8>> {
    let mut out = BTreeMap::new();
    let mut work = vec![root.to_path_buf()];
    while let Some(dir) = work.pop() {
        for e in std::fs::read_dir(&dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                work.push(p);
            } else {
                out.insert(p.strip_prefix(root).unwrap().to_string_lossy().to_string(), std::fs::read(&p).unwrap());
            }
        }
    }
    out
}

/// A folder of someone's files: two at the top, one in a subfolder named like an output's.
fn foreign_folder(dir: &Path) {
    std::fs::create_dir_all(dir.join("textures")).unwrap();
    std::fs::write(dir.join("thesis.tex"), "\\documentclass{article} % a user's file\n").unwrap();
    std::fs::write(dir.join("photo.jpg"), [0xff, 0xd8, 0xff, 0xe0, 1, 2, 3]).unwrap();
    std::fs::write(dir.join("textures/wood.png"), b"not a png, but the user's").unwrap();
}

fn enhance_args<'a>(input: &'a str, out: &'a str, extra: &[&'a str]) -> Vec<&'a str> {
    let mut a = vec!["enhance", input, "--type", "0", "--seed", "1", "--resolution", "8x8", "--mask-size", "16", "-o", out];
    a.extend_from_slice(extra);
    a
}

#[test]
fn enhance_refuses_a_foreign_folder_and_leaves_every_file_byte_identical() {
    let root = temp_dir(SCOPE, "foreign");
    let out = root.join("home");
    foreign_folder(&out);
    let before = snapshot(&out);
    for input in [copper(), repo().join("examples/pbr_materials.mtlx")] {
        let (code, _, stderr) = uplift(&enhance_args(s(&input), s(&out), &[]));
        assert_eq!(code, 1, "enhance {} onto a foreign folder must fail: {stderr}", input.display());
        assert!(stderr.contains("did not write") && stderr.contains("`photo.jpg`") && stderr.contains("--force"), "the error names the folder's files and the way out: {stderr}");
        assert_eq!(snapshot(&out), before, "enhance {} changed the foreign folder", input.display());
    }
    // Nothing was left beside it either (no staging folder).
    assert_eq!(std::fs::read_dir(&root).unwrap().count(), 1);
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn enhance_refuses_a_file_at_the_output_path_even_with_force() {
    let root = temp_dir(SCOPE, "file");
    let out = root.join("notes.txt");
    std::fs::write(&out, "a user's notes\n").unwrap();
    for force in [&[][..], &["--force"][..]] {
        let (code, _, stderr) = uplift(&enhance_args(s(&copper()), s(&out), force));
        assert_eq!(code, 1, "enhance onto a file {force:?}: {stderr}");
        assert!(stderr.contains("notes.txt: exists and is not a folder"), "{stderr}");
        assert_eq!(std::fs::read_to_string(&out).unwrap(), "a user's notes\n");
    }
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn enhance_reruns_onto_its_own_output_and_force_keeps_foreign_files() {
    let root = temp_dir(SCOPE, "own");
    let out = root.join("copper");
    let (code, _, stderr) = uplift(&enhance_args(s(&copper()), s(&out), &[]));
    assert_eq!(code, 0, "{stderr}");
    let first = snapshot(&out);
    assert!(first.contains_key("params.exr") && first.contains_key("meta.json") && first.contains_key(".uplift-output-enhance"), "{:?}", first.keys());
    // A user's file put into the output, and a fit's record of it.
    std::fs::write(out.join("my_notes.txt"), "keep me").unwrap();
    std::fs::write(out.join("fit.json"), "{}").unwrap();
    // The rerun (another seed) replaces enhance's own files, keeps the note, drops the stale fit record.
    let input = copper();
    let mut other_seed = enhance_args(s(&input), s(&out), &[]);
    other_seed[5] = "2";
    let (code, _, stderr) = uplift(&other_seed);
    assert_eq!(code, 0, "a rerun onto its own output: {stderr}");
    let second = snapshot(&out);
    assert_eq!(second["my_notes.txt"], b"keep me");
    assert!(!second.contains_key("fit.json"), "the fit of the replaced parameters must not survive them");
    assert_ne!(second["meta.json"], first["meta.json"], "the rerun with seed 2 must replace meta.json");
    let own: Vec<&String> = first.keys().collect();
    assert_eq!(second.keys().filter(|k| *k != "my_notes.txt").collect::<Vec<_>>(), own, "the rerun writes the same files");

    // --force onto a foreign folder: enhance's files go beside the user's, which stay as they were.
    let forced = root.join("forced");
    foreign_folder(&forced);
    let before = snapshot(&forced);
    let (code, _, stderr) = uplift(&enhance_args(s(&copper()), s(&forced), &["--force"]));
    assert_eq!(code, 0, "{stderr}");
    let after = snapshot(&forced);
    for (name, bytes) in &before {
        assert_eq!(after.get(name), Some(bytes), "--force changed the user's {name}");
    }
    assert!(after.contains_key("params.exr") && after.contains_key("meta.json"));
    // A foreign file with an output's name is never replaced, with --force too.
    let clash = root.join("clash");
    foreign_folder(&clash);
    std::fs::write(clash.join("meta.json"), "the user's meta.json").unwrap();
    let before = snapshot(&clash);
    let (code, _, stderr) = uplift(&enhance_args(s(&copper()), s(&clash), &["--force"]));
    assert_eq!(code, 1, "{stderr}");
    assert!(stderr.contains("meta.json: exists and was not written by `uplift enhance`"), "{stderr}");
    assert_eq!(snapshot(&clash), before);
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn shards_verifies_the_files_its_manifests_record() {
    let root = temp_dir(SCOPE, "shards");
    let out = root.join("data");
    for shard in ["0/2", "1/2"] {
        let (code, _, stderr) = uplift(&["datagen", "--class", "haze", "--count", "32768", "--shard-rows", "16384", "--shard", shard, "-o", s(&out)]);
        assert_eq!(code, 0, "{stderr}");
    }
    let (code, stdout, stderr) = uplift(&["shards", s(&out)]);
    assert_eq!(code, 0, "{stdout}{stderr}");
    assert!(stdout.contains("datagen: 2/2 shards complete (2 started); 2 finished, 0 missing, 0 duplicated, 0 damaged"), "{stdout}");
    // One shard's file deleted, the other's changed by a byte: neither is reported finished.
    let files: Vec<PathBuf> = std::fs::read_dir(&out).unwrap().map(|e| e.unwrap().path()).filter(|p| p.extension().is_some_and(|e| e == "safetensors")).collect();
    assert_eq!(files.len(), 2, "{files:?}");
    std::fs::remove_file(&files[0]).unwrap();
    let mut bytes = std::fs::read(&files[1]).unwrap();
    let last = bytes.len() - 1;
    bytes[last] ^= 1;
    std::fs::write(&files[1], bytes).unwrap();
    let (code, stdout, _) = uplift(&["shards", s(&out)]);
    assert_eq!(code, 1, "{stdout}");
    assert!(stdout.contains("0 finished, 0 missing, 0 duplicated, 2 damaged"), "{stdout}");
    assert!(stdout.contains(&format!("{} is gone", files[0].display())), "{stdout}");
    assert!(stdout.contains(&format!("{} changed since it was written (SHA-256 differs)", files[1].display())), "{stdout}");
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn a_batch_fit_with_other_settings_refits_and_says_why() {
    let root = temp_dir(SCOPE, "refit");
    let out = root.join("batch");
    let (code, _, stderr) = uplift(&["enhance", s(&repo().join("examples/pbr_materials.mtlx")), "--type", "0", "--resolution", "4x4", "--mask-size", "16", "-o", s(&out)]);
    assert_eq!(code, 0, "{stderr}");
    let (code, _, stderr) = uplift(&["fit", s(&out), "--steps", "3"]);
    assert_eq!(code, 0, "{stderr}");
    let (code, _, stderr) = uplift(&["fit", s(&out), "--steps", "3"]);
    assert_eq!(code, 0, "{stderr}");
    assert!(stderr.contains("fitted 0 material(s)") && stderr.contains("4 already fitted with these settings"), "{stderr}");
    let (code, _, stderr) = uplift(&["fit", s(&out), "--steps", "2"]);
    assert_eq!(code, 0, "{stderr}");
    assert!(stderr.contains("refitting: its fit.json records --steps 3, this run 2"), "{stderr}");
    assert!(stderr.contains("fitted 4 material(s)") && stderr.contains("(4 refitted: their fits had other settings)"), "{stderr}");
    let fit: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("copper/fit.json")).unwrap()).unwrap();
    assert_eq!(fit["steps"], 2);
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn errors_name_the_users_files_never_a_staging_copy() {
    let root = temp_dir(SCOPE, "staging");
    // A rule whose graph passes the interface check but not the compiler (line 40: a node input
    // its nodedef lacks).
    let wet = std::fs::read_to_string(repo().join("examples/rules/wet.mtlx")).unwrap();
    let from = "      <input name=\"in2\" type=\"float\" interfacename=\"wetness\" />\n    </multiply>";
    assert!(wet.contains(from));
    let rule = root.join("bad_input_name.mtlx");
    std::fs::write(&rule, wet.replacen(from, "      <input name=\"in2\" type=\"float\" interfacename=\"wetness\" />\n      <input name=\"in7\" type=\"float\" value=\"1\" />\n    </multiply>", 1)).unwrap();
    let (code, _, stderr) = uplift(&["enhance", s(&copper()), "--rule", s(&rule), "--resolution", "8x8", "--mask-size", "16", "-o", s(&root.join("out"))]);
    assert_eq!(code, 1, "{stderr}");
    assert!(stderr.contains(&format!("{}:41:", rule.display())) && !stderr.contains(".staging-"), "{stderr}");
    // A truncated texture: the error names the user's file.
    let png = std::fs::read(repo().join("tests/hostile/paths/secret.png")).unwrap();
    let truncated = root.join("base.png");
    std::fs::write(&truncated, &png[..png.len() - 20]).unwrap();
    let grey = root.join("grey.png");
    std::fs::copy(repo().join("tests/hostile/paths/secret.png"), &grey).unwrap();
    let (code, _, stderr) = uplift(&["enhance", "--base-color", s(&truncated), "--roughness", s(&grey), "--metalness", s(&grey), "--type", "0", "--mask-size", "16", "-o", s(&root.join("out2"))]);
    assert_eq!(code, 1, "{stderr}");
    assert!(stderr.contains(&truncated.display().to_string()) && !stderr.contains(".staging-"), "{stderr}");
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn compile_never_exits_0_with_nothing_written_and_writes_one_file_per_material() {
    let root = temp_dir(SCOPE, "compile");
    let materials = repo().join("examples/pbr_materials.mtlx");
    let (code, stdout, stderr) = uplift(&["compile", s(&materials), "--target", "spirv", "-o", s(&root)]);
    assert_eq!(code, 1, "{stdout}{stderr}");
    assert!(stderr.contains("nothing written") && stderr.contains("give --context eval|albedo|sample|pdf"), "{stderr}");
    assert_eq!(std::fs::read_dir(&root).unwrap().count(), 0);
    // With a context, each material into its own file, as MaterialX's generateshader.py does.
    let (code, stdout, stderr) = uplift(&["compile", s(&materials), "--context", "eval", "--target", "wgsl", "-o", s(&root)]);
    assert_eq!(code, 0, "{stderr}");
    let mut names: Vec<String> = std::fs::read_dir(&root).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().to_string()).collect();
    names.sort();
    assert_eq!(names, ["pbr_materials_blue_plastic.wgsl", "pbr_materials_ceramic.wgsl", "pbr_materials_copper.wgsl", "pbr_materials_red_cloth.wgsl"], "{stdout}");
    // --output names one: one file, named after the document.
    let one = root.join("one");
    let (code, _, stderr) = uplift(&["compile", s(&materials), "--context", "eval", "--output", "copper", "--target", "wgsl", "-o", s(&one)]);
    assert_eq!(code, 0, "{stderr}");
    assert!(one.join("pbr_materials.wgsl").is_file());
    std::fs::remove_dir_all(&root).unwrap();
}
