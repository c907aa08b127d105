//! The PBR materials `uplift enhance` reads, in one form whatever the source:
//! (a) texture files (`--base-color --roughness --metalness [--normal]`, or a folder whose file
//! names say which is which), (b) glTF 2.0 materials (metallicRoughness packed as G = roughness,
//! B = metalness; base color sRGB; factors multiplied in), (c) MaterialX materials whose shader
//! is `gltf_pbr`, `standard_surface`, `open_pbr_surface` or `UsdPreviewSurface`, with constant
//! inputs or inputs connected to an image node (directly, through a `normalmap` for normals, or
//! through a nodegraph output).
//!
//! Colour: every value here is what the rule reads. Constants are linear. Files keep their
//! encoding and name their colour space as MaterialX does (`srgb_texture` for 8-bit base
//! colors, `lin_rec709` otherwise); derived images ([`PbrChannel::Pixels`]) are linear. A float
//! input reads the first channel of its image, as MaterialX's `image` node does.

use crate::gltf_input::{self, GltfAsset};
use uplift_engines::batch::TextureData;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// One PBR input's source.
#[derive(Clone, Debug)]
pub enum PbrChannel {
    /// Linear components (1 or 3).
    Constant(Vec<f32>),
    /// An image file used as it is.
    File { path: PathBuf, colorspace: String },
    /// A derived linear image (from a glTF material: a channel of a packed texture, or a
    /// texture times its factor).
    Pixels(Arc<TextureData>),
}

/// The surface the material's texture space lies on.
#[derive(Clone)]
pub enum Surface {
    /// A unit square in the XZ plane facing +Y (a swatch lying on the ground; texture rows run
    /// along +Z), for materials without geometry.
    Plane,
    /// A glTF material's triangles, rasterised in UV space.
    Gltf { asset: Arc<GltfAsset>, material: usize },
}

impl std::fmt::Debug for Surface {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Surface::Plane => write!(f, "Plane"),
            Surface::Gltf { asset, material } => write!(f, "Gltf({}, material {material})", asset.path.display()),
        }
    }
}

/// A PBR material ready to be enhanced.
#[derive(Clone, Debug)]
pub struct PbrMaterial {
    /// A name usable as a folder name.
    pub name: String,
    /// Where it came from (for meta.json).
    pub source: String,
    pub base_color: PbrChannel,
    pub roughness: PbrChannel,
    pub metalness: PbrChannel,
    pub normal_map: Option<PbrChannel>,
    pub surface: Surface,
}

impl PbrMaterial {
    /// The PBR inputs of the rules ([`super::rules::PBR_INPUTS`]) this material sets.
    pub fn channels(&self) -> Vec<(&'static str, &PbrChannel)> {
        let mut v = vec![("base_color", &self.base_color), ("roughness", &self.roughness), ("metalness", &self.metalness)];
        if let Some(n) = &self.normal_map {
            v.push(("normal_map", n));
        }
        v
    }
}

/// A name made safe for a folder: letters, digits, `-` and `_`.
pub fn safe_name(name: &str) -> String {
    let s: String = name.chars().map(|c| if c.is_ascii_alphanumeric() || c == '-' || c == '_' { c } else { '_' }).collect();
    if s.is_empty() {
        "material".into()
    } else {
        s
    }
}

fn is_image(p: &Path) -> bool {
    matches!(p.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()).as_deref(), Some("png" | "jpg" | "jpeg"))
}

/// Conventional file-name words per input, checked in this order (so `normal` and
/// `roughness` are found before the generic `color`).
const FOLDER_WORDS: [(&str, &[&str]); 4] = [
    ("normal_map", &["normal", "nrm", "nor_gl", "nor"]),
    ("roughness", &["roughness", "rough"]),
    ("metalness", &["metalness", "metallic", "metal"]),
    ("base_color", &["basecolor", "base_color", "albedo", "diffuse", "diff", "color", "col"]),
];

