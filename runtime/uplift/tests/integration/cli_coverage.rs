//! Every subcommand of the `uplift` binary as a user meets it on a bad day: `--help` exits 0 and
//! names the command; an unknown flag exits 2 with clap's message; a missing input file or
//! folder, a folder that is not an enhanced material, or an output that cannot be written exits
//! 1 with a message naming the path — never a panic (exit 101) or a signal.

use std::path::{Path, PathBuf};
use std::process::Command;

fn uplift(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_uplift")).args(args).output().expect("run uplift");
    (out.status.code().unwrap_or(-1), String::from_utf8_lossy(&out.stdout).into(), String::from_utf8_lossy(&out.stderr).into())
}

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
    let d = std::env::temp_dir().join(format!("uplift-cli-coverage-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
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
