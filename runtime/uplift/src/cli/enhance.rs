//! `uplift enhance INPUT --type auto|0..5 --seed S -o OUT/`: enhances a PBR material by an
//! uplift rule (mtlx/rules/), or by user-written rules (`--rule FILE.mtlx`, repeatable, each
//! material's rule drawn by `--rule-share`; docs/enhance.md, "Write your own rule"). INPUT is a .gltf/.glb or .mtlx file, a folder of conventionally
//! named textures, or a folder of those (batch: one output folder per material under OUT,
//! Types drawn in the paper's proportions, finished outputs skipped on re-run); or give the
//! textures with --base-color, --roughness, --metalness [--normal]. One material writes
//! OUT/material.mtlx, OUT/textures/, OUT/masks/*.png, OUT/params.exr and OUT/meta.json.

use uplift_engines::batch::PatternEngine;
use uplift_engines::cpu_engine::CpuEngine;
use uplift_engines::wgpu_engine::WgpuEngine;
use uplift_enhance::pbr_input::{self, PbrMaterial};
use uplift_base::output_folder::OutputFolder;
use uplift_enhance::pipeline::{batch_names, enhance_batch, enhance_into, EnhanceOptions};
use uplift::shard::{Shard, ShardRun};
use uplift_enhance::rules::{self, EnhancementType};
use clap::Args;
use std::path::PathBuf;

#[derive(Args)]
pub struct EnhanceArgs {
    /// A .gltf/.glb or .mtlx material file, a texture folder, or a folder of those.
    pub input: Option<PathBuf>,
    /// Base color texture (sRGB), instead of INPUT.
    #[arg(long, requires_all = ["roughness", "metalness"], conflicts_with = "input")]
    pub base_color: Option<PathBuf>,
    /// Roughness texture (linear; first channel).
    #[arg(long, requires = "base_color")]
    pub roughness: Option<PathBuf>,
    /// Metalness texture (linear; first channel).
    #[arg(long, requires = "base_color")]
    pub metalness: Option<PathBuf>,
    /// Tangent-space normal map (linear), optional.
    #[arg(long, requires = "base_color")]
    pub normal: Option<PathBuf>,
    /// Enhancement Type: `auto` (drawn in the paper's proportions) or 0 to 5.
    #[arg(long = "type", default_value = "auto")]
    pub kind: String,
    /// A user-written rule (a document with an `uplift_rule` nodegraph), or a folder of them
    /// with their shares in its `shares.json`; repeatable. Replaces the built-in Types.
    #[arg(long = "rule", conflicts_with = "kind")]
    pub rules: Vec<PathBuf>,
    /// The share of each `--rule`, in their order (default: equal shares).
    #[arg(long = "rule-share", requires = "rules")]
    pub rule_shares: Vec<f64>,
    /// The engine the rule's kernel bakes on (cpu: built-in rules run in-process, a user rule in
    /// a runner built once with cargo; wgpu: no build).
    #[arg(long, value_enum, default_value_t = super::eval::Engine::Cpu)]
    pub engine: super::eval::Engine,
    /// Put glints on the stack (paper §5.3): an `uplift_glint` node whose inputs are drawn per
    /// material; `render` applies them to the reference and the neural material.
    #[arg(long)]
    pub glints: bool,
    /// A rule option applied on top of every material's rule: a builtin one (`iridescence`)
    /// or an `uplift_rule_option` document (repeatable; docs/enhance.md).
    #[arg(long = "option", value_name = "NAME|FILE")]
    pub options: Vec<String>,
    /// Shorthand for `--option iridescence`: a thin film on the clearcoat (its Airy
    /// reflectance), thickness and IOR drawn per material; acts where the rule has a coat.
    #[arg(long)]
    pub iridescence: bool,
    /// Seed of every random choice.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Bake resolution WxH (default: the largest input texture, else 256x256).
    #[arg(long)]
    pub resolution: Option<String>,
    /// Width of the square procedural masks.
    #[arg(long, default_value_t = 512, value_parser = super::bounds::TEXTURE_SIDE.parser::<usize>())]
    pub mask_size: usize,
    /// Output folder: a new or empty one, or this command's own earlier output (its
    /// `.uplift-output-enhance` manifest); finished materials of a batch are skipped.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Write into an existing folder that holds files `enhance` did not write: they are kept,
    /// and one with the name of an output is still refused (docs/ARCHITECTURE.md, outputs).
    #[arg(long)]
    pub force: bool,
    /// Enhance only this shard of a batch: `i/N`, or `auto` in a Slurm job array or a
    /// Kubernetes indexed job (docs/scale.md).
    #[arg(long)]
    pub shard: Option<String>,
    #[command(flatten)]
    pub stack: super::StackArgs,
    /// Extra library folder (repeatable; MATERIALX_SEARCH_PATH is read too): files the input
    /// and the rules name (textures, glTF buffers and images, includes) may also lie there.
    #[arg(long = "library")]
    pub library: Vec<PathBuf>,
    /// Let the input and the rules name files anywhere; by default a file they name must lie in
    /// the naming input's folder or a library search path.
    #[arg(long = "allow-any-path")]
    pub allow_any_path: bool,
}

