//! Kill and resume (issue 23, item 7): `enhance`, `fit`, `datagen` and `train` SIGKILLed at
//! seeded random points and then rerun end as an uninterrupted run of the same command ends:
//! - every output file has the same bytes (wall-clock times that records keep aside);
//! - nothing partial is left: the file tree equals the uninterrupted run's (no temporary file of
//!   an atomic write, no staging folder, no checkpoint);
//! - nothing is done twice: what a run found finished stays untouched (same inode: never
//!   rewritten, not even with the same bytes), and the rerun says it skipped it or from which
//!   checkpoint step it resumed.
//!
//! The kill points are seeded random fractions of the uninterrupted run's wall time (one very
//! early, during start-up), so they fall inside the run however fast the machine is; `train`'s
//! are fractions of its start-up and of its training after it, so that kills leave checkpoints.

use crate::common::cli::{command, repo, s, temp_dir, uplift, uplift_killed_after, Ending};
use crate::common::Rng;
use std::collections::BTreeMap;
use std::os::unix::fs::MetadataExt;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};
use uplift_neural::weights::TensorFile;

const SCOPE: &str = "kill_resume";

/// Runs the binary to completion; its stderr and wall time.
fn run_ok(args: &[&str]) -> (String, Duration) {
    let start = Instant::now();
    let (code, stdout, stderr) = uplift(args);
    assert_eq!(code, 0, "uplift {}: {stdout}{stderr}", args.join(" "));
    (stderr, start.elapsed())
}

/// Kill delays for a run that takes `d` uninterrupted: one at 3 % (start-up), then `n` drawn
/// from `seed` in `[lo, hi)` × `d`.
fn kill_delays(seed: u64, d: Duration, n: usize, lo: f32, hi: f32) -> Vec<Duration> {
    let mut rng = Rng::new(seed);
    std::iter::once(0.03).chain((0..n).map(|_| rng.range(lo, hi))).map(|f| d.mul_f32(f)).collect()
}

/// Every file and folder under `root` (folders with a trailing `/`), relative, sorted; hidden
/// ones included.
fn tree(root: &Path) -> Vec<String> {
    let mut out = Vec::new();
    let mut work = vec![root.to_path_buf()];
    while let Some(dir) = work.pop() {
        for e in std::fs::read_dir(&dir).unwrap() {
            let p = e.unwrap().path();
            let rel = p.strip_prefix(root).unwrap().to_string_lossy().to_string();
            if p.is_dir() {
                out.push(format!("{rel}/"));
                work.push(p);
            } else {
                out.push(rel);
            }
        }
    }
    out.sort();
    out
}

/// Asserts that `b` holds the same files as `a` with the same bytes, after `normalise`
/// (relative path, bytes) takes out what legitimately differs.
fn assert_same_outputs(a: &Path, b: &Path, normalise: impl Fn(&str, Vec<u8>) -> Vec<u8>) {
    let (ta, tb) = (tree(a), tree(b));
    assert_eq!(tb, ta, "the resumed run's files ({}) differ from the uninterrupted run's ({})", b.display(), a.display());
    for rel in ta.iter().filter(|r| !r.ends_with('/')) {
        let (x, y) = (normalise(rel, std::fs::read(a.join(rel)).unwrap()), normalise(rel, std::fs::read(b.join(rel)).unwrap()));
        assert!(x == y, "{rel}: the resumed run's bytes differ from the uninterrupted run's");
    }
}

/// The inode of each file in `paths` that exists, by name.
fn inodes(paths: impl IntoIterator<Item = PathBuf>) -> BTreeMap<String, u64> {
    paths.into_iter().filter_map(|p| Some((p.to_string_lossy().to_string(), std::fs::metadata(&p).ok()?.ino()))).collect()
}

/// Runs `args` once per delay, killed there, and checks after each run that every file
/// `finished` listed before it is still the same file (not rewritten, not removed).
fn kill_loop(args: &[&str], delays: &[Duration], finished: impl Fn() -> BTreeMap<String, u64>) -> Vec<Ending> {
    let mut endings = Vec::new();
    for &delay in delays {
        let before = finished();
        let (ending, stderr) = uplift_killed_after(args, delay);
        assert!(matches!(ending, Ending::Killed | Ending::Exited(0)), "uplift {} killed at {delay:?}: {ending:?}: {stderr}", args.join(" "));
        let after = finished();
        for (file, ino) in &before {
            assert_eq!(after.get(file), Some(ino), "{file}, finished before the run killed at {delay:?}, was rewritten or removed by it");
        }
        endings.push(ending);
    }
    assert_eq!(endings[0], Ending::Killed, "the start-up kill at {:?} came after the run ended", delays[0]);
    endings
}

