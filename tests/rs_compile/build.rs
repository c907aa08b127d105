//! Lists every Rust snapshot in `tests/out/rs/` and writes `$OUT_DIR/kernels.rs`: one module per
//! snapshot (`include!`d), an `MxTextures` impl of each module's trait for every
//! [`Textures`] type (such as `Checker`), and
//! `KERNELS`, a table that runs any kernel's `mx_pattern_batch` by name; and one module
//! `wgsl_<stem>` per `tests/out/rs_wgsl/<stem>.rs` (Rust written from plain WGSL modules that
//! pin down WGSL semantics). A new snapshot is picked up by the next build.
//!
//! It also writes `$OUT_DIR/oracle.rs` for `tests/integration/oracle_naga_rust_back.rs`: for each document of
//! [`ORACLE_DOCUMENTS`], the Rust that `naga-rust-back` (an independent naga → Rust writer) writes
//! from the same naga Module as our writer, and a row function around its `mx_pattern`.

use std::fmt::Write as _;
use std::path::Path;

/// Sorted stems of the `.rs` files in `dir` (none when it is missing).
fn rust_stems(dir: &Path) -> Vec<String> {
    println!("cargo:rerun-if-changed={}", dir.display());
    let mut stems: Vec<String> = std::fs::read_dir(dir)
        .map(|entries| {
            entries
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|e| e == "rs"))
                .map(|p| p.file_stem().unwrap().to_string_lossy().to_string())
                .collect()
        })
        .unwrap_or_default();
    stems.sort();
    stems
}

fn main() {
    write_oracles();
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../out/rs");
    let stems = rust_stems(&dir);
    let mut out = String::new();
    let wgsl_dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../out/rs_wgsl");
    for stem in rust_stems(&wgsl_dir) {
        let path = wgsl_dir.join(format!("{stem}.rs"));
        let path = path.canonicalize().unwrap_or(path);
        let _ = writeln!(out, "/// `tests/out/rs_wgsl/{stem}.rs`.\npub mod wgsl_{stem} {{\n    include!({:?});\n}}\n", path.display().to_string());
    }
    let packet_dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../out/packet");
    for stem in rust_stems(&packet_dir) {
        let path = packet_dir.join(format!("{stem}.rs"));
        let path = path.canonicalize().unwrap_or(path);
        let _ = writeln!(out, "/// `tests/out/packet/{stem}.rs`.\npub mod packet_{stem} {{\n    include!({:?});\n}}\n", path.display().to_string());
    }
    for stem in &stems {
        let path = dir.join(format!("{stem}.rs"));
        let path = path.canonicalize().unwrap_or(path);
        let _ = writeln!(out, "/// `tests/out/rs/{stem}.rs`.\npub mod {stem} {{\n    include!({:?});\n}}\n", path.display().to_string());
        let _ = writeln!(
            out,
            "impl<T: Textures + ?Sized> {stem}::MxTextures for T {{\n    fn load(&self, texture: usize, x: i32, y: i32) -> glam::Vec4 {{\n        Textures::load(self, texture, x, y)\n    }}\n    fn dimensions(&self, texture: usize) -> glam::UVec2 {{\n        Textures::dimensions(self, texture)\n    }}\n}}\n"
        );
    }
    out.push_str("/// Every snapshot kernel: (name, input stride, output stride, batch function).\npub const KERNELS: &[Kernel] = &[\n");
    for stem in &stems {
        let _ = writeln!(
            out,
            "    Kernel {{ name: {stem:?}, input_stride: {stem}::INPUT_COLUMNS, output_stride: {stem}::OUTPUT_COLUMNS, batch: |g, i, o, t| crate::batch_rows!({stem}, g, i, o, t), texture_count: {stem}::TEXTURE_COUNT, batch_with: |g, i, o, t| crate::batch_rows!({stem}, g, i, o, t) }},"
        );
    }
    out.push_str("];\n");
    let dest = Path::new(&std::env::var("OUT_DIR").unwrap()).join("kernels.rs");
    std::fs::write(dest, out).unwrap();
}

/// Documents (`tests/in/<stem>.mtlx`) whose kernels are also written by `naga-rust-back`: a
/// spread of node families (arithmetic, vector math, trigonometry, smoothstep/remap, Perlin
/// fractal noise with its integer hashing, cell noise, Worley noise, conditionals, compositing,
/// HSV conversion, integer and boolean outputs, interface inputs).
///
/// `naga-rust-back` 0.4.0 writes every other snapshot too except those whose `mx_pattern` reads
/// a texture (struct_colorspace, struct_fileprefix, tex_filename_interface, tex_image,
/// tex_shared_bindings, tex_tiledimage, tex_triplanar): textures are global variables of the
/// module, which this oracle removes together with the compute entry point and the storage
/// buffers (naga-rust-back does not support storage buffers; on the unmodified module it panics:
/// "internal error: entered unreachable code: multi-level ref/deref", writer.rs:1098, while
/// translating `mx_main`'s buffer accesses).
///
/// Compiling the oracle of proc_worley prints rustc's "label name `'naga_break` shadows a label
/// name that is already in scope" (naga-rust-back labels every loop alike; inner labels are
/// meant to shadow outer ones, so the code is right). That warning has no lint name and cannot be
/// allowed; the document stays for its nested loops.
const ORACLE_DOCUMENTS: &[&str] = &[
    "adj_luminance_hsv",
    "adj_remap_smoothstep",
    "comp_mix",
    "cond_boolean_logic",
    "cond_ifgreater",
    "math_float_ops",
    "math_integer",
    "math_trig_vector2",
    "math_vector_ops",
    "proc_cellnoise",
    "proc_noise3d_fractal",
    "proc_worley",
    "struct_interfacename",
];

