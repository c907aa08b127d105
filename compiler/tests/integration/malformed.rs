//! Malformed documents: every `tests/malformed/*.mtlx` holds one mistake and says, in its
//! first line, which diagnostic a careful user expects:
//!
//! ```text
//! <!-- expect: LINE:COL: MESSAGE -->
//! <!-- expect: include/other.mtlx:LINE:COL: MESSAGE -->
//! ```
//!
//! `LINE:COL` is the element at fault (1-based; the column of its `<`, or of the offending
//! text for XML syntax errors). `MESSAGE` is one or more fragments separated by ` && `, each of
//! which the message must contain. The position's file is the malformed document itself, or the
//! named file relative to `tests/malformed/` when the fault lies in an included document.
//!
//! Each document is checked (`Compiler::check_file`); the test asserts an *error* diagnostic with
//! that position and message, and that the compiler never panics. Each check runs in a child
//! process (this test binary again, see `check_in_child`) under `catch_unwind`, so that a panic
//! is reported clearly and an abort (a stack overflow on runaway recursion) is reported as a
//! crash of that document instead of killing the whole test run.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use uplift_compiler::Compiler;

/// Documents for which the compiler currently reports something other than what is expected
/// (wrong position, missing or unhelpful message), with what it reports. Each entry is a compiler
/// bug to fix: while it keeps failing it is reported but tolerated; once the compiler gets it
/// right, the test fails until the entry is removed. The lead empties this list.
const KNOWN_GAPS: &[(&str, &str)] = &[
];

struct Expectation {
    /// Relative to the repository root (`tests/malformed/x.mtlx`).
    file: String,
    line: u32,
    column: u32,
    fragments: Vec<String>,
}

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().expect("compiler/ has a parent").to_path_buf()
}

fn parse_expectation(rel: &str, text: &str) -> Result<Expectation, String> {
    let first = text.lines().next().unwrap_or("");
    let body = first
        .trim()
        .strip_prefix("<!-- expect:")
        .and_then(|s| s.strip_suffix("-->"))
        .ok_or_else(|| format!("{rel}: the first line must be `<!-- expect: LINE:COL: MESSAGE -->`, found {first:?}"))?
        .trim();
    let bad = || format!("{rel}: cannot read the expectation {body:?}");
    let (head, after) = body.split_once(':').ok_or_else(bad)?;
    let (file, rest) = if head.trim().parse::<u32>().is_ok() {
        (rel.to_string(), body)
    } else {
        (Path::new(rel).parent().unwrap().join(head.trim()).display().to_string(), after)
    };
    let mut it = rest.splitn(3, ':');
    let (Some(line), Some(column), Some(message)) = (it.next(), it.next(), it.next()) else { return Err(bad()) };
    let (line, column) = (line.trim(), column.trim());
    let fragments: Vec<String> = message.split(" && ").map(|s| s.trim().to_string()).filter(|s| !s.is_empty()).collect();
    if fragments.is_empty() {
        return Err(bad());
    }
    Ok(Expectation { file, line: line.parse().map_err(|_| bad())?, column: column.parse().map_err(|_| bad())?, fragments })
}

/// The child test's name as libtest knows it in this binary (tests/integration/main.rs).
const CHILD_TEST: &str = "malformed::child_checks_one_document";

/// Environment variable that makes `child_checks_one_document` check one document.
const CHILD_ENV: &str = "UPLIFT_MALFORMED_CHILD";

/// Checks `rel` in a child process (this test binary, running `child_checks_one_document`):
/// a panic is caught there with `catch_unwind`, and an abort (stack overflow) cannot take the
/// whole test down. Returns the diagnostics, or a description of the crash.
fn check_in_child(rel: &str) -> Result<Vec<Diag>, String> {
    let exe = std::env::current_exe().unwrap();
    let out = std::process::Command::new(exe)
        .args([CHILD_TEST, "--exact", "--nocapture", "--test-threads=1"])
        .env(CHILD_ENV, rel)
        .output()
        .map_err(|e| format!("cannot start the child test process: {e}"))?;
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    let mut diags = Vec::new();
    let mut done = false;
    for line in stdout.lines() {
        // libtest may print `test child_checks_one_document ... ` before the first line.
        let Some(at) = line.find("UPLIFT-") else { continue };
        let line = &line[at..];
        if let Some(rest) = line.strip_prefix("UPLIFT-DIAG\t") {
            let f: Vec<&str> = rest.splitn(5, '\t').collect();
            if let [sev, file, l, c, m] = f.as_slice() {
                diags.push(Diag {
                    error: *sev == "error",
                    file: file.to_string(),
                    line: l.parse().unwrap_or(0),
                    column: c.parse().unwrap_or(0),
                    message: m.replace("\\n", "\n"),
                    text: String::new(),
                });
            }
        } else if let Some(p) = line.strip_prefix("UPLIFT-PANIC\t") {
            return Err(format!("the compiler PANICKED: {}", p.replace("\\n", "\n")));
        } else if line == "UPLIFT-DONE" {
            done = true;
        }
    }
    if !done {
        let tail: Vec<&str> = stderr.lines().rev().take(6).collect::<Vec<_>>().into_iter().rev().collect();
        return Err(format!("the compiler CRASHED (exit status {}):\n      {}", out.status, tail.join("\n      ")));
    }
    for d in &mut diags {
        d.text = format!("{}:{}:{}: {}: {}", d.file, d.line, d.column, if d.error { "error" } else { "warning" }, d.message);
    }
    Ok(diags)
}

