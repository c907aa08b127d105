//! The demo report's data-for-generative-models section: one fitted material exported as an
//! orbit on a UV sphere (`uplift export`; a strip of frames per modality) and its own latent and
//! base-colour frames projected back into texture space (`uplift project`), rendered beside the
//! original with the sampling decoder, with the base colour's PSNR on the projected texels and
//! the FLIP between the two renders.

use std::path::Path;
use std::sync::Arc;
use uplift_engines::stack::Stack;
use uplift_render::environment::Environment;
use uplift_render::image_files::write_png;
use uplift_render::integrator::{render, RenderOptions};
use uplift_render::metrics::{default_pixels_per_degree, flip_ldr};
use uplift_render::orbit::OrbitOptions;
use uplift_render::shading::Shading;
use uplift_render::surface::SurfaceTextures;
use uplift_render::tonemap::to_display;

/// The modalities shown, in the strip's order.
pub const SHOWN: [&str; 8] = ["shaded", "normal_camera", "normal_world", "position", "base_color", "latent0", "latent1", "mask"];

/// What the section shows.
#[derive(Clone, Debug)]
pub struct OrbitSection {
    pub material: String,
    pub frames: usize,
    /// Per modality: its name and the strip image under img/.
    pub strips: Vec<(String, String)>,
    pub original_image: String,
    pub projected_image: String,
    pub coverage_image: String,
    pub projected_texels: usize,
    pub chart_texels: usize,
    pub base_color_psnr: f64,
    pub flip: f64,
}

/// Exports `material` (a fitted folder) into `work`, projects it back, writes the images into
/// `img` and measures the round trip; `shading` is the neural model with its sampling decoder.
#[allow(clippy::too_many_arguments)]
pub fn orbit_section(material: &Path, name: &str, work: &Path, img: &Path, stack: &Arc<Stack>, shading: &Shading, size: usize, texture: usize, spp: usize, seed: u64, threads: usize) -> Result<OrbitSection, String> {
    let sphere = uplift_enhance::uv_sphere::write_uv_sphere_gltf(&work.join("mesh"), 64, 32)?;
    let asset = uplift_enhance::gltf_input::load(&sphere)?;
    let mesh = uplift_render::mesh::Mesh::new(asset.world_triangles())?;
    let env = Environment::studio();
    let frames = 8;
    let exported = work.join("export").join(name);
    let o = crate::export::ExportOptions { orbit: OrbitOptions { frames, width: size, height: size, seed, ..Default::default() }, spp, bounces: 3, exposure: 1.0, threads, neural: None, latent_affine: crate::export::UNIT_LATENT_AFFINE, mp4: false };
    crate::export::export_asset(material, &mesh, &env, stack, &exported, &o, false)?;
    let mut strips = Vec::new();
    for m in SHOWN {
        let mut strip = vec![0u8; frames * size * size * 3];
        for k in 0..frames {
            let frame = image::open(crate::export::frame_path(&exported, m, k, "png")).map_err(|e| format!("{m} frame {k}: {e}"))?.to_rgb8();
            for (p, px) in frame.pixels().enumerate() {
                let (x, y) = (p % size, p / size);
                let at = (y * frames * size + k * size + x) * 3;
                strip[at..at + 3].copy_from_slice(&px.0);
            }
        }
        let file = format!("orbit_{m}.png");
        write_png(&img.join(&file), &strip, frames * size, size)?;
        strips.push((m.to_string(), file));
    }
    let projected = work.join("projected").join(name);
    let s = crate::project::project(&exported, &asset, stack, &projected, &crate::project::ProjectOptions { width: texture, height: texture, material: 0, fill: None })?;
    // Base colour on the projected texels.
    let coverage = image::open(projected.join("coverage.png")).map_err(|e| e.to_string())?.to_rgb8().into_raw();
    let a = image::open(material.join("textures/base_color.png")).map_err(|e| e.to_string())?.to_rgb8();
    let b = image::open(projected.join("textures/base_color.png")).map_err(|e| e.to_string())?.to_rgb8();
    let seen: Vec<bool> = coverage.chunks(3).map(|c| c == [40, 200, 60]).collect();
    let psnr = if a.dimensions() == b.dimensions() { uplift_render::metrics::psnr(&a.into_raw(), &b.into_raw(), Some(&seen)) } else { f64::NAN };
    let cam = uplift_render::scene::Camera::look_at([1.8, 1.4, 2.2], [0.0; 3], [0.0, 1.0, 0.0], 40.0);
    let ro = RenderOptions { width: size, height: size, spp: spp.max(16), bounces: 1, seed, camera: Some(cam), ..Default::default() };
    let x = render(&mesh, &env, &SurfaceTextures::load(material, stack, true)?, shading, &ro, None)?;
    let y = render(&mesh, &env, &SurfaceTextures::load(&projected, stack, true)?, shading, &ro, None)?;
    let (dx, dy) = (to_display(&x.radiance, 1.0), to_display(&y.radiance, 1.0));
    let map = flip_ldr(&dx, &dy, size, size, default_pixels_per_degree())?;
    let flip = map.mean_over(&x.object_mask());
    let (oi, pi, ci) = (format!("orbit_{name}_original.png"), format!("orbit_{name}_projected.png"), format!("orbit_{name}_coverage.png"));
    write_png(&img.join(&oi), &dx, size, size)?;
    write_png(&img.join(&pi), &dy, size, size)?;
    std::fs::copy(projected.join("coverage.png"), img.join(&ci)).map_err(|e| format!("{}: {e}", img.join(&ci).display()))?;
    Ok(OrbitSection { material: name.to_string(), frames, strips, original_image: oi, projected_image: pi, coverage_image: ci, projected_texels: s.projected, chart_texels: s.in_charts, base_color_psnr: psnr, flip })
}
