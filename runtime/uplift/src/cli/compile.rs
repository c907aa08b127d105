//! `uplift compile FILE.mtlx [--output NAME] --target wgsl|spirv|msl|glsl|hlsl|rust -o DIR`:
//! writes the pattern kernel and, with `--dump-ir`, the graph IR (`DIR/<stem>.ir`). With
//! `--bench` it instead times library loading and repeated compilation and prints the figures.
//!
//! Targets other than WGSL go through naga's own backends on the kernel's validated Module:
//! `spirv` → `<stem>.spv` (binary SPIR-V 1.0 words), `msl` → `<stem>.metal` (MSL 2.0), `glsl` →
//! `<stem>.comp.glsl` (GLSL 4.50 core compute shader), `hlsl` → `<stem>.hlsl` (shader model
//! 5.1). The entry point is `mx_main` (GLSL requires `main`). `rust` → `<stem>.rs`: our own
//! naga → Rust writer (`uplift_compiler::backend_rust`), a module with `mx_pattern_batch`.

use uplift_base::atomic_write::write_atomically;
use std::path::PathBuf;
use uplift_compiler::kernel::ENTRY_POINT;
use uplift_compiler::{OutputSelection, PatternKernel};

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Target {
    Wgsl,
    Spirv,
    Msl,
    Glsl,
    Hlsl,
    Rust,
}

impl Target {
    /// The file name suffix the target writes after the document's stem.
    pub fn extension(self) -> &'static str {
        match self {
            Target::Wgsl => "wgsl",
            Target::Spirv => "spv",
            Target::Msl => "metal",
            Target::Glsl => "comp.glsl",
            Target::Hlsl => "hlsl",
            Target::Rust => "rs",
        }
    }
}

/// The kernel in `target`'s language (bytes to write); a backend error becomes a message.
pub fn emit(kernel: &PatternKernel, target: Target) -> Result<Vec<u8>, String> {
    use naga::back;
    let (module, info) = (&kernel.module, &kernel.info);
    let stage = naga::ShaderStage::Compute;
    let entry = ENTRY_POINT.to_string();
    match target {
        Target::Wgsl => Ok(kernel.wgsl.clone().into_bytes()),
        Target::Spirv => {
            let options = back::spv::Options { flags: back::spv::WriterFlags::empty(), ..Default::default() };
            let pipeline = back::spv::PipelineOptions { shader_stage: stage, entry_point: entry };
            let words = back::spv::write_vec(module, info, &options, Some(&pipeline)).map_err(|e| format!("SPIR-V backend: {e}"))?;
            Ok(words.iter().flat_map(|w| w.to_le_bytes()).collect())
        }
        Target::Msl => {
            let options = back::msl::Options {
                lang_version: (2, 0),
                per_entry_point_map: [(entry.clone(), msl_resources(module))].into_iter().collect(),
                fake_missing_bindings: false,
                ..Default::default()
            };
            let pipeline = back::msl::PipelineOptions { entry_point: Some((stage, entry)), ..Default::default() };
            let (text, _) = back::msl::write_string(module, info, &options, &pipeline).map_err(|e| format!("MSL backend: {e}"))?;
            Ok(text.into_bytes())
        }
        Target::Glsl => {
            // Explicit `layout(binding = N)`: each resource keeps its WGSL binding number.
            let binding_map = module.global_variables.iter().filter_map(|(_, g)| g.binding).map(|b| (b, b.binding as u8)).collect();
            let options = back::glsl::Options {
                version: back::glsl::Version::Desktop(450),
                writer_flags: back::glsl::WriterFlags::empty(),
                binding_map,
                ..Default::default()
            };
            let pipeline = back::glsl::PipelineOptions { shader_stage: stage, entry_point: entry, multiview: None };
            let mut text = String::new();
            let mut w = back::glsl::Writer::new(&mut text, module, info, &options, &pipeline, naga::proc::BoundsCheckPolicies::default())
                .map_err(|e| format!("GLSL backend: {e}"))?;
            w.write().map_err(|e| format!("GLSL backend: {e}"))?;
            Ok(text.into_bytes())
        }
        Target::Hlsl => {
            let options = back::hlsl::Options { shader_model: back::hlsl::ShaderModel::V5_1, ..Default::default() };
            let pipeline = back::hlsl::PipelineOptions { entry_point: Some((stage, entry)) };
            let mut text = String::new();
            let mut w = back::hlsl::Writer::new(&mut text, &options, &pipeline);
            w.write(module, info, None).map_err(|e| format!("HLSL backend: {e}"))?;
            Ok(text.into_bytes())
        }
        Target::Rust => uplift_compiler::backend_rust::write_rust_kernel(kernel).map(String::into_bytes).map_err(|e| format!("Rust backend: {e}")),
    }
}

