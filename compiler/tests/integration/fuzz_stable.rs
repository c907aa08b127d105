//! The fuzz targets on stable Rust, for CI (`uplift_compiler::fuzz_stable`): the bodies of `fuzz/fuzz_targets/*`
//! (`uplift_compiler::fuzz_entry::{read, check, compile}`) run over their seed corpus — the
//! snapshot inputs `tests/in`, the malformed documents `tests/malformed` and, when
//! `UPLIFT_MTLX_DATA` is set, MaterialX's TestSuite — and then over seeded random mutations of it
//! (byte edits, range deletions and copies, splices of two seeds, MaterialX tokens inserted) for
//! a time budget. Without coverage guidance this finds less than `cargo fuzz`; it keeps every
//! input class the fuzzers found crashes in (tests/malformed) from regressing and catches gross
//! faults on each push.
//!
//! Budget: `UPLIFT_FUZZ_SECONDS` per target (default 8: CI spends ≈ 25 s of CPU here); seed:
//! `UPLIFT_FUZZ_SEED` (default 1). Before each input runs it is written to
//! `$CARGO_TARGET_TMPDIR/fuzz-stable-<target>.mtlx`, so that an abort (a stack overflow kills the
//! process) leaves the input behind; a panic reports the input's file and its iteration. An
//! input that takes longer than 10 s counts as a hang and fails too.

use std::path::{Path, PathBuf};

/// The MaterialX words a mutation inserts: element and attribute names, types, values
/// MaterialX rejects, XML syntax.
const TOKENS: &[&str] = &[
    "<nodegraph name=\"g\">", "</nodegraph>", "<input name=\"in\" type=\"float\" value=\"1\"/>",
    "<output name=\"out\" type=\"color3\" nodename=\"n\"/>", "<nodedef name=\"ND_x\" node=\"x\">", "</nodedef>",
    "<add name=\"n\" type=\"float\">", "</add>", "<multiply name=\"m\" type=\"color3\">", "</multiply>",
    "<xi:include href=\"fuzz.mtlx\"/>", "<image name=\"i\" type=\"color3\">", "<input name=\"file\" type=\"filename\" value=\"x.png\"/>",
    " nodename=\"n\"", " nodegraph=\"g\"", " output=\"out\"", " interfacename=\"in\"", " type=\"vector3\"", " type=\"integer\"",
    " type=\"boolean\"", " type=\"matrix44\"", " type=\"BSDF\"", " type=\"surfaceshader\"", " type=\"multioutput\"",
    " value=\"nan\"", " value=\"inf\"", " value=\"1e39\"", " value=\"1, 2\"", " value=\"\"", " value=\"-0\"",
    " fileprefix=\"../\"", " colorspace=\"srgb_texture\"", " version=\"1.38\"", " channels=\"rgb\"", " channels=\"zz\"",
    " uniform=\"true\"", " default=\"0\"", " nodedef=\"ND_add_float\"", " node=\"add\"", " namespace=\"ns\"",
    "<!-- c -->", "<![CDATA[x]]>", "&amp;", "&#0;", "\u{0}", "<", ">", "/>", "\"", "=", " ",
];

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap().to_path_buf()
}

/// The `.mtlx` files under `dir`, sorted.
fn mtlx_files(dir: &Path) -> impl Iterator<Item = PathBuf> {
    mtlx::library::files_under(dir).into_iter().filter(|p| p.extension().is_some_and(|e| e == "mtlx"))
}

/// The seed corpus (the same folders `fuzz/seed-corpus.sh` copies for `cargo fuzz`).
fn corpus() -> Vec<Vec<u8>> {
    let root = repo_root();
    let mut files = Vec::new();
    files.extend(mtlx_files(&root.join("tests/in")));
    files.extend(mtlx_files(&root.join("tests/malformed")));
    match std::env::var_os("UPLIFT_MTLX_DATA") {
        Some(data) => files.extend(mtlx_files(&Path::new(&data).join("Materials/TestSuite"))),
        None => eprintln!("UPLIFT_MTLX_DATA is not set: the seed corpus is tests/in and tests/malformed only"),
    }
    let corpus: Vec<Vec<u8>> = files.iter().map(|f| std::fs::read(f).unwrap()).collect();
    assert!(corpus.len() >= 100, "seed corpus of only {} documents", corpus.len());
    corpus
}

fn run_target(name: &str, target: fn(&[u8])) {
    let last = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("fuzz-stable-{name}.mtlx"));
    uplift_compiler::fuzz_stable::run(name, &corpus(), TOKENS, &last, target);
}

#[test]
fn read_survives_mutated_documents() {
    run_target("read", uplift_compiler::fuzz_entry::read);
}

#[test]
fn check_survives_mutated_documents() {
    run_target("check", uplift_compiler::fuzz_entry::check);
}

#[test]
fn compile_survives_mutated_documents() {
    run_target("compile", uplift_compiler::fuzz_entry::compile);
}
