//! Enhancing one PBR material, and a batch of them: choose the Type, draw the rule's scalars,
//! write the textures, masks and self-contained `material.mtlx`, bake every `uplift_stack`
//! input per texel into `params.exr` with the rule's compiled pattern kernel, and write
//! `meta.json`. Everything is written into a staging folder that is renamed into place at the
//! end, so an output folder either is complete or does not exist; a batch skips finished ones.

use crate::gltf_input;
use crate::masks::{self, MaskKind};
use crate::material_writer::{material_document, MaterialSpec, PbrValue};
use crate::pbr_input::{PbrChannel, PbrMaterial, Surface};
use crate::rule_option::RuleOption;
use crate::rules::{self, uniform, EnhancementType, RuleInterface};
use uplift_base::rng::{hash_str, mix64};
use uplift_base::atomic_write::write_atomically;
use uplift_base::output_folder::OutputFolder;
use uplift_engines::batch::{Columns, Geometry, PatternBatch, PatternEngine, TextureData};
use uplift_base::exr::ExrImage;
use uplift_material::meta::META_FORMAT;
use uplift_material::{MaskRecord, MaterialFolder, Meta, NormalSpace};
use uplift_engines::texture_loader::load_texture;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use uplift_compiler::OutputSelection;
use uplift_engines::stack::Stack;

/// How to enhance.
#[derive(Clone, Debug)]
pub struct EnhanceOptions {
    /// A fixed Type, or `None` to draw one in the paper's proportions.
    pub kind: Option<EnhancementType>,
    /// User-written rules with their shares (`--rule`, `--rule-share`): when given, each
    /// material's rule is drawn among them in proportion to the shares, instead of a Type.
    pub rules: Vec<(RuleInterface, f64)>,
    pub seed: u64,
    /// Bake resolution (width, height); default: the largest input texture, else 256².
    pub resolution: Option<(usize, usize)>,
    /// Width of the square masks.
    pub mask_size: usize,
    /// Put glints on the stack (`crate::glints`), their inputs drawn from the seed.
    pub glints: bool,
    /// The stack the rules bake for (`Stack::builtin`, or `--stack DIR`'s).
    pub stack: Arc<Stack>,
    /// Rule options applied on top of every material's rule (`--option`, `--iridescence`).
    pub rule_options: Vec<RuleOption>,
}

/// What was written for one material.
#[derive(Clone, Debug)]
pub struct Enhanced {
    pub kind: EnhancementType,
    /// The rule's name (`type0_haze`, or a user rule's file stem).
    pub rule: String,
    pub out_dir: PathBuf,
    pub scalars: Vec<(String, f64)>,
}

/// Mean of a channel's first component (constants: the value).
fn channel_mean(c: &PbrChannel) -> Result<f32, String> {
    Ok(match c {
        PbrChannel::Constant(v) => v[0],
        PbrChannel::File { path, colorspace } => mean_first(&load_texture(path, Some(colorspace))?),
        PbrChannel::Pixels(t) => mean_first(t),
    })
}

fn mean_first(t: &TextureData) -> f32 {
    let n = (t.width * t.height) as f64;
    (t.rgba.chunks(4).map(|p| p[0] as f64).sum::<f64>() / n) as f32
}

/// The rule for a material: one of the user's rules drawn by their shares when there are any,
/// else the built-in rule of `choose_type`'s Type.
pub fn choose_rule(material: &PbrMaterial, options: &EnhanceOptions) -> Result<RuleInterface, String> {
    if options.rules.is_empty() {
        return rules::interface(choose_type(material, options)?, &options.stack);
    }
    let total: f64 = options.rules.iter().map(|(_, share)| share).sum();
    let u = uniform(options.seed, hash_str("enhancement rule"), 0) * total;
    let mut acc = 0.0;
    for (rule, share) in &options.rules {
        acc += share;
        if u < acc {
            return Ok(rule.clone());
        }
    }
    Ok(options.rules.last().unwrap().0.clone())
}

