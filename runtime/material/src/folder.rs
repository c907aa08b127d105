//! [`MaterialFolder`]: the paths of an enhanced material's files, the checks that a folder is
//! one, and reading and writing each file — params.exr and latent.exr through `uplift_base`'s
//! EXR codec, latent*.png through `image`, meta.json and fit.json through serde. Every write is
//! atomic; every error names the file.

use crate::fit_record::{FitRecord, FIT_FORMAT};
use crate::meta::{Meta, META_FORMAT};
use serde::de::DeserializeOwned;
use serde::Serialize;
use std::path::{Path, PathBuf};
use uplift_base::atomic_write::write_atomically;
use uplift_base::exr::{self, Compression, ExrImage};
use uplift_engines::stack::Stack;

/// The diffuse colour channels of params.exr.
pub const DIFFUSE_CHANNELS: [&str; 3] = ["diffuse_color.R", "diffuse_color.G", "diffuse_color.B"];

/// The params.exr header attribute recording the stack signature it was baked for
/// (`Stack::signature`).
pub const STACK_ATTRIBUTE: &str = "uplift_stack";

/// The baked shading-normal channels of params.exr.
pub const NORMAL_CHANNELS: [&str; 3] = ["normal.X", "normal.Y", "normal.Z"];

/// The paper's latent values per texel (two RGB latent textures).
pub const LATENTS: usize = 6;

/// The widest latent latent.exr holds.
pub const MAX_LATENTS: usize = 16;

/// latent.exr's channel of latent value `k`: values in RGB textures, three per texture in
/// order (`latent0.R/G/B`, `latent1.R/G/B`, … — the paper's 6 are two textures; 8 fill a
/// third texture's R and G).
pub fn latent_channel(k: usize) -> String {
    format!("latent{}.{}", k / 3, ["R", "G", "B"][k % 3])
}

/// An enhanced material's folder.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MaterialFolder {
    dir: PathBuf,
}

/// params.exr as the runtime reads it.
#[derive(Clone, Debug, PartialEq)]
pub struct ParamsImage {
    pub width: usize,
    pub height: usize,
    /// The stack's parameters per texel (texels × `Stack::len`, row-major, row 0 at the top).
    pub params: Vec<f32>,
    /// The diffuse colour c per texel (texels × 3); `None` for folders written before
    /// `uplift enhance` baked it.
    pub diffuse: Option<Vec<f32>>,
    /// The baked shading normal per texel; `None` without a normal map.
    pub normals: Option<Vec<[f32; 3]>>,
}

/// latent.exr: `channels` values per texel (the decoder's latent width), row-major.
#[derive(Clone, Debug, PartialEq)]
pub struct LatentImage {
    pub width: usize,
    pub height: usize,
    pub channels: usize,
    pub latents: Vec<f32>,
}

impl MaterialFolder {
    /// A folder a writer is about to fill (`uplift enhance` stages one and renames it into
    /// place); nothing is checked.
    pub fn create(dir: impl Into<PathBuf>) -> MaterialFolder {
        MaterialFolder { dir: dir.into() }
    }

    /// An existing enhanced material: the folder exists and holds params.exr (and, when it
    /// has one, a meta.json this build can read). A missing folder, a plain file or a folder
    /// of something else is an error naming it.
    pub fn open(dir: impl Into<PathBuf>) -> Result<MaterialFolder, String> {
        let folder = MaterialFolder { dir: dir.into() };
        let dir = &folder.dir;
        if !dir.exists() {
            return Err(format!("{}: no such folder", dir.display()));
        }
        if !dir.is_dir() {
            return Err(format!("{}: not a folder (an enhanced material is a folder written by `uplift enhance`)", dir.display()));
        }
        if !folder.params_path().is_file() {
            return Err(format!("{}: not an enhanced material (no params.exr; `uplift enhance` writes one)", dir.display()));
        }
        if folder.meta_path().is_file() {
            folder.read_meta()?;
        }
        Ok(folder)
    }

    /// Whether `dir` holds a finished enhanced material (meta.json is written last).
    pub fn is_finished(dir: &Path) -> bool {
        dir.join("meta.json").is_file()
    }

