//! glTF input for `uplift enhance`: loading a `.gltf` / `.glb` asset's materials (factors and
//! texture references) and baking, per material, the surface each texel of its texture space
//! sees (world position, normal, tangent) by rasterising the material's triangles in UV space.
//!
//! Loading ([`load`]): the JSON is parsed and index-validated by the `gltf` crate; buffers
//! come from the GLB binary chunk, `data:` base64 URIs or files relative to the `.gltf`
//! (percent-decoded). Accessors are read here with bounds checks: any component type, with
//! `normalized` honoured (so KHR_mesh_quantization-style integer attributes and normalized
//! u8/u16 UVs work) and `byteStride` honoured; POSITION's min/max are not required. Every
//! primitive of every mesh is decoded at load. Rejected, with an error naming the file
//! and the item: unreadable file, bad JSON or GLB framing, glTF validation failures, missing
//! or short buffers, accessors reaching past their bufferView or buffer, sparse accessors,
//! primitive modes POINTS / LINES / LINE_LOOP / LINE_STRIP (strips and fans are accepted),
//! out-of-range indices, attributes whose count differs from POSITION's, `extensionsRequired`
//! other than KHR_mesh_quantization / KHR_texture_transform (Draco, meshopt, ...),
//! KHR_texture_transform on a base color, metallic-roughness or normal texture, those
//! textures with texCoord != 0, images that are not PNG or JPEG, node hierarchies deeper than
//! 256 levels or with over 2^20 node visits (cycles). Ignored: skins, morph targets, cameras,
//! lights, animations, samplers (baking assumes REPEAT wrapping) and material extensions.
//! Image files are not read at load ([`ImageSource::bytes`] does).
//!
//! UV-space conventions of [`rasterize_uv`]: bakes are row-major with row 0 at the top of the
//! image; glTF UV (0,0) is the image's top-left, so texel (x, y) sees
//! uv = ((x+0.5)/W, (y+0.5)/H) with no V flip. Only TEXCOORD_0 is used. UVs outside [0,1]
//! wrap (REPEAT): a triangle covers every texel whose centre, shifted by whole tiles, lies in
//! it; a triangle spanning more than 16 tiles is an error. Coverage is an edge-function test at
//! texel centres with a top-left tie rule (a texel centre on an edge shared by two triangles
//! belongs to exactly one); attributes are interpolated affinely. Where triangles overlap in UV
//! the last one drawn wins. Drawing order: scene traversal (the default scene, else every scene
//! in order, else every root node; depth first, children in order), then primitives, then
//! triangles, so of several instances of a mesh the later one wins. Positions, normals and
//! tangents are world space: node transforms composed, normals through the inverse transpose,
//! flat face normals where NORMAL is absent (flipped under mirroring transforms, per glTF's
//! winding rule), tangents from TANGENT.xyz through the node matrix, else the triangle's dP/du,
//! orthogonalised against the normal. Dilation: up to 16 passes, each giving every empty texel
//! the value of its first filled 8-neighbour (edge neighbours before diagonals; no wrap at the
//! image border); texels still empty get position = bbox centre, normal = +Y, tangent = +X.
//! `covered` is coverage before dilation. Rasterisation is sequential and a dilation pass reads
//! only the previous pass, so the output is deterministic.

use glam::{DMat3, DMat4, DQuat, DVec2, DVec3};
use gltf::json;
use rayon::prelude::*;
use std::ops::Range;
use mtlx::{FileAccess, UriTarget};
use std::path::{Path, PathBuf};

/// The largest world coordinate a vertex may have (metres: 10⁹ m, far past any scene, where
/// f32 squares still stay finite).
pub const WORLD_LIMIT: f64 = 1e9;

/// A loaded glTF asset: its materials and the decoded, instanced geometry.
#[derive(Debug)]
pub struct GltfAsset {
    pub path: PathBuf,
    pub materials: Vec<GltfMaterial>,
    prims: Vec<Prim>,
    /// (index into `prims`, world matrix), in drawing order.
    instances: Vec<(usize, DMat4)>,
}

#[derive(Clone, Debug, PartialEq)]
pub struct GltfMaterial {
    pub index: usize,
    /// glTF name, or `material_<index>`.
    pub name: String,
    /// Linear, as in glTF.
    pub base_color_factor: [f32; 4],
    pub metallic_factor: f32,
    pub roughness_factor: f32,
    /// sRGB-encoded RGB(A).
    pub base_color_texture: Option<TextureRef>,
    /// Linear: G = roughness, B = metalness.
    pub metallic_roughness_texture: Option<TextureRef>,
    pub normal_texture: Option<TextureRef>,
    pub normal_scale: f32,
}

#[derive(Clone, Debug, PartialEq)]
pub struct TextureRef {
    /// glTF image index.
    pub image: usize,
    pub source: ImageSource,
    /// Always 0 (other sets are rejected at load).
    pub tex_coord: u32,
}

#[derive(Clone, Debug, PartialEq)]
pub enum ImageSource {
    /// The `.gltf`'s directory joined with the percent-decoded URI.
    File(PathBuf),
    /// From a bufferView or a `data:` URI.
    Embedded { bytes: Vec<u8>, mime: String },
}

impl ImageSource {
    pub fn bytes(&self) -> Result<Vec<u8>, String> {
        match self {
            ImageSource::File(p) => std::fs::read(p).map_err(|e| format!("{}: cannot read image: {e}", p.display())),
            ImageSource::Embedded { bytes, .. } => Ok(bytes.clone()),
        }
    }

    /// "png" or "jpg".
    pub fn extension(&self) -> &'static str {
        image_ext(self).unwrap_or("png")
    }
}

fn image_ext(s: &ImageSource) -> Option<&'static str> {
    let by_name = |n: &str| match n.to_ascii_lowercase().as_str() {
        "png" | "image/png" => Some("png"),
        "jpg" | "jpeg" | "image/jpeg" | "image/jpg" => Some("jpg"),
        _ => None,
    };
    match s {
        ImageSource::File(p) => by_name(p.extension()?.to_str()?),
        ImageSource::Embedded { bytes, mime } => by_name(mime)
            .or(bytes.starts_with(b"\x89PNG").then_some("png"))
            .or(bytes.starts_with(&[0xFF, 0xD8]).then_some("jpg")),
    }
}

/// World-space surface seen by each texel of a material's texture space (see module doc).
#[derive(Clone, Debug, PartialEq)]
pub struct SurfaceBake {
    pub width: usize,
    pub height: usize,
    /// Texel centre inside some triangle of this material (before dilation).
    pub covered: Vec<bool>,
    pub position: Vec<[f32; 3]>,
    pub normal: Vec<[f32; 3]>,
    pub tangent: Vec<[f32; 3]>,
    pub bbox_min: [f32; 3],
    pub bbox_max: [f32; 3],
}

/// One world-space triangle of the scene, for rendering (render/mesh.rs): vertex positions,
/// normals (NORMAL through the inverse transpose, else the face normal), tangents (TANGENT.xyz
/// through the node matrix, else the face's dP/du) and TEXCOORD_0 (glTF convention: (0, 0) at
/// the image's top-left; (0, 0) where absent) — the conventions of [`rasterize_uv`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WorldTriangle {
    pub position: [[f32; 3]; 3],
    pub normal: [[f32; 3]; 3],
    pub tangent: [[f32; 3]; 3],
    pub uv: [[f32; 2]; 3],
}

/// One decoded primitive (object space; `tan` is TANGENT.xyz).
#[derive(Debug)]
struct Prim {
    mesh: usize,
    prim: usize,
    material: Option<usize>,
    pos: Vec<DVec3>,
    nrm: Option<Vec<DVec3>>,
    tan: Option<Vec<DVec3>>,
    uv: Option<Vec<DVec2>>,
    tris: Vec<[usize; 3]>,
}

