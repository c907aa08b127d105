//! `uplift train-sampler [--decoder FILE] -o OUT.safetensors`: trains the sampling decoder
//! (`uplift_neural::sampler`) for a trained encoder and decoder, by maximum likelihood on
//! directions from the reference stack's own sampler across the training classes, and writes
//! the weights file again with it (`sampler.*` tensors, its command, loss history and time). The
//! renderer samples neural materials with it when the decoder file has one.

use clap::Args;
use std::path::PathBuf;
use uplift_engines::cpu_engine::CpuEngine;
use uplift_neural::datagen::{ClassMix, DataGenerator};
use uplift_neural::sampler::{train_sampler, SamplerOptions};
use uplift_neural::weights::{load_model, source_name, TensorFile, SHIPPED_DECODER};

#[derive(Args)]
pub struct TrainSamplerArgs {
    /// The weights file whose encoder and decoder the sampler serves.
    #[arg(long, default_value = SHIPPED_DECODER)]
    pub decoder: PathBuf,
    /// Adam steps.
    #[arg(long, default_value_t = 1500, value_parser = super::bounds::STEPS.parser::<u64>())]
    pub steps: u64,
    /// Views (parameter rows of the training classes) per step.
    #[arg(long, default_value_t = 512, value_parser = super::bounds::VIEWS.parser::<usize>())]
    pub views: usize,
    /// Reference directions per view (half from the stack's sampler, half cosine).
    #[arg(long, default_value_t = 32)]
    pub directions: usize,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    #[arg(long)]
    pub threads: Option<usize>,
    /// The weights file to write: the decoder file's contents with the sampler added.
    #[arg(short, long)]
    pub output: PathBuf,
    #[command(flatten)]
    pub stack: super::StackArgs,
}

pub fn run(args: TrainSamplerArgs) -> Result<(), String> {
    if args.steps == 0 || args.views == 0 || args.directions < 2 {
        return Err("--steps and --views must be at least 1, --directions at least 2".into());
    }
    let stack = args.stack.load()?;
    let model = load_model(&args.decoder, &stack)?;
    let threads = args.threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get())).max(1);
    let generator = DataGenerator::new(CpuEngine::with_threads(threads)?, &stack, ClassMix::All, args.seed)?;
    let o = SamplerOptions { steps: args.steps, views: args.views, directions: args.directions, seed: args.seed, ..Default::default() };
    let trained = train_sampler(&model, &generator, &o, true)?;
    let mut file = TensorFile::read(&args.decoder)?;
    file.put_mlp("sampler", &trained.net);
    let mut command = format!("uplift train-sampler --decoder {} --steps {} --views {} --directions {} --seed {}", source_name(&args.decoder), args.steps, args.views, args.directions, args.seed);
    for dir in &args.stack.stack {
        command += &format!(" --stack {}", dir.display());
    }
    let history: String = std::iter::once("step,loss\n".to_string()).chain(trained.history.iter().map(|(s, l)| format!("{s},{l:.6}\n"))).collect();
    file.metadata.insert("sampler.command".into(), command);
    file.metadata.insert("sampler.history".into(), history);
    file.metadata.insert("sampler.seconds".into(), format!("{:.1}", trained.seconds));
    file.write(&args.output)?;
    let first = trained.history.first().map_or(f32::NAN, |h| h.1);
    let last = trained.history.last().map_or(f32::NAN, |h| h.1);
    eprintln!("{} steps in {:.0} s; loss (−Σ ŵ ln q per view) {first:.4} over the first 50 steps → {last:.4} over the last", args.steps, trained.seconds);
    eprintln!("wrote {}", args.output.display());
    Ok(())
}
