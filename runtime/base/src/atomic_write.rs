//! Writing output files atomically: write a temporary file beside the target, then rename,
//! so a crash never leaves a partial output. A process killed mid-write (SIGKILL, power loss)
//! still leaves its temporary file; the next write of the same target removes it
//! (`remove_stale`), so a rerun leaves nothing partial behind.

use std::io::Write;
use std::path::Path;

pub fn write_atomically(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let dir = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let name = path.file_name().map(|n| n.to_string_lossy().to_string()).unwrap_or_default();
    remove_stale(dir, &format!(".{name}."), ".tmp");
    let tmp = dir.join(format!(".{name}.{}.tmp", std::process::id()));
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Removes the files and folders in `dir` named `<prefix><pid><suffix>` that a process other
/// than this one left and that no running process owns: what a killed writer left of its
/// temporary file (`.<name>.<pid>.tmp`) or staging folder. A process counts as running where
/// `/proc/<pid>` exists; without procfs every other process's leftovers count as stale.
/// Errors are ignored (a leftover that cannot be removed is left as it was).
pub fn remove_stale(dir: &Path, prefix: &str, suffix: &str) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    let procfs = Path::new("/proc/self").exists();
    for e in entries.flatten() {
        let file_name = e.file_name();
        let Some(pid) = file_name.to_str().and_then(|n| n.strip_prefix(prefix)?.strip_suffix(suffix)?.parse::<u32>().ok()) else { continue };
        if pid == std::process::id() || (procfs && Path::new("/proc").join(pid.to_string()).exists()) {
            continue;
        }
        let path = e.path();
        let _ = if e.file_type().is_ok_and(|t| t.is_dir()) { std::fs::remove_dir_all(&path) } else { std::fs::remove_file(&path) };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_dead_writers_temporary_file_is_removed_and_a_live_ones_kept() {
        let dir = std::env::temp_dir().join(format!("uplift-atomic-write-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        // Pid 4194304 is above Linux's pid_max (2^22): no process has it.
        let dead = dir.join(".out.bin.4194304.tmp");
        std::fs::write(&dead, b"partial").unwrap();
        // Pid 1 (init) always runs.
        let live = dir.join(".out.bin.1.tmp");
        std::fs::write(&live, b"in flight").unwrap();
        let other = dir.join(".other.bin.4194304.tmp");
        std::fs::write(&other, b"another target's").unwrap();
        write_atomically(&dir.join("out.bin"), b"whole").unwrap();
        assert_eq!(std::fs::read(dir.join("out.bin")).unwrap(), b"whole");
        assert!(!dead.exists(), "a dead writer's temporary file is removed");
        assert_eq!(live.exists(), Path::new("/proc/self").exists(), "a running writer's temporary file is kept where procfs tells");
        assert!(other.exists(), "another target's temporary file is not this write's business");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
