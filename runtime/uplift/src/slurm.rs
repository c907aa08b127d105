//! Slurm job arrays for the batch commands (docs/scale.md): `uplift slurm submit` writes an
//! `sbatch` script that runs one uplift stage (`enhance`, `fit`, `export`, …) as an N-task job
//! array, task i running `--shard i/N` (uplift::shard), and submits it; `uplift slurm status`
//! asks Slurm about the submitted jobs and reads the shards' manifests. Slurm is the engine:
//! uplift writes its script, calls `sbatch`, `sacct` and `squeue`, and reads their output.

use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::process::Command;
use uplift_base::atomic_write::write_atomically;

use crate::shard::MANIFEST_DIR;

/// The stages a job array can run: the batch commands that take `--shard`.
pub const STAGES: [&str; 6] = ["enhance", "fit", "export", "datagen", "furnace", "eval-fit"];

/// One job array to submit.
#[derive(Clone, Debug)]
pub struct Submit {
    /// The uplift command line of the stage (`fit OUT --steps 200`), without `--shard`.
    pub command: Vec<String>,
    /// Array tasks (shards).
    pub tasks: usize,
    /// The folder of the script, the logs and the job record (the stage's output folder).
    pub dir: PathBuf,
    /// The uplift binary the tasks run (this one, by its absolute path).
    pub uplift: PathBuf,
    pub cpus_per_task: usize,
    pub partition: Option<String>,
    pub mem: Option<String>,
    pub time: Option<String>,
    /// Tasks to (re)submit, in sbatch's `--array` syntax (`2`, `0,3`): the rest of an array
    /// that finished. Default: every task.
    pub only: Option<String>,
    /// Start after this job finished successfully (`--dependency=afterok:JOB`): a pipeline.
    pub after: Option<String>,
}

/// A submitted job, as `jobs.json` records it.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct JobRecord {
    pub job: String,
    pub stage: String,
    pub tasks: usize,
    pub array: String,
    pub script: String,
}

/// The folder of Slurm's files under `dir`.
pub fn slurm_dir(dir: &Path) -> PathBuf {
    dir.join(MANIFEST_DIR).join("slurm")
}

/// Single-quoted for bash.
fn quote(s: &str) -> String {
    format!("'{}'", s.replace('\'', "'\\''"))
}

impl Submit {
    fn stage(&self) -> Result<&str, String> {
        let stage = self.command.first().map(String::as_str).ok_or("slurm submit: give the stage's command after `--` (e.g. -- fit OUT --steps 200)")?;
        if !STAGES.contains(&stage) {
            return Err(format!("slurm submit: `{stage}` takes no --shard; a job array runs one of: {}", STAGES.join(", ")));
        }
        if self.command.iter().any(|a| a == "--shard" || a.starts_with("--shard=")) {
            return Err("slurm submit: the command must not give --shard: each array task gets its own".into());
        }
        if self.tasks == 0 {
            return Err("slurm submit: --tasks must be at least 1".into());
        }
        Ok(stage)
    }

    /// The sbatch script: array 0..tasks−1, each task running the stage with `--shard
    /// $SLURM_ARRAY_TASK_ID/tasks` (the count written in, so a resubmitted subset of the array
    /// keeps the original split), one log per task.
    pub fn script(&self) -> Result<String, String> {
        let stage = self.stage()?;
        let logs = slurm_dir(&self.dir).join("logs");
        let mut s = String::from("#!/bin/bash\n# Written by `uplift slurm submit` (runtime/uplift/src/slurm.rs).\n");
        s += &format!("#SBATCH --job-name=uplift-{stage}\n");
        s += &format!("#SBATCH --array=0-{}\n", self.tasks - 1);
        s += &format!("#SBATCH --cpus-per-task={}\n", self.cpus_per_task);
        s += "#SBATCH --ntasks=1\n";
        s += &format!("#SBATCH --output={}/{stage}_%A_%a.log\n", logs.display());
        for (flag, v) in [("partition", &self.partition), ("mem", &self.mem), ("time", &self.time)] {
            if let Some(v) = v {
                s += &format!("#SBATCH --{flag}={v}\n");
            }
        }
        s += "set -euo pipefail\n";
        s += "echo \"uplift: task ${SLURM_ARRAY_TASK_ID} of job ${SLURM_ARRAY_JOB_ID} on $(hostname)\"\n";
        let args: Vec<String> = self.command.iter().map(|a| quote(a)).collect();
        s += &format!("exec {} {} --shard \"${{SLURM_ARRAY_TASK_ID}}/{}\"\n", quote(&self.uplift.to_string_lossy()), args.join(" "), self.tasks);
        Ok(s)
    }