/// Batch enhancement of the four materials of examples/pbr_materials.mtlx at 128²: finished
/// material folders (meta.json present) are skipped and never rewritten; an unfinished one's
/// staging folder is removed by the rerun.
#[test]
fn enhance_killed_and_rerun_ends_as_an_uninterrupted_run() {
    let root = temp_dir(SCOPE, "enhance");
    let input = repo().join("examples/pbr_materials.mtlx");
    let args = |out: &Path| -> Vec<String> { ["enhance", s(&input), "--seed", "3", "--resolution", "128x128", "--mask-size", "128", "-o", s(out)].map(String::from).to_vec() };
    let (a, b) = (root.join("a"), root.join("b"));
    let args_a = args(&a);
    let (_, d) = run_ok(&args_a.iter().map(String::as_str).collect::<Vec<_>>());
    let args_b = args(&b);
    let args_b: Vec<&str> = args_b.iter().map(String::as_str).collect();
    let finished = || {
        // Output folders only: a killed run's staging folder (`.name.staging-PID`) may already
        // hold its meta.json, but it is no finished output until renamed into place.
        let output = |p: &std::path::Path| p.file_name().is_some_and(|n| !n.to_string_lossy().starts_with('.'));
        let dirs = std::fs::read_dir(&b).map(|r| r.flatten().map(|e| e.path()).filter(|p| output(p) && p.join("meta.json").exists()).collect::<Vec<_>>()).unwrap_or_default();
        inodes(dirs.iter().flat_map(|p| [p.join("meta.json"), p.join("params.exr"), p.join("material.mtlx")]))
    };
    kill_loop(&args_b, &kill_delays(71, d, 4, 0.1, 0.9), finished);
    let done = finished().len() / 3;
    let before = finished();
    let (stderr, _) = run_ok(&args_b);
    assert!(stderr.contains(&format!("enhanced {} material(s) into {}; {done} already finished", 4 - done, b.display())), "the rerun must skip the {done} finished material(s): {stderr}");
    let after = finished();
    assert!(before.iter().all(|(f, ino)| after.get(f) == Some(ino)), "the rerun rewrote a finished material");
    assert_same_outputs(&a, &b, |_, bytes| bytes);
    std::fs::remove_dir_all(&root).unwrap();
}

/// Datagen of 6 shards of 16,384 rows: written shards are skipped and never rewritten; a
/// half-written shard's temporary file is removed when the rerun writes that shard.
#[test]
fn datagen_killed_and_rerun_ends_as_an_uninterrupted_run() {
    let root = temp_dir(SCOPE, "datagen");
    let (a, b) = (root.join("a"), root.join("b"));
    let args = |out: &Path| -> Vec<String> { ["datagen", "--count", "98304", "--shard-rows", "16384", "--seed", "5", "-o", s(out)].map(String::from).to_vec() };
    let args_a = args(&a);
    let (_, d) = run_ok(&args_a.iter().map(String::as_str).collect::<Vec<_>>());
    // Six shards and datagen's output manifest (uplift_base::output_folder).
    assert_eq!(tree(&a).len(), 7, "{:?}", tree(&a));
    assert!(tree(&a).contains(&".uplift-output-datagen".to_string()), "{:?}", tree(&a));
    let args_b = args(&b);
    let args_b: Vec<&str> = args_b.iter().map(String::as_str).collect();
    let finished = || inodes((0..6).map(|k| b.join(format!("all-{k:05}.safetensors"))));
    kill_loop(&args_b, &kill_delays(72, d, 4, 0.1, 0.9), finished);
    let done = finished().len();
    let before = finished();
    let (stderr, _) = run_ok(&args_b);
    assert!(stderr.contains(&format!("wrote {} shard(s) to {}; {done} already written", 6 - done, b.display())), "the rerun must skip the {done} written shard(s): {stderr}");
    let after = finished();
    assert!(before.iter().all(|(f, ino)| after.get(f) == Some(ino)), "the rerun rewrote a written shard");
    assert_same_outputs(&a, &b, |_, bytes| bytes);
    std::fs::remove_dir_all(&root).unwrap();
}

