//! `uplift train --steps N --seed S -o decoder.safetensors`: universal training of the encoder
//! and decoder on generated data (all five classes), with a progress bar showing the loss;
//! resumes from `decoder.checkpoint.safetensors` when a run was interrupted (saying at which
//! step). Prints and stores (in the file's metadata) the held-out relative L1 error of f·cos per
//! class. The checkpoint of the last step is kept until the weights with that table are written,
//! so a run killed during the held-out evaluation does not train again.

use uplift_engines::cpu_engine::CpuEngine;
use uplift_neural::datagen::{ClassMix, DataGenerator, ViewDistribution};
use uplift_neural::evaluate::holdout_errors;
use uplift_neural::trainer::{finish, train_checkpointed, weights_file, TrainOptions};
use clap::Args;
use std::path::PathBuf;

#[derive(Args)]
pub struct TrainArgs {
    /// Training steps.
    #[arg(long, default_value_t = 1000, value_parser = super::bounds::STEPS.parser::<u64>())]
    pub steps: u64,
    /// Rows per step.
    #[arg(long, default_value_t = 16384, value_parser = super::bounds::BATCH.parser::<usize>())]
    pub batch: usize,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Learning rate at the first step (cosine decay to --lr-end).
    #[arg(long, default_value_t = 1e-3)]
    pub lr: f64,
    #[arg(long, default_value_t = 1e-5)]
    pub lr_end: f64,
    /// Half-width of the uniform latent jitter (paper: 0.005).
    #[arg(long, default_value_t = 0.005)]
    pub jitter: f32,
    /// Training data: `all` (the five classes, 20 % each), one class, or `name=factor,…` (the
    /// named classes' shares multiplied: `dust=2,inner=2`).
    #[arg(long, default_value = "all")]
    pub class: String,
    /// Threads (default: every core).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Steps between checkpoints.
    #[arg(long, default_value_t = 200)]
    pub checkpoint_every: u64,
    /// Stop after this many steps with a checkpoint; run again (same options) to resume.
    #[arg(long)]
    pub stop_after: Option<u64>,
    /// Held-out rows per class for the final report.
    #[arg(long, default_value_t = 16384)]
    pub holdout: usize,
    /// The weights file to write.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Start from this weights file (a fine-tune) instead of a fresh initialisation.
    #[arg(long)]
    pub init: Option<PathBuf>,
    /// Training views: `cosine` (cosine-weighted) or `mixed` (half with μv uniform).
    #[arg(long, default_value = "cosine")]
    pub views: String,
    /// Light directions per (parameter set, view) in the generated rows (`uplift datagen
    /// --directions-per-view`); a divisor of --batch.
    #[arg(long, default_value_t = 1, value_parser = super::bounds::DIRECTIONS_PER_VIEW.parser::<usize>())]
    pub directions_per_view: usize,
    /// Latent values per texel (default: the --init file's, or the paper's 6 — two RGB
    /// textures); wider than the --init file's widens it (the new inputs start unused).
    #[arg(long)]
    pub latent: Option<usize>,
    /// The engine: the CPU, or wgpu — training data by the stack's WGSL kernels, and both
    /// networks' forward and backward passes, Eq. 3 and Adam as emitted WGSL, the weights kept
    /// on the device between checkpoints (docs/scale.md).
    #[arg(long, value_enum, default_value_t = super::eval::Engine::Cpu)]
    pub engine: super::eval::Engine,
    #[command(flatten)]
    pub stack: super::StackArgs,
}

