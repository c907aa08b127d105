//! The fuzz targets on stable Rust, for CI: the bodies of `fuzz/fuzz_targets/*`
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
use std::time::{Duration, Instant};

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

/// A small seeded generator (xorshift64*), so every run's input sequence is reproducible.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn below(&mut self, n: usize) -> usize {
        if n == 0 { 0 } else { (self.next() % n as u64) as usize }
    }
}

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

/// One mutation of `input` (1–4 edits), drawing on `corpus` for splices.
fn mutate(rng: &mut Rng, corpus: &[Vec<u8>]) -> Vec<u8> {
    let mut v = corpus[rng.below(corpus.len())].clone();
    for _ in 0..1 + rng.below(4) {
        let len = v.len();
        let at = rng.below(len + 1);
        match rng.below(6) {
            0 if len > 0 => {
                let i = rng.below(len);
                v[i] ^= 1 << rng.below(8);
            }
            1 if len > 0 => {
                let end = (at + 1 + rng.below(64)).min(len);
                v.drain(at..end);
            }
            2 if len > 0 => {
                let from = rng.below(len);
                let end = (from + 1 + rng.below(256)).min(len);
                let piece = v[from..end].to_vec();
                v.splice(at..at, piece);
            }
            3 => {
                let other = &corpus[rng.below(corpus.len())];
                let from = rng.below(other.len());
                let end = (from + 1 + rng.below(512)).min(other.len());
                let cut_end = (at + rng.below(512)).min(len);
                v.splice(at..cut_end, other[from..end].iter().copied());
            }
            _ => {
                let t = TOKENS[rng.below(TOKENS.len())].as_bytes();
                v.splice(at..at, t.iter().copied());
            }
        }
    }
    v
}

fn run_target(name: &str, target: fn(&[u8])) {
    let seconds: u64 = std::env::var("UPLIFT_FUZZ_SECONDS").ok().map(|s| s.parse().expect("UPLIFT_FUZZ_SECONDS: a whole number of seconds")).unwrap_or(8);
    let seed: u64 = std::env::var("UPLIFT_FUZZ_SEED").ok().map(|s| s.parse().expect("UPLIFT_FUZZ_SEED: a whole number")).unwrap_or(1);
    let corpus = corpus();
    let last = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("fuzz-stable-{name}.mtlx"));
    let mut rng = Rng(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1);
    let start = Instant::now();
    let budget = Duration::from_secs(seconds);
    let mut runs = 0usize;
    let mut slowest = Duration::ZERO;
    while runs < corpus.len() || start.elapsed() < budget {
        let input = if runs < corpus.len() { corpus[runs].clone() } else { mutate(&mut rng, &corpus) };
        std::fs::write(&last, &input).unwrap();
        let t = Instant::now();
        let result = std::panic::catch_unwind(|| target(&input));
        let took = t.elapsed();
        if let Err(e) = result {
            let msg = e.downcast_ref::<String>().cloned().or_else(|| e.downcast_ref::<&str>().map(|s| s.to_string())).unwrap_or_default();
            panic!("fuzz target `{name}` panicked on input {runs} (seed {seed}), saved as {}: {msg}", last.display());
        }
        assert!(took < Duration::from_secs(10), "fuzz target `{name}` took {took:?} on input {runs} (seed {seed}), saved as {}", last.display());
        slowest = slowest.max(took);
        runs += 1;
    }
    let secs = start.elapsed().as_secs_f64();
    eprintln!("fuzz target `{name}`: {runs} inputs ({} seeds) in {secs:.1} s, {:.0}/s, slowest {slowest:?}", corpus.len(), runs as f64 / secs);
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
