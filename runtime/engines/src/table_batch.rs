//! Tables of points as batches (what `uplift eval` reads and writes): the CSV columns a kernel
//! accepts — the geometric columns `texcoord_x,texcoord_y,position_x,…,tangent_z` (object space
//! equals world space) and the kernel's interface inputs by name with component suffixes
//! (`_x/_y/_z/_w` for vectors, `_r/_g/_b/_a` for colors, `_0…` for matrices, none for scalars) —
//! a table's rows as a [`PatternBatch`] (missing interface columns take the document's values;
//! columns naming an input of the output's nodegraph that this output does not read are accepted
//! and ignored, so one table serves every output of a graph), and the output columns' names.

use crate::batch::{Geometry, PatternBatch};
use crate::texture_loader::load_texture;
use mtlx::DataType;
use std::collections::HashMap;
use std::path::Path;
use uplift_base::csv_table;
use uplift_compiler::PatternKernel;

/// The geometric input columns and their defaults: texcoord (0, 0), position (0, 0, 0),
/// normal (0, 0, 1), tangent (1, 0, 0).
pub const GEOMETRY_COLUMNS: [(&str, f32); 11] = [
    ("texcoord_x", 0.0),
    ("texcoord_y", 0.0),
    ("position_x", 0.0),
    ("position_y", 0.0),
    ("position_z", 0.0),
    ("normal_x", 0.0),
    ("normal_y", 0.0),
    ("normal_z", 1.0),
    ("tangent_x", 1.0),
    ("tangent_y", 0.0),
    ("tangent_z", 0.0),
];

/// Where a CSV column's value goes.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Slot {
    /// Index into [`GEOMETRY_COLUMNS`].
    Geometry(usize),
    /// Float offset in the kernel's input row.
    Input(usize),
    /// An input of the output's nodegraph that this output does not read: accepted, ignored.
    Unused,
    /// A name that two interface inputs (or an input and a geometric column) both claim.
    Ambiguous,
}

/// Every column name accepted: the geometric ones, the kernel's interface inputs, and the other
/// inputs of the output's nodegraph (`graph_inputs`, ignored).
fn column_slots(kernel: &PatternKernel, graph_inputs: &[(String, DataType)]) -> HashMap<String, Slot> {
    let mut slots: HashMap<String, Slot> = GEOMETRY_COLUMNS.iter().enumerate().map(|(k, (n, _))| (n.to_string(), Slot::Geometry(k))).collect();
    for inp in &kernel.inputs {
        for (k, suffix) in inp.input.ty.component_suffixes().iter().enumerate() {
            let name = format!("{}{suffix}", inp.input.name);
            let slot = if slots.contains_key(&name) { Slot::Ambiguous } else { Slot::Input(inp.offset + k) };
            slots.insert(name, slot);
        }
    }
    for (name, ty) in graph_inputs {
        if !ty.is_numeric() || kernel.inputs.iter().any(|i| &i.input.name == name) {
            continue;
        }
        for suffix in ty.component_suffixes() {
            let name = format!("{name}{suffix}");
            let slot = if matches!(slots.get(&name), Some(Slot::Geometry(_))) { Slot::Ambiguous } else { Slot::Unused };
            slots.entry(name).or_insert(slot);
        }
    }
    slots
}

/// The `<input>`s (name, type) of the nodegraph holding `output` in `file`; empty for a
/// document-level output or when the document cannot be read.
pub fn graph_inputs(file: &Path, output: &str) -> Vec<(String, DataType)> {
    let (doc, _) = mtlx::read_file(file);
    let outputs = uplift_compiler::graph_builder::document_outputs(&doc);
    let found: Vec<_> = outputs.iter().filter(|o| o.name == output || o.name.rsplit('/').next() == Some(output)).collect();
    let [one] = found.as_slice() else { return Vec::new() };
    if one.graph == doc.root() {
        return Vec::new();
    }
    doc.children_of(one.graph, "input")
        .map(|i| {
            let e = doc.get(i);
            (e.name().to_string(), DataType::from_name(e.attr("type").unwrap_or("")))
        })
        .collect()
}

/// The output CSV header: one column per output component.
pub fn output_columns(kernel: &PatternKernel) -> Vec<String> {
    let mut cols = vec![String::new(); kernel.output_stride];
    for o in &kernel.outputs {
        for (k, suffix) in o.ty.component_suffixes().iter().enumerate() {
            cols[o.offset + k] = format!("{}{suffix}", o.name);
        }
    }
    cols
}

/// The kernel's per-point inputs for the rows of `table` (`file` names it in errors).
/// `graph_inputs` are the nodegraph's other inputs (see [`graph_inputs`]): their columns are
/// accepted and ignored.
pub fn batch_from_table(kernel: &PatternKernel, graph_inputs: &[(String, DataType)], table: &csv_table::Table, file: &str) -> Result<PatternBatch, String> {
    let slots = column_slots(kernel, graph_inputs);
    let mut mapping = Vec::with_capacity(table.header.len());
    for name in &table.header {
        match slots.get(name) {
            Some(Slot::Ambiguous) => {
                return Err(format!("{file}:{}: column `{name}` is ambiguous: several inputs of the graph have that name", table.header_line))
            }
            Some(s) => mapping.push(*s),
            None => {
                let mut inputs: Vec<String> = slots.iter().filter(|(_, s)| matches!(s, Slot::Input(_) | Slot::Unused)).map(|(n, _)| n.clone()).collect();
                inputs.sort();
                let inputs = if inputs.is_empty() { "none".to_string() } else { inputs.join(", ") };
                return Err(format!(
                    "{file}:{}: unknown column `{name}`; expected geometric columns ({}) or the graph's interface inputs ({inputs})",
                    table.header_line,
                    GEOMETRY_COLUMNS.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", ")
                ));
            }
        }
    }
    let mut input_defaults = vec![0.0f32; kernel.input_stride];
    for inp in &kernel.inputs {
        let d = &inp.input.default;
        input_defaults[inp.offset..inp.offset + d.len()].copy_from_slice(d);
    }
    let n = table.rows.len();
    let mut points = Vec::with_capacity(n);
    let mut inputs = Vec::with_capacity(n * kernel.input_stride);
    for row in &table.rows {
        let mut g: [f32; 11] = GEOMETRY_COLUMNS.map(|(_, d)| d);
        let start = inputs.len();
        inputs.extend_from_slice(&input_defaults);
        for (v, slot) in row.iter().zip(&mapping) {
            match slot {
                Slot::Geometry(k) => g[*k] = *v,
                Slot::Input(o) => inputs[start + o] = *v,
                Slot::Unused => {}
                Slot::Ambiguous => unreachable!("rejected above"),
            }
        }
        points.push(Geometry { texcoord: [g[0], g[1]], position: [g[2], g[3], g[4]], normal: [g[5], g[6], g[7]], tangent: [g[8], g[9], g[10]] });
    }
    let mut textures = Vec::with_capacity(kernel.textures.len());
    for t in &kernel.textures {
        textures.push(load_texture(&t.path, t.colorspace.as_deref())?);
    }
    Ok(PatternBatch::from_rows(&points, &inputs, kernel.input_stride, textures))
}