impl GltfAsset {
    /// Every instanced triangle of the scene in world space, in drawing order (degenerate ones
    /// skipped).
    pub fn world_triangles(&self) -> Vec<WorldTriangle> {
        let f32s = |v: DVec3| v.as_vec3().to_array();
        let mut out = Vec::new();
        for &(pi, m) in &self.instances {
            let p = &self.prims[pi];
            let m3 = DMat3::from_mat4(m);
            let (nmat, flip) = (m3.inverse().transpose(), m3.determinant() < 0.0);
            for &[a, b, c] in &p.tris {
                let wp = [a, b, c].map(|i| m.transform_point3(p.pos[i]));
                let uv = [a, b, c].map(|i| p.uv.as_ref().map_or(DVec2::ZERO, |uv| uv[i]));
                let (e1, e2, d1, d2) = (wp[1] - wp[0], wp[2] - wp[0], uv[1] - uv[0], uv[2] - uv[0]);
                let face_n = e1.cross(e2).normalize_or_zero() * if flip { -1.0 } else { 1.0 };
                if face_n == DVec3::ZERO || !wp.iter().all(|v| v.is_finite()) {
                    continue;
                }
                let det = d1.perp_dot(d2);
                let face_t = if det != 0.0 { ((e1 * d2.y - e2 * d1.y) / det).normalize_or_zero() } else { DVec3::ZERO };
                let face_t = if face_t == DVec3::ZERO || !face_t.is_finite() { face_n.any_orthonormal_vector() } else { face_t };
                let normal = [a, b, c].map(|i| p.nrm.as_ref().map(|n| (nmat * n[i]).normalize_or_zero()).filter(|n| *n != DVec3::ZERO && n.is_finite()).unwrap_or(face_n));
                let tangent = [a, b, c].map(|i| p.tan.as_ref().map(|t| m3 * t[i]).filter(|t| t.length_squared() > 0.0 && t.is_finite()).unwrap_or(face_t));
                out.push(WorldTriangle { position: wp.map(f32s), normal: normal.map(f32s), tangent: tangent.map(f32s), uv: uv.map(|v| [v.x as f32, v.y as f32]) });
            }
        }
        out
    }
}

/// Loads a `.gltf` or `.glb` (told apart by the GLB magic, not the extension); the files its
/// URIs name lie in its folder ([`load_with`] the default `mtlx::FileAccess`).
pub fn load(path: &Path) -> Result<GltfAsset, String> {
    load_with(path, &FileAccess::default())
}

/// [`load`], with the files its buffer and image URIs name where `access` allows
/// (`mtlx::file_access`: percent-decoded, `data:` URIs read in place; a URI outside is refused
/// before anything is read, with the same message whether or not the file exists).
pub fn load_with(path: &Path, access: &FileAccess) -> Result<GltfAsset, String> {
    load_inner(path, access).map_err(|e| format!("{}: {e}", path.display()))
}

fn load_inner(path: &Path, access: &FileAccess) -> Result<GltfAsset, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("cannot read: {e}"))?;
    let (text, bin) = match bytes.starts_with(b"glTF") {
        true => split_glb(&bytes)?,
        false => (bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(&bytes), None),
    };
    let value: json::Value = json::deserialize::from_slice(text).map_err(|e| format!("invalid JSON: {e}"))?;
    for (i, m) in value.get("materials").and_then(json::Value::as_array).into_iter().flatten().enumerate() {
        for t in ["/pbrMetallicRoughness/baseColorTexture", "/pbrMetallicRoughness/metallicRoughnessTexture", "/normalTexture"] {
            if m.pointer(&format!("{t}/extensions/KHR_texture_transform")).is_some() {
                return Err(format!("material {i} {t}: KHR_texture_transform is not supported"));
            }
        }
    }
    let mut root: json::Root = json::deserialize::from_value(value).map_err(|e| format!("invalid glTF: {e}"))?;
    root.extensions_required.retain(|e| e != "KHR_mesh_quantization" && e != "KHR_texture_transform");
    if !root.extensions_required.is_empty() {
        let list = root.extensions_required.join(", ");
        return Err(format!("requires unsupported extension(s) {list} (KHR_mesh_quantization and KHR_texture_transform are allowed)"));
    }
    // gltf-json's validator indexes POSITION's accessor unchecked (check it first) and insists
    // on its min/max, which are not used here (fill them in).
    for (mi, m) in root.meshes.iter().enumerate() {
        for (pi, p) in m.primitives.iter().enumerate() {
            let pos = p.attributes.get(&json::validation::Checked::Valid(json::mesh::Semantic::Positions));
            let acc = pos.and_then(|a| root.accessors.get_mut(a.value())).ok_or_else(|| format!("mesh {mi} primitive {pi}: POSITION missing or out of range"))?;
            for v in [&mut acc.min, &mut acc.max] {
                v.get_or_insert(json::Value::Array(vec![0.into(); 3]));
            }
        }
    }
    let doc = gltf::Document::from_json(root).map_err(|e| match e {
        gltf::Error::Validation(errs) => {
            let list: Vec<String> = errs.iter().take(5).map(|(p, e)| format!("{p}: {e}")).collect();
            format!("invalid glTF: {}", list.join("; "))
        }
        e => format!("invalid glTF: {e}"),
    })?;
    let mut bufs = Vec::new();
    for b in doc.buffers() {
        let data = match b.source() {
            gltf::buffer::Source::Bin => bin.ok_or_else(|| format!("buffer {} has no uri and no GLB chunk", b.index()))?.to_vec(),
            gltf::buffer::Source::Uri(uri) => read_uri(path, access, uri).map_err(|e| format!("buffer {}: {e}", b.index()))?.1,
        };
        if data.len() < b.length() {
            let (i, n, l) = (b.index(), data.len(), b.length());
            return Err(format!("buffer {i} has {n} bytes but byteLength is {l}"));
        }
        bufs.push(data);
    }

    let image = |i: usize| -> Result<ImageSource, String> {
        let img = &doc.as_json().images[i];
        let src = match (img.buffer_view, &img.uri) {
            (Some(v), _) => {
                let view = doc.views().nth(v.value()).ok_or("bad bufferView")?;
                let mime = img.mime_type.as_ref().map_or(String::new(), |m| m.0.clone());
                ImageSource::Embedded { bytes: view_bytes(&bufs, &view)?.to_vec(), mime }
            }
            (None, Some(uri)) => match access.resolve_uri(uri, path, path).map_err(|e| format!("image {i}: {e}"))? {
                UriTarget::Data(_) => {
                    let (mime, bytes) = read_uri(path, access, uri)?;
                    ImageSource::Embedded { bytes, mime }
                }
                UriTarget::File(file) => ImageSource::File(file),
            },
            (None, None) => return Err(format!("image {i} has neither uri nor bufferView")),
        };
        image_ext(&src).ok_or_else(|| format!("image {i} is not PNG or JPEG"))?;
        Ok(src)
    };
    let mut materials = Vec::new();
    for m in doc.materials() {
        let index = materials.len();
        let name = m.name().map_or_else(|| format!("material_{index}"), str::to_string);
        let tref = |tex: Option<(gltf::Texture, u32)>, what: &str| -> Result<Option<TextureRef>, String> {
            let Some((t, set)) = tex else { return Ok(None) };
            let ctx = |e: String| format!("material {index} ({name}) {what}: {e}");
            if set != 0 {
                return Err(ctx(format!("uses TEXCOORD_{set}; only TEXCOORD_0 is supported")));
            }
            let img = t.source().index();
            Ok(Some(TextureRef { image: img, source: image(img).map_err(ctx)?, tex_coord: 0 }))
        };
        let (pbr, normal) = (m.pbr_metallic_roughness(), m.normal_texture());
        fn info(t: gltf::texture::Info) -> (gltf::Texture, u32) {
            (t.texture(), t.tex_coord())
        }
        let base_color_texture = tref(pbr.base_color_texture().map(info), "baseColorTexture")?;
        let metallic_roughness_texture = tref(pbr.metallic_roughness_texture().map(info), "metallicRoughnessTexture")?;
        let normal_texture = tref(normal.as_ref().map(|n| (n.texture(), n.tex_coord())), "normalTexture")?;
        let (base_color_factor, metallic_factor, roughness_factor) = (pbr.base_color_factor(), pbr.metallic_factor(), pbr.roughness_factor());
        let normal_scale = normal.as_ref().map_or(1.0, |n| n.scale());
        // Factors are checked where they enter (glTF 2.0: each in 0..1; a JSON number past f32
        // reads as inf), naming the material.
        let factors: [(&str, &[f32]); 3] = [
            ("pbrMetallicRoughness.baseColorFactor", &base_color_factor[..]),
            ("pbrMetallicRoughness.roughnessFactor", std::slice::from_ref(&roughness_factor)),
            ("pbrMetallicRoughness.metallicFactor", std::slice::from_ref(&metallic_factor)),
        ];
        for (what, values) in factors {
            crate::pbr_input::unit_range(values).map_err(|why| format!("materials[{index}] (`{name}`): {what} {why}"))?;
        }
        if !normal_scale.is_finite() {
            return Err(format!("materials[{index}] (`{name}`): normalTexture.scale {normal_scale} is not a finite number"));
        }
        materials.push(GltfMaterial { index, name, base_color_factor, metallic_factor, roughness_factor, base_color_texture, metallic_roughness_texture, normal_texture, normal_scale });
    }

    let (mut prims, mut mesh_prims) = (Vec::new(), Vec::new());
    for mesh in doc.meshes() {
        let first = prims.len();
        for p in mesh.primitives() {
            let ctx = |e: String| format!("mesh {} primitive {}: {e}", mesh.index(), p.index());
            prims.push(decode_prim(&p, mesh.index(), &bufs).map_err(ctx)?);
        }
        mesh_prims.push(first..prims.len());
    }
    let roots: Vec<gltf::Node> = match doc.default_scene() {
        Some(s) => s.nodes().collect(),
        None if doc.scenes().len() > 0 => doc.scenes().flat_map(|s| s.nodes()).collect(),
        None => {
            let mut child = vec![false; doc.nodes().len()];
            doc.nodes().flat_map(|n| n.children()).for_each(|c| child[c.index()] = true);
            doc.nodes().filter(|n| !child[n.index()]).collect()
        }
    };
    let (mut instances, mut visits) = (Vec::new(), 0);
    for n in &roots {
        visit(n, DMat4::IDENTITY, 0, &mut visits, &mesh_prims, &mut instances)?;
    }
    // World positions are checked where they enter: finite and within ±WORLD_LIMIT, so that the
    // bake's positions, its bounding box and the object size stay finite in f32.
    for &(pi, world) in &instances {
        let p = &prims[pi];
        if let Some(v) = p.pos.iter().map(|&v| world.transform_point3(v)).find(|v| !(v.is_finite() && v.abs().max_element() <= WORLD_LIMIT)) {
            return Err(format!("mesh {} primitive {}: a vertex lies at {v} after its node's transform, past ±{WORLD_LIMIT:e} (a node scale or translation too large)", p.mesh, p.prim));
        }
    }
    Ok(GltfAsset { path: path.to_path_buf(), materials, prims, instances })
}