/// A diagnostic as the child reports it.
struct Diag {
    error: bool,
    file: String,
    line: u32,
    column: u32,
    message: String,
    text: String,
}

/// Not a test on its own: the child side of `check_in_child`.
#[test]
fn child_checks_one_document() {
    let Some(rel) = std::env::var_os(CHILD_ENV) else { return };
    std::env::set_current_dir(repo_root()).unwrap();
    let rel = PathBuf::from(rel);
    let compiler = Compiler::builtin();
    match catch_unwind(AssertUnwindSafe(|| compiler.check_file(&rel))) {
        Ok(diags) => {
            for d in diags {
                let sev = if d.is_error() { "error" } else { "warning" };
                println!("UPLIFT-DIAG\t{sev}\t{}\t{}\t{}\t{}", d.pos.file, d.pos.line, d.pos.column, d.message.replace('\n', "\\n"));
            }
        }
        Err(p) => println!("UPLIFT-PANIC\t{}", panic_message(&p).replace('\n', "\\n")),
    }
    println!("UPLIFT-DONE");
}

fn panic_message(p: &Box<dyn std::any::Any + Send>) -> String {
    p.downcast_ref::<&str>().map(|s| s.to_string()).or_else(|| p.downcast_ref::<String>().cloned()).unwrap_or_else(|| "(non-string panic)".into())
}

/// Compares file names of positions, whatever the separators.
fn same_file(a: &str, b: &str) -> bool {
    let norm = |s: &str| {
        let p = Path::new(s);
        p.canonicalize().unwrap_or_else(|_| p.to_path_buf())
    };
    a == b || norm(a) == norm(b)
}

