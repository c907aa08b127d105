//! `uplift demo -o OUT/`: the main job (runtime/uplift/src/demo): a procedural PBR set enhanced across
//! all six Types, fitted with the shipped decoder, rendered reference vs neural, FLIP and white
//! furnace, and `OUT/report/index.html`.

use uplift_neural::weights::SHIPPED_DECODER;
use uplift::demo::{run_demo, DemoOptions};
use uplift_render::evaluation::format_table;
use clap::Args;
use std::path::PathBuf;

#[derive(Args)]
pub struct DemoArgs {
    #[arg(short, long, default_value = "out/demo")]
    pub output: PathBuf,
    /// Write into an existing folder that holds files this command did not write (they are
    /// kept; it refuses such a folder otherwise: docs/cli.md, output folders).
    #[arg(long)]
    pub force: bool,
    #[arg(long, default_value = SHIPPED_DECODER)]
    pub decoder: PathBuf,
    /// Materials per enhancement Type.
    #[arg(long, default_value_t = 4)]
    pub per_type: usize,
    /// Texture (and bake) size of the procedural materials.
    #[arg(long, default_value_t = 128)]
    pub texture_size: usize,
    /// Preview-ball image size.
    #[arg(long, default_value_t = 160, value_parser = super::bounds::IMAGE_SIDE.parser::<usize>())]
    pub render_size: usize,
    #[arg(long, default_value_t = 32, value_parser = super::bounds::SPP.parser::<usize>())]
    pub spp: usize,
    /// Adam steps of the latent fitting.
    #[arg(long, default_value_t = 100)]
    pub fit_steps: u64,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    #[arg(long)]
    pub threads: Option<usize>,
    /// The sampling decoder's study: samples per pixel of the compared renders.
    #[arg(long, default_value_t = 16)]
    pub sampler_spp: usize,
    /// The sampling decoder's study: samples per pixel of the converged render.
    #[arg(long, default_value_t = 1024)]
    pub sampler_converged_spp: usize,
}

pub fn run(args: DemoArgs) -> Result<(), String> {
    super::claim_output(&args.output, "demo", args.force)?;
    let threads = args.threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get())).max(1);
    let o = DemoOptions {
        out: args.output,
        decoder: args.decoder,
        per_type: args.per_type,
        texture_size: args.texture_size,
        render_size: args.render_size,
        spp: args.spp,
        fit_steps: args.fit_steps,
        seed: args.seed,
        threads,
        sampler_study: uplift_render::sampler_error::SamplerErrorOptions { spp: args.sampler_spp, converged_spp: args.sampler_converged_spp, ..Default::default() },
    };
    let s = run_demo(&o)?;
    println!("{}", format_table(&s.table));
    println!("iridescent clearcoat (the coated Types' materials with --iridescence):\n{}", format_table(&s.iridescent_table));
    if !s.sampler_table.is_empty() {
        println!("sampling decoder: squared error of cosine sampling / of the sampling decoder at equal spp, per Type (lowest / median / highest):");
        for r in &s.sampler_table {
            println!("  Type {}: {} materials, {:.2}× / {:.2}× / {:.2}×", r.kind, r.count, r.ratio.0, r.ratio.1, r.ratio.2);
        }
    }
    println!(
        "white furnace: reference {} of {} materials pass, neural {} of {}",
        s.furnace_reference_passed, s.materials, s.furnace_neural_passed, s.materials
    );
    println!("wrote {}", s.report.display());
    Ok(())
}
