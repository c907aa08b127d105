//! The bodies of the `enhance` fuzz targets, shared by the libFuzzer targets under `fuzz/`
//! (`cargo +nightly fuzz run gltf|rule`) and the stable-Rust runner in CI
//! (`runtime/uplift/tests/integration/fuzz_enhance.rs`): each takes arbitrary bytes and must
//! return without panicking, aborting or hanging. A property that fails panics saying which.
//!
//! - [`gltf`]: a `.gltf` / `.glb` as `uplift enhance` reads it — parsing and validation, buffer
//!   and image URIs (data URIs, percent-encoding, containment), every material's factors and
//!   image bytes, the scene's world triangles and each material's UV-space bake at 16×16.
//! - [`rule`]: a rule document as `uplift enhance --rule FILE` reads it — its `xi:include`s
//!   under the default containment, its interface checked against the builtin stack, its random
//!   scalars drawn for a few seeds; the same text read as a rule option (`--option FILE`).
//!
//! Properties beyond "no panic": every accepted input yields finite values (factors, bake,
//! triangles, draws inside the scalar's range or 0 for a switch-off draw), and nothing is read
//! outside the input's folder. Inputs are written into a private temporary folder
//! (`<tmp>/uplift-fuzz-enhance-<pid>/input/`) beside a folder `outside/` that holds an existing
//! PNG and a buffer (`../outside/secret.png`, `../outside/secret.bin`): an image that resolves
//! outside `input/`, or an input that reads successfully while naming a file outside, fails.

use crate::{gltf_input, rule_option, rules};
use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};
use uplift_base::random_scalar::RandomScalar;
use uplift_engines::stack::Stack;

/// The bake size the glTF target rasterises at.
pub const BAKE_SIZE: usize = 16;

/// The seeds the rule target draws for.
pub const DRAW_SEEDS: std::ops::Range<u64> = 0..4;

/// A 1×1 PNG, the `outside/secret.png` an escaping URI would find.
const SECRET_PNG: &[u8] = &[
    0x89, 0x50, 0x4E, 0x47, 0x0D, 0x0A, 0x1A, 0x0A, 0x00, 0x00, 0x00, 0x0D, 0x49, 0x48, 0x44, 0x52, 0x00, 0x00, 0x00, 0x01, 0x00, 0x00, 0x00, 0x01, 0x08, 0x02, 0x00, 0x00, 0x00, 0x90, 0x77, 0x53,
    0xDE, 0x00, 0x00, 0x00, 0x0C, 0x49, 0x44, 0x41, 0x54, 0x08, 0xD7, 0x63, 0xF8, 0xCF, 0xC0, 0x00, 0x00, 0x03, 0x01, 0x01, 0x00, 0x18, 0xDD, 0x8D, 0xB0, 0x00, 0x00, 0x00, 0x00, 0x49, 0x45, 0x4E,
    0x44, 0xAE, 0x42, 0x60, 0x82,
];

/// The fuzz folder: (`input/`, `outside/`), created once per process.
fn folders() -> &'static (PathBuf, PathBuf) {
    static F: OnceLock<(PathBuf, PathBuf)> = OnceLock::new();
    F.get_or_init(|| {
        let root = std::env::temp_dir().join(format!("uplift-fuzz-enhance-{}", std::process::id()));
        let (input, outside) = (root.join("input"), root.join("outside"));
        std::fs::create_dir_all(&input).expect("fuzz input folder");
        std::fs::create_dir_all(&outside).expect("fuzz outside folder");
        std::fs::write(outside.join("secret.png"), SECRET_PNG).expect("outside/secret.png");
        std::fs::write(outside.join("secret.bin"), [0u8; 4096]).expect("outside/secret.bin");
        // What the seeds name inside the folder: a buffer and an image.
        std::fs::write(input.join("seed.bin"), triangle_bytes()).expect("input/seed.bin");
        std::fs::write(input.join("albedo.png"), SECRET_PNG).expect("input/albedo.png");
        let input = input.canonicalize().expect("fuzz input folder");
        (input, outside)
    })
}

