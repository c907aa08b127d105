//! `uplift eval FILE.mtlx --output NAME --engine cpu|wgpu --input inputs.csv -o out.csv`:
//! compiles one output and evaluates it for every row of a CSV file.
//!
//! Input columns (all optional, any order; see [`GEOMETRY_COLUMNS`] for the defaults):
//! the geometric columns `texcoord_x,texcoord_y,position_x,…,tangent_z` (object space equals
//! world space), and the kernel's interface inputs by name with component suffixes (`_x/_y/_z/_w`
//! for vectors, `_r/_g/_b/_a` for colors, `_0…` for matrices, none for scalars). A missing
//! interface column takes the input's value in the document; a column naming an input of the
//! output's nodegraph that this output does not read is accepted and ignored, so one CSV serves
//! every output of a graph. Output columns: the output's name as the kernel reports it
//! (`graph/output`, or `output` for a top-level one) with the same suffixes. Textures named by
//! the graph are loaded from their files (see `texture_loader`).

use std::path::PathBuf;
use uplift_base::atomic_write::write_atomically;
use uplift_base::csv_table;
use uplift_compiler::OutputSelection;
use uplift_engines::batch::PatternEngine;
use uplift_engines::cpu_engine::CpuEngine;
use uplift_engines::table_batch::{batch_from_table, graph_inputs, output_columns};
use uplift_engines::wgpu_engine::WgpuEngine;

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Engine {
    /// Generated Rust on the CPU (shipped kernels in-process; others built once with cargo).
    Cpu,
    /// Generated WGSL as wgpu compute shaders.
    Wgpu,
}

#[derive(clap::Args)]
pub struct EvalArgs {
    /// The MaterialX document.
    pub file: PathBuf,
    /// The output to evaluate (`graph/output` or `output`).
    #[arg(long)]
    pub output: String,
    #[arg(long, value_enum, default_value = "wgpu")]
    pub engine: Engine,
    /// CSV of inputs, one row per evaluation.
    #[arg(long)]
    pub input: PathBuf,
    /// CSV file to write, one row per input row.
    #[arg(short = 'o', long = "out")]
    pub out: PathBuf,
    /// Extra library folder (repeatable); MATERIALX_SEARCH_PATH is read too.
    #[arg(long = "library")]
    pub library: Vec<PathBuf>,
    /// Let the document name files anywhere; by default a file it names (a texture) must lie
    /// in the document's folder or a library search path.
    #[arg(long = "allow-any-path")]
    pub allow_any_path: bool,
    /// Evaluate even when a texture file the output reads does not exist: the texture node
    /// returns its `default`, as MaterialX does (without this flag, a missing file is an error).
    #[arg(long)]
    pub allow_missing_textures: bool,
    /// For a BSDF, surfaceshader or material output: the closure context. Its inputs are
    /// `wv_x,wv_y,wv_z` and `wl_*` (eval) or `u_*` (sample: three uniforms in [0, 1)), local
    /// frame (normal +z, tangent +x) unless geometry columns say otherwise; its outputs
    /// `response_*`/`albedo_*`, `throughput_*` (sample: also `wl_*` and `pdf`).
    #[arg(long, value_enum)]
    pub context: Option<super::ContextArg>,
}

/// The document's whole pattern kernel and the offset of `kernel`'s one output in its rows, when
/// that kernel is shipped (in-process on the CPU engine) and `kernel` is a pattern kernel.
fn shipped_whole(compiler: &uplift_compiler::Compiler, args: &EvalArgs, kernel: &uplift_compiler::PatternKernel) -> Option<(uplift_compiler::PatternKernel, usize)> {
    if kernel.context.is_some() || kernel.outputs.len() != 1 || CpuEngine::is_shipped(kernel) {
        return None;
    }
    let whole = compiler.compile_file_in(&args.file, &OutputSelection::AllNumeric, None).kernel?;
    let out = whole.outputs.iter().find(|o| o.name == kernel.outputs[0].name && o.ty == kernel.outputs[0].ty)?;
    let offset = out.offset;
    CpuEngine::is_shipped(&whole).then_some((whole, offset))
}

pub fn run(args: EvalArgs) -> Result<(), String> {
    let compiler = super::compiler(&args.library, args.allow_any_path)?;
    let c = compiler.compile_file_in(&args.file, &OutputSelection::Named(vec![args.output.clone()]), args.context.map(|c| c.context()));
    super::report(&c.diagnostics);
    let Some(kernel) = c.kernel else {
        return Err(format!("{}: cannot evaluate output `{}` (see the errors above)", args.file.display(), args.output));
    };
    if let Some((file, pos)) = kernel.graph.missing_files.first().filter(|_| !args.allow_missing_textures) {
        return Err(format!(
            "{pos}: texture file `{file}` not found: output `{}` would read the node's `default` instead (pass --allow-missing-textures to evaluate it so, as MaterialX does)",
            args.output
        ));
    }
    let input_name = args.input.display().to_string();
    let text = std::fs::read_to_string(&args.input).map_err(|e| format!("{input_name}: cannot read: {e}"))?;
    let table = csv_table::parse(&input_name, &text)?;
    let n = table.rows.len();
    let batch = batch_from_table(&kernel, &graph_inputs(&args.file, &args.output), &table, &input_name)?;
    let named = |e: String| format!("{}: output `{}`: {e}", args.file.display(), args.output);
    let (columns, rows) = match args.engine {
        Engine::Wgpu => (output_columns(&kernel), WgpuEngine::new()?.run_pattern(&kernel, &batch).map_err(named)?.to_rows()),
        Engine::Cpu => match shipped_whole(&compiler, &args, &kernel) {
            // The document's whole pattern kernel ships with the runtime (examples/marble.mtlx):
            // it runs in-process, and this output's columns are kept (the same code the
            // one-output kernel would run, without a runner build).
            Some((whole, offset)) => {
                let width = kernel.output_stride;
                let all = CpuEngine::new()?.run_pattern(&whole, &batch_from_table(&whole, &graph_inputs(&args.file, &args.output), &table, &input_name)?)?.to_rows();
                (output_columns(&kernel), all.chunks_exact(whole.output_stride).flat_map(|r| r[offset..offset + width].to_vec()).collect())
            }
            None => (output_columns(&kernel), CpuEngine::new()?.run_pattern(&kernel, &batch).map_err(named)?.to_rows()),
        },
    };
    let text = csv_table::write(&columns, &rows);
    write_atomically(&args.out, text.as_bytes()).map_err(|e| format!("{}: {e}", args.out.display()))?;
    println!("wrote {} ({n} rows)", args.out.display());
    Ok(())
}
