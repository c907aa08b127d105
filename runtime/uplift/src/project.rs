//! `uplift project`: generated views back into texture space (paper §5.2, Fig. 11) — the inverse
//! of `uplift export`. Frames of latent videos (`latent0/`, `latent1/`) and base colour
//! (`base_color/`), as `export` writes them or as a generator returns them, with `cameras.json`,
//! become an ordinary fitted material folder.
//!
//! Per texel of the mesh's texture space (enhance's UV rasterisation: the surface point and
//! normal each texel centre sees), per frame: project the point through the camera; keep the
//! view when the point is the first hit of the camera's ray to it (a depth test against the
//! mesh itself), faces it at more than a grazing angle (cos > [`MIN_COS`]: silhouettes), and its
//! pixel's 3×3 neighbourhood is on the object with no depth edge (a jump over [`DEPTH_EDGE`] of
//! the depth); sample the frames bilinearly, weight by cos^[`COS_POWER`] of the view angle and
//! average the views. Then, within each UV chart (the rasterised texels), the projected region is
//! eroded by [`ERODE`] texels (its border is where views disagree) and every texel without a
//! value is filled by inpainting (repeated averaging of its filled 8-neighbours and, at a chart's
//! border, of its partners across the UV seam, `seams.rs`: convex combinations of projected
//! latents, so the fill creates no energy the projected texels lack)
//! or, with `fill`, given the decoder's diffuse latent (the base colour is inpainted either way),
//! and a gutter of [`GUTTER`] texels is dilated outside the charts (bilinear lookups at chart
//! edges read no background).
//!
//! The folder: latent.exr (and latent0/1.png), textures/base_color.png, params.exr with the
//! stack's nodedef defaults (a generated material has no rule parameters; its reference render
//! is the default stack, and it renders with the sampling decoder, `render --neural
//! --sampler`) and the diffuse colour from the projected base colour, fit.json
//! naming the projection, and `coverage.png` (per texel: projected, filled, gutter) with
//! `projection.json` (counts and settings).

use rayon::prelude::*;
use std::path::Path;
use uplift_base::exr::ExrImage;
use uplift_enhance::gltf_input::{rasterize_uv, GltfAsset};
use uplift_engines::stack::Stack;
use uplift_material::{LatentImage, MaterialFolder};
use uplift_render::mesh::Mesh;
use uplift_render::orbit::cameras_from_json;
use uplift_render::scene::{dot, Scene};

/// Views more grazing than this cosine are dropped (silhouettes).
pub const MIN_COS: f32 = 0.2;
/// The view weight is cos^COS_POWER of the angle to the normal.
pub const COS_POWER: i32 = 4;
/// A depth jump over this fraction of the depth in a pixel's 3×3 neighbourhood is an edge.
pub const DEPTH_EDGE: f32 = 0.03;
/// Texels the projected region is eroded by inside each chart.
pub const ERODE: usize = 4;
/// Texels of gutter dilated outside the charts.
pub const GUTTER: usize = 8;

/// The projection's settings.
#[derive(Clone, Debug)]
pub struct ProjectOptions {
    pub width: usize,
    pub height: usize,
    /// The glTF material whose texture space is filled.
    pub material: usize,
    /// The latent given to chart texels no frame saw (the decoder's diffuse latent,
    /// uplift_neural::diffuse_latent); None: they are inpainted like the base colour.
    pub fill: Option<Vec<f32>>,
}

/// What a projection did.
#[derive(Clone, Debug)]
pub struct ProjectSummary {
    pub texels: usize,
    pub in_charts: usize,
    pub projected: usize,
    pub filled: usize,
    /// Chart-border texels linked across a UV seam (seams.rs).
    pub seam_texels: usize,
    pub seconds: f64,
}

/// A frame of one modality: RGB values v in [0, 1] (16-bit or 8-bit PNG), mapped through
/// the modality's affine from meta.json when there is one.
struct Frame {
    w: usize,
    h: usize,
    rgb: Vec<[f32; 3]>,
}

impl Frame {
    fn read(path: &Path, affine: Option<([f32; 3], [f32; 3])>) -> Result<Frame, String> {
        let img = image::open(path).map_err(|e| format!("{}: {e}", path.display()))?.to_rgb32f();
        let (w, h) = (img.width() as usize, img.height() as usize);
        let rgb = img
            .pixels()
            .map(|p| {
                let v = p.0;
                match affine {
                    Some((s, o)) => [0, 1, 2].map(|c| o[c] + s[c] * (2.0 * v[c] - 1.0)),
                    None => v,
                }
            })
            .collect();
        Ok(Frame { w, h, rgb })
    }

