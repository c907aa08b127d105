//! `uplift masks --seed S --size N -o DIR`: writes the procedural masks of the uplift rules
//! (`DIR/dust.png`, `DIR/damage.png`; 16-bit grey, tileable). The example masks beside the
//! rules (`mtlx/rules/masks/`) are `uplift masks --seed 0 --size 256 -o mtlx/rules/masks`.

use uplift_enhance::masks::{generate, MaskKind};
use clap::Args;
use std::path::PathBuf;

#[derive(Args)]
pub struct MasksArgs {
    /// Seed of the masks.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Width and height in texels.
    #[arg(long, default_value_t = 512, value_parser = super::bounds::TEXTURE_SIDE.parser::<usize>())]
    pub size: usize,
    /// Output folder.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Write into an existing folder that holds files this command did not write (they are
    /// kept; it refuses such a folder otherwise: docs/cli.md, output folders).
    #[arg(long)]
    pub force: bool,
}

pub fn run(args: MasksArgs) -> Result<(), String> {
    if args.size == 0 || args.size > 16384 {
        return Err(format!("--size {}: masks are 1 to 16384 texels wide", args.size));
    }
    super::claim_output(&args.output, "masks", args.force)?;
    for kind in [MaskKind::Dust, MaskKind::Damage] {
        let path = args.output.join(format!("{}.png", kind.file_stem()));
        generate(kind, args.seed, args.size).write_png(&path)?;
        eprintln!("wrote {}", path.display());
    }
    Ok(())
}