/// Appends (primitive, world matrix) for `node` and its subtree, depth first.
fn visit(node: &gltf::Node, parent: DMat4, depth: usize, visits: &mut usize, mesh_prims: &[Range<usize>], out: &mut Vec<(usize, DMat4)>) -> Result<(), String> {
    *visits += 1;
    if depth > 256 || *visits > 1 << 20 {
        return Err(format!("node {}: hierarchy too deep or too large (cycle?)", node.index()));
    }
    let f = |a: [f32; 3]| DVec3::from(a.map(f64::from));
    let local = match node.transform() {
        gltf::scene::Transform::Matrix { matrix } => DMat4::from_cols_array_2d(&matrix.map(|c| c.map(f64::from))),
        gltf::scene::Transform::Decomposed { translation, rotation, scale } => {
            let q = DQuat::from_array(rotation.map(f64::from));
            let q = if q.length() > 0.0 { q.normalize() } else { DQuat::IDENTITY };
            DMat4::from_scale_rotation_translation(f(scale), q, f(translation))
        }
    };
    let world = parent * local;
    if !world.is_finite() {
        return Err(format!("node {}: its transform is not finite (or overflows with its parents')", node.index()));
    }
    if let Some(mesh) = node.mesh() {
        out.extend(mesh_prims[mesh.index()].clone().map(|p| (p, world)));
    }
    for c in node.children() {
        visit(&c, world, depth + 1, visits, mesh_prims, out)?;
    }
    Ok(())
}

fn decode_prim(p: &gltf::Primitive, mesh: usize, bufs: &[Vec<u8>]) -> Result<Prim, String> {
    use gltf::accessor::DataType;
    use gltf::mesh::{Mode, Semantic};
    let attr = |s: Semantic, k: usize| p.get(&s).map(|a| read_acc(&a, bufs, k)).transpose();
    let pos = attr(Semantic::Positions, 3)?.ok_or("no POSITION attribute")?;
    if let Some(i) = pos.iter().position(|v| !v.is_finite()) {
        return Err(format!("POSITION of vertex {} is not finite", i / 3));
    }
    let n = pos.len() / 3;
    let checked = |v: Option<Vec<f64>>, k: usize, name: &str| match v {
        Some(v) if v.len() != n * k => Err(format!("{name} has {} elements, POSITION has {n}", v.len() / k)),
        v => Ok(v),
    };
    let vec3 = |v: Vec<f64>, k: usize| -> Vec<DVec3> { v.chunks_exact(k).map(|c| DVec3::new(c[0], c[1], c[2])).collect() };
    let nrm = checked(attr(Semantic::Normals, 3)?, 3, "NORMAL")?.map(|v| vec3(v, 3));
    let tan = checked(attr(Semantic::Tangents, 4)?, 4, "TANGENT")?.map(|v| vec3(v, 4));
    let uv: Option<Vec<DVec2>> = checked(attr(Semantic::TexCoords(0), 2)?, 2, "TEXCOORD_0")?
        .map(|v| v.chunks_exact(2).map(|c| DVec2::new(c[0], c[1])).collect());
    // Checked where they enter, like positions (non-finite normals and tangents fall back to
    // the face's): a texture coordinate that is not finite is an error.
    if let Some(i) = uv.as_ref().and_then(|uv| uv.iter().position(|t| !t.is_finite())) {
        return Err(format!("TEXCOORD_0 of vertex {i} is not finite"));
    }
    let idx: Vec<usize> = match p.indices() {
        None => (0..n).collect(),
        Some(a) => {
            if !matches!(a.data_type(), DataType::U8 | DataType::U16 | DataType::U32) || a.normalized() {
                return Err(format!("indices accessor {} is not unsigned byte/short/int", a.index()));
            }
            let v = read_acc(&a, bufs, 1)?;
            if let Some(i) = v.iter().find(|&&i| i >= n as f64) {
                return Err(format!("index {i} out of range (POSITION has {n} vertices)"));
            }
            v.into_iter().map(|i| i as usize).collect()
        }
    };
    let tris = match p.mode() {
        Mode::Triangles => idx.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
        Mode::TriangleStrip => (2..idx.len())
            .map(|i| if i % 2 == 0 { [idx[i - 2], idx[i - 1], idx[i]] } else { [idx[i - 2], idx[i], idx[i - 1]] })
            .collect(),
        Mode::TriangleFan => (2..idx.len()).map(|i| [idx[0], idx[i - 1], idx[i]]).collect(),
        m => {
            let name = match m { Mode::Points => "POINTS", Mode::Lines => "LINES", Mode::LineLoop => "LINE_LOOP", _ => "LINE_STRIP" };
            return Err(format!("mode {name} is not supported (only TRIANGLES, TRIANGLE_STRIP, TRIANGLE_FAN)"));
        }
    };
    Ok(Prim { mesh, prim: p.index(), material: p.material().index(), pos: vec3(pos, 3), nrm, tan, uv, tris })
}