    /// Bilinear at image point (x, y) in pixels (pixel centres at half-integers).
    fn sample(&self, x: f32, y: f32) -> [f32; 3] {
        let (fx, fy) = (x - 0.5, y - 0.5);
        let (x0, y0) = (fx.floor(), fy.floor());
        let (ax, ay) = (fx - x0, fy - y0);
        let at = |dx: f32, dy: f32| {
            let xi = ((x0 + dx) as i64).clamp(0, self.w as i64 - 1) as usize;
            let yi = ((y0 + dy) as i64).clamp(0, self.h as i64 - 1) as usize;
            self.rgb[yi * self.w + xi]
        };
        let (a, b, c, d) = (at(0.0, 0.0), at(1.0, 0.0), at(0.0, 1.0), at(1.0, 1.0));
        [0, 1, 2].map(|k| (1.0 - ay) * ((1.0 - ax) * a[k] + ax * b[k]) + ay * ((1.0 - ax) * c[k] + ax * d[k]))
    }
}

const NB8: [(i64, i64); 8] = [(-1, 0), (1, 0), (0, -1), (0, 1), (-1, -1), (1, -1), (-1, 1), (1, 1)];

/// Projects the generated frames in `generated` onto `asset`'s texture space into `out`.
pub fn project(generated: &Path, asset: &GltfAsset, stack: &Stack, out: &Path, o: &ProjectOptions) -> Result<ProjectSummary, String> {
    let start = std::time::Instant::now();
    let cam_path = generated.join("cameras.json");
    let text = std::fs::read_to_string(&cam_path).map_err(|e| format!("{}: {e}", cam_path.display()))?;
    let json: serde_json::Value = serde_json::from_str(&text).map_err(|e| format!("{}: {e}", cam_path.display()))?;
    let (cams, fw, fh, _) = cameras_from_json(&json).map_err(|e| format!("{}: {e}", cam_path.display()))?;
    let meta: Option<serde_json::Value> = std::fs::read_to_string(generated.join("meta.json")).ok().and_then(|t| serde_json::from_str(&t).ok());
    let affine = |m: &str| -> Option<([f32; 3], [f32; 3])> {
        let mm = meta.as_ref()?;
        let v = |k: &str| -> Option<[f32; 3]> { Some([0, 1, 2].map(|c| mm["modalities"][m][k][c].as_f64().unwrap_or(f64::NAN) as f32)).filter(|a| a.iter().all(|x| x.is_finite())) };
        Some((v("scale")?, v("offset")?))
    };
    let mesh = Mesh::new(asset.world_triangles())?;
    let bake = rasterize_uv(asset, o.material, o.width, o.height)?;
    let (w, h) = (o.width, o.height);
    let n = w * h;
    let to_mesh = |p: [f32; 3]| [0, 1, 2].map(|c| (p[c] - mesh.centre[c]) / mesh.radius);

    // Accumulate weighted views: 6 latent values and the base colour per texel.
    let mut acc = vec![[0.0f32; 9]; n];
    let mut weight = vec![0.0f32; n];
    for (k, cam) in cams.iter().enumerate() {
        let read = |m: &str| Frame::read(&crate::export::frame_path(generated, m, k, "png"), affine(m));
        let (l0, l1, base) = (read("latent0")?, read("latent1")?, Frame::read(&crate::export::frame_path(generated, "base_color", k, "png"), None)?);
        for f in [&l0, &l1, &base] {
            if (f.w, f.h) != (fw, fh) {
                return Err(format!("{}: frame {k} is {}×{}, cameras.json says {fw}×{fh}", generated.display(), f.w, f.h));
            }
        }
        // The frame's own depth at pixel centres (our mesh, this camera), for the edge test.
        let depth: Vec<Option<f32>> = (0..fw * fh)
            .into_par_iter()
            .map(|p| {
                let (ro, rd) = cam.ray((p % fw) as f32 + 0.5, (p / fw) as f32 + 0.5, fw, fh);
                mesh.intersect(ro, rd).map(|hit| hit.t * dot(rd, cam.forward))
            })
            .collect();
        acc.par_iter_mut().zip(weight.par_iter_mut()).enumerate().for_each(|(t, (acc, weight))| {
            if !bake.covered[t] {
                return;
            }
            let p = to_mesh(bake.position[t]);
            let nrm = bake.normal[t];
            let Some((x, y, z)) = cam.project(p, fw, fh) else { return };
            if !(x >= 1.0 && y >= 1.0 && x <= fw as f32 - 1.0 && y <= fh as f32 - 1.0) {
                return;
            }
            let to_cam = [0, 1, 2].map(|c| cam.position[c] - p[c]);
            let dist = dot(to_cam, to_cam).sqrt();
            let cos = dot(nrm, to_cam) / dist;
            if cos <= MIN_COS {
                return;
            }
            // Depth test: the camera's ray towards the point hits it first.
            let dir = to_cam.map(|c| -c / dist);
            match mesh.intersect(cam.position, dir) {
                Some(hit) if (hit.t - dist).abs() <= 2e-3 * dist => {}
                _ => return,
            }
            // Depth edges and the object's border around the pixel.
            let (px, py) = (x as i64, y as i64);
            let mut edge = false;
            for (dx, dy) in NB8.iter().chain(&[(0, 0)]) {
                let (qx, qy) = (px + dx, py + dy);
                let d = if qx < 0 || qy < 0 || qx >= fw as i64 || qy >= fh as i64 { None } else { depth[qy as usize * fw + qx as usize] };
                match d {
                    Some(d) if (d - z).abs() <= DEPTH_EDGE * z => {}
                    _ => edge = true,
                }
            }
            if edge {
                return;
            }
            let wgt = cos.powi(COS_POWER);
            let (a, b, c) = (l0.sample(x, y), l1.sample(x, y), base.sample(x, y));
            let v = [a[0], a[1], a[2], b[0], b[1], b[2], c[0], c[1], c[2]];
            for i in 0..9 {
                acc[i] += wgt * v[i];
            }
            *weight += wgt;
        });
    }
    let mut value: Vec<Option<[f32; 9]>> = (0..n).map(|t| (weight[t] > 0.0).then(|| acc[t].map(|x| x / weight[t]))).collect();
    // Erode the projected region inside the charts.
    let inside = |x: i64, y: i64| x >= 0 && y >= 0 && x < w as i64 && y < h as i64;
    for _ in 0..ERODE {
        let before: Vec<bool> = value.iter().map(|v| v.is_some()).collect();
        for t in 0..n {
            if before[t] {
                let (x, y) = ((t % w) as i64, (t / w) as i64);
                if NB8.iter().any(|(dx, dy)| inside(x + dx, y + dy) && bake.covered[((y + dy) as usize) * w + (x + dx) as usize] && !before[((y + dy) as usize) * w + (x + dx) as usize]) {
                    value[t] = None;
                }
            }
        }
    }
    let projected = value.iter().filter(|v| v.is_some()).count();
    if projected == 0 {
        return Err(format!("{}: no texel of the mesh's texture space is seen by any frame", generated.display()));
    }
    // Inpaint the rest of each chart, then dilate a gutter outside the charts.
    let mut state: Vec<u8> = (0..n).map(|t| if value[t].is_some() { 1 } else { 0 }).collect(); // 1 projected, 2 filled, 3 gutter
    // Inpainting crosses seams: the texels on a seam's two sides are neighbours (seams.rs).
    let partners = crate::seams::seam_partners(&bake.covered, &bake.position, w, h);
    let seam_links = partners.iter().filter(|p| !p.is_empty()).count();
    let grow = |value: &mut Vec<Option<[f32; 9]>>, state: &mut Vec<u8>, allowed: &dyn Fn(usize) -> bool, mark: u8, passes: usize, seams: bool| {
        for _ in 0..passes {
            let snapshot = value.clone();
            let mut changed = false;
            for t in 0..n {
                if snapshot[t].is_some() || !allowed(t) {
                    continue;
                }
                let (x, y) = ((t % w) as i64, (t / w) as i64);
                let (mut s, mut c) = ([0.0f32; 9], 0.0f32);
                let grid = NB8.iter().filter(|(dx, dy)| inside(x + dx, y + dy)).map(|(dx, dy)| ((y + dy) as usize) * w + (x + dx) as usize);
                let across: &[u32] = if seams { &partners[t] } else { &[] };
                for u in grid.chain(across.iter().map(|&u| u as usize)) {
                    if let Some(v) = snapshot[u] {
                        for i in 0..9 {
                            s[i] += v[i];
                        }
                        c += 1.0;
                    }
                }
                if c > 0.0 {
                    value[t] = Some(s.map(|x| x / c));
                    state[t] = mark;
                    changed = true;
                }
            }
            if !changed {
                break;
            }
        }
    };
    grow(&mut value, &mut state, &|t| bake.covered[t], 2, w + h, true);
    let filled = state.iter().filter(|&&s| s == 2).count();
    grow(&mut value, &mut state, &|t| !bake.covered[t], 3, GUTTER, false);
    // Texels still empty (another chart's gutter never reached them): the mean projected value.
    let mean = {
        let mut s = [0.0f32; 9];
        for v in value.iter().zip(&state).filter(|(_, s)| **s == 1).filter_map(|(v, _)| v.as_ref()) {
            for i in 0..9 {
                s[i] += v[i] / projected as f32;
            }
        }
        s
    };
    let mut values: Vec<[f32; 9]> = value.into_iter().map(|v| v.unwrap_or(mean)).collect();
    if let Some(z) = &o.fill {
        if z.len() != 6 {
            return Err(format!("the fill latent has {} values; the frames carry 6", z.len()));
        }
        for (v, s) in values.iter_mut().zip(&state) {
            if *s != 1 {
                v[..6].copy_from_slice(z);
            }
        }
    }

    // The material folder.
    std::fs::create_dir_all(out.join("textures")).map_err(|e| format!("{}: {e}", out.display()))?;
    let folder = MaterialFolder::create(out);
    let mut params = ExrImage::new(w, h);
    for (p, default) in stack.parameters().iter().zip(stack.defaults()) {
        params.push(&p.channel, vec![default; n])?;
    }
    // The base colour frames hold the texture's values as the export stores them, which are
    // the diffuse colour's (uplift's textures are linear).
    for (c, name) in uplift_material::folder::DIFFUSE_CHANNELS.iter().enumerate() {
        params.push(name, values.iter().map(|v| v[6 + c].clamp(0.0, 1.0)).collect())?;
    }
    params.attributes.push((uplift_material::folder::STACK_ATTRIBUTE.into(), stack.signature()));
    folder.write_params_image(&params)?;
    let latent = LatentImage { width: w, height: h, channels: 6, latents: values.iter().flat_map(|v| v[..6].iter().map(|x| x.clamp(0.0, 1.0))).collect() };
    folder.write_latents(&latent)?;
    // fit.json: what `has_fit` and the commands reading a fit expect; no Eq. 3 was minimised.
    let none = uplift_material::LossRecord::default();
    folder.write_fit(&uplift_material::FitRecord {
        format: 0,
        decoder: format!("projected from {}", generated.display()),
        texels: n,
        groups: 0,
        steps: 0,
        directions: 0,
        levels: 0,
        seconds: start.elapsed().as_secs_f64(),
        eq3_encoder_only: none,
        eq3_fitted: none,
        eq3_fitted_before_energy_bound: none,
        fitting_loss_first_step: none,
        fitting_loss_last_step: none,
        energy_bound: None,
    })?;
    let to8 = |x: f32| (x.clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
    uplift_render::image_files::write_png(&out.join("textures").join("base_color.png"), &values.iter().flat_map(|v| [to8(v[6]), to8(v[7]), to8(v[8])]).collect::<Vec<_>>(), w, h)?;
    let colours = [[0u8, 0, 0], [40, 200, 60], [230, 160, 30], [60, 90, 220]];
    uplift_render::image_files::write_png(&out.join("coverage.png"), &state.iter().flat_map(|&s| colours[s as usize]).collect::<Vec<_>>(), w, h)?;
    let summary = ProjectSummary { texels: n, in_charts: bake.covered.iter().filter(|&&c| c).count(), projected, filled, seam_texels: seam_links, seconds: start.elapsed().as_secs_f64() };
    let record = serde_json::json!({
        "format": 1,
        "generated": generated.display().to_string(),
        "mesh": asset.path.display().to_string(),
        "texels": summary.texels, "in_charts": summary.in_charts, "projected": summary.projected, "filled": summary.filled, "seam_texels": summary.seam_texels,
        "frames": cams.len(),
        "settings": {"min_cos": MIN_COS, "cos_power": COS_POWER, "depth_edge": DEPTH_EDGE, "erode": ERODE, "gutter": GUTTER},
        "coverage_png": "green: projected, orange: inpainted inside a chart, blue: gutter, black: empty",
    });
    uplift_base::atomic_write::write_atomically(&out.join("projection.json"), serde_json::to_string_pretty(&record).map_err(|e| e.to_string())?.as_bytes()).map_err(|e| format!("{}: {e}", out.display()))?;
    Ok(summary)
}