/// One triangle: 3 positions, then 3 texture coordinates (little-endian f32).
fn triangle_bytes() -> Vec<u8> {
    let v: [f32; 15] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0];
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// [`triangle_bytes`] as base64, for a `data:` URI.
const TRIANGLE_BASE64: &str = "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAAAAAAIA/AAAAAAAAAAAAAIA/AAAAAAAAAAAAAIA/";

/// A glTF of the triangle: `buffer` is the buffer's `uri` part (empty: none, the GLB's chunk),
/// `node` the node, `extra` more top-level members (materials, textures, images, samplers).
fn triangle_gltf(buffer: &str, node: &str, material: &str, extra: &str) -> String {
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{node}],"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"TEXCOORD_0":1}},"material":0}}]}}],"materials":[{material}],"buffers":[{{"byteLength":60{buffer}}}],"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":24}}],"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,0,1]}},{{"bufferView":1,"componentType":5126,"count":3,"type":"VEC2"}}]{extra}}}"#
    )
}

/// A GLB holding `json` and the binary chunk `bin`.
fn glb(json: &str, bin: &[u8]) -> Vec<u8> {
    let pad = |n: usize| n.next_multiple_of(4);
    let (j, b) = (pad(json.len()), pad(bin.len()));
    let mut out = Vec::with_capacity(12 + 8 + j + 8 + b);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&((12 + 8 + j + 8 + b) as u32).to_le_bytes());
    out.extend_from_slice(&(j as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(json.as_bytes());
    out.resize(12 + 8 + j, b' ');
    out.extend_from_slice(&(b as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(bin);
    out.resize(12 + 8 + j + 8 + b, 0);
    out
}

/// The glTF target's seeds: the triangle with its buffer in a file, in a `data:` URI and in a
/// GLB chunk; with node transforms (TRS, a matrix, children); with factors and textures (a
/// file image, a percent-encoded name, an image outside the folder, a `data:` image); with a
/// normal texture and its scale.
pub fn gltf_seeds() -> Vec<Vec<u8>> {
    let file = r#","uri":"seed.bin""#;
    let data = format!(r#","uri":"data:application/octet-stream;base64,{TRIANGLE_BASE64}""#);
    let plain = r#"{"mesh":0}"#;
    let unlit = r#"{"name":"m"}"#;
    let textured = r#"{"name":"m","pbrMetallicRoughness":{"baseColorFactor":[0.8,0.5,0.2,1],"metallicFactor":0.3,"roughnessFactor":0.6,"baseColorTexture":{"index":0},"metallicRoughnessTexture":{"index":0}},"normalTexture":{"index":0,"scale":0.5}}"#;
    let images = |uri: &str| format!(r#","textures":[{{"source":0,"sampler":0}}],"samplers":[{{}}],"images":[{{"uri":"{uri}"}}]"#);
    let mut seeds = vec![
        triangle_gltf(file, plain, unlit, ""),
        triangle_gltf(&data, plain, unlit, ""),
        triangle_gltf(file, r#"{"mesh":0,"translation":[1,2,3],"rotation":[0,0.7071068,0,0.7071068],"scale":[2,2,2]}"#, unlit, ""),
        triangle_gltf(file, r#"{"children":[1],"matrix":[1,0,0,0,0,1,0,0,0,0,-1,0,0,0,0,1]},{"mesh":0,"scale":[1,-1,1]}"#, unlit, ""),
        triangle_gltf(file, plain, textured, &images("albedo.png")),
        triangle_gltf(file, plain, textured, &images("albedo%2Epng")),
        triangle_gltf(file, plain, textured, &images("../outside/secret.png")),
        triangle_gltf(r#","uri":"../outside/secret.bin""#, plain, unlit, ""),
    ]
    .into_iter()
    .map(String::into_bytes)
    .collect::<Vec<_>>();
    seeds.push(glb(&triangle_gltf("", plain, unlit, ""), &triangle_bytes()));
    seeds.push(glb(&triangle_gltf("", plain, textured, &images("albedo.png")), &triangle_bytes()));
    seeds
}

/// Writes `data` as `input/<name>` and returns its path.
fn input_file(name: &str, data: &[u8]) -> PathBuf {
    let path = folders().0.join(name);
    std::fs::write(&path, data).expect("writing the fuzz input");
    path
}

fn stack() -> &'static Arc<Stack> {
    static S: OnceLock<Arc<Stack>> = OnceLock::new();
    S.get_or_init(Stack::builtin)
}

/// True when `path` lies inside the input folder (lexically, `..` resolved; symlinks are not
/// made by the fuzzer).
fn inside_input(path: &Path) -> bool {
    let mut parts: Vec<std::path::Component> = Vec::new();
    for c in path.components() {
        match c {
            std::path::Component::ParentDir => {
                parts.pop();
            }
            std::path::Component::CurDir => {}
            c => parts.push(c),
        }
    }
    parts.iter().collect::<PathBuf>().starts_with(&folders().0)
}

fn assert_finite(what: &str, values: impl IntoIterator<Item = f32>) {
    for v in values {
        assert!(v.is_finite(), "an accepted glTF gives a non-finite {what}: {v}");
    }
}

/// A `.gltf` / `.glb` (told apart by the GLB magic, as `gltf_input::load` does).
pub fn gltf(data: &[u8]) {
    let path = input_file("fuzz.gltf", data);
    let Ok(asset) = gltf_input::load(&path) else { return };
    for m in &asset.materials {
        assert_finite("base color factor", m.base_color_factor);
        assert_finite("metallic factor", [m.metallic_factor]);
        assert_finite("roughness factor", [m.roughness_factor]);
        assert_finite("normal scale", [m.normal_scale]);
        for t in [&m.base_color_texture, &m.metallic_roughness_texture, &m.normal_texture].into_iter().flatten() {
            if let gltf_input::ImageSource::File(p) = &t.source {
                assert!(inside_input(p), "an accepted glTF names an image outside its folder: {}", p.display());
            }
            let _ = t.source.bytes();
        }
    }
    for t in asset.world_triangles() {
        assert_finite("world triangle", t.position.iter().chain(&t.normal).chain(&t.tangent).flatten().copied().chain(t.uv.iter().flatten().copied()));
    }
    for index in 0..asset.materials.len().min(4) {
        let Ok(bake) = gltf_input::rasterize_uv(&asset, index, BAKE_SIZE, BAKE_SIZE) else { continue };
        assert_eq!(bake.position.len(), BAKE_SIZE * BAKE_SIZE, "a bake of the wrong size");
        assert_finite("baked position", bake.position.iter().flatten().copied());
        assert_finite("baked normal", bake.normal.iter().flatten().copied());
        assert_finite("baked tangent", bake.tangent.iter().flatten().copied());
        assert_finite("bake bounding box", bake.bbox_min.into_iter().chain(bake.bbox_max));
    }
}

/// Every draw of `random` for [`DRAW_SEEDS`] is finite and inside its range (or 0, the draw of
/// a non-uniform scalar that switches its effect off).
fn assert_draws(what: &str, random: &[RandomScalar]) {
    for r in random {
        assert!(r.min.is_finite() && r.max.is_finite() && r.min <= r.max, "an accepted {what} has scalar `{}` with range {}..{}", r.name, r.min, r.max);
    }
    for seed in DRAW_SEEDS {
        for (r, (name, v)) in random.iter().zip(rules::draw_all(random, seed)) {
            assert!(v.is_finite(), "an accepted {what} draws a non-finite `{name}` for seed {seed}: {v}");
            assert!((r.min..=r.max).contains(&v) || v == 0.0, "an accepted {what} draws `{name}` = {v} outside {}..{} for seed {seed}", r.min, r.max);
        }
    }
}

/// A rule document (`uplift enhance --rule FILE`), and the same text as a rule option.
pub fn rule(data: &[u8]) {
    let path = input_file("fuzz_rule.mtlx", data);
    if let Ok(rule) = rules::interface_file(&path, stack()) {
        assert_draws("rule", &rule.random);
    }
    if let Ok(option) = rule_option::read_option(&path.display().to_string(), stack()) {
        assert_draws("rule option", &option.random);
    }
}
