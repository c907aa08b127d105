//! The `enhance` fuzz targets on stable Rust, for CI (`uplift_compiler::fuzz_stable`): the
//! bodies of `fuzz/fuzz_targets/{gltf,rule}.rs` (`uplift_enhance::fuzz_entry`) over their seed
//! corpus — glTF and GLB assets built by `fuzz_entry::gltf_seeds` (file, `data:` and GLB
//! buffers, transforms, factors, textures inside and outside the folder) and, when
//! `UPLIFT_MTLX_DATA` is set, MaterialX's `Geometry/*.glb`; the shipped rules, rule options and
//! example rules — and then seeded mutations of it for `UPLIFT_FUZZ_SECONDS` each (default 8).

use std::path::{Path, PathBuf};
use uplift_enhance::fuzz_entry;

/// glTF words a mutation inserts: members, numbers past every range, URIs that escape.
const GLTF_TOKENS: &[&str] = &[
    "\"uri\":\"../outside/secret.png\"", "\"uri\":\"/etc/passwd\"", "\"uri\":\"..%2Foutside%2Fsecret.bin\"", "\"uri\":\"data:image/png;base64,AAAA\"",
    "\"scale\":[1e30,1e30,1e30]", "\"matrix\":[1e300,0,0,0,0,1,0,0,0,0,1,0,0,0,0,1]", "\"translation\":[1e38,0,0]", "\"rotation\":[0,0,0,0]",
    "\"metallicFactor\":-3", "\"roughnessFactor\":1e39", "\"baseColorFactor\":[50,0,0,1]", "\"scale\":-1e38", "\"children\":[0]",
    "\"count\":4294967295", "\"byteOffset\":4294967295", "\"byteStride\":255", "\"componentType\":5125", "\"type\":\"MAT4\"",
    "\"indices\":1", "\"mode\":1", "\"mode\":6", "\"normalized\":true", "1e39", "-0", "NaN", "null", "[]", "{}", ",", ":", "\"",
];

/// Rule words a mutation inserts: random scalars with hostile ranges and distributions,
/// includes that escape, masks, the stack's outputs.
const RULE_TOKENS: &[&str] = &[
    " uimin=\"-1e30\"", " uimax=\"1e39\"", " uimin=\"nan\"", " uimax=\"inf\"", " uplift_distribution=\"normal(nan, 0.08)\"",
    " uplift_distribution=\"normal(0.5, 1e308)\"", " uplift_distribution=\"optional(2)\"", " type=\"float\"", " type=\"color3\"",
    "<xi:include href=\"../outside/secret.mtlx\"/>", "<xi:include href=\"/etc/passwd\"/>", "<input name=\"x\" type=\"float\" value=\"0.5\" uimin=\"0\" uimax=\"1\"/>",
    "<input name=\"m\" type=\"filename\" value=\"masks/dust.png\"/>", "<output name=\"haze_weight_out\" type=\"float\" nodename=\"n\"/>",
    "<nodegraph name=\"uplift_rule\">", "</nodegraph>", " interfacename=\"x\"", " nodename=\"n\"", " value=\"1e39\"", "<", ">", "/>", "\"",
];

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn files(dir: &Path, ext: &str) -> Vec<Vec<u8>> {
    let mut paths: Vec<PathBuf> = std::fs::read_dir(dir).map(|d| d.flatten().map(|e| e.path()).filter(|p| p.extension().is_some_and(|e| e == ext)).collect()).unwrap_or_default();
    paths.sort();
    paths.iter().map(|p| std::fs::read(p).unwrap()).collect()
}

/// Runs `target` over `corpus` and its mutations; with `UPLIFT_FUZZ_WRITE_SEEDS=DIR` it writes
/// the corpus to `DIR/<name>/` instead (fuzz/seed-corpus.sh seeds `cargo fuzz` so).
fn run(name: &str, corpus: &[Vec<u8>], tokens: &[&str], target: fn(&[u8])) {
    if let Some(dir) = std::env::var_os("UPLIFT_FUZZ_WRITE_SEEDS") {
        let dir = Path::new(&dir).join(name);
        std::fs::create_dir_all(&dir).unwrap();
        for (k, seed) in corpus.iter().enumerate() {
            std::fs::write(dir.join(format!("seed-{k:03}")), seed).unwrap();
        }
        return;
    }
    uplift_compiler::fuzz_stable::run(name, corpus, tokens, &last_input(name), target);
}

fn last_input(name: &str) -> PathBuf {
    Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("fuzz-stable-{name}.bin"))
}

#[test]
fn gltf_survives_mutated_assets() {
    let mut corpus = fuzz_entry::gltf_seeds();
    match std::env::var_os("UPLIFT_MTLX_DATA") {
        Some(data) => corpus.extend(files(&Path::new(&data).join("Geometry"), "glb").into_iter().filter(|g| g.len() < 4 << 20)),
        None => eprintln!("UPLIFT_MTLX_DATA is not set: the glTF seeds are fuzz_entry::gltf_seeds only"),
    }
    run("gltf", &corpus, GLTF_TOKENS, fuzz_entry::gltf);
}

#[test]
fn rule_survives_mutated_rules() {
    let mut corpus = files(&repo().join("mtlx/rules"), "mtlx");
    corpus.extend(files(&repo().join("mtlx/rules/options"), "mtlx"));
    corpus.extend(files(&repo().join("examples/rules"), "mtlx"));
    assert!(corpus.len() >= 8, "rule seeds: {}", corpus.len());
    run("rule", &corpus, RULE_TOKENS, fuzz_entry::rule);
}