/// Reads an accessor as f64s (normalized integers mapped to [0,1] / [-1,1]), `k` per element.
fn read_acc(a: &gltf::Accessor, bufs: &[Vec<u8>], k: usize) -> Result<Vec<f64>, String> {
    use gltf::accessor::DataType as T;
    let what = format!("accessor {}", a.index());
    if a.sparse().is_some() {
        return Err(format!("{what} is sparse (sparse accessors are not supported)"));
    }
    use gltf::accessor::Dimensions as D;
    if a.dimensions().multiplicity() != k || matches!(a.dimensions(), D::Mat2 | D::Mat3 | D::Mat4) {
        return Err(format!("{what} has type {:?}, expected {k} components", a.dimensions()));
    }
    let (dt, norm, n, size) = (a.data_type(), a.normalized(), a.count(), a.data_type().size());
    let view = a.view().ok_or_else(|| format!("{what} has no bufferView"))?; // validated
    let data = view_bytes(bufs, &view)?;
    let (elem, stride) = (size * k, view.stride().unwrap_or(size * k));
    let need = if n == 0 { Some(0) } else { (n - 1).checked_mul(stride).and_then(|x| x.checked_add(elem)) };
    let data = need
        .and_then(|need| data.get(a.offset()..a.offset().checked_add(need)?))
        .filter(|_| stride >= elem)
        .ok_or_else(|| format!("{what} (count {n}, stride {stride}) does not fit in bufferView {}", view.index()))?;
    let mut out = Vec::with_capacity(n * k);
    for i in 0..n {
        for c in 0..k {
            let s = &data[i * stride + c * size..][..size];
            let (v, scale) = match dt {
                T::I8 => (s[0] as i8 as f64, 127.0),
                T::U8 => (s[0] as f64, 255.0),
                T::I16 => (i16::from_le_bytes([s[0], s[1]]) as f64, 32767.0),
                T::U16 => (u16::from_le_bytes([s[0], s[1]]) as f64, 65535.0),
                T::U32 => (u32::from_le_bytes([s[0], s[1], s[2], s[3]]) as f64, u32::MAX as f64),
                T::F32 => (f32::from_le_bytes([s[0], s[1], s[2], s[3]]) as f64, 0.0),
            };
            out.push(if norm && scale > 0.0 { (v / scale).max(-1.0) } else { v });
        }
    }
    Ok(out)
}

fn view_bytes<'a>(bufs: &'a [Vec<u8>], v: &gltf::buffer::View) -> Result<&'a [u8], String> {
    let buf = &bufs[v.buffer().index()];
    let bytes = v.offset().checked_add(v.length()).and_then(|end| buf.get(v.offset()..end));
    bytes.ok_or_else(|| format!("bufferView {} exceeds buffer {} ({} bytes)", v.index(), v.buffer().index(), buf.len()))
}

/// Splits a GLB into its JSON chunk and optional BIN chunk.
fn split_glb(b: &[u8]) -> Result<(&[u8], Option<&[u8]>), String> {
    let word = |o: usize| b.get(o..o + 4).map(|s| u32::from_le_bytes([s[0], s[1], s[2], s[3]]) as usize);
    let bad = |what: &str| format!("malformed GLB: {what}");
    let (version, total) = (word(4).ok_or(bad("truncated header"))?, word(8).ok_or(bad("truncated header"))?);
    if version != 2 {
        return Err(bad(&format!("version {version}, expected 2")));
    }
    if total > b.len() || total < 20 {
        return Err(bad(&format!("header says {total} bytes, file has {}", b.len())));
    }
    let (mut off, mut json, mut bin) = (12, None, None);
    while off + 8 <= total {
        let (len, ty) = (word(off).unwrap_or(0), &b[off + 4..off + 8]);
        let data = b.get(off + 8..).and_then(|d| d.get(..len)).filter(|_| off + 8 + len <= total);
        let data = data.ok_or_else(|| bad(&format!("chunk at byte {off} runs past the end")))?;
        match ty {
            b"JSON" => json = json.or(Some(data)),
            b"BIN\0" => bin = bin.or(Some(data)),
            _ => {}
        }
        off += 8 + len;
    }
    Ok((json.ok_or(bad("no JSON chunk"))?, bin))
}

/// The bytes a URI of the asset at `gltf` names: a `data:` URI's, or a file's where `access`
/// allows it (checked before the file is opened; no message holds the file's bytes).
fn read_uri(gltf: &Path, access: &FileAccess, uri: &str) -> Result<(String, Vec<u8>), String> {
    match access.resolve_uri(uri, gltf, gltf).map_err(|e| e.to_string())? {
        UriTarget::Data(rest) => {
            let (head, data) = rest.split_once(',').ok_or("malformed data: URI")?;
            let mime = head.strip_suffix(";base64").ok_or("data: URI is not base64")?;
            Ok((mime.to_string(), base64(data)?))
        }
        UriTarget::File(file) => {
            let bytes = std::fs::read(&file).map_err(|e| format!("cannot read {}: {e}", file.display()))?;
            Ok((String::new(), bytes))
        }
    }
}

fn base64(s: &str) -> Result<Vec<u8>, String> {
    let (mut out, mut acc, mut bits) = (Vec::with_capacity(s.len() / 4 * 3), 0u32, 0);
    for c in s.bytes() {
        let v = match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' | b'-' => 62,
            b'/' | b'_' => 63,
            b'=' => break,
            b' ' | b'\n' | b'\r' | b'\t' => continue,
            _ => return Err(format!("invalid base64 character {:?}", c as char)),
        };
        (acc, bits) = ((acc << 6) | v as u32, bits + 6);
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
            acc &= (1 << bits) - 1;
        }
    }
    Ok(out)
}

/// Twice the signed area of (a, b, p), computed identically (up to sign) for (b, a, p).
fn edge(a: DVec2, b: DVec2, p: DVec2) -> f64 {
    if (a.x, a.y) <= (b.x, b.y) { (b - a).perp_dot(p - a) } else { -(a - b).perp_dot(p - b) }
}