    /// Whether `dir` holds a finished fit (latent.exr and fit.json).
    pub fn has_fit(&self) -> bool {
        self.latent_path().is_file() && self.fit_path().is_file()
    }

    pub fn dir(&self) -> &Path {
        &self.dir
    }
    pub fn material_path(&self) -> PathBuf {
        self.dir.join("material.mtlx")
    }
    pub fn params_path(&self) -> PathBuf {
        self.dir.join("params.exr")
    }
    pub fn meta_path(&self) -> PathBuf {
        self.dir.join("meta.json")
    }
    pub fn latent_path(&self) -> PathBuf {
        self.dir.join("latent.exr")
    }
    pub fn fit_path(&self) -> PathBuf {
        self.dir.join("fit.json")
    }
    pub fn masks_dir(&self) -> PathBuf {
        self.dir.join("masks")
    }
    pub fn textures_dir(&self) -> PathBuf {
        self.dir.join("textures")
    }

    /// The folder's name (the material's name in reports).
    pub fn name(&self) -> String {
        self.dir.file_name().map(|s| s.to_string_lossy().to_string()).unwrap_or_default()
    }

    /// meta.json.
    pub fn read_meta(&self) -> Result<Meta, String> {
        let meta: Meta = read_json(&self.meta_path())?;
        check_format(&self.meta_path(), meta.format, META_FORMAT)?;
        Ok(meta)
    }

    /// meta.json, or `None` when the folder has none (folders from before meta.json).
    pub fn read_meta_if_any(&self) -> Result<Option<Meta>, String> {
        if self.meta_path().is_file() {
            self.read_meta().map(Some)
        } else {
            Ok(None)
        }
    }

    /// Writes meta.json (at this build's format).
    pub fn write_meta(&self, meta: &Meta) -> Result<(), String> {
        write_json(&self.meta_path(), &Meta { format: META_FORMAT, ..meta.clone() })
    }

    /// fit.json.
    pub fn read_fit(&self) -> Result<FitRecord, String> {
        let fit: FitRecord = read_json(&self.fit_path())?;
        check_format(&self.fit_path(), fit.format, FIT_FORMAT)?;
        Ok(fit)
    }

    /// Writes fit.json (at this build's format).
    pub fn write_fit(&self, fit: &FitRecord) -> Result<(), String> {
        write_json(&self.fit_path(), &FitRecord { format: FIT_FORMAT, ..fit.clone() })
    }

    /// Writes params.exr (ZIP-compressed float channels).
    pub fn write_params_image(&self, img: &ExrImage) -> Result<(), String> {
        exr::write(&self.params_path(), img, Compression::Zip)
    }

