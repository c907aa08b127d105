//! `uplift fit OUT/ [--decoder FILE]`: fits the latent textures of an enhanced material (two RGB
//! textures for the paper's latent of 6; the decoder's width) (`uplift enhance`'s
//! OUT/params.exr) against the frozen decoder (default: the shipped
//! runtime/weights/decoder.safetensors), initialised from its encoder. Writes OUT/latent.exr
//! (channels latent0.R/G/B, latent1.R/G/B, …, float), OUT/latent0.png, latent1.png, … (the same
//! quantised to 8 bits) and OUT/fit.json (Eq. 3 per term before and after, groups, time).
//! Given a folder of enhanced materials (as a batch `uplift enhance` writes), fits each one
//! without a finished fit, in name order, or only those of `--shard i/N` (docs/scale.md).

use clap::Args;
use std::path::PathBuf;
use uplift_engines::cpu_engine::CpuEngine;
use uplift_neural::datagen::{ClassMix, DataGenerator};
use uplift_neural::fit::{fit_material, FitOptions};
use uplift::shard::{Shard, ShardRun};
use uplift_material::folder::find_material_folders;
use uplift_material::{MaterialFolder, ParamsImage};
use uplift_neural::weights::{load_model, SHIPPED_DECODER};

#[derive(Args)]
pub struct FitArgs {
    /// An enhanced material's folder (with params.exr), or a folder of them.
    pub material: PathBuf,
    /// Encoder and decoder weights (safetensors from `uplift train`).
    #[arg(long, default_value = SHIPPED_DECODER)]
    pub decoder: PathBuf,
    /// Adam steps.
    #[arg(long, default_value_t = 200, value_parser = super::bounds::STEPS.parser::<u64>())]
    pub steps: u64,
    /// Direction pairs per texel group and step (fresh every step).
    #[arg(long, default_value_t = 8, value_parser = super::bounds::DIRECTIONS_PER_VIEW.parser::<usize>())]
    pub directions: usize,
    /// Quantisation steps per encoded parameter when grouping texels (0: exact vectors only).
    #[arg(long, default_value_t = 16)]
    pub levels: u32,
    /// Skip the energy bound (neural/energy_bound.rs): keep the Eq. 3 fit even where its
    /// energy exceeds the reference's.
    #[arg(long)]
    pub no_energy_bound: bool,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    #[arg(long)]
    pub threads: Option<usize>,
    /// The engine: the CPU, or wgpu — the reference data by the stack's WGSL kernels, the
    /// decoder's forward and backward passes and Eq. 3 by the emitted WGSL (docs/scale.md).
    #[arg(long, value_enum, default_value_t = super::eval::Engine::Cpu)]
    pub engine: super::eval::Engine,
    /// Fit only this shard of a folder of materials: `i/N`, or `auto` in a Slurm job array or
    /// a Kubernetes indexed job (docs/scale.md).
    #[arg(long)]
    pub shard: Option<String>,
    #[command(flatten)]
    pub stack: super::StackArgs,
}

pub fn run(args: FitArgs) -> Result<(), String> {
    let threads = args.threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get())).max(1);
    if args.steps == 0 || args.directions == 0 {
        return Err("--steps and --directions must be at least 1".into());
    }
    let stack = args.stack.load()?;
    let model = load_model(&args.decoder, &stack)?;
    let engine: uplift_engines::prepared_kernel::AnyEngine = match args.engine {
        super::eval::Engine::Cpu => CpuEngine::with_threads(threads)?.into(),
        super::eval::Engine::Wgpu => uplift_engines::wgpu_engine::WgpuEngine::new()?.into(),
    };
    let generator = DataGenerator::new(engine, &stack, ClassMix::All, args.seed)?;
    let mut o = FitOptions { steps: args.steps, directions: args.directions, levels: args.levels, seed: args.seed, threads, ..Default::default() };
    if args.no_energy_bound {
        o.energy = None;
    }
    let shard = Shard::from_arg(args.shard.as_deref())?;
    if args.material.join("params.exr").is_file() {
        if shard.is_some() {
            return Err(format!("{}: --shard splits a folder of materials; this is one material", args.material.display()));
        }
        return fit_one(&MaterialFolder::open(&args.material)?, &args, &stack, &model, &generator, &o, true);
    }
    // A batch: every material folder under MATERIAL, the shard's own, by folder name.
    let folders = find_material_folders(std::slice::from_ref(&args.material))?;
    let name = |f: &std::path::Path| f.file_name().map(|n| n.to_string_lossy().to_string()).unwrap_or_default();
    let mine: Vec<PathBuf> = folders.iter().filter(|f| shard.is_none_or(|s| s.owns(&name(f)))).cloned().collect();
    let mut run = ShardRun::begin(&args.material, "fit", shard, mine.iter().map(|f| name(f)).collect())?;
    let bar = indicatif::ProgressBar::new(mine.len() as u64);
    bar.set_style(indicatif::ProgressStyle::with_template("{bar:30} {pos}/{len} {msg}").map_err(|e| e.to_string())?);
    let (mut skipped, mut refitted) = (0, 0);
    for f in &mine {
        bar.set_message(name(f));
        let folder = MaterialFolder::open(f)?;
        // A finished fit is kept only when it was made with this run's settings; one with other
        // settings is refitted, and the run says so.
        let other = match folder.has_fit() {
            true => other_settings(&folder.read_fit()?, &args, &o),
            false => None,
        };
        if let Some(why) = &other {
            bar.suspend(|| eprintln!("{}: refitting: its fit.json records {why}", f.display()));
            refitted += 1;
        }
        let skip = folder.has_fit() && other.is_none();
        if skip {
            skipped += 1;
        } else {
            bar.suspend(|| fit_one(&folder, &args, &stack, &model, &generator, &o, false)).map_err(|e| format!("{}: {e}", f.display()))?;
        }
        run.finished(&name(f), skip)?;
        bar.inc(1);
    }
    bar.finish_and_clear();
    run.end()?;
    let of = shard.map_or(String::new(), |s| format!(" (shard {s}: {} of {} materials)", mine.len(), folders.len()));
    let re = if refitted > 0 { format!(" ({refitted} refitted: their fits had other settings)") } else { String::new() };
    eprintln!("fitted {} material(s) under {}{re}; {skipped} already fitted with these settings{of}", mine.len() - skipped, args.material.display());
    Ok(())
}

