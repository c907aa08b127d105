//! Builds the CPU kernels the runtime ships: every graph in `runtime/kernels/graphs/`,
//! `examples/marble.mtlx` and the uplift rules' baked outputs (`mtlx/rules/`), compiled by
//! `uplift_compiler::build_api` into `OUT_DIR`; `albedo_table_data.rs`, the pbrlib albedo tables
//! once, which every kernel reading them uses; and `builtin_kernels.rs`, the table `shipped`
//! includes (each kernel's fingerprint, shape and dispatching batch function). Adding a node to
//! `mtlx/libraries/` and rebuilding is all a shipped graph needs.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

fn main() {
    let manifest = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").unwrap());
    let out_dir = PathBuf::from(std::env::var("OUT_DIR").unwrap());
    let graphs_dir = manifest.join("graphs");
    let mut graphs = mtlx_files(&graphs_dir);
    graphs.push(manifest.join("../../examples/marble.mtlx"));
    let mut builder = uplift_compiler::build_api::Builder::new().shared_albedo_tables("crate::albedo_table_data::MX_ALBEDO_TABLE_DATA");
    builder
        .write_albedo_tables("MX_ALBEDO_TABLE_DATA", &out_dir.join("albedo_table_data.rs"))
        .unwrap_or_else(|e| panic!("writing the albedo tables: {e}"));
    for g in &graphs {
        builder = builder.graph(g);
    }
    // Uplift rules (`mtlx/rules/`): the pattern outputs of `uplift_rule` (the uplift_stack
    // parameters and the shading normal) that `uplift enhance` bakes.
    let rules_dir = manifest.join("../../mtlx/rules");
    for r in &mtlx_files(&rules_dir) {
        println!("cargo:rerun-if-changed={}", r.display());
        let outputs = rule_pattern_outputs(r);
        let names: Vec<&str> = outputs.iter().map(String::as_str).collect();
        builder = builder.graph_outputs(r, &names);
        graphs.push(r.clone());
    }
    println!("cargo:rerun-if-changed={}", rules_dir.join("masks").display());
    // BSDF graphs (`graphs/bsdf/`): one kernel per closure context.
    let bsdf_dir = graphs_dir.join("bsdf");
    let bsdf = mtlx_files(&bsdf_dir);
    let mut contexts: Vec<Option<&str>> = vec![None; graphs.len()];
    for g in &bsdf {
        for c in uplift_compiler::ClosureContext::ALL {
            builder = builder.closure_graph(g, c);
            graphs.push(g.clone());
            contexts.push(Some(c.name()));
        }
    }
    let kernels = builder.compile_kernels(&out_dir).unwrap_or_else(|e| panic!("compiling the runtime's graphs:\n{e}"));

    let mut table = String::from("// Written by runtime/kernels/build.rs: the CPU kernels the runtime ships.\n\n");
    let mut entries = String::new();
    for ((graph, kernel), context) in graphs.iter().zip(&kernels).zip(&contexts) {
        let (file, fingerprint) = (&kernel.file, kernel.fingerprint);
        let stem = file.file_stem().unwrap().to_string_lossy().to_string();
        let _ = writeln!(
            table,
            "#[allow(clippy::all, dead_code, unused_imports)]\npub mod {stem} {{\n    include!({:?});\n}}\n",
            file.display().to_string()
        );
        let _ = writeln!(
            entries,
            "    BuiltinKernel {{ name: {stem:?}, source: {:?}, context: {context:?}, fingerprint: {fingerprint:#x}, shape: KernelShape {{ input_columns: {stem}::INPUT_COLUMNS, output_columns: {stem}::OUTPUT_COLUMNS, texture_count: {stem}::TEXTURE_COUNT }}, batch: cpu_batch_fn!({stem}) }},",
            relative(graph, &manifest.join("../.."))
        );
    }
    let _ = writeln!(table, "/// Every shipped kernel.\npub static BUILTIN_KERNELS: &[BuiltinKernel] = &[\n{entries}];");
    std::fs::write(out_dir.join("builtin_kernels.rs"), table).unwrap();

}

/// The `.mtlx` files of a folder, sorted; the folder is watched for changes.
fn mtlx_files(dir: &Path) -> Vec<PathBuf> {
    println!("cargo:rerun-if-changed={}", dir.display());
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "mtlx"))
        .collect();
    files.sort();
    files
}

/// A rule's pattern outputs, `uplift_rule/<name>_out` for every non-closure output.
fn rule_pattern_outputs(rule: &Path) -> Vec<String> {
    let (doc, diags) = mtlx::read_file(rule);
    if let Some(d) = diags.iter().find(|d| d.severity == mtlx::Severity::Error) {
        panic!("{d}");
    }
    let graph = doc.top_level().iter().copied().find(|&id| doc.get(id).name() == "uplift_rule").unwrap_or_else(|| panic!("{}: no uplift_rule", rule.display()));
    doc.children_of(graph, "output")
        .map(|id| doc.get(id))
        .filter(|e| e.name().ends_with("_out") && e.attr("type") != Some("BSDF"))
        .map(|e| format!("uplift_rule/{}", e.name()))
        .collect()
}

/// `path` relative to the repository root, with `/` separators (`..` resolved).
fn relative(path: &Path, root: &Path) -> String {
    let (path, root) = (path.canonicalize().unwrap_or(path.to_path_buf()), root.canonicalize().unwrap_or(root.to_path_buf()));
    path.strip_prefix(&root).unwrap_or(&path).to_string_lossy().replace('\\', "/")
}
