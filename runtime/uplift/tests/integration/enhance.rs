//! `uplift enhance` and the uplift rules (mtlx/rules/), against independent references:
//! - every rule and every output validates with MaterialX's own validator
//!   (`UPLIFT_MTLX_VALIDATOR`; skipped, saying so, when absent) and compiles with uplift; the
//!   rules' shipped CPU kernels agree with the wgpu engine;
//! - `params.exr` equals the written `material.mtlx`'s own graph (image nodes reading the written
//!   textures, compiled afresh, run on wgpu) at 1,000 random texels, for texture-folder and glTF
//!   inputs;
//! - the material's BSDF, compiled from `material.mtlx` and evaluated at texels (through the
//!   library and through `uplift eval --context eval`), equals the uplift_stack composition of
//!   lobes.md §2.2 written out here from single-lobe kernels, fed with the baked parameters,
//!   plus the Lambertian base scaled by the throughput;
//! - white furnace for every Type with a white base color;
//! - determinism (same seed: same bytes; other seed: other values), batch mode (one folder per
//!   material, finished ones skipped), and clear errors for bad input.

use crate::common;

use common::bsdf::{bsdf, gulbrandsen, view, Bsdf, Params};
use common::Rng;
use std::path::{Path, PathBuf};
use std::process::Command;
use uplift_engines::batch::{Columns, Geometry, PatternBatch, PatternEngine, TextureData};
use uplift_engines::cpu_engine::CpuKernel;
use uplift_base::exr;
use uplift_engines::texture_loader::load_texture;
use uplift_compiler::{ClosureContext, OutputSelection, PatternKernel};

/// The binary's exit code and its stdout and stderr together.
fn uplift(args: &[&str]) -> (i32, String) {
    let (code, stdout, stderr) = crate::common::cli::uplift(args);
    (code, format!("{stdout}{stderr}"))
}

fn temp_dir(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("enhance-{name}"));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

use crate::common::cli::repo;

/// Runs MaterialX's validator on `path`; `None` when it is not available.
pub(crate) fn validate(path: &Path) -> Option<Result<(), String>> {
    let tool = std::env::var_os("UPLIFT_MTLX_VALIDATOR").map(PathBuf::from).filter(|p| p.is_file())?;
    let out = Command::new("python3").arg(&tool).arg(path).output().ok()?;
    let text = String::from_utf8_lossy(&out.stdout).to_string();
    if text.contains("No module named") || String::from_utf8_lossy(&out.stderr).contains("No module named 'MaterialX'") {
        return None;
    }
    Some(if out.status.success() && text.starts_with("VALID") { Ok(()) } else { Err(format!("{text}{}", String::from_utf8_lossy(&out.stderr))) })
}

pub(crate) fn say_validator_skipped() {
    uplift_base::test_env::skip("MaterialX validation", "set UPLIFT_MTLX_VALIDATOR to shared/tools/mtlx_validate.py with python3 and the `materialx` package (.ci/run does)");
}

fn png8(path: &Path, w: u32, h: u32, channels: usize, f: impl Fn(u32, u32) -> [u8; 3]) {
    let data: Vec<u8> = (0..h).flat_map(|y| (0..w).map(move |x| (x, y))).flat_map(|(x, y)| f(x, y)[..channels].to_vec()).collect();
    let ty = if channels == 1 { image::ExtendedColorType::L8 } else { image::ExtendedColorType::Rgb8 };
    image::save_buffer(path, &data, w, h, ty).unwrap();
}

/// A texture folder with conventional names: a smooth base color, a roughness ramp, the given
/// metalness and (optionally) a normal map with gentle bumps. `w × h` texels.
fn texture_folder(dir: &Path, w: u32, h: u32, base: Option<[u8; 3]>, metal: u8, normal: bool) {
    std::fs::create_dir_all(dir).unwrap();
    png8(&dir.join("wood_basecolor.png"), w, h, 3, |x, y| base.unwrap_or([(40 + 5 * x % 200) as u8, (90 + 3 * y % 150) as u8, ((x * y) % 255) as u8]));
    png8(&dir.join("wood_roughness.png"), w, h, 1, |x, y| [(20 + (230 * (x + 2 * y)) / (w + 2 * h)) as u8; 3]);
    png8(&dir.join("wood_metalness.png"), w, h, 1, |_, _| [metal; 3]);
    if normal {
        png8(&dir.join("wood_normal.png"), w, h, 3, |x, y| {
            let (a, b) = ((x as f32 * 0.4).sin() * 0.3, (y as f32 * 0.3).cos() * 0.3);
            let z = (1.0 - a * a - b * b).sqrt();
            [((a * 0.5 + 0.5) * 255.0) as u8, ((b * 0.5 + 0.5) * 255.0) as u8, ((z * 0.5 + 0.5) * 255.0) as u8]
        });
    }
}

fn enhance(input: &Path, kind: &str, seed: u64, out: &Path) {
    let (code, text) = uplift(&["enhance", input.to_str().unwrap(), "--type", kind, "--seed", &seed.to_string(), "--mask-size", "128", "-o", out.to_str().unwrap()]);
    assert_eq!(code, 0, "uplift enhance {} --type {kind}: {text}", input.display());
}

/// The plane geometry `uplift enhance` bakes texture-only materials on (a unit square in XZ
/// facing +Y; texel rows along +Z), at texel (x, y) of a `w × h` bake.
fn plane_texel(x: usize, y: usize, w: usize, h: usize) -> Geometry {
    Geometry {
        texcoord: [(x as f32 + 0.5) / w as f32, 1.0 - (y as f32 + 0.5) / h as f32],
        position: [(x as f32 + 0.5) / w as f32 - 0.5, 0.0, (y as f32 + 0.5) / h as f32 - 0.5],
        normal: [0.0, 1.0, 0.0],
        tangent: [1.0, 0.0, 0.0],
    }
}