use naga_rust_back::naga;

/// A copy of `module` with its entry point and global variables (the kernel's buffers) removed,
/// validated again: the library functions and `mx_pattern`, which take everything as arguments.
fn functions_only(stem: &str, module: &naga::Module) -> (naga::Module, naga::valid::ModuleInfo) {
    let mut m = module.clone();
    m.entry_points.clear();
    for (_, f) in m.functions.iter() {
        if f.expressions.iter().any(|(_, e)| matches!(e, naga::Expression::GlobalVariable(_))) {
            panic!("oracle {stem}: function `{}` reads a global variable (a texture?)", f.name.as_deref().unwrap_or("?"));
        }
    }
    m.global_variables = naga::Arena::new();
    let info = naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::all())
        .validate(&m)
        .unwrap_or_else(|e| panic!("oracle {stem}: the module without its entry point does not validate: {e:?}"));
    (m, info)
}

/// Members of the struct type named `name` (none when the module has no such struct).
fn struct_members<'m>(module: &'m naga::Module, name: &str) -> &'m [naga::StructMember] {
    module
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some(name))
        .map(|(_, t)| match &t.inner {
            naga::TypeInner::Struct { members, .. } => members.as_slice(),
            other => panic!("{name} is not a struct: {other:?}"),
        })
        .unwrap_or(&[])
}

/// (scalar kind, components) of a struct member of a kernel's input or output struct.
fn member_shape(stem: &str, module: &naga::Module, m: &naga::StructMember) -> (naga::ScalarKind, usize) {
    match &module.types[m.ty].inner {
        naga::TypeInner::Scalar(s) => (s.kind, 1),
        naga::TypeInner::Vector { size, scalar } => (scalar.kind, *size as usize),
        other => panic!("oracle {stem}: member `{}` has a type the oracle's glue does not handle: {other:?}", m.name.as_deref().unwrap_or("?")),
    }
}

/// The row value at `slot` of `row`, as the struct member's scalar type (rows hold floats;
/// booleans are 0.0/1.0 and integers are floats, as in the generated `mx_pattern_batch`'s columns).
fn read_scalar(kind: naga::ScalarKind, row: &str, slot: usize) -> String {
    match kind {
        naga::ScalarKind::Float => format!("{row}[{slot}]"),
        naga::ScalarKind::Sint => format!("{row}[{slot}] as i32"),
        naga::ScalarKind::Uint => format!("{row}[{slot}] as u32"),
        naga::ScalarKind::Bool => format!("{row}[{slot}] != 0.0"),
        other => panic!("scalar kind {other:?}"),
    }
}

/// Field names of `pub struct {name}` in naga-rust-back's output, in order (it renames some
/// members, e.g. `cell2` → `cell2_`, so the glue takes the names from its output; the order
/// is the naga struct's).
fn rust_struct_fields(stem: &str, rust: &str, name: &str) -> Vec<String> {
    let head = format!("pub struct {name} {{");
    let Some(start) = rust.find(&head) else { return Vec::new() };
    let body = &rust[start + head.len()..];
    let body = &body[..body.find('}').unwrap_or_else(|| panic!("oracle {stem}: unterminated struct {name}"))];
    body.lines()
        .filter_map(|l| l.trim().strip_prefix("pub ").and_then(|l| l.split(':').next()).map(|n| n.trim().to_string()))
        .collect()
}

