//! `uplift project GENERATED_DIR --mesh FILE -o MATERIAL_DIR`: frames of latent and base-colour
//! videos (as `uplift export` writes them, or as a generator returns them) with cameras.json,
//! projected into the mesh's texture space as a fitted material folder (uplift::project).

use clap::Args;
use std::path::PathBuf;
use uplift::project::{project, ProjectOptions};
use uplift_enhance::gltf_input;

#[derive(Args)]
pub struct ProjectArgs {
    /// The generated (or exported) frames: cameras.json, latent0/, latent1/, base_color/.
    #[arg(value_name = "GENERATED_DIR")]
    pub generated: PathBuf,
    /// The mesh (.gltf or .glb) the frames show.
    #[arg(long)]
    pub mesh: PathBuf,
    #[arg(short, long)]
    pub output: PathBuf,
    /// Write into an existing folder that holds files this command did not write (they are
    /// kept; it refuses such a folder otherwise: docs/cli.md, output folders).
    #[arg(long)]
    pub force: bool,
    /// Texture size (width and height).
    #[arg(long, default_value_t = 512, value_parser = super::bounds::BAKE_SIDE.parser::<usize>())]
    pub resolution: usize,
    /// The glTF material whose texture space is filled.
    #[arg(long, default_value_t = 0)]
    pub gltf_material: usize,
    /// Texels no frame saw: `inpaint` (from their neighbours) or `diffuse` (the decoder's
    /// diffuse latent: no non-diffuse reflection, all light to the diffuse base).
    #[arg(long, default_value = "inpaint")]
    pub fill: String,
    /// The decoder whose diffuse latent `--fill diffuse` uses.
    #[arg(long, default_value = uplift_neural::weights::SHIPPED_DECODER)]
    pub decoder: PathBuf,
    #[command(flatten)]
    pub stack: super::StackArgs,
}

pub fn run(args: ProjectArgs) -> Result<(), String> {
    let asset = gltf_input::load(&args.mesh)?;
    let stack = args.stack.load()?;
    let fill = match args.fill.as_str() {
        "inpaint" => None,
        "diffuse" => {
            let model = uplift_neural::weights::load_model(&args.decoder, &stack)?;
            let file = uplift_neural::weights::TensorFile::read(&args.decoder)?;
            let (d, stored) = uplift_neural::diffuse_latent::diffuse_latent_of(&file, &model).map_err(|e| format!("{}: {e}", args.decoder.display()))?;
            let whence = if stored { "stored in" } else { "found for (the file does not store one)" };
            eprintln!("diffuse latent {whence} {}: {:?} (mean f·cos {:.4}, mean |T − 1| {:.4})", args.decoder.display(), d.latent, d.fcos, d.t_error);
            Some(d.latent)
        }
        other => return Err(format!("--fill {other}: inpaint or diffuse")),
    };
    let o = ProjectOptions { width: args.resolution, height: args.resolution, material: args.gltf_material, fill };
    super::claim_output(&args.output, "project", args.force)?;
    let s = project(&args.generated, &asset, &stack, &args.output, &o)?;
    eprintln!(
        "projected {} into {}: {} of {} texels in the UV charts seen by the frames, {} inpainted; {:.1} s ({:.0} k texels/s)",
        args.generated.display(),
        args.output.display(),
        s.projected,
        s.in_charts,
        s.filled,
        s.seconds,
        s.texels as f64 / s.seconds / 1e3
    );
    Ok(())
}