/// Compiles `material.mtlx` (outputs named, or its BSDF in `context`).
fn compile_material(dir: &Path, outputs: Option<Vec<String>>, context: Option<ClosureContext>) -> PatternKernel {
    let path = dir.join("material.mtlx");
    let selection = match outputs {
        Some(o) => OutputSelection::Named(o),
        None => OutputSelection::Named(vec!["uplift_material/bsdf_out".into()]),
    };
    let c = common::compiler().compile_file_in(&path, &selection, context);
    let k = c.kernel.filter(|_| !mtlx::has_errors(&c.diagnostics)).unwrap_or_else(|| panic!("{}: {:?}", path.display(), c.diagnostics.iter().map(|d| d.to_string()).collect::<Vec<_>>()));
    // Both backends: the WGSL was validated by the compiler; the Rust writer must take it too.
    uplift_compiler::backend_rust::write_rust_kernel(&k).unwrap_or_else(|e| panic!("{}: Rust backend: {e}", path.display()));
    k
}

fn kernel_textures(k: &PatternKernel) -> Vec<TextureData> {
    k.textures.iter().map(|t| load_texture(&t.path, t.colorspace.as_deref()).unwrap()).collect()
}

/// Runs a kernel on wgpu at the given geometry, interface inputs at their document values
/// except `set` (per point, by name).
fn run_wgpu(k: &PatternKernel, geometry: &[Geometry], set: &[(&str, Vec<[f32; 3]>)]) -> Columns {
    let n = geometry.len();
    let mut inputs = Columns::zeros(n, k.input_stride);
    for inp in &k.inputs {
        let given = set.iter().find(|(name, _)| *name == inp.input.name);
        for c in 0..inp.input.ty.components().unwrap() {
            let col = inputs.column_mut(inp.offset + c);
            match given {
                Some((_, v)) => col.iter_mut().zip(v).for_each(|(x, v)| *x = v[c]),
                None => col.fill(inp.input.default[c]),
            }
        }
    }
    let batch = PatternBatch { geometry: Geometry::columns(geometry), inputs, textures: kernel_textures(k), points_per_group: 1 };
    common::engine().run_pattern(k, &batch).unwrap_or_else(|e| panic!("{e}"))
}

fn output_column(k: &PatternKernel, out: &Columns, name: &str, c: usize) -> Vec<f32> {
    let o = k.outputs.iter().find(|o| o.name == name || o.name.ends_with(&format!("/{name}"))).unwrap_or_else(|| panic!("no output {name}"));
    out.column(o.offset + c).to_vec()
}

/// The baked outputs of a material: (output name, EXR channel names).
fn baked_outputs(params: &exr::ExrImage) -> Vec<(String, Vec<String>)> {
    let mut outs: Vec<(String, Vec<String>)> = Vec::new();
    for ch in &params.channels {
        let base = ch.name.split('.').next().unwrap().to_string();
        match outs.iter_mut().find(|(b, _)| *b == base) {
            Some((_, v)) => v.push(ch.name.clone()),
            None => outs.push((base, vec![ch.name.clone()])),
        }
    }
    // EXR stores channels sorted by name (B, G, R); components go R, G, B (X, Y, Z).
    let rank = |n: &str| ["R", "G", "B", "X", "Y", "Z"].iter().position(|s| n.ends_with(&format!(".{s}"))).unwrap_or(0);
    for (_, v) in &mut outs {
        v.sort_by_key(|n| rank(n));
    }
    outs
}

/// params.exr against the material document's own graph at `texels` with `geometry`.
fn check_params_against_document(dir: &Path, texels: &[(usize, usize)], geometry: &[Geometry]) -> f32 {
    let params = exr::read(&dir.join("params.exr")).unwrap();
    let outs = baked_outputs(&params);
    let stack = uplift_engines::stack::Stack::builtin();
    assert_eq!(outs.len(), stack.inputs().len() + 2, "the uplift_stack inputs, the diffuse colour and the normal: {outs:?}");
    // Optional stack inputs the rule leaves out (the coat's thin film) have no output in the
    // document: params.exr holds their nodedef values.
    let doc = std::fs::read_to_string(dir.join("material.mtlx")).unwrap();
    let (outs, defaults): (Vec<_>, Vec<_>) = outs.into_iter().partition(|(b, _)| doc.contains(&format!("name=\"{b}_out\"")));
    for (base, channels) in &defaults {
        assert!(stack.inputs().iter().any(|i| i.name == *base && i.optional), "{base}: baked without an output, but not optional");
        for ch in channels {
            let want = stack.parameters()[stack.index_of(ch).unwrap()].default;
            assert!(params.channel(ch).unwrap().iter().all(|&v| v == want), "{ch}: not its nodedef value {want}");
        }
    }
    let names: Vec<String> = outs.iter().map(|(b, _)| format!("uplift_material/{b}_out")).collect();
    let k = compile_material(dir, Some(names), None);
    let got = run_wgpu(&k, geometry, &[]);
    let mut worst = 0.0f32;
    for (base, channels) in &outs {
        for (c, ch) in channels.iter().enumerate() {
            let baked = params.channel(ch).unwrap();
            let col = output_column(&k, &got, &format!("{base}_out"), c);
            for (i, &(x, y)) in texels.iter().enumerate() {
                let (b, g) = (baked[y * params.width + x], col[i]);
                let err = (b - g).abs();
                worst = worst.max(err);
                assert!(err <= 1e-5, "{}: texel ({x}, {y}) channel {ch}: params.exr {b}, material.mtlx {g}", dir.display());
            }
        }
    }
    worst
}

fn random_texels(w: usize, h: usize, n: usize, seed: u64) -> Vec<(usize, usize)> {
    let mut r = Rng::new(seed);
    (0..n).map(|_| ((r.next_u64() % w as u64) as usize, (r.next_u64() % h as u64) as usize)).collect()
}

