//! `uplift gallery DIR -o OUT/`: renders every material of every MaterialX document under DIR
//! (each document's material nodes; a document without any, its surface shaders) on the
//! preview ball through its own compiled closure kernels (render/mtlx_material.rs), and writes
//! one PNG per material and `index.html`, a page that shows them with their document, name and
//! the compiler's warnings (a missing texture, …), or why one failed. Failures do not stop the
//! gallery; the command exits 1 after writing the page if any material failed. Rendered
//! images are kept: a second run renders only what is missing (`--rerender` renders all).

use super::render::{environment, write_outputs};
use uplift::demo::report::escape;
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use uplift_engines::cpu_engine::CpuEngine;
use uplift_engines::wgpu_engine::WgpuEngine;
use uplift_render::integrator::{render_model, RenderOptions};
use uplift_render::mtlx_material::{gallery_outputs, MtlxMaterial};
use uplift_render::scene::Sphere;
use uplift_render::shading::ShadingEngine;

#[derive(Args)]
pub struct GalleryArgs {
    /// A folder of MaterialX documents (searched recursively), or one document.
    pub documents: PathBuf,
    /// The output folder (PNG per material, index.html).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Write into an existing folder that holds files this command did not write (they are
    /// kept; it refuses such a folder otherwise: docs/cli.md, output folders).
    #[arg(long)]
    pub force: bool,
    /// The engine the kernels run on (wgpu: no per-material build).
    #[arg(long, value_enum, default_value_t = super::eval::Engine::Wgpu)]
    pub engine: super::eval::Engine,
    /// Environment: an equirectangular .hdr/.exr file, `studio` or `white`.
    #[arg(long, default_value = "studio")]
    pub env: String,
    /// Image width and height in pixels.
    #[arg(long, default_value_t = 160, value_parser = super::bounds::IMAGE_SIDE.parser::<usize>())]
    pub size: usize,
    #[arg(long, default_value_t = 64, value_parser = super::bounds::SPP.parser::<usize>())]
    pub spp: usize,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Surface interactions after the first.
    #[arg(long, default_value_t = 2, value_parser = super::bounds::BOUNCES.parser::<usize>())]
    pub bounces: usize,
    /// Extra library folder (repeatable); MATERIALX_SEARCH_PATH is read too.
    #[arg(long = "library")]
    pub library: Vec<PathBuf>,
    /// Let documents name files anywhere (by default in their folder or a library search path).
    #[arg(long)]
    pub allow_any_path: bool,
    /// Render every material again, even those whose image exists.
    #[arg(long)]
    pub rerender: bool,
}

/// One gallery entry.
struct Entry {
    document: String,
    material: String,
    image: Option<String>,
    notes: Vec<String>,
    failed: bool,
}

fn mtlx_files(dir: &Path, out: &mut Vec<PathBuf>) -> Result<(), String> {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir).map_err(|e| format!("{}: {e}", dir.display()))?.filter_map(|e| e.ok().map(|e| e.path())).collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            mtlx_files(&p, out)?;
        } else if p.extension().is_some_and(|e| e.eq_ignore_ascii_case("mtlx")) {
            out.push(p);
        }
    }
    Ok(())
}

/// A file name for (document, material): path separators and other characters to `_`.
fn image_name(document: &str, material: &str) -> String {
    let clean = |s: &str| s.chars().map(|c| if c.is_ascii_alphanumeric() || c == '-' { c } else { '_' }).collect::<String>();
    format!("{}__{}.png", clean(document.trim_end_matches(".mtlx")), clean(material))
}

