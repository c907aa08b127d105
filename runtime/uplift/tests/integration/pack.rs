//! `uplift pack` (uplift::pack): two exported assets packed into WebDataset shards small enough
//! to need two; Python reads the shards — with the `webdataset` package when it is installed
//! (.ci/run installs it), else the standard library's `tarfile`, saying which — reconstructs
//! every sample's members byte for byte against the export folders, and verifies index.json's
//! SHA-256s and offsets; packing twice gives identical bytes; bad input is a clear error.

use std::path::Path;

const READER: &str = r#"
import hashlib, io, json, os, sys, tarfile
shards, exports = sys.argv[1], sys.argv[2:]
index = json.load(open(os.path.join(shards, "index.json")))
urls = [os.path.join(shards, s["name"]) for s in index["shards"]]
try:
    import webdataset
    samples = {}
    for s in webdataset.WebDataset(urls, shardshuffle=False, empty_check=False):
        samples[s["__key__"]] = {k: v for k, v in s.items() if not k.startswith("__")}
    reader = "webdataset " + webdataset.__version__ if hasattr(webdataset, "__version__") else "webdataset"
except ImportError:
    samples = {}
    for u in urls:
        with tarfile.open(u) as t:
            for m in t.getmembers():
                key, ext = m.name.split(".", 1)
                samples.setdefault(key, {})[ext] = t.extractfile(m).read()
    reader = "tarfile (webdataset is not installed)"
assert sorted(samples) == sorted(s["asset"] for s in index["samples"]), (sorted(samples), index["samples"])
for s in index["samples"]:
    shard = open(os.path.join(shards, s["shard"]), "rb").read()
    got = samples[s["asset"]]
    assert len(got) == len(s["members"]), (s["asset"], len(got), len(s["members"]))
    for m in s["members"]:
        data = got[m["name"].split(".", 1)[1]]
        assert hashlib.sha256(data).hexdigest() == m["sha256"], m["name"]
        assert shard[m["offset"]:m["offset"] + m["size"]] == data, m["name"]
for sh in index["shards"]:
    assert hashlib.sha256(open(os.path.join(shards, sh["name"]), "rb").read()).hexdigest() == sh["sha256"], sh["name"]
# Every file of every export is a member, with its bytes.
for e in exports:
    asset = os.path.basename(e)
    n = 0
    for root, _, files in os.walk(e):
        for f in files:
            rel = os.path.relpath(os.path.join(root, f), e).replace(os.sep, ".")
            assert samples[asset][rel] == open(os.path.join(root, f), "rb").read(), (asset, rel)
            n += 1
    assert n == len(samples[asset]), (asset, n, len(samples[asset]))
print(f"{reader}: {len(samples)} samples, {sum(len(v) for v in samples.values())} members, {len(urls)} shards verified")
"#;

#[test]
fn shards_read_back_in_python_and_pack_deterministically() {
    let root = Path::new(env!("CARGO_TARGET_TMPDIR")).join("pack_test");
    let _ = std::fs::remove_dir_all(&root);
    let a = crate::export::small_export(&root, "asset_a", 2, 1);
    let b = crate::export::small_export(&root, "asset_b", 3, 2);
    // A shard limit below two assets' size: two shards, one asset each.
    let one: u64 = walk_bytes(&a);
    let (s1, s2) = (root.join("shards1"), root.join("shards2"));
    let summary = uplift::pack::pack(&[b.clone(), a.clone()], &s1, one + 64 * 1024).unwrap();
    assert_eq!((summary.samples, summary.shards), (2, 2));
    uplift::pack::pack(&[a.clone(), b.clone()], &s2, one + 64 * 1024).unwrap();
    for f in ["index.json", "shard-000000.tar", "shard-000001.tar"] {
        assert!(std::fs::read(s1.join(f)).unwrap() == std::fs::read(s2.join(f)).unwrap(), "{f} differs between two packs");
    }
    // Bad input: a folder that is no export, a name with WebDataset's separator, one asset twice.
    assert!(uplift::pack::pack(&[root.join("mesh")], &root.join("x"), 1 << 20).unwrap_err().contains("not an export"));
    let dotted = root.join("a.b");
    std::fs::create_dir_all(&dotted).unwrap();
    assert!(uplift::pack::pack(&[dotted], &root.join("x"), 1 << 20).unwrap_err().contains("'.'"));
    assert!(uplift::pack::pack(&[a.clone(), a.clone()], &root.join("x"), 1 << 20).unwrap_err().contains("two exports"));

    let python_ok = std::process::Command::new("python3").arg("--version").output().is_ok_and(|o| o.status.success());
    if !python_ok {
        return uplift_base::test_env::skip("shards_read_back_in_python", "needs python3 (.ci/run has it)");
    }
    let script = root.join("read_shards.py");
    std::fs::write(&script, READER).unwrap();
    let o = std::process::Command::new("python3").arg(&script).arg(&s1).arg(&a).arg(&b).output().unwrap();
    assert!(o.status.success(), "python: {}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    let said = String::from_utf8_lossy(&o.stdout);
    eprintln!("{}", said.trim());
    if std::env::var_os("UPLIFT_REQUIRE_ALL").is_some() {
        assert!(said.starts_with("webdataset"), "UPLIFT_REQUIRE_ALL is set but Python read the shards without webdataset: {said}");
    }
    let _ = std::fs::remove_dir_all(&root);
}

fn walk_bytes(dir: &Path) -> u64 {
    std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()).map(|p| if p.is_dir() { walk_bytes(&p) } else { std::fs::metadata(&p).unwrap().len().div_ceil(512) * 512 + 512 }).sum()
}