#[test]
fn rules_validate_and_their_shipped_kernels_agree_with_wgpu() {
    let engine = common::bsdf::cpu_engine();
    let mut validated = 0;
    for entry in std::fs::read_dir(repo().join("mtlx/rules")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "mtlx") {
            continue;
        }
        match validate(&path) {
            Some(r) => {
                r.unwrap_or_else(|e| panic!("{}: {e}", path.display()));
                validated += 1;
            }
            None => say_validator_skipped(),
        }
        let kind = uplift_enhance::rules::EnhancementType::ALL.into_iter().find(|t| path.ends_with(t.file_name())).unwrap();
        let rule = uplift_enhance::rules::interface(kind, &uplift_engines::stack::Stack::builtin()).unwrap();
        let kernel = uplift_enhance::pipeline::rule_kernel(&rule, &repo().join("mtlx/rules")).unwrap();
        let prepared = engine.prepare(&kernel).unwrap();
        assert!(matches!(prepared, CpuKernel::Builtin(_)), "{}: not shipped", path.display());
        // Random PBR inputs and scalars at random points of a sphere.
        let mut r = Rng::new(0x5eed + kind.index() as u64);
        let n = 512;
        let geometry: Vec<Geometry> = (0..n)
            .map(|_| {
                let z = r.range(-1.0, 1.0);
                let phi = r.range(0.0, std::f32::consts::TAU);
                let s = (1.0 - z * z).sqrt();
                let nrm = [s * phi.cos(), s * phi.sin(), z];
                Geometry { texcoord: [r.range(0.0, 1.0), r.range(0.0, 1.0)], position: nrm.map(|v| v * 0.7), normal: nrm, tangent: [-phi.sin(), phi.cos(), 0.0] }
            })
            .collect();
        let mut inputs = Columns::zeros(n, kernel.input_stride);
        for inp in &kernel.inputs {
            let range = rule.random.iter().find(|s| s.name == inp.input.name).map(|s| (s.min as f32, s.max as f32));
            for c in 0..inp.input.ty.components().unwrap() {
                for v in inputs.column_mut(inp.offset + c) {
                    *v = match (inp.input.name.as_str(), range) {
                        (_, Some((lo, hi))) => r.range(lo, hi),
                        ("object_size", _) => 1.4,
                        _ => r.range(0.0, 1.0),
                    };
                }
            }
        }
        let batch = PatternBatch { geometry: Geometry::columns(&geometry), inputs, textures: kernel_textures(&kernel), points_per_group: 1 };
        let cpu = engine.run_prepared(&prepared, &batch).unwrap();
        let gpu = common::engine().run_pattern(&kernel, &batch).unwrap();
        for col in 0..kernel.output_stride {
            for i in 0..n {
                let (a, b) = (cpu.column(col)[i], gpu.column(col)[i]);
                assert!((a - b).abs() <= 2e-5 * (1.0 + b.abs()), "{}: output column {col} point {i}: CPU {a}, wgpu {b}", path.display());
            }
        }
        // The full material's BSDF compiles in every closure context.
        for context in ClosureContext::ALL {
            let c = common::compiler().compile_file_in(&path, &OutputSelection::Named(vec!["uplift_rule/bsdf_out".into()]), Some(context));
            assert!(c.kernel.is_some() && !mtlx::has_errors(&c.diagnostics), "{} ({}): {:?}", path.display(), context.name(), c.diagnostics);
        }
    }
    eprintln!("{validated} rules validated with MaterialX");
}

#[test]
fn every_type_validates_and_params_equal_the_document_graph() {
    let root = temp_dir("types");
    let input = root.join("wood");
    texture_folder(&input, 48, 32, None, 0, true);
    for kind in 0..6 {
        let out = root.join(format!("type{kind}"));
        enhance(&input, &kind.to_string(), 11 + kind, &out);
        match validate(&out.join("material.mtlx")) {
            Some(r) => r.unwrap_or_else(|e| panic!("type {kind}: {e}")),
            None => say_validator_skipped(),
        }
        let meta = std::fs::read_to_string(out.join("meta.json")).unwrap();
        assert!(meta.contains(&format!("\"type\": {kind},")), "{meta}");
        let texels = random_texels(48, 32, 1000, kind);
        let geometry: Vec<Geometry> = texels.iter().map(|&(x, y)| plane_texel(x, y, 48, 32)).collect();
        let worst = check_params_against_document(&out, &texels, &geometry);
        eprintln!("type {kind}: worst |params.exr − material.mtlx| over 1000 texels: {worst:.2e}");
        for context in ClosureContext::ALL {
            compile_material(&out, None, Some(context));
        }
    }
}

/// Single-lobe kernels and the lobes.md §2.2 composition, evaluated for one parameter set.
struct Lobes {
    transparent: [Bsdf; 2],
    opaque: [Bsdf; 2],
}

impl Lobes {
    fn new() -> Lobes {
        Lobes {
            transparent: [bsdf("bsdf_transparent_lobes", ClosureContext::Eval), bsdf("bsdf_transparent_lobes", ClosureContext::Albedo)],
            opaque: [bsdf("bsdf_opaque_lobes", ClosureContext::Eval), bsdf("bsdf_opaque_lobes", ClosureContext::Albedo)],
        }
    }

    /// (f·cos per channel, untinted albedo E per channel) of one lobe at (wv, wl), local frame.
    fn lobe(&self, opaque: bool, p: &Params, wv: [f32; 3], wl: [f32; 3]) -> ([f64; 3], [f64; 3]) {
        let [e, a] = if opaque { &self.opaque } else { &self.transparent };
        let out_e = e.run(&[vec![wv], vec![wl]], &[(0..1, p)]);
        let out_a = a.run(&[vec![wv]], &[(0..1, p)]);
        ([0, 1, 2].map(|c| e.column(&out_e, "response", c)[0] as f64), [0, 1, 2].map(|c| a.column(&out_a, "albedo", c)[0] as f64))
    }