pub fn run(args: TrainArgs) -> Result<(), String> {
    let mix = ClassMix::parse(&args.class).map_err(|e| format!("--class: {e}"))?;
    if !(args.lr > 0.0 && args.lr_end > 0.0 && args.lr.is_finite()) {
        return Err(format!("--lr {} / --lr-end {}: learning rates are positive", args.lr, args.lr_end));
    }
    if !(0.0..=0.5).contains(&args.jitter) {
        return Err(format!("--jitter {}: the latent jitter is in [0, 0.5]", args.jitter));
    }
    let threads = args.threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get())).max(1);
    let views = ViewDistribution::parse(&args.views).map_err(|e| format!("--views: {e}"))?;
    let opts = TrainOptions { steps: args.steps, batch: args.batch, seed: args.seed, lr_start: args.lr, lr_end: args.lr_end, jitter: args.jitter, threads, mix: mix.clone(), checkpoint_every: args.checkpoint_every, stop_after: args.stop_after, init: args.init.clone(), views, latent: args.latent, ..Default::default() };
    if let Some(parent) = args.output.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent).map_err(|e| format!("{}: {e}", parent.display()))?;
    }
    let stack = args.stack.load()?;
    let engine: uplift_engines::prepared_kernel::AnyEngine = match args.engine {
        super::eval::Engine::Cpu => CpuEngine::with_threads(threads)?.into(),
        super::eval::Engine::Wgpu => uplift_engines::wgpu_engine::WgpuEngine::new()?.into(),
    };
    let mut generator = DataGenerator::new(engine, &stack, mix.clone(), args.seed)?;
    let named: Vec<&str> = match &mix {
        ClassMix::All => vec![],
        ClassMix::Only(name) => vec![name.as_str()],
        ClassMix::Weighted(w) => w.iter().map(|(n, _)| n.as_str()).collect(),
    };
    for name in named {
        generator.classes().index_of(name).map_err(|e| format!("--class: {e}"))?;
    }
    generator.views = views;
    if args.directions_per_view == 0 || args.batch % args.directions_per_view != 0 {
        return Err(format!("--directions-per-view {}: a divisor of --batch {}", args.directions_per_view, args.batch));
    }
    generator.directions_per_view = args.directions_per_view;
    eprintln!("training data from {}", generator.describe());
    let mut command = format!("uplift train --steps {} --batch {} --seed {} --lr {} --lr-end {} --jitter {} --class {}", args.steps, args.batch, args.seed, args.lr, args.lr_end, args.jitter, args.class);
    if views != ViewDistribution::Cosine {
        command += &format!(" --views {}", views.name());
    }
    if args.directions_per_view != 1 {
        command += &format!(" --directions-per-view {}", args.directions_per_view);
    }
    if let Some(latent) = args.latent {
        command += &format!(" --latent {latent}");
    }
    for dir in &args.stack.stack {
        command += &format!(" --stack {}", dir.display());
    }
    let mut extra = vec![];
    if let Some(init) = &args.init {
        command += &format!(" --init {}", init.display());
        // Keep the starting point's record beside the fine-tune's.
        let f = uplift_neural::weights::TensorFile::read(init)?;
        for key in ["command", "history", "seconds", "holdout"] {
            if let Some(v) = f.metadata.get(key) {
                extra.push((key, v.clone()));
            }
        }
    }
    let extra: Vec<(String, String)> = std::iter::once(("command".to_string(), command.clone())).chain(extra.into_iter().map(|(k, v)| (format!("init.{k}"), v))).collect();
    let extra_refs: Vec<(&str, String)> = extra.iter().map(|(k, v)| (k.as_str(), v.clone())).collect();
    let state = train_checkpointed(&generator, &opts, &args.output, true)?;
    if state.step < opts.steps {
        eprintln!("stopped at step {} of {}; the checkpoint is {} — run the same command again to resume", state.step, opts.steps, uplift_neural::trainer::checkpoint_path(&args.output).display());
        return Ok(());
    }
    let errors = holdout_errors(&state.model, &mut generator, args.seed, args.holdout)?;
    let last = state.history.last().copied().unwrap_or_default();
    eprintln!("{} steps × {} rows in {:.0} s ({:.0} rows/s including data generation); last loss {:.4} (f {:.4}, T {:.4}, R {:.4})", state.step, args.batch, state.seconds, (state.step as f64 * args.batch as f64) / state.seconds.max(1e-9), last.loss.total, last.loss.f, last.loss.t, last.loss.r);
    eprintln!("held-out ({} rows per class): class, relative L1 of f·cos, mean |ΔT|, mean |ΔR|", args.holdout);
    let mut table = String::from("class,fcos_relative_l1,t_l1,r_l1\n");
    for e in &errors {
        eprintln!("  {:<10} {:.4}  {:.4}  {:.4}", e.class, e.fcos_relative_l1, e.t_l1, e.r_l1);
        table += &format!("{},{:.5},{:.5},{:.5}\n", e.class, e.fcos_relative_l1, e.t_l1, e.r_l1);
    }
    // Store the held-out table beside the training record; then the checkpoint is done with.
    let mut file = weights_file(&state, &stack, &opts, &extra_refs);
    file.metadata.insert("holdout".into(), table);
    uplift_neural::weights::record_latent_space(&mut file, &state.model);
    file.write(&args.output)?;
    finish(&args.output);
    eprintln!("wrote {}", args.output.display());
    Ok(())
}
