//! Distant lighting: an equirectangular environment (loaded from `.hdr` or `.exr`, a constant
//! one, or the built-in procedural studio), its radiance and its importance sampling.
//!
//! Mapping (world y up): a direction d has θ = acos(d.y) and φ = atan2(d.x, −d.z) in [0, 2π);
//! texel column = φ / 2π · W, row = θ / π · H (row 0 at the top, the sky). Radiance is piecewise
//! constant per texel, and sampling picks a texel with probability ∝ (luminance + a floor) ×
//! its exact solid angle, then a direction uniformly within the texel's solid angle, so
//! pdf(d) = P(texel) / Ω(texel) exactly, and every direction with radiance has pdf > 0.

use uplift_base::exr;
use std::f32::consts::{PI, TAU};
use std::path::Path;

pub struct Environment {
    pub width: usize,
    pub height: usize,
    /// Row-major RGB radiance.
    pub texels: Vec<[f32; 3]>,
    /// Cumulative row probabilities (height + 1 entries, last = 1).
    row_cdf: Vec<f32>,
    /// Per row, cumulative column probabilities within the row (width + 1 entries each).
    col_cdf: Vec<f32>,
    /// Probability of each texel.
    texel_p: Vec<f32>,
    /// cos θ at each row boundary (height + 1 entries).
    row_cos: Vec<f32>,
}

fn luminance(c: [f32; 3]) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

/// The first index i with cdf[i + 1] > u (cdf starts at 0 and ends at 1).
fn find_interval(cdf: &[f32], u: f32) -> usize {
    let n = cdf.len() - 1;
    let i = cdf.partition_point(|&c| c <= u);
    i.saturating_sub(1).min(n - 1)
}

impl Environment {
    /// An environment from row-major RGB texels. Radiance must be finite and non-negative.
    pub fn from_texels(width: usize, height: usize, texels: Vec<[f32; 3]>, what: &str) -> Result<Environment, String> {
        if width == 0 || height == 0 || texels.len() != width * height {
            return Err(format!("{what}: environment must have width × height texels (got {width}×{height}, {} texels)", texels.len()));
        }
        if let Some(i) = texels.iter().position(|t| t.iter().any(|x| !x.is_finite() || *x < 0.0)) {
            return Err(format!("{what}: texel ({}, {}) has radiance {:?}; radiance must be finite and ≥ 0", i % width, i / width, texels[i]));
        }
        let row_cos: Vec<f32> = (0..=height).map(|j| (PI * j as f32 / height as f32).cos()).collect();
        let mean = texels.iter().map(|&t| luminance(t) as f64).sum::<f64>() / texels.len() as f64;
        let floor = (1e-3 * mean).max(1e-12);
        let mut weights = vec![0.0f64; width * height];
        for j in 0..height {
            let omega = (TAU / width as f32) as f64 * (row_cos[j] - row_cos[j + 1]).max(0.0) as f64;
            for i in 0..width {
                weights[j * width + i] = (luminance(texels[j * width + i]) as f64 + floor) * omega;
            }
        }
        let total: f64 = weights.iter().sum();
        let mut row_cdf = vec![0.0f32; height + 1];
        let mut col_cdf = vec![0.0f32; height * (width + 1)];
        let mut texel_p = vec![0.0f32; width * height];
        let mut acc = 0.0f64;
        for j in 0..height {
            let row: f64 = weights[j * width..(j + 1) * width].iter().sum();
            let mut c = 0.0f64;
            for i in 0..width {
                texel_p[j * width + i] = (weights[j * width + i] / total) as f32;
                c += weights[j * width + i];
                col_cdf[j * (width + 1) + i + 1] = if row > 0.0 { (c / row) as f32 } else { (i + 1) as f32 / width as f32 };
            }
            col_cdf[j * (width + 1) + width] = 1.0;
            acc += row;
            row_cdf[j + 1] = (acc / total) as f32;
        }
        row_cdf[height] = 1.0;
        Ok(Environment { width, height, texels, row_cdf, col_cdf, texel_p, row_cos })
    }

