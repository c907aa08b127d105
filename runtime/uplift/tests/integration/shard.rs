//! The shard contract (uplift::shard): `--shard` specs and the environment of job arrays, the
//! hash assignment (one shard per asset, balanced), and the manifests' status.

use uplift::shard::{status, Shard, ShardRun};


fn env(pairs: &'static [(&'static str, &'static str)]) -> impl Fn(&str) -> Option<String> {
    move |k| pairs.iter().find(|(n, _)| *n == k).map(|(_, v)| v.to_string())
}

#[test]
fn specs_parse_and_bad_ones_are_clear_errors() {
    let none = env(&[]);
    assert_eq!(Shard::parse("2/4", &none).unwrap(), Shard { index: 2, count: 4 });
    assert!(Shard::parse("4/4", &none).unwrap_err().contains("out of range"));
    assert!(Shard::parse("0/0", &none).unwrap_err().contains("at least 1"));
    assert!(Shard::parse("x", &none).unwrap_err().contains("expected i/N"));
    assert!(Shard::parse("auto", &none).unwrap_err().contains("SLURM_ARRAY_TASK_ID"));
    let slurm = env(&[("SLURM_ARRAY_TASK_ID", "5"), ("SLURM_ARRAY_TASK_MIN", "4"), ("SLURM_ARRAY_TASK_MAX", "7"), ("SLURM_ARRAY_TASK_STEP", "1"), ("SLURM_ARRAY_TASK_COUNT", "4")]);
    assert_eq!(Shard::parse("auto", &slurm).unwrap(), Shard { index: 1, count: 4 });
    let stepped = env(&[("SLURM_ARRAY_TASK_ID", "2"), ("SLURM_ARRAY_TASK_MIN", "0"), ("SLURM_ARRAY_TASK_MAX", "6"), ("SLURM_ARRAY_TASK_STEP", "2"), ("SLURM_ARRAY_TASK_COUNT", "4")]);
    assert!(Shard::parse("auto", &stepped).unwrap_err().contains("dense range"));
    let k8s = env(&[("JOB_COMPLETION_INDEX", "3"), ("UPLIFT_SHARD_COUNT", "8")]);
    assert_eq!(Shard::parse("auto", &k8s).unwrap(), Shard { index: 3, count: 8 });
    assert!(Shard::parse("auto", &env(&[("JOB_COMPLETION_INDEX", "3")])).unwrap_err().contains("UPLIFT_SHARD_COUNT"));
}

#[test]
fn every_asset_has_exactly_one_shard_and_shards_balance() {
    let ids: Vec<String> = (0..4000).map(|i| format!("material_{i:05}")).collect();
    for n in [1, 3, 4, 7] {
        let mut sizes = vec![0usize; n];
        for id in &ids {
            let owners: Vec<usize> = (0..n).filter(|&i| Shard { index: i, count: n }.owns(id)).collect();
            assert_eq!(owners.len(), 1, "{id} in {n} shards: {owners:?}");
            sizes[owners[0]] += 1;
        }
        // A uniform hash: each shard within 5 standard deviations of its expected share.
        let (mean, sd) = (ids.len() as f64 / n as f64, (ids.len() as f64 * (1.0 / n as f64) * (1.0 - 1.0 / n as f64)).sqrt());
        assert!(sizes.iter().all(|&s| (s as f64 - mean).abs() <= 5.0 * sd + 1e-9), "{n} shards: {sizes:?}");
    }
}

