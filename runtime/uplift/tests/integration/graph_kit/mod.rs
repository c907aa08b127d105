//! Small helpers shared by the hand-written numeric tests (numeric_procedural, numeric_noise,
//! numeric_texture): writing a nodegraph document as text, filling interface-input rows by
//! input name, and reading an output's components by output name (offsets come from the
//! compiled kernel, so unused or reordered inputs cannot shift a test's columns).
#![allow(dead_code)]

use uplift_compiler::PatternKernel;

/// Where a node input comes from.
pub enum Src<'a> {
    /// A literal value (the document's text form, e.g. "0.5, 1").
    V(&'a str),
    /// The nodegraph's interface input of this name.
    I(&'a str),
    /// The (single) output of the node of this name.
    N(&'a str),
}

/// Components of a MaterialX type name.
pub fn comps(ty: &str) -> usize {
    match ty {
        "float" | "integer" | "boolean" => 1,
        "vector2" => 2,
        "vector3" | "color3" => 3,
        "vector4" | "color4" => 4,
        "matrix33" => 9,
        "matrix44" => 16,
        _ => panic!("no components for {ty}"),
    }
}

/// `<tag name=.. type=..>` with its inputs.
pub fn node(tag: &str, name: &str, ty: &str, inputs: &[(&str, &str, Src)]) -> String {
    let mut s = format!("<{tag} name=\"{name}\" type=\"{ty}\">");
    for (n, t, src) in inputs {
        match src {
            Src::V(v) => s += &format!("<input name=\"{n}\" type=\"{t}\" value=\"{v}\"/>"),
            Src::I(i) => s += &format!("<input name=\"{n}\" type=\"{t}\" interfacename=\"{i}\"/>"),
            Src::N(m) => s += &format!("<input name=\"{n}\" type=\"{t}\" nodename=\"{m}\"/>"),
        }
    }
    s + &format!("</{tag}>\n")
}

/// A document with one nodegraph: interface inputs (name, type; value zero), the node
/// elements, and outputs (name, type, node name). Outputs share the nodegraph's namespace with
/// the nodes, so output `x` is written as `o_x` (the kernel calls it `g/o_x`); [`out`] reads it
/// back by `x`.
pub fn graph_doc(inputs: &[(&str, &str)], nodes: &[String], outputs: &[(String, String, String)]) -> String {
    let mut s = String::from("<?xml version=\"1.0\"?>\n<materialx version=\"1.39\">\n<nodegraph name=\"g\">\n");
    for (n, t) in inputs {
        let zero = vec!["0"; comps(t)].join(", ");
        let zero = if *t == "boolean" { "false".to_string() } else { zero };
        s += &format!("<input name=\"{n}\" type=\"{t}\" value=\"{zero}\"/>\n");
    }
    for n in nodes {
        s += n;
    }
    for (n, t, from) in outputs {
        s += &format!("<output name=\"o_{n}\" type=\"{t}\" nodename=\"{from}\"/>\n");
    }
    s + "</nodegraph>\n</materialx>\n"
}

/// One interface-input row: every kernel input from `values` by name. Every kernel input must
/// be given, and every given name must be a kernel input (catches typos and dropped inputs).
pub fn input_row(k: &PatternKernel, values: &[(&str, Vec<f32>)]) -> Vec<f32> {
    let mut row = vec![f32::NAN; k.input_stride];
    for (name, v) in values {
        let ki = k.inputs.iter().find(|i| i.input.name == *name).unwrap_or_else(|| panic!("kernel has no input `{name}`"));
        assert_eq!(v.len(), ki.input.ty.components().unwrap(), "width of input `{name}`");
        row[ki.offset..ki.offset + v.len()].copy_from_slice(v);
    }
    for ki in &k.inputs {
        assert!(values.iter().any(|(n, _)| *n == ki.input.name), "no value given for kernel input `{}`", ki.input.name);
    }
    row
}

/// The components of output `name` (written by [`graph_doc`]) in an output row.
pub fn out<'a>(k: &PatternKernel, row: &'a [f32], name: &str) -> &'a [f32] {
    let o = k.outputs.iter().find(|o| o.name == format!("g/o_{name}")).unwrap_or_else(|| panic!("kernel has no output `{name}`"));
    &row[o.offset..o.offset + o.ty.components().unwrap()]
}

/// max |got - want| over components.
pub fn max_err(got: &[f32], want: &[f32]) -> f32 {
    assert_eq!(got.len(), want.len());
    got.iter().zip(want).map(|(g, w)| (g - w).abs()).fold(0.0, f32::max)
}

/// Formats a float list as a MaterialX value.
pub fn val(v: &[f32]) -> String {
    v.iter().map(|x| format!("{x:?}")).collect::<Vec<_>>().join(", ")
}