    /// Radiance `rgb` from every direction.
    pub fn constant(rgb: [f32; 3]) -> Environment {
        Environment::from_texels(8, 4, vec![rgb; 32], "constant environment").expect("a constant environment is valid")
    }

    /// The built-in studio: a dim graded sky and floor, a large key softbox, a fill softbox and a
    /// rim strip (mean luminance ≈ 0.5), 256 × 128 texels.
    pub fn studio() -> Environment {
        let (w, h) = (256usize, 128usize);
        // Softboxes as (θ centre, φ centre, half-height, half-width in radians, radiance).
        let boxes: [(f32, f32, f32, f32, [f32; 3]); 3] = [
            (0.85, 0.75, 0.30, 0.38, [9.0, 8.6, 8.0]),
            (1.15, 4.00, 0.28, 0.45, [2.2, 2.35, 2.6]),
            (1.45, 2.65, 0.07, 0.70, [4.0, 4.0, 4.0]),
        ];
        let mut texels = Vec::with_capacity(w * h);
        for j in 0..h {
            let theta = PI * (j as f32 + 0.5) / h as f32;
            for i in 0..w {
                let phi = TAU * (i as f32 + 0.5) / w as f32;
                let y = theta.cos();
                let mut c = if y > 0.0 {
                    let g = 0.12 + 0.18 * y;
                    [g, g, g * 1.08]
                } else {
                    let g = 0.06 + 0.04 * (1.0 + y);
                    [g * 1.05, g, g * 0.95]
                };
                for &(t0, p0, ht, hw, rad) in &boxes {
                    let mut dp = (phi - p0).abs();
                    dp = dp.min(TAU - dp);
                    if (theta - t0).abs() <= ht && dp <= hw {
                        c = rad;
                    }
                }
                texels.push(c);
            }
        }
        Environment::from_texels(w, h, texels, "studio environment").expect("the studio environment is valid")
    }

    /// An equirectangular `.hdr` (Radiance RGBE) or `.exr` (channels R, G, B) file.
    pub fn load(path: &Path) -> Result<Environment, String> {
        let what = path.display().to_string();
        let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
        match ext.as_str() {
            "hdr" => {
                let img = image::open(path).map_err(|e| format!("{what}: {e}"))?.into_rgb32f();
                let (w, h) = (img.width() as usize, img.height() as usize);
                let texels = img.pixels().map(|p| p.0).collect();
                Environment::from_texels(w, h, texels, &what)
            }
            "exr" => {
                let img = exr::read(path)?;
                let ch = |n: &str| img.channel(n).ok_or_else(|| format!("{what}: the environment needs channels R, G and B (no `{n}`)"));
                let (r, g, b) = (ch("R")?, ch("G")?, ch("B")?);
                let texels = (0..img.width * img.height).map(|i| [r[i], g[i], b[i]]).collect();
                Environment::from_texels(img.width, img.height, texels, &what)
            }
            _ => Err(format!("{what}: an environment must be an equirectangular .hdr or .exr file")),
        }
    }

    fn texel_of(&self, d: [f32; 3]) -> usize {
        let theta = d[1].clamp(-1.0, 1.0).acos();
        let mut phi = d[0].atan2(-d[2]);
        if phi < 0.0 {
            phi += TAU;
        }
        let i = ((phi / TAU * self.width as f32) as usize).min(self.width - 1);
        let j = ((theta / PI * self.height as f32) as usize).min(self.height - 1);
        j * self.width + i
    }

    /// Radiance arriving from direction `d` (unit, world space).
    pub fn radiance(&self, d: [f32; 3]) -> [f32; 3] {
        self.texels[self.texel_of(d)]
    }

    /// The solid-angle density with which `sample` draws `d`.
    pub fn pdf(&self, d: [f32; 3]) -> f32 {
        let t = self.texel_of(d);
        let j = t / self.width;
        let omega = TAU / self.width as f32 * (self.row_cos[j] - self.row_cos[j + 1]);
        if omega <= 0.0 {
            return 0.0;
        }
        self.texel_p[t] / omega
    }