#[test]
fn status_reports_done_missing_duplicated_and_refuses_overlapping_splits() {
    let out = std::env::temp_dir().join(format!("uplift-shard-status-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let ids = ["a", "b", "c", "d", "e", "f"];
    let of = |i: usize| ids.iter().filter(|a| Shard { index: i, count: 2 }.owns(a)).map(|a| a.to_string()).collect::<Vec<_>>();
    let mut r0 = ShardRun::begin(&out, "fit", Some(Shard { index: 0, count: 2 }), of(0)).unwrap();
    for a in of(0) {
        r0.finished(&a, false).unwrap();
    }
    r0.end().unwrap();
    let mut r1 = ShardRun::begin(&out, "fit", Some(Shard { index: 1, count: 2 }), of(1)).unwrap();
    let first = of(1)[0].clone();
    r1.finished(&first, true).unwrap();
    // Killed here: shard 1 is started, not complete; its other assets are missing.
    let s = &status(&out).unwrap()[0];
    assert_eq!((s.shards, s.started.clone(), s.complete.clone()), (2, vec![0, 1], vec![0]));
    assert_eq!(s.finished, of(0).len() + 1);
    assert_eq!(s.missing, of(1)[1..].to_vec());
    assert!(s.duplicated.is_empty() && !s.is_done());
    // Resumed: the manifest keeps what it finished.
    let mut r1 = ShardRun::begin(&out, "fit", Some(Shard { index: 1, count: 2 }), of(1)).unwrap();
    assert_eq!(r1.manifest.finished.len(), 1);
    for a in of(1) {
        r1.finished(&a, false).unwrap();
    }
    r1.end().unwrap();
    assert!(status(&out).unwrap()[0].is_done());
    // Another split of the same stage into the same folder is refused.
    let e = ShardRun::begin(&out, "fit", Some(Shard { index: 0, count: 3 }), vec![]).err().unwrap();
    assert!(e.contains("2-way split") && e.contains("overlap"), "{e}");
    std::fs::remove_dir_all(&out).unwrap();
}

mod runs {
    use crate::common::cli::{command, repo, s, temp_dir, uplift, uplift_with};
    use std::path::{Path, PathBuf};
    use std::process::Stdio;
    use std::time::{Duration, Instant};

    const SCOPE: &str = "shard";

    /// Every file under `root` (manifests and Slurm's files left out) → its bytes, fit.json
    /// without its wall time (`seconds`).
    fn outputs(root: &Path) -> std::collections::BTreeMap<String, Vec<u8>> {
        let mut out = std::collections::BTreeMap::new();
        let mut work = vec![root.to_path_buf()];
        while let Some(d) = work.pop() {
            for e in std::fs::read_dir(&d).unwrap().flatten() {
                let p = e.path();
                let rel = p.strip_prefix(root).unwrap().to_string_lossy().to_string();
                if rel.starts_with(uplift::shard::MANIFEST_DIR) {
                    continue;
                }
                if p.is_dir() {
                    work.push(p);
                } else {
                    let mut bytes = std::fs::read(&p).unwrap();
                    if rel.ends_with("fit.json") {
                        let text = String::from_utf8(bytes).unwrap();
                        assert_eq!(text.matches("\"seconds\":").count(), 1, "{text}");
                        bytes = text.lines().filter(|l| !l.trim_start().starts_with("\"seconds\":")).collect::<Vec<_>>().join("\n").into_bytes();
                    }
                    out.insert(rel, bytes);
                }
            }
        }
        out
    }

    fn ok(args: &[&str]) -> String {
        let (code, stdout, stderr) = uplift(args);
        assert_eq!(code, 0, "{args:?}:\n{stderr}");
        stdout + &stderr
    }

    /// 12 materials: three copies of examples/pbr_materials.mtlx (the batch names them
    /// `copper`, `copper_2`, `copper_3`, …).
    fn input(root: &Path) -> PathBuf {
        let dir = root.join("in");
        std::fs::create_dir_all(&dir).unwrap();
        for x in ["a", "b", "c"] {
            std::fs::copy(repo().join("examples/pbr_materials.mtlx"), dir.join(format!("{x}.mtlx"))).unwrap();
        }
        dir
    }

    fn enhance_args<'a>(input: &'a Path, out: &'a Path) -> Vec<&'a str> {
        vec!["enhance", s(input), "--seed", "3", "--resolution", "8x8", "--mask-size", "16", "-o", s(out)]
    }

    const FIT: [&str; 6] = ["--steps", "30", "--threads", "1", "--seed", "2"];

    /// Enhance and fit 12 materials as 3 shards each — one fit shard killed after its first
    /// material and run again — and as one process: the same files, byte for byte; the
    /// manifests tell what is missing until the rerun, and nothing duplicated.
    #[test]
    fn shards_of_enhance_and_fit_equal_one_process_and_a_killed_shard_resumes() {
        let root = temp_dir(SCOPE, "runs");
        let input = input(&root);
        let (single, sharded) = (root.join("single"), root.join("sharded"));
        ok(&enhance_args(&input, &single));
        ok(&[&["fit", s(&single)][..], &FIT].concat());
        for i in 0..3 {
            let spec = format!("{i}/3");
            let log = ok(&[&enhance_args(&input, &sharded)[..], &["--shard", &spec]].concat());
            assert!(log.contains(&format!("(shard {i}/3: ")), "{log}");
        }
        // The shard with the most materials is killed once its first fit is recorded.
        let names: Vec<String> = outputs(&single).keys().filter_map(|k| k.strip_suffix("/meta.json").map(String::from)).collect();
        assert_eq!(names.len(), 12, "{names:?}");
        let sizes: Vec<usize> = (0..3).map(|i| names.iter().filter(|n| uplift::shard::Shard { index: i, count: 3 }.owns(n)).count()).collect();
        let victim = (0..3).max_by_key(|&i| sizes[i]).unwrap();
        assert!(sizes[victim] >= 2, "{sizes:?}");
        for i in (0..3).filter(|&i| i != victim) {
            ok(&[&["fit", s(&sharded)][..], &FIT, &["--shard", &format!("{i}/3")]].concat());
        }
        let spec = format!("{victim}/3");
        let args: Vec<&str> = [&["fit", s(&sharded)][..], &FIT, &["--shard", &spec]].concat();
        let manifest = sharded.join(uplift::shard::MANIFEST_DIR).join(format!("fit.{victim}-of-3.json"));
        let mut child = command(&args).stdout(Stdio::null()).stderr(Stdio::null()).spawn().unwrap();
        let start = Instant::now();
        loop {
            let m: Option<uplift::shard::Manifest> = std::fs::read_to_string(&manifest).ok().and_then(|t| serde_json::from_str(&t).ok());
            if m.is_some_and(|m| !m.finished.is_empty()) {
                break;
            }
            assert!(child.try_wait().unwrap().is_none(), "shard {victim} finished before it could be killed");
            assert!(start.elapsed() < Duration::from_secs(120), "shard {victim} recorded no fit in 120 s");
            std::thread::sleep(Duration::from_millis(5));
        }
        child.kill().unwrap();
        child.wait().unwrap();
        let (code, status, err) = uplift(&["shards", s(&sharded)]);
        assert_eq!(code, 1, "an unfinished stage is exit 1: {status}{err}");
        assert!(status.contains("fit: 2/3 shards complete (3 started)") && status.contains("missing: ") && status.contains(" 0 duplicated"), "{status}");
        assert!(status.contains("enhance: 3/3 shards complete (3 started); 12 finished, 0 missing, 0 duplicated"), "{status}");
        // Rerun only the killed shard: it skips what it finished.
        let log = ok(&args);
        assert!(log.contains("already fitted"), "{log}");
        let status = ok(&["shards", s(&sharded)]);
        assert!(status.contains("fit: 3/3 shards complete (3 started); 12 finished, 0 missing, 0 duplicated"), "{status}");
        let (a, b) = (outputs(&single), outputs(&sharded));
        assert_eq!(a.keys().collect::<Vec<_>>(), b.keys().collect::<Vec<_>>());
        for (k, v) in &a {
            assert!(b[k] == *v, "{k}: the sharded run's file differs from the single process's");
        }
        // The checks split the same way: furnace verdicts in the manifests; eval-fit's table
        // from every shard's figures equals one process's.
        let furnace = ["--max-texels", "8", "--directions", "64", "--views", "4", "--threads", "1"];
        for i in 0..2 {
            let log = ok(&[&["furnace", s(&sharded)][..], &furnace, &["--shard", &format!("{i}/2")]].concat());
            assert!(log.contains("materials pass (100.0 %)"), "{log}");
        }
        let furnace_status = ok(&["shards", s(&sharded)]);
        assert!(furnace_status.contains("furnace: 2/2 shards complete (2 started); 12 finished, 0 missing, 0 duplicated"), "{furnace_status}");
        let render = ["--size", "16", "--spp", "1", "--threads", "1"];
        ok(&[&["eval-fit", s(&single), "-o", s(&root.join("eval1"))][..], &render].concat());
        for i in 0..2 {
            ok(&[&["eval-fit", s(&sharded), "-o", s(&root.join("eval2"))][..], &render, &["--shard", &format!("{i}/2")]].concat());
        }
        let table = |d: &str| std::fs::read_to_string(root.join(d).join("table.md")).unwrap();
        assert_eq!(table("eval1"), table("eval2"), "eval-fit's table over 2 shards differs from one process's");
        assert_eq!(std::fs::read_dir(root.join("eval2/evals")).unwrap().count(), 12);
        // Bad use: a shard out of range; another split of the same stage into the same folder.
        let (code, _, err) = uplift(&[&["fit", s(&sharded)][..], &["--shard", "3/3"]].concat());
        assert!(code == 1 && err.contains("--shard 3/3: shard 3 is out of range"), "{err}");
        let (code, _, err) = uplift(&[&["fit", s(&sharded)][..], &FIT, &["--shard", "0/4"]].concat());
        assert!(code == 1 && err.contains("3-way split of `fit`") && err.contains("overlap"), "{err}");
        let (code, _, err) = uplift_with(&[&["fit", s(&sharded)][..], &["--shard", "auto"]].concat(), &[("SLURM_ARRAY_TASK_ID", "1")]);
        assert!(code == 1 && err.contains("SLURM_ARRAY_TASK_COUNT is not"), "{err}");
        std::fs::remove_dir_all(&root).unwrap();
    }

    /// Slurm's client commands, pointed at the test's cluster.
    fn slurm(dir: &Path, args: &[&str]) -> std::process::Output {
        std::process::Command::new(args[0]).args(&args[1..]).env("SLURM_CONF", dir.join("slurm.conf")).output().unwrap()
    }

    /// Waits until Slurm has no pending or running task of `job`.
    fn wait_for(cluster: &Path, job: &str) {
        let start = Instant::now();
        loop {
            let q = slurm(cluster, &["squeue", "-h", "-r", "-j", job, "-o", "%i %T"]);
            let text = String::from_utf8_lossy(&q.stdout).to_string();
            if q.status.success() && text.trim().is_empty() {
                return;
            }
            assert!(start.elapsed() < Duration::from_secs(300), "job {job} still queued after 300 s: {text}");
            std::thread::sleep(Duration::from_millis(200));
        }
    }

    /// A real single-host Slurm (munged, slurmctld, slurmd: tests/slurm/cluster.sh) runs
    /// `uplift slurm submit`'s job arrays: enhance 12 materials in 4 tasks, then fit them in 4
    /// tasks, one task cancelled mid-way (scancel) and only its index resubmitted; every
    /// material once, the files equal to a single process's.
    #[test]
    fn a_slurm_job_array_enhances_and_fits_and_a_cancelled_task_is_resubmitted() {
        let installed = ["munged", "slurmctld", "slurmd", "sbatch"].iter().all(|t| std::process::Command::new("sh").arg("-c").arg(format!("command -v {t}")).output().is_ok_and(|o| o.status.success()));
        if !installed {
            return uplift_base::test_env::skip("slurm_cluster", "Slurm is not installed (Debian: apt install munge slurmctld slurmd slurm-client; .ci/run does)");
        }
        let root = temp_dir(SCOPE, "cluster");
        let cluster = root.join("cluster");
        let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/slurm/cluster.sh");
        let st = std::process::Command::new("bash").arg(&script).arg("start").arg(&cluster).status().unwrap();
        assert!(st.success(), "cluster.sh start: {st}");
        struct Stop<'a>(&'a Path, &'a Path);
        impl Drop for Stop<'_> {
            fn drop(&mut self) {
                let _ = std::process::Command::new("bash").arg(self.0).arg("stop").arg(self.1).status();
            }
        }
        let _stop = Stop(&script, &cluster);
        let input = input(&root);
        let (single, out) = (root.join("single"), root.join("out"));
        ok(&enhance_args(&input, &single));
        ok(&[&["fit", s(&single)][..], &FIT].concat());
        let conf = cluster.join("slurm.conf");
        let env = [("SLURM_CONF", s(&conf))];
        let submit = |extra: &[&str], command: &[&str]| -> String {
            let args: Vec<&str> = [&["slurm", "submit", "--tasks", "4", "--dir", s(&out), "--cpus-per-task", "1"][..], extra, &["--"], command].concat();
            let (code, stdout, stderr) = uplift_with(&args, &env);
            assert_eq!(code, 0, "{args:?}: {stderr}");
            stdout.trim().to_string()
        };
        let job = submit(&[], &enhance_args(&input, &out));
        wait_for(&cluster, &job);
        let logs: Vec<PathBuf> = std::fs::read_dir(out.join(".uplift-shards/slurm/logs")).unwrap().flatten().map(|e| e.path()).collect();
        assert_eq!(logs.len(), 4, "one log per task: {logs:?}");
        for l in &logs {
            let text = std::fs::read_to_string(l).unwrap();
            assert!(text.contains(&format!("of job {job} on ")) && text.contains("enhanced "), "{}: {text}", l.display());
        }
        let (code, status, err) = uplift_with(&["slurm", "status", s(&out)], &env);
        assert_eq!(code, 0, "{status}{err}");
        assert!(status.contains("enhance: 4/4 shards complete (4 started); 12 finished, 0 missing, 0 duplicated"), "{status}");
        // Fit, 4 tasks; the task with the most materials is cancelled once it recorded one.
        let names: Vec<String> = outputs(&single).keys().filter_map(|k| k.strip_suffix("/meta.json").map(String::from)).collect();
        let sizes: Vec<usize> = (0..4).map(|i| names.iter().filter(|n| uplift::shard::Shard { index: i, count: 4 }.owns(n)).count()).collect();
        let victim = (0..4).max_by_key(|&i| sizes[i]).unwrap();
        assert!(sizes[victim] >= 2, "{sizes:?}");
        let slow_fit: Vec<&str> = [&["fit", s(&out)][..], &FIT].concat();
        let job = submit(&[], &slow_fit);
        let manifest = out.join(uplift::shard::MANIFEST_DIR).join(format!("fit.{victim}-of-4.json"));
        let start = Instant::now();
        loop {
            let m: Option<uplift::shard::Manifest> = std::fs::read_to_string(&manifest).ok().and_then(|t| serde_json::from_str(&t).ok());
            if m.is_some_and(|m| !m.finished.is_empty()) {
                break;
            }
            assert!(start.elapsed() < Duration::from_secs(300), "task {victim} recorded no fit in 300 s");
            std::thread::sleep(Duration::from_millis(5));
        }
        let c = slurm(&cluster, &["scancel", &format!("{job}_{victim}")]);
        assert!(c.status.success(), "scancel: {}", String::from_utf8_lossy(&c.stderr));
        wait_for(&cluster, &job);
        let (code, status, _) = uplift_with(&["slurm", "status", s(&out)], &env);
        if code == 0 {
            // The task finished between the manifest's write and the cancel: nothing to resubmit.
            eprintln!("task {victim} finished before scancel reached it");
        } else {
            assert!(status.contains("fit: 3/4 shards complete (4 started)") && status.contains("missing: "), "{status}");
            let again = submit(&["--only", &victim.to_string()], &slow_fit);
            wait_for(&cluster, &again);
        }
        let (code, status, err) = uplift_with(&["slurm", "status", s(&out)], &env);
        assert_eq!(code, 0, "{status}{err}");
        assert!(status.contains("fit: 4/4 shards complete (4 started); 12 finished, 0 missing, 0 duplicated"), "{status}");
        let (a, b) = (outputs(&single), outputs(&out));
        assert_eq!(a.keys().collect::<Vec<_>>(), b.keys().collect::<Vec<_>>());
        for (k, v) in &a {
            assert!(b[k] == *v, "{k}: the job array's file differs from the single process's");
        }
        drop(_stop);
        std::fs::remove_dir_all(&root).unwrap();
    }

    /// The job array's script, run as Slurm runs it (bash, one process per array task with
    /// SLURM_ARRAY_TASK_ID set), enhances every material once; a missing Slurm is a clear error.
    #[test]
    fn the_slurm_script_runs_each_task_as_its_shard_and_a_missing_slurm_is_an_error() {
        let root = temp_dir(SCOPE, "slurm");
        let input = input(&root);
        let out = root.join("out");
        let submit = |extra: &[&str]| -> (i32, String, String) {
            let args: Vec<&str> = [&["slurm", "submit", "--tasks", "4", "--dir", s(&out), "--cpus-per-task", "1", "--mem", "1G", "--time", "0:10:00"][..], extra, &["--"], &enhance_args(&input, &out)].concat();
            uplift_with(&args, &[("PATH", s(&root))])
        };
        let (code, script, err) = submit(&["--dry-run"]);
        assert_eq!(code, 0, "{err}");
        for line in ["#SBATCH --array=0-3", "#SBATCH --cpus-per-task=1", "#SBATCH --mem=1G", "#SBATCH --time=0:10:00", "--shard \"${SLURM_ARRAY_TASK_ID}/4\""] {
            assert!(script.contains(line), "no `{line}` in\n{script}");
        }
        for task in 0..4 {
            let st = std::process::Command::new("bash").arg("-c").arg(&script).env("SLURM_ARRAY_TASK_ID", task.to_string()).env("SLURM_ARRAY_JOB_ID", "7").stdout(Stdio::null()).stderr(Stdio::null()).status().unwrap();
            assert!(st.success(), "task {task}: {st}");
        }
        let status = ok(&["shards", s(&out)]);
        assert!(status.contains("enhance: 4/4 shards complete (4 started); 12 finished, 0 missing, 0 duplicated"), "{status}");
        // No sbatch on PATH (PATH is an empty folder here).
        let (code, _, err) = submit(&[]);
        assert!(code == 1 && err.contains("`sbatch` is not on PATH") && err.contains("slurm"), "{err}");
        let (code, _, err) = uplift(&["slurm", "submit", "--tasks", "2", "--dir", s(&out), "--", "render", s(&out)]);
        assert!(code == 1 && err.contains("`render` takes no --shard"), "{err}");
        let (code, _, err) = uplift(&["slurm", "status", s(&root)]);
        assert!(code == 1 && err.contains("no jobs submitted here"), "{err}");
        std::fs::remove_dir_all(&root).unwrap();
    }
}
