//! What the fuzz targets share: [`keep_last_input`], so that a run killed by a signal
//! libFuzzer cannot report (a stack overflow faults again inside its handler, which then saves
//! nothing) still leaves the input that killed it.

use std::path::PathBuf;
use std::sync::OnceLock;

/// Writes `data` to the file `UPLIFT_FUZZ_LAST_INPUT` names, if set, before each execution
/// (`/dev/shm/…` keeps it cheap): after a crash the file holds the crashing input.
pub fn keep_last_input(data: &[u8]) {
    static PATH: OnceLock<Option<PathBuf>> = OnceLock::new();
    if let Some(path) = PATH.get_or_init(|| std::env::var_os("UPLIFT_FUZZ_LAST_INPUT").map(PathBuf::from)) {
        let _ = std::fs::write(path, data);
    }
}