fn parse_type(s: &str) -> Result<Option<EnhancementType>, String> {
    if s == "auto" {
        return Ok(None);
    }
    let k: u32 = s.parse().map_err(|_| format!("--type {s}: expected auto or 0 to 5"))?;
    EnhancementType::new(k).map(Some).map_err(|e| format!("--type {s}: {e}"))
}

/// The rules of a folder (every `*.mtlx`, in name order) with their shares: from the folder's
/// `shares.json` (`{"wet.mtlx": 2, "patina.mtlx": 1}`, one positive share per rule file), or
/// equal without one.
fn rule_folder(dir: &std::path::Path) -> Result<Vec<(PathBuf, f64)>, String> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| format!("{}: {e}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file() && p.extension().is_some_and(|e| e.eq_ignore_ascii_case("mtlx")))
        .collect();
    files.sort();
    if files.is_empty() {
        return Err(format!("{}: no rule documents (.mtlx)", dir.display()));
    }
    let shares_path = dir.join("shares.json");
    if !shares_path.is_file() {
        return Ok(files.into_iter().map(|f| (f, 1.0)).collect());
    }
    let text = std::fs::read_to_string(&shares_path).map_err(|e| format!("{}: {e}", shares_path.display()))?;
    let shares: std::collections::BTreeMap<String, f64> = serde_json::from_str(&text).map_err(|e| format!("{}:{}:{}: {e}", shares_path.display(), e.line(), e.column()))?;
    for (name, share) in &shares {
        if !files.iter().any(|f| f.file_name().is_some_and(|n| n.to_string_lossy() == *name)) {
            return Err(format!("{}: `{name}` is not a rule document of the folder", shares_path.display()));
        }
        if !(share.is_finite() && *share > 0.0) {
            return Err(format!("{}: the share of `{name}` is {share}; shares are positive", shares_path.display()));
        }
    }
    files
        .into_iter()
        .map(|f| {
            let name = f.file_name().map(|n| n.to_string_lossy().to_string()).unwrap_or_default();
            let share = *shares.get(&name).ok_or_else(|| format!("{}: no share for `{name}`", shares_path.display()))?;
            Ok((f, share))
        })
        .collect()
}

fn parse_resolution(s: &str) -> Result<(usize, usize), String> {
    let bad = || format!("--resolution {s}: expected WxH, e.g. 512x512, 1 to 8192 per side");
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(bad)?;
    let (w, h): (usize, usize) = (w.trim().parse().map_err(|_| bad())?, h.trim().parse().map_err(|_| bad())?);
    if w == 0 || h == 0 || w > 8192 || h > 8192 {
        return Err(bad());
    }
    Ok((w, h))
}

