//! Every nodedef of the stdlib `channel`, `conditional` and `organization` node groups and the
//! `constant` nodes of `procedural`, every type variant: compiled from a generated nodegraph,
//! run on wgpu for 256 random rows, compared with a closed form written here from the
//! MaterialX spec (MaterialX.StandardNodes.md) and MaterialX's GLSL semantics.
//!
//! Booleans travel as 0/1 and integers as whole-numbered f32 (see numeric_smoke.rs). All these
//! nodes move or select values, so the tolerance is the arithmetic one, 1e-5 absolute.

use crate::common;
use crate::nodedef_harness;

use common::Rng;
use mtlx::schema::{NodeDef, PortDef};
use mtlx::DataType;
use nodedef_harness::*;

fn gen(nd: &NodeDef, p: &PortDef, rng: &mut Rng) -> Option<Vec<f32>> {
    Some(match (nd.node.as_str(), p.name.as_str()) {
        // Compared values come from a small set so that equality (and its boundary for
        // ifgreater/ifgreatereq) happens often.
        ("ifgreater" | "ifgreatereq" | "ifequal", "value1" | "value2") => match p.ty {
            DataType::Float => vec![[-1.0, -0.5, 0.0, 0.5, 1.0][(rng.next_u64() % 5) as usize]],
            DataType::Integer => vec![int_in(rng, -2, 2)],
            _ => return None, // booleans: 0/1
        },
        // `which` in [-2, 10): below 0 selects in1. At 10 and above the spec says in10 (floor +
        // 1, clamped to 1-10) but MaterialX's own nodegraph (NG_switch_*, a chain of
        // `ifgreater(k, which)`) gives 0 there: the two disagree, so that range is left out.
        ("switch", "which") => match p.ty {
            DataType::Integer => vec![int_in(rng, -2, 9)],
            _ => vec![rng.range(-2.0, 10.0)],
        },
        // Valid indices only: the spec calls any other index an error.
        ("extract", "index") => {
            let n = match nd.input("in").unwrap().ty {
                DataType::Matrix33 => 3,
                DataType::Matrix44 => 4,
                ref t => t.components().unwrap(),
            };
            vec![int_in(rng, 0, n as i32 - 1)]
        }
        _ => return None,
    })
}

fn select(cond: bool, nd: &NodeDef, x: &Inputs) -> Vec<f32> {
    if nd.input("in1").is_none() {
        // The boolean variants output the comparison itself.
        vec![b2f(cond)]
    } else if cond {
        x.v("in1")
    } else {
        x.v("in2")
    }
}

fn reference(nd: &NodeDef, x: &Inputs) -> Vec<f32> {
    match nd.node.as_str() {
        "convert" => {
            let from = &nd.inputs[0].ty;
            let to = &nd.outputs[0].ty;
            let m = to.components().unwrap();
            let v = x.v("in");
            match from {
                // Booleans become 0/1 (all channels), integers their value, true for non-zero.
                DataType::Boolean => vec![b2f(x.b("in")); m],
                DataType::Integer if *to == DataType::Boolean => vec![b2f(x.i("in") != 0)],
                DataType::Integer | DataType::Float => vec![v[0]; m],
                // colorN/vectorN to colorM/vectorM: copy, truncate, or pad with 0 except the
                // fourth channel, which is 1.
                _ => (0..m).map(|k| if k < v.len() { v[k] } else if k == 3 { 1.0 } else { 0.0 }).collect(),
            }
        }
        "combine2" | "combine3" | "combine4" => nd.inputs.iter().flat_map(|p| x.v(&p.name)).collect(),
        "extract" => {
            let v = x.v("in");
            let i = x.i("index") as usize;
            match nd.inputs[0].ty {
                // A matrix gives its index-th row (MaterialX rows are the value list's rows).
                DataType::Matrix33 => v[i * 3..i * 3 + 3].to_vec(),
                DataType::Matrix44 => v[i * 4..i * 4 + 4].to_vec(),
                _ => vec![v[i]],
            }
        }
        "separate2" | "separate3" | "separate4" => x.v("in"),
        // Strictly greater, as the spec and GLSL `>`.
        "ifgreater" => select(x.f("value1") > x.f("value2"), nd, x),
        "ifgreatereq" => select(x.f("value1") >= x.f("value2"), nd, x),
        "ifequal" => select(x.f("value1") == x.f("value2"), nd, x),
        "switch" => {
            // Input floor(which) + 1, clamped to 1..10.
            let k = (x.f("which").floor() as i32).clamp(0, 9) + 1;
            x.v(&format!("in{k}"))
        }
        "and" => vec![b2f(x.b("in1") && x.b("in2"))],
        "or" => vec![b2f(x.b("in1") || x.b("in2"))],
        "xor" => vec![b2f(x.b("in1") != x.b("in2"))],
        "not" => vec![b2f(!x.b("in"))],
        "dot" => x.v("in"),
        "constant" => x.v("value"),
        c => panic!("no reference for {c}"),
    }
}

const ABS: Tol = Tol::Abs(1e-5);

macro_rules! specs {
    ($($cat:literal),* $(,)?) => {
        &[$(Spec { category: $cat, tol: ABS, gen, reference }),*]
    };
}

const SPECS: &[Spec] = specs![
    "convert", "combine2", "combine3", "combine4", "extract", "separate2", "separate3", "separate4",
    "ifgreater", "ifgreatereq", "ifequal", "switch", "and", "or", "xor", "not", "dot", "constant",
];

/// Not tested, with the reason.
const SKIP: &[(&str, &str)] = &[
    // Non-numeric types: nothing a pattern kernel outputs.
    ("ND_constant_string", "string value"),
    ("ND_constant_filename", "filename value"),
    ("ND_dot_string", "string value"),
    ("ND_dot_filename", "filename value"),
    ("ND_dot_surfaceshader", "shader type"),
    ("ND_dot_displacementshader", "shader type"),
    ("ND_dot_volumeshader", "shader type"),
    ("ND_dot_lightshader", "shader type"),
    // Procedural nodes other than `constant` are outside this test (hash-based values).
    ("ND_randomfloat_float", "not a constant: hash-based random value"),
    ("ND_randomfloat_integer", "not a constant: hash-based random value"),
];

/// Left out because of a known compiler problem (reported; see the test's report).
const KNOWN_FAILURES: &[(&str, &str)] = &[];

#[test]
fn every_channel_conditional_organization_constant_nodedef_matches_its_closed_form() {
    run_plan(&Plan {
        groups: &["channel", "conditional", "organization", "procedural"],
        filter: all,
        specs: SPECS,
        skip: SKIP,
        known_failures: KNOWN_FAILURES,
        seed: 22,
    });
}