    /// The material's f·cos: the uplift_stack composition plus T·c/π·cos θl.
    fn material(&self, get: &dyn Fn(&str) -> Vec<f32>, base: [f32; 3], wv: [f32; 3], wl: [f32; 3]) -> [f64; 3] {
        let f = |k: &str| get(k)[0];
        let sq = |a: f32| vec![a, a];
        let sheen = |w: f32| Params::from([("k_weight", vec![1.0]), ("k_color", vec![1.0; 3]), ("k_roughness", vec![w.max(0.02)])]);
        let diel = |ior: f32, a: f32| Params::from([("d_weight", vec![1.0]), ("d_tint", vec![1.0; 3]), ("d_ior", vec![ior]), ("d_roughness", sq(a))]);
        let fuzz = self.lobe(false, &sheen(f("fuzz_thickness")), wv, wl);
        let coat = self.lobe(false, &diel(f("coat_ior"), 0.01), wv, wl);
        let core = self.lobe(false, &diel(f("specular_ior"), f("core_roughness")), wv, wl);
        let haze = self.lobe(false, &diel(f("specular_ior"), f("haze_roughness")), wv, wl);
        let sub = self.lobe(false, &diel(f("specular_ior"), f("subcutaneous_roughness")), wv, wl);
        let inner = self.lobe(false, &sheen(f("inner_thickness")), wv, wl);
        let (refl, edge) = (get("reflectivity"), get("edge_color"));
        let nk: Vec<(f32, f32)> = (0..3).map(|c| gulbrandsen(refl[c], edge[c])).collect();
        let cond = |a: f32| {
            Params::from([("c_weight", vec![1.0]), ("c_ior", nk.iter().map(|x| x.0).collect()), ("c_extinction", nk.iter().map(|x| x.1).collect()), ("c_roughness", sq(a))])
        };
        let cond_core = self.lobe(true, &cond(f("core_roughness")), wv, wl);
        let cond_haze = self.lobe(true, &cond(f("haze_roughness")), wv, wl);
        let (wf, wc, m, wh, win, wsub) =
            (f("fuzz_weight") as f64, f("coat_weight") as f64, f("metalness") as f64, f("haze_weight") as f64, f("inner_weight") as f64, f("subcutaneous_weight") as f64);
        let cs = get("scatter_color");
        [0, 1, 2].map(|c| {
            let cs = cs[c] as f64;
            let (e1, e2, e5, e6, e7, e8) = (fuzz.1[c], coat.1[c], core.1[c], haze.1[c], inner.1[c], sub.1[c]);
            let f_cond = (1.0 - wh) * cond_core.0[c] + wh * cond_haze.0[c];
            let tau56 = 1.0 - ((1.0 - wh) * e5 + wh * e6);
            let f_diel = (1.0 - wh) * core.0[c] + wh * haze.0[c] + tau56 * (win * cs * inner.0[c] + (1.0 - win * e7) * wsub * cs * sub.0[c]);
            let f_neu = wf * fuzz.0[c] + (1.0 - wf * e1) * (wc * coat.0[c] + (1.0 - wc * e2) * (m * f_cond + (1.0 - m) * f_diel));
            let t = (1.0 - wf * e1) * (1.0 - wc * e2) * (1.0 - m) * tau56 * (1.0 - win * e7) * (1.0 - wsub * e8);
            f_neu + t * base[c] as f64 / std::f64::consts::PI * wl[2].max(0.0) as f64
        })
    }
}

/// Local shading frame (normal +z) to the plane's world frame (normal +Y, tangent +X).
fn to_world(v: [f32; 3]) -> [f32; 3] {
    [v[0], v[2], -v[1]]
}

/// The material's BSDF through `uplift eval --context eval` (wgpu): response RGB per point.
fn eval_through_cli(dir: &Path, geometry: &[Geometry], dirs: &[([f32; 3], [f32; 3])]) -> Vec<[f64; 3]> {
    let mut csv = String::from("texcoord_x,texcoord_y,position_x,position_y,position_z,normal_x,normal_y,normal_z,tangent_x,tangent_y,tangent_z,wv_x,wv_y,wv_z,wl_x,wl_y,wl_z\n");
    for (g, (wv, wl)) in geometry.iter().zip(dirs) {
        let row: Vec<String> = g.texcoord.iter().chain(&g.position).chain(&g.normal).chain(&g.tangent).chain(&to_world(*wv)).chain(&to_world(*wl)).map(|v| format!("{v:?}")).collect();
        csv.push_str(&row.join(","));
        csv.push('\n');
    }
    let (input, output) = (dir.join("eval-in.csv"), dir.join("eval-out.csv"));
    std::fs::write(&input, csv).unwrap();
    let m = dir.join("material.mtlx");
    let (code, text) = uplift(&["eval", m.to_str().unwrap(), "--output", "uplift_material/bsdf_out", "--context", "eval", "--engine", "wgpu", "--input", input.to_str().unwrap(), "-o", output.to_str().unwrap()]);
    assert_eq!(code, 0, "{text}");
    let table = std::fs::read_to_string(&output).unwrap();
    let mut lines = table.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let cols: Vec<usize> = ["r", "g", "b"].iter().map(|c| header.iter().position(|h| h.ends_with(&format!("response_{c}"))).unwrap_or_else(|| panic!("{header:?}"))).collect();
    let _ = std::fs::remove_file(&input);
    let _ = std::fs::remove_file(&output);
    lines
        .map(|l| {
            let v: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
            [v[cols[0]], v[cols[1]], v[cols[2]]]
        })
        .collect()
}

#[test]
fn enhanced_material_eval_equals_the_written_out_stack_with_its_baked_parameters() {
    let root = temp_dir("eval");
    let input = root.join("wood");
    texture_folder(&input, 16, 16, None, 0, false);
    let metal_input = root.join("metal");
    texture_folder(&metal_input, 16, 16, None, 200, false);
    let lobes = Lobes::new();
    let mut worst = 0.0f64;
    for (kind, src) in [(0, &metal_input), (1, &input), (2, &metal_input), (3, &input), (4, &input), (5, &input)] {
        let out = root.join(format!("type{kind}"));
        enhance(src, &kind.to_string(), 100 + kind, &out);
        let params = exr::read(&out.join("params.exr")).unwrap();
        let base = load_texture(&out.join("textures/base_color.png"), Some("srgb_texture")).unwrap();
        let k = compile_material(&out, None, Some(ClosureContext::Eval));
        let texels = random_texels(16, 16, 12, kind);
        let mut r = Rng::new(kind);
        let dirs: Vec<([f32; 3], [f32; 3])> = texels
            .iter()
            .map(|_| {
                let mut d = || {
                    let mu = r.range(0.05, 1.0);
                    let phi = r.range(0.0, std::f32::consts::TAU);
                    let s = (1.0 - mu * mu).sqrt();
                    [s * phi.cos(), s * phi.sin(), mu]
                };
                (d(), d())
            })
            .collect();
        let geometry: Vec<Geometry> = texels.iter().map(|&(x, y)| plane_texel(x, y, 16, 16)).collect();
        let got = run_wgpu(&k, &geometry, &[("wv", dirs.iter().map(|d| to_world(d.0)).collect()), ("wl", dirs.iter().map(|d| to_world(d.1)).collect())]);
        let cli = eval_through_cli(&out, &geometry, &dirs);
        for (i, &(x, y)) in texels.iter().enumerate() {
            let at = |name: &str| -> Vec<f32> {
                match params.channel(name) {
                    Some(v) => vec![v[y * 16 + x]],
                    None => ["R", "G", "B"].iter().map(|c| params.channel(&format!("{name}.{c}")).unwrap()[y * 16 + x]).collect(),
                }
            };
            let c = [0, 1, 2].map(|ch| base.rgba[(y * 16 + x) * 4 + ch]);
            let want = lobes.material(&at, c, dirs[i].0, dirs[i].1);
            for ch in 0..3 {
                let g = output_column(&k, &got, "response", ch)[i] as f64;
                let err = (g - want[ch]).abs() / want[ch].abs().max(1.0);
                worst = worst.max(err);
                assert!(err <= 2e-4, "type {kind} texel ({x},{y}) channel {ch}: material {g}, written-out stack {}", want[ch]);
                let e = (cli[i][ch] - want[ch]).abs() / want[ch].abs().max(1.0);
                assert!(e <= 2e-4, "type {kind} texel ({x},{y}) channel {ch}: `uplift eval` {}, written-out stack {}", cli[i][ch], want[ch]);
            }
        }
    }
    eprintln!("worst |material − written-out stack| (relative above 1): {worst:.2e}");
}