/// The Type for a material: the requested one (refused for metals when dielectric-only), or a
/// draw in the paper's proportions from the seed.
pub fn choose_type(material: &PbrMaterial, options: &EnhanceOptions) -> Result<EnhancementType, String> {
    let metallic = channel_mean(&material.metalness)? >= 0.5;
    match options.kind {
        Some(t) if t.dielectric_only() && metallic => Err(format!(
            "{}: Type {} is for dielectric materials, and this material's mean metalness is at least 0.5",
            material.source,
            t.index()
        )),
        Some(t) => Ok(t),
        None => Ok(EnhancementType::draw(uniform(options.seed, hash_str("enhancement type"), 0), metallic)),
    }
}

fn texture_size(c: &PbrChannel) -> Result<Option<(usize, usize)>, String> {
    Ok(match c {
        PbrChannel::Constant(_) => None,
        PbrChannel::File { path, .. } => {
            let (w, h) = image::image_dimensions(path).map_err(|e| format!("{}: cannot read texture: {e}", path.display()))?;
            Some((w as usize, h as usize))
        }
        PbrChannel::Pixels(t) => Some((t.width as usize, t.height as usize)),
    })
}

/// Bilinear resampling of linear RGBA to `w × h` (texel centres to texel centres, clamped).
fn resample(t: &TextureData, w: usize, h: usize) -> TextureData {
    let (sw, sh) = (t.width as usize, t.height as usize);
    let mut rgba = vec![0.0f32; w * h * 4];
    for y in 0..h {
        let fy = ((y as f32 + 0.5) * sh as f32 / h as f32 - 0.5).clamp(0.0, (sh - 1) as f32);
        let (y0, ty) = (fy.floor() as usize, fy.fract());
        let y1 = (y0 + 1).min(sh - 1);
        for x in 0..w {
            let fx = ((x as f32 + 0.5) * sw as f32 / w as f32 - 0.5).clamp(0.0, (sw - 1) as f32);
            let (x0, tx) = (fx.floor() as usize, fx.fract());
            let x1 = (x0 + 1).min(sw - 1);
            for c in 0..4 {
                let at = |xx: usize, yy: usize| t.rgba[(yy * sw + xx) * 4 + c];
                let top = at(x0, y0) * (1.0 - tx) + at(x1, y0) * tx;
                let bottom = at(x0, y1) * (1.0 - tx) + at(x1, y1) * tx;
                rgba[(y * w + x) * 4 + c] = top * (1.0 - ty) + bottom * ty;
            }
        }
    }
    TextureData { width: w as u32, height: h as u32, rgba }
}

/// Linear RGBA as a 16-bit PNG: grey for float inputs, RGB otherwise (the encoder takes
/// native-endian samples).
fn png16(t: &TextureData, grey: bool) -> Result<Vec<u8>, String> {
    let q = |v: f32| (v.clamp(0.0, 1.0) * 65535.0).round() as u16;
    let mut bytes = Vec::new();
    let encoder = image::codecs::png::PngEncoder::new(&mut bytes);
    let (w, h) = (t.width, t.height);
    let result = if grey {
        let data: Vec<u16> = t.rgba.chunks(4).map(|p| q(p[0])).collect();
        image::ImageEncoder::write_image(encoder, bytemuck::cast_slice(&data), w, h, image::ExtendedColorType::L16)
    } else {
        let data: Vec<u16> = t.rgba.chunks(4).flat_map(|p| [q(p[0]), q(p[1]), q(p[2])]).collect();
        image::ImageEncoder::write_image(encoder, bytemuck::cast_slice(&data), w, h, image::ExtendedColorType::Rgb16)
    };
    result.map_err(|e| format!("encoding a PNG: {e}"))?;
    Ok(bytes)
}

