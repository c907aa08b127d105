//! `uplift eval-fit MATERIAL/… [-o DIR]`: renders each fitted material (params.exr, latent.exr)
//! on the preview ball by the reference kernels and by the neural decoder, measures LDR-FLIP
//! over the ball and the whole image, and prints the per-Type best / median / worst table in
//! the paper's Table 1 format. With `-o`, writes each material's reference, neural and FLIP
//! images and `table.md` there, and each material's figures as `evals/<name>.json`; with
//! `--shard i/N` (docs/scale.md) a shard evaluates its own materials, skips those whose
//! figures are already there, and writes `table.md` from every material's figures in the
//! folder — complete once the last shard ends.

use uplift_neural::weights::load_model;
use uplift::shard::{asset_id, MaterialBatch, Shard, ShardRun};
use super::render::{environment, RenderSettings};
use uplift_base::atomic_write::write_atomically;
use uplift_engines::cpu_engine::CpuEngine;
use uplift_render::evaluation::{evaluate_material, format_table, per_type, write_eval_images, MaterialEval};
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
    /// Evaluate only this shard of a folder of materials (`i/N`, or `auto` in a job array);
    /// needs `-o`.
    #[arg(long, requires = "output")]
    pub shard: Option<String>,
    #[command(flatten)]
    pub settings: RenderSettings,
}

pub fn run(args: EvalFitArgs) -> Result<(), String> {
    let threads = args.settings.check()?;
    let st = &args.settings;
    let shard = Shard::from_arg(args.shard.as_deref())?;
    let batch = MaterialBatch::find(&args.materials, shard)?;
    let folders = &batch.mine;
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
    let mut run = ShardRun::begin(args.output.as_deref().unwrap_or(std::path::Path::new(".")), "eval-fit", shard, folders.iter().map(|f| asset_id(f)).collect())?;
    let record = |name: &str| args.output.as_ref().map(|o| o.join("evals").join(format!("{name}.json")));
    for dir in folders {
        bar.set_message(dir.display().to_string());
        if let Some(path) = record(&asset_id(dir)).filter(|p| shard.is_some() && p.is_file()) {
            evals.push(read_eval(&path)?);
            run.finished(&asset_id(dir), true)?;
            bar.inc(1);
            continue;
        }
        let (e, images) = evaluate_material(dir, &reference, &neural, &env, &o, st.exposure)?;
        if let Some(out) = &args.output {
            write_eval_images(out, &e.name, &images, (o.width, o.height))?;
            let path = record(&asset_id(dir)).expect("an output folder");
            std::fs::create_dir_all(out.join("evals")).map_err(|e| format!("{}: {e}", out.display()))?;
            let text = serde_json::to_string_pretty(&e).map_err(|e| e.to_string())? + "\n";
            write_atomically(&path, text.as_bytes()).map_err(|e| format!("{}: {e}", path.display()))?;
        }
        let line = format!("{} (Type {}): FLIP {:.4} over the ball, {:.4} over the image; PSNR {:.1} dB", e.name, e.kind, e.flip_object, e.flip_full, e.psnr_object);
        bar.suspend(|| println!("{line}"));
        evals.push(e);
        run.finished(&asset_id(dir), false)?;
        bar.inc(1);
    }
    bar.finish_and_clear();
    run.end()?;
    if let (Some(out), Some(_)) = (&args.output, shard) {
        // Every shard's figures so far: the whole batch's once the last shard ends.
        let dir = out.join("evals");
        let mut paths: Vec<PathBuf> = std::fs::read_dir(&dir).map_err(|e| format!("{}: {e}", dir.display()))?.flatten().map(|e| e.path()).filter(|p| p.extension().is_some_and(|x| x == "json")).collect();
        paths.sort();
        evals = paths.iter().map(|p| read_eval(p)).collect::<Result<_, _>>()?;
        println!("(table over the {} materials evaluated in {} so far, of {} in the batch)", evals.len(), out.display(), batch.all);
    }
    let table = format_table(&per_type(&evals));
    println!("\n{table}");
    if let Some(out) = &args.output {
        let path = out.join("table.md");
        write_atomically(&path, table.as_bytes()).map_err(|e| format!("{}: {e}", path.display()))?;
    }
    Ok(())
}

fn read_eval(path: &std::path::Path) -> Result<MaterialEval, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    serde_json::from_str(&text).map_err(|e| format!("{}:{}:{}: {e}", path.display(), e.line(), e.column()))
}