    /// Writes the script and submits it with `sbatch --parsable`; records the job in
    /// `jobs.json`. Returns the job id.
    pub fn submit(&self) -> Result<JobRecord, String> {
        let stage = self.stage()?.to_string();
        let script = self.script()?;
        let dir = slurm_dir(&self.dir);
        std::fs::create_dir_all(dir.join("logs")).map_err(|e| format!("{}: {e}", dir.display()))?;
        let path = dir.join(format!("{stage}.sbatch"));
        write_atomically(&path, script.as_bytes()).map_err(|e| format!("{}: {e}", path.display()))?;
        let mut cmd = Command::new("sbatch");
        cmd.arg("--parsable");
        if let Some(only) = &self.only {
            cmd.arg(format!("--array={only}"));
        }
        if let Some(after) = &self.after {
            cmd.arg(format!("--dependency=afterok:{after}"));
        }
        cmd.arg(&path);
        let out = run_slurm(&mut cmd, "sbatch")?;
        // `--parsable` prints `jobid` or `jobid;cluster`.
        let job = out.trim().split(';').next().unwrap_or("").to_string();
        if job.is_empty() || !job.chars().all(|c| c.is_ascii_digit()) {
            return Err(format!("sbatch printed no job id: {out:?}"));
        }
        let record = JobRecord { job, stage, tasks: self.tasks, array: self.only.clone().unwrap_or_else(|| format!("0-{}", self.tasks - 1)), script: path.to_string_lossy().into() };
        let mut jobs = read_jobs(&self.dir)?;
        jobs.push(record.clone());
        let jobs_path = dir.join("jobs.json");
        let text = serde_json::to_string_pretty(&jobs).map_err(|e| e.to_string())? + "\n";
        write_atomically(&jobs_path, text.as_bytes()).map_err(|e| format!("{}: {e}", jobs_path.display()))?;
        Ok(record)
    }
}

/// Runs a Slurm client command; a missing one is an error saying Slurm is not installed.
fn run_slurm(cmd: &mut Command, name: &str) -> Result<String, String> {
    let out = cmd.output().map_err(|e| {
        if e.kind() == std::io::ErrorKind::NotFound {
            format!("`{name}` is not on PATH: uplift slurm needs a Slurm installation's client commands (Debian: apt install slurm-client; a cluster's login node has them)")
        } else {
            format!("{name}: {e}")
        }
    })?;
    if !out.status.success() {
        return Err(format!("{name} failed ({}): {}", out.status, String::from_utf8_lossy(&out.stderr).trim()));
    }
    Ok(String::from_utf8_lossy(&out.stdout).into())
}

/// The jobs submitted for `dir` (none yet: empty).
pub fn read_jobs(dir: &Path) -> Result<Vec<JobRecord>, String> {
    let path = slurm_dir(dir).join("jobs.json");
    match std::fs::read_to_string(&path) {
        Ok(text) => serde_json::from_str(&text).map_err(|e| format!("{}:{}:{}: {e}", path.display(), e.line(), e.column())),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(Vec::new()),
        Err(e) => Err(format!("{}: {e}", path.display())),
    }
}

/// The state of each array task of the recorded jobs (`job_task` → state), from `sacct`, or
/// from `squeue` where accounting is off (then finished tasks are absent).
pub fn task_states(jobs: &[JobRecord]) -> Result<Vec<(String, String)>, String> {
    if jobs.is_empty() {
        return Ok(Vec::new());
    }
    let ids: Vec<&str> = jobs.iter().map(|j| j.job.as_str()).collect();
    let sacct = run_slurm(Command::new("sacct").args(["-n", "-P", "-X", "--format=JobID,State", "-j", &ids.join(",")]), "sacct");
    let text = match sacct {
        Ok(t) => t,
        Err(e) if e.contains("not on PATH") => return Err(e),
        Err(_) => run_slurm(Command::new("squeue").args(["-h", "-r", "-o", "%i|%T", "-j", &ids.join(",")]), "squeue")?,
    };
    Ok(text
        .lines()
        .filter_map(|l| {
            let (id, state) = l.split_once('|')?;
            Some((id.trim().to_string(), state.split_whitespace().next().unwrap_or("").to_string()))
        })
        .collect())
}