pub fn run(args: GalleryArgs) -> Result<(), String> {
    if args.size == 0 || args.spp == 0 {
        return Err("--size and --spp must be at least 1".into());
    }
    let env = environment(&args.env)?;
    let compiler = super::compiler(&args.library, args.allow_any_path)?;
    let (root, files) = if args.documents.is_file() {
        (args.documents.parent().unwrap_or(Path::new(".")).to_path_buf(), vec![args.documents.clone()])
    } else {
        let mut files = Vec::new();
        mtlx_files(&args.documents, &mut files)?;
        (args.documents.clone(), files)
    };
    if files.is_empty() {
        return Err(format!("{}: no MaterialX documents (.mtlx)", args.documents.display()));
    }
    super::claim_output(&args.output, "gallery", args.force)?;
    // What to render: each document's materials, else its surface shaders.
    let mut jobs: Vec<(PathBuf, String, Option<String>)> = Vec::new();
    let mut entries: Vec<Entry> = Vec::new();
    for f in &files {
        let rel = f.strip_prefix(&root).unwrap_or(f).display().to_string();
        let (doc, diags) = mtlx::read_file(f);
        if let Some(e) = diags.iter().find(|d| d.is_error()) {
            entries.push(Entry { document: rel, material: "—".into(), image: None, notes: vec![e.to_string()], failed: true });
            continue;
        }
        for m in gallery_outputs(&doc) {
            jobs.push((f.clone(), rel.clone(), Some(m)));
        }
    }
    let bar = ProgressBar::new(jobs.len() as u64).with_style(ProgressStyle::with_template("gallery [{bar:30}] {pos}/{len} {msg} {elapsed}").map_err(|e| e.to_string())?.progress_chars("=> "));
    let o = RenderOptions { width: args.size, height: args.size, spp: args.spp, bounces: args.bounces, seed: args.seed, ..Default::default() };
    let wgpu = match args.engine {
        super::eval::Engine::Wgpu => Some(WgpuEngine::new()?),
        super::eval::Engine::Cpu => None,
    };
    for (path, rel, name) in jobs {
        let name = name.unwrap_or_default();
        bar.set_message(format!("{rel} / {name}"));
        let image = image_name(&rel, &name);
        let out = args.output.join(&image);
        let mut entry = Entry { document: rel.clone(), material: name.clone(), image: None, notes: Vec::new(), failed: false };
        let engine = match &wgpu {
            Some(e) => ShadingEngine::Wgpu(e.clone()),
            None => ShadingEngine::Cpu(CpuEngine::new()?),
        };
        match MtlxMaterial::compile(&compiler, &path, Some(&name), engine) {
            Ok(material) => {
                // Positions relative to the gallery's folder, as the captions name documents.
                let prefix = format!("{}/", root.display());
                entry.notes = material.warnings.iter().map(|w| w.replace(&prefix, "")).collect();
                let rendered = if out.is_file() && !args.rerender {
                    Ok(())
                } else {
                    render_model(&Sphere::preview(), &env, &material, &o, None).and_then(|img| write_outputs(&[out.clone()], &img.radiance, (img.width, img.height), 1.0))
                };
                match rendered {
                    Ok(()) => entry.image = Some(image),
                    Err(e) => {
                        entry.notes.push(e);
                        entry.failed = true;
                    }
                }
            }
            Err(e) => {
                entry.notes.push(e);
                entry.failed = true;
            }
        }
        entries.push(entry);
        bar.inc(1);
    }
    bar.finish_and_clear();
    let failed = entries.iter().filter(|e| e.failed).count();
    let mut html = String::from("<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>uplift gallery</title>\n<style>body{font-family:sans-serif;background:#222;color:#ddd}figure{display:inline-block;margin:8px;width:");
    let _ = write!(html, "{}px;vertical-align:top}}figcaption{{font-size:12px}}.note{{color:#e9a}}img{{background:#000}}</style></head><body>\n", args.size.max(160));
    let _ = writeln!(
        html,
        "<h1>uplift gallery</h1><p>{} materials from <code>{}</code>, each rendered on the preview ball through its own compiled closure kernels ({} engine, {} environment, {}² pixels, {} spp, {} bounces, seed {}); {} failed.</p>",
        entries.len(),
        escape(&args.documents.display().to_string()),
        if wgpu.is_some() { "wgpu" } else { "CPU" },
        escape(&args.env),
        args.size,
        args.spp,
        args.bounces,
        args.seed,
        failed
    );
    for e in &entries {
        html.push_str("<figure>");
        if let Some(img) = &e.image {
            let _ = write!(html, "<img src=\"{}\" width=\"{}\" height=\"{}\" alt=\"{}\">", escape(img), args.size, args.size, escape(&e.material));
        }
        let _ = write!(html, "<figcaption><b>{}</b><br>{}", escape(&e.material), escape(&e.document));
        for n in &e.notes {
            let _ = write!(html, "<br><span class=\"note\">{}</span>", escape(n));
        }
        html.push_str("</figcaption></figure>\n");
    }
    html.push_str("</body></html>\n");
    let index = args.output.join("index.html");
    uplift_base::atomic_write::write_atomically(&index, html.as_bytes()).map_err(|e| format!("{}: {e}", index.display()))?;
    eprintln!("wrote {} ({} materials, {failed} failed)", index.display(), entries.len());
    if failed > 0 {
        return Err(format!("{failed} of {} materials failed; index.html says why", entries.len()));
    }
    Ok(())
}