/// Texture files given one by one (a).
pub fn from_files(base_color: &Path, roughness: &Path, metalness: &Path, normal: Option<&Path>, name: &str) -> Result<PbrMaterial, String> {
    for p in [Some(base_color), Some(roughness), Some(metalness), normal].into_iter().flatten() {
        if !p.is_file() {
            return Err(format!("{}: no such texture file", p.display()));
        }
    }
    let file = |p: &Path, cs: &str| PbrChannel::File { path: p.to_path_buf(), colorspace: cs.into() };
    Ok(PbrMaterial {
        name: safe_name(name),
        source: base_color.parent().unwrap_or(Path::new(".")).display().to_string(),
        base_color: file(base_color, "srgb_texture"),
        roughness: file(roughness, "lin_rec709"),
        metalness: file(metalness, "lin_rec709"),
        normal_map: normal.map(|n| file(n, "lin_rec709")),
        surface: Surface::Plane,
    })
}

/// A folder of conventionally named texture files (a); `Ok(None)` when it holds no base color.
pub fn from_folder(dir: &Path) -> Result<Option<PbrMaterial>, String> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| format!("{}: {e}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file() && is_image(p))
        .collect();
    files.sort();
    let mut found: Vec<(&str, PathBuf)> = Vec::new();
    for f in &files {
        let stem = f.file_stem().map(|s| s.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
        let words: Vec<&str> = stem.split(|c: char| !c.is_ascii_alphanumeric() && c != '_').collect();
        let matches = |w: &str| stem.contains(w) && (w.len() > 4 || words.iter().any(|x| x.split('_').any(|p| p == w)));
        if let Some((input, _)) = FOLDER_WORDS.iter().find(|(_, ws)| ws.iter().any(|w| matches(w))) {
            if let Some((_, first)) = found.iter().find(|(i, _)| i == input) {
                return Err(format!("{}: both `{}` and `{}` look like the {input} texture", dir.display(), first.display(), f.display()));
            }
            found.push((input, f.clone()));
        }
    }
    let get = |i: &str| found.iter().find(|(n, _)| *n == i).map(|(_, p)| p.clone());
    let Some(base) = get("base_color") else { return Ok(None) };
    let name = dir.file_name().map(|n| n.to_string_lossy().to_string()).unwrap_or_else(|| "material".into());
    let channel = |i: &str, default: f32| match get(i) {
        Some(p) => PbrChannel::File { path: p, colorspace: "lin_rec709".into() },
        None => PbrChannel::Constant(vec![default]),
    };
    Ok(Some(PbrMaterial {
        name: safe_name(&name),
        source: dir.display().to_string(),
        base_color: PbrChannel::File { path: base, colorspace: "srgb_texture".into() },
        roughness: channel("roughness", 0.5),
        metalness: channel("metalness", 0.0),
        normal_map: get("normal_map").map(|p| PbrChannel::File { path: p, colorspace: "lin_rec709".into() }),
        surface: Surface::Plane,
    }))
}

/// Every material of a glTF asset (b).
pub fn from_gltf(path: &Path, access: &mtlx::FileAccess) -> Result<Vec<PbrMaterial>, String> {
    let asset = Arc::new(gltf_input::load_with(path, access)?);
    let mut out = Vec::new();
    for (k, m) in asset.materials.iter().enumerate() {
        let decode = |t: &gltf_input::TextureRef, what: &str| -> Result<image::Rgba32FImage, String> {
            let bytes = t.source.bytes()?;
            let img = image::load_from_memory(&bytes).map_err(|e| format!("{}: material `{}`: cannot decode the {what} image: {e}", path.display(), m.name))?;
            Ok(img.to_rgba32f())
        };
        let pixels = |img: &image::Rgba32FImage, f: &dyn Fn(&[f32]) -> [f32; 4]| {
            let rgba: Vec<f32> = img.pixels().flat_map(|p| f(&p.0)).collect();
            PbrChannel::Pixels(Arc::new(TextureData { width: img.width(), height: img.height(), rgba }))
        };
        let bf = m.base_color_factor;
        let base_color = match &m.base_color_texture {
            None => PbrChannel::Constant(bf[..3].to_vec()),
            Some(t) => {
                let img = decode(t, "base color")?;
                let lin = uplift_base::color::srgb_to_linear;
                pixels(&img, &|p| [lin(p[0]) * bf[0], lin(p[1]) * bf[1], lin(p[2]) * bf[2], 1.0])
            }
        };
        let (roughness, metalness) = match &m.metallic_roughness_texture {
            None => (PbrChannel::Constant(vec![m.roughness_factor]), PbrChannel::Constant(vec![m.metallic_factor])),
            Some(t) => {
                let img = decode(t, "metallicRoughness")?;
                let (r, mf) = (m.roughness_factor, m.metallic_factor);
                (pixels(&img, &|p| [p[1] * r, p[1] * r, p[1] * r, 1.0]), pixels(&img, &|p| [p[2] * mf, p[2] * mf, p[2] * mf, 1.0]))
            }
        };
        let normal_map = match &m.normal_texture {
            None => None,
            Some(t) => {
                let img = decode(t, "normal")?;
                let s = m.normal_scale;
                // glTF's scale multiplies the decoded X and Y (core spec, normalTextureInfo).
                Some(pixels(&img, &|p| [(p[0] * 2.0 - 1.0) * s * 0.5 + 0.5, (p[1] * 2.0 - 1.0) * s * 0.5 + 0.5, p[2], 1.0]))
            }
        };
        let stem = path.file_stem().map(|s| s.to_string_lossy().to_string()).unwrap_or_default();
        let name = if asset.materials.len() == 1 { stem.clone() } else { format!("{stem}_{}", m.name) };
        out.push(PbrMaterial {
            name: safe_name(&name),
            source: format!("{}#material{k}", path.display()),
            base_color,
            roughness,
            metalness,
            normal_map,
            surface: Surface::Gltf { asset: asset.clone(), material: k },
        });
    }
    if out.is_empty() {
        return Err(format!("{}: the asset has no materials", path.display()));
    }
    Ok(out)
}

/// Shader input names per supported MaterialX shader: base color, roughness, metalness, normal.
const MTLX_SHADERS: [(&str, [&str; 4]); 4] = [
    ("gltf_pbr", ["base_color", "roughness", "metallic", "normal"]),
    ("standard_surface", ["base_color", "specular_roughness", "metalness", "normal"]),
    ("open_pbr_surface", ["base_color", "specular_roughness", "base_metalness", "geometry_normal"]),
    ("UsdPreviewSurface", ["diffuseColor", "roughness", "metallic", "normal"]),
];

/// Every material of a MaterialX document whose shader is a supported PBR shader (c).
pub fn from_mtlx(path: &Path, access: &mtlx::FileAccess) -> Result<Vec<PbrMaterial>, String> {
    let (doc, diags) = mtlx::read_file_with(path, access);
    if let Some(d) = diags.iter().find(|d| d.severity == mtlx::Severity::Error) {
        return Err(d.to_string());
    }
    let root_cs = doc.get(doc.root()).attr("colorspace").map(str::to_string);
    let top = |name: &str| doc.top_level().iter().copied().find(|&id| doc.get(id).name() == name);
    let mut out = Vec::new();
    for &mat in doc.top_level() {
        if doc.get(mat).category != "surfacematerial" {
            continue;
        }
        let Some(shader) = doc
            .children_of(mat, "input")
            .find(|&i| doc.get(i).name() == "surfaceshader")
            .and_then(|i| doc.get(i).attr("nodename"))
            .and_then(|n| top(n))
        else {
            continue;
        };
        let category = doc.get(shader).category.clone();
        let Some((_, names)) = MTLX_SHADERS.iter().find(|(c, _)| *c == category) else {
            let e = doc.get(shader);
            return Err(format!("{}: material `{}` uses `{category}`; supported shaders: gltf_pbr, standard_surface, open_pbr_surface, UsdPreviewSurface", e.pos, doc.get(mat).name()));
        };
        let defaults: [Vec<f32>; 3] = [vec![0.8, 0.8, 0.8], vec![0.5], vec![0.0]];
        let mut channels = Vec::new();
        for (k, input_name) in names.iter().enumerate() {
            let input = doc.children_of(shader, "input").find(|&i| doc.get(i).name() == *input_name);
            let channel = match input {
                None if k < 3 => Some(PbrChannel::Constant(defaults[k].clone())),
                None => None,
                Some(i) => Some(mtlx_channel(&doc, i, (path, access), root_cs.as_deref(), k == 3)?),
            };
            // A constant base color, roughness or metalness is physical: each component in 0..1.
            if let (Some(i), Some(PbrChannel::Constant(v))) = (input, &channel) {
                unit_range(v).map_err(|why| format!("{}: input `{input_name}` {why}", doc.get(i).pos))?;
            }
            channels.push(channel);
        }
        let [base, rough, metal, normal]: [Option<PbrChannel>; 4] = channels.try_into().unwrap();
        let name = doc.get(mat).name().to_string();
        out.push(PbrMaterial {
            name: safe_name(&name),
            source: format!("{}#{name}", path.display()),
            base_color: base.unwrap(),
            roughness: rough.unwrap(),
            metalness: metal.unwrap(),
            normal_map: normal,
            surface: Surface::Plane,
        });
    }
    if out.is_empty() {
        return Err(format!("{}: no surfacematerial with a supported PBR shader", path.display()));
    }
    Ok(out)
}

/// Checks a base color, roughness or metalness: every component in 0..1 (a reflectance, a
/// roughness, a metal fraction; MaterialX's and glTF's documented ranges), else says which.
pub fn unit_range(values: &[f32]) -> Result<(), String> {
    match values.iter().find(|v| !(0.0..=1.0).contains(*v)) {
        None => Ok(()),
        Some(v) => Err(format!("`{v}` is outside 0..1 (a physical base color, roughness and metalness lie in 0..1)")),
    }
}

/// A shader input as a channel: its value, or the image it is connected to.
fn mtlx_channel(doc: &mtlx::Document, input: mtlx::ElementId, (top, access): (&Path, &mtlx::FileAccess), root_cs: Option<&str>, normal: bool) -> Result<PbrChannel, String> {
    let e = doc.get(input);
    let pos = e.pos.clone();
    let mut node = match (e.attr("nodename"), e.attr("nodegraph")) {
        (Some(n), _) => doc.top_level().iter().copied().find(|&id| doc.get(id).name() == n),
        (None, Some(g)) => {
            let graph = doc.top_level().iter().copied().find(|&id| doc.get(id).name() == g);
            let output = e.attr("output").unwrap_or("out");
            graph
                .and_then(|g| doc.children_of(g, "output").find(|&o| doc.get(o).name() == output).map(|o| (g, o)))
                .and_then(|(g, o)| doc.get(o).attr("nodename").and_then(|n| doc.children(g).iter().copied().find(|&c| doc.get(c).name() == n)))
        }
        (None, None) => {
            if normal {
                return Err(format!("{pos}: a constant normal is not a normal map; leave the input unset"));
            }
            let v = e.attr("value").ok_or_else(|| format!("{pos}: input `{}` has neither a value nor a connection", e.name()))?;
            // The document's value rules (MaterialX's): finite numbers, as many as the type has.
            let ty = mtlx::DataType::from_name(e.attr("type").unwrap_or("float"));
            return match mtlx::Value::parse(&ty, v) {
                Ok(mtlx::Value::Floats(f)) => Ok(PbrChannel::Constant(f)),
                Ok(_) => Err(format!("{pos}: input `{}` has type `{}`, not a number, vector or color", e.name(), ty.name())),
                Err(why) => Err(format!("{pos}: input `{}`: {why}", e.name())),
            };
        }
    }
    .ok_or_else(|| format!("{pos}: input `{}`: the node it connects to is not in the document", e.name()))?;
    if normal && doc.get(node).category == "normalmap" {
        let parent = doc.get(node).parent;
        let inner = doc.children_of(node, "input").find(|&i| doc.get(i).name() == "in").and_then(|i| doc.get(i).attr("nodename"));
        node = inner
            .and_then(|n| parent.and_then(|p| doc.children(p).iter().copied().find(|&c| doc.get(c).name() == n)))
            .ok_or_else(|| format!("{}: normalmap without an image on `in`", doc.get(node).pos))?;
    }
    let n = doc.get(node);
    if !matches!(n.category.as_str(), "image" | "tiledimage" | "gltf_image" | "gltf_normalmap" | "UsdUVTexture") {
        return Err(format!("{}: `{}` is connected to a `{}` node; uplift reads constants and image nodes only", pos, e.name(), n.category));
    }
    let file = doc
        .children_of(node, "input")
        .find(|&i| doc.get(i).name() == "file")
        .ok_or_else(|| format!("{}: image node `{}` has no `file` input", n.pos, n.name()))?;
    let f = doc.get(file);
    let value = f.attr("value").unwrap_or("");
    let prefix = ancestors_attr(doc, file, "fileprefix").unwrap_or_default();
    // The one path rule (mtlx::file_access), before looking for the file: the same message
    // for a name outside whether or not a file is there.
    let path = access.resolve(&format!("{prefix}{value}"), Path::new(&*f.pos.file), top).map_err(|outside| format!("{}: texture {outside}", f.pos))?;
    if !path.is_file() {
        return Err(format!("{}: texture `{}` not found", f.pos, path.display()));
    }
    let colorspace = f
        .attr("colorspace")
        .map(str::to_string)
        .or_else(|| ancestors_attr(doc, file, "colorspace"))
        .or(root_cs.map(str::to_string))
        .unwrap_or_else(|| "lin_rec709".into());
    Ok(PbrChannel::File { path, colorspace })
}

fn ancestors_attr(doc: &mtlx::Document, mut id: mtlx::ElementId, name: &str) -> Option<String> {
    loop {
        if let Some(v) = doc.get(id).attr(name) {
            return Some(v.to_string());
        }
        id = doc.get(id).parent?;
    }
}

/// The materials an input path holds: a glTF or MaterialX file, a folder of textures, or a
/// folder of those (batch).
/// The files they name lie where `access` allows (`--library`, `--allow-any-path`).
pub fn discover(path: &Path, access: &mtlx::FileAccess) -> Result<Vec<PbrMaterial>, String> {
    let ext = path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase());
    if path.is_file() {
        return match ext.as_deref() {
            Some("gltf" | "glb") => from_gltf(path, access),
            Some("mtlx") => from_mtlx(path, access),
            _ => Err(format!("{}: not a .gltf, .glb or .mtlx file (texture files go with --base-color, --roughness, --metalness)", path.display())),
        };
    }
    if !path.is_dir() {
        return Err(format!("{}: no such file or folder", path.display()));
    }
    if let Some(m) = from_folder(path)? {
        return Ok(vec![m]);
    }
    let mut entries: Vec<PathBuf> = std::fs::read_dir(path).map_err(|e| format!("{}: {e}", path.display()))?.filter_map(|e| e.ok().map(|e| e.path())).collect();
    entries.sort();
    let mut out = Vec::new();
    for e in entries {
        let ext = e.extension().and_then(|x| x.to_str()).map(|x| x.to_ascii_lowercase());
        if e.is_dir() {
            if let Some(m) = from_folder(&e)? {
                out.push(m);
            }
        } else if matches!(ext.as_deref(), Some("gltf" | "glb" | "mtlx")) {
            out.extend(discover(&e, access)?);
        }
    }
    if out.is_empty() {
        return Err(format!("{}: no materials (texture folders with a base color, .gltf, .glb or .mtlx files)", path.display()));
    }
    Ok(out)
}