#[test]
fn white_furnace_holds_for_every_type_with_a_white_base() {
    let root = temp_dir("furnace");
    let input = root.join("white");
    texture_folder(&input, 16, 16, Some([255, 255, 255]), 0, true);
    let mut worst = 0.0f32;
    for kind in 0..6 {
        let out = root.join(format!("type{kind}"));
        enhance(&input, &kind.to_string(), 7 + kind, &out);
        let k = compile_material(&out, None, Some(ClosureContext::Albedo));
        let texels = random_texels(16, 16, 64, 40 + kind);
        let mut geometry = Vec::new();
        let mut views = Vec::new();
        for &(x, y) in &texels {
            for mu in [0.02, 0.1, 0.3, 0.5, 0.7, 0.9, 1.0] {
                geometry.push(plane_texel(x, y, 16, 16));
                views.push(to_world(view(mu)));
            }
        }
        let got = run_wgpu(&k, &geometry, &[("wv", views)]);
        for c in 0..3 {
            for (i, a) in output_column(&k, &got, "albedo", c).iter().enumerate() {
                worst = worst.max((a - 1.0).abs());
                assert!((a - 1.0).abs() <= 2e-3, "type {kind} point {i} channel {c}: albedo of the material over a white base {a}");
            }
        }
    }
    eprintln!("white furnace, every Type: worst |A − 1| {worst:.2e}");
}

fn files(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            for (n, b) in files(&p) {
                out.push((format!("{}/{n}", p.file_name().unwrap().to_string_lossy()), b));
            }
        } else {
            out.push((p.file_name().unwrap().to_string_lossy().to_string(), std::fs::read(&p).unwrap()));
        }
    }
    out.sort();
    out
}

#[test]
fn same_seed_same_bytes_other_seed_other_values() {
    let root = temp_dir("determinism");
    let input = root.join("wood");
    texture_folder(&input, 24, 24, None, 0, true);
    let (a, b, c) = (root.join("a"), root.join("b"), root.join("c"));
    enhance(&input, "auto", 5, &a);
    enhance(&input, "auto", 5, &b);
    enhance(&input, "auto", 6, &c);
    let (fa, fb) = (files(&a), files(&b));
    assert_eq!(fa.iter().map(|f| &f.0).collect::<Vec<_>>(), fb.iter().map(|f| &f.0).collect::<Vec<_>>());
    for ((n, x), (_, y)) in fa.iter().zip(&fb) {
        assert!(x == y, "{n} differs between two runs with seed 5");
    }
    let pa = std::fs::read(a.join("params.exr")).unwrap();
    let pc = std::fs::read(c.join("params.exr")).unwrap();
    assert_ne!(pa, pc, "seeds 5 and 6 give the same params.exr");
    assert_ne!(std::fs::read(a.join("meta.json")).unwrap(), std::fs::read(c.join("meta.json")).unwrap());
}

/// A glTF 2.0 quad (two triangles, y = 0.3, normal +Y, under a node scaled by 2) whose
/// material reads base color and metallicRoughness textures written beside it.
fn gltf_quad(dir: &Path) -> PathBuf {
    std::fs::create_dir_all(dir).unwrap();
    // No channel is exactly 0: the rules' edge color r^γ has an infinite slope at r = 0, where
    // the image node's bilinear weights (off by ~1e-7 at texel centres in f32) would show.
    png8(&dir.join("base.png"), 20, 20, 3, |x, y| [(10 * x + 3) as u8, (12 * y + 3) as u8, 128]);
    png8(&dir.join("mr.png"), 20, 20, 3, |x, y| [0, (40 + 9 * x) as u8, (5 * y) as u8]);
    let positions: [[f32; 3]; 4] = [[-0.5, 0.3, -0.5], [0.5, 0.3, -0.5], [0.5, 0.3, 0.5], [-0.5, 0.3, 0.5]];
    let normals = [[0.0f32, 1.0, 0.0]; 4];
    let uvs: [[f32; 2]; 4] = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
    let indices: [u16; 6] = [0, 2, 1, 0, 3, 2];
    let mut bin = Vec::new();
    positions.iter().flatten().chain(normals.iter().flatten()).chain(uvs.iter().flatten()).for_each(|v| bin.extend_from_slice(&v.to_le_bytes()));
    indices.iter().for_each(|i| bin.extend_from_slice(&i.to_le_bytes()));
    std::fs::write(dir.join("quad.bin"), &bin).unwrap();
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0,"scale":[2,2,2]}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"NORMAL":1,"TEXCOORD_0":2}},"indices":3,"material":0}}]}}],
"materials":[{{"name":"quad","pbrMetallicRoughness":{{"baseColorTexture":{{"index":0}},"metallicRoughnessTexture":{{"index":1}},"roughnessFactor":0.9,"metallicFactor":0.5}}}}],
"textures":[{{"source":0}},{{"source":1}}],"images":[{{"uri":"base.png"}},{{"uri":"mr.png"}}],
"buffers":[{{"uri":"quad.bin","byteLength":{}}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":48}},{{"buffer":0,"byteOffset":96,"byteLength":32}},{{"buffer":0,"byteOffset":128,"byteLength":12}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[-0.5,0.3,-0.5],"max":[0.5,0.3,0.5]}},{{"bufferView":1,"componentType":5126,"count":4,"type":"VEC3"}},{{"bufferView":2,"componentType":5126,"count":4,"type":"VEC2"}},{{"bufferView":3,"componentType":5123,"count":6,"type":"SCALAR"}}]}}"#,
        bin.len()
    );
    let path = dir.join("quad.gltf");
    std::fs::write(&path, json).unwrap();
    path
}

