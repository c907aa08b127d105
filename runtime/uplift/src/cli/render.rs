//! `uplift render MATERIAL/ -o ball.png [-o ball.exr]`: renders an enhanced material (its
//! params.exr), or any MaterialX material (`uplift render FILE.mtlx [--material NAME]`: one
//! material or surface shader of the document, shaded by its own compiled closure kernels with
//! their emission, render/mtlx_material.rs) on the preview ball under an environment (`--env FILE.hdr|FILE.exr`, `studio`,
//! the default, or `white`, a unit environment), shaded by the compiled reference kernels or,
//! with `--neural`, by the decoder on the material's fitted latent.exr (`--sampler`: sampled by the
//! decoder file's sampling decoder). `--mesh FILE.gltf|.glb`
//! renders a glTF scene's triangles instead of the ball (scaled into the ball's unit sphere,
//! with their own uvs, normals and tangents; render/mesh.rs). A `.png` output is the AgX display
//! image, an `.exr` output the linear radiance.

use uplift_neural::weights::{load_model, load_sampler, SHIPPED_DECODER};
use uplift_engines::cpu_engine::CpuEngine;
use uplift_render::environment::Environment;
use uplift_render::image_files::{write_exr, write_png};
use uplift_render::integrator::{render, render_model, RenderOptions, Strategy};
use uplift_render::mtlx_material::MtlxMaterial;
use uplift_enhance::gltf_input;
use uplift_render::mesh::Mesh;
use uplift_render::scene::{Scene, Sphere};
use uplift_render::shading::{Model, Shading, ShadingEngine};
use uplift_render::surface::SurfaceTextures;
use uplift_render::tonemap::to_display;
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct RenderArgs {
    /// An enhanced material's folder (params.exr; latent.exr with --neural), or a MaterialX
    /// document (.mtlx).
    #[arg(value_name = "MATERIAL")]
    pub material: PathBuf,
    /// With a .mtlx document: the material (or surface shader, `graph/output`) to render;
    /// default the document's first material.
    #[arg(long = "material", value_name = "NAME")]
    pub material_name: Option<String>,
    /// With a .mtlx document: the engine its kernels run on.
    #[arg(long, value_enum, default_value_t = super::eval::Engine::Cpu)]
    pub engine: super::eval::Engine,
    /// With a .mtlx document: extra library folder (repeatable); MATERIALX_SEARCH_PATH is read too.
    #[arg(long = "library")]
    pub library: Vec<PathBuf>,
    /// With a .mtlx document: let it name files anywhere (by default in its folder or a library
    /// search path).
    #[arg(long)]
    pub allow_any_path: bool,
    /// Output images: `.png` (AgX display) and/or `.exr` (linear radiance).
    #[arg(short, long, required = true)]
    pub output: Vec<PathBuf>,
    /// Shade with the neural decoder and the fitted latents instead of the reference kernels.
    #[arg(long)]
    pub neural: bool,
    /// With --neural: sample the non-diffuse part with the decoder file's sampling decoder
    /// (`uplift train-sampler`) instead of the stack's sampler on the material's parameters.
    #[arg(long, requires = "neural")]
    pub sampler: bool,
    /// Render this glTF scene's triangles (.gltf or .glb) instead of the preview ball.
    #[arg(long)]
    pub mesh: Option<PathBuf>,
    #[command(flatten)]
    pub settings: RenderSettings,
    /// Surface interactions after the first.
    #[arg(long, default_value_t = 2, value_parser = super::bounds::BOUNCES.parser::<usize>())]
    pub bounces: usize,
    /// Direct lighting: mis, bsdf or light.
    #[arg(long, default_value = "mis")]
    pub strategy: String,
}

/// The settings `render` and `eval-fit` share.
#[derive(Args)]
pub struct RenderSettings {
    /// Encoder and decoder weights (the neural material).
    #[arg(long, default_value = SHIPPED_DECODER)]
    pub decoder: PathBuf,
    /// Environment: an equirectangular .hdr/.exr file, `studio` or `white`.
    #[arg(long, default_value = "studio")]
    pub env: String,
    /// Image width and height in pixels.
    #[arg(long, default_value_t = 256, value_parser = super::bounds::IMAGE_SIDE.parser::<usize>())]
    pub size: usize,
    #[arg(long, default_value_t = 64, value_parser = super::bounds::SPP.parser::<usize>())]
    pub spp: usize,
    /// Exposure multiplier before AgX.
    #[arg(long, default_value_t = 1.0)]
    pub exposure: f32,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    #[arg(long)]
    pub threads: Option<usize>,
    #[command(flatten)]
    pub stack: super::StackArgs,
}

impl RenderSettings {
    /// Checks the numbers; returns the thread count.
    pub fn check(&self) -> Result<usize, String> {
        if self.size == 0 || self.spp == 0 {
            return Err("--size and --spp must be at least 1".into());
        }
        if !(self.exposure > 0.0 && self.exposure.is_finite()) {
            return Err(format!("--exposure must be positive (got {})", self.exposure));
        }
        Ok(self.threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get())).max(1))
    }
}