/// How a finished fit's recorded settings differ from this run's (`--steps 600, this run 10`),
/// or None when they are the same.
fn other_settings(rec: &uplift_material::FitRecord, args: &FitArgs, o: &FitOptions) -> Option<String> {
    let this_decoder = args.decoder.display().to_string();
    let bound = |b: bool| if b { "on" } else { "off" }.to_string();
    let pairs = [
        ("--decoder", rec.decoder.clone(), this_decoder),
        ("--steps", rec.steps.to_string(), o.steps.to_string()),
        ("--directions", rec.directions.to_string(), o.directions.to_string()),
        ("--levels", rec.levels.to_string(), o.levels.to_string()),
        ("the energy bound", bound(rec.energy_bound.is_some()), bound(o.energy.is_some())),
    ];
    let differ: Vec<String> = pairs.iter().filter(|(_, a, b)| a != b).map(|(flag, a, b)| format!("{flag} {a}, this run {b}")).collect();
    (!differ.is_empty()).then(|| differ.join("; "))
}

/// Fits one material folder; `verbose` prints its Eq. 3 and energy-bound figures.
fn fit_one(
    folder: &MaterialFolder,
    args: &FitArgs,
    stack: &uplift_engines::stack::Stack,
    model: &uplift_neural::model::NeuralModel<f32>,
    generator: &DataGenerator,
    o: &FitOptions,
    verbose: bool,
) -> Result<(), String> {
    let ParamsImage { width: w, height: h, params, diffuse, .. } = folder.read_params(stack)?;
    let r = fit_material(model, generator, &params, diffuse.as_deref(), w, h, o, verbose)?;
    // Never a non-finite fit on disk (or a `null` in fit.json): a diverged fit is an error and
    // nothing is written.
    let losses = [("before", r.before.total), ("after", r.after.total), ("after_unbounded", r.after_unbounded.total)];
    if let Some((what, v)) = losses.iter().find(|(_, v)| !v.is_finite()) {
        return Err(format!("{}: the fit diverged (Eq. 3 {what} the fit is {v}); nothing written — are params.exr's values inside the stack's ranges?", folder.dir().display()));
    }
    if let Some(i) = r.latents.iter().position(|x| !x.is_finite()) {
        let t = i / r.latent.max(1);
        return Err(format!("{}: the fit diverged (latent {} of texel ({}, {}) is {}); nothing written", folder.dir().display(), i % r.latent.max(1), t % w, t / w, r.latents[i]));
    }
    folder.write_latents(&r.latent_image())?;
    folder.write_fit(&r.record(&args.decoder, o))?;
    if !verbose {
        return Ok(());
    }
    eprintln!(
        "fitted {w}×{h} texels ({} groups) in {:.1} s; Eq. 3 at {} check texels: encoder only {:.5} (f {:.5}, T {:.5}, R {:.5}) → fitted {:.5} (f {:.5}, T {:.5}, R {:.5})",
        r.groups, r.seconds, o.check_texels.min(w * h), r.before.total, r.before.f, r.before.t, r.before.r, r.after.total, r.after.f, r.after.t, r.after.r
    );
    if let Some(e) = &r.energy {
        eprintln!(
            "energy bound: {} of {} groups over it (worst excess {:.4}) → {} after {} steps (worst {:.4}); Eq. 3 before the bound {:.5}",
            e.over_before, e.groups, e.worst_before, e.over_after, e.steps, e.worst_after, r.after_unbounded.total
        );
    }
    eprintln!("wrote {}", folder.latent_path().display());
    Ok(())
}