/// Bakes world position / normal / tangent per texel of `material`'s texture space.
pub fn rasterize_uv(asset: &GltfAsset, material: usize, width: usize, height: usize) -> Result<SurfaceBake, String> {
    let fail = |e: String| format!("{}: {e}", asset.path.display());
    let mat = asset.materials.get(material).ok_or_else(|| fail(format!("no material {material}")))?;
    let n = width.checked_mul(height).filter(|&n| n > 0 && n <= 1 << 28);
    let n = n.ok_or_else(|| fail(format!("bad bake size {width}x{height}")))?;
    let mut bake = SurfaceBake {
        width,
        height,
        covered: vec![false; n],
        position: vec![[0.0; 3]; n],
        normal: vec![[0.0, 1.0, 0.0]; n],
        tangent: vec![[1.0, 0.0, 0.0]; n],
        bbox_min: [0.0; 3],
        bbox_max: [0.0; 3],
    };
    let size = DVec2::new(width as f64, height as f64);
    let (mut lo, mut hi, mut any) = (DVec3::INFINITY, DVec3::NEG_INFINITY, false);
    let f32s = |v: DVec3| v.as_vec3().to_array();
    for &(pi, m) in &asset.instances {
        let p = &asset.prims[pi];
        if p.material != Some(material) {
            continue;
        }
        let ctx = |e: &str| fail(format!("mesh {} primitive {} (material {material}): {e}", p.mesh, p.prim));
        let uv = p.uv.as_ref().ok_or_else(|| ctx("no TEXCOORD_0"))?;
        let m3 = DMat3::from_mat4(m);
        let (nmat, flip) = (m3.inverse().transpose(), m3.determinant() < 0.0);
        let wp: Vec<DVec3> = p.pos.iter().map(|&v| m.transform_point3(v)).collect();
        let wn: Option<Vec<DVec3>> = p.nrm.as_ref().map(|v| v.iter().map(|&n| (nmat * n).normalize_or_zero()).collect());
        let wt: Option<Vec<DVec3>> = p.tan.as_ref().map(|v| v.iter().map(|&t| m3 * t).collect());
        for &[a, b, c] in &p.tris {
            for i in [a, b, c] {
                (lo, hi, any) = (lo.min(wp[i]), hi.max(wp[i]), true);
            }
            let t = [uv[a] * size, uv[b] * size, uv[c] * size];
            if !t.iter().all(|v| v.is_finite()) {
                return Err(ctx("non-finite TEXCOORD_0"));
            }
            let (e1, e2, d1, d2) = (wp[b] - wp[a], wp[c] - wp[a], uv[b] - uv[a], uv[c] - uv[a]);
            let face_n = e1.cross(e2).normalize_or_zero() * if flip { -1.0 } else { 1.0 };
            let face_t = (e1 * d2.y - e2 * d1.y) / d1.perp_dot(d2);
            let area = edge(t[0], t[1], t[2]);
            if area == 0.0 {
                continue;
            }
            let (v, vi) = if area > 0.0 { (t, [a, b, c]) } else { ([t[0], t[2], t[1]], [a, c, b]) };
            let (mn, mx) = (v[0].min(v[1]).min(v[2]), v[0].max(v[1]).max(v[2]));
            if mx.x - mn.x > 16.0 * size.x || mx.y - mn.y > 16.0 * size.y {
                return Err(ctx("a triangle's TEXCOORD_0 spans more than 16 UV tiles"));
            }
            let edges = [(v[1], v[2]), (v[2], v[0]), (v[0], v[1])];
            let top_left = |(a, b): (DVec2, DVec2)| b.y < a.y || (b.y == a.y && b.x > a.x);
            for y in (mn.y - 0.5).ceil() as i64..=(mx.y - 0.5).floor() as i64 {
                for x in (mn.x - 0.5).ceil() as i64..=(mx.x - 0.5).floor() as i64 {
                    let pc = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
                    let w = edges.map(|(a, b)| edge(a, b, pc));
                    if !(0..3).all(|k| w[k] > 0.0 || (w[k] == 0.0 && top_left(edges[k]))) {
                        continue;
                    }
                    let s = w[0] + w[1] + w[2];
                    let at = |v: &[DVec3]| (v[vi[0]] * w[0] + v[vi[1]] * w[1] + v[vi[2]] * w[2]) / s;
                    let mut nn = wn.as_ref().map_or(face_n, |wn| at(wn).normalize_or_zero());
                    if nn == DVec3::ZERO {
                        nn = if face_n == DVec3::ZERO { DVec3::Y } else { face_n };
                    }
                    let t0 = wt.as_ref().map_or(face_t, |wt| at(wt));
                    let mut tt = (t0 - nn * nn.dot(t0)).normalize_or_zero();
                    if tt == DVec3::ZERO {
                        tt = nn.any_orthonormal_vector();
                    }
                    let i = y.rem_euclid(height as i64) as usize * width + x.rem_euclid(width as i64) as usize;
                    bake.covered[i] = true;
                    (bake.position[i], bake.normal[i], bake.tangent[i]) = (f32s(at(&wp)), f32s(nn), f32s(tt));
                }
            }
        }
    }
    if !any {
        return Err(fail(format!("material {material} ({}) has no triangles in the scene", mat.name)));
    }
    (bake.bbox_min, bake.bbox_max) = (f32s(lo), f32s(hi));
    dilate(&mut bake, f32s((lo + hi) * 0.5));
    Ok(bake)
}