#[test]
fn gltf_input_bakes_on_the_rasterised_surface() {
    let root = temp_dir("gltf");
    let gltf = gltf_quad(&root.join("asset"));
    let out = root.join("out");
    enhance(&gltf, "1", 3, &out);
    match validate(&out.join("material.mtlx")) {
        Some(r) => r.unwrap(),
        None => say_validator_skipped(),
    }
    let asset = uplift_enhance::gltf_input::load(&gltf).unwrap();
    let bake = uplift_enhance::gltf_input::rasterize_uv(&asset, 0, 20, 20).unwrap();
    // The quad lies at world y = 0.6 (scaled by 2), normal +Y.
    assert!(bake.position.iter().all(|p| (p[1] - 0.6).abs() < 1e-5) && bake.normal.iter().all(|n| (n[1] - 1.0).abs() < 1e-5));
    let texels = random_texels(20, 20, 1000, 9);
    let geometry: Vec<Geometry> = texels
        .iter()
        .map(|&(x, y)| {
            let i = y * 20 + x;
            Geometry { texcoord: [(x as f32 + 0.5) / 20.0, 1.0 - (y as f32 + 0.5) / 20.0], position: bake.position[i], normal: bake.normal[i], tangent: bake.tangent[i] }
        })
        .collect();
    let worst = check_params_against_document(&out, &texels, &geometry);
    eprintln!("glTF: worst |params.exr − material.mtlx| {worst:.2e}");
    // Roughness and metalness come from the packed texture's G and B channels times the factors.
    let params = exr::read(&out.join("params.exr")).unwrap();
    let metal = params.channel("metalness").unwrap();
    for y in 0..20 {
        let want = (5 * y) as f32 / 255.0 * 0.5;
        assert!((metal[y * 20 + 7] - want).abs() < 1e-4, "row {y}: metalness {} want {want}", metal[y * 20 + 7]);
    }
    let meta = std::fs::read_to_string(out.join("meta.json")).unwrap();
    assert!(meta.contains("\"object_size\": 2.828"), "{meta}");
}

#[test]
fn mtlx_materials_with_images_and_constants_are_read() {
    let root = temp_dir("mtlx");
    let tex = root.join("in");
    texture_folder(&tex, 8, 8, None, 0, true);
    let doc = r#"<?xml version="1.0"?>
<materialx version="1.39">
  <image name="base_img" type="color3"><input name="file" type="filename" value="wood_basecolor.png" colorspace="srgb_texture" /></image>
  <image name="rough_img" type="float"><input name="file" type="filename" value="wood_roughness.png" /></image>
  <image name="normal_img" type="vector3"><input name="file" type="filename" value="wood_normal.png" /></image>
  <normalmap name="nmap" type="vector3"><input name="in" type="vector3" nodename="normal_img" /></normalmap>
  <standard_surface name="ss" type="surfaceshader">
    <input name="base_color" type="color3" nodename="base_img" />
    <input name="specular_roughness" type="float" nodename="rough_img" />
    <input name="metalness" type="float" value="0.0" />
    <input name="normal" type="vector3" nodename="nmap" />
  </standard_surface>
  <surfacematerial name="wood" type="material"><input name="surfaceshader" type="surfaceshader" nodename="ss" /></surfacematerial>
  <UsdPreviewSurface name="usd" type="surfaceshader">
    <input name="diffuseColor" type="color3" value="0.2, 0.4, 0.6" />
    <input name="roughness" type="float" value="0.3" />
    <input name="metallic" type="float" value="1.0" />
  </UsdPreviewSurface>
  <surfacematerial name="blue_metal" type="material"><input name="surfaceshader" type="surfaceshader" nodename="usd" /></surfacematerial>
</materialx>
"#;
    std::fs::write(tex.join("materials.mtlx"), doc).unwrap();
    let out = root.join("out");
    // Two materials: batch mode, one folder each.
    let (code, text) = uplift(&["enhance", tex.join("materials.mtlx").to_str().unwrap(), "--seed", "1", "--mask-size", "64", "-o", out.to_str().unwrap()]);
    assert_eq!(code, 0, "{text}");
    for name in ["wood", "blue_metal"] {
        let dir = out.join(name);
        assert!(dir.join("params.exr").is_file() && dir.join("meta.json").is_file(), "{text}");
        if let Some(r) = validate(&dir.join("material.mtlx")) {
            r.unwrap();
        }
    }
    let wood = std::fs::read_to_string(out.join("wood/material.mtlx")).unwrap();
    assert!(wood.contains("textures/base_color.png") && wood.contains("textures/normal_map.png"), "{wood}");
    // The metal is never given a dielectric-only Type.
    let meta = std::fs::read_to_string(out.join("blue_metal/meta.json")).unwrap();
    assert!(!meta.contains("\"type\": 4") && !meta.contains("\"type\": 5"), "{meta}");
    let params = exr::read(&out.join("blue_metal/params.exr")).unwrap();
    assert_eq!(params.width, 256, "constant-only materials bake at 256²");
    assert!(params.channel("reflectivity.B").unwrap().iter().all(|&v| (v - 0.6).abs() < 1e-6));
}

