//! `uplift export`: an enhanced, fitted material on a mesh as the multi-view intrinsic video a
//! generative model trains on (paper §5.2, Fig. 9–11). A camera orbit (render/orbit.rs) and, per
//! frame, the intrinsic buffers (render/intrinsics.rs: one exact sample per pixel centre) and the
//! shaded frame (the path tracer, Blender's AgX to 8-bit sRGB), written losslessly under one
//! folder per modality, with `cameras.json` (nerfstudio), `meta.json` (every encoding) and
//! `prompt.txt` (the enhancement Type's keywords).
//!
//! Encodings (`meta.json` records them): an encoded channel stores v ∈ [0, 1] in a 16-bit PNG,
//! and the tokenizer convention 2v − 1 gives u ∈ [−1, 1]; the physical value is
//! `offset + scale·u` per channel: normals (scale 1, offset 0), positions (the bounding box:
//! scale (hi − lo)/2, offset (hi + lo)/2), latents (the affine the decoder file records,
//! `latent.scale`/`latent.offset`: ½ and ½ for latents in [0, 1]). Base colour is the material's base colour texture as stored. Floats (depth,
//! positions, normals) are also written as EXR. Frames already written (their shaded PNG, the
//! last file of a frame, exists) are skipped, so an interrupted export resumes.

use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use uplift_base::atomic_write::write_atomically;
use uplift_base::exr::{self, Compression, ExrImage};
use uplift_engines::cpu_engine::CpuEngine;
use uplift_engines::stack::Stack;
use uplift_material::MaterialFolder;
use uplift_render::agx_blender::to_display_blender;
use uplift_render::environment::Environment;
use uplift_render::image_files::write_png;
use uplift_render::integrator::{render, RenderOptions};
use uplift_render::intrinsics::{colour_texture, intrinsic_frame, IntrinsicFrame};
use uplift_render::mesh::Mesh;
use uplift_render::orbit::{nerfstudio_json, orbit, OrbitOptions};
use uplift_render::scene::Vec3;
use uplift_render::shading::{Model, Shading};
use uplift_render::surface::SurfaceTextures;

/// The native size of the video models' shapes (`--native`).
pub const NATIVE_SIZE: (usize, usize) = (1280, 704);

/// What to export.
#[derive(Clone, Debug)]
pub struct ExportOptions {
    pub orbit: OrbitOptions,
    /// Samples per pixel and bounces of the shaded frames.
    pub spp: usize,
    pub bounces: usize,
    pub exposure: f32,
    pub threads: usize,
    /// Shade with the neural decoder (these weights) instead of the reference stack.
    pub neural: Option<PathBuf>,
    /// The latents' storage affine, per latent value (scale, offset): stored v = ½ + (latent −
    /// offset) / (2 · scale). The decoder file records it (`weights::latent_affine`).
    pub latent_affine: LatentAffine,
    /// Also encode each PNG modality as a lossless MP4 (`video.rs`; needs ffmpeg).
    pub mp4: bool,
}

/// Scale and offset per latent value: latent = offset + scale · (2v − 1).
pub type LatentAffine = ([f32; 6], [f32; 6]);

/// The affine of latents in [0, 1] stored as they are.
pub const UNIT_LATENT_AFFINE: LatentAffine = ([0.5; 6], [0.5; 6]);

/// The affine a decoder file records, for the export's six latent values.
pub fn latent_affine_of(decoder: &Path) -> Result<LatentAffine, String> {
    let file = uplift_neural::weights::TensorFile::read(decoder)?;
    let (scale, offset) = uplift_neural::weights::latent_affine(&file, 6).map_err(|e| format!("{}: {e}", decoder.display()))?;
    if scale.iter().any(|s| *s <= 0.0) {
        return Err(format!("{}: metadata `{}` must be positive", decoder.display(), uplift_neural::weights::LATENT_SCALE_KEY));
    }
    Ok((std::array::from_fn(|k| scale[k]), std::array::from_fn(|k| offset[k])))
}

/// The enhancement Types' caption keywords (the paper augments captions with them).
pub const TYPE_KEYWORDS: [&[&str]; 6] = [
    &["hazy gloss", "layered specular"],
    &["dusty", "dust layer"],
    &["clear coat", "glossy coating"],
    &["dusty", "clear coat", "worn coating"],
    &["fuzzy sheen", "subsurface scattering", "translucent"],
    &["fuzzy sheen", "subsurface scattering", "clear coat"],
];

