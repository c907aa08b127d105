//! `uplift furnace MATERIAL/… [--neural] [--filter DIR]`: the per-texel white furnace test
//! (render/furnace.rs) of enhanced materials — a folder holding params.exr, or a folder of such
//! folders. Prints each material's worst total albedo and verdict, and the pass rate; with
//! `--filter DIR`, failing material folders are moved into DIR (paper §4.3 discards them).

use uplift::shard::{asset_id, MaterialBatch, Shard, ShardRun};
use uplift_neural::weights::{load_model, SHIPPED_DECODER};
use uplift_engines::cpu_engine::CpuEngine;
use uplift_render::furnace::{white_furnace, FurnaceOptions};
use uplift_render::shading::{Model, Shading};
use uplift_render::surface::SurfaceTextures;
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct FurnaceArgs {
    /// Enhanced material folders, or folders of them.
    #[arg(required = true)]
    pub materials: Vec<PathBuf>,
    /// Check the neural material (decoder on latent.exr) instead of the reference.
    #[arg(long)]
    pub neural: bool,
    /// Encoder and decoder weights for --neural.
    #[arg(long, default_value = SHIPPED_DECODER)]
    pub decoder: PathBuf,
    /// Move failing material folders into this folder.
    #[arg(long)]
    pub filter: Option<PathBuf>,
    /// Check only this shard of a folder of materials (`i/N`, or `auto` in a job array); its
    /// verdicts go to the folder's shard manifest, and a rerun skips those already there
    /// (docs/scale.md).
    #[arg(long)]
    pub shard: Option<String>,
    /// View cosines per texel.
    #[arg(long, default_value_t = 16, value_parser = super::bounds::VIEWS.parser::<usize>())]
    pub views: usize,
    /// Light directions per texel and view.
    #[arg(long, default_value_t = 1024)]
    pub directions: usize,
    /// Distinct texels checked per material (a seeded subset when there are more).
    #[arg(long, default_value_t = 256)]
    pub max_texels: usize,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    #[arg(long)]
    pub threads: Option<usize>,
    #[command(flatten)]
    pub stack: super::StackArgs,
}


fn move_aside(dir: &Path, into: &Path) -> Result<PathBuf, String> {
    std::fs::create_dir_all(into).map_err(|e| format!("{}: {e}", into.display()))?;
    let name = dir.file_name().ok_or_else(|| format!("{}: no folder name", dir.display()))?;
    let target = into.join(name);
    if target.exists() {
        return Err(format!("{}: already exists; not moving {}", target.display(), dir.display()));
    }
    std::fs::rename(dir, &target).map_err(|e| format!("moving {} to {}: {e}", dir.display(), target.display()))?;
    Ok(target)
}

pub fn run(args: FurnaceArgs) -> Result<(), String> {
    let threads = args.threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get())).max(1);
    if args.views == 0 || args.directions == 0 || args.max_texels == 0 {
        return Err("--views, --directions and --max-texels must be at least 1".into());
    }
    let shard = Shard::from_arg(args.shard.as_deref())?;
    let batch = MaterialBatch::find(&args.materials, shard)?;
    let folders = &batch.mine;
    let stage = if args.neural { "furnace-neural" } else { "furnace" };
    let mut run = ShardRun::begin(batch.root.as_deref().unwrap_or(Path::new(".")), stage, shard, folders.iter().map(|f| asset_id(f)).collect())?;
    let stack = args.stack.load()?;
    let model = if args.neural { Model::Neural(load_model(&args.decoder, &stack)?.decoder) } else { Model::Reference };
    let shading = Shading::new(CpuEngine::with_threads(threads)?, &stack, model)?;
    let o = FurnaceOptions { views: args.views, directions: args.directions, max_texels: args.max_texels, seed: args.seed, ..Default::default() };
    let bar = ProgressBar::new(folders.len() as u64).with_style(ProgressStyle::with_template("furnace [{bar:30}] {pos}/{len} {msg}").map_err(|e| e.to_string())?.progress_chars("=> "));
    let mut passed = 0;
    let mut failed = Vec::new();
    for dir in folders {
        bar.set_message(dir.display().to_string());
        if let Some(verdict) = run.previous(&asset_id(dir)) {
            // Checked by an earlier run of this shard.
            if verdict == "pass" { passed += 1 } else { failed.push(dir.clone()) }
            bar.inc(1);
            continue;
        }
        let surface = SurfaceTextures::load(dir, &stack, args.neural)?;
        let r = white_furnace(&surface, &shading, &o)?;
        let line = format!(
            "{}: {} — worst albedo {:.4} at texel ({}, {}), μv {:.3}; {} of {} (texel, view) pairs above 1; {} of {} distinct texels checked",
            dir.display(),
            if r.passed { "pass" } else { "FAIL" },
            r.worst,
            r.worst_texel.0,
            r.worst_texel.1,
            r.worst_mu,
            r.over_one,
            r.pairs,
            r.checked_texels,
            r.distinct_texels
        );
        bar.suspend(|| println!("{line}"));
        if r.passed { passed += 1 } else { failed.push(dir.clone()) }
        run.record(&asset_id(dir), if r.passed { "pass" } else { "fail" })?;
        bar.inc(1);
    }
    bar.finish_and_clear();
    run.end()?;
    println!("white furnace ({}): {passed} of {} materials pass ({:.1} %)", if args.neural { "neural" } else { "reference" }, folders.len(), 100.0 * passed as f64 / folders.len() as f64);
    if let Some(into) = &args.filter {
        for dir in &failed {
            let target = move_aside(dir, into)?;
            println!("moved {} → {}", dir.display(), target.display());
        }
    }
    Ok(())
}