    /// params.exr: `stack`'s parameters (every channel required, but for optional inputs in a
    /// file older than the signature attribute; a file recording another stack's signature is
    /// an error naming the difference), and the diffuse colour and
    /// normals when present. Non-finite values are an error naming the texel.
    pub fn read_params(&self, stack: &Stack) -> Result<ParamsImage, String> {
        let path = self.params_path();
        let img = exr::read(&path)?;
        let recorded = img.attributes.iter().find(|(k, _)| k == STACK_ATTRIBUTE).map(|(_, v)| v);
        if let Some(recorded) = recorded {
            stack.check_signature(recorded).map_err(|e| format!("{}: {e} (enhanced with --stack DIR? pass the same folder)", path.display()))?;
        }
        let (w, h) = (img.width, img.height);
        let n = w * h;
        let np = stack.len();
        let mut params = vec![0.0f32; n * np];
        for (k, p) in stack.parameters().iter().enumerate() {
            let optional = stack.inputs().iter().any(|i| i.name == p.input && i.optional);
            match img.channel(&p.channel) {
                Some(ch) => {
                    for t in 0..n {
                        params[t * np + k] = ch[t];
                    }
                }
                // A file from before the stack had this optional input (it records no stack
                // signature): the input's nodedef value, which is what rules bake for it.
                None if recorded.is_none() && optional => {
                    for t in 0..n {
                        params[t * np + k] = p.default;
                    }
                }
                None => return Err(format!("{}: no channel `{}` (is this an `uplift enhance` params.exr of this stack?)", path.display(), p.channel)),
            }
        }
        let diffuse = match DIFFUSE_CHANNELS.map(|name| img.channel(name)) {
            [Some(r), Some(g), Some(b)] => Some((0..n).flat_map(|t| [r[t], g[t], b[t]]).collect::<Vec<f32>>()),
            _ => None,
        };
        let normals = match NORMAL_CHANNELS.map(|c| img.channel(c)) {
            [Some(x), Some(y), Some(z)] => Some((0..n).map(|t| [x[t], y[t], z[t]]).collect::<Vec<[f32; 3]>>()),
            _ => None,
        };
        let texel = |i: usize, per: usize| (i / per % w, i / per / w);
        if let Some(i) = params.iter().position(|x| !x.is_finite()) {
            let (x, y) = texel(i, np);
            return Err(format!("{}: texel ({x}, {y}) holds a non-finite parameter", path.display()));
        }
        if let Some(i) = diffuse.iter().flatten().position(|x| !x.is_finite()) {
            let (x, y) = texel(i, 3);
            return Err(format!("{}: texel ({x}, {y}) holds a non-finite diffuse colour", path.display()));
        }
        if let Some(t) = normals.iter().flatten().position(|v| !v.iter().all(|x| x.is_finite())) {
            return Err(format!("{}: texel ({}, {}) holds a non-finite normal", path.display(), t % w, t / w));
        }
        Ok(ParamsImage { width: w, height: h, params, diffuse, normals })
    }

    /// latent.exr: its latent channels in order (`latent_channel`; at least the paper's 6,
    /// none missing between; non-finite values are an error).
    pub fn read_latents(&self) -> Result<LatentImage, String> {
        let path = self.latent_path();
        let img = exr::read(&path)?;
        let n = img.width * img.height;
        let mut columns = Vec::new();
        while let Some(ch) = img.channel(&latent_channel(columns.len())) {
            columns.push(ch);
        }
        let channels = columns.len();
        if channels < LATENTS {
            return Err(format!("{}: no channel `{}` (written by `uplift fit`)", path.display(), latent_channel(channels)));
        }
        if channels > MAX_LATENTS {
            return Err(format!("{}: {channels} latent channels (at most {MAX_LATENTS})", path.display()));
        }
        if let Some(stray) = (channels..MAX_LATENTS + 3).map(latent_channel).find(|c| img.channel(c).is_some()) {
            return Err(format!("{}: channel `{stray}` without `{}` before it", path.display(), latent_channel(channels)));
        }
        let mut latents = vec![0.0f32; n * channels];
        for (k, ch) in columns.iter().enumerate() {
            for t in 0..n {
                latents[t * channels + k] = ch[t];
            }
        }
        if let Some(i) = latents.iter().position(|x| !x.is_finite()) {
            let t = i / channels;
            return Err(format!("{}: texel ({}, {}) holds a non-finite latent", path.display(), t % img.width, t / img.width));
        }
        Ok(LatentImage { width: img.width, height: img.height, channels, latents })
    }

