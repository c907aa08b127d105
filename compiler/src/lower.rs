//! Lowering: graph IR → WGSL glue text (the askama template `templates/pattern_kernel.wgsl`),
//! concatenated with exactly the library items it calls; parsed once by naga, validated,
//! compacted, validated again, and written by naga's WGSL writer.

use crate::ir::{GeomProp, Graph, InterfaceInput, ValueKind};
use crate::kernel::*;
use crate::const_eval::ConstEvaluator;
use crate::naga_import;
use crate::node_library::{NodeLibrary, TABLE_ACCESSOR, TABLE_DATA};
use crate::wgsl_items::ItemKind;
use crate::wgsl_types::{constant_expr, has_emission, is_scattering, wgsl_type};
use askama::Template;
use mtlx::DataType;
use std::collections::HashSet;

struct Field {
    field: String,
    wgsl_type: String,
}

struct TextureSlot {
    binding: u32,
    name: String,
    file: String,
}

#[derive(Template)]
#[template(path = "pattern_kernel.wgsl", escape = "none")]
struct PatternKernelTemplate<'a> {
    source: &'a str,
    items: Vec<&'a str>,
    albedo_table_binding: Option<u32>,
    inputs: Vec<Field>,
    outputs: Vec<Field>,
    textures: Vec<TextureSlot>,
    body: Vec<String>,
    result: String,
    geometry_loads: Vec<String>,
    input_loads: Vec<String>,
    output_stores: Vec<String>,
    geometry_stride: usize,
    input_stride: usize,
    output_stride: usize,
    workgroup_size: u32,
}

/// A failure of lowering: an unsupported type, or naga rejecting the assembled module (which
/// means a library function is wrong; the message names it).
#[derive(Debug)]
pub struct LowerError(pub String);

/// Turns a MaterialX name into a WGSL identifier, unique among `used`.
fn identifier(name: &str, prefix: &str, used: &mut HashSet<String>) -> String {
    let mut s: String = name.chars().map(|c| if c.is_ascii_alphanumeric() { c } else { '_' }).collect();
    s = format!("{prefix}{s}");
    let base = s.clone();
    let mut k = 1;
    while !used.insert(s.clone()) {
        s = format!("{base}_{k}");
        k += 1;
    }
    s
}

/// Reads `ty` from columns `offset..` of the column-major buffer `buf` (component `c` of point
/// `i` at `buf[c * n + i]`) as a WGSL expression.
fn load_expr(ty: &DataType, buf: &str, offset: usize) -> String {
    let at = |k: usize| format!("{buf}[{}u * n + i]", offset + k);
    match ty {
        DataType::Boolean => format!("{} != 0.0", at(0)),
        DataType::Integer => format!("i32({})", at(0)),
        DataType::Float => at(0),
        t => {
            let n = t.components().unwrap();
            let parts: Vec<String> = (0..n).map(at).collect();
            format!("{}({})", wgsl_type(t, false).unwrap(), parts.join(", "))
        }
    }
}

/// Stores `value` (of type `ty`) into columns `offset..` of the column-major output buffer, one
/// statement per component.
fn store_stmts(ty: &DataType, value: &str, offset: usize) -> Vec<String> {
    let at = |k: usize| format!("mx_output_buffer[{}u * n + i]", offset + k);
    match ty {
        DataType::Boolean => vec![format!("{} = select(0.0, 1.0, {value});", at(0))],
        DataType::Integer => vec![format!("{} = f32({value});", at(0))],
        DataType::Float => vec![format!("{} = {value};", at(0))],
        DataType::Matrix33 | DataType::Matrix44 => {
            let n = if *ty == DataType::Matrix33 { 3 } else { 4 };
            (0..n * n).map(|k| format!("{} = {value}[{}][{}];", at(k), k / n, k % n)).collect()
        }
        t => {
            let n = t.components().unwrap();
            (0..n).map(|k| format!("{} = {value}.{};", at(k), ["x", "y", "z", "w"][k])).collect()
        }
    }
}

