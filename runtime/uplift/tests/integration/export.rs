//! `uplift export` (uplift::export) against independent references:
//! - Blender's AgX in closed form (render/agx_blender.rs): mid grey gives Blender's 0.4614
//!   (118 of 255), black 0, greys rise monotonically, the sigmoid matches the values Troy
//!   Sobotka's reference script (AgX_LUT_Gen's sigmoid.py) prints, and the whole chain matches
//!   an independent f64 implementation written here within 1e-6;
//! - the camera check: every exported world position (position/NNNN.exr) projects through
//!   cameras.json (nerfstudio intrinsics and camera-to-world, OpenGL axes) onto its own pixel
//!   centre within 0.5 px; the 16-bit PNG encodings of positions and normals decode through
//!   meta.json's affine to the float buffers within one quantisation step; camera-space normals
//!   are the world normals rotated by cameras.json's matrix;
//! - an interrupted export resumes (finished frames are skipped) and a second export writes the
//!   same bytes.

use std::path::Path;
use uplift_engines::stack::Stack;
use uplift_render::agx_blender::{agx_blender, sigmoid};
use uplift_render::orbit::OrbitOptions;

/// The same closed form, written independently: Rec. 709 → Rec. 2020 from the primaries'
/// published matrix, the inset and outset as Blender's generator prints them, the sigmoid as
/// Jed Smith's tunable sigmoid in its original (limit, transition) form.
fn agx_reference(rgb: [f64; 3]) -> [f64; 3] {
    let to2020 = [[0.6274039, 0.32928304, 0.04331307], [0.06909729, 0.9195404, 0.01136232], [0.01639144, 0.08801331, 0.89559525]];
    let inset = [[0.856627153315983, 0.0951212405381588, 0.0482516061458583], [0.137318972929847, 0.761241990602591, 0.101439036467562], [0.11189821299995, 0.0767994186031903, 0.811302368396859]];
    let outset = [[1.1271005818144368, -0.11060664309660323, -0.016493938717834573], [-0.1413297634984383, 1.157823702216272, -0.016493938717834257], [-0.14132976349843826, -0.11060664309660294, 1.2519364065950405]];
    let mul = |m: &[[f64; 3]; 3], v: [f64; 3]| [0, 1, 2].map(|r| m[r][0] * v[0] + m[r][1] * v[1] + m[r][2] * v[2]);
    let inv = |m: [[f64; 3]; 3]| {
        let det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
        let c = |r: usize, k: usize| {
            let (r1, r2, k1, k2) = ((r + 1) % 3, (r + 2) % 3, (k + 1) % 3, (k + 2) % 3);
            m[r1][k1] * m[r2][k2] - m[r1][k2] * m[r2][k1]
        };
        [0, 1, 2].map(|i| [0, 1, 2].map(|j| c(j, i) / det))
    };
    let curve = |x: f64| {
        let (xp, yp, slope, p) = (10.0 / 16.5, 0.18f64.powf(1.0 / 2.4), 2.4, 1.5);
        let (lx, ly) = if x < xp { (0.0, 0.0) } else { (1.0, 1.0) };
        let a = (slope * (lx - xp)).abs().powf(-p);
        let b = (slope * (lx - xp) / (ly - yp)).powf(p) - 1.0;
        let scale = (a * b).powf(-1.0 / p) * if x < xp { -1.0 } else { 1.0 };
        let t = slope * (x - xp) / scale;
        scale * t / (1.0 + t.powf(p)).powf(1.0 / p) + yp
    };
    let v = mul(&inset, mul(&to2020, rgb.map(|x| x.max(0.0))));
    let v = v.map(|x| curve(((x.max(1e-10) / 0.18).log2() + 10.0) / 16.5).clamp(0.0, 1.0).max(0.0).powf(2.4));
    let v = mul(&inv(to2020), mul(&outset, v));
    v.map(|x| {
        let x = x.clamp(0.0, 1.0);
        if x <= 0.0031308 { 12.92 * x } else { 1.055 * x.powf(1.0 / 2.4) - 0.055 }
    })
}

