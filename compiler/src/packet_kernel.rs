//! The packet kernel of a pattern kernel (issue 24): the packet writer's module
//! (`backend_packet.rs`) followed by its batch loop, one packet of points at a time, and the
//! batch entry at this machine's SIMD level (askama template `templates/packet_kernel.rs`). The
//! batch ABI is the scalar kernel's (`templates/pattern_kernel.rs`) without textures: the
//! packet writer does not read textures yet, so a kernel with textures is a [`PacketError`].

use crate::backend_packet::{packet_names, unsupported, write_packet_split, write_packet_with, PacketError, PacketOptions};
use crate::kernel::{PatternKernel, GEOMETRY_LAYOUT, GEOMETRY_STRIDE};
use askama::Template;
use mtlx::DataType;
use naga::proc::NameKey;
use naga::{Handle, TypeInner};

struct Field {
    name: String,
    expr: String,
}

/// The grouped batch entry of a dependence-split kernel (`packet_split.rs`).
struct SplitFields {
    group_fn: String,
    point_fn: String,
    slots: usize,
    /// Geometry and inputs of the group pass (a packet of groups; per-point inputs zero).
    group_geometry: Vec<Field>,
    group_inputs: Vec<Field>,
    /// Geometry and inputs of the point pass (per-group ones splatted from the group's row).
    point_geometry: Vec<Field>,
    point_inputs: Vec<Field>,
    /// Input columns read per point (the others are per group).
    point_columns: Vec<usize>,
}

/// Inputs of a BSDF kernel that vary per point in the grouped layout: the light direction
/// (eval, pdf) and the sample's random numbers (sample). Everything else — material
/// parameters, the view, the geometry — is per group.
pub const POINT_INPUTS: &[&str] = &["wl", "u"];

#[derive(Template)]
#[template(path = "packet_kernel.rs", escape = "none")]
struct PacketKernelTemplate<'a> {
    source: &'a str,
    naga_version: &'a str,
    module: &'a str,
    geometry_stride: usize,
    input_stride: usize,
    output_stride: usize,
    geometry_struct: String,
    geometry_fields: Vec<Field>,
    inputs_struct: Option<String>,
    input_fields: Vec<Field>,
    call: String,
    output_stores: Vec<String>,
    split: Option<SplitFields>,
    /// Write the unsplit batch entry (`mx_pattern_packets`, `mx_pattern_batch_simd`).
    plain_entry: bool,
}