#[test]
fn malformed_documents_report_positioned_errors() {
    let root = repo_root();
    std::env::set_current_dir(&root).unwrap();
    let dir = root.join("tests/malformed");
    let mut stems: Vec<String> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("cannot list {}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file() && p.extension().is_some_and(|e| e == "mtlx"))
        .map(|p| p.file_stem().unwrap().to_string_lossy().to_string())
        .collect();
    stems.sort();
    assert!(stems.len() >= 22, "expected at least 22 malformed documents, found {}", stems.len());

    let mut failures = Vec::new();
    let mut gaps = Vec::new();
    for stem in &stems {
        let rel = format!("tests/malformed/{stem}.mtlx");
        let text = std::fs::read_to_string(&rel).unwrap();
        let exp = match parse_expectation(&rel, &text) {
            Ok(e) => e,
            Err(m) => {
                failures.push(m);
                continue;
            }
        };
        let diags = match check_in_child(&rel) {
            Ok(d) => d,
            Err(crash) => {
                let msg = format!("{rel}: {crash}");
                match KNOWN_GAPS.iter().find(|(n, _)| n == stem) {
                    Some((_, why)) => gaps.push(format!("{msg} (known gap: {why})")),
                    None => failures.push(msg),
                }
                continue;
            }
        };
        let ok = diags.iter().any(|d| {
            d.error
                && d.line == exp.line
                && d.column == exp.column
                && same_file(&d.file, &exp.file)
                && exp.fragments.iter().all(|f| d.message.contains(f.as_str()))
        });
        let got: Vec<String> = diags.iter().map(|d| d.text.clone()).collect();
        let got = if got.is_empty() { "no diagnostics".to_string() } else { got.join("\n      ") };
        let wanted = format!("{}:{}:{}: error: …{}…", exp.file, exp.line, exp.column, exp.fragments.join("…"));
        let known = KNOWN_GAPS.iter().find(|(n, _)| n == stem);
        match (ok, known) {
            (true, None) => {}
            (true, Some(_)) => failures.push(format!(
                "{rel}: the compiler now reports the expected diagnostic: remove `{stem}` from KNOWN_GAPS in compiler/tests/integration/malformed.rs"
            )),
            (false, Some((_, why))) => gaps.push(format!("{rel} (known gap: {why})\n      expected {wanted}\n      got      {got}")),
            (false, None) => failures.push(format!("{rel}:\n      expected {wanted}\n      got      {got}")),
        }
    }
    for (n, _) in KNOWN_GAPS {
        if !stems.iter().any(|s| s == n) {
            failures.push(format!("KNOWN_GAPS names `{n}`, which is not in tests/malformed"));
        }
    }
    for g in &gaps {
        eprintln!("known gap: {g}");
    }
    if !failures.is_empty() {
        panic!("{} malformed-document failure(s) over {} documents:\n  - {}", failures.len(), stems.len(), failures.join("\n  - "));
    }
}

/// Documents 20,000 elements deep (nested nodegraphs; a chain of `add` nodes feeding the
/// output), generated here: reading, checking and compiling them to WGSL and Rust gives a result
/// or a positioned error — never a stack overflow (the reader and writer use work lists; the
/// graph builder grows its stack up to `MAX_GRAPH_DEPTH`). Run on a test thread (2 MiB stack).
#[test]
fn documents_20000_deep_compile_or_fail_with_a_position() {
    const N: usize = 20_000;
    let mut nested = String::from("<?xml version=\"1.0\"?>\n<materialx version=\"1.39\">\n");
    for i in 0..N {
        nested += &format!("<nodegraph name=\"g{i}\">\n");
    }
    nested += "<constant name=\"c\" type=\"float\"><input name=\"value\" type=\"float\" value=\"1\"/></constant>\n<output name=\"out\" type=\"float\" nodename=\"c\"/>\n";
    nested += &"</nodegraph>\n".repeat(N);
    nested += "</materialx>\n";
    let mut chain = String::from("<?xml version=\"1.0\"?>\n<materialx version=\"1.39\">\n<constant name=\"n0\" type=\"float\"><input name=\"value\" type=\"float\" value=\"0.5\"/></constant>\n");
    for i in 1..N {
        chain += &format!("<add name=\"n{i}\" type=\"float\"><input name=\"in1\" type=\"float\" nodename=\"n{}\"/><input name=\"in2\" type=\"float\" interfacename=\"step\"/></add>\n", i - 1);
    }
    chain += &format!("<input name=\"step\" type=\"float\" value=\"0.25\"/>\n<output name=\"out\" type=\"float\" nodename=\"n{}\"/>\n</materialx>\n", N - 1);
    let compiler = Compiler::builtin();
    for (name, text) in [("nested.mtlx", &nested), ("chain.mtlx", &chain)] {
        let (doc, diags) = mtlx::read_str(text, name);
        assert!(diags.iter().all(|d| !d.is_error()), "{name}: {:?}", diags.iter().map(|d| d.to_string()).collect::<Vec<_>>());
        // The document writes back out and reads in again unchanged.
        let again = mtlx::read_str(&mtlx::writer::write_string(&doc), name).0;
        assert!(again.same_content(&doc), "{name}: the written document reads back differently");
        let c = compiler.compile_document(doc, diags, name, &uplift_compiler::OutputSelection::AllNumeric);
        for d in c.diagnostics.iter().filter(|d| d.is_error()) {
            assert!(d.pos.line > 0, "{name}: an error without a position: {d}");
        }
        if let Some(k) = &c.kernel {
            uplift_compiler::lower::to_naga(&k.wgsl).unwrap_or_else(|e| panic!("{name}: the emitted WGSL does not re-validate: {}", e.0));
            let rust = uplift_compiler::backend_rust::write_rust_kernel(k).unwrap_or_else(|e| panic!("{name}: the Rust writer failed: {e}"));
            assert!(!rust.is_empty());
        }
        eprintln!("{name}: {} ({} diagnostics)", if c.kernel.is_some() { "compiled" } else { "no kernel" }, c.diagnostics.len());
        if name == "chain.mtlx" {
            assert!(c.kernel.is_some(), "the 20,000-node chain compiles: {:?}", c.diagnostics.iter().map(|d| d.to_string()).collect::<Vec<_>>());
        }
    }
}
