//! Records, from the workspace's Cargo.lock, the exact versions of the crates the CPU engine's
//! kernel runners depend on (`cpu_engine/external.rs` writes them into each runner's manifest),
//! so a runner builds against the same glam, rayon and multiversion as the runtime.

use std::path::PathBuf;

fn main() {
    let manifest = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").unwrap());
    let lock = manifest.join("../../Cargo.lock");
    println!("cargo:rerun-if-changed={}", lock.display());
    let lock = std::fs::read_to_string(&lock).unwrap_or_default();
    for (krate, fallback) in [("glam", "=0.30.10"), ("rayon", "1"), ("multiversion", "0.8")] {
        let version = locked_version(&lock, krate).map(|v| format!("={v}")).unwrap_or_else(|| fallback.to_string());
        println!("cargo:rustc-env=UPLIFT_RUNNER_{}_VERSION={version}", krate.to_uppercase());
    }
}

/// The version Cargo.lock records for `krate`.
fn locked_version(lock: &str, krate: &str) -> Option<String> {
    let head = format!("name = \"{krate}\"\nversion = \"");
    let at = lock.find(&head)? + head.len();
    Some(lock[at..].split('"').next()?.to_string())
}