#[test]
fn agx_matches_blender_and_an_independent_closed_form() {
    // Mid grey: 0.18 → 0.18 through the curve, 0.4614 sRGB-encoded, 118 of 255 as in Blender.
    let grey = agx_blender([0.18; 3]);
    assert!(grey.iter().all(|&g| (g - 0.461_356_1).abs() < 1e-5), "mid grey → {grey:?}");
    assert_eq!((grey[0] * 255.0 + 0.5) as u8, 118);
    assert!(agx_blender([0.0; 3]).iter().all(|&x| x.abs() < 1e-6), "black → {:?}", agx_blender([0.0; 3]));
    let mut last = -1.0f32;
    for k in 0..=400 {
        let g = 2f32.powf(-14.0 + k as f32 * 0.05);
        let v = agx_blender([g; 3])[0];
        assert!(v >= last, "not monotone at {g}: {v} < {last}");
        last = v;
    }
    assert!(last > 0.99, "the brightest grey → {last}");
    // The sigmoid against Troy Sobotka's reference script (calculate_sigmoid with pivots
    // (10/16.5, 0.18^(1/2.4)), slope 2.4, powers 1.5; printed with numpy in f64).
    for (x, y) in [(0.1, 0.0188332540113223), (0.3, 0.0884922242427314), (10.0 / 16.5, 0.4894370895738783), (0.7, 0.6916817853726303), (0.9, 0.9368883795263101), (1.0, 1.0)] {
        assert!((sigmoid(x) - y).abs() < 1e-12, "sigmoid({x}) = {} ≠ {y}", sigmoid(x));
    }
    // The whole chain on colours across the range: within 1e-6 of the independent form.
    let mut worst = 0.0f64;
    let mut state = 0x2545F4914F6CDD1Du64;
    for _ in 0..20000 {
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let rgb = [0, 1, 2].map(|_| 2f64.powf(-12.0 + 18.0 * next()) * if next() < 0.05 { 0.0 } else { 1.0 });
        let got = agx_blender(rgb.map(|x| x as f32));
        // f32 input: compare against the reference at the same f32 input.
        let want = agx_reference(rgb.map(|x| x as f32 as f64));
        for c in 0..3 {
            worst = worst.max((got[c] as f64 - want[c]).abs());
        }
    }
    eprintln!("AgX: worst difference to the independent closed form {worst:.2e}");
    assert!(worst <= 1e-6, "AgX differs from the independent closed form by {worst:.2e}");
}

/// A fitted 16² material of Type 3 (dust over a clearcoat) in `dir`.
fn fitted_material(dir: &Path) {
    crate::project::textured_material(dir, 3, 16);
}

fn png16(path: &Path) -> (usize, usize, Vec<u16>) {
    let img = image::open(path).unwrap().to_rgb16();
    (img.width() as usize, img.height() as usize, img.into_raw())
}

/// A small export (`frames` frames of 24², 1 spp) of a fitted material on a UV sphere under
/// `root`, into `root/<name>`.
pub(crate) fn small_export(root: &Path, name: &str, frames: usize, seed: u64) -> std::path::PathBuf {
    let material = root.join("material");
    if !material.join("fit.json").is_file() {
        fitted_material(&material);
    }
    let mesh_path = crate::render::write_uv_sphere_gltf(&root.join("mesh"), 16, 8);
    let mesh = uplift_render::mesh::Mesh::new(uplift_enhance::gltf_input::load(&mesh_path).unwrap().world_triangles()).unwrap();
    let o = uplift::export::ExportOptions { orbit: OrbitOptions { frames, width: 24, height: 24, seed, ..Default::default() }, spp: 1, bounces: 1, exposure: 1.0, threads: 2, neural: None, latent_affine: uplift::export::UNIT_LATENT_AFFINE, mp4: false };
    let out = root.join(name);
    uplift::export::export_asset(&material, &mesh, &uplift_render::environment::Environment::studio(), &Stack::builtin(), &out, &o, false).unwrap();
    out
}

