//! Hostile inputs: arguments (issue 46). Sizes, counts, sample counts, steps and frames have
//! documented bounds (docs/cli.md, `cli/bounds.rs`): a value past one is refused by the parser
//! before anything is allocated or written — no allocation failure, no backtrace, no folder.

use crate::common::cli::{repo, s, temp_dir, uplift};

const SCOPE: &str = "hostile-args";

#[test]
fn sizes_and_counts_past_their_bounds_are_refused_before_anything_is_allocated() {
    let root = temp_dir(SCOPE, "bounds");
    let marble = repo().join("examples/marble.mtlx");
    let out = root.join("out");
    let png = root.join("a.png");
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["render", s(&marble), "-o", s(&png), "--size", "100000"], "invalid value '100000' for '--size <SIZE>': 100000 is not in 1..=8192"),
        (vec!["render", s(&marble), "-o", s(&png), "--spp", "0"], "invalid value '0' for '--spp <SPP>': 0 is not in 1..=65536"),
        (vec!["render", s(&marble), "-o", s(&png), "--bounces", "1000"], "is not in 0..=64"),
        (vec!["datagen", "--count", "18446744073709551615", "-o", s(&out)], "invalid value '18446744073709551615' for '--count <COUNT>': 18446744073709551615 is not in 1..=1099511627776"),
        (vec!["datagen", "--count", "1099511627776", "--shard-rows", "16384", "-o", s(&out)], "--count / --shard-rows: 67108864 is not in 1..=1048576 (shards)"),
        (vec!["datagen", "--count", "16384", "--shard-rows", "1073741824", "-o", s(&out)], "is not in 1..=4194304"),
        (vec!["export", s(&out), "-o", s(&out), "--frames", "100000"], "is not in 1..=4096"),
        (vec!["masks", "--size", "100000", "-o", s(&out)], "is not in 1..=16384"),
        (vec!["fit", s(&out), "--steps", "0"], "0 is not in 1..=100000000"),
        (vec!["train", "-o", s(&out), "--batch", "99999999999"], "is not in 1..=16777216"),
    ];
    for (args, want) in cases {
        let started = std::time::Instant::now();
        let (code, _, stderr) = uplift(&args);
        assert_ne!(code, 0, "{args:?}: {stderr}");
        assert!(stderr.contains(want), "{args:?}: expected `{want}` in: {stderr}");
        assert!(!stderr.contains("memory allocation") && !stderr.contains("panicked") && !stderr.contains("backtrace"), "{args:?}: {stderr}");
        assert!(started.elapsed().as_secs() < 30, "{args:?} took {:?}", started.elapsed());
        assert!(!out.exists() && !png.exists(), "{args:?} wrote something");
    }
    std::fs::remove_dir_all(&root).unwrap();
}