    /// A direction drawn from three uniforms; returns (direction, pdf, radiance).
    pub fn sample(&self, u: [f32; 3]) -> ([f32; 3], f32, [f32; 3]) {
        let j = find_interval(&self.row_cdf, u[0]);
        let cols = &self.col_cdf[j * (self.width + 1)..(j + 1) * (self.width + 1)];
        let i = find_interval(cols, u[1]);
        let phi = TAU * (i as f32 + u[2].fract()) / self.width as f32;
        // Uniform in cos θ within the row: uniform in solid angle. The fraction of u[1] inside
        // its interval drives cos θ, so the three uniforms stay independent.
        let span = (cols[i + 1] - cols[i]).max(1e-30);
        let fu = ((u[1] - cols[i]) / span).clamp(0.0, 1.0);
        let cos_t = self.row_cos[j] + fu * (self.row_cos[j + 1] - self.row_cos[j]);
        let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
        let d = [sin_t * phi.sin(), cos_t, -sin_t * phi.cos()];
        // Radiance and pdf are looked up from `d` itself, so a direction that rounds into a
        // neighbouring texel stays consistent with `radiance` and `pdf`.
        (d, self.pdf(d), self.radiance(d))
    }

    /// The mean radiance over the sphere (solid-angle weighted), per channel.
    pub fn mean_radiance(&self) -> [f32; 3] {
        let mut acc = [0.0f64; 3];
        for j in 0..self.height {
            let omega = (TAU / self.width as f32 * (self.row_cos[j] - self.row_cos[j + 1])) as f64;
            for i in 0..self.width {
                for c in 0..3 {
                    acc[c] += self.texels[j * self.width + i][c] as f64 * omega;
                }
            }
        }
        acc.map(|a| (a / (4.0 * std::f64::consts::PI)) as f32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use uplift_base::rng::unit_from_key as unit;

    #[test]
    fn sampling_is_consistent_with_pdf_and_radiance() {
        let env = Environment::studio();
        // E[L/pdf] over samples = ∫ L dω = 4π · mean radiance; E[1/pdf]·… = 4π on the sphere.
        let n = 400_000;
        let (mut acc, mut solid) = ([0.0f64; 3], 0.0f64);
        for i in 0..n {
            let (d, pdf, l) = env.sample([unit(3 * i), unit(3 * i + 1), unit(3 * i + 2)]);
            assert!(pdf > 0.0 && ((d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) - 1.0).abs() < 1e-4);
            assert!((pdf - env.pdf(d)).abs() <= 1e-6 * pdf && l == env.radiance(d));
            solid += 1.0 / pdf as f64;
            for c in 0..3 {
                acc[c] += l[c] as f64 / pdf as f64;
            }
        }
        let mean = env.mean_radiance();
        let four_pi = 4.0 * std::f64::consts::PI;
        assert!((solid / n as f64 - four_pi).abs() < 0.05 * four_pi, "∫ dω = {}", solid / n as f64);
        for c in 0..3 {
            let want = four_pi * mean[c] as f64;
            assert!((acc[c] / n as f64 - want).abs() < 0.01 * want, "channel {c}: {} vs {want}", acc[c] / n as f64);
        }
        // Uniform directions: the pdf integrates to 1.
        let mut total = 0.0f64;
        for i in 0..n {
            let z = 1.0 - 2.0 * unit(7 * i + 5);
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = TAU * unit(7 * i + 6);
            total += env.pdf([r * phi.cos(), z, r * phi.sin()]) as f64;
        }
        assert!((total / n as f64 * four_pi - 1.0).abs() < 0.02, "∫ pdf = {}", total / n as f64 * four_pi);
    }

    #[test]
    fn bad_environments_are_errors() {
        assert!(Environment::from_texels(2, 1, vec![[1.0; 3], [f32::NAN, 0.0, 0.0]], "t").err().unwrap().contains("texel (1, 0)"));
        assert!(Environment::from_texels(2, 2, vec![[1.0; 3]; 3], "t").is_err());
        assert!(Environment::load(Path::new("sky.png")).err().unwrap().contains(".hdr or .exr"));
    }
}
