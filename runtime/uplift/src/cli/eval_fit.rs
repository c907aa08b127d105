//! `uplift eval-fit MATERIAL/… [-o DIR]`: renders each fitted material (params.exr, latent.exr)
//! on the preview ball by the reference kernels and by the neural decoder, measures LDR-FLIP
//! over the ball and the whole image, and prints the per-Type best / median / worst table in
//! the paper's Table 1 format. With `-o`, writes each material's reference, neural and FLIP
//! images and `table.md` there.

use uplift_neural::weights::load_model;
use uplift_material::folder::find_material_folders as material_folders;
use super::render::{environment, RenderSettings};
use uplift_base::atomic_write::write_atomically;
use uplift_engines::cpu_engine::CpuEngine;
use uplift_render::evaluation::{evaluate_material, format_table, per_type, write_eval_images};
use uplift_render::integrator::RenderOptions;
use uplift_render::shading::{Model, Shading};
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
    #[command(flatten)]
    pub settings: RenderSettings,
}

pub fn run(args: EvalFitArgs) -> Result<(), String> {
    let threads = args.settings.check()?;
    let st = &args.settings;
    let folders = material_folders(&args.materials)?;
    let env = environment(&st.env)?;
    let stack = st.stack.load()?;
    let reference = Shading::new(CpuEngine::with_threads(threads)?, &stack, Model::Reference)?;
    let neural = Shading::new(CpuEngine::with_threads(threads)?, &stack, Model::Neural(load_model(&st.decoder, &stack)?.decoder))?;
    let o = RenderOptions { width: st.size, height: st.size, spp: st.spp, seed: st.seed, ..Default::default() };
    if let Some(out) = &args.output {
        std::fs::create_dir_all(out).map_err(|e| format!("{}: {e}", out.display()))?;
    }
    let bar = ProgressBar::new(folders.len() as u64).with_style(ProgressStyle::with_template("eval-fit [{bar:30}] {pos}/{len} {msg}").map_err(|e| e.to_string())?.progress_chars("=> "));
    let mut evals = Vec::new();
    for dir in &folders {
        bar.set_message(dir.display().to_string());
        let (e, images) = evaluate_material(dir, &reference, &neural, &env, &o, st.exposure)?;
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