#[derive(clap::Args)]
pub struct CompileArgs {
    /// The MaterialX document(s). With --bench, every .mtlx under the given folders too.
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
    /// Output to compile (`graph/output` or `output`; repeatable). Default: every numeric output.
    #[arg(long)]
    pub output: Vec<String>,
    #[arg(long, value_enum, default_value = "wgsl")]
    pub target: Target,
    /// Output folder.
    #[arg(short = 'o', long = "out-dir", default_value = ".")]
    pub out_dir: PathBuf,
    /// Also write the graph IR dump.
    #[arg(long)]
    pub dump_ir: bool,
    /// Extra library folder (repeatable); MATERIALX_SEARCH_PATH is read too.
    #[arg(long = "library")]
    pub library: Vec<PathBuf>,
    /// Let the document name files anywhere; by default a file it names (a texture) must lie
    /// in the document's folder or a library search path.
    #[arg(long = "allow-any-path")]
    pub allow_any_path: bool,
    /// Library folders loaded before the builtin one (a redefined `uplift_stack` with new lobes,
    /// as for `enhance`; repeatable).
    #[arg(long = "stack", value_name = "DIR")]
    pub stack: Vec<PathBuf>,
    /// Time library loading and per-document compilation instead of writing files.
    #[arg(long)]
    pub bench: bool,
    /// Compile the BSDF, surfaceshader or material output in this closure context (its
    /// directions become the first inputs) instead of the pattern outputs.
    #[arg(long, value_enum)]
    pub context: Option<super::ContextArg>,
    /// Specialise: bind interface input NAME to the constant VALUE (MaterialX value text, e.g.
    /// `fuzz_weight=0` or `scatter_color=0.5,0.5,0.5`; repeatable). The input leaves the
    /// kernel's interface and what depends on it folds: a lobe whose weight becomes 0 leaves
    /// the kernel.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    pub set: Vec<String>,
}

/// Metal argument slots for the kernel's resources: buffers in `[[buffer(k)]]` in binding order,
/// then the buffer-sizes buffer; textures in `[[texture(k)]]` in binding order.
fn msl_resources(module: &naga::Module) -> naga::back::msl::EntryPointResources {
    use naga::back::msl::{BindTarget, EntryPointResources};
    let mut globals: Vec<(&naga::ResourceBinding, &naga::GlobalVariable)> =
        module.global_variables.iter().filter_map(|(_, g)| g.binding.as_ref().map(|b| (b, g))).collect();
    globals.sort_by_key(|(b, _)| (b.group, b.binding));
    let (mut buffers, mut textures) = (0u8, 0u8);
    let mut resources = naga::back::msl::BindingMap::new();
    for (binding, g) in globals {
        let mut target = BindTarget::default();
        if matches!(module.types[g.ty].inner, naga::TypeInner::Image { .. }) {
            target.texture = Some(textures);
            textures += 1;
        } else {
            target.buffer = Some(buffers);
            target.mutable = matches!(g.space, naga::AddressSpace::Storage { access } if access.contains(naga::StorageAccess::STORE));
            buffers += 1;
        }
        resources.insert(*binding, target);
    }
    EntryPointResources { resources, immediates_buffer: None, sizes_buffer: Some(buffers) }
}

pub fn run(args: CompileArgs) -> Result<(), String> {
    if args.bench {
        return crate::cli::compile_bench::run(&args.files, &args.library, args.context.map(|c| c.context()));
    }
    let mut compiler = super::layered_compiler(&args.stack, &args.library, args.allow_any_path)?;
    for binding in &args.set {
        let Some((name, value)) = binding.split_once('=') else {
            return Err(format!("--set {binding}: expected NAME=VALUE"));
        };
        compiler.constant_inputs.push((name.trim().to_string(), value.trim().to_string()));
    }
    let selection = if args.output.is_empty() { OutputSelection::AllNumeric } else { OutputSelection::Named(args.output.clone()) };
    let context = args.context.map(|c| c.context());
    let mut failed = false;
    for file in &args.files {
        let stem = file.file_stem().map(|s| s.to_string_lossy().to_string()).unwrap_or_else(|| "kernel".into());
        // A closure context without --output: each renderable element into its own file
        // (`<stem>_<element>`, as MaterialX's generateshader.py writes one per element) when the
        // document holds several; one kernel named after the document otherwise.
        let renderable = match (context, args.output.is_empty()) {
            (Some(_), true) => compiler.renderable_outputs(file),
            _ => Vec::new(),
        };
        let units: Vec<(OutputSelection, String)> = match renderable.len() > 1 {
            true => renderable.iter().map(|n| (OutputSelection::Named(vec![n.clone()]), format!("{stem}_{}", n.replace('/', "_")))).collect(),
            false => vec![(selection.clone(), stem.clone())],
        };
        for (selection, name) in units {
            let c = compiler.compile_file_in(file, &selection, context);
            let errors = super::report(&c.diagnostics);
            failed |= errors;
            let Some(kernel) = c.kernel else {
                // Never exit 0 with nothing written.
                if !errors {
                    failed = true;
                    match (context, c.skipped_closures.is_empty()) {
                        (None, false) => eprintln!(
                            "{}: error: nothing written: its outputs ({}) are closures, which compile in a closure context: give --context eval|albedo|sample|pdf",
                            file.display(),
                            c.skipped_closures.join(", ")
                        ),
                        _ => eprintln!("{}: error: nothing written: the document has nothing to compile", file.display()),
                    }
                }
                continue;
            };
            std::fs::create_dir_all(&args.out_dir).map_err(|e| format!("{}: cannot create folder: {e}", args.out_dir.display()))?;
            let bytes = emit(&kernel, args.target).map_err(|e| format!("{}: {e}", file.display()))?;
            let path = args.out_dir.join(format!("{name}.{}", args.target.extension()));
            write_atomically(&path, &bytes).map_err(|e| format!("{}: {e}", path.display()))?;
            println!("wrote {}", path.display());
            if args.dump_ir {
                let path = args.out_dir.join(format!("{name}.ir"));
                write_atomically(&path, kernel.graph.dump().as_bytes()).map_err(|e| format!("{}: {e}", path.display()))?;
            }
        }
    }
    if failed {
        Err(String::new())
    } else {
        Ok(())
    }
}
