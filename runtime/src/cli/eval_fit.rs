//! `uplift eval-fit MATERIAL/… [-o DIR]`: renders each fitted material (params.exr, latent.exr)
//! on the preview ball by the reference kernels and by the neural decoder, measures LDR-FLIP
//! over the ball and the whole image, and prints the per-Type best / median / worst table in
//! the paper's Table 1 format. With `-o`, writes each material's reference, neural and FLIP
//! images and `table.md` there.

use super::fit::{load_model, SHIPPED_DECODER};
use super::furnace::material_folders;
use super::render::environment;
use crate::atomic_write::write_atomically;
use crate::cpu_engine::CpuEngine;
use crate::render::evaluation::{evaluate_material, format_table, per_type, write_eval_images};
use crate::render::integrator::RenderOptions;
use crate::render::shading::{Model, Shading};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use std::path::PathBuf;

#[derive(Args)]
pub struct EvalFitArgs {
    /// Fitted material folders, or folders of them.
    #[arg(required = true)]
    pub materials: Vec<PathBuf>,
    /// Write images and table.md here.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    #[arg(long, default_value = SHIPPED_DECODER)]
    pub decoder: PathBuf,
    /// Environment: an equirectangular .hdr/.exr file, `studio` or `white`.
    #[arg(long, default_value = "studio")]
    pub env: String,
    #[arg(long, default_value_t = 256)]
    pub size: usize,
    #[arg(long, default_value_t = 64)]
    pub spp: usize,
    #[arg(long, default_value_t = 1.0)]
    pub exposure: f32,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    #[arg(long)]
    pub threads: Option<usize>,
}

pub fn run(args: EvalFitArgs) -> Result<(), String> {
    let threads = args.threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get())).max(1);
    if args.size == 0 || args.spp == 0 || !(args.exposure > 0.0 && args.exposure.is_finite()) {
        return Err("--size and --spp must be at least 1 and --exposure positive".into());
    }
    let folders = material_folders(&args.materials)?;
    let env = environment(&args.env)?;
    let reference = Shading::new(CpuEngine::with_threads(threads)?, Model::Reference)?;
    let neural = Shading::new(CpuEngine::with_threads(threads)?, Model::Neural(load_model(&args.decoder)?.decoder))?;
    let o = RenderOptions { width: args.size, height: args.size, spp: args.spp, seed: args.seed, ..Default::default() };
    if let Some(out) = &args.output {
        std::fs::create_dir_all(out).map_err(|e| format!("{}: {e}", out.display()))?;
    }
    let bar = ProgressBar::new(folders.len() as u64).with_style(ProgressStyle::with_template("eval-fit [{bar:30}] {pos}/{len} {msg}").map_err(|e| e.to_string())?.progress_chars("=> "));
    let mut evals = Vec::new();
    for dir in &folders {
        bar.set_message(dir.display().to_string());
        let (e, images) = evaluate_material(dir, &reference, &neural, &env, &o, args.exposure)?;
        if let Some(out) = &args.output {
            write_eval_images(out, &e.name, &images, (o.width, o.height))?;
        }
        let line = format!("{} (Type {}): FLIP {:.4} over the ball, {:.4} over the image; PSNR {:.1} dB", e.name, e.kind, e.flip_object, e.flip_full, e.psnr_object);
        bar.suspend(|| println!("{line}"));
        evals.push(e);
        bar.inc(1);
    }
    bar.finish_and_clear();
    let table = format_table(&per_type(&evals));
    println!("\n{table}");
    if let Some(out) = &args.output {
        let path = out.join("table.md");
        write_atomically(&path, table.as_bytes()).map_err(|e| format!("{}: {e}", path.display()))?;
    }
    Ok(())
}
