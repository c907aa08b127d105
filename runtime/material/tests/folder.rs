//! The material folder: files written before the crate split (the fixture `fixtures/v0_type1`,
//! written by the previous `uplift enhance` and `uplift fit`: meta.json and fit.json without a
//! format field, params.exr and latent.exr from the previous EXR writer) read back with the same
//! values; what this build writes reads back equal; a missing, foreign or newer folder is a clear
//! error naming it.

use std::path::{Path, PathBuf};
use uplift_engines::stack::Stack;
use uplift_material::fit_record::FIT_FORMAT;
use uplift_material::folder::{find_material_folders, LATENTS};
use uplift_material::meta::META_FORMAT;
use uplift_material::{LatentImage, MaterialFolder, NormalSpace};

fn fixture() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/v0_type1")
}

fn temp(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("material_{name}"));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// FNV-1a over the values' bit patterns: equal hashes mean bit-identical values.
fn bits_hash(values: &[f32]) -> u64 {
    values.iter().flat_map(|v| v.to_bits().to_le_bytes()).fold(0xcbf2_9ce4_8422_2325u64, |h, b| (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3))
}

#[test]
fn files_written_before_the_split_read_back_identically() {
    let folder = MaterialFolder::open(fixture()).unwrap();
    let meta = folder.read_meta().unwrap();
    assert_eq!(meta.format, 0, "the fixture predates the format field");
    assert_eq!((meta.kind, meta.seed, meta.resolution), (1, 3, [8, 6]));
    assert_eq!(meta.rule, "mtlx/rules/type1_dust.mtlx");
    assert_eq!(meta.normal_space, NormalSpace::Plane);
    // The fixture's stored value (which is √2 in f32).
    assert_eq!(meta.object_size, std::f32::consts::SQRT_2);
    assert_eq!(meta.scalars.len(), 11);
    assert_eq!(meta.scalars.get_index(0).map(|(k, v)| (k.as_str(), *v)), Some(("core_exponent", 2.960_961_3)));
    assert_eq!(meta.scalars["dust_amount"], 0.495_959_43);
    assert_eq!(meta.masks["dust_mask"].file, "masks/dust.png");
    assert_eq!(meta.masks["dust_mask"].seed, 18_397_942_423_386_196_113);

    let fit = folder.read_fit().unwrap();
    assert_eq!((fit.format, fit.texels, fit.groups, fit.steps, fit.directions, fit.levels), (0, 48, 22, 2, 8, 16));
    assert_eq!(fit.seconds, 0.15);
    assert_eq!((fit.eq3_encoder_only.total, fit.eq3_encoder_only.t), (0.029662, 0.092147));
    assert_eq!(fit.eq3_fitted.total, 0.035546);
    let e = fit.energy_bound.unwrap();
    assert_eq!((e.groups, e.over_before, e.over_after, e.worst_excess_before, e.steps), (22, 0, 0, -0.26712, 0));

    // Pixel values: hashes of what the previous codec read from these files.
    let p = folder.read_params(&uplift_engines::stack::Stack::builtin()).unwrap();
    let stack = Stack::builtin();
    let np = stack.len();
    assert_eq!((p.width, p.height, p.params.len()), (8, 6, 48 * np));
    assert!(p.normals.is_some() && p.diffuse.is_some());
    // The file predates the optional inputs (the coat's thin film): they read as their nodedef
    // values, and the others are what the previous codec read.
    let optional = |k: usize| stack.inputs().iter().any(|i| i.optional && i.name == stack.parameters()[k].input);
    let stored: Vec<f32> = (0..48).flat_map(|t| (0..np).filter(|&k| !optional(k)).map(move |k| (t, k))).map(|(t, k)| p.params[t * np + k]).collect();
    assert_eq!(stored.len(), 48 * 22);
    assert!((0..48).all(|t| (0..np).filter(|&k| optional(k)).all(|k| p.params[t * np + k] == stack.parameters()[k].default)));
    assert_eq!(bits_hash(&stored), PARAMS_HASH, "params");
    assert_eq!(bits_hash(p.diffuse.as_ref().unwrap()), DIFFUSE_HASH, "diffuse");
    let l = folder.read_latents().unwrap();
    assert_eq!((l.width, l.height, l.latents.len()), (8, 6, 48 * LATENTS));
    assert_eq!(bits_hash(&l.latents), LATENT_HASH, "latents");
    // The parameters are in the table's order: Type 1 lays dust (the fuzz lobe) somewhere, with
    // weights in [0, 1].
    let fuzz = stack.index_of("fuzz_weight").expect("a fuzz weight");
    let weights: Vec<f32> = (0..48).map(|t| p.params[t * np + fuzz]).collect();
    assert!(weights.iter().all(|w| (0.0..=1.0).contains(w)) && weights.iter().any(|&w| w > 0.0), "{weights:?}");
}

// What the previous (hand-written) EXR codec read from the fixture, before the `exr` crate.
const PARAMS_HASH: u64 = 0x2f1d_c540_7ae6_8380;
const DIFFUSE_HASH: u64 = 0x3868_d2d5_ffac_2d43;
const LATENT_HASH: u64 = 0x4081_11f6_adc1_5c31;

