//! The runtime's crates form layers (ARCHITECTURE.md, "Crates"): each may depend only on the
//! workspace crates listed for it here, so a lower layer never reaches a higher one (engines →
//! neural, anything → the CLI). Cargo already forbids cycles; this test forbids the edges that
//! would be legal for Cargo but break the layering. It reads the workspace's manifests through
//! `cargo metadata`, normal and build dependencies alike (dev-dependencies are tests' business).

use std::collections::{BTreeMap, BTreeSet};
use std::process::Command;

/// Each workspace crate and the workspace crates it may depend on.
const ALLOWED: &[(&str, &[&str])] = &[
    ("mtlx", &[]),
    ("uplift_compiler", &["mtlx"]),
    ("uplift_base", &[]),
    ("uplift_simd", &[]),
    ("uplift_kernels", &["uplift_base", "uplift_simd"]),
    ("uplift_engines", &["uplift_base", "uplift_simd", "uplift_kernels", "mtlx", "uplift_compiler"]),
    ("uplift_material", &["uplift_base", "uplift_simd", "uplift_kernels", "uplift_engines", "mtlx", "uplift_compiler"]),
    ("uplift_enhance", &["uplift_base", "uplift_simd", "uplift_kernels", "uplift_engines", "uplift_material", "mtlx", "uplift_compiler"]),
    ("uplift_neural", &["uplift_base", "uplift_simd", "uplift_kernels", "uplift_engines", "uplift_material", "mtlx", "uplift_compiler"]),
    ("uplift_render", &["uplift_base", "uplift_simd", "uplift_kernels", "uplift_engines", "uplift_material", "uplift_enhance", "uplift_neural", "mtlx", "uplift_compiler"]),
    ("uplift", &["uplift_base", "uplift_simd", "uplift_kernels", "uplift_engines", "uplift_material", "uplift_enhance", "uplift_neural", "uplift_render", "mtlx", "uplift_compiler"]),
    ("uplift_rs_snapshots", &["mtlx", "uplift_compiler", "uplift_base", "uplift_simd", "uplift_engines"]),
];

/// (crate, its workspace dependencies) from `cargo metadata`.
fn workspace_edges() -> BTreeMap<String, BTreeSet<String>> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let manifest = concat!(env!("CARGO_MANIFEST_DIR"), "/../../Cargo.toml");
    let out = Command::new(cargo).args(["metadata", "--format-version", "1", "--no-deps", "--offline", "--manifest-path", manifest]).output().expect("cargo metadata runs");
    assert!(out.status.success(), "cargo metadata failed: {}", String::from_utf8_lossy(&out.stderr));
    let meta: serde_json::Value = serde_json::from_slice(&out.stdout).expect("cargo metadata prints JSON");
    let packages = meta["packages"].as_array().expect("packages");
    let members: BTreeSet<String> = packages.iter().map(|p| p["name"].as_str().unwrap().to_string()).collect();
    packages
        .iter()
        .map(|p| {
            let deps = p["dependencies"]
                .as_array()
                .unwrap()
                .iter()
                .filter(|d| d["kind"].as_str() != Some("dev"))
                .map(|d| d["name"].as_str().unwrap().to_string())
                .filter(|d| members.contains(d))
                .collect();
            (p["name"].as_str().unwrap().to_string(), deps)
        })
        .collect()
}

/// Edges of `edges` that `allowed` does not permit, and crates it does not know.
fn violations(edges: &BTreeMap<String, BTreeSet<String>>, allowed: &[(&str, &[&str])]) -> Vec<String> {
    let allowed: BTreeMap<&str, &[&str]> = allowed.iter().copied().collect();
    let mut bad = Vec::new();
    for (krate, deps) in edges {
        let Some(ok) = allowed.get(krate.as_str()) else {
            bad.push(format!("`{krate}` is a workspace crate with no layer: add it to ALLOWED and to ARCHITECTURE.md"));
            continue;
        };
        for d in deps {
            if !ok.contains(&d.as_str()) {
                bad.push(format!("`{krate}` depends on `{d}`, which is not below it"));
            }
        }
    }
    bad
}

#[test]
fn runtime_crates_depend_only_downwards() {
    let edges = workspace_edges();
    for krate in ["uplift_base", "uplift_simd", "uplift_kernels", "uplift_engines", "uplift_material", "uplift_enhance", "uplift_neural", "uplift_render", "uplift"] {
        assert!(edges.contains_key(krate), "`{krate}` is not a workspace member");
    }
    let bad = violations(&edges, ALLOWED);
    assert!(bad.is_empty(), "layering violations:\n{}", bad.join("\n"));
}

#[test]
fn an_upward_edge_is_reported() {
    // The check itself: an engines → neural edge and an edge into the CLI crate are caught.
    let mut edges = workspace_edges();
    edges.get_mut("uplift_engines").unwrap().insert("uplift_neural".into());
    edges.get_mut("uplift_render").unwrap().insert("uplift".into());
    let bad = violations(&edges, ALLOWED);
    assert_eq!(bad.len(), 2, "{bad:?}");
    assert!(bad[0].contains("`uplift_engines` depends on `uplift_neural`") || bad[1].contains("`uplift_engines` depends on `uplift_neural`"), "{bad:?}");
}