/// An environment from the command line's `--env`.
pub fn environment(arg: &str) -> Result<Environment, String> {
    match arg {
        "studio" => Ok(Environment::studio()),
        "white" => Ok(Environment::constant([1.0; 3])),
        path => Environment::load(Path::new(path)),
    }
}

/// Writes a rendering to each output by its extension.
pub fn write_outputs(outputs: &[PathBuf], radiance: &[[f32; 3]], size: (usize, usize), exposure: f32) -> Result<(), String> {
    for out in outputs {
        match out.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()).as_deref() {
            Some("png") => write_png(out, &to_display(radiance, exposure), size.0, size.1)?,
            Some("exr") => write_exr(out, radiance, size.0, size.1)?,
            _ => return Err(format!("{}: an output must end in .png or .exr", out.display())),
        }
    }
    Ok(())
}

pub fn run(args: RenderArgs) -> Result<(), String> {
    let threads = args.settings.check()?;
    let st = &args.settings;
    for out in &args.output {
        if !matches!(out.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()).as_deref(), Some("png" | "exr")) {
            return Err(format!("{}: an output must end in .png or .exr", out.display()));
        }
    }
    let strategy = Strategy::parse(&args.strategy)?;
    let env = environment(&st.env)?;
    let is_document = args.material.extension().is_some_and(|e| e.eq_ignore_ascii_case("mtlx"));
    if !is_document && (args.material_name.is_some() || !args.library.is_empty() || args.allow_any_path) {
        return Err(format!("{}: --material, --library and --allow-any-path apply to a MaterialX document (.mtlx), not a material folder", args.material.display()));
    }
    if is_document && args.neural {
        return Err(format!("{}: --neural renders an enhanced material's fitted latents; a MaterialX document has none", args.material.display()));
    }
    let o = RenderOptions { width: st.size, height: st.size, spp: st.spp, bounces: args.bounces, seed: st.seed, strategy, ..Default::default() };
    let scene: Box<dyn Scene> = match &args.mesh {
        Some(path) => Box::new(Mesh::new(gltf_input::load(path)?.world_triangles()).map_err(|e| format!("{}: {e}", path.display()))?),
        None => Box::new(Sphere::preview()),
    };
    if is_document {
        let compiler = super::compiler(&args.library, args.allow_any_path)?;
        let engine = match args.engine {
            super::eval::Engine::Cpu => ShadingEngine::Cpu(CpuEngine::with_threads(threads)?),
            super::eval::Engine::Wgpu => ShadingEngine::Wgpu(uplift_engines::wgpu_engine::WgpuEngine::new()?),
        };
        let material = MtlxMaterial::compile(&compiler, &args.material, args.material_name.as_deref(), engine)?;
        for w in &material.warnings {
            eprintln!("{w}");
        }
        let bar = progress_bar(o.spp, format!("rendering {} / {}", args.material.display(), material.name))?;
        let start = std::time::Instant::now();
        let img = render_model(scene.as_ref(), &env, &material, &o, Some(&bar))?;
        bar.finish_and_clear();
        write_outputs(&args.output, &img.radiance, (img.width, img.height), st.exposure)?;
        report_speed(&o, start);
        return Ok(());
    }
    let stack = st.stack.load()?;
    let surface = SurfaceTextures::load(&args.material, &stack, args.neural)?;
    let model = if args.neural { Model::Neural(load_model(&st.decoder, &stack)?.decoder) } else { Model::Reference };
    let mut shading = Shading::new(CpuEngine::with_threads(threads)?, &stack, model)?;
    if args.sampler {
        let sampler = load_sampler(&st.decoder)?.ok_or_else(|| format!("{}: no sampling decoder (add one with `uplift train-sampler`)", st.decoder.display()))?;
        shading = shading.with_sampler(sampler).map_err(|e| format!("{}: {e}", st.decoder.display()))?;
    }
    let bar = progress_bar(o.spp, format!("rendering {}", args.material.display()))?;
    let start = std::time::Instant::now();
    let img = render(scene.as_ref(), &env, &surface, &shading, &o, Some(&bar))?;
    bar.finish_and_clear();
    write_outputs(&args.output, &img.radiance, (img.width, img.height), st.exposure)?;
    report_speed(&o, start);
    Ok(())
}

fn progress_bar(spp: usize, message: String) -> Result<ProgressBar, String> {
    let bar = ProgressBar::new(spp as u64).with_style(ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} spp {elapsed}").map_err(|e| e.to_string())?.progress_chars("=> "));
    bar.set_message(message);
    Ok(bar)
}

fn report_speed(o: &RenderOptions, start: std::time::Instant) {
    let secs = start.elapsed().as_secs_f64();
    eprintln!("rendered {}×{} at {} spp in {secs:.1} s ({:.0} k paths/s)", o.width, o.height, o.spp, (o.width * o.height * o.spp) as f64 / secs / 1e3);
}
