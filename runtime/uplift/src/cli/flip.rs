//! `uplift flip REFERENCE.png TEST.png [-o error.png]`: LDR-FLIP of two 8-bit images (NVIDIA's
//! FLIP through nv-flip, 67.02 pixels per degree unless `--ppd`), with PSNR; `-o` writes the
//! error map in FLIP's magma colours.

use uplift_render::image_files::write_png;
use uplift_render::metrics::{default_pixels_per_degree, flip_ldr, psnr};
use clap::Args;
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct FlipArgs {
    pub reference: PathBuf,
    pub test: PathBuf,
    /// Write the error map (magma) here.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Pixels per degree of visual angle (default: FLIP's, 0.7 m from a 0.7 m wide 3840-pixel screen).
    #[arg(long)]
    pub ppd: Option<f32>,
}

fn read_rgb8(path: &Path) -> Result<(Vec<u8>, usize, usize), String> {
    let img = image::open(path).map_err(|e| format!("{}: {e}", path.display()))?.into_rgb8();
    let (w, h) = (img.width() as usize, img.height() as usize);
    Ok((img.into_raw(), w, h))
}

pub fn run(args: FlipArgs) -> Result<(), String> {
    let (a, w, h) = read_rgb8(&args.reference)?;
    let (b, w2, h2) = read_rgb8(&args.test)?;
    if (w, h) != (w2, h2) {
        return Err(format!("{} is {w}×{h} but {} is {w2}×{h2}", args.reference.display(), args.test.display()));
    }
    let map = flip_ldr(&a, &b, w, h, args.ppd.unwrap_or_else(default_pixels_per_degree))?;
    println!("FLIP {:.6}  PSNR {:.2} dB", map.mean(), psnr(&a, &b, None));
    if let Some(out) = &args.output {
        write_png(out, &map.to_magma(), w, h)?;
    }
    Ok(())
}
