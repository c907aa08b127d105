//! A decoder's "diffuse" latent (docs/export.md, `uplift project --fill diffuse`): the latent
//! whose decoded non-diffuse part reflects almost nothing and passes almost all light on to the
//! diffuse base (f·cos ≈ 0, T ≈ 1), so that a texel no generated view saw falls back to the
//! plain diffuse material and cannot create energy.
//!
//! Found by a seeded search over [0, 1]^L on a fixed direction set (views cosine-weighted,
//! lights uniform on the hemisphere): the best of [`CANDIDATES`] random latents, then
//! coordinate refinement with halving steps. The objective is the mean luminance of f·μl plus
//! the mean |T − 1| over the directions and channels. Deterministic for a decoder (about a
//! second): `uplift train` stores it in the decoder file's metadata ([`METADATA_KEY`], with the
//! latents' storage affine, `weights::LATENT_SCALE_KEY`), and [`diffuse_latent_of`] reads it back,
//! finding it anew only for files written before it was stored.

use crate::evaluate::decode;
use crate::features::{cosine_hemisphere, direction_features, FEATURES};
use crate::model::NeuralModel;
use crate::weights::TensorFile;
use uplift_base::rng::{mix64, unit_from_key as unit};

/// The decoder file's metadata entry that holds its diffuse latent (JSON: `latent`, `fcos`,
/// `t_error`, `seed`).
pub const METADATA_KEY: &str = "diffuse_latent";
/// The seed the stored diffuse latent is found with.
pub const SEED: u64 = 1;

/// Random latents tried before refinement.
pub const CANDIDATES: usize = 2048;
/// Directions each latent is judged on.
pub const DIRECTIONS: usize = 256;

/// The latent and how diffuse it decodes.
#[derive(Clone, Debug, PartialEq)]
pub struct DiffuseLatent {
    pub latent: Vec<f32>,
    /// Mean luminance of f·μl over the directions (the non-diffuse reflectance density).
    pub fcos: f32,
    /// Mean |T − 1| over the directions and channels.
    pub t_error: f32,
}

impl DiffuseLatent {
    /// The metadata entry's text.
    pub fn to_metadata(&self) -> String {
        serde_json::json!({"latent": self.latent, "fcos": self.fcos, "t_error": self.t_error, "seed": SEED}).to_string()
    }

    /// Reads a metadata entry for a decoder whose latent has `width` values.
    pub fn from_metadata(text: &str, width: usize) -> Result<DiffuseLatent, String> {
        let bad = |why: String| format!("metadata `{METADATA_KEY}`: {why}");
        let v: serde_json::Value = serde_json::from_str(text).map_err(|e| bad(e.to_string()))?;
        let num = |x: &serde_json::Value, what: &str| x.as_f64().map(|f| f as f32).ok_or_else(|| bad(format!("`{what}` is not a number")));
        let latent = v["latent"].as_array().ok_or_else(|| bad("no `latent` array".into()))?.iter().map(|x| num(x, "latent")).collect::<Result<Vec<f32>, String>>()?;
        if latent.len() != width || latent.iter().any(|x| !(0.0..=1.0).contains(x)) {
            return Err(bad(format!("a latent of {} values in [0, 1] expected, found {:?}", width, latent)));
        }
        Ok(DiffuseLatent { latent, fcos: num(&v["fcos"], "fcos")?, t_error: num(&v["t_error"], "t_error")? })
    }
}

/// The diffuse latent of the decoder in `file` (`model`, loaded from it): the stored one, or,
/// for a file written before it was stored, found now. The flag says whether it was stored.
pub fn diffuse_latent_of(file: &TensorFile, model: &NeuralModel<f32>) -> Result<(DiffuseLatent, bool), String> {
    match file.metadata.get(METADATA_KEY) {
        Some(text) => Ok((DiffuseLatent::from_metadata(text, model.latent())?, true)),
        None => Ok((find_diffuse_latent(model, SEED), false)),
    }
}