/// Fitting one enhanced material (100 steps): `fit` has no checkpoint, so a killed fit starts
/// again from the encoder on the rerun (its partial steps are lost, not repeated into the
/// result); fit.json is written last, so wherever it exists the latents beside it are final.
/// fit.json's `seconds` (wall time) is left out of the comparison.
#[test]
fn fit_killed_and_rerun_ends_as_an_uninterrupted_run() {
    let root = temp_dir(SCOPE, "fit");
    let enhanced = root.join("enhanced");
    run_ok(&["enhance", s(&repo().join("examples/pbr_materials.mtlx")), "--seed", "3", "--resolution", "16x16", "--mask-size", "32", "-o", s(&enhanced)]);
    let (a, b) = (root.join("a"), root.join("b"));
    for dst in [&a, &b] {
        copy_tree(&enhanced.join("copper"), dst);
    }
    let args = |m: &Path| -> Vec<String> { ["fit", s(m), "--steps", "100", "--threads", "2", "--seed", "6"].map(String::from).to_vec() };
    let args_a = args(&a);
    let (_, d) = run_ok(&args_a.iter().map(String::as_str).collect::<Vec<_>>());
    let args_b = args(&b);
    let args_b: Vec<&str> = args_b.iter().map(String::as_str).collect();
    let delays = kill_delays(73, d, 4, 0.1, 0.95);
    for &delay in &delays {
        let (ending, stderr) = uplift_killed_after(&args_b, delay);
        assert!(matches!(ending, Ending::Killed | Ending::Exited(0)), "fit killed at {delay:?}: {ending:?}: {stderr}");
        if b.join("fit.json").exists() {
            for f in ["latent.exr", "latent0.png", "latent1.png"] {
                assert_eq!(std::fs::read(b.join(f)).ok(), std::fs::read(a.join(f)).ok(), "{f} beside a fit.json after the run killed at {delay:?} is not the final one");
            }
        }
    }
    let (stderr, _) = run_ok(&args_b);
    assert_eq!(stderr.lines().filter(|l| l.starts_with("fitted ")).count(), 1, "{stderr}");
    assert_same_outputs(&a, &b, |rel, bytes| {
        if rel != "fit.json" {
            return bytes;
        }
        let text = String::from_utf8(bytes).unwrap();
        assert_eq!(text.matches("\"seconds\":").count(), 1, "{text}");
        text.lines().filter(|l| !l.trim_start().starts_with("\"seconds\":")).collect::<Vec<_>>().join("\n").into_bytes()
    });
    std::fs::remove_dir_all(&root).unwrap();
}

