//! Snapshot tests, naga style: every `tests/in/*.mtlx` (sorted; sub-folders such as
//! `tests/in/include/` and `tests/in/images/` hold support files, not inputs) is compiled and
//! its graph IR, WGSL kernel and Rust kernel are compared with `tests/out/ir/<stem>.ir`,
//! `tests/out/wgsl/<stem>.wgsl` and `tests/out/rs/<stem>.rs`. Every emitted WGSL text is parsed
//! and validated again by naga; every Rust kernel is compiled (and a few are run) by the test
//! crate `tests/rs_compile` (`cargo test -p uplift_rs_snapshots`).
//!
//! To accept new output: `UPLIFT_BLESS=1 cargo test -p uplift_compiler --test snapshots`,
//! then review the changes with `git diff tests/out`.
//!
//! Documents are compiled with their path relative to the repository root
//! (`tests/in/x.mtlx`), which the WGSL header names; no output may contain an absolute path of
//! the machine that ran the test.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use uplift_compiler::{Compiler, OutputSelection};

/// Inputs that are valid MaterialX but that the compiler cannot compile yet. Each is skipped
/// (with a note) while it keeps failing; once it compiles, the test fails until its entry is
/// removed here and its outputs are blessed.
const KNOWN_FAILURES: &[(&str, &str)] = &[];

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().expect("compiler/ has a parent").to_path_buf()
}

fn blessing() -> bool {
    std::env::var_os("UPLIFT_BLESS").is_some_and(|v| !v.is_empty() && v != "0")
}

/// The first line where `expected` and `actual` differ, as a message.
fn first_difference(expected: &str, actual: &str) -> String {
    let (mut e, mut a) = (expected.lines(), actual.lines());
    let mut n = 1;
    loop {
        match (e.next(), a.next()) {
            (Some(x), Some(y)) if x == y => n += 1,
            (None, None) => {
                return "the texts differ only in line endings or a final newline".into();
            }
            (x, y) => {
                return format!(
                    "first difference at line {n}:\n      expected: {}\n      actual:   {}",
                    x.map_or("<end of file>".to_string(), |s| format!("{s:?}")),
                    y.map_or("<end of file>".to_string(), |s| format!("{s:?}")),
                );
            }
        }
    }
}

/// Compares `actual` with the snapshot at `rel` (relative to the repository root), or writes
/// it when blessing. Returns a failure message.
fn check_snapshot(root: &Path, rel: &str, actual: &str, bless: bool) -> Option<String> {
    let path = root.join(rel);
    if bless {
        let current = std::fs::read_to_string(&path).ok();
        if current.as_deref() != Some(actual) {
            std::fs::create_dir_all(path.parent().unwrap()).unwrap();
            std::fs::write(&path, actual).unwrap_or_else(|e| panic!("cannot write {rel}: {e}"));
            eprintln!("blessed {rel}");
        }
        return None;
    }
    match std::fs::read_to_string(&path) {
        Err(_) => Some(format!("{rel} is missing (run with UPLIFT_BLESS=1 and review with git diff)")),
        Ok(expected) if expected == actual => None,
        Ok(expected) => Some(format!(
            "{rel} differs from the compiler's output; {}\n    (run with UPLIFT_BLESS=1 and review with git diff)",
            first_difference(&expected, actual)
        )),
    }
}

/// Absolute paths of this machine that must never appear in a snapshot.
fn forbidden_paths(root: &Path) -> Vec<String> {
    let mut v = vec![root.display().to_string()];
    if let Ok(c) = root.canonicalize() {
        v.push(c.display().to_string());
    }
    v.push(std::env::temp_dir().display().to_string());
    if let Some(home) = std::env::var_os("HOME") {
        let h = PathBuf::from(home).display().to_string();
        if h.len() > 1 {
            v.push(h);
        }
    }
    v.retain(|p| p.len() > 1);
    v
}