/// The modalities written per frame: folder and file extension.
pub const MODALITIES: [(&str, &str); 11] = [
    ("normal_camera", "png"),
    ("normal_world", "png"),
    ("position", "png"),
    ("base_color", "png"),
    ("latent0", "png"),
    ("latent1", "png"),
    ("mask", "png"),
    ("depth", "exr"),
    ("position", "exr"),
    ("normal_world", "exr"),
    ("shaded", "png"),
];

/// The file of modality `name` at frame `k`.
pub fn frame_path(out: &Path, name: &str, k: usize, ext: &str) -> PathBuf {
    out.join(name).join(format!("{k:04}.{ext}"))
}

/// What an export wrote.
#[derive(Debug)]
pub struct ExportSummary {
    pub frames: usize,
    pub skipped: usize,
    pub seconds_intrinsic: f64,
    pub seconds_shaded: f64,
}

fn write_png16(path: &Path, v: &[[f32; 3]], width: usize, height: usize) -> Result<(), String> {
    let data: Vec<u16> = v.iter().flat_map(|p| p.map(|x| (x.clamp(0.0, 1.0) * 65535.0).round() as u16)).collect();
    let img = image::ImageBuffer::<image::Rgb<u16>, Vec<u16>>::from_raw(width as u32, height as u32, data).ok_or("a 16-bit image of the wrong size")?;
    let mut bytes = std::io::Cursor::new(Vec::new());
    img.write_to(&mut bytes, image::ImageFormat::Png).map_err(|e| format!("{}: encoding PNG: {e}", path.display()))?;
    write_atomically(path, &bytes.into_inner()).map_err(|e| format!("{}: {e}", path.display()))
}

fn write_mask(path: &Path, mask: &[bool], width: usize, height: usize) -> Result<(), String> {
    let img = image::GrayImage::from_raw(width as u32, height as u32, mask.iter().map(|&m| if m { 255 } else { 0 }).collect()).ok_or("a mask of the wrong size")?;
    let mut bytes = std::io::Cursor::new(Vec::new());
    img.write_to(&mut bytes, image::ImageFormat::Png).map_err(|e| format!("{}: encoding PNG: {e}", path.display()))?;
    write_atomically(path, &bytes.into_inner()).map_err(|e| format!("{}: {e}", path.display()))
}

fn write_float_exr(path: &Path, channels: &[(&str, Vec<f32>)], width: usize, height: usize) -> Result<(), String> {
    let mut img = ExrImage::new(width, height);
    for (name, data) in channels {
        img.push(name, data.clone())?;
    }
    exr::write(path, &img, Compression::Zip)
}

fn xyz(v: &[Vec3]) -> Vec<(&'static str, Vec<f32>)> {
    ["X", "Y", "Z"].iter().enumerate().map(|(c, n)| (*n, v.iter().map(|p| p[c]).collect())).collect()
}

/// The material's base colour texture (textures/base_color.png, its values as stored: linear
/// for uplift's materials, where they are the diffuse colour), or its diffuse colour where it
/// has none.
fn base_color_texture(dir: &Path, surface: &SurfaceTextures) -> Result<SurfaceTextures, String> {
    let path = dir.join("textures").join("base_color.png");
    if path.is_file() {
        let img = image::open(&path).map_err(|e| format!("{}: {e}", path.display()))?.to_rgb32f();
        let (w, h) = (img.width() as usize, img.height() as usize);
        return Ok(colour_texture(w, h, img.into_raw()));
    }
    let rgb = (0..surface.width * surface.height).flat_map(|t| surface.texel(t).diffuse.map(|x| x.clamp(0.0, 1.0))).collect();
    Ok(colour_texture(surface.width, surface.height, rgb))
}

