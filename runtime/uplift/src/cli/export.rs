//! `uplift export MATERIAL_DIR --mesh FILE.gltf|.glb -o OUT/`: a fitted material on a mesh as a
//! multi-view intrinsic video (uplift::export). A folder of material folders exports each one
//! into `OUT/<name>/` (the batch form), or only those of `--shard i/N` (docs/scale.md);
//! finished frames are skipped on a rerun.

use clap::Args;
use std::path::PathBuf;
use uplift::export::{export_asset, ExportOptions, NATIVE_SIZE};
use uplift::shard::{Shard, ShardRun};
use uplift_enhance::gltf_input;
use uplift_material::MaterialFolder;
use uplift_neural::weights::SHIPPED_DECODER;
use uplift_render::mesh::Mesh;
use uplift_render::orbit::OrbitOptions;

#[derive(Args)]
pub struct ExportArgs {
    /// A fitted material's folder, or a folder of them.
    #[arg(value_name = "MATERIAL_DIR")]
    pub material: PathBuf,
    /// The mesh (.gltf or .glb) the material is shown on.
    #[arg(long)]
    pub mesh: PathBuf,
    #[arg(short, long)]
    pub output: PathBuf,
    /// Write into an existing folder that holds files this command did not write (they are
    /// kept; it refuses such a folder otherwise: docs/cli.md, output folders).
    #[arg(long)]
    pub force: bool,
    /// Frames of the orbit (17 = 8k + 1 suits causal video tokenizers).
    #[arg(long, default_value_t = 16, value_parser = super::bounds::FRAMES.parser::<usize>())]
    pub frames: usize,
    /// Square frames of this many pixels.
    #[arg(long, default_value_t = 512, value_parser = super::bounds::IMAGE_SIDE.parser::<usize>())]
    pub size: usize,
    /// The video models' native 1280×704 instead of --size.
    #[arg(long)]
    pub native: bool,
    /// Samples per pixel of the shaded frames.
    #[arg(long, default_value_t = 64, value_parser = super::bounds::SPP.parser::<usize>())]
    pub spp: usize,
    /// Bounces of the shaded frames' paths.
    #[arg(long, default_value_t = 3, value_parser = super::bounds::BOUNCES.parser::<usize>())]
    pub bounces: usize,
    /// Environment: an equirectangular .hdr/.exr file, `studio` or `white`.
    #[arg(long, default_value = "studio")]
    pub env: String,
    /// Exposure multiplier before AgX.
    #[arg(long, default_value_t = 1.0)]
    pub exposure: f32,
    /// The orbit's start azimuth and elevation phase.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Shade with the neural decoder (and the fitted latents) instead of the reference stack.
    #[arg(long)]
    pub neural: bool,
    #[arg(long, default_value = SHIPPED_DECODER)]
    pub decoder: PathBuf,
    #[arg(long)]
    pub threads: Option<usize>,
    /// Also write each PNG modality as a lossless 8-bit RGB MP4 (`<modality>.mp4`; needs
    /// ffmpeg, Debian's package).
    #[arg(long)]
    pub mp4: bool,
    /// Export only this shard of a folder of materials: `i/N`, or `auto` in a Slurm job array
    /// or a Kubernetes indexed job (docs/scale.md).
    #[arg(long)]
    pub shard: Option<String>,
    #[command(flatten)]
    pub stack: super::StackArgs,
}

pub fn run(args: ExportArgs) -> Result<(), String> {
    if args.spp == 0 || args.size == 0 {
        return Err("--spp and --size must be at least 1".into());
    }
    if !(args.exposure > 0.0 && args.exposure.is_finite()) {
        return Err(format!("--exposure must be positive (got {})", args.exposure));
    }
    let threads = args.threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get())).max(1);
    let (width, height) = if args.native { NATIVE_SIZE } else { (args.size, args.size) };
    let orbit = OrbitOptions { frames: args.frames, width, height, seed: args.seed, ..Default::default() };
    orbit.check().map_err(|e| format!("--frames/--size: {e}"))?;
    let mesh = Mesh::new(gltf_input::load(&args.mesh)?.world_triangles()).map_err(|e| format!("{}: {e}", args.mesh.display()))?;
    let env = super::render::environment(&args.env)?;
    let stack = args.stack.load()?;
    let o = ExportOptions { orbit, spp: args.spp, bounces: args.bounces, exposure: args.exposure, threads, neural: args.neural.then(|| args.decoder.clone()), latent_affine: uplift::export::latent_affine_of(&args.decoder)?, mp4: args.mp4 };
    // One material, or a folder of them (the shard's own, by folder name).
    let shard = Shard::from_arg(args.shard.as_deref())?;
    let assets: Vec<(PathBuf, PathBuf)> = if MaterialFolder::open(&args.material).is_ok() {
        if shard.is_some() {
            return Err(format!("{}: --shard splits a folder of materials; this is one material", args.material.display()));
        }
        vec![(args.material.clone(), args.output.clone())]
    } else {
        let entries = std::fs::read_dir(&args.material).map_err(|e| format!("{}: {e}", args.material.display()))?;
        let mut dirs: Vec<PathBuf> = entries.filter_map(|e| e.ok().map(|e| e.path())).filter(|p| MaterialFolder::open(p).is_ok()).collect();
        dirs.sort();
        if dirs.is_empty() {
            return Err(format!("{}: neither an enhanced material (no params.exr) nor a folder of them", args.material.display()));
        }
        dirs.into_iter().map(|d| (d.clone(), args.output.join(d.file_name().unwrap_or_default()))).filter(|(_, out)| shard.is_none_or(|s| s.owns(&asset_name(out)))).collect()
    };
    super::claim_output(&args.output, "export", args.force)?;
    let mut run = ShardRun::begin(&args.output, "export", shard, assets.iter().map(|(_, out)| asset_name(out)).collect())?;
    for (dir, out) in &assets {
        let start = std::time::Instant::now();
        let s = export_asset(dir, &mesh, &env, &stack, out, &o, true)?;
        eprintln!(
            "exported {} → {}: {} frames of {width}×{height} ({} already there); intrinsic {:.1} s ({:.2} frames/s), shaded at {} spp {:.1} s ({:.3} frames/s); {:.1} s in all",
            dir.display(),
            out.display(),
            s.frames,
            s.skipped,
            s.seconds_intrinsic,
            (s.frames - s.skipped) as f64 / s.seconds_intrinsic.max(1e-9),
            o.spp,
            s.seconds_shaded,
            (s.frames - s.skipped) as f64 / s.seconds_shaded.max(1e-9),
            start.elapsed().as_secs_f64()
        );
        run.finished(&asset_name(out), s.skipped == s.frames)?;
    }
    run.end()
}

fn asset_name(out: &std::path::Path) -> String {
    out.file_name().map(|n| n.to_string_lossy().to_string()).unwrap_or_default()
}