#[test]
fn what_this_build_writes_reads_back_equal() {
    let dir = temp("roundtrip");
    let old = MaterialFolder::open(fixture()).unwrap();
    for f in ["params.exr"] {
        std::fs::copy(fixture().join(f), dir.join(f)).unwrap();
    }
    let folder = MaterialFolder::open(&dir).unwrap();
    let meta = old.read_meta().unwrap();
    folder.write_meta(&meta).unwrap();
    let back = folder.read_meta().unwrap();
    assert_eq!(back.format, META_FORMAT);
    assert_eq!(back, uplift_material::Meta { format: META_FORMAT, ..meta });
    let text = std::fs::read_to_string(folder.meta_path()).unwrap();
    assert!(text.contains("\"type\": 1,") && text.contains("\"normal_space\": \"plane\""), "{text}");
    // Maps keep the rule's order.
    assert!(text.find("core_exponent").unwrap() < text.find("dust_frequency").unwrap());

    let fit = old.read_fit().unwrap();
    folder.write_fit(&fit).unwrap();
    assert_eq!(folder.read_fit().unwrap(), uplift_material::FitRecord { format: FIT_FORMAT, ..fit });

    // A latent of 8 (a wider decoder's): a third texture's R and G, its B 0 in the PNG.
    let wide = LatentImage { width: 3, height: 2, channels: 8, latents: (0..48).map(|k| k as f32 / 47.0).collect() };
    folder.write_latents(&wide).unwrap();
    assert_eq!(folder.read_latents().unwrap(), wide);
    let png = image::open(dir.join("latent2.png")).unwrap().to_rgb8();
    // Texel (2, 1) = 5, latent2.G = value 5·8 + 7 = 47/47 → 255; its B → 0.
    assert_eq!((png.get_pixel(2, 1)[1], png.get_pixel(2, 1)[2]), (255, 0));
    // The paper's 6 over it: latent2.png, now stale, is removed.
    let latents = LatentImage { width: 3, height: 2, channels: LATENTS, latents: (0..36).map(|k| k as f32 / 35.0 - 0.25).collect() };
    folder.write_latents(&latents).unwrap();
    assert_eq!(folder.read_latents().unwrap(), latents);
    assert!(!dir.join("latent2.png").exists());
    let png = image::open(dir.join("latent1.png")).unwrap().to_rgb8();
    // Texel (1, 0), latent1.G = value 1·6 + 4 = 10/35 − 0.25 → 0.0357 → 9 of 255.
    assert_eq!(png.get_pixel(1, 0)[1], ((10.0f32 / 35.0 - 0.25) * 255.0).round() as u8);
    // A gap in the channels is an error naming the missing one.
    let mut gap = uplift_base::exr::ExrImage::new(1, 1);
    for c in (0..6).chain([7]) {
        gap.push(&uplift_material::folder::latent_channel(c), vec![0.5]).unwrap();
    }
    uplift_base::exr::write(&folder.latent_path(), &gap, uplift_base::exr::Compression::Zip).unwrap();
    let e = folder.read_latents().unwrap_err();
    assert!(e.contains("latent.exr") && e.contains("`latent2.G` without `latent2.R`"), "{e}");
    folder.write_latents(&latents).unwrap();
    assert!(folder.has_fit());
    assert!(std::fs::read_dir(&dir).unwrap().all(|e| !e.unwrap().file_name().to_string_lossy().ends_with(".tmp")), "no temporary files left");
}

#[test]
fn missing_foreign_and_newer_folders_are_clear_errors() {
    let root = temp("errors");
    let missing = root.join("nope");
    let e = MaterialFolder::open(&missing).unwrap_err();
    assert!(e.contains("nope") && e.contains("no such folder"), "{e}");
    let file = root.join("file.txt");
    std::fs::write(&file, "x").unwrap();
    let e = MaterialFolder::open(&file).unwrap_err();
    assert!(e.contains("not a folder"), "{e}");
    let foreign = root.join("photos");
    std::fs::create_dir_all(&foreign).unwrap();
    std::fs::write(foreign.join("a.png"), "x").unwrap();
    let e = MaterialFolder::open(&foreign).unwrap_err();
    assert!(e.contains("photos") && e.contains("not an enhanced material") && e.contains("params.exr"), "{e}");
    let e = find_material_folders(&[foreign.clone()]).unwrap_err();
    assert!(e.contains("neither an enhanced material"), "{e}");

    let newer = root.join("newer");
    std::fs::create_dir_all(&newer).unwrap();
    std::fs::copy(fixture().join("params.exr"), newer.join("params.exr")).unwrap();
    let text = std::fs::read_to_string(fixture().join("meta.json")).unwrap().replacen('{', "{\n  \"format\": 99,", 1);
    std::fs::write(newer.join("meta.json"), text).unwrap();
    let e = MaterialFolder::open(&newer).unwrap_err();
    assert!(e.contains("meta.json") && e.contains("format 99") && e.contains("newer uplift"), "{e}");

    let broken = root.join("broken");
    std::fs::create_dir_all(&broken).unwrap();
    std::fs::copy(fixture().join("params.exr"), broken.join("params.exr")).unwrap();
    std::fs::write(broken.join("meta.json"), "{\n  \"type\": \"one\"\n}\n").unwrap();
    let e = MaterialFolder::open(&broken).unwrap_err();
    assert!(e.contains("meta.json:2:"), "the error names the line: {e}");
    // A folder of materials is found; one material is itself.
    assert_eq!(find_material_folders(&[fixture()]).unwrap(), vec![fixture()]);
    assert_eq!(find_material_folders(&[root.clone()]).unwrap(), vec![root.join("broken"), root.join("newer")]);
}
