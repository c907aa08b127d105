//! Lowering: graph IR → WGSL glue text (the askama template `templates/pattern_kernel.wgsl`),
//! concatenated with exactly the library items it calls; parsed once by naga, validated,
//! compacted, validated again, and written by naga's WGSL writer.

use crate::ir::{GeomProp, Graph, ValueKind};
use crate::kernel::*;
use crate::node_library::NodeLibrary;
use crate::wgsl_types::{constant_expr, wgsl_type};
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
pub fn lower(lib: &NodeLibrary, graph: Graph, source: &str) -> Result<PatternKernel, LowerError> {
    let mut used = HashSet::new();
    // Interface inputs and outputs.
    let mut inputs = Vec::new();
    let mut input_fields = Vec::new();
    let mut input_loads = Vec::new();
    let mut offset = 0;
    for inp in &graph.inputs {
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
    for out in &graph.outputs {
        let t = wgsl_type(&out.ty, false).ok_or_else(|| LowerError(format!("output `{}` has unsupported type {}", out.name, out.ty)))?;
        let field = identifier(&out.name, "", &mut used);
        output_stores.extend(store_stmts(&out.ty, &format!("out.{field}"), offset));
        output_fields.push(Field { field, wgsl_type: t.into() });
        outputs.push(KernelOutput { name: out.name.clone(), ty: out.ty.clone(), offset });
        offset += out.ty.components().unwrap();
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
    // Leaves (constants, geometry, inputs, textures) are written inline where they are used;
    // every call gets one `let` (naga's parse time grows with the statements it reads).
    let mut operand: Vec<String> = Vec::with_capacity(graph.values.len());
    for (h, v) in graph.values.iter() {
        let rhs = match &v.kind {
            // Strings and filenames exist only at compile time (enum strings are already
            // integers, filenames texture bindings): they have no WGSL expression.
            ValueKind::Constant(lit) => {
                operand.push(constant_expr(&v.ty, lit).unwrap_or_default());
                continue;
            }
            ValueKind::Geometry(g) => {
                operand.push(format!("geom.{}", g.field()));
                continue;
            }
            ValueKind::Input(i) => {
                operand.push(format!("inputs.{}", input_fields[*i].field));
                continue;
            }
            ValueKind::Texture(t) => {
                operand.push(textures[*t].name.clone());
                continue;
            }
            ValueKind::Call { function, args, geometry } => {
                roots.push(function);
                let mut a: Vec<String> = args.iter().map(|&x| operand[x.index()].clone()).collect();
                if *geometry {
                    a.insert(0, "geom".into());
                }
                format!("{function}({})", a.join(", "))
            }
            ValueKind::Field { base, field } => format!("{}.{field}", operand[base.index()]),
        };
        let name = format!("v{}", h.index());
        body.push(format!("let {name} = {rhs};"));
        operand.push(name);
    }
    let result: Vec<String> = graph.outputs.iter().map(|o| operand[o.value.index()].clone()).collect();
    let items: Vec<&str> = lib.wgsl.closure(&roots).into_iter().map(|i| i.text.as_str()).collect();
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
    let template = PatternKernelTemplate {
        source,
        items,
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
    let text = template.render().map_err(|e| LowerError(format!("template: {e}")))?;
    let (module, info) = to_naga(&text)?;
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
    })
}

fn naga_version() -> &'static str {
    "30.0.1"
}

/// Parses, validates, compacts and re-validates WGSL text.
pub fn to_naga(text: &str) -> Result<(naga::Module, naga::valid::ModuleInfo), LowerError> {
    let mut module = naga::front::wgsl::parse_str(text).map_err(|e| LowerError(format!("naga rejected the assembled kernel:\n{}", e.emit_to_string(text))))?;
    // Compaction (dropping what the entry point does not reach) needs no prior validation;
    // the one validation runs on what is emitted (spans still point into `text`).
    naga::compact::compact(&mut module, naga::compact::KeepUnused::No);
    let mut validator = naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::default());
    let info = validator
        .validate(&module)
        .map_err(|e| LowerError(format!("naga validation failed:\n{}", e.emit_to_string(text))))?;
    Ok((module, info))
}