pub fn run(args: EnhanceArgs) -> Result<(), String> {
    if !args.rule_shares.is_empty() && args.rule_shares.len() != args.rules.len() {
        return Err(format!("--rule-share: {} shares for {} rules", args.rule_shares.len(), args.rules.len()));
    }
    if let Some(bad) = args.rule_shares.iter().find(|s| !(s.is_finite() && **s > 0.0)) {
        return Err(format!("--rule-share {bad}: a share must be positive"));
    }
    let stack = args.stack.load()?;
    let access = mtlx::FileAccess::for_libraries(&args.library.iter().chain(&args.stack.stack).cloned().collect::<Vec<_>>(), args.allow_any_path);
    let mut user_rules = Vec::new();
    for (k, path) in args.rules.iter().enumerate() {
        if path.is_dir() {
            if !args.rule_shares.is_empty() {
                return Err(format!("{}: a folder of rules takes its shares from its shares.json, not --rule-share", path.display()));
            }
            for (file, share) in rule_folder(path)? {
                user_rules.push((rules::interface_file_with(&file, &stack, &access)?, share));
            }
        } else {
            user_rules.push((rules::interface_file_with(path, &stack, &access)?, args.rule_shares.get(k).copied().unwrap_or(1.0)));
        }
    }
    let options = EnhanceOptions {
        rules: user_rules,
        kind: if args.rules.is_empty() { parse_type(&args.kind)? } else { None },
        seed: args.seed,
        resolution: args.resolution.as_deref().map(parse_resolution).transpose()?,
        mask_size: args.mask_size,
        glints: args.glints,
        rule_options: {
            let mut names = args.options.clone();
            if args.iridescence && !names.iter().any(|n| n == "iridescence") {
                names.push("iridescence".into());
            }
            names.iter().map(|n| uplift_enhance::rule_option::read_option(n, &stack)).collect::<Result<Vec<_>, _>>()?
        },
        stack,
    };
    if options.mask_size == 0 || options.mask_size > 8192 {
        return Err(format!("--mask-size {}: 1 to 8192", options.mask_size));
    }
    let materials: Vec<PbrMaterial> = match (&args.input, &args.base_color) {
        (Some(input), None) => pbr_input::discover(input, &access)?,
        (None, Some(base)) => {
            let name = args.output.file_name().map(|n| n.to_string_lossy().to_string()).unwrap_or_else(|| "material".into());
            vec![pbr_input::from_files(base, args.roughness.as_ref().unwrap(), args.metalness.as_ref().unwrap(), args.normal.as_deref(), &name)?]
        }
        _ => return Err("give INPUT, or --base-color, --roughness and --metalness".into()),
    };
    let engine: Box<dyn PatternEngine> = match args.engine {
        super::eval::Engine::Cpu => Box::new(CpuEngine::new()?),
        super::eval::Engine::Wgpu => Box::new(WgpuEngine::new()?),
    };
    if args.shard.is_some() && args.input.is_none() {
        return Err("--shard splits a batch: give INPUT (a folder of materials, or a document of several)".into());
    }
    if materials.len() == 1 && args.shard.is_none() {
        let e = enhance_into(&materials[0], &options, &args.output, args.force, engine.as_ref())?;
        eprintln!("wrote {} (Type {}, {})", e.out_dir.display(), e.kind.index(), e.rule);
    } else {
        let shard = Shard::from_arg(args.shard.as_deref())?;
        let batch: Vec<(String, &PbrMaterial)> = batch_names(&materials).into_iter().zip(&materials).filter(|(name, _)| shard.is_none_or(|s| s.owns(name))).collect();
        // Claimed before anything (the shard manifest included) is written there.
        let root = OutputFolder::claim(&args.output, "enhance", args.force)?;
        root.create()?;
        let mut run = ShardRun::begin(&args.output, "enhance", shard, batch.iter().map(|(n, _)| n.clone()).collect())?;
        let (done, skipped) = enhance_batch(&batch, &options, &root, args.force, engine.as_ref(), &mut |name, skipped| run.finished(name, skipped))?;
        run.end()?;
        let of = shard.map_or(String::new(), |s| format!(" (shard {s}: {} of {} materials)", batch.len(), materials.len()));
        eprintln!("enhanced {done} material(s) into {}; {skipped} already finished{of}", args.output.display());
    }
    Ok(())
}
