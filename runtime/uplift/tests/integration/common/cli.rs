//! Running the `uplift` binary from the integration tests: the command (its kernel runners
//! cached in the target folder), the command killed part-way, a fresh folder per test, the
//! repository root.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// The binary with `args`, as `uplift` runs it.
pub fn command(args: &[&str]) -> Command {
    // The CPU engine builds runners for kernels it does not ship; keep them in the target folder.
    let cache = Path::new(env!("CARGO_TARGET_TMPDIR")).join("uplift-kernel-cache");
    let mut c = Command::new(env!("CARGO_BIN_EXE_uplift"));
    c.args(args).env("UPLIFT_CACHE_DIR", cache);
    c
}

/// Runs the binary; (exit code, or −1 for a signal; stdout; stderr).
pub fn uplift(args: &[&str]) -> (i32, String, String) {
    uplift_with(args, &[])
}

/// [`uplift`] with environment variables set for the run.
pub fn uplift_with(args: &[&str], env: &[(&str, &str)]) -> (i32, String, String) {
    let out = command(args).envs(env.iter().copied()).output().expect("run uplift");
    (out.status.code().unwrap_or(-1), String::from_utf8_lossy(&out.stdout).into(), String::from_utf8_lossy(&out.stderr).into())
}

/// How a run of `uplift_killed_after` ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Ending {
    /// Still running at the deadline, and SIGKILLed there.
    Killed,
    /// Exited by itself first, with this code (−1 for a signal).
    Exited(i32),
}

/// Starts the binary (stdout discarded) and SIGKILLs it (`Child::kill` on unix) `delay` after
/// the start unless it has exited by then; how it ended, and its stderr so far (kept in a pipe:
/// for commands that print less than a pipe holds, 64 KiB on Linux).
pub fn uplift_killed_after(args: &[&str], delay: Duration) -> (Ending, String) {
    let start = Instant::now();
    let mut child = command(args).stdout(Stdio::null()).stderr(Stdio::piped()).spawn().expect("start uplift");
    let ending = loop {
        if let Some(status) = child.try_wait().expect("wait for uplift") {
            break Ending::Exited(status.code().unwrap_or(-1));
        }
        let left = delay.saturating_sub(start.elapsed());
        if left.is_zero() {
            let _ = child.kill();
            // A child that exited between the last poll and the kill has its own exit code.
            break match child.wait().expect("wait for uplift").code() {
                Some(code) => Ending::Exited(code),
                None => Ending::Killed,
            };
        }
        std::thread::sleep(left.min(Duration::from_millis(2)));
    };
    let mut stderr = String::new();
    let _ = std::io::Read::read_to_string(&mut child.stderr.take().unwrap(), &mut stderr);
    (ending, stderr)
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