fn dilate(b: &mut SurfaceBake, centre: [f32; 3]) {
    const NB: [(i64, i64); 8] = [(-1, 0), (1, 0), (0, -1), (0, 1), (-1, -1), (1, -1), (-1, 1), (1, 1)];
    let (w, h) = (b.width as i64, b.height as i64);
    let mut filled = b.covered.clone();
    for _ in 0..16 {
        let updates: Vec<(usize, usize)> = (0..filled.len())
            .into_par_iter()
            .filter(|&i| !filled[i])
            .filter_map(|i| {
                let (x, y) = (i as i64 % w, i as i64 / w);
                NB.iter()
                    .map(|&(dx, dy)| (x + dx, y + dy))
                    .filter(|&(x, y)| x >= 0 && y >= 0 && x < w && y < h)
                    .map(|(x, y)| (y * w + x) as usize)
                    .find(|&j| filled[j])
                    .map(|j| (i, j))
            })
            .collect();
        if updates.is_empty() {
            break;
        }
        for (i, j) in updates {
            filled[i] = true;
            (b.position[i], b.normal[i], b.tangent[i]) = (b.position[j], b.normal[j], b.tangent[j]);
        }
    }
    for (i, _) in filled.iter().enumerate().filter(|(_, f)| !**f) {
        (b.position[i], b.normal[i], b.tangent[i]) = (centre, [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fs;

    /// Minimal glTF writer: one buffer; bufferViews and accessors as JSON text.
    #[derive(Default, Clone)]
    struct Doc { bin: Vec<u8>, views: Vec<String>, accs: Vec<String> }

    impl Doc {
        fn view(&mut self, bytes: &[u8], stride: Option<usize>) -> usize {
            self.bin.resize(self.bin.len().next_multiple_of(4), 0);
            let s = stride.map_or(String::new(), |s| format!(r#","byteStride":{s}"#));
            self.views.push(format!(r#"{{"buffer":0,"byteOffset":{},"byteLength":{}{s}}}"#, self.bin.len(), bytes.len()));
            self.bin.extend_from_slice(bytes);
            self.views.len() - 1
        }
        fn acc(&mut self, view: usize, ctype: u32, count: usize, ty: &str, extra: &str) -> usize {
            let norm = ctype != 5126 && ty != "SCALAR";
            let f = format!(r#"{{"bufferView":{view},"componentType":{ctype},"normalized":{norm},"count":{count},"type":"{ty}"{extra}}}"#);
            self.accs.push(f);
            self.accs.len() - 1
        }
        /// Tightly packed float accessor with min/max, `k` components.
        fn floats(&mut self, data: &[f32], k: usize) -> usize {
            let v = self.view(&data.iter().flat_map(|f| f.to_le_bytes()).collect::<Vec<_>>(), None);
            let (mut lo, mut hi) = (vec![f32::MAX; k], vec![f32::MIN; k]);
            data.chunks(k).for_each(|c| (0..k).for_each(|i| (lo[i], hi[i]) = (lo[i].min(c[i]), hi[i].max(c[i]))));
            self.acc(v, 5126, data.len() / k, ["SCALAR", "VEC2", "VEC3", "VEC4"][k - 1], &format!(r#","min":{lo:?},"max":{hi:?}"#))
        }
        fn indices(&mut self, idx: &[u32], ctype: u32) -> usize {
            let n = match ctype { 5121 => 1, 5123 => 2, _ => 4 };
            let v = self.view(&idx.iter().flat_map(|i| i.to_le_bytes()[..n].to_vec()).collect::<Vec<_>>(), None);
            self.acc(v, ctype, idx.len(), "SCALAR", "")
        }
        /// The document; `uri` None = GLB binary chunk, Some("") = data: URI, else a file.
        fn json(&self, uri: Option<&str>, rest: &str) -> String {
            let uri = match uri {
                None => String::new(),
                Some("") => format!(r#","uri":"data:application/octet-stream;base64,{}""#, b64(&self.bin)),
                Some(u) => format!(r#","uri":"{u}""#),
            };
            let (n, v, a) = (self.bin.len(), self.views.join(","), self.accs.join(","));
            format!(r#"{{"asset":{{"version":"2.0"}},"buffers":[{{"byteLength":{n}{uri}}}],"bufferViews":[{v}],"accessors":[{a}]{rest}}}"#)
        }
    }

    fn b64(data: &[u8]) -> String {
        const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
        let mut s = String::new();
        for c in data.chunks(3) {
            let n = (c[0] as u32) << 16 | (*c.get(1).unwrap_or(&0) as u32) << 8 | *c.get(2).unwrap_or(&0) as u32;
            (0..4).for_each(|k| s.push(if k <= c.len() { A[(n >> (18 - 6 * k) & 63) as usize] as char } else { '=' }));
        }
        s
    }

    fn glb(json: &str, bin: &[u8]) -> Vec<u8> {
        let pad = |mut v: Vec<u8>, p: u8| -> Vec<u8> { v.resize(v.len().next_multiple_of(4), p); v };
        let (j, b) = (pad(json.into(), b' '), pad(bin.to_vec(), 0));
        let mut out = [&b"glTF"[..], &2u32.to_le_bytes(), &((28 + j.len() + b.len()) as u32).to_le_bytes()].concat();
        for (ty, chunk) in [(b"JSON", &j), (b"BIN\0", &b)] {
            out.extend((chunk.len() as u32).to_le_bytes().iter().chain(ty).chain(chunk));
        }
        out
    }

    fn tmp(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("uplift_gltf_{}_{name}", std::process::id()));
        let _ = fs::remove_dir_all(&d);
        fs::create_dir_all(&d).unwrap();
        d
    }

    fn write(dir: &Path, name: &str, bytes: impl AsRef<[u8]>) -> PathBuf {
        fs::write(dir.join(name), bytes).unwrap();
        dir.join(name)
    }

    /// Unit quad in the XZ plane (normal +Y, CCW from above), vertex (x, 0, z) at UV
    /// (x + 0.5, z + 0.5) * uv_scale, with indices of component type `idx` (None: non-indexed),
    /// UVs of component type `uvt` (integers normalized) interleaved with junk to `stride`, and
    /// NORMAL if `normals`. Returns the primitive's JSON (material 0).
    fn quad(d: &mut Doc, idx: Option<u32>, uvt: u32, stride: Option<usize>, normals: bool, uv_scale: f32) -> String {
        let (corners, tri) = ([[0.0f32, 0.0], [0.0, 1.0], [1.0, 1.0], [1.0, 0.0]], [0u32, 1, 2, 0, 2, 3]);
        let verts: Vec<[f32; 2]> = match idx {
            Some(_) => corners.to_vec(),
            None => tri.iter().map(|&i| corners[i as usize]).collect(),
        };
        let mut attrs = format!(r#""POSITION":{}"#, d.floats(&verts.iter().flat_map(|c| [c[0] - 0.5, 0.0, c[1] - 0.5]).collect::<Vec<_>>(), 3));
        if normals {
            attrs += &format!(r#","NORMAL":{}"#, d.floats(&verts.iter().flat_map(|_| [0.0, 1.0, 0.0]).collect::<Vec<_>>(), 3));
        }
        let (size, mut bytes) = (match uvt { 5126 => 4, 5123 => 2, _ => 1 }, Vec::new());
        for c in &verts {
            for u in c.map(|u| u * uv_scale) {
                match uvt {
                    5126 => bytes.extend(u.to_le_bytes()),
                    5123 => bytes.extend(((u * 65535.0).round() as u16).to_le_bytes()),
                    _ => bytes.push((u * 255.0).round() as u8),
                }
            }
            bytes.resize(bytes.len() + stride.map_or(0, |s| s - 2 * size), 0xAB);
        }
        let v = d.view(&bytes, stride);
        attrs += &format!(r#","TEXCOORD_0":{}"#, d.acc(v, uvt, verts.len(), "VEC2", ""));
        let indices = idx.map_or(String::new(), |t| format!(r#","indices":{}"#, d.indices(&tri, t)));
        format!(r#"{{"attributes":{{{attrs}}}{indices},"mode":4,"material":0}}"#)
    }

    /// Meshes, nodes, one scene of node 0 and one default material, after the accessors.
    fn one_mesh(prims: &str, nodes: &str) -> String {
        format!(r#","meshes":[{{"primitives":[{prims}]}}],"nodes":{nodes},"scenes":[{{"nodes":[0]}}],"scene":0,"materials":[{{}}]"#)
    }

    fn close(a: [f32; 3], b: [f64; 3], tol: f64) -> bool {
        (0..3).all(|i| (a[i] as f64 - b[i]).abs() <= tol)
    }

    #[test]
    fn quad_bakes_analytic_plane_in_every_encoding() {
        let (dir, w, h) = (tmp("quad"), 64, 32);
        // (indices, UV type, UV stride, normals): u16 / none / u8 / u32 indices; float,
        // normalized u16 and u8 UVs; tight and interleaved; vertex and flat normals.
        let encs = [(Some(5123), 5126, None, true), (None, 5123, Some(8), false), (Some(5121), 5121, Some(4), true), (Some(5125), 5126, Some(12), false)];
        for (k, &(idx, uvt, stride, normals)) in encs.iter().enumerate() {
            let mut d = Doc::default();
            let prim = quad(&mut d, idx, uvt, stride, normals, 1.0);
            let path = write(&dir, &format!("q{k}.gltf"), d.json(Some(""), &one_mesh(&prim, r#"[{"mesh":0}]"#)));
            let b = rasterize_uv(&load(&path).unwrap(), 0, w, h).unwrap();
            assert_eq!((b.bbox_min, b.bbox_max), ([-0.5, 0.0, -0.5], [0.5, 0.0, 0.5]));
            for i in 0..w * h {
                let (u, v) = (((i % w) as f64 + 0.5) / w as f64, ((i / w) as f64 + 0.5) / h as f64);
                assert!(b.covered[i] && close(b.position[i], [u - 0.5, 0.0, v - 0.5], 1e-5), "enc {k} texel {i}: {:?}", b.position[i]);
                assert!(close(b.normal[i], [0.0, 1.0, 0.0], 1e-6) && close(b.tangent[i], [1.0, 0.0, 0.0], 1e-6));
            }
        }
        // UVs covering [0, 0.25]^2 of a 128^2 bake: 32x32 covered, 16 rings dilated, rest default.
        let mut d = Doc::default();
        let prim = quad(&mut d, Some(5123), 5126, None, true, 0.25);
        let path = write(&dir, "small.gltf", d.json(Some(""), &one_mesh(&prim, r#"[{"mesh":0}]"#)));
        let b = rasterize_uv(&load(&path).unwrap(), 0, 128, 128).unwrap();
        assert_eq!(b.covered.iter().filter(|&&c| c).count(), 32 * 32);
        assert_eq!(b.position[47 * 128 + 47], b.position[31 * 128 + 31]); // 16 rings out, diagonal
        assert_eq!(b.position[20 * 128 + 40], b.position[20 * 128 + 31]); // straight out
        assert_eq!(b.position[48 * 128 + 48], [0.0; 3]); // 17 rings out: bbox centre
        let _ = fs::remove_dir_all(&dir);
    }

    #[test]
    fn node_transforms_instances_and_normal_matrix() {
        let dir = tmp("xform");
        let q = glam::Quat::from_axis_angle(glam::Vec3::new(1.0, 2.0, 3.0).normalize(), 0.7);
        let (c, s) = (30f32.to_radians().cos(), 30f32.to_radians().sin());
        let mx = [1.0, 0.0, 0.0, 0.0, 0.0, c, s, 0.0, 0.0, -s, c, 0.0, 0.0, 0.0, 0.0, 1.0f32];
        // Node 0 (identity) and node 2 (under TRS node 1) both instance the mesh; node 2 is
        // drawn later and wins.
        let nodes = format!(
            r#"[{{"mesh":0}},{{"translation":[1,2,3],"rotation":{:?},"scale":[2,3,0.5],"children":[2]}},{{"matrix":{mx:?},"mesh":0}}]"#,
            q.to_array()
        );
        let mut d = Doc::default();
        let prim = quad(&mut d, Some(5123), 5126, None, true, 1.0); // + TANGENT (1,0,0,1): M3 * t path
        let prim = prim.replace(r#""POSITION""#, &format!(r#""TANGENT":{},"POSITION""#, d.floats(&[1.0, 0.0, 0.0, 1.0].repeat(4), 4)));
        let json = d.json(Some(""), &one_mesh(&prim, &nodes).replace(r#""nodes":[0]}"#, r#""nodes":[0,1]}"#));
        let bake = rasterize_uv(&load(&write(&dir, "x.gltf", json)).unwrap(), 0, 32, 32).unwrap();
        let qd = glam::DQuat::from_array(q.to_array().map(f64::from)).normalize();
        let m = DMat4::from_scale_rotation_translation(DVec3::new(2.0, 3.0, 0.5), qd, DVec3::new(1.0, 2.0, 3.0))
            * DMat4::from_cols_array(&mx.map(f64::from));
        let m3 = DMat3::from_mat4(m);
        let (n, tx) = ((m3.inverse().transpose() * DVec3::Y).normalize(), m3 * DVec3::X);
        // Independent of the formula: the normal is orthogonal to the transformed surface.
        assert!(n.dot(tx).abs() < 1e-12 && n.dot(m3 * DVec3::Z).abs() < 1e-12 && n.dot(m3 * DVec3::Y) > 0.0);
        for i in 0..32 * 32 {
            let (u, v) = (((i % 32) as f64 + 0.5) / 32.0, ((i / 32) as f64 + 0.5) / 32.0);
            let p = m.transform_point3(DVec3::new(u - 0.5, 0.0, v - 0.5));
            assert!(bake.covered[i] && close(bake.position[i], p.to_array(), 1e-5), "{i}: {:?} vs {p}", bake.position[i]);
            assert!(close(bake.normal[i], n.to_array(), 1e-6), "{:?} vs {n}", bake.normal[i]);
            assert!(close(bake.tangent[i], tx.normalize().to_array(), 1e-6));
        }
        let _ = fs::remove_dir_all(&dir);
    }

    /// Unit cube faces (normal, first in-plane axis), laid out in a 3x2 UV atlas: face f in
    /// cell (f % 3, f / 3), inset by 4 texels of a 96x64 bake (32x32-texel cells).
    const FACES: [([f64; 3], [f64; 3]); 6] = [
        ([1.0, 0.0, 0.0], [0.0, 0.0, 1.0]), ([-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]), ([0.0, 1.0, 0.0], [1.0, 0.0, 0.0]),
        ([0.0, -1.0, 0.0], [1.0, 0.0, 0.0]), ([0.0, 0.0, 1.0], [1.0, 0.0, 0.0]), ([0.0, 0.0, -1.0], [1.0, 0.0, 0.0]),
    ];

    #[test]
    fn cube_atlas_coverage_normals_and_dilation() {
        let (w, h, mu, mv) = (96usize, 64usize, 4.0 / 96.0, 4.0 / 64.0);
        let corner = |f: usize, su: f64, sv: f64| {
            let (n, t) = (DVec3::from(FACES[f].0), DVec3::from(FACES[f].1));
            0.5 * (n + su * t + sv * n.cross(t)) // (t, n x t) is CCW around n
        };
        let (mut d, mut pos, mut nrm, mut uv, mut idx) = (Doc::default(), vec![], vec![], vec![], vec![]);
        for f in 0..6 {
            let (u0, v0) = ((f % 3) as f64 / 3.0 + mu, (f / 3) as f64 / 2.0 + mv);
            for (su, sv) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                pos.extend(corner(f, su, sv).as_vec3().to_array());
                nrm.extend(FACES[f].0.map(|x| x as f32));
                uv.extend([u0 + (su + 1.0) / 2.0 * (1.0 / 3.0 - 2.0 * mu), v0 + (sv + 1.0) / 2.0 * (0.5 - 2.0 * mv)].map(|x| x as f32));
            }
            idx.extend([0, 1, 2, 0, 2, 3].map(|i| i + 4 * f as u32));
        }
        let (p, n, t, i) = (d.floats(&pos, 3), d.floats(&nrm, 3), d.floats(&uv, 2), d.indices(&idx, 5123));
        let prim = format!(r#"{{"attributes":{{"POSITION":{p},"NORMAL":{n},"TEXCOORD_0":{t}}},"indices":{i},"material":0}}"#);
        let dir = tmp("cube");
        let path = write(&dir, "cube.glb", glb(&d.json(None, &one_mesh(&prim, r#"[{"mesh":0}]"#)), &d.bin));
        let b = rasterize_uv(&load(&path).unwrap(), 0, w, h).unwrap();
        let covered = b.covered.iter().filter(|&&c| c).count() as f64;
        let analytic = 6.0 * (1.0 / 3.0 - 2.0 * mu) * (0.5 - 2.0 * mv) * (w * h) as f64;
        assert!((covered - analytic).abs() <= 4.0, "{covered} texels covered, analytic {analytic}");
        for (k, (x, y)) in (0..h).flat_map(|y| (0..w).map(move |x| (x, y))).enumerate() {
            let f = (y / 32) * 3 + x / 32;
            // Covered or dilated, every texel carries its own cell's face (gaps are 8 wide).
            assert!(close(b.normal[k], FACES[f].0, 1e-6), "({x},{y}) normal {:?}, face {f}", b.normal[k]);
            assert!((DVec3::from(b.position[k].map(f64::from)).dot(DVec3::from(FACES[f].0)) - 0.5).abs() < 1e-6);
            if b.covered[k] {
                let su = ((x as f64 + 0.5) / w as f64 - (f % 3) as f64 / 3.0 - mu) / (1.0 / 3.0 - 2.0 * mu) * 2.0 - 1.0;
                let sv = ((y as f64 + 0.5) / h as f64 - (f / 3) as f64 / 2.0 - mv) / (0.5 - 2.0 * mv) * 2.0 - 1.0;
                assert!(close(b.position[k], corner(f, su, sv).to_array(), 1e-5));
            }
        }
        let _ = fs::remove_dir_all(&dir);
    }

    fn png(rgba: [u8; 4]) -> Vec<u8> {
        let mut v = Vec::new();
        let img = image::RgbaImage::from_pixel(2, 2, image::Rgba(rgba));
        img.write_to(&mut std::io::Cursor::new(&mut v), image::ImageFormat::Png).unwrap();
        v
    }

    #[test]
    fn glb_and_gltf_agree_and_materials_parse() {
        let (dir, mut d) = (tmp("agree"), Doc::default());
        let (p0, p1) = (quad(&mut d, Some(5123), 5126, None, true, 1.0), quad(&mut d, None, 5126, None, false, 0.5));
        let prims = format!("{p0},{}", p1.replace(r#""material":0"#, r#""material":1"#));
        let materials = r#","textures":[{"source":0},{"source":1}],"materials":[{"name":"painted","pbrMetallicRoughness":{"baseColorFactor":[0.5,0.25,0.125,1.0],"metallicFactor":0.3,"roughnessFactor":0.6,"baseColorTexture":{"index":0},"metallicRoughnessTexture":{"index":1}},"normalTexture":{"index":0,"scale":0.7}},{}]"#;
        let scene = one_mesh(&prims, r#"[{"mesh":0,"translation":[0,1,0]}]"#).replace(r#","materials":[{}]"#, materials);
        let (png0, png1, mut g) = (png([200, 100, 50, 255]), png([0, 128, 255, 255]), d.clone());
        let (v0, v1) = (g.view(&png0, None), g.view(&png1, None));
        let embedded = format!(r#","images":[{{"bufferView":{v0},"mimeType":"image/png"}},{{"bufferView":{v1},"mimeType":"image/png"}}]"#);
        let files = r#","images":[{"uri":"tex0.png"},{"uri":"tex%201.png"}]"#;
        (write(&dir, "tex0.png", &png0), write(&dir, "tex 1.png", &png1), write(&dir, "geo.bin", &d.bin));
        let assets = [
            load(&write(&dir, "a.glb", glb(&g.json(None, &(scene.clone() + &embedded)), &g.bin))).unwrap(),
            load(&write(&dir, "a.gltf", d.json(Some(""), &(scene.clone() + files)))).unwrap(),
            load(&write(&dir, "b.gltf", d.json(Some("geo.bin"), &(scene + files)))).unwrap(),
        ];
        for m in assets.iter().map(|a| &a.materials) {
            assert_eq!(m.len(), 2);
            assert_eq!((m[0].index, m[0].name.as_str(), m[0].base_color_factor), (0, "painted", [0.5, 0.25, 0.125, 1.0]));
            assert_eq!((m[0].metallic_factor, m[0].roughness_factor, m[0].normal_scale), (0.3, 0.6, 0.7));
            let refs = [&m[0].base_color_texture, &m[0].metallic_roughness_texture, &m[0].normal_texture];
            for (r, (img, bytes)) in refs.iter().zip([(0, &png0), (1, &png1), (0, &png0)]) {
                let r = r.as_ref().unwrap();
                assert_eq!((r.image, r.tex_coord, r.source.extension(), &r.source.bytes().unwrap()), (img, 0, "png", bytes));
            }
            let (none, one) = (None, [1.0; 4]);
            let defaults = GltfMaterial {
                index: 1, name: "material_1".into(), base_color_factor: one, metallic_factor: 1.0, roughness_factor: 1.0,
                base_color_texture: none.clone(), metallic_roughness_texture: none.clone(), normal_texture: none, normal_scale: 1.0,
            };
            assert_eq!(m[1], defaults);
        }
        let src = |a: &GltfAsset| a.materials[0].metallic_roughness_texture.as_ref().unwrap().source.clone();
        assert_eq!(src(&assets[0]), ImageSource::Embedded { bytes: png1.clone(), mime: "image/png".into() });
        assert_eq!(src(&assets[1]), ImageSource::File(dir.join("tex 1.png")));
        for mat in 0..2 {
            let bakes: Vec<_> = assets.iter().map(|a| rasterize_uv(a, mat, 40, 24).unwrap()).collect();
            assert!(bakes[0] == bakes[1] && bakes[0] == bakes[2], "material {mat}: bakes differ");
            assert_eq!(bakes[0].bbox_min[1], 1.0); // node translation
        }
        let _ = fs::remove_dir_all(&dir);
    }

    #[test]
    fn bad_input_is_an_error_not_a_panic() {
        let (dir, mut d) = (tmp("errors"), Doc::default());
        let prim = quad(&mut d, Some(5123), 5126, None, true, 1.0);
        let base = d.json(Some(""), &one_mesh(&prim, r#"[{"mesh":0}]"#));
        let good_glb = glb(&d.json(None, &one_mesh(&prim, r#"[{"mesh":0}]"#)), &d.bin);
        assert!(load(&write(&dir, "ok.glb", &good_glb)).is_ok());
        for n in 0..good_glb.len() {
            assert!(load(&write(&dir, "t.glb", &good_glb[..n])).is_err(), "prefix {n} loaded");
        }
        // Bit flips in the GLB and the .gltf text: any result but a panic.
        let mut seed = 12345u64;
        for (name, bytes) in [("f.glb", good_glb.clone()), ("f.gltf", base.clone().into_bytes())] {
            for _ in 0..300 {
                let mut b = bytes.clone();
                seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                let n = b.len();
                b[(seed >> 33) as usize % n] ^= 1 << ((seed >> 20) % 8);
                if let Ok(a) = load(&write(&dir, name, &b)) {
                    let _ = rasterize_uv(&a, 0, 16, 16);
                }
            }
        }
        let with_images = r#","textures":[{"source":0}],"images":[{"uri":"x.png"}],"materials":[{"pbrMetallicRoughness":{"baseColorTexture":{"index":0}}}]"#;
        let textured = base.replace(r#","materials":[{}]"#, with_images);
        assert!(load(&write(&dir, "tex.gltf", &textured)).is_ok());
        let mut no_min_max = base.clone(); // POSITION min/max are optional here
        while let Some(i) = no_min_max.find(r#","min":"#) {
            no_min_max.replace_range(i..i + no_min_max[i..].find("]}").unwrap() + 1, "");
        }
        assert!(load(&write(&dir, "nominmax.gltf", no_min_max)).is_ok());
        let sparse = r#""type":"VEC2","sparse":{"count":1,"indices":{"bufferView":0,"componentType":5123},"values":{"bufferView":0}}"#;
        let cases = [
            ("json.gltf", "{\"asset\":".to_string(), "invalid JSON"),
            ("missing.gltf", d.json(Some("no_such.bin"), &one_mesh(&prim, r#"[{"mesh":0}]"#)), "no_such.bin"),
            ("lines.gltf", base.replace(r#""mode":4"#, r#""mode":1"#), "mode LINES"),
            ("sparse.gltf", base.replacen(r#""type":"VEC2""#, sparse, 1), "sparse"),
            ("draco.gltf", base.replace(r#"{"asset""#, r#"{"extensionsRequired":["KHR_draco_mesh_compression"],"asset""#), "KHR_draco_mesh_compression"),
            ("set1.gltf", textured.replace(r#"{"index":0}"#, r#"{"index":0,"texCoord":1}"#), "TEXCOORD_1"),
            ("xform.gltf", textured.replace(r#"{"index":0}"#, r#"{"index":0,"extensions":{"KHR_texture_transform":{}}}"#), "KHR_texture_transform"),
            ("webp.gltf", textured.replace("x.png", "x.webp"), "not PNG or JPEG"),
        ];
        for (name, text, needle) in cases {
            let e = load(&write(&dir, name, text)).err().unwrap_or_else(|| panic!("{name} loaded"));
            assert!(e.contains(needle) && e.contains(name), "{name}: {e}");
        }
        let mut d2 = Doc::default();
        let (p, i) = (d2.floats(&[0.0; 9], 3), d2.indices(&[0, 1, 7], 5123));
        let text = d2.json(Some(""), &one_mesh(&format!(r#"{{"attributes":{{"POSITION":{p}}},"indices":{i},"material":0}}"#), r#"[{"mesh":0}]"#));
        assert!(load(&write(&dir, "range.gltf", &text)).unwrap_err().contains("index 7 out of range"));
        let a = load(&write(&dir, "nouv.gltf", text.replace(r#","indices":1"#, ""))).unwrap();
        assert!(rasterize_uv(&a, 0, 8, 8).unwrap_err().contains("TEXCOORD_0"));
        let _ = fs::remove_dir_all(&dir);
    }

    #[test]
    fn shaderball_glb() {
        let Ok(root) = std::env::var("UPLIFT_MTLX_DATA") else {
            return uplift_base::test_env::skip("shaderball_glb", "UPLIFT_MTLX_DATA is not set (set it to ../shared/data/materialx; .ci/run does)");
        };
        let b = rasterize_uv(&load(&Path::new(&root).join("Geometry/shaderball.glb")).unwrap(), 0, 256, 256).unwrap();
        let covered = b.covered.iter().filter(|&&c| c).count();
        println!("shaderball material 0: {covered} of 65536 texels covered, bbox {:?}..{:?}", b.bbox_min, b.bbox_max);
        assert!(covered > 0);
        let dot = |a: [f32; 3], b: [f32; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        for (p, (n, t)) in b.position.iter().zip(b.normal.iter().zip(&b.tangent)) {
            assert!(p.iter().chain(n).chain(t).all(|v| v.is_finite()));
            assert!((dot(*n, *n) - 1.0).abs() < 1e-4 && (dot(*t, *t) - 1.0).abs() < 1e-4 && dot(*n, *t).abs() < 1e-4);
        }
    }
}