/// Writes one PBR channel into `dir/textures/` at `size` (copying a file that already has that
/// size, resampling otherwise); returns its value in the document.
fn write_channel(input: &str, c: &PbrChannel, size: (usize, usize), dir: &Path) -> Result<PbrValue, String> {
    let grey = input != "base_color" && input != "normal_map";
    let textures = dir.join("textures");
    let save = |name: String, bytes: &[u8], colorspace: &str| -> Result<PbrValue, String> {
        std::fs::create_dir_all(&textures).map_err(|e| format!("{}: {e}", textures.display()))?;
        let path = textures.join(&name);
        write_atomically(&path, bytes).map_err(|e| format!("{}: {e}", path.display()))?;
        Ok(PbrValue::Texture { file: format!("textures/{name}"), colorspace: colorspace.into() })
    };
    match c {
        PbrChannel::Constant(v) => Ok(PbrValue::Constant(v.clone())),
        // A file is decoded and its texels checked here, where it enters (errors name the
        // user's file, not the copy), then copied as it is or resampled.
        PbrChannel::File { path, colorspace } => {
            let t = load_texture(path, Some(colorspace))?;
            check_texels(input, &t).map_err(|why| format!("{}: {why}", path.display()))?;
            if (t.width as usize, t.height as usize) == size {
                let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("png").to_ascii_lowercase();
                let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
                save(format!("{input}.{ext}"), &bytes, colorspace)
            } else {
                save(format!("{input}.png"), &png16(&resample(&t, size.0, size.1), grey)?, "lin_rec709")
            }
        }
        PbrChannel::Pixels(t) => {
            check_texels(input, t)?;
            let t = if (t.width as usize, t.height as usize) == size { (**t).clone() } else { resample(t, size.0, size.1) };
            save(format!("{input}.png"), &png16(&t, grey)?, "lin_rec709")
        }
    }
}

/// Checks a PBR input's texels where they enter: finite, and for a base color, roughness or
/// metalness in 0..1 (`pbr_input::unit_range`; a normal map's may be any finite value).
fn check_texels(input: &str, t: &TextureData) -> Result<(), String> {
    let channels = if input == "base_color" { 3 } else { 1 };
    for (i, px) in t.rgba.chunks_exact(4).enumerate() {
        let (x, y) = (i % t.width.max(1) as usize, i / t.width.max(1) as usize);
        let v = &px[..if input == "normal_map" { 3 } else { channels }];
        if let Some(bad) = v.iter().find(|c| !c.is_finite()) {
            return Err(format!("{input} texel ({x}, {y}) is {bad}, not a finite number"));
        }
        if input != "normal_map" {
            crate::pbr_input::unit_range(v).map_err(|why| format!("{input} texel ({x}, {y}): {why}"))?;
        }
    }
    Ok(())
}

/// Per-texel geometry of the material's texture space and the object's size.
fn surface_geometry(material: &PbrMaterial, w: usize, h: usize) -> Result<(Vec<Geometry>, f32), String> {
    let texcoord = |x: usize, y: usize| [(x as f32 + 0.5) / w as f32, 1.0 - (y as f32 + 0.5) / h as f32];
    match &material.surface {
        Surface::Plane => {
            let mut g = Vec::with_capacity(w * h);
            for y in 0..h {
                for x in 0..w {
                    let position = [(x as f32 + 0.5) / w as f32 - 0.5, 0.0, (y as f32 + 0.5) / h as f32 - 0.5];
                    g.push(Geometry { texcoord: texcoord(x, y), position, normal: [0.0, 1.0, 0.0], tangent: [1.0, 0.0, 0.0] });
                }
            }
            Ok((g, std::f32::consts::SQRT_2))
        }
        Surface::Gltf { asset, material: k } => {
            let bake = gltf_input::rasterize_uv(asset, *k, w, h)?;
            let d: f32 = (0..3).map(|i| (bake.bbox_max[i] - bake.bbox_min[i]).powi(2)).sum::<f32>().sqrt();
            let g = (0..w * h)
                .map(|i| Geometry { texcoord: texcoord(i % w, i / w), position: bake.position[i], normal: bake.normal[i], tangent: bake.tangent[i] })
                .collect();
            Ok((g, d.max(1e-6)))
        }
    }
}

/// The seed of a mask of a material.
fn mask_seed(seed: u64, kind: MaskKind) -> u64 {
    mix64(seed ^ hash_str(kind.file_stem()))
}