    /// Writes latent.exr and latent0.png, latent1.png, … (each latent texture clamped to [0, 1]
    /// and quantised to 8 bits; a last texture's missing channels 0).
    pub fn write_latents(&self, latents: &LatentImage) -> Result<(), String> {
        let (w, h, k) = (latents.width, latents.height, latents.channels);
        let n = w * h;
        if !(1..=MAX_LATENTS).contains(&k) || latents.latents.len() != n * k {
            return Err(format!("{}: {} latent values for {w}×{h} texels of {k}", self.latent_path().display(), latents.latents.len()));
        }
        let l = &latents.latents;
        let mut img = ExrImage::new(w, h);
        for c in 0..k {
            img.push(&latent_channel(c), (0..n).map(|t| l[t * k + c]).collect())?;
        }
        for tex in 0..k.div_ceil(3) {
            let value = move |t: usize, c: usize| if 3 * tex + c < k { l[t * k + 3 * tex + c] } else { 0.0 };
            let px: Vec<u8> = (0..n).flat_map(|t| (0..3).map(move |c| (value(t, c).clamp(0.0, 1.0) * 255.0).round() as u8)).collect();
            let png = image::RgbImage::from_raw(w as u32, h as u32, px).ok_or("latent image size")?;
            let mut bytes = std::io::Cursor::new(Vec::new());
            png.write_to(&mut bytes, image::ImageFormat::Png).map_err(|e| format!("encoding latent{tex}.png: {e}"))?;
            let path = self.dir.join(format!("latent{tex}.png"));
            write_atomically(&path, &bytes.into_inner()).map_err(|e| format!("{}: {e}", path.display()))?;
        }
        // A previous, wider fit's textures would be stale.
        for tex in k.div_ceil(3)..MAX_LATENTS.div_ceil(3) {
            let path = self.dir.join(format!("latent{tex}.png"));
            if path.exists() {
                std::fs::remove_file(&path).map_err(|e| format!("{}: {e}", path.display()))?;
            }
        }
        exr::write(&self.latent_path(), &img, Compression::Zip)
    }
}

/// The material folders under the arguments (a folder with params.exr, or its subfolders that
/// have one), sorted.
pub fn find_material_folders(args: &[PathBuf]) -> Result<Vec<PathBuf>, String> {
    let mut out = Vec::new();
    for a in args {
        if is_material(a) {
            out.push(a.clone());
            continue;
        }
        let entries = std::fs::read_dir(a).map_err(|e| format!("{}: {e}", a.display()))?;
        let mut found: Vec<PathBuf> = entries.filter_map(|e| e.ok().map(|e| e.path())).filter(|p| is_material(p)).collect();
        if found.is_empty() {
            return Err(format!("{}: neither an enhanced material (no params.exr) nor a folder of them", a.display()));
        }
        found.sort();
        out.extend(found);
    }
    Ok(out)
}

/// Whether `dir` looks like an enhanced material (it holds params.exr).
fn is_material(dir: &Path) -> bool {
    dir.join("params.exr").is_file()
}

/// A JSON file as `T`; errors name the file (and serde's line and column).
fn read_json<T: DeserializeOwned>(path: &Path) -> Result<T, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
    serde_json::from_str(&text).map_err(|e| format!("{}:{}:{}: {e}", path.display(), e.line(), e.column()))
}

/// Writes `value` as pretty JSON with a trailing newline, atomically.
/// Writes a record atomically; a number that is not finite (which serde_json would write as
/// `null`) is an error naming its field, and nothing is written. The records' optional fields
/// are left out when absent, so a `null` can only be such a number.
fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<(), String> {
    let tree = serde_json::to_value(value).map_err(|e| format!("{}: {e}", path.display()))?;
    if let Some(field) = null_field(&tree, String::new()) {
        return Err(format!("{}: `{field}` is not a finite number; nothing written", path.display()));
    }
    let mut text = serde_json::to_string_pretty(value).map_err(|e| format!("{}: {e}", path.display()))?;
    text.push('\n');
    write_atomically(path, text.as_bytes()).map_err(|e| format!("{}: {e}", path.display()))
}

/// The path (`a.b[2]`) of the first `null` in a JSON tree.
fn null_field(v: &serde_json::Value, at: String) -> Option<String> {
    match v {
        serde_json::Value::Null => Some(at),
        serde_json::Value::Array(a) => a.iter().enumerate().find_map(|(i, x)| null_field(x, format!("{at}[{i}]"))),
        serde_json::Value::Object(o) => o.iter().find_map(|(k, x)| null_field(x, if at.is_empty() { k.clone() } else { format!("{at}.{k}") })),
        _ => None,
    }
}

/// A file's format must not be newer than what this build reads.
fn check_format(path: &Path, found: u32, supported: u32) -> Result<(), String> {
    if found > supported {
        return Err(format!("{}: format {found} was written by a newer uplift (this build reads formats 0 to {supported})", path.display()));
    }
    Ok(())
}