/// Writes `kernel` as packet Rust with its batch loop (module doc).
pub fn write_packet_kernel(kernel: &PatternKernel, options: &PacketOptions) -> Result<String, PacketError> {
    if !kernel.textures.is_empty() {
        return Err(unsupported("a kernel that reads textures"));
    }
    let module = kernel.cpu_module.as_ref().map_or(&kernel.module, |m| &m.0);
    let is_bsdf = kernel.context.is_some();
    let (body, instance) = if is_bsdf {
        write_packet_split(module, options, "mx_pattern", POINT_INPUTS)?
    } else {
        (write_packet_with(module, options)?, None)
    };
    let names = packet_names(module);
    let err = |what: String| PacketError { construct: what, function: Some("mx_pattern".into()) };
    let (ph, pf) = module.functions.iter().find(|(_, f)| f.name.as_deref() == Some("mx_pattern")).ok_or_else(|| err("a pattern kernel without `mx_pattern`".into()))?;
    let struct_named = |name: &str| module.types.iter().find(|(_, t)| t.name.as_deref() == Some(name) && matches!(t.inner, TypeInner::Struct { .. })).map(|(h, _)| h);
    let members = |h: Handle<naga::Type>| -> Vec<(String, String)> {
        match &module.types[h].inner {
            TypeInner::Struct { members, .. } => members.iter().enumerate().map(|(k, m)| (m.name.clone().unwrap_or_default(), names[&NameKey::StructMember(h, k as u32)].clone())).collect(),
            _ => Vec::new(),
        }
    };
    // Geometry: every field from its columns; bitangents are normal × tangent.
    let gh = struct_named("mx_geometry").ok_or_else(|| err("a pattern kernel without `mx_geometry`".into()))?;
    let column = |field: &str| GEOMETRY_LAYOUT.iter().find(|(p, _)| p.field() == field).map(|(_, o)| *o);
    let load3 = |o: usize| format!("[mx_g({o}), mx_g({}), mx_g({})]", o + 1, o + 2);
    let mut geometry_fields = Vec::new();
    for (wgsl_name, rust_name) in members(gh) {
        let expr = match (column(&wgsl_name), wgsl_name.strip_prefix("bitangent_")) {
            (Some(o), _) if wgsl_name == "texcoord" => format!("[mx_g({o}), mx_g({})]", o + 1),
            (Some(o), _) => load3(o),
            (None, Some(space)) => {
                let n = column(&format!("normal_{space}")).ok_or_else(|| err(format!("the geometry field `{wgsl_name}`")))?;
                let t = column(&format!("tangent_{space}")).ok_or_else(|| err(format!("the geometry field `{wgsl_name}`")))?;
                format!("uplift_simd::vector::cross::<S>({}, {})", load3(n), load3(t))
            }
            _ => return Err(err(format!("the geometry field `{wgsl_name}`"))),
        };
        geometry_fields.push(Field { name: rust_name, expr });
    }
    let (inputs_struct, input_fields) = match struct_named("MxInputs") {
        Some(ih) => {
            let m = members(ih);
            if m.len() != kernel.inputs.len() {
                return Err(err("`MxInputs` that does not match the kernel's inputs".into()));
            }
            let mut fields = Vec::new();
            for ((_, rust_name), inp) in m.into_iter().zip(&kernel.inputs) {
                fields.push(Field { name: rust_name, expr: load(&inp.input.ty, inp.offset).map_err(err)? });
            }
            (Some(names[&NameKey::Type(ih)].clone()), fields)
        }
        None if kernel.inputs.is_empty() => (None, Vec::new()),
        None => return Err(err("a kernel with inputs but no `MxInputs`".into())),
    };
    let oh = struct_named("MxOutputs").ok_or_else(|| err("a pattern kernel without `MxOutputs`".into()))?;
    let out_members = members(oh);
    if out_members.len() != kernel.outputs.len() {
        return Err(err("`MxOutputs` that does not match the kernel's outputs".into()));
    }
    let mut output_stores = Vec::new();
    for ((_, rust_name), out) in out_members.iter().zip(&kernel.outputs) {
        output_stores.extend(store(&out.ty, &format!("mx_out.{rust_name}"), out.offset).map_err(err)?);
    }
    let mut args = vec!["s".to_string()];
    for a in &pf.arguments {
        match module.types[a.ty].name.as_deref() {
            Some("mx_geometry") => args.push("mx_geom".into()),
            Some("MxInputs") => args.push("mx_inputs".into()),
            _ => return Err(err("an `mx_pattern` argument other than the geometry and the inputs".into())),
        }
    }
    let call = format!("{}({})", names[&NameKey::Function(ph)], args.join(", "));
    let split = match instance {
        Some(i) if inputs_struct.is_some() => {
            let zero = |ty: &DataType| match ty.components() {
                Some(n @ 2..=4) => format!("[s.splat(0.0); {n}]"),
                _ => "s.splat(0.0)".to_string(),
            };
            let mut group_inputs = Vec::new();
            let mut point_inputs = Vec::new();
            let mut point_columns = Vec::new();
            for (f, inp) in input_fields.iter().zip(&kernel.inputs) {
                if POINT_INPUTS.contains(&inp.input.name.as_str()) {
                    if !matches!(inp.input.ty, DataType::Float | DataType::Vector2 | DataType::Vector3 | DataType::Vector4) {
                        return Err(err(format!("a per-point input `{}` of type {}", inp.input.name, inp.input.ty)));
                    }
                    group_inputs.push(Field { name: f.name.clone(), expr: zero(&inp.input.ty) });
                    point_inputs.push(Field { name: f.name.clone(), expr: f.expr.clone() });
                    point_columns.extend(inp.offset..inp.offset + inp.input.ty.components().unwrap_or(1));
                } else {
                    group_inputs.push(Field { name: f.name.clone(), expr: f.expr.replace("mx_x(", "mx_xg(") });
                    point_inputs.push(Field { name: f.name.clone(), expr: f.expr.replace("mx_x(", "mx_xs(") });
                }
            }
            let group_geometry = geometry_fields.iter().map(|f| Field { name: f.name.clone(), expr: f.expr.replace("mx_g(", "mx_gg(") }).collect();
            let point_geometry = geometry_fields.iter().map(|f| Field { name: f.name.clone(), expr: f.expr.replace("mx_g(", "mx_gs(") }).collect();
            Some(SplitFields { group_fn: i.group, point_fn: i.point, slots: i.slots, group_geometry, group_inputs, point_geometry, point_inputs, point_columns })
        }
        _ => None,
    };
    let source = kernel.source_name();
    let template = PacketKernelTemplate {
        source,
        naga_version: crate::backend_rust::NAGA_VERSION,
        module: &body,
        geometry_stride: GEOMETRY_STRIDE,
        input_stride: kernel.input_stride,
        output_stride: kernel.output_stride,
        geometry_struct: names[&NameKey::Type(gh)].clone(),
        geometry_fields,
        inputs_struct,
        input_fields,
        call,
        output_stores,
        plain_entry: !options.grouped_only || split.is_none(),
        split,
    };
    let mut text = template.render().map_err(|e| unsupported(format!("(template error) {e}")))?;
    if !text.ends_with('\n') {
        text.push('\n');
    }
    Ok(text)
}

/// A value of MaterialX type `ty` from columns `offset..` of the current packet.
fn load(ty: &DataType, offset: usize) -> Result<String, String> {
    let list = |n: usize| (0..n).map(|k| format!("mx_x({})", offset + k)).collect::<Vec<_>>().join(", ");
    Ok(match ty {
        DataType::Boolean => format!("mx_x({offset}).ne(s.splat(0.0))"),
        DataType::Integer => format!("mx_x({offset}).to_i32()"),
        DataType::Float => format!("mx_x({offset})"),
        t => match t.components() {
            Some(n @ 2..=4) if !matches!(t, DataType::Matrix33 | DataType::Matrix44) => format!("[{}]", list(n)),
            _ => return Err(format!("an input of type {t}")),
        },
    })
}

/// Stores of a value of MaterialX type `ty` into columns `offset..` of the current packet.
fn store(ty: &DataType, value: &str, offset: usize) -> Result<Vec<String>, String> {
    let at = |c: usize, v: String| format!("s.store_partial({v}, &mut outputs[{}][mx_start..mx_end]);", offset + c);
    Ok(match ty {
        DataType::Boolean => vec![at(0, format!("{value}.select(s.splat(1.0), s.splat(0.0))"))],
        DataType::Integer => vec![at(0, format!("{value}.to_f32()"))],
        DataType::Float => vec![at(0, value.to_string())],
        t => match t.components() {
            Some(n @ 2..=4) if !matches!(t, DataType::Matrix33 | DataType::Matrix44) => (0..n).map(|k| at(k, format!("{value}[{k}]"))).collect(),
            _ => return Err(format!("an output of type {t}")),
        },
    })
}