#[test]
fn exported_frames_reproject_and_decode_to_their_floats() {
    let root = Path::new(env!("CARGO_TARGET_TMPDIR")).join("export_test");
    let _ = std::fs::remove_dir_all(&root);
    let material = root.join("material");
    fitted_material(&material);
    let mesh_path = crate::render::write_uv_sphere_gltf(&root.join("mesh"), 32, 16);
    let mesh = uplift_render::mesh::Mesh::new(uplift_enhance::gltf_input::load(&mesh_path).unwrap().world_triangles()).unwrap();
    let stack = std::sync::Arc::new(Stack::builtin());
    let (w, h) = (48, 40);
    let o = uplift::export::ExportOptions { orbit: OrbitOptions { frames: 3, width: w, height: h, seed: 9, ..Default::default() }, spp: 2, bounces: 1, exposure: 1.0, threads: 2, neural: None, latent_affine: uplift::export::UNIT_LATENT_AFFINE, mp4: false };
    let env = uplift_render::environment::Environment::studio();
    let out = root.join("out");
    let s = uplift::export::export_asset(&material, &mesh, &env, &stack, &out, &o, false).unwrap();
    assert_eq!((s.frames, s.skipped), (3, 0));

    let cameras: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("cameras.json")).unwrap()).unwrap();
    let meta: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("meta.json")).unwrap()).unwrap();
    let f = |k: &str| cameras[k].as_f64().unwrap();
    let (fx, fy, cx, cy) = (f("fl_x"), f("fl_y"), f("cx"), f("cy"));
    assert_eq!((cameras["w"].as_u64(), cameras["h"].as_u64()), (Some(w as u64), Some(h as u64)));
    let affine = |m: &str| -> ([f64; 3], [f64; 3]) {
        let v = |k: &str| [0, 1, 2].map(|c| meta["modalities"][m][k][c].as_f64().unwrap());
        (v("scale"), v("offset"))
    };
    let (mut worst_px, mut worst_pos, mut worst_nrm, mut worst_cam, mut covered) = (0.0f64, 0.0f64, 0.0f64, 0.0f64, 0usize);
    for k in 0..3 {
        let m: Vec<[f64; 4]> = (0..4).map(|r| [0, 1, 2, 3].map(|c| cameras["frames"][k]["transform_matrix"][r][c].as_f64().unwrap())).collect();
        let exr = |name: &str| uplift_base::exr::read(&uplift::export::frame_path(&out, name, k, "exr")).unwrap();
        let (pos, nrm) = (exr("position"), exr("normal_world"));
        let mask = image::open(uplift::export::frame_path(&out, "mask", k, "png")).unwrap().to_luma8().into_raw();
        let (_, _, pos16) = png16(&uplift::export::frame_path(&out, "position", k, "png"));
        let (_, _, nrm16) = png16(&uplift::export::frame_path(&out, "normal_world", k, "png"));
        let (_, _, cam16) = png16(&uplift::export::frame_path(&out, "normal_camera", k, "png"));
        let ((ps, po), (ns, no)) = (affine("position"), affine("normal_world"));
        for p in 0..w * h {
            if mask[p] == 0 {
                continue;
            }
            covered += 1;
            let world = [0, 1, 2].map(|c| pos.channel(["X", "Y", "Z"][c]).unwrap()[p] as f64);
            // Camera coordinates: the inverse of the rigid camera-to-world.
            let d = [0, 1, 2].map(|c| world[c] - m[c][3]);
            let cam = [0, 1, 2].map(|a| (0..3).map(|r| m[r][a] * d[r]).sum::<f64>());
            assert!(cam[2] < 0.0, "frame {k} pixel {p}: the point is behind the camera");
            let (u, v) = (cx + fx * cam[0] / -cam[2], cy - fy * cam[1] / -cam[2]);
            let (px, py) = ((p % w) as f64 + 0.5, (p / w) as f64 + 0.5);
            worst_px = worst_px.max((u - px).abs().max((v - py).abs()));
            let n = [0, 1, 2].map(|c| nrm.channel(["X", "Y", "Z"][c]).unwrap()[p] as f64);
            for c in 0..3 {
                let decode = |v16: u16, s: f64, o: f64| o + s * (2.0 * v16 as f64 / 65535.0 - 1.0);
                worst_pos = worst_pos.max((decode(pos16[p * 3 + c], ps[c], po[c]) - world[c]).abs() / (2.0 * ps[c] / 65535.0));
                worst_nrm = worst_nrm.max((decode(nrm16[p * 3 + c], ns[c], no[c]) - n[c]).abs() / (2.0 * ns[c] / 65535.0));
                // Camera-space normal: the world normal in the camera's axes.
                let want = (0..3).map(|r| m[r][c] * n[r]).sum::<f64>();
                worst_cam = worst_cam.max((decode(cam16[p * 3 + c], 1.0, 0.0) - want).abs() / (2.0 / 65535.0));
            }
        }
    }
    eprintln!("camera check over {covered} covered pixels: reprojection within {worst_px:.2e} px; PNG16 vs float: positions {worst_pos:.2} steps, world normals {worst_nrm:.2} steps, camera normals {worst_cam:.2} steps");
    assert!(covered > 3 * w * h / 8, "the sphere covers only {covered} pixels");
    assert!(worst_px <= 0.5, "a world position reprojects {worst_px} px from its pixel");
    // Rounding to the nearest code is half a step; the f32 affine adds a little.
    assert!(worst_pos <= 1.0 && worst_nrm <= 1.0 && worst_cam <= 1.0, "decoded PNG16 values are {worst_pos} / {worst_nrm} / {worst_cam} steps from the floats");
    assert_eq!(std::fs::read_to_string(out.join("prompt.txt")).unwrap().trim(), "dusty, clear coat, worn coating");

    // Resume: with frame 2's shaded image gone, only frame 2 is rendered again, to the same bytes.
    let shaded2 = uplift::export::frame_path(&out, "shaded", 2, "png");
    let before = std::fs::read(&shaded2).unwrap();
    std::fs::remove_file(&shaded2).unwrap();
    let s = uplift::export::export_asset(&material, &mesh, &env, &stack, &out, &o, false).unwrap();
    assert_eq!(s.skipped, 2);
    assert!(std::fs::read(&shaded2).unwrap() == before, "the resumed frame differs");
    // The same options give the same bytes in another folder.
    let again = root.join("again");
    uplift::export::export_asset(&material, &mesh, &env, &stack, &again, &o, false).unwrap();
    for (name, ext) in uplift::export::MODALITIES {
        let p = |d: &Path| uplift::export::frame_path(d, name, 1, ext);
        assert!(std::fs::read(p(&out)).unwrap() == std::fs::read(p(&again)).unwrap(), "{name}.{ext} differs between two exports");
    }
    let _ = std::fs::remove_dir_all(&root);
}

