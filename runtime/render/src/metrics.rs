//! Image comparison: LDR-FLIP through `nv-flip` (NVIDIA's FLIP C++ library) on 8-bit display
//! images, at FLIP's default viewing condition (0.7 m from a 0.7 m wide 3840-pixel monitor:
//! 67.02 pixels per degree), its error map coloured with FLIP's magma map, the mean over all
//! pixels or a mask, and PSNR.

use nv_flip::{flip, magma_lut, pixels_per_degree, FlipImageFloat, FlipImageRgb8};

/// FLIP's default pixels per degree.
pub fn default_pixels_per_degree() -> f32 {
    pixels_per_degree(0.7, 3840.0, 0.7)
}

/// A FLIP error map.
pub struct FlipMap {
    pub width: usize,
    pub height: usize,
    pub error: Vec<f32>,
}

impl FlipMap {
    /// Mean error over all pixels.
    pub fn mean(&self) -> f64 {
        self.error.iter().map(|&e| e as f64).sum::<f64>() / self.error.len().max(1) as f64
    }

    /// Mean error over the pixels where `mask` holds (NaN if none).
    pub fn mean_over(&self, mask: &[bool]) -> f64 {
        let (mut s, mut n) = (0.0f64, 0usize);
        for (&e, &m) in self.error.iter().zip(mask) {
            if m {
                s += e as f64;
                n += 1;
            }
        }
        if n == 0 { f64::NAN } else { s / n as f64 }
    }

    /// The error map through FLIP's magma colour map, 8-bit RGB.
    pub fn to_magma(&self) -> Vec<u8> {
        let img = FlipImageFloat::with_data(self.width as u32, self.height as u32, &self.error);
        img.apply_color_lut(&magma_lut()).to_vec()
    }
}

/// LDR-FLIP of `test` against `reference` (8-bit sRGB, row-major RGB, same size).
pub fn flip_ldr(reference: &[u8], test: &[u8], width: usize, height: usize, pixels_per_degree: f32) -> Result<FlipMap, String> {
    let want = width * height * 3;
    if reference.len() != want || test.len() != want || width == 0 || height == 0 {
        return Err(format!("FLIP: images must both be {width}×{height} RGB ({want} bytes); got {} and {}", reference.len(), test.len()));
    }
    if !(pixels_per_degree > 0.0 && pixels_per_degree.is_finite()) {
        return Err(format!("FLIP: pixels per degree must be positive (got {pixels_per_degree})"));
    }
    let r = FlipImageRgb8::with_data(width as u32, height as u32, reference);
    let t = FlipImageRgb8::with_data(width as u32, height as u32, test);
    let map = flip(r, t, pixels_per_degree);
    Ok(FlipMap { width, height, error: map.to_vec() })
}

/// PSNR in dB of 8-bit images (over the pixels where `mask` holds, or all): +∞ when equal.
pub fn psnr(reference: &[u8], test: &[u8], mask: Option<&[bool]>) -> f64 {
    let (mut se, mut n) = (0.0f64, 0usize);
    for (p, (a, b)) in reference.chunks(3).zip(test.chunks(3)).enumerate() {
        if mask.is_some_and(|m| !m[p]) {
            continue;
        }
        for c in 0..3 {
            let d = a[c] as f64 - b[c] as f64;
            se += d * d;
        }
        n += 3;
    }
    if n == 0 {
        return f64::NAN;
    }
    let mse = se / n as f64;
    if mse == 0.0 { f64::INFINITY } else { 10.0 * (255.0f64 * 255.0 / mse).log10() }
}
