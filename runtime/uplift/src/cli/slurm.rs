//! `uplift slurm submit --tasks N --dir OUT [resources] -- STAGE ARGS…` writes and submits a
//! Slurm job array running one batch stage sharded N ways (uplift::slurm; `--dry-run` prints
//! the script instead); `uplift slurm status OUT` shows the jobs' task states and the shards'
//! manifests (docs/scale.md).

use clap::{Args, Subcommand};
use std::path::PathBuf;
use uplift::slurm::{read_jobs, task_states, Submit};

#[derive(Args)]
pub struct SlurmArgs {
    #[command(subcommand)]
    pub command: SlurmCommand,
}

#[derive(Subcommand)]
pub enum SlurmCommand {
    /// Write and submit a job array running a batch stage (enhance, fit, export, datagen,
    /// furnace, eval-fit) sharded N ways.
    Submit(SubmitArgs),
    /// The submitted jobs' tasks and the shards' manifests under OUT.
    Status(StatusArgs),
}

#[derive(Args)]
pub struct SubmitArgs {
    /// Array tasks: the stage runs as shards 0/N to N−1/N.
    #[arg(long)]
    pub tasks: usize,
    /// The stage's output folder: the script, the tasks' logs and jobs.json go under
    /// OUT/.uplift-shards/slurm/.
    #[arg(long, value_name = "OUT")]
    pub dir: PathBuf,
    #[arg(long, default_value_t = 2)]
    pub cpus_per_task: usize,
    #[arg(long)]
    pub partition: Option<String>,
    /// Memory per task, in sbatch's syntax (`8G`).
    #[arg(long)]
    pub mem: Option<String>,
    /// Time limit per task, in sbatch's syntax (`2:00:00`).
    #[arg(long)]
    pub time: Option<String>,
    /// Submit only these tasks of the array (`2`, `0,3`): resubmitting what did not finish.
    #[arg(long)]
    pub only: Option<String>,
    /// Start after this job succeeded (a pipeline: enhance, then fit, then export).
    #[arg(long, value_name = "JOB")]
    pub after: Option<String>,
    /// Print the script; submit nothing.
    #[arg(long)]
    pub dry_run: bool,
    /// The stage's command line: `fit OUT --steps 200` (without --shard).
    #[arg(last = true, required = true)]
    pub command: Vec<String>,
}

#[derive(Args)]
pub struct StatusArgs {
    #[arg(value_name = "OUT")]
    pub dir: PathBuf,
}

pub fn run(args: SlurmArgs) -> Result<(), String> {
    match args.command {
        SlurmCommand::Submit(a) => submit(a),
        SlurmCommand::Status(a) => status(a),
    }
}

fn submit(a: SubmitArgs) -> Result<(), String> {
    if a.cpus_per_task == 0 {
        return Err("--cpus-per-task must be at least 1".into());
    }
    let uplift = std::env::current_exe().map_err(|e| format!("the uplift binary's path: {e}"))?;
    let s = Submit { command: a.command, tasks: a.tasks, dir: a.dir, uplift, cpus_per_task: a.cpus_per_task, partition: a.partition, mem: a.mem, time: a.time, only: a.only, after: a.after };
    if a.dry_run {
        print!("{}", s.script()?);
        return Ok(());
    }
    let job = s.submit()?;
    println!("{}", job.job);
    eprintln!("submitted job {} ({} tasks {}, {}); logs under {}", job.job, job.stage, job.array, job.script, uplift::slurm::slurm_dir(&s.dir).join("logs").display());
    Ok(())
}

fn status(a: StatusArgs) -> Result<(), String> {
    let jobs = read_jobs(&a.dir)?;
    if jobs.is_empty() {
        return Err(format!("{}: no jobs submitted here (uplift slurm submit --dir {} …)", a.dir.display(), a.dir.display()));
    }
    let states = task_states(&jobs)?;
    for j in &jobs {
        let mine: Vec<&(String, String)> = states.iter().filter(|(id, _)| id.split('_').next() == Some(j.job.as_str())).collect();
        let mut counts: std::collections::BTreeMap<&str, usize> = std::collections::BTreeMap::new();
        for (_, st) in &mine {
            *counts.entry(st.as_str()).or_default() += 1;
        }
        let summary: Vec<String> = counts.iter().map(|(s, n)| format!("{n} {s}")).collect();
        println!("job {} ({}, tasks {} of {}): {}", j.job, j.stage, j.array, j.tasks, if summary.is_empty() { "no tasks known to Slurm".into() } else { summary.join(", ") });
    }
    super::shards::run(super::shards::ShardsArgs { outputs: vec![a.dir] })
}