/// Training 300 steps of 1,024 rows with a checkpoint every 5 steps (not a multiple of the
/// 20-step loss record, so a resume lands inside a record's window), killed three times: every
/// run that gets past its start resumes from the checkpoint's step (never an earlier one) and
/// says so, the final weights equal the uninterrupted run's, and the checkpoint is gone at the
/// end. The weights file's `seconds` and the `seconds` column of its `history` (wall time) are
/// left out of the comparison.
#[test]
fn train_killed_and_rerun_ends_as_an_uninterrupted_run() {
    let root = temp_dir(SCOPE, "train");
    let (a, b) = (root.join("a"), root.join("b"));
    let args = |dir: &Path| -> Vec<String> {
        ["train", "--steps", "300", "--batch", "1024", "--checkpoint-every", "5", "--holdout", "1024", "--threads", "2", "--seed", "4", "-o", s(&dir.join("decoder.safetensors"))].map(String::from).to_vec()
    };
    // The uninterrupted run, timed: its start-up (until the first checkpoint) and its training.
    let args_a = args(&a);
    let start = Instant::now();
    let mut child = command(&args_a.iter().map(String::as_str).collect::<Vec<_>>()).stdout(std::process::Stdio::null()).stderr(std::process::Stdio::null()).spawn().unwrap();
    let mut first_checkpoint = None;
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if first_checkpoint.is_none() && a.join("decoder.checkpoint.safetensors").exists() {
            first_checkpoint = Some(start.elapsed());
        }
        std::thread::sleep(Duration::from_millis(2));
    };
    assert!(status.success(), "the uninterrupted train: {status}");
    let d = start.elapsed();
    let startup = first_checkpoint.expect("the uninterrupted run never wrote a checkpoint");
    let args_b = args(&b);
    let args_b: Vec<&str> = args_b.iter().map(String::as_str).collect();
    let (ckpt, out) = (b.join("decoder.checkpoint.safetensors"), b.join("decoder.safetensors"));
    let step = || TensorFile::read(&ckpt).ok().map(|f| f.meta("step").unwrap().parse::<u64>().unwrap());
    // A run that starts from checkpoint step `from` and trains on (or finishes) must say so.
    let check_resume = |from: u64, stderr: &str, what: &str| {
        let said = format!("resuming from {} at step {from} of 300", ckpt.display());
        assert_eq!(stderr.contains(&said), from > 0, "{what} started at checkpoint step {from}: {stderr}");
    };
    // Kill points: one in the start-up, then two after it, each training at most 40 % of the run
    // (the time after the start-up), so that the kills leave a checkpoint to resume.
    let (mut last, mut resumed, mut finished) = (0, 0, false);
    let mut rng = Rng::new(74);
    let delays = [startup.mul_f32(rng.range(0.0, 1.0))].into_iter().chain((0..2).map(|_| startup + (d - startup).mul_f32(rng.range(0.1, 0.4))));
    for delay in delays {
        let (ending, stderr) = uplift_killed_after(&args_b, delay);
        assert!(matches!(ending, Ending::Killed | Ending::Exited(0)), "train killed at {delay:?}: {ending:?}: {stderr}");
        let now = step();
        if ending == Ending::Exited(0) {
            // It ran to the end after all (a machine faster now than when `d` was measured).
            assert!(now.is_none() && out.exists(), "train exited by itself, yet left no weights or its checkpoint");
            check_resume(last, &stderr, &format!("the run meant to be killed at {delay:?}"));
            resumed += (last > 0) as usize;
            finished = true;
            break;
        }
        let now = now.unwrap_or(0);
        assert!(now >= last, "the run killed at {delay:?} went back from checkpoint step {last} to {now}");
        if now > last {
            check_resume(last, &stderr, &format!("the run killed at {delay:?}"));
            resumed += (last > 0) as usize;
        }
        last = now;
    }
    if !finished && last == 0 {
        // Every timed kill came before the first checkpoint (a machine slower now than when the
        // run was timed): kill once a checkpoint exists, so that the rerun has one to resume.
        let mut child = command(&args_b).stdout(std::process::Stdio::null()).stderr(std::process::Stdio::null()).spawn().unwrap();
        while child.try_wait().unwrap().is_none() && step().unwrap_or(0) == 0 {
            std::thread::sleep(Duration::from_millis(2));
        }
        let _ = child.kill();
        let ended = child.wait().unwrap();
        assert!(ended.success() || ended.code().is_none(), "train killed after its first checkpoint: {ended}");
        if ended.success() {
            finished = true;
            assert!(out.exists() && step().is_none(), "train exited by itself, yet left no weights or its checkpoint");
        } else {
            last = step().unwrap_or(0);
        }
    }
    if !finished {
        let (stderr, _) = run_ok(&args_b);
        check_resume(last, &stderr, "the rerun");
        resumed += (last > 0) as usize;
    }
    assert!(resumed > 0, "no run resumed from a checkpoint: the kills all came before the first one");
    assert_same_outputs(&a, &b, |_, bytes| without_wall_time(bytes));
    std::fs::remove_dir_all(&root).unwrap();
}

/// A weights file's bytes without its wall times: the `seconds` entry and the last (`seconds`)
/// column of `history`.
fn without_wall_time(bytes: Vec<u8>) -> Vec<u8> {
    let mut f = TensorFile::from_bytes(&bytes).unwrap();
    assert!(f.metadata.remove("seconds").is_some(), "no `seconds` entry");
    let history = f.metadata.get_mut("history").expect("a `history` entry");
    assert!(history.starts_with("step,loss,loss_f,loss_t,loss_r,lr,seconds\n"), "{history}");
    *history = history.lines().map(|l| l.rsplit_once(',').unwrap().0).collect::<Vec<_>>().join("\n");
    f.to_bytes().unwrap()
}

/// Copies the folder `from` to `to`, recursively.
fn copy_tree(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let p = e.unwrap().path();
        let dst = to.join(p.file_name().unwrap());
        if p.is_dir() {
            copy_tree(&p, &dst);
        } else {
            std::fs::copy(&p, &dst).unwrap();
        }
    }
}
