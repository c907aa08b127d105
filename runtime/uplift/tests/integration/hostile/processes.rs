//! Hostile inputs: processes (issue 46). A kernel too large to build fails within seconds on
//! both engines; a SIGKILLed `uplift` leaves no `cargo build` behind; a user rule builds one
//! CPU runner whatever the materials, seeds and path spellings; wgpu runs print nothing about
//! a missing Wayland display.

use crate::common::cli::{command, repo, s, temp_dir, uplift};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

const SCOPE: &str = "hostile-processes";

/// A nodegraph of one chain of `n` `add` nodes on an interface input.
fn chain(dir: &Path, n: usize) -> PathBuf {
    let mut text = String::from("<?xml version=\"1.0\"?>\n<materialx version=\"1.39\">\n  <nodegraph name=\"g\">\n    <input name=\"x\" type=\"float\" value=\"0.5\" />\n");
    let mut prev = "interfacename=\"x\"".to_string();
    for i in 0..n {
        text += &format!("    <add name=\"a{i}\" type=\"float\"><input name=\"in1\" type=\"float\" {prev} /><input name=\"in2\" type=\"float\" value=\"0.001\" /></add>\n");
        prev = format!("nodename=\"a{i}\"");
    }
    text += &format!("    <output name=\"out\" type=\"float\" nodename=\"a{}\" />\n  </nodegraph>\n</materialx>\n", n - 1);
    let path = dir.join(format!("chain{n}.mtlx"));
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn eval_of_a_20000_node_chain_fails_clearly_within_seconds_on_both_engines() {
    let root = temp_dir(SCOPE, "chain");
    let doc = chain(&root, 20_000);
    let csv = root.join("in.csv");
    std::fs::write(&csv, "x\n0.5\n").unwrap();
    for engine in ["cpu", "wgpu"] {
        let started = Instant::now();
        let (code, _, stderr) = uplift(&["eval", s(&doc), "--output", "g/out", "--engine", engine, "--input", s(&csv), "-o", s(&root.join("out.csv"))]);
        let took = started.elapsed();
        assert_eq!(code, 1, "{engine}: {stderr}");
        assert!(stderr.contains("chain20000.mtlx: output `g/out`: the kernel has 20002 graph values; the engines build kernels of up to 4096"), "{engine}: {stderr}");
        // The limit is checked before any build: the time is the compile's (1–2 s release).
        assert!(took < Duration::from_secs(30), "{engine}: {took:?}");
    }
    // `check` and `compile` still take the document.
    let (code, _, stderr) = uplift(&["check", s(&doc)]);
    assert_eq!(code, 0, "{stderr}");
    std::fs::remove_dir_all(&root).unwrap();
}

/// The pids of processes whose command line contains `needle`.
fn processes_with(needle: &str) -> Vec<u32> {
    let mut out = Vec::new();
    for e in std::fs::read_dir("/proc").unwrap().flatten() {
        let Ok(pid) = e.file_name().to_string_lossy().parse::<u32>() else { continue };
        let Ok(cmdline) = std::fs::read(e.path().join("cmdline")) else { continue };
        if String::from_utf8_lossy(&cmdline).replace('\0', " ").contains(needle) {
            out.push(pid);
        }
    }
    out
}

#[test]
fn a_sigkilled_uplift_leaves_no_runner_build_behind() {
    if !cfg!(target_os = "linux") {
        eprintln!("skipped: PR_SET_PDEATHSIG is Linux's");
        return;
    }
    let root = temp_dir(SCOPE, "pdeathsig");
    // A kernel no other test builds (its constant is this test's own), in a fresh cache: the
    // CPU engine starts `cargo build` for it.
    let doc = root.join("k.mtlx");
    std::fs::write(&doc, "<?xml version=\"1.0\"?>\n<materialx version=\"1.39\">\n  <nodegraph name=\"g\">\n    <input name=\"x\" type=\"float\" value=\"0.5\" />\n    <multiply name=\"m\" type=\"float\"><input name=\"in1\" type=\"float\" interfacename=\"x\" /><input name=\"in2\" type=\"float\" value=\"0.4615\" /></multiply>\n    <output name=\"out\" type=\"float\" nodename=\"m\" />\n  </nodegraph>\n</materialx>\n").unwrap();
    let csv = root.join("in.csv");
    std::fs::write(&csv, "x\n0.5\n").unwrap();
    let cache = root.join("cache");
    let mut child = command(&["eval", s(&doc), "--output", "g/out", "--engine", "cpu", "--input", s(&csv), "-o", s(&root.join("out.csv"))])
        .env("UPLIFT_CACHE_DIR", &cache)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let needle = cache.join("kernels").display().to_string();
    let deadline = Instant::now() + Duration::from_secs(60);
    while processes_with(&needle).is_empty() {
        assert!(child.try_wait().unwrap().is_none(), "uplift ended before its runner build started");
        assert!(Instant::now() < deadline, "no cargo build under {needle} started");
        std::thread::sleep(Duration::from_millis(20));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let deadline = Instant::now() + Duration::from_secs(20);
    loop {
        let left: Vec<u32> = processes_with(&needle).into_iter().filter(|pid| std::fs::read_to_string(format!("/proc/{pid}/stat")).is_ok_and(|st| !st.rsplit(')').next().unwrap_or("").trim_start().starts_with('Z'))).collect();
        if left.is_empty() {
            break;
        }
        assert!(Instant::now() < deadline, "processes of the killed uplift's build still run: {left:?}");
        std::thread::sleep(Duration::from_millis(50));
    }
    std::fs::remove_dir_all(&root).unwrap();
}

/// Runner folders (`uplift-kernel-<hash>`) under a kernel cache.
fn runners(cache: &Path) -> Vec<String> {
    let Ok(entries) = std::fs::read_dir(cache.join("kernels")) else { return Vec::new() };
    let mut names: Vec<String> = entries.flatten().map(|e| e.file_name().to_string_lossy().to_string()).filter(|n| n.starts_with("uplift-kernel-")).collect();
    names.sort();
    names
}

#[test]
fn a_user_rule_builds_one_runner_for_every_material_seed_and_path() {
    let root = temp_dir(SCOPE, "one-runner");
    let cache = Path::new(env!("CARGO_TARGET_TMPDIR")).join("uplift-kernel-cache");
    let rule = root.join("wet.mtlx");
    std::fs::copy(repo().join("examples/rules/wet.mtlx"), &rule).unwrap();
    let run = |input: &str, rule: &str, seed: &str, out: &str| {
        let (code, _, stderr) = uplift(&["enhance", input, "--rule", rule, "--seed", seed, "--resolution", "8x8", "--mask-size", "16", "-o", out]);
        assert_eq!(code, 0, "{stderr}");
    };
    // The first run may build the rule's runner (or find it from an earlier test run).
    let materials = repo().join("examples/pbr_materials.mtlx");
    run(s(&materials), s(&rule), "1", s(&root.join("a")));
    let after_first = runners(&cache);
    // Four materials, two more seeds, the rule by a relative path: no other runner.
    run(s(&materials), s(&rule), "2", s(&root.join("b")));
    let relative = pathdiff(&rule);
    let mut c = command(&["enhance", s(&materials), "--rule", &relative, "--seed", "3", "--resolution", "8x8", "--mask-size", "16", "-o", s(&root.join("c"))]);
    let out = c.current_dir(std::env::current_dir().unwrap()).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(runners(&cache), after_first, "another runner was built for the same rule");
    std::fs::remove_dir_all(&root).unwrap();
}

/// `path` relative to the working directory (`../../tmp/…`).
fn pathdiff(path: &Path) -> String {
    let cwd = std::env::current_dir().unwrap();
    let up = cwd.components().count() - 1;
    format!("{}{}", "../".repeat(up), path.strip_prefix("/").unwrap().display())
}

#[test]
fn wgpu_runs_print_nothing_about_a_missing_wayland_display() {
    let root = temp_dir(SCOPE, "xdg");
    let csv = root.join("in.csv");
    std::fs::write(&csv, "scale\n4\n").unwrap();
    let out = command(&["eval", s(&repo().join("examples/marble.mtlx")), "--output", "out_roughness", "--engine", "wgpu", "--input", s(&csv), "-o", s(&root.join("out.csv"))])
        .env_remove("XDG_RUNTIME_DIR")
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("NODEVICE_SELECT")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(!stderr.contains("XDG_RUNTIME_DIR"), "{stderr}");
    std::fs::remove_dir_all(&root).unwrap();
}