/// Lowers `graph` to a validated naga module and WGSL text. `source` names the document.
/// With a closure `context`, the graph's one output must be BSDF-typed; the kernel then reads
/// the context's directions first and writes the context's outputs.
pub fn lower(lib: &NodeLibrary, graph: Graph, source: &str, context: Option<ClosureContext>, options: LowerOptions) -> Result<PatternKernel, LowerError> {
    let mut used = HashSet::new();
    // Interface inputs and outputs.
    let mut inputs = Vec::new();
    let mut input_fields = Vec::new();
    let mut input_loads = Vec::new();
    let mut offset = 0;
    let direction_inputs: Vec<InterfaceInput> = context
        .map(|c| c.direction_inputs())
        .unwrap_or_default()
        .iter()
        .map(|name| InterfaceInput { name: name.to_string(), ty: DataType::Vector3, default: vec![0.0, 0.0, 1.0], pos: mtlx::SourcePos::synthetic(source) })
        .collect();
    if let Some(clash) = graph.inputs.iter().find(|i| direction_inputs.iter().any(|d| d.name == i.name)) {
        return Err(LowerError(format!("interface input `{}` has the name of a closure-context input ({}); rename it", clash.name, direction_inputs.iter().map(|d| d.name.as_str()).collect::<Vec<_>>().join(", "))));
    }
    let directions = direction_inputs.len();
    for inp in direction_inputs.iter().chain(&graph.inputs) {
        let t = wgsl_type(&inp.ty, false).ok_or_else(|| LowerError(format!("input `{}` has unsupported type {}", inp.name, inp.ty)))?;
        input_fields.push(Field { field: identifier(&inp.name, "", &mut used), wgsl_type: t.into() });
        input_loads.push(load_expr(&inp.ty, "mx_input_buffer", offset));
        inputs.push(KernelInput { input: inp.clone(), offset });
        offset += inp.ty.components().unwrap();
    }
    let input_stride = offset;
    let mut outputs = Vec::new();
    let mut output_fields = Vec::new();
    let mut output_stores = Vec::new();
    let mut offset = 0;
    let output_list: Vec<(String, DataType)> = match context {
        None => graph.outputs.iter().map(|o| (o.name.clone(), o.ty.clone())).collect(),
        Some(c) => {
            match graph.outputs.as_slice() {
                [one] if one.ty.is_closure() && is_scattering(&one.ty) => {}
                _ => return Err(LowerError(format!("the {} context needs exactly one BSDF, surfaceshader or material output", c.name()))),
            }
            let mut list: Vec<(String, DataType)> = c.outputs().into_iter().map(|(n, t)| (n.to_string(), t)).collect();
            if has_emission(&graph.outputs[0].ty) {
                list.push(("emission".to_string(), DataType::Color3));
            }
            list
        }
    };
    for (name, ty) in &output_list {
        let t = wgsl_type(ty, false).filter(|_| ty.is_numeric()).ok_or_else(|| LowerError(format!("output `{name}` has type {ty}, which is not a pattern value (compile it with a closure context)")))?;
        let field = identifier(name, "", &mut used);
        output_stores.extend(store_stmts(ty, &format!("out.{field}"), offset));
        output_fields.push(Field { field, wgsl_type: t.into() });
        outputs.push(KernelOutput { name: name.clone(), ty: ty.clone(), offset });
        offset += ty.components().unwrap();
    }
    let output_stride = offset;
    if outputs.is_empty() {
        return Err(LowerError("nothing to compile: no numeric output".into()));
    }
    // Textures.
    let textures: Vec<TextureSlot> = graph
        .textures
        .iter()
        .enumerate()
        .map(|(k, t)| TextureSlot {
            binding: BINDING_FIRST_TEXTURE + k as u32,
            name: format!("mx_texture_{k}"),
            file: t.path.file_name().map(|f| f.to_string_lossy().to_string()).unwrap_or_default(),
        })
        .collect();
    // Body.
    let mut body = Vec::new();
    let mut roots: Vec<&str> = vec!["mx_geometry"];
    // Values that depend on the closure context are emitted once per pass (the sample context
    // runs the closure tree twice: choose a direction, then evaluate its pdf and response).
    let mut per_pass = vec![false; graph.values.len()];
    for (h, v) in graph.values.iter() {
        per_pass[h.index()] = match &v.kind {
            ValueKind::Call { args, closure, .. } => *closure || args.iter().any(|a| per_pass[a.index()]),
            ValueKind::Field { base, .. } => per_pass[base.index()],
            _ => false,
        };
    }
    // A surface shader's (or material's) BSDF part, for the context's outputs.
    let bsdf_of = if context.is_some() && has_emission(&graph.outputs[0].ty) { ".bsdf" } else { "" };
    let passes: &[i32] = match context {
        None => &[],
        Some(ClosureContext::Eval) => &[CONTEXT_EVAL],
        Some(ClosureContext::Albedo) => &[CONTEXT_ALBEDO],
        Some(ClosureContext::Sample) => &[CONTEXT_SAMPLE, CONTEXT_PDF],
        Some(ClosureContext::Pdf) => &[CONTEXT_PDF],
    };
    if context.is_some() {
        roots.extend(["mx_closure_new", "mx_closure_for_lobe", "mx_closure_pdf"]);
        let field = |k: usize| format!("inputs.{}", input_fields[k].field);
        let (wv, second) = (field(0), field(1.min(directions - 1)));
        let (wl, u) = match context {
            Some(ClosureContext::Sample) => ("vec3<f32>(0.0, 0.0, 1.0)".to_string(), second),
            Some(ClosureContext::Eval | ClosureContext::Pdf) => (second, "vec3<f32>(0.0)".to_string()),
            _ => ("vec3<f32>(0.0, 0.0, 1.0)".to_string(), "vec3<f32>(0.0)".to_string()),
        };
        body.push(format!("let cl{} = mx_closure_new({}, {wv}, {wl}, {u});", passes[0], passes[0]));
    }
    // Leaves (constants, geometry, inputs, textures) are written inline where they are used;
    // every call gets one `let` (naga's parse time grows with the statements it reads).
    // operand[h][p] is value h's expression in pass p (one entry for pass-independent values).
    let mut operand: Vec<Vec<String>> = vec![Vec::new(); graph.values.len()];
    let pick = |operand: &Vec<Vec<String>>, x: usize, p: usize| -> String {
        let o = &operand[x];
        o.get(p).or_else(|| o.first()).cloned().unwrap_or_default()
    };
    // Pass-independent values first (in order), then each pass's values (in order): every
    // value still follows what it uses.
    let order: Vec<(usize, Option<usize>)> = (0..graph.values.len())
        .filter(|&h| !per_pass[h])
        .map(|h| (h, None))
        .chain((0..passes.len()).flat_map(|p| (0..graph.values.len()).filter(|&h| per_pass[h]).map(move |h| (h, Some(p)))))
        .collect();
    for (h, pass) in order {
        let v = &graph.values[crate::arena::Handle::from_index(h)];
        let p = pass.unwrap_or(0);
        if pass == Some(1) && operand.iter().all(|o| o.len() < 2) {
            // First value of the pdf pass: its context, at the direction the sample pass chose.
            let chosen = pick(&operand, graph.outputs[0].value.index(), 0);
            body.push(format!("let cl{} = mx_closure_new({}, cl{}.wv, {chosen}{bsdf_of}.lobe.xyz, cl{}.u);", passes[1], passes[1], passes[0], passes[0]));
        }
        let rhs = match &v.kind {
            // Strings and filenames exist only at compile time (enum strings are already
            // integers, filenames texture bindings): they have no WGSL expression.
            ValueKind::Constant(lit) => {
                if let DataType::Closure(name) = &v.ty {
                    if let Some((ty, empty)) = crate::wgsl_types::closure_type(name) {
                        roots.extend([ty, empty.split('(').next().unwrap_or(ty)]);
                    }
                }
                operand[h].push(constant_expr(&v.ty, lit).unwrap_or_default());
                continue;
            }
            ValueKind::Geometry(g) => {
                operand[h].push(format!("geom.{}", g.field()));
                continue;
            }
            ValueKind::Input(i) => {
                operand[h].push(format!("inputs.{}", input_fields[*i + directions].field));
                continue;
            }
            ValueKind::Texture(t) => {
                operand[h].push(textures[*t].name.clone());
                continue;
            }
            ValueKind::Call { function, args, geometry, closure } => {
                roots.push(function);
                let mut a: Vec<String> = args.iter().map(|&x| pick(&operand, x.index(), p)).collect();
                if *closure {
                    let Some(k) = pass.map(|p| passes[p]) else {
                        return Err(LowerError(format!("`{function}` evaluates a closure: compile its output with a closure context (eval, albedo or sample)")));
                    };
                    // The lobe's id (its race variable in the sample context) from its node's
                    // path, not its place in the graph: a kernel specialised with some lobes
                    // removed (closure_fold.rs) samples the others exactly as the generic one.
                    a.insert(0, format!("mx_closure_for_lobe(cl{k}, {}u)", lobe_id(&v.origin)));
                }
                if *geometry {
                    a.insert(0, "geom".into());
                }
                format!("{function}({})", a.join(", "))
            }
            ValueKind::Field { base, field } => format!("{}.{field}", pick(&operand, base.index(), p)),
        };
        let name = match pass {
            Some(p) if passes.len() > 1 => format!("v{h}_{p}"),
            _ => format!("v{h}"),
        };
        body.push(format!("let {name} = {rhs};"));
        operand[h].push(name);
    }
    let result: Vec<String> = match context {
        None => graph.outputs.iter().map(|o| pick(&operand, o.value.index(), 0)).collect(),
        Some(c) => {
            let value = pick(&operand, graph.outputs[0].value.index(), passes.len() - 1);
            let last = format!("{value}{bsdf_of}");
            let mut result = match c {
                ClosureContext::Eval | ClosureContext::Albedo => vec![format!("{last}.response"), format!("{last}.throughput")],
                ClosureContext::Pdf => vec![format!("mx_closure_pdf({last})"), format!("{last}.response"), format!("{last}.throughput")],
                ClosureContext::Sample => {
                    if operand.iter().all(|o| o.len() < 2) {
                        // A closure tree with no lobe (an empty closure): nothing to choose.
                        body.push(format!("let cl{} = mx_closure_new({}, cl{}.wv, vec3<f32>(0.0, 0.0, 1.0), cl{}.u);", passes[1], passes[1], passes[0], passes[0]));
                    }
                    vec![format!("cl{}.wl", passes[1]), format!("mx_closure_pdf({last})"), format!("{last}.response"), format!("{last}.throughput")]
                }
            };
            if !bsdf_of.is_empty() {
                result.push(format!("{value}.emission"));
            }
            result
        }
    };
    let closure_items = lib.wgsl.closure(&roots);
    // Albedo tables: CPU kernels read the library's constant array (a Rust static); GPU kernels
    // read the same data from a storage buffer, since a shader indexing a large constant array
    // copies it at every access (naga's SPIR-V writer; lavapipe then never finishes compiling).
    let uses_tables = closure_items.iter().any(|i| i.name == TABLE_ACCESSOR);
    // With `stubs`, every library function and array constant is a stub whose body or value is
    // imported from the library parsed once (naga_import.rs), unless the library did not parse
    // as one module; without, the items' full text.
    let library_module = lib.evaluator.as_ref().filter(|_| options.import_library);
    let stub_texts: Vec<Option<String>> = closure_items
        .iter()
        .map(|i| match (&library_module, i.kind, &i.signature) {
            (Some(_), ItemKind::Function, Some(sig)) => naga_import::stub(&i.text, sig.result.as_deref()),
            (Some(_), ItemKind::Const, _) => naga_import::const_stub(&i.text),
            _ => None,
        })
        .collect();
    let assemble = |gpu: bool, stubs: bool| -> Stubbed {
        let mut s = Stubbed::default();
        for (i, stub) in closure_items.iter().zip(&stub_texts) {
            match (gpu, i.name.as_str(), stub.as_ref().filter(|_| stubs)) {
                (true, TABLE_DATA, _) => {}
                (true, TABLE_ACCESSOR, _) => s.texts.push(GPU_TABLE_ACCESSOR),
                (_, _, Some(stub)) => {
                    s.texts.push(stub.as_str());
                    match i.kind {
                        ItemKind::Function => s.functions.push(i.name.as_str()),
                        _ => s.constants.push(i.name.as_str()),
                    }
                }
                _ => s.texts.push(i.text.as_str()),
            }
        }
        s
    };
    let (items, cpu_items) = (assemble(true, false).texts, assemble(false, false).texts);
    if !lib.wgsl.items.contains_key("mx_geometry") {
        return Err(LowerError("the library defines no `mx_geometry` struct (stdlib/wgsl/geometric.wgsl)".into()));
    }
    // Load only the geometric properties the graph reads (all of them when a library function
    // receives the whole `mx_geometry`); a bitangent also needs its normal and tangent. The
    // others stay zero.
    let whole = graph.values.iter().any(|(_, v)| matches!(v.kind, ValueKind::Call { geometry: true, .. }));
    let mut used: HashSet<GeomProp> = graph.values.iter().filter_map(|(_, v)| match v.kind { ValueKind::Geometry(g) => Some(g), _ => None }).collect();
    let bitangents = [
        (GeomProp::BitangentObject, GeomProp::NormalObject, GeomProp::TangentObject),
        (GeomProp::BitangentWorld, GeomProp::NormalWorld, GeomProp::TangentWorld),
    ];
    for (b, n, t) in bitangents {
        if whole || used.contains(&b) {
            used.extend([b, n, t]);
        }
    }
    let mut geometry_loads = Vec::new();
    for (prop, offset) in GEOMETRY_LAYOUT {
        if whole || used.contains(&prop) {
            geometry_loads.push(format!("geom.{} = {};", prop.field(), load_expr(&prop.data_type(), "mx_geometry_buffer", offset)));
        }
    }
    for (b, n, t) in bitangents {
        if used.contains(&b) || whole {
            geometry_loads.push(format!("geom.{} = cross(geom.{}, geom.{});", b.field(), n.field(), t.field()));
        }
    }
    let mut template = PatternKernelTemplate {
        source,
        items,
        albedo_table_binding: uses_tables.then_some(BINDING_ALBEDO_TABLES),
        inputs: input_fields,
        outputs: output_fields,
        textures,
        body,
        result: result.join(", "),
        geometry_loads,
        input_loads,
        output_stores,
        geometry_stride: GEOMETRY_STRIDE,
        input_stride,
        output_stride,
        workgroup_size: WORKGROUP_SIZE,
    };
    let (module, info) = kernel_module(&mut template, library_module, assemble(true, true), options)?;
    let (cpu_module, albedo_tables) = if uses_tables {
        template.items = cpu_items;
        template.albedo_table_binding = None;
        let data = lib.albedo_table_data.clone().ok_or_else(|| LowerError(format!("the library's `{TABLE_DATA}` is not a constant f32 array")))?;
        (Some(kernel_module(&mut template, library_module, assemble(false, true), options)?), Some(data))
    } else {
        (None, None)
    };
    let wgsl = naga::back::wgsl::write_string(&module, &info, naga::back::wgsl::WriterFlags::empty())
        .map_err(|e| LowerError(format!("naga WGSL writer: {e}")))?;
    let header = format!("// Generated by uplift (template: templates/pattern_kernel.wgsl; writer: naga {}) from {source}. Do not edit.\n", naga_version());
    Ok(PatternKernel {
        textures: graph.textures.clone(),
        graph,
        module,
        info,
        wgsl: header + &wgsl,
        inputs,
        input_stride,
        outputs,
        output_stride,
        context,
        cpu_module,
        albedo_tables,
    })
}

