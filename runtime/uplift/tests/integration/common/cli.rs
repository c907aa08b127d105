//! Running the `uplift` binary from the integration tests: the command (its kernel runners
//! cached in the target folder), a fresh folder per test, the repository root.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::Command;

/// Runs the binary; (exit code, or −1 for a signal; stdout; stderr).
pub fn uplift(args: &[&str]) -> (i32, String, String) {
    // The CPU engine builds runners for kernels it does not ship; keep them in the target folder.
    let cache = Path::new(env!("CARGO_TARGET_TMPDIR")).join("uplift-kernel-cache");
    let out = Command::new(env!("CARGO_BIN_EXE_uplift")).args(args).env("UPLIFT_CACHE_DIR", cache).output().expect("run uplift");
    (out.status.code().unwrap_or(-1), String::from_utf8_lossy(&out.stdout).into(), String::from_utf8_lossy(&out.stderr).into())
}

/// The repository root.
pub fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// An empty folder `uplift-<scope>-<name>-<pid>` in the system's temporary folder (`scope`
/// names the test module, so that modules of the one test binary never share a folder).
pub fn temp_dir(scope: &str, name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("uplift-{scope}-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A path as a command-line argument.
pub fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}