fn inputs(root: &Path) -> Vec<String> {
    let dir = root.join("tests/in");
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("cannot list {}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file() && p.extension().is_some_and(|e| e == "mtlx"))
        .map(|p| p.file_stem().unwrap().to_string_lossy().to_string())
        .collect();
    names.sort();
    names
}

#[test]
fn snapshots() {
    let root = repo_root();
    // Positions and the WGSL header name documents relative to the repository root.
    std::env::set_current_dir(&root).unwrap();
    let bless = blessing();
    let compiler = Compiler::builtin();
    let forbidden = forbidden_paths(&root);
    let names = inputs(&root);
    assert!(names.len() >= 45, "expected at least 45 snapshot inputs in tests/in, found {}", names.len());

    let mut failures: Vec<String> = Vec::new();
    let mut notes: Vec<String> = Vec::new();
    for stem in &names {
        let source = format!("tests/in/{stem}.mtlx");
        let c = compiler.compile_file(Path::new(&source), &OutputSelection::AllNumeric);
        let errors: Vec<String> = c.diagnostics.iter().filter(|d| d.is_error()).map(|d| d.to_string()).collect();
        let known = KNOWN_FAILURES.iter().find(|(n, _)| n == stem);
        let (graph, kernel) = match (c.graph, c.kernel) {
            (Some(g), Some(k)) if errors.is_empty() => (g, k),
            (_, _) => {
                match known {
                    Some((_, why)) => notes.push(format!("{source}: known failure ({why}):\n    {}", errors.join("\n    "))),
                    None => failures.push(format!("{source} does not compile:\n    {}", errors.join("\n    "))),
                }
                continue;
            }
        };
        if known.is_some() {
            failures.push(format!(
                "{source} compiles now: remove it from KNOWN_FAILURES in compiler/tests/snapshots.rs and bless its outputs"
            ));
            continue;
        }
        let ir = graph.dump();
        let wgsl = kernel.wgsl.clone();
        let rs = match uplift_compiler::backend_rust::write_rust_kernel(&kernel) {
            Ok(text) => text,
            Err(e) => {
                failures.push(format!("{source}: the Rust writer failed: {e}"));
                String::new()
            }
        };
        for (what, text) in [("IR", &ir), ("WGSL", &wgsl), ("Rust", &rs)] {
            for p in &forbidden {
                if text.contains(p.as_str()) {
                    failures.push(format!("{source}: the {what} output contains the absolute path `{p}`"));
                }
            }
        }
        if !wgsl.contains(&format!("from {source}.")) {
            failures.push(format!("{source}: the WGSL header does not name the source as `{source}`"));
        }
        let rs_header = rs.lines().next().unwrap_or_default();
        if !rs_header.starts_with("// Generated by uplift (template: templates/pattern_kernel.rs") || !rs_header.contains(&format!("from {source}.")) {
            failures.push(format!("{source}: the Rust header does not name its template and `{source}`: {rs_header:?}"));
        }
        if rs.contains("unsafe") {
            failures.push(format!("{source}: the Rust kernel contains `unsafe`"));
        }
        for (i, t) in kernel.textures.iter().enumerate() {
            let file = t.path.file_name().unwrap().to_string_lossy().to_string();
            let line = ir.lines().find(|l| l.starts_with(&format!("texture #{i} ")));
            if line.is_none_or(|l| !l.starts_with(&format!("texture #{i} {file} "))) {
                failures.push(format!("{source}: texture #{i} is not dumped by file name only ({file}): {line:?}"));
            }
        }
        failures.extend(check_snapshot(&root, &format!("tests/out/ir/{stem}.ir"), &ir, bless));
        failures.extend(check_snapshot(&root, &format!("tests/out/wgsl/{stem}.wgsl"), &wgsl, bless));
        if !rs.is_empty() {
            failures.extend(check_snapshot(&root, &format!("tests/out/rs/{stem}.rs"), &rs, bless));
        }
        // The emitted text (as written to the snapshot) parses and validates on its own.
        if let Err(e) = uplift_compiler::lower::to_naga(&wgsl) {
            failures.push(format!("{source}: emitted WGSL does not re-validate with naga: {}", e.0));
        }
    }

    // Snapshots whose input is gone.
    for (sub, ext) in [("ir", "ir"), ("wgsl", "wgsl"), ("rs", "rs")] {
        let dir = root.join("tests/out").join(sub);
        let Ok(entries) = std::fs::read_dir(&dir) else { continue };
        for e in entries {
            let p = e.unwrap().path();
            let stem = p.file_stem().unwrap().to_string_lossy().to_string();
            if p.extension().is_some_and(|e| e == ext) && !names.contains(&stem) {
                if bless {
                    std::fs::remove_file(&p).unwrap();
                    eprintln!("removed stale tests/out/{sub}/{stem}.{ext}");
                } else {
                    failures.push(format!("tests/out/{sub}/{stem}.{ext} has no input tests/in/{stem}.mtlx (run with UPLIFT_BLESS=1 to remove it)"));
                }
            }
        }
    }
    // Known failures must still name existing inputs.
    for (n, _) in KNOWN_FAILURES {
        if !names.iter().any(|x| x == n) {
            failures.push(format!("KNOWN_FAILURES names `{n}`, which is not in tests/in"));
        }
    }

    for n in &notes {
        eprintln!("note: {n}");
    }
    if !failures.is_empty() {
        let mut msg = format!("{} snapshot failure(s) over {} inputs:\n", failures.len(), names.len());
        for f in &failures {
            let _ = writeln!(msg, "  - {f}");
        }
        panic!("{msg}");
    }
}

/// WGSL modules (functions only) that pin down the WGSL semantics the Rust writer keeps:
/// `tests/wgsl/<stem>.wgsl` → `tests/out/rs_wgsl/<stem>.rs` (same bless rules), run by the test
/// crate `tests/rs_compile`.
#[test]
fn wgsl_semantics_snapshots() {
    let root = repo_root();
    let bless = blessing();
    let dir = root.join("tests/wgsl");
    let mut stems: Vec<String> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("cannot list {}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "wgsl"))
        .map(|p| p.file_stem().unwrap().to_string_lossy().to_string())
        .collect();
    stems.sort();
    assert!(!stems.is_empty(), "no WGSL inputs in tests/wgsl");
    let mut failures = Vec::new();
    for stem in &stems {
        let text = std::fs::read_to_string(dir.join(format!("{stem}.wgsl"))).unwrap();
        let module = naga::front::wgsl::parse_str(&text).unwrap_or_else(|e| panic!("tests/wgsl/{stem}.wgsl: {}", e.emit_to_string(&text)));
        let info = naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::default())
            .validate(&module)
            .unwrap_or_else(|e| panic!("tests/wgsl/{stem}.wgsl: {}", e.emit_to_string(&text)));
        match uplift_compiler::backend_rust::write_rust(&module, &info, &Default::default()) {
            Ok(rs) => failures.extend(check_snapshot(&root, &format!("tests/out/rs_wgsl/{stem}.rs"), &rs, bless)),
            Err(e) => failures.push(format!("tests/wgsl/{stem}.wgsl: the Rust writer failed: {e}")),
        }
        // `packet_*` modules are also the packet writer's (tests/out/packet/, compared with the
        // scalar writer's by tests/rs_compile/tests/integration/packet_vs_scalar.rs).
        if stem.starts_with("packet_") {
            match uplift_compiler::backend_packet::write_packet(&module) {
                Ok(rs) => {
                    let rs = format!("// Generated by the packet writer (compiler/src/backend_packet.rs) from tests/wgsl/{stem}.wgsl.\n{rs}");
                    failures.extend(check_snapshot(&root, &format!("tests/out/packet/{stem}.rs"), &rs, bless))
                }
                Err(e) => failures.push(format!("tests/wgsl/{stem}.wgsl: the packet writer failed: {e}")),
            }
        }
    }
    if let Ok(entries) = std::fs::read_dir(root.join("tests/out/rs_wgsl")) {
        for e in entries {
            let p = e.unwrap().path();
            let stem = p.file_stem().unwrap().to_string_lossy().to_string();
            if !stems.contains(&stem) {
                if bless {
                    std::fs::remove_file(&p).unwrap();
                } else {
                    failures.push(format!("tests/out/rs_wgsl/{stem}.rs has no input tests/wgsl/{stem}.wgsl"));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The shipped closure kernels that also ship in packet form (`<graph>_<context>`): those where
/// it is faster than the scalar kernel. Measured (engines bench, Xeon AVX-512, packet /
/// scalar): the conductor's eval 1.34× (1 thread), 1.20× (2 threads). `uplift_stack` eval was
/// 1.18× until the dielectric albedo below IOR 1 became a table lookup (albedo tables format
/// 3): that removed from the scalar kernel a 16-step moment loop its vectorised form ran on
/// every lane, and the packet form now runs at 0.58× of the scalar one (one material per
/// batch, 2 threads 0.61×) and 0.50× (random parameters), so it no longer ships;
/// albedo 0.97×, sample 0.76× (lanes choose different lobes, and a packet samples every lobe
/// some lane chose), pdf 0.86× never did. Each packet kernel costs build time (two SIMD levels).
const PACKET_KERNELS: &[&str] = &["bsdf_conductor_eval"];

/// Kernels shipped with only the grouped form of their packet kernel (the dependence-split
/// passes, for batches with several light directions per material and view): the scalar
/// kernel stays their ungrouped form, being faster than the unsplit packet one (above).
/// Measured (engines bench, Xeon AVX-512, 2 threads, one material, 16 directions per view):
/// `uplift_stack` eval grouped 54.5 M evals/s against 36.1 scalar (1.51×).
const GROUPED_KERNELS: &[&str] = &["uplift_stack_eval", "uplift_stack_sample"];

/// The kernels the runtime ships, `runtime/kernels/src/generated/`, are snapshots too: the
/// compiler's Rust for every graph in `runtime/kernels/graphs/`, `examples/marble.mtlx`, the
/// uplift rules' baked pattern outputs (`mtlx/rules/`, `uplift_rule/<name>_out`), the training
/// classes' (`mtlx/rules/classes/`, `uplift_class/<name>_out`), the rule options'
/// (`mtlx/rules/options/`, `uplift_rule_option/<name>_out`) and every BSDF
/// graph in `runtime/kernels/graphs/bsdf/` in every closure context; the albedo tables once
/// (`albedo_table_data.rs`), which every kernel that reads them shares; and `mod.rs`, their
/// table (each kernel's fingerprint, shape and dispatching batch function). They are committed
/// (generated code as an artefact, like glam's) so that the runtime's kernels crate builds
/// without the compiler; this test fails when they are stale, and `UPLIFT_BLESS=1` rewrites them.
#[test]
fn shipped_kernels_are_current() {
    let root = repo_root();
    std::env::set_current_dir(&root).unwrap();
    let bless = blessing();
    const GENERATED: &str = "runtime/kernels/src/generated";
    let mtlx_files = |dir: &str| -> Vec<PathBuf> {
        let mut v: Vec<PathBuf> = std::fs::read_dir(root.join(dir))
            .unwrap_or_else(|e| panic!("{dir}: {e}"))
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|x| x == "mtlx"))
            .map(|p| Path::new(dir).join(p.file_name().unwrap()))
            .collect();
        v.sort();
        v
    };
    let mut builder = uplift_compiler::build_api::Builder::new().shared_albedo_tables("crate::generated::albedo_table_data::MX_ALBEDO_TABLE_DATA");
    let mut sources: Vec<PathBuf> = mtlx_files("runtime/kernels/graphs");
    sources.push(PathBuf::from("examples/marble.mtlx"));
    for g in &sources {
        builder = builder.graph(g);
    }
    let mut rule_documents = mtlx_files("mtlx/rules");
    rule_documents.extend(mtlx_files("mtlx/rules/classes"));
    rule_documents.extend(mtlx_files("mtlx/rules/options"));
    for rule in rule_documents {
        let (doc, diags) = mtlx::read_file(&rule);
        assert!(!mtlx::has_errors(&diags), "{}: {:?}", rule.display(), diags.iter().map(|d| d.to_string()).collect::<Vec<_>>());
        let graph = doc.top_level().iter().copied().find(|&id| ["uplift_rule", "uplift_class", "uplift_rule_option"].contains(&doc.get(id).name())).unwrap_or_else(|| panic!("{}: no uplift_rule, uplift_class or uplift_rule_option", rule.display()));
        let graph_name = doc.get(graph).name().to_string();
        let outputs: Vec<String> = doc
            .children_of(graph, "output")
            .map(|id| doc.get(id))
            .filter(|e| e.name().ends_with("_out") && e.attr("type") != Some("BSDF"))
            .map(|e| format!("{graph_name}/{}", e.name()))
            .collect();
        if outputs.is_empty() {
            // The infill class draws uniformly: no kernel.
            continue;
        }
        builder = builder.graph_outputs(&rule, &outputs.iter().map(String::as_str).collect::<Vec<_>>());
    }
    for g in mtlx_files("runtime/kernels/graphs/bsdf") {
        for c in uplift_compiler::ClosureContext::ALL {
            let name = format!("{}_{}", g.file_stem().unwrap().to_string_lossy(), c.name());
            builder = if PACKET_KERNELS.contains(&name.as_str()) {
                builder.packet_closure_graph(&g, c)
            } else if GROUPED_KERNELS.contains(&name.as_str()) {
                builder.grouped_closure_graph(&g, c)
            } else {
                builder.closure_graph(&g, c)
            };
        }
    }
    let kernels = builder.generate().unwrap_or_else(|e| panic!("compiling the runtime's graphs:\n{e}"));
    assert!(kernels.len() >= 30, "only {} shipped kernels", kernels.len());

    let header = |what: &str| format!("// Generated by uplift (compiler/tests/snapshots.rs, shipped_kernels_are_current: {what}). Do not edit; rewrite with\n// `UPLIFT_BLESS=1 cargo test -p uplift_compiler --test snapshots`.\n");
    let mut files: Vec<(String, String)> = Vec::new();
    let tables = builder.albedo_tables_source("MX_ALBEDO_TABLE_DATA").unwrap();
    files.push(("albedo_table_data.rs".into(), format!("{}//! The pbrlib albedo tables (mtlx/libraries/pbrlib/wgsl/albedo_tables.wgsl) as one static, which\n//! every shipped kernel that reads them uses.\n\n{tables}", header("the library's albedo tables"))));
    let mut table = header("the table of shipped kernels");
    table += "//! The kernels the runtime ships (see `crate::shipped`): one module per kernel, and their table.\n\nuse crate::{cpu_batch_fn, packet_batch_fn};\nuse crate::driver::{BatchFn, TextureSet};\nuse crate::shipped::{BuiltinKernel, Grouped};\nuse crate::KernelShape;\n\npub mod albedo_table_data;\n";
    let mut entries = String::new();
    for k in &kernels {
        let stem = &k.stem;
        let _ = writeln!(table, "#[allow(clippy::all, dead_code, unused_imports)]\npub mod {stem};");
        // Every scalar form is one named `static` (its functions' symbols name the kernel, which
        // runtime/uplift/benches/disasm/kernel_disasm.py reads), shared by a packet kernel's
        // fallback and `scalar`: every `cpu_batch_fn!` compiles the whole kernel once per level.
        let scalar = format!("{}_SCALAR", stem.to_uppercase());
        let _ = writeln!(table, "static {scalar}: BatchFn = cpu_batch_fn!({stem});");
        let batch = match &k.packet {
            Some(packet) => {
                let _ = writeln!(table, "#[allow(clippy::all, dead_code, unused_imports)]\npub mod {stem}_packet;");
                files.push((format!("{stem}_packet.rs"), packet.clone()));
                let grouped = match packet.contains("pub fn mx_pattern_grouped_batch_simd") {
                    true => format!("Some(Grouped {{ run: {stem}_packet::mx_pattern_grouped_batch_simd, point_columns: {stem}_packet::POINT_INPUT_COLUMNS }})"),
                    false => "None".into(),
                };
                match packet.contains("pub fn mx_pattern_batch_simd") {
                    true => format!("packet_batch_fn!({stem}_packet, {scalar}), scalar: Some({scalar}), grouped: {grouped}"),
                    false => format!("{scalar}, scalar: None, grouped: {grouped}"),
                }
            }
            None => format!("{scalar}, scalar: None, grouped: None"),
        };
        let context = k.context.map(|c| c.name());
        let _ = writeln!(
            entries,
            "    BuiltinKernel {{ name: {stem:?}, source: {:?}, context: {context:?}, fingerprint: {:#x}, shape: KernelShape {{ input_columns: {stem}::INPUT_COLUMNS, output_columns: {stem}::OUTPUT_COLUMNS, texture_count: {stem}::TEXTURE_COUNT }}, batch: {batch} }},",
            k.source.display().to_string().replace('\\', "/"),
            k.fingerprint
        );
        files.push((format!("{stem}.rs"), k.rust.clone()));
    }
    let _ = writeln!(table, "\n/// Every shipped kernel.\npub static BUILTIN_KERNELS: &[BuiltinKernel] = &[\n{entries}];");
    files.push(("mod.rs".into(), table));

    let forbidden = forbidden_paths(&root);
    let mut failures: Vec<String> = Vec::new();
    for (name, text) in &files {
        if let Some(p) = forbidden.iter().find(|p| text.contains(p.as_str())) {
            failures.push(format!("{GENERATED}/{name} contains the absolute path `{p}`"));
        }
        failures.extend(check_snapshot(&root, &format!("{GENERATED}/{name}"), text, bless));
    }
    for e in std::fs::read_dir(root.join(GENERATED)).unwrap() {
        let p = e.unwrap().path();
        let name = p.file_name().unwrap().to_string_lossy().to_string();
        if !files.iter().any(|(n, _)| *n == name) {
            if bless {
                std::fs::remove_file(&p).unwrap();
                eprintln!("removed stale {GENERATED}/{name}");
            } else {
                failures.push(format!("{GENERATED}/{name} is not a shipped kernel any more (run with UPLIFT_BLESS=1 to remove it)"));
            }
        }
    }
    assert!(failures.is_empty(), "{} shipped-kernel failure(s):\n  - {}", failures.len(), failures.join("\n  - "));
}