/// The albedo-table accessor's GPU form (reading the storage buffer the kernel template
/// declares).
const GPU_TABLE_ACCESSOR: &str = "fn mx_albedo_table(i: i32) -> f32 {\n    return mx_albedo_table_buffer[i];\n}";

/// The context numbers of closure.wgsl (MX_CONTEXT_*).
const CONTEXT_EVAL: i32 = 0;
const CONTEXT_ALBEDO: i32 = 1;
const CONTEXT_SAMPLE: i32 = 2;
const CONTEXT_PDF: i32 = 3;

fn naga_version() -> &'static str {
    "30.0.1"
}

/// How [`lower`] builds the naga module.
#[derive(Clone, Copy, Debug)]
pub struct LowerOptions {
    /// Import the library's functions pre-parsed (naga_import.rs) instead of parsing their
    /// text in every kernel. The modules are the same either way (tested); off, lowering
    /// takes the reference path.
    pub import_library: bool,
    /// When the import refuses (a construct naga_import.rs does not re-point), parse the full
    /// text instead; off, that is an error naming the construct (tests use it to show that
    /// the import path is the one taken).
    pub fall_back_to_text: bool,
}

impl Default for LowerOptions {
    fn default() -> Self {
        LowerOptions { import_library: true, fall_back_to_text: true }
    }
}

