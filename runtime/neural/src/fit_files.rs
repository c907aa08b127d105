//! The files of an enhanced material's folder that fitting reads and writes: params.exr's 22
//! parameters and diffuse colour (`uplift enhance`), and the fit's outputs — latent.exr
//! (channels latent0.R/G/B, latent1.R/G/B, float), latent0.png and latent1.png (the same
//! quantised to 8 bits) and fit.json (Eq. 3 per term before and after, groups, time).

use crate::energy_bound::EnergyReport;
use crate::fit::{FitOptions, FitResult};
use crate::loss::LossParts;
use crate::model::LATENT;
use std::path::Path;
use uplift_base::atomic_write::write_atomically;
use uplift_base::exr::{self, Compression, ExrImage};
use uplift_engines::stack_params::{PARAMETERS, PARAMETER_TABLE};

/// Diffuse colour channels of params.exr.
pub const DIFFUSE_CHANNELS: [&str; 3] = ["diffuse_color.R", "diffuse_color.G", "diffuse_color.B"];

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