/// Exports the material in `dir` on `mesh` into `out`.
pub fn export_asset(dir: &Path, mesh: &Mesh, env: &Environment, stack: &Arc<Stack>, out: &Path, o: &ExportOptions, progress: bool) -> Result<ExportSummary, String> {
    let folder = MaterialFolder::open(dir)?;
    if !folder.has_fit() {
        return Err(format!("{}: no fitted latents (latent.exr and fit.json; run `uplift fit` first)", dir.display()));
    }
    let meta = folder.read_meta()?;
    let surface = SurfaceTextures::load(dir, stack, true)?;
    if surface.latents == 0 || surface.latents > 6 {
        return Err(format!("{}: {} latent values per texel; the export writes two RGB latent videos (6 values)", folder.latent_path().display(), surface.latents));
    }
    let base = base_color_texture(dir, &surface)?;
    if o.mp4 {
        crate::video::check_ffmpeg()?;
    }
    let cams = orbit(&o.orbit)?;
    let (w, h) = (o.orbit.width, o.orbit.height);
    let bounds = mesh.bounds();
    for (name, _) in MODALITIES {
        std::fs::create_dir_all(out.join(name)).map_err(|e| format!("{}: {e}", out.join(name).display()))?;
    }
    // The records first: they are cheap and the same for every run with these options.
    let cameras = nerfstudio_json(&cams, w, h, |k| format!("shaded/{k:04}.png"), bounds);
    let json = |v: &serde_json::Value| serde_json::to_string_pretty(v).map_err(|e| e.to_string());
    write_atomically(&out.join("cameras.json"), json(&cameras)?.as_bytes()).map_err(|e| format!("{}: {e}", out.join("cameras.json").display()))?;
    let half = |lo: f32, hi: f32| (hi - lo).max(1e-6) * 0.5;
    let (pos_scale, pos_offset) = ([0, 1, 2].map(|c| half(bounds.0[c], bounds.1[c])), [0, 1, 2].map(|c| 0.5 * (bounds.0[c] + bounds.1[c])));
    let meta_json = serde_json::json!({
        "format": 1,
        "asset": meta.name,
        "material": dir.display().to_string(),
        "type": meta.kind,
        "frames": cams.len(), "width": w, "height": h,
        "mesh_transform": {"centre": mesh.centre, "radius": mesh.radius, "note": "world = (source − centre) / radius"},
        "bounding_box": [bounds.0, bounds.1],
        "decode": "physical = offset + scale · (2v − 1), v the stored value in [0, 1] (16-bit PNG: v = stored / 65535)",
        "modalities": {
            "normal_camera": {"file": "png16", "space": "camera, OpenGL axes (x right, y up, z towards the viewer)", "scale": [1.0, 1.0, 1.0], "offset": [0.0, 0.0, 0.0], "float": null},
            "normal_world": {"file": "png16", "space": "world (+Y up)", "scale": [1.0, 1.0, 1.0], "offset": [0.0, 0.0, 0.0], "float": "normal_world/NNNN.exr (X, Y, Z)"},
            "position": {"file": "png16", "space": "world, normalised to the bounding box", "scale": pos_scale, "offset": pos_offset, "float": "position/NNNN.exr (X, Y, Z)"},
            "base_color": {"file": "png16", "encoding": "the material's base colour texture (textures/base_color.png) as stored, v as is (linear for uplift's materials)"},
            "latent0": {"file": "png16", "values": "latent values 0, 1, 2", "scale": o.latent_affine.0[..3], "offset": o.latent_affine.1[..3]},
            "latent1": {"file": "png16", "values": "latent values 3, 4, 5", "scale": o.latent_affine.0[3..], "offset": o.latent_affine.1[3..]},
            "mask": {"file": "png8", "encoding": "255 where the object covers the pixel centre, else 0"},
            "depth": {"file": "exr", "encoding": "distance along the view axis (channel Z), 0 where uncovered"},
            "shaded": {"file": "png8", "encoding": "path traced, Blender's AgX (closed form) to sRGB", "spp": o.spp, "bounces": o.bounces, "exposure": o.exposure, "model": if o.neural.is_some() { "neural" } else { "reference" }},
        },
        "intrinsic_sampling": "one ray through each pixel centre, no filtering",
    });
    let mut meta_json = meta_json;
    if o.mp4 {
        meta_json["videos"] = serde_json::json!({
            "files": crate::video::VIDEO_MODALITIES.map(|m| format!("{m}.mp4")),
            "codec": "H.264 (libx264rgb), lossless (qp 0), RGB 8 bits per channel, no chroma subsampling",
            "fps": crate::video::VIDEO_FPS,
            "values": "8-bit modalities as their PNGs (the mask replicated into R, G, B); 16-bit ones rounded, v8 = round(v16 / 257): v = v8 / 255 decodes through the same affines",
        });
    }
    write_atomically(&out.join("meta.json"), json(&meta_json)?.as_bytes()).map_err(|e| format!("{}: {e}", out.join("meta.json").display()))?;
    let kind = (meta.kind as usize).min(5);
    let mut words: Vec<&str> = TYPE_KEYWORDS[kind].to_vec();
    if meta.glint.is_some() {
        words.push("glinty sparkles");
    }
    write_atomically(&out.join("prompt.txt"), format!("{}\n", words.join(", ")).as_bytes()).map_err(|e| format!("{}: {e}", out.join("prompt.txt").display()))?;

    let model = match &o.neural {
        Some(weights) => Model::Neural(uplift_neural::weights::load_model(weights, stack)?.decoder),
        None => Model::Reference,
    };
    let shading = Shading::new(CpuEngine::with_threads(o.threads)?, stack, model)?;
    let bar = if progress { ProgressBar::new(cams.len() as u64) } else { ProgressBar::hidden() };
    bar.set_style(ProgressStyle::with_template("export {msg} [{bar:30}] {pos}/{len} frames {elapsed}").map_err(|e| e.to_string())?.progress_chars("=> "));
    bar.set_message(meta.name.clone());
    let mut s = ExportSummary { frames: cams.len(), skipped: 0, seconds_intrinsic: 0.0, seconds_shaded: 0.0 };
    for (k, cam) in cams.iter().enumerate() {
        if frame_path(out, "shaded", k, "png").is_file() {
            s.skipped += 1;
            bar.inc(1);
            continue;
        }
        let start = std::time::Instant::now();
        let f = intrinsic_frame(mesh, &surface, &base, cam, w, h);
        write_intrinsics(out, k, &f, bounds, &o.latent_affine)?;
        s.seconds_intrinsic += start.elapsed().as_secs_f64();
        let start = std::time::Instant::now();
        let ro = RenderOptions { width: w, height: h, spp: o.spp, bounces: o.bounces, seed: o.orbit.seed ^ uplift_base::rng::mix64(k as u64), camera: Some(*cam), ..Default::default() };
        let img = render(mesh, env, &surface, &shading, &ro, None)?;
        write_png(&frame_path(out, "shaded", k, "png"), &to_display_blender(&img.radiance, o.exposure), w, h)?;
        s.seconds_shaded += start.elapsed().as_secs_f64();
        bar.inc(1);
    }
    bar.finish_and_clear();
    if o.mp4 {
        for name in crate::video::VIDEO_MODALITIES {
            if !crate::video::video_path(out, name).is_file() {
                crate::video::write_modality_video(out, name, cams.len())?;
            }
        }
    }
    Ok(s)
}