/// Compiles the rule's pattern outputs as if the rule document sat in `dir` (so its
/// `masks/*.png` are the material's): the same kernel the runtime ships (`runtime/kernels/src/generated/`).
pub fn rule_kernel(rule: &RuleInterface, dir: &Path) -> Result<uplift_compiler::PatternKernel, String> {
    let name = dir.join(rule.file_name()).display().to_string();
    let outputs: Vec<String> = stack_outputs(&rule.document).into_iter().map(|o| format!("{}/{o}", rules::RULE_GRAPH)).collect();
    // Compiled as if it lay in the material's folder (so its `masks/…` resolve to the masks
    // written there), but its messages name the user's rule (the lines are the file's).
    compile_outputs(&rule.stack, rule.standalone_text(), &name, outputs).map_err(|e| e.replace(&name, &rule.path))
}

/// The pattern kernel of `outputs` of the document `text` (named `source`), compiled with the
/// stack's library; errors are the compiler's positioned diagnostics.
fn compile_outputs(stack: &Stack, text: &str, source: &str, outputs: Vec<String>) -> Result<uplift_compiler::PatternKernel, String> {
    let (doc, diags) = mtlx::read_str(text, source);
    let c = stack.compiler().compile_document(doc, diags, source, &OutputSelection::Named(outputs));
    if mtlx::has_errors(&c.diagnostics) {
        return Err(c.diagnostics.iter().filter(|d| d.is_error()).map(|d| d.to_string()).collect::<Vec<_>>().join("\n"));
    }
    c.kernel.ok_or_else(|| format!("{source}: no pattern outputs"))
}

/// Puts each output of `kernel` computed in `out` into `img` as its channels (`channel_names`),
/// replacing channels of the same name.
fn put_channels(kernel: &uplift_compiler::PatternKernel, out: &Columns, img: &mut ExrImage) -> Result<(), String> {
    for o in &kernel.outputs {
        let components = o.ty.components().unwrap_or(1);
        for (c, name) in channel_names(&o.name, components, o.ty.is_color()).iter().enumerate() {
            img.channels.retain(|ch| ch.name != *name);
            img.push(name, out.column(o.offset + c).to_vec())?;
        }
    }
    Ok(())
}

/// The rule's baked outputs (`<name>_out`, not closures), in document order.
pub fn stack_outputs(rule: &mtlx::Document) -> Vec<String> {
    let Some(graph) = rule.top_level().iter().copied().find(|&id| rule.get(id).name() == rules::RULE_GRAPH) else { return Vec::new() };
    rule.children_of(graph, "output")
        .map(|id| rule.get(id))
        .filter(|e| e.name().ends_with("_out") && e.attr("type") != Some("BSDF"))
        .map(|e| e.name().to_string())
        .collect()
}

/// An output's EXR channel names: `name` for floats, `name.R/G/B` for colors, `name.X/Y/Z`
/// for vectors.
pub fn channel_names(output: &str, components: usize, is_color: bool) -> Vec<String> {
    let base = output.rsplit('/').next().unwrap_or(output).trim_end_matches("_out");
    match components {
        1 => vec![base.to_string()],
        _ => (if is_color { ["R", "G", "B"] } else { ["X", "Y", "Z"] }).iter().take(components).map(|c| format!("{base}.{c}")).collect(),
    }
}

/// Enhances one material into `out`: a new or empty folder, or `enhance`'s own earlier output
/// (uplift_base::output_folder; a foreign folder is refused).
pub fn enhance(material: &PbrMaterial, options: &EnhanceOptions, out: &Path, engine: &dyn PatternEngine) -> Result<Enhanced, String> {
    enhance_into(material, options, out, false, engine)
}

