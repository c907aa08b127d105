//! Child processes that die with uplift (issue 46): a kernel runner's `cargo build`, a runner,
//! an ffmpeg encoder. [`tie_to_parent`] makes the child its own process group's leader (so a
//! terminal's Ctrl-C reaches uplift, which stops it, not the build behind uplift's back) and asks
//! the kernel to SIGKILL it when the thread that spawned it ends (`PR_SET_PDEATHSIG`): a
//! SIGKILLed uplift leaves no build running, re-parented to init. The parent's death is checked
//! once more after the request, for a parent that died before it was made. Linux only; elsewhere
//! it does nothing.

use std::process::Command;

/// Ties `cmd`'s child to the calling thread's lifetime (see the module doc). Spawn it from the
/// thread that waits for it.
pub fn tie_to_parent(cmd: &mut Command) -> &mut Command {
    #[cfg(target_os = "linux")]
    {
        use std::os::unix::process::CommandExt;
        // SAFETY: the closure runs in the forked child before exec and only makes the two
        // async-signal-safe system calls prctl and getppid (and kill on itself), touching no
        // memory of the parent's.
        let parent = std::process::id() as libc::pid_t;
        unsafe {
            cmd.pre_exec(move || {
                if libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL as libc::c_ulong, 0, 0, 0) != 0 {
                    return Err(std::io::Error::last_os_error());
                }
                if libc::getppid() != parent {
                    libc::kill(libc::getpid(), libc::SIGKILL);
                }
                Ok(())
            });
        }
        cmd.process_group(0);
    }
    cmd
}

#[cfg(all(test, target_os = "linux"))]
mod tests {
    use super::*;

    #[test]
    fn a_tied_child_runs_in_its_own_group_and_reports_its_status() {
        let out = tie_to_parent(Command::new("sh").args(["-c", "ps -o pgid= -p $$; exit 3"])).output().unwrap();
        assert_eq!(out.status.code(), Some(3));
        let pgid: u32 = String::from_utf8_lossy(&out.stdout).trim().parse().unwrap();
        assert_ne!(pgid, std::process::id(), "the child leads a group of its own");
    }

    #[test]
    fn a_tied_child_is_killed_when_its_spawning_thread_ends() {
        let (tx, rx) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let child = tie_to_parent(Command::new("sleep").arg("30")).spawn().unwrap();
            tx.send(child.id()).unwrap();
            std::mem::forget(child);
        })
        .join()
        .unwrap();
        let pid = rx.recv().unwrap();
        // The kernel delivers SIGKILL as the thread exits; the zombie is reaped by nobody, so
        // look for it as dead (state Z) or gone.
        let deadline = std::time::Instant::now() + std::time::Duration::from_secs(10);
        loop {
            let state = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok().and_then(|s| s.rsplit(')').next().and_then(|r| r.split_whitespace().next().map(str::to_string)));
            if state.as_deref().is_none_or(|s| s == "Z" || s == "X") {
                break;
            }
            assert!(std::time::Instant::now() < deadline, "sleep {pid} still runs ({state:?}) after its spawning thread ended");
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
    }
}