/// Writes frame `k`'s intrinsic buffers.
fn write_intrinsics(out: &Path, k: usize, f: &IntrinsicFrame, bounds: (Vec3, Vec3), affine: &LatentAffine) -> Result<(), String> {
    let (w, h) = (f.width, f.height);
    let unit = |n: &Vec3| n.map(|x| 0.5 * x + 0.5);
    write_png16(&frame_path(out, "normal_camera", k, "png"), &f.normal_camera.iter().zip(&f.mask).map(|(n, &m)| if m { unit(n) } else { [0.0; 3] }).collect::<Vec<_>>(), w, h)?;
    write_png16(&frame_path(out, "normal_world", k, "png"), &f.normal_world.iter().zip(&f.mask).map(|(n, &m)| if m { unit(n) } else { [0.0; 3] }).collect::<Vec<_>>(), w, h)?;
    let pos: Vec<[f32; 3]> = f.position.iter().zip(&f.mask).map(|(p, &m)| if m { [0, 1, 2].map(|c| (p[c] - bounds.0[c]) / (bounds.1[c] - bounds.0[c]).max(1e-6)) } else { [0.0; 3] }).collect();
    write_png16(&frame_path(out, "position", k, "png"), &pos, w, h)?;
    write_png16(&frame_path(out, "base_color", k, "png"), &f.base_color, w, h)?;
    for t in 0..2 {
        let stored = |c: usize, x: f32| if affine == &UNIT_LATENT_AFFINE { x } else { 0.5 + (x - affine.1[c]) / (2.0 * affine.0[c]) };
        let v: Vec<[f32; 3]> = (0..w * h).map(|p| [0, 1, 2].map(|c| if 3 * t + c < f.latents { stored(3 * t + c, f.latent[p * f.latents + 3 * t + c]) } else { 0.0 })).collect();
        write_png16(&frame_path(out, &format!("latent{t}"), k, "png"), &v, w, h)?;
    }
    write_mask(&frame_path(out, "mask", k, "png"), &f.mask, w, h)?;
    write_float_exr(&frame_path(out, "depth", k, "exr"), &[("Z", f.depth.clone())], w, h)?;
    write_float_exr(&frame_path(out, "position", k, "exr"), &xyz(&f.position), w, h)?;
    write_float_exr(&frame_path(out, "normal_world", k, "exr"), &xyz(&f.normal_world), w, h)?;
    Ok(())
}
