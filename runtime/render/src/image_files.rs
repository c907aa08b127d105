//! Writing rendered images: 8-bit RGB PNGs (display images, error maps) and linear float EXRs
//! (channels R, G, B), each written atomically.

use uplift_base::atomic_write::write_atomically;
use uplift_base::exr::{self, Compression, ExrImage};
use std::path::Path;

/// Writes 8-bit RGB pixels (row-major) as a PNG.
pub fn write_png(path: &Path, rgb: &[u8], width: usize, height: usize) -> Result<(), String> {
    let img = image::RgbImage::from_raw(width as u32, height as u32, rgb.to_vec()).ok_or_else(|| format!("{}: {} bytes is not a {width}×{height} RGB image", path.display(), rgb.len()))?;
    let mut bytes = std::io::Cursor::new(Vec::new());
    img.write_to(&mut bytes, image::ImageFormat::Png).map_err(|e| format!("{}: encoding PNG: {e}", path.display()))?;
    write_atomically(path, &bytes.into_inner()).map_err(|e| format!("{}: {e}", path.display()))
}

/// Writes linear RGB radiance as a float EXR.
pub fn write_exr(path: &Path, radiance: &[[f32; 3]], width: usize, height: usize) -> Result<(), String> {
    let mut img = ExrImage::new(width, height);
    for (c, name) in ["R", "G", "B"].iter().enumerate() {
        img.push(name, radiance.iter().map(|p| p[c]).collect())?;
    }
    exr::write(path, &img, Compression::Zip)
}