/// Writes `$OUT_DIR/oracle_<stem>.rs` (naga-rust-back's Rust) for every oracle document and
/// `$OUT_DIR/oracle.rs`, which includes each in a module with an `eval_row` function and lists
/// them in `ORACLES`.
fn write_oracles() {
    let out_dir = std::path::PathBuf::from(std::env::var("OUT_DIR").unwrap());
    let in_dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../in");
    let compiler = uplift_compiler::Compiler::builtin();
    let mut out = String::from("// Written by tests/rs_compile/build.rs: naga-rust-back's translation of some snapshot kernels.\n\n");
    for stem in ORACLE_DOCUMENTS {
        let path = in_dir.join(format!("{stem}.mtlx"));
        println!("cargo:rerun-if-changed={}", path.display());
        let c = compiler.compile_file(&path, &uplift_compiler::OutputSelection::AllNumeric);
        let kernel = c.kernel.unwrap_or_else(|| panic!("oracle {stem}: does not compile: {:?}", c.diagnostics.iter().map(|d| d.to_string()).collect::<Vec<_>>()));
        let (module, info) = functions_only(stem, &kernel.module);
        let config = naga_rust_back::Config::new().public_items(true);
        let rust = naga_rust_back::write_string(&module, &info, config).unwrap_or_else(|e| panic!("oracle {stem}: naga-rust-back: {e}"));
        let file = out_dir.join(format!("oracle_{stem}.rs"));
        std::fs::write(&file, &rust).unwrap();
        let input_fields = rust_struct_fields(stem, &rust, "MxInputs");
        let output_fields = rust_struct_fields(stem, &rust, "MxOutputs");

        // The row function: geometry row → mx_geometry, input row → MxInputs, MxOutputs → row.
        let v3 = |o: usize| format!("[g[{o}], g[{}], g[{}]].into()", o + 1, o + 2);
        let cross = |a: usize, b: usize| format!("cross([g[{a}], g[{}], g[{}]], [g[{b}], g[{}], g[{}]]).into()", a + 1, a + 2, b + 1, b + 2);
        let mut glue = String::new();
        let _ = writeln!(glue, "    /// Evaluates this module's `mx_pattern` on one geometry row (`GEOMETRY_STRIDE` floats)");
        let _ = writeln!(glue, "    /// and input row, writing one output row, with the row layout the tests use.");
        let _ = writeln!(glue, "    pub fn eval_row(g: &[f32], x: &[f32], o: &mut [f32]) {{");
        let _ = writeln!(glue, "        let _ = x;");
        let _ = writeln!(
            glue,
            "        let geom = mx_geometry {{ texcoord: [g[0], g[1]].into(), position_object: {}, position_world: {}, normal_object: {}, normal_world: {}, tangent_object: {}, tangent_world: {}, bitangent_object: {}, bitangent_world: {} }};",
            v3(2), v3(5), v3(8), v3(11), v3(14), v3(17), cross(8, 14), cross(11, 17)
        );
        let inputs = struct_members(&module, "MxInputs");
        let mut slot = 0;
        let mut args = String::from("geom");
        assert_eq!(inputs.len(), input_fields.len(), "oracle {stem}: MxInputs fields");
        if !inputs.is_empty() {
            let mut fields = Vec::new();
            for (m, name) in inputs.iter().zip(&input_fields) {
                let (kind, n) = member_shape(stem, &module, m);
                let value = if n == 1 {
                    read_scalar(kind, "x", slot)
                } else {
                    format!("[{}].into()", (slot..slot + n).map(|s| read_scalar(kind, "x", s)).collect::<Vec<_>>().join(", "))
                };
                fields.push(format!("{name}: {value}"));
                slot += n;
            }
            let _ = writeln!(glue, "        let inputs = MxInputs {{ {} }};", fields.join(", "));
            args.push_str(", inputs");
        }
        assert_eq!(slot, kernel.input_stride, "oracle {stem}: MxInputs members do not fill the input row");
        let _ = writeln!(glue, "        let r = mx_pattern({args});");
        let mut slot = 0;
        let outputs = struct_members(&module, "MxOutputs");
        assert_eq!(outputs.len(), output_fields.len(), "oracle {stem}: MxOutputs fields");
        for (m, name) in outputs.iter().zip(&output_fields) {
            let (kind, n) = member_shape(stem, &module, m);
            for c in 0..n {
                let value = if n == 1 { format!("r.{name}") } else { format!("r.{name}.{}", ["x", "y", "z", "w"][c]) };
                let value = match kind {
                    naga::ScalarKind::Float => value,
                    naga::ScalarKind::Bool => format!("if {value} {{ 1.0 }} else {{ 0.0 }}"),
                    _ => format!("{value} as f32"),
                };
                let _ = writeln!(glue, "        o[{slot}] = {value};");
                slot += 1;
            }
        }
        assert_eq!(slot, kernel.output_stride, "oracle {stem}: MxOutputs members do not fill the output row");
        let _ = writeln!(glue, "    }}");
        let _ = writeln!(
            out,
            "/// naga-rust-back's Rust for `tests/in/{stem}.mtlx` (entry point and buffers removed).\n#[allow(dead_code, unused_variables, unused_mut, unused_assignments, unused_imports, unused_labels, unreachable_code, non_camel_case_types, non_snake_case, clippy::all)]\npub mod {stem} {{\n    use super::{{cross, RtMissing as _}};\n    include!({:?});\n\n{glue}}}\n",
            file.display().to_string()
        );
    }
    out.push_str("/// Every oracle: (document stem, row function).\npub const ORACLES: &[(&str, fn(&[f32], &[f32], &mut [f32]))] = &[\n");
    for stem in ORACLE_DOCUMENTS {
        let _ = writeln!(out, "    ({stem:?}, {stem}::eval_row),");
    }
    out.push_str("];\n");
    std::fs::write(out_dir.join("oracle.rs"), out).unwrap();
}