/// [`enhance`], and with `force` into a folder that holds files `enhance` did not write (they
/// are kept). The output is written into a staging folder beside `out` and put in place at the
/// end: renamed as a whole onto a new path; onto its own earlier output, its files replace that
/// output's (and the folder's `fit.json`, the record of a fit of the replaced parameters, is
/// removed so that a batch `fit` refits it), every other file left as it was.
pub fn enhance_into(material: &PbrMaterial, options: &EnhanceOptions, out: &Path, force: bool, engine: &dyn PatternEngine) -> Result<Enhanced, String> {
    let mut claim = OutputFolder::claim(out, "enhance", force)?;
    let rule = choose_rule(material, options)?;
    let kind = rule.kind;
    let mut scalars = rules::draw_all(&rule.random, options.seed);
    for o in &options.rule_options {
        o.check_against(&rule)?;
        scalars.extend(rules::draw_all(&o.random, options.seed));
    }
    let parent = out.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    std::fs::create_dir_all(parent).map_err(|e| format!("{}: {e}", parent.display()))?;
    let leaf = out.file_name().map(|n| n.to_string_lossy().to_string()).ok_or_else(|| format!("{}: not a folder name", out.display()))?;
    // What a killed run left: its staging folder, or the replaced output it was removing
    // (`.old-`, the name builds before output_folder used).
    uplift_base::atomic_write::remove_stale(parent, &format!(".{leaf}.staging-"), "");
    uplift_base::atomic_write::remove_stale(parent, &format!(".{leaf}.old-"), "");
    let staging = parent.join(format!(".{leaf}.staging-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&staging);
    std::fs::create_dir_all(&staging).map_err(|e| format!("{}: {e}", staging.display()))?;
    let result = write_outputs(material, options, kind, &rule, &scalars, &staging, engine).and_then(|()| {
        let replacing = claim.owns("meta.json");
        claim.install(&staging, Some("meta.json"))?;
        if replacing {
            let _ = std::fs::remove_file(out.join("fit.json"));
        }
        Ok(())
    });
    if let Err(e) = result {
        let _ = std::fs::remove_dir_all(&staging);
        return Err(e);
    }
    let name = std::iter::once(rule.name.as_str()).chain(options.rule_options.iter().map(|o| o.name.as_str())).collect::<Vec<_>>().join("+");
    Ok(Enhanced { kind, rule: name, out_dir: out.to_path_buf(), scalars })
}

fn write_outputs(
    material: &PbrMaterial,
    options: &EnhanceOptions,
    kind: EnhancementType,
    rule: &RuleInterface,
    scalars: &[(String, f64)],
    dir: &Path,
    engine: &dyn PatternEngine,
) -> Result<(), String> {
    // Resolution: the largest texture, unless given.
    let mut size = options.resolution;
    if size.is_none() {
        for (_, c) in material.channels() {
            if let Some(s) = texture_size(c)? {
                size = Some(size.map_or(s, |(w, h): (usize, usize)| (w.max(s.0), h.max(s.1))));
            }
        }
    }
    let (w, h) = size.unwrap_or((256, 256));
    if w == 0 || h == 0 || w > 8192 || h > 8192 {
        return Err(format!("bake resolution {w}x{h}: 1 to 8192 texels per side"));
    }

    let (geometry, object_size) = surface_geometry(material, w, h)?;
    let mut pbr: Vec<(String, PbrValue)> = Vec::new();
    for (input, c) in material.channels() {
        pbr.push((input.to_string(), write_channel(input, c, (w, h), dir)?));
    }
    pbr.push(("object_size".into(), PbrValue::Constant(vec![object_size])));

    let masks_dir = dir.join("masks");
    std::fs::create_dir_all(&masks_dir).map_err(|e| format!("{}: {e}", masks_dir.display()))?;
    for (_, kind) in &rule.masks {
        masks::generate(*kind, mask_seed(options.seed, *kind), options.mask_size).write_png(&masks_dir.join(format!("{}.png", kind.file_stem())))?;
    }

    let glint = if options.glints { Some(crate::glints::draw(mix64(options.seed ^ hash_str("glints")), object_size)?) } else { None };
    let doc = material_document(&MaterialSpec { rule, options: &options.rule_options, scalars, pbr: &pbr, glint: glint.as_ref() })?;
    let path = dir.join("material.mtlx");
    write_atomically(&path, mtlx::write_string(&doc).as_bytes()).map_err(|e| format!("{}: {e}", path.display()))?;

    let folder = MaterialFolder::create(dir);
    let mut params = bake(rule, scalars, &pbr, dir, &geometry, w, h, engine)?;
    for o in &options.rule_options {
        bake_option(o, &rule.stack, scalars, &geometry, &mut params, engine)?;
    }
    // Never a non-finite parameter on disk: the rule's arithmetic on its inputs is checked here,
    // naming the channel and texel (an input past its range, a division by zero in the rule).
    for c in &params.channels {
        if let Some(i) = c.data.iter().position(|x| !x.is_finite()) {
            return Err(format!("{}: the rule gives `{}` = {} at texel ({}, {}); parameters must be finite", rule.path, c.name, c.data[i], i % w, i / w));
        }
    }
    folder.write_params_image(&params)?;
    // meta.json last: its presence marks a finished material.
    let mut meta = Meta { glint, ..meta(material, kind, options.seed, scalars, (w, h), object_size, rule) };
    for o in &options.rule_options {
        meta.rule += &format!(" + {}", o.path);
    }
    folder.write_meta(&meta)
}

/// Evaluates the rule's kernel at every texel: the PBR inputs read from the written textures
/// (exactly what the document's image nodes read at texel centres), the drawn scalars, and the
/// texel's geometry.
#[allow(clippy::too_many_arguments)]
fn bake(
    rule: &RuleInterface,
    scalars: &[(String, f64)],
    pbr: &[(String, PbrValue)],
    dir: &Path,
    geometry: &[Geometry],
    w: usize,
    h: usize,
    engine: &dyn PatternEngine,
) -> Result<ExrImage, String> {
    let kernel = rule_kernel(rule, dir)?;
    let n = w * h;
    let mut rows = vec![0.0f32; n * kernel.input_stride];
    for input in &kernel.inputs {
        let name = input.input.name.as_str();
        let width = input.input.default.len().max(1);
        let constant = |v: &[f32], rows: &mut Vec<f32>| {
            for r in 0..n {
                rows[r * kernel.input_stride + input.offset..][..width].copy_from_slice(&v[..width]);
            }
        };
        if let Some((_, v)) = scalars.iter().find(|(s, _)| s == name) {
            constant(&[*v as f32], &mut rows);
        } else if let Some((_, value)) = pbr.iter().find(|(p, _)| p == name) {
            match value {
                PbrValue::Constant(v) => constant(v, &mut rows),
                PbrValue::Texture { file, colorspace } => {
                    let t = load_texture(&dir.join(file), Some(colorspace))?;
                    if (t.width as usize, t.height as usize) != (w, h) {
                        return Err(format!("{file}: {}x{} texels, the bake is {w}x{h}", t.width, t.height));
                    }
                    for r in 0..n {
                        rows[r * kernel.input_stride + input.offset..][..width].copy_from_slice(&t.rgba[r * 4..r * 4 + width]);
                    }
                }
            }
        } else {
            constant(&input.input.default, &mut rows);
        }
    }
    let textures = kernel
        .textures
        .iter()
        .map(|t| load_texture(&t.path, t.colorspace.as_deref()))
        .collect::<Result<Vec<_>, _>>()?;
    let batch = PatternBatch { geometry: Geometry::columns(geometry), inputs: Columns::from_rows(&rows, kernel.input_stride), textures, points_per_group: 1 };
    let out = engine.run_pattern(&kernel, &batch)?;
    let mut img = ExrImage::new(w, h);
    put_channels(&kernel, &out, &mut img)?;
    // Optional stack inputs the rule leaves out keep their nodedef values.
    for p in rule.stack.parameters() {
        if img.channel(&p.channel).is_none() {
            img.push(&p.channel, vec![p.default; n])?;
        }
    }
    img.attributes.push(("uplift_rule".into(), rule.name.clone()));
    img.attributes.push((uplift_material::folder::STACK_ATTRIBUTE.into(), rule.stack.signature()));
    Ok(img)
}

/// Bakes a rule option's outputs into `img` (replacing the rule's channels of the same name):
/// the option's own kernel on its drawn scalars at every texel.
fn bake_option(option: &RuleOption, stack: &Stack, scalars: &[(String, f64)], geometry: &[Geometry], img: &mut ExrImage, engine: &dyn PatternEngine) -> Result<(), String> {
    let kernel = compile_outputs(stack, &option.text(), &option.path, option.kernel_outputs())?;
    let n = geometry.len();
    let mut rows = vec![0.0f32; n * kernel.input_stride];
    for input in &kernel.inputs {
        let (_, v) = scalars.iter().find(|(s, _)| *s == input.input.name).ok_or_else(|| format!("{}: the option's outputs read `{}`, which is not one of its random scalars", option.path, input.input.name))?;
        for r in 0..n {
            rows[r * kernel.input_stride + input.offset] = *v as f32;
        }
    }
    let batch = PatternBatch { geometry: Geometry::columns(geometry), inputs: Columns::from_rows(&rows, kernel.input_stride), textures: vec![], points_per_group: 1 };
    put_channels(&kernel, &engine.run_pattern(&kernel, &batch)?, img)
}

/// meta.json of a material enhanced by `kind` with `seed`.
fn meta(material: &PbrMaterial, kind: EnhancementType, seed: u64, scalars: &[(String, f64)], size: (usize, usize), object_size: f32, rule: &RuleInterface) -> Meta {
    Meta {
        format: META_FORMAT,
        kind: kind.index() as u32,
        rule: rule.path.clone(),
        seed,
        source: material.source.clone(),
        name: material.name.clone(),
        resolution: [size.0, size.1],
        object_size,
        normal_space: match material.surface {
            Surface::Plane => NormalSpace::Plane,
            Surface::Gltf { .. } => NormalSpace::World,
        },
        scalars: scalars.iter().map(|(k, v)| (k.clone(), *v as f32)).collect(),
        masks: rule.masks.iter().map(|(input, k)| (input.clone(), MaskRecord { file: format!("masks/{}.png", k.file_stem()), seed: mask_seed(seed, *k) })).collect(),
        uplift: env!("CARGO_PKG_VERSION").to_string(),
        glint: None,
    }
}

/// The output folder names of a batch, in its order: each material's name, made unique by a
/// suffix (`name_2`, `name_3`, …) where an earlier one took it. The names are the batch's
/// asset ids: seeds and shard assignment derive from them.
pub fn batch_names(materials: &[PbrMaterial]) -> Vec<String> {
    let mut used: std::collections::HashSet<String> = std::collections::HashSet::new();
    materials
        .iter()
        .map(|m| {
            let mut name = m.name.clone();
            let mut k = 2;
            while used.contains(&name) {
                name = format!("{}_{k}", m.name);
                k += 1;
            }
            used.insert(name.clone());
            name
        })
        .collect()
}

/// Enhances each `(name, material)` into `out/<name>/`, one seed per material derived from
/// `options.seed` and its name (so a material's output does not depend on the rest of the
/// batch, or on how it is split); finished outputs (a `meta.json` present) are skipped.
/// `finished(name, skipped)` runs after each. Shows a progress bar. Returns (enhanced,
/// skipped) counts. `out` is the batch folder as the caller claimed it for `enhance`
/// (uplift_base::output_folder, before anything is written there); each material's folder is
/// checked against it (a foreign one of that name is refused) and claimed itself.
pub fn enhance_batch(
    batch: &[(String, &PbrMaterial)],
    options: &EnhanceOptions,
    root: &OutputFolder,
    force: bool,
    engine: &dyn PatternEngine,
    finished: &mut dyn FnMut(&str, bool) -> Result<(), String>,
) -> Result<(usize, usize), String> {
    let bar = indicatif::ProgressBar::new(batch.len() as u64);
    bar.set_style(indicatif::ProgressStyle::with_template("{bar:30} {pos}/{len} {msg}").map_err(|e| e.to_string())?);
    root.create()?;
    let (mut done, mut skipped) = (0, 0);
    for (name, m) in batch {
        // Each material's folder is claimed on its own (its manifest inside); the batch folder's
        // manifest is not rewritten per material, so concurrent shards never race on it.
        root.check(name)?;
        let dir = root.dir().join(name);
        bar.set_message(name.clone());
        let skip = MaterialFolder::is_finished(&dir);
        if skip {
            skipped += 1;
        } else {
            let o = EnhanceOptions { seed: mix64(options.seed ^ hash_str(name)), ..options.clone() };
            enhance_into(m, &o, &dir, force, engine).map_err(|e| format!("{name}: {e}"))?;
            done += 1;
        }
        finished(name, skip)?;
        bar.inc(1);
    }
    bar.finish_and_clear();
    Ok((done, skipped))
}
