//! Reference vs neural evaluation of fitted materials (paper §4.3, Table 1): each material is
//! rendered on the preview ball by the reference kernels and by the neural decoder with the
//! same seed, both through AgX; LDR-FLIP is measured over the ball's pixels and over the whole
//! image. Per Type, the best / median / worst FLIP over the materials form the paper's table.

use crate::environment::Environment;
use crate::image_files::write_png;
use crate::integrator::{render, RenderOptions};
use crate::metrics::{default_pixels_per_degree, flip_ldr, psnr};
use crate::scene::Sphere;
use crate::shading::Shading;
use crate::surface::SurfaceTextures;
use crate::tonemap::to_display;
use std::path::Path;

/// Paper Table 1: (Type, best, medium, worst) mean FLIP over 50 materials per Type.
pub const PAPER_TABLE1: [(usize, f64, f64, f64); 6] = [
    (0, 0.0487, 0.0920, 0.1871),
    (1, 0.0312, 0.0727, 0.1670),
    (2, 0.0649, 0.0858, 0.1192),
    (3, 0.0554, 0.0877, 0.1664),
    (4, 0.0276, 0.0643, 0.1705),
    (5, 0.0454, 0.0807, 0.1754),
];

/// One material's evaluation.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct MaterialEval {
    pub name: String,
    pub kind: usize,
    /// Mean FLIP over the ball's pixels, and over the whole image.
    pub flip_object: f64,
    pub flip_full: f64,
    /// PSNR (dB) over the ball's pixels.
    pub psnr_object: f64,
    pub seconds_reference: f64,
    pub seconds_neural: f64,
}

/// The display images of one evaluation.
pub struct EvalImages {
    pub reference: Vec<u8>,
    pub neural: Vec<u8>,
    pub flip_magma: Vec<u8>,
}

/// A material's Type from its meta.json.
pub fn material_type(dir: &Path) -> Result<usize, String> {
    Ok(uplift_material::MaterialFolder::open(dir)?.read_meta()?.kind as usize)
}

/// Renders one fitted material both ways and compares.
pub fn evaluate_material(dir: &Path, reference: &Shading, neural: &Shading, env: &Environment, o: &RenderOptions, exposure: f32) -> Result<(MaterialEval, EvalImages), String> {
    let kind = material_type(dir)?;
    let surface = SurfaceTextures::load(dir, reference.stack(), true)?;
    let t0 = std::time::Instant::now();
    let r = render(&Sphere::preview(), env, &surface, reference, o, None)?;
    let t1 = std::time::Instant::now();
    let n = render(&Sphere::preview(), env, &surface, neural, o, None)?;
    let t2 = std::time::Instant::now();
    let (ri, ni) = (to_display(&r.radiance, exposure), to_display(&n.radiance, exposure));
    let map = flip_ldr(&ri, &ni, o.width, o.height, default_pixels_per_degree())?;
    let mask = r.object_mask();
    let name = dir.file_name().map(|s| s.to_string_lossy().to_string()).unwrap_or_default();
    let eval = MaterialEval {
        name,
        kind,
        flip_object: map.mean_over(&mask),
        flip_full: map.mean(),
        psnr_object: psnr(&ri, &ni, Some(&mask)),
        seconds_reference: (t1 - t0).as_secs_f64(),
        seconds_neural: (t2 - t1).as_secs_f64(),
    };
    Ok((eval, EvalImages { reference: ri, neural: ni, flip_magma: map.to_magma() }))
}

/// Writes an evaluation's images as `<stem>_reference.png`, `_neural.png`, `_flip.png`.
pub fn write_eval_images(dir: &Path, stem: &str, images: &EvalImages, size: (usize, usize)) -> Result<(), String> {
    write_png(&dir.join(format!("{stem}_reference.png")), &images.reference, size.0, size.1)?;
    write_png(&dir.join(format!("{stem}_neural.png")), &images.neural, size.0, size.1)?;
    write_png(&dir.join(format!("{stem}_flip.png")), &images.flip_magma, size.0, size.1)
}

/// One Type's row: materials, best / median / worst FLIP (object pixels and full image).
#[derive(Clone, Debug)]
pub struct TypeRow {
    pub kind: usize,
    pub count: usize,
    pub object: (f64, f64, f64),
    pub full: (f64, f64, f64),
}

fn best_median_worst(mut v: Vec<f64>) -> (f64, f64, f64) {
    v.sort_by(|a, b| a.total_cmp(b));
    let n = v.len();
    let median = if n % 2 == 1 { v[n / 2] } else { 0.5 * (v[n / 2 - 1] + v[n / 2]) };
    (v[0], median, v[n - 1])
}

/// Per-Type rows over the evaluations (Types without materials are left out).
pub fn per_type(evals: &[MaterialEval]) -> Vec<TypeRow> {
    (0..6)
        .filter_map(|k| {
            let of: Vec<&MaterialEval> = evals.iter().filter(|e| e.kind == k && e.flip_object.is_finite()).collect();
            if of.is_empty() {
                return None;
            }
            Some(TypeRow {
                kind: k,
                count: of.len(),
                object: best_median_worst(of.iter().map(|e| e.flip_object).collect()),
                full: best_median_worst(of.iter().map(|e| e.flip_full).collect()),
            })
        })
        .collect()
}

/// The table in the paper's format, with the paper's own medians beside ours.
pub fn format_table(rows: &[TypeRow]) -> String {
    let mut s = String::from("| Type | materials | best | median | worst | full image: best / median / worst | paper median |\n|---|---|---|---|---|---|---|\n");
    for r in rows {
        let paper = PAPER_TABLE1.iter().find(|p| p.0 == r.kind).map(|p| p.2).unwrap_or(f64::NAN);
        s += &format!(
            "| {} | {} | {:.4} | {:.4} | {:.4} | {:.4} / {:.4} / {:.4} | {:.4} |\n",
            r.kind, r.count, r.object.0, r.object.1, r.object.2, r.full.0, r.full.1, r.full.2, paper
        );
    }
    s
}