/// A kernel's library items with stubs in place of library functions and array constants
/// (naga_import.rs), and the names of the stubbed items.
#[derive(Default)]
struct Stubbed<'a> {
    texts: Vec<&'a str>,
    functions: Vec<&'a str>,
    constants: Vec<&'a str>,
}

/// The kernel's naga module from the template: with the library's functions and array
/// constants as stubs, their bodies and values imported, when `library` is given, else — or
/// when the import refuses — from the template's items as they are (`template.items` on entry:
/// the full text).
fn kernel_module<'a>(template: &mut PatternKernelTemplate<'a>, library: Option<&ConstEvaluator>, stubbed: Stubbed<'a>, options: LowerOptions) -> Result<(naga::Module, naga::valid::ModuleInfo), LowerError> {
    let render = |t: &PatternKernelTemplate| t.render().map_err(|e| LowerError(format!("template: {e}")));
    if let Some(lib) = library {
        let full = std::mem::replace(&mut template.items, stubbed.texts);
        let text = render(template)?;
        template.items = full;
        let imported = naga::front::wgsl::parse_str(&text).map_err(|e| e.emit_to_string(&text)).and_then(|mut module| {
            naga_import::import_bodies(lib.module(), |n| lib.function(n), &mut module, &stubbed.functions, &stubbed.constants)?;
            let info = compact_and_validate(&mut module).map_err(|e| format!("validation: {e}"))?;
            Ok((module, info))
        });
        match imported {
            Ok(m) => return Ok(m),
            Err(e) if !options.fall_back_to_text => return Err(LowerError(format!("importing the library functions: {e}"))),
            Err(_) => {}
        }
    }
    to_naga(&render(template)?)
}

/// Parses, validates, compacts and re-validates WGSL text.
pub fn to_naga(text: &str) -> Result<(naga::Module, naga::valid::ModuleInfo), LowerError> {
    let mut module = naga::front::wgsl::parse_str(text).map_err(|e| LowerError(format!("naga rejected the assembled kernel:\n{}", e.emit_to_string(text))))?;
    let info = compact_and_validate(&mut module).map_err(|e| LowerError(format!("naga validation failed:\n{}", e.emit_to_string(text))))?;
    Ok((module, info))
}

/// Compaction (dropping what the entry point does not reach) needs no prior validation; the one
/// validation runs on what is emitted.
fn compact_and_validate(module: &mut naga::Module) -> Result<naga::valid::ModuleInfo, Box<naga::WithSpan<naga::valid::ValidationError>>> {
    naga::compact::compact(module, naga::compact::KeepUnused::No);
    naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::default()).validate(module).map_err(Box::new)
}

/// A lobe's id: the FNV-1a hash of its node's path (`Value::origin`).
fn lobe_id(origin: &str) -> u32 {
    origin.bytes().fold(0x811c_9dc5u32, |h, b| (h ^ b as u32).wrapping_mul(0x0100_0193))
}
