//! `uplift fit OUT/ [--decoder FILE]`: fits the two RGB latent textures of an enhanced material
//! (`uplift enhance`'s OUT/params.exr) against the frozen decoder (default: the shipped
//! runtime/weights/decoder.safetensors), initialised from its encoder. Writes OUT/latent.exr
//! (channels latent0.R/G/B, latent1.R/G/B, float), OUT/latent0.png and OUT/latent1.png (the same
//! quantised to 8 bits) and OUT/fit.json (Eq. 3 per term before and after, groups, time).

use crate::atomic_write::write_atomically;
use crate::cpu_engine::CpuEngine;
use crate::exr::{self, Compression, ExrImage};
use crate::neural::datagen::{ClassMix, DataGenerator};
use crate::neural::energy_bound::EnergyReport;
use crate::render::surface::DIFFUSE_CHANNELS;
use crate::neural::fit::{fit_material, FitOptions, FitResult};
use crate::neural::loss::LossParts;
use crate::neural::model::{NeuralModel, LATENT};
use crate::neural::params::{PARAMETERS, PARAMETER_TABLE};
use crate::neural::weights::TensorFile;
use clap::Args;
use std::path::{Path, PathBuf};

/// The decoder the repository ships.
pub const SHIPPED_DECODER: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/weights/decoder.safetensors");

#[derive(Args)]
pub struct FitArgs {
    /// An enhanced material's folder (with params.exr).
    pub material: PathBuf,
    /// Encoder and decoder weights (safetensors from `uplift train`).
    #[arg(long, default_value = SHIPPED_DECODER)]
    pub decoder: PathBuf,
    /// Adam steps.
    #[arg(long, default_value_t = 200)]
    pub steps: u64,
    /// Direction pairs per texel group and step (fresh every step).
    #[arg(long, default_value_t = 8)]
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
}

/// The encoder and decoder of a weights file.
pub fn load_model(path: &Path) -> Result<NeuralModel<f32>, String> {
    let f = TensorFile::read(path)?;
    let at = |e: String| format!("{}: {e}", path.display());
    Ok(NeuralModel { encoder: f.mlp("encoder").map_err(at)?, decoder: f.mlp("decoder").map_err(at)? })
}

/// What fitting reads from an enhanced material's params.exr (read once).
pub struct FitInputs {
    pub width: usize,
    pub height: usize,
    /// The 22 parameters per texel.
    pub params: Vec<f32>,
    /// The diffuse colour c per texel (texels × 3), if params.exr has the channels (folders
    /// written before `uplift enhance` baked them do not; the energy bound then assumes c = 1).
    pub diffuse: Option<Vec<f32>>,
}

/// Reads [`FitInputs`] from params.exr.
pub fn read_params(path: &Path) -> Result<FitInputs, String> {
    let img = exr::read(path)?;
    let n = img.width * img.height;
    let mut params = vec![0.0f32; n * PARAMETERS];
    for (k, p) in PARAMETER_TABLE.iter().enumerate() {
        let ch = img.channel(p.channel).ok_or_else(|| format!("{}: no channel `{}` (is this an `uplift enhance` params.exr?)", path.display(), p.channel))?;
        for t in 0..n {
            params[t * PARAMETERS + k] = ch[t];
        }
    }
    let diffuse = match DIFFUSE_CHANNELS.map(|name| img.channel(name)) {
        [Some(r), Some(g), Some(b)] => Some((0..n).flat_map(|t| [r[t], g[t], b[t]]).collect()),
        _ => None,
    };
    Ok(FitInputs { width: img.width, height: img.height, params, diffuse })
}

fn parts_json(p: &LossParts) -> String {
    format!("{{\"total\": {:.6}, \"f\": {:.6}, \"T\": {:.6}, \"R\": {:.6}}}", p.total, p.f, p.t, p.r)
}

fn energy_json(e: &EnergyReport) -> String {
    format!(
        "{{\"groups\": {}, \"over_before\": {}, \"over_after\": {}, \"worst_excess_before\": {:.5}, \"worst_excess_after\": {:.5}, \"steps\": {}}}",
        e.groups, e.over_before, e.over_after, e.worst_before, e.worst_after, e.steps
    )
}

/// Writes latent.exr, the two PNGs and fit.json into `dir`.
pub fn write_fit(dir: &Path, r: &FitResult, decoder: &Path, o: &FitOptions) -> Result<(), String> {
    let n = r.width * r.height;
    let mut img = ExrImage::new(r.width, r.height);
    for tex in 0..2 {
        for (c, ch) in ["R", "G", "B"].iter().enumerate() {
            img.push(&format!("latent{tex}.{ch}"), (0..n).map(|t| r.latents[t * LATENT + 3 * tex + c]).collect())?;
        }
        let px: Vec<u8> = (0..n).flat_map(|t| (0..3).map(move |c| (r.latents[t * LATENT + 3 * tex + c].clamp(0.0, 1.0) * 255.0).round() as u8)).collect();
        let png = image::RgbImage::from_raw(r.width as u32, r.height as u32, px).ok_or("latent image size")?;
        let mut bytes = std::io::Cursor::new(Vec::new());
        png.write_to(&mut bytes, image::ImageFormat::Png).map_err(|e| format!("encoding latent{tex}.png: {e}"))?;
        let path = dir.join(format!("latent{tex}.png"));
        write_atomically(&path, &bytes.into_inner()).map_err(|e| format!("{}: {e}", path.display()))?;
    }
    exr::write(&dir.join("latent.exr"), &img, Compression::Zip)?;
    let json = format!(
        "{{\n  \"decoder\": {:?},\n  \"texels\": {n},\n  \"groups\": {},\n  \"steps\": {},\n  \"directions\": {},\n  \"levels\": {},\n  \"seconds\": {:.2},\n  \"eq3_encoder_only\": {},\n  \"eq3_fitted\": {},\n  \"eq3_fitted_before_energy_bound\": {},\n  \"fitting_loss_first_step\": {},\n  \"fitting_loss_last_step\": {},\n  \"energy_bound\": {}\n}}\n",
        decoder.display().to_string(),
        r.groups,
        o.steps,
        o.directions,
        o.levels,
        r.seconds,
        parts_json(&r.before),
        parts_json(&r.after),
        parts_json(&r.after_unbounded),
        parts_json(&r.first_step),
        parts_json(&r.last_step),
        r.energy.as_ref().map_or("null".to_string(), energy_json)
    );
    let path = dir.join("fit.json");
    write_atomically(&path, json.as_bytes()).map_err(|e| format!("{}: {e}", path.display()))
}

pub fn run(args: FitArgs) -> Result<(), String> {
    let threads = args.threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get())).max(1);
    if args.steps == 0 || args.directions == 0 {
        return Err("--steps and --directions must be at least 1".into());
    }
    let model = load_model(&args.decoder)?;
    let FitInputs { width: w, height: h, params, diffuse } = read_params(&args.material.join("params.exr"))?;
    let generator = DataGenerator::new(CpuEngine::with_threads(threads)?, ClassMix::All, args.seed)?;
    let mut o = FitOptions { steps: args.steps, directions: args.directions, levels: args.levels, seed: args.seed, threads, ..Default::default() };
    if args.no_energy_bound {
        o.energy = None;
    }
    let r = fit_material(&model, &generator, &params, diffuse.as_deref(), w, h, &o, true)?;
    write_fit(&args.material, &r, &args.decoder, &o)?;
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
    eprintln!("wrote {}", args.material.join("latent.exr").display());
    Ok(())
}