#[test]
fn batch_mode_writes_one_folder_per_material_and_skips_finished_ones() {
    let root = temp_dir("batch");
    let input = root.join("library");
    for (k, name) in ["oak", "pine", "steel"].iter().enumerate() {
        texture_folder(&input.join(name), 8 + 4 * k as u32, 8, None, if *name == "steel" { 255 } else { 0 }, false);
    }
    let out = root.join("out");
    let (code, text) = uplift(&["enhance", input.to_str().unwrap(), "--seed", "2", "--mask-size", "64", "-o", out.to_str().unwrap()]);
    assert_eq!(code, 0, "{text}");
    assert!(text.contains("enhanced 3 material(s)"), "{text}");
    let meta_before = std::fs::read(out.join("pine/meta.json")).unwrap();
    std::fs::remove_dir_all(out.join("oak")).unwrap();
    let (code, text) = uplift(&["enhance", input.to_str().unwrap(), "--seed", "2", "--mask-size", "64", "-o", out.to_str().unwrap()]);
    assert_eq!(code, 0, "{text}");
    assert!(text.contains("enhanced 1 material(s)") && text.contains("2 already finished"), "{text}");
    assert_eq!(std::fs::read(out.join("pine/meta.json")).unwrap(), meta_before);
    // No staging folders are left behind: the three materials and enhance's manifest.
    let mut names: Vec<String> = std::fs::read_dir(&out).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into()).collect();
    names.sort();
    assert_eq!(names, [".uplift-output-enhance", "oak", "pine", "steel"], "{names:?}");
    let steel = std::fs::read_to_string(out.join("steel/meta.json")).unwrap();
    assert!(!steel.contains("\"type\": 4") && !steel.contains("\"type\": 5"), "{steel}");
}