/// `--mp4`: every PNG modality's video decodes (ffmpeg, back to raw RGB) to its frames exactly
/// — the 8-bit PNGs as they are, the 16-bit ones rounded to v16 / 257 (computed here from the
/// PNGs, not with uplift's conversion) — `meta.json` names the videos, and a second export
/// writes identical bytes. Needs ffmpeg (Debian's; .ci/run installs it).
#[test]
fn mp4_videos_decode_losslessly_to_the_frames() {
    if !std::process::Command::new("sh").arg("-c").arg("command -v ffmpeg").output().is_ok_and(|o| o.status.success()) {
        return uplift_base::test_env::skip("mp4_videos", "ffmpeg is not installed (Debian: apt install ffmpeg; .ci/run does)");
    }
    let root = Path::new(env!("CARGO_TARGET_TMPDIR")).join("export_mp4");
    let _ = std::fs::remove_dir_all(&root);
    let material = root.join("material");
    fitted_material(&material);
    let mesh_path = crate::render::write_uv_sphere_gltf(&root.join("mesh"), 16, 8);
    let mesh = uplift_render::mesh::Mesh::new(uplift_enhance::gltf_input::load(&mesh_path).unwrap().world_triangles()).unwrap();
    let (w, h, frames) = (30usize, 22usize, 3usize);
    let export = |name: &str| {
        let o = uplift::export::ExportOptions { orbit: OrbitOptions { frames, width: w, height: h, seed: 2, ..Default::default() }, spp: 1, bounces: 1, exposure: 1.0, threads: 2, neural: None, latent_affine: uplift::export::UNIT_LATENT_AFFINE, mp4: true };
        let out = root.join(name);
        uplift::export::export_asset(&material, &mesh, &uplift_render::environment::Environment::studio(), &Stack::builtin(), &out, &o, false).unwrap();
        out
    };
    let (a, b) = (export("a"), export("b"));
    let meta: serde_json::Value = serde_json::from_slice(&std::fs::read(a.join("meta.json")).unwrap()).unwrap();
    let listed: Vec<String> = meta["videos"]["files"].as_array().expect("meta.json lists the videos").iter().map(|v| v.as_str().unwrap().to_string()).collect();
    assert_eq!(listed.len(), 8);
    let mut covered = 0;
    for file in &listed {
        let modality = file.trim_end_matches(".mp4");
        let video = a.join(file);
        assert_eq!(std::fs::read(&video).unwrap(), std::fs::read(b.join(file)).unwrap(), "{file}: a second export differs");
        let decoded = std::process::Command::new("ffmpeg").args(["-hide_banner", "-loglevel", "error", "-i"]).arg(&video).args(["-f", "rawvideo", "-pix_fmt", "rgb24", "pipe:1"]).output().unwrap();
        assert!(decoded.status.success(), "{file}: {}", String::from_utf8_lossy(&decoded.stderr));
        assert_eq!(decoded.stdout.len(), frames * w * h * 3, "{file}: {} bytes decoded", decoded.stdout.len());
        for k in 0..frames {
            let img = image::open(a.join(modality).join(format!("{k:04}.png"))).unwrap();
            let want: Vec<u8> = match img.color() {
                image::ColorType::Rgb16 => img.to_rgb16().into_raw().iter().map(|&v| (v as f64 / 257.0).round() as u8).collect(),
                image::ColorType::L8 => img.to_luma8().into_raw().iter().flat_map(|&v| [v; 3]).collect(),
                image::ColorType::Rgb8 => img.to_rgb8().into_raw(),
                c => panic!("{modality}: a frame of colour type {c:?}"),
            };
            let got = &decoded.stdout[k * w * h * 3..(k + 1) * w * h * 3];
            let differ = want.iter().zip(got).filter(|(x, y)| x != y).count();
            assert_eq!(differ, 0, "{file} frame {k}: {differ} of {} values differ from the frame", want.len());
            covered += want.iter().filter(|&&v| v > 0).count();
        }
    }
    assert!(covered > 1000, "only {covered} non-zero values: the frames would prove little");
    std::fs::remove_dir_all(&root).unwrap();
}