/// The fixed direction set: features and light cosines.
fn directions() -> (Vec<f32>, Vec<f32>) {
    let (mut features, mut mu) = (Vec::with_capacity(DIRECTIONS * FEATURES), Vec::with_capacity(DIRECTIONS));
    for k in 0..DIRECTIONS as u64 {
        let key = mix64(0xd1ff_05e ^ k);
        let wv = cosine_hemisphere(unit(key), unit(key ^ 1));
        let (u1, u2) = (unit(key ^ 2), unit(key ^ 3));
        let z = u1.max(1e-3);
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = std::f32::consts::TAU * u2;
        let wl = [r * phi.cos(), r * phi.sin(), z];
        features.extend_from_slice(&direction_features([wv[0], wv[1], wv[2].max(1e-3)], wl));
        mu.push(z);
    }
    (features, mu)
}

/// The objective of each of `latents` (rows of the latent width).
fn objective(model: &NeuralModel<f32>, latents: &[f32], features: &[f32], mu: &[f32]) -> Vec<f32> {
    let l = model.latent();
    let n = latents.len() / l;
    let z: Vec<f32> = (0..n).flat_map(|c| (0..DIRECTIONS).flat_map(move |_| latents[c * l..(c + 1) * l].iter().copied())).collect();
    let f: Vec<f32> = (0..n).flat_map(|_| features.iter().copied()).collect();
    let out = decode(model, &z, &f);
    (0..n)
        .map(|c| {
            let mut s = 0.0f32;
            for d in 0..DIRECTIONS {
                let o = &out[(c * DIRECTIONS + d) * 7..][..7];
                let y = 0.2126 * o[0] + 0.7152 * o[1] + 0.0722 * o[2];
                s += (y * mu[d]).max(0.0) + ((o[3] - 1.0).abs() + (o[4] - 1.0).abs() + (o[5] - 1.0).abs()) / 3.0;
            }
            if s.is_finite() { s / DIRECTIONS as f32 } else { f32::INFINITY }
        })
        .collect()
}

/// Finds the decoder's diffuse latent (seeded).
pub fn find_diffuse_latent(model: &NeuralModel<f32>, seed: u64) -> DiffuseLatent {
    let l = model.latent();
    let (features, mu) = directions();
    let candidates: Vec<f32> = (0..CANDIDATES * l).map(|k| unit(mix64(seed ^ 0x5eed ^ k as u64))).collect();
    let scores = objective(model, &candidates, &features, &mu);
    let best = (0..CANDIDATES).min_by(|&a, &b| scores[a].total_cmp(&scores[b])).unwrap_or(0);
    let mut z = candidates[best * l..(best + 1) * l].to_vec();
    let mut score = scores[best];
    let mut step = 0.1f32;
    while step > 1e-3 {
        // All 2L coordinate moves at once; take the best if it improves.
        let moves: Vec<f32> = (0..2 * l).flat_map(|m| {
            let mut c = z.clone();
            c[m / 2] = (c[m / 2] + if m % 2 == 0 { step } else { -step }).clamp(0.0, 1.0);
            c
        }).collect();
        let s = objective(model, &moves, &features, &mu);
        let m = (0..2 * l).min_by(|&a, &b| s[a].total_cmp(&s[b])).unwrap_or(0);
        if s[m] < score {
            score = s[m];
            z = moves[m * l..(m + 1) * l].to_vec();
        } else {
            step *= 0.5;
        }
    }
    // Report the two terms separately.
    let zz: Vec<f32> = (0..DIRECTIONS).flat_map(|_| z.iter().copied()).collect();
    let out = decode(model, &zz, &features);
    let (mut fcos, mut t) = (0.0f32, 0.0f32);
    for d in 0..DIRECTIONS {
        let o = &out[d * 7..][..7];
        fcos += (0.2126 * o[0] + 0.7152 * o[1] + 0.0722 * o[2]) * mu[d] / DIRECTIONS as f32;
        t += ((o[3] - 1.0).abs() + (o[4] - 1.0).abs() + (o[5] - 1.0).abs()) / (3.0 * DIRECTIONS as f32);
    }
    DiffuseLatent { latent: z, fcos, t_error: t }
}