#[test]
fn bad_input_gets_a_clear_error_and_no_output() {
    let root = temp_dir("errors");
    let metal = root.join("steel");
    texture_folder(&metal, 8, 8, None, 255, false);
    let out = root.join("out");
    let (code, text) = uplift(&["enhance", metal.to_str().unwrap(), "--type", "4", "-o", out.to_str().unwrap()]);
    assert_eq!(code, 1);
    assert!(text.contains("Type 4 is for dielectric materials"), "{text}");
    assert!(!out.exists(), "a failed enhance leaves no output");
    let (code, text) = uplift(&["enhance", root.join("missing").to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert_eq!(code, 1);
    assert!(text.contains("missing: no such file or folder"), "{text}");
    let (code, text) = uplift(&["enhance", metal.to_str().unwrap(), "--type", "9", "-o", out.to_str().unwrap()]);
    assert!(code != 0 && text.contains("--type 9"), "{text}");
    let bad = root.join("bad.mtlx");
    std::fs::write(&bad, "<materialx version=\"1.39\">\n  <standard_surface name=\"s\" type=\"surfaceshader\">\n    <input name=\"base_color\" type=\"color3\" nodename=\"nowhere\" />\n  </standard_surface>\n  <surfacematerial name=\"m\" type=\"material\"><input name=\"surfaceshader\" type=\"surfaceshader\" nodename=\"s\" /></surfacematerial>\n</materialx>\n").unwrap();
    let (code, text) = uplift(&["enhance", bad.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert_eq!(code, 1);
    assert!(text.contains("bad.mtlx:3:") && text.contains("not in the document"), "{text}");
    assert!(!out.exists());
}

/// A user-written rule from a folder of its own (examples/rules/wet.mtlx, copied): `enhance
/// --rule` bakes it on wgpu (no runner build), records it in meta.json and params.exr, writes
/// a material that validates with MaterialX's validator; `fit` and `render` take the folder
/// like any other. The baked values follow the rule: the coat weight is the drawn wetness and
/// the diffuse colour is the base colour darkened by its exponent.
#[test]
fn a_user_written_rule_runs_through_enhance_fit_and_render() {
    use crate::common::cli::{repo, s, uplift};
    let dir = crate::common::cli::temp_dir("enhance", "user_rule");
    let rules = dir.join("my_rules");
    std::fs::create_dir_all(&rules).unwrap();
    let rule = rules.join("wet.mtlx");
    std::fs::copy(repo().join("examples/rules/wet.mtlx"), &rule).unwrap();
    let out = dir.join("wet_copper");
    let run = |args: &[&str]| {
        let (code, stdout, stderr) = uplift(args);
        assert_eq!(code, 0, "uplift {args:?}:\n{stderr}");
        format!("{stdout}{stderr}")
    };
    let input = repo().join("examples/pbr_materials.mtlx");
    let said = run(&["enhance", s(&input), "--rule", s(&rule), "--engine", "wgpu", "--seed", "9", "--resolution", "8x8", "--mask-size", "32", "-o", s(&out)]);
    assert!(said.contains("enhanced 4 material(s)"), "{said}");
    let ceramic = out.join("ceramic");
    let meta: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(ceramic.join("meta.json")).unwrap()).unwrap();
    assert_eq!(meta["type"], 2, "the rule's uplift_type");
    assert_eq!(meta["rule"].as_str().unwrap(), s(&rule));
    let wetness = meta["scalars"]["wetness"].as_f64().unwrap() as f32;
    let darkening = meta["scalars"]["darkening"].as_f64().unwrap() as f32;
    assert!((0.4..=1.0).contains(&wetness), "wetness {wetness}");
    let params = uplift_base::exr::read(&ceramic.join("params.exr")).unwrap();
    assert!(params.attributes.iter().any(|(k, v)| k == "uplift_rule" && v == "wet"), "{:?}", params.attributes);
    for &c in params.channel("coat_weight").unwrap() {
        assert!((c - wetness).abs() < 1e-6, "coat weight {c}, wetness {wetness}");
    }
    // The ceramic's base colour is constant (examples/pbr_materials.mtlx, its UsdPreviewSurface's
    // diffuseColor 0.8, 0.78, 0.72): diffuse = c^(1 + d·w).
    let base = [0.8f32, 0.78, 0.72];
    for (k, ch) in ["diffuse_color.R", "diffuse_color.G", "diffuse_color.B"].iter().enumerate() {
        let want = base[k].powf(1.0 + darkening * wetness);
        for &v in params.channel(ch).unwrap() {
            assert!((v - want).abs() < 1e-4 * want.max(1e-3) + 1e-6, "{ch} {v}, want {want}");
        }
    }
    match validate(&ceramic.join("material.mtlx")) {
        Some(r) => r.unwrap_or_else(|e| panic!("material.mtlx does not validate: {e}")),
        None => say_validator_skipped(),
    }
    run(&["fit", s(&ceramic), "--steps", "10", "--threads", "2"]);
    let png = dir.join("wet.png");
    run(&["render", s(&ceramic), "--neural", "-o", s(&png), "--size", "16", "--spp", "2", "--threads", "2"]);
    assert!(png.is_file());
}

/// Every way a user rule can break the contract is an error naming the file, line and column:
/// a missing output, a mistyped one, an output the stack does not have, an input that is none
/// of the kinds, a missing `uplift_type`; `--rule` with `--type` is refused by the parser.
#[test]
fn a_user_rule_that_breaks_the_contract_is_a_positioned_error() {
    use crate::common::cli::{repo, s, uplift};
    let dir = crate::common::cli::temp_dir("enhance", "bad_rules");
    let good = std::fs::read_to_string(repo().join("examples/rules/wet.mtlx")).unwrap();
    let line_of = |text: &str, needle: &str| text[..text.find(needle).unwrap()].matches('\n').count() + 1;
    let cases: Vec<(&str, String, String)> = vec![
        ("missing", good.replace("    <output name=\"coat_ior_out\" type=\"float\" nodename=\"coat_ior\" />\n", ""), format!(":{}:3: nodegraph `uplift_rule` has no output `coat_ior_out` (float)", line_of(&good, "<nodegraph"))),
        ("mistyped", good.replace("<output name=\"metalness_out\" type=\"float\"", "<output name=\"metalness_out\" type=\"color3\""), format!(":{}:5: output `metalness_out` is color3; the stack's input takes float", line_of(&good, "<output name=\"metalness_out\""))),
        ("unknown_output", good.replace("<output name=\"bsdf_out\"", "<output name=\"gloss_out\" type=\"float\" nodename=\"coat_weight\" />\n    <output name=\"bsdf_out\""), format!(":{}:5: output `gloss_out` is not an input of uplift_stack", line_of(&good, "<output name=\"bsdf_out\""))),
        ("unknown_input", good.replace("<input name=\"wetness\" type=\"float\" value=\"0.8\" uimin=\"0.4\" uimax=\"1.0\"", "<input name=\"wetness\" type=\"float\" value=\"0.8\""), format!(":{}:5: input `wetness` is neither a PBR input", line_of(&good, "<input name=\"wetness\""))),
        ("untyped", good.replace(" uplift_type=\"2\"", ""), format!(":{}:3: nodegraph `uplift_rule` declares no `uplift_type`", line_of(&good, "<nodegraph"))),
    ];
    for (name, text, want) in &cases {
        let path = dir.join(format!("{name}.mtlx"));
        std::fs::write(&path, text).unwrap();
        let (code, _, stderr) = uplift(&["enhance", s(&repo().join("examples/pbr_materials.mtlx")), "--rule", s(&path), "--engine", "wgpu", "-o", s(&dir.join("out"))]);
        assert_eq!(code, 1, "{name}: {stderr}");
        assert!(stderr.contains(&format!("{}{want}", s(&path))), "{name}: want `{want}` in:\n{stderr}");
    }
    assert!(!dir.join("out").exists(), "nothing written for a broken rule");
    let (code, _, stderr) = uplift(&["enhance", s(&repo().join("examples/pbr_materials.mtlx")), "--rule", s(&repo().join("examples/rules/wet.mtlx")), "--type", "1", "-o", s(&dir.join("out"))]);
    assert_eq!(code, 2, "{stderr}");
}

/// `--rule DIR`: every rule document of the folder, drawn per material by the shares of its
/// `shares.json`; a share naming no rule of the folder, or JSON that does not parse, is an error
/// naming the file (and line and column).
#[test]
fn a_folder_of_rules_runs_with_its_shares() {
    use crate::common::cli::{repo, s, uplift};
    let dir = crate::common::cli::temp_dir("enhance", "rule_folder");
    let rules = dir.join("rules");
    std::fs::create_dir_all(&rules).unwrap();
    let wet = std::fs::read_to_string(repo().join("examples/rules/wet.mtlx")).unwrap();
    std::fs::write(rules.join("wet.mtlx"), &wet).unwrap();
    std::fs::write(rules.join("soaked.mtlx"), wet.replace("uimin=\"0.4\" uimax=\"1.0\" doc=\"How wet", "uimin=\"0.95\" uimax=\"1.0\" doc=\"How wet")).unwrap();
    std::fs::write(rules.join("shares.json"), "{\"wet.mtlx\": 1, \"soaked.mtlx\": 3}").unwrap();
    let out = dir.join("out");
    let input = repo().join("examples/pbr_materials.mtlx");
    let (code, _, stderr) = uplift(&["enhance", s(&input), "--rule", s(&rules), "--engine", "wgpu", "--seed", "4", "--resolution", "4x4", "--mask-size", "16", "-o", s(&out)]);
    assert_eq!(code, 0, "{stderr}");
    for m in ["blue_plastic", "ceramic", "copper", "red_cloth"] {
        let meta: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join(m).join("meta.json")).unwrap()).unwrap();
        let rule = meta["rule"].as_str().unwrap();
        let wetness = meta["scalars"]["wetness"].as_f64().unwrap();
        assert!(rule.ends_with("wet.mtlx") || rule.ends_with("soaked.mtlx"), "{m}: rule {rule}");
        if rule.ends_with("soaked.mtlx") {
            assert!(wetness >= 0.95, "{m}: soaked with wetness {wetness}");
        }
    }
    std::fs::write(rules.join("shares.json"), "{\"wet.mtlx\": 1, \"dry.mtlx\": 1}").unwrap();
    let (code, _, stderr) = uplift(&["enhance", s(&input), "--rule", s(&rules), "--engine", "wgpu", "-o", s(&dir.join("out2"))]);
    assert_eq!(code, 1);
    assert!(stderr.contains("shares.json: `dry.mtlx` is not a rule document of the folder"), "{stderr}");
    std::fs::write(rules.join("shares.json"), "{\"wet.mtlx\": 1,\n \"soaked.mtlx\" 3}").unwrap();
    let (code, _, stderr) = uplift(&["enhance", s(&input), "--rule", s(&rules), "--engine", "wgpu", "-o", s(&dir.join("out2"))]);
    assert_eq!(code, 1);
    assert!(stderr.contains("shares.json:2:"), "{stderr}");
}
