//! A data-driven harness for per-nodedef numeric tests.
//!
//! For every nodedef of the node groups a test names, the harness writes a nodegraph with one
//! interface `<input>` per numeric nodedef input (connected by `interfacename` to one node of the
//! nodedef's category) and one `<output>` per nodedef output, compiles it, runs 256 random rows
//! on wgpu and compares every output component with a closed-form reference that the test file
//! computes in Rust (a [`Spec`] per category). Many nodedefs share one document (and one wgpu
//! run); a failure names the nodedef, the row, its inputs, and what was expected.
//!
//! Every nodedef of the named groups must be covered: it has a [`Spec`] for its category, or it
//! sits in the test's skip list (with a reason) or known-failure list (compiler issues, with a
//! reason). A nodedef with neither fails the test rather than being skipped silently.
//!
//! For an atomic nodedef the harness also checks that the node calls that nodedef's own WGSL
//! function (that node matching picked it). With `UPLIFT_NUMERIC_STATS=1` (and `--nocapture`)
//! it prints each nodedef's largest error and each chunk's compile and run time.
#![allow(dead_code)]

use crate::common::{compiler, engine, Rng};
use mtlx::schema::{NodeDef, PortDef};
use mtlx::DataType;
use std::collections::BTreeMap;
use uplift_engines::batch::{Geometry, PatternBatch, PatternEngine};
use uplift_compiler::ir::ValueKind;
use uplift_compiler::node_library::NodeLibrary;
use uplift_compiler::{OutputSelection, PatternKernel};

/// Rows per nodedef.
pub const ROWS: usize = 256;
/// Nodedefs per generated document (one compile and one wgpu run each).
const CHUNK: usize = 24;

/// How far a result may be from the reference.
#[derive(Clone, Copy, Debug)]
pub enum Tol {
    /// |got - want| ≤ tol.
    Abs(f32),
    /// |got - want| ≤ tol · max(1, |want|): for outputs of large magnitude.
    Rel(f32),
}

impl Tol {
    fn ok(self, got: f32, want: f32) -> bool {
        if got.is_nan() && want.is_nan() {
            return true;
        }
        let err = (got - want).abs();
        match self {
            Tol::Abs(t) => err <= t,
            Tol::Rel(t) => err <= t * want.abs().max(1.0),
        }
    }
}

/// A generator of one input's value: `None` falls back to the default for its type.
pub type Gen = fn(&NodeDef, &PortDef, &mut Rng) -> Option<Vec<f32>>;
/// A closed-form reference: every output's components, concatenated in nodedef output order.
pub type Reference = fn(&NodeDef, &Inputs) -> Vec<f32>;

/// How to test the nodedefs of one category.
pub struct Spec {
    pub category: &'static str,
    pub tol: Tol,
    pub gen: Gen,
    pub reference: Reference,
}

/// Default generation only.
pub fn no_gen(_: &NodeDef, _: &PortDef, _: &mut Rng) -> Option<Vec<f32>> {
    None
}

/// One row's input values, by nodedef input name.
pub struct Inputs {
    pub values: BTreeMap<String, Vec<f32>>,
}

impl Inputs {
    /// All components of input `name`.
    pub fn v(&self, name: &str) -> Vec<f32> {
        self.values.get(name).unwrap_or_else(|| panic!("no input `{name}`")).clone()
    }
    /// The first component of input `name`.
    pub fn f(&self, name: &str) -> f32 {
        self.v(name)[0]
    }
    pub fn i(&self, name: &str) -> i32 {
        self.f(name) as i32
    }
    pub fn b(&self, name: &str) -> bool {
        self.f(name) != 0.0
    }
    /// Input `name` with `n` components: a scalar is broadcast (the `FA` variants).
    pub fn n(&self, name: &str, n: usize) -> Vec<f32> {
        let v = self.v(name);
        if v.len() == 1 {
            vec![v[0]; n]
        } else {
            assert_eq!(v.len(), n, "input `{name}` width");
            v
        }
    }
}

/// Number of components of the first output of `nd`.
pub fn out_n(nd: &NodeDef) -> usize {
    nd.outputs[0].ty.components().unwrap()
}

/// Number of components of input `name` of `nd`.
pub fn in_n(nd: &NodeDef, name: &str) -> usize {
    nd.input(name).unwrap().ty.components().unwrap()
}

/// Componentwise map of one input (broadcast to the output width).
pub fn map1(nd: &NodeDef, x: &Inputs, a: &str, f: impl Fn(f32) -> f32) -> Vec<f32> {
    x.n(a, out_n(nd)).into_iter().map(f).collect()
}

/// Componentwise map of two inputs (scalars broadcast to the output width).
pub fn map2(nd: &NodeDef, x: &Inputs, a: &str, b: &str, f: impl Fn(f32, f32) -> f32) -> Vec<f32> {
    let n = out_n(nd);
    x.n(a, n).into_iter().zip(x.n(b, n)).map(|(p, q)| f(p, q)).collect()
}

/// Componentwise map of three inputs.
pub fn map3(nd: &NodeDef, x: &Inputs, a: &str, b: &str, c: &str, f: impl Fn(f32, f32, f32) -> f32) -> Vec<f32> {
    let n = out_n(nd);
    let (p, q, r) = (x.n(a, n), x.n(b, n), x.n(c, n));
    (0..n).map(|k| f(p[k], q[k], r[k])).collect()
}

/// The value a type's generator picks when the spec does not: floats in [-2, 2], integers in
/// [-5, 5], booleans 0/1.
pub fn default_value(ty: &DataType, rng: &mut Rng) -> Vec<f32> {
    match ty {
        DataType::Boolean => vec![(rng.next_u64() & 1) as f32],
        DataType::Integer => vec![int_in(rng, -5, 5)],
        t => (0..t.components().unwrap()).map(|_| rng.range(-2.0, 2.0)).collect(),
    }
}

/// An integer in [lo, hi], as f32.
pub fn int_in(rng: &mut Rng, lo: i32, hi: i32) -> f32 {
    (lo + (rng.next_u64() % (hi - lo + 1) as u64) as i32) as f32
}

/// `n` values uniform in [lo, hi).
pub fn uniform(rng: &mut Rng, n: usize, lo: f32, hi: f32) -> Vec<f32> {
    (0..n).map(|_| rng.range(lo, hi)).collect()
}

/// `n` values with magnitude in [lo, hi) and a random sign (away from zero).
pub fn away_from_zero(rng: &mut Rng, n: usize, lo: f32, hi: f32) -> Vec<f32> {
    (0..n).map(|_| if rng.next_u64() & 1 == 0 { rng.range(lo, hi) } else { -rng.range(lo, hi) }).collect()
}

fn zero_value(ty: &DataType) -> String {
    match ty {
        DataType::Boolean => "false".into(),
        t => vec!["0"; t.components().unwrap()].join(","),
    }
}

/// Names used in the generated document for nodedef `nd`.
fn node_name(nd: &NodeDef) -> String {
    nd.name.strip_prefix("ND_").unwrap_or(&nd.name).to_string()
}

fn port_input_name(nd: &NodeDef, port: &str) -> String {
    format!("{}__{}", node_name(nd), port)
}

fn output_name(nd: &NodeDef, out: &str) -> String {
    format!("{}__o_{}", node_name(nd), out)
}

/// The nodegraph body for one nodedef: interface inputs, the node, outputs.
fn nodedef_xml(nd: &NodeDef) -> String {
    let mut s = String::new();
    for p in nd.inputs.iter().filter(|p| p.ty.is_numeric()) {
        s += &format!(
            "  <input name=\"{}\" type=\"{}\" value=\"{}\"/>\n",
            port_input_name(nd, &p.name),
            p.ty.name(),
            zero_value(&p.ty)
        );
    }
    let ty = if nd.outputs.len() == 1 { nd.outputs[0].ty.name().to_string() } else { "multioutput".to_string() };
    s += &format!("  <{} name=\"{}\" type=\"{}\">\n", nd.node, node_name(nd), ty);
    for p in &nd.inputs {
        if p.ty.is_numeric() {
            s += &format!(
                "    <input name=\"{}\" type=\"{}\" interfacename=\"{}\"/>\n",
                p.name,
                p.ty.name(),
                port_input_name(nd, &p.name)
            );
        } else if let Some(v) = string_input_value(nd, p) {
            s += &format!("    <input name=\"{}\" type=\"{}\" value=\"{}\"/>\n", p.name, p.ty.name(), v);
        }
    }
    s += &format!("  </{}>\n", nd.node);
    for o in &nd.outputs {
        let sel = if nd.outputs.len() > 1 { format!(" output=\"{}\"", o.name) } else { String::new() };
        s += &format!(
            "  <output name=\"{}\" type=\"{}\" nodename=\"{}\"{sel}/>\n",
            output_name(nd, &o.name),
            o.ty.name(),
            node_name(nd)
        );
    }
    s
}

/// Fixed values for string inputs: the spaces of `transform*` (world to world: the identity
/// whatever the renderer's spaces are); the first enum value otherwise.
fn string_input_value(_nd: &NodeDef, p: &PortDef) -> Option<String> {
    match p.name.as_str() {
        "fromspace" | "tospace" => Some("world".into()),
        _ => p.enum_values.as_ref().map(|e| e[0].clone()),
    }
}

fn document(nds: &[&NodeDef]) -> String {
    let mut s = String::from("<?xml version=\"1.0\"?>\n<materialx version=\"1.39\">\n<nodegraph name=\"g\">\n");
    for nd in nds {
        s += &nodedef_xml(nd);
    }
    s += "</nodegraph>\n</materialx>\n";
    s
}

fn try_compile(text: &str) -> Result<PatternKernel, String> {
    let (doc, diags) = mtlx::read_str(text, "test.mtlx");
    let c = compiler().compile_document(doc, diags, "test.mtlx", &OutputSelection::AllNumeric);
    match c.kernel {
        Some(k) => Ok(k),
        None => Err(c.diagnostics.iter().map(|d| d.to_string()).collect::<Vec<_>>().join("\n")),
    }
}

fn input_offset(k: &PatternKernel, name: &str) -> Option<usize> {
    k.inputs.iter().find(|i| i.input.name == name || i.input.name.ends_with(&format!("/{name}"))).map(|i| i.offset)
}

fn output_offset(k: &PatternKernel, name: &str) -> Option<usize> {
    k.outputs.iter().find(|o| o.name == name || o.name.ends_with(&format!("/{name}"))).map(|o| o.offset)
}

/// What a test run covers and excludes.
pub struct Plan<'a> {
    /// Node groups (`nodegroup` of the nodedef) whose every nodedef must be covered.
    pub groups: &'a [&'a str],
    /// Restricts the nodedefs of those groups (e.g. only `constant` of `procedural`).
    pub filter: fn(&NodeDef) -> bool,
    pub specs: &'a [Spec],
    /// Nodedefs not tested, with the reason (closure, string, texture types, ...).
    pub skip: &'a [(&'a str, &'a str)],
    /// Nodedefs left out because of a known compiler problem, with the problem.
    pub known_failures: &'a [(&'a str, &'a str)],
    pub seed: u64,
}

pub fn all(_: &NodeDef) -> bool {
    true
}

/// Runs the plan; panics with every mismatch (nodedef, row, inputs, got, want).
pub fn run_plan(plan: &Plan) {
    let defs = &compiler().library.defs;
    let mut errors: Vec<String> = Vec::new();
    for (name, _) in plan.skip.iter().chain(plan.known_failures) {
        if defs.nodedef(name).is_none() {
            errors.push(format!("skip/known-failure list names {name}, which is not a nodedef"));
        }
    }
    let mut tested: Vec<(&NodeDef, &Spec)> = Vec::new();
    for nd in defs.nodedefs.iter() {
        let Some(group) = nd.nodegroup.as_deref() else { continue };
        if !plan.groups.contains(&group) || !(plan.filter)(nd) {
            continue;
        }
        if plan.skip.iter().chain(plan.known_failures).any(|(n, _)| *n == nd.name) {
            continue;
        }
        match plan.specs.iter().find(|s| s.category == nd.node) {
            Some(spec) => tested.push((nd, spec)),
            None => errors.push(format!("{}: no reference for category `{}` (add a Spec or a skip entry)", nd.name, nd.node)),
        }
    }
    for s in plan.specs {
        if !tested.iter().any(|(_, t)| t.category == s.category) {
            errors.push(format!("spec for `{}` tested no nodedef", s.category));
        }
    }

    // Chunks run on a few threads (compiling and running are independent); each chunk has its
    // own seeded generator so results do not depend on scheduling.
    let chunks: Vec<&[(&NodeDef, &Spec)]> = tested.chunks(CHUNK).collect();
    let mut per_category: BTreeMap<&str, usize> = BTreeMap::new();
    for (g, group) in chunks.chunks(4).enumerate() {
        let first = g * 4;
        let results: Vec<(Vec<String>, BTreeMap<&str, usize>)> = std::thread::scope(|s| {
            let handles: Vec<_> = group
                .iter()
                .enumerate()
                .map(|(i, chunk)| {
                    let seed = plan.seed.wrapping_mul(1000).wrapping_add((first + i) as u64);
                    s.spawn(move || run_chunk(chunk, seed))
                })
                .collect();
            handles.into_iter().map(|h| h.join().unwrap()).collect()
        });
        for (e, c) in results {
            errors.extend(e);
            for (k, v) in c {
                *per_category.entry(k).or_default() += v;
            }
        }
    }
    println!("nodedefs tested per category: {per_category:?}");
    println!("total: {}", per_category.values().sum::<usize>());
    if !errors.is_empty() {
        let n = errors.len();
        let shown: Vec<_> = errors.into_iter().take(60).collect();
        panic!("{n} problem(s):\n{}", shown.join("\n"));
    }
}

fn run_chunk<'a>(chunk: &[(&'a NodeDef, &'a Spec)], seed: u64) -> (Vec<String>, BTreeMap<&'a str, usize>) {
    let mut rng = Rng::new(seed);
    let mut errors = Vec::new();
    let mut per_category = BTreeMap::new();
    let nds: Vec<&NodeDef> = chunk.iter().map(|(nd, _)| *nd).collect();
    let t0 = std::time::Instant::now();
    let compiled = try_compile(&document(&nds));
    if std::env::var_os("UPLIFT_NUMERIC_STATS").is_some() {
        println!("chunk {}..: compile {:?}", nds[0].name, t0.elapsed());
    }
    match compiled {
        Ok(k) => {
            let t0 = std::time::Instant::now();
            check_chunk(&k, chunk, &mut rng, &mut errors, &mut per_category);
            if std::env::var_os("UPLIFT_NUMERIC_STATS").is_some() {
                println!("chunk {}..: run {:?}", nds[0].name, t0.elapsed());
            }
        }
        Err(_) => {
            // Find the nodedefs that do not compile; run the rest together.
            let mut ok = Vec::new();
            for (nd, spec) in chunk {
                match try_compile(&document(&[nd])) {
                    Ok(_) => ok.push((*nd, *spec)),
                    Err(e) => errors.push(format!("{}: does not compile:\n{e}\n{}", nd.name, document(&[nd]))),
                }
            }
            if !ok.is_empty() {
                let nds: Vec<&NodeDef> = ok.iter().map(|(nd, _)| *nd).collect();
                match try_compile(&document(&nds)) {
                    Ok(k) => check_chunk(&k, &ok, &mut rng, &mut errors, &mut per_category),
                    Err(e) => errors.push(format!(
                        "nodedefs {:?} compile alone but not together:\n{e}",
                        nds.iter().map(|n| &n.name).collect::<Vec<_>>()
                    )),
                }
            }
        }
    }
    (errors, per_category)
}

fn check_chunk<'a>(
    k: &PatternKernel,
    chunk: &[(&'a NodeDef, &'a Spec)],
    rng: &mut Rng,
    errors: &mut Vec<String>,
    per_category: &mut BTreeMap<&'a str, usize>,
) {
    // Generate per-nodedef input values, then lay them out in kernel input rows.
    let mut rows = vec![vec![0.0f32; k.input_stride]; ROWS];
    let mut values: Vec<Vec<Inputs>> = Vec::new();
    for (nd, spec) in chunk {
        let mut per_row = Vec::new();
        for row in rows.iter_mut() {
            let mut inputs = Inputs { values: BTreeMap::new() };
            for p in nd.inputs.iter().filter(|p| p.ty.is_numeric()) {
                let v = (spec.gen)(nd, p, rng).unwrap_or_else(|| default_value(&p.ty, rng));
                assert_eq!(v.len(), p.ty.components().unwrap(), "{}: generated width of `{}`", nd.name, p.name);
                let name = port_input_name(nd, &p.name);
                let off = input_offset(k, &name).unwrap_or_else(|| panic!("{}: kernel has no input {name}", nd.name));
                row[off..off + v.len()].copy_from_slice(&v);
                inputs.values.insert(p.name.clone(), v);
            }
            per_row.push(inputs);
        }
        values.push(per_row);
    }
    let geometry = vec![Geometry::default(); ROWS];
    let flat: Vec<f32> = rows.iter().flatten().copied().collect();
    let batch = PatternBatch::from_rows(&geometry, &flat, k.input_stride, vec![]);
    let out = engine().run_pattern(k, &batch).unwrap_or_else(|e| panic!("{e}")).to_rows();
    let out: Vec<&[f32]> = out.chunks(k.output_stride).collect();

    for ((nd, spec), per_row) in chunk.iter().zip(&values) {
        *per_category.entry(spec.category).or_default() += 1;
        // An atomic nodedef's node must call its own function (node matching picked it), unless
        // the compiler folded the node away (identity nodes such as `dot`).
        if !compiler().library.defs.graphs.contains_key(&nd.name) {
            let want = NodeLibrary::function_name(&nd.name);
            let suffix = format!("/{}", node_name(nd));
            for (_, v) in k.graph.values.iter() {
                if let ValueKind::Call { function, .. } = &v.kind {
                    if v.origin.ends_with(&suffix) && *function != want {
                        errors.push(format!("{}: the node calls {function}, not {want}", nd.name));
                    }
                }
            }
        }
        let mut bad_rows = 0;
        let mut max_err = 0.0f32;
        for (r, inputs) in per_row.iter().enumerate() {
            let want = (spec.reference)(nd, inputs);
            let mut got = Vec::new();
            for o in &nd.outputs {
                let name = output_name(nd, &o.name);
                let off = output_offset(k, &name).unwrap_or_else(|| panic!("{}: kernel has no output {name}", nd.name));
                got.extend_from_slice(&out[r][off..off + o.ty.components().unwrap()]);
            }
            assert_eq!(got.len(), want.len(), "{}: reference width", nd.name);
            for c in 0..got.len() {
                max_err = max_err.max((got[c] - want[c]).abs());
            }
            let bad: Vec<usize> = (0..got.len()).filter(|&c| !spec.tol.ok(got[c], want[c])).collect();
            if !bad.is_empty() {
                bad_rows += 1;
                if bad_rows <= 3 {
                    errors.push(format!(
                        "{} row {r}: inputs {:?}\n    got  {:?}\n    want {:?}\n    (components {:?} beyond {:?})",
                        nd.name, inputs.values, got, want, bad, spec.tol
                    ));
                }
            }
        }
        if std::env::var_os("UPLIFT_NUMERIC_STATS").is_some() {
            println!("{:40} max |err| {max_err:e}", nd.name);
        }
        if bad_rows > 3 {
            errors.push(format!("{}: {bad_rows} of {ROWS} rows differ", nd.name));
        }
    }
}

// ---- small linear algebra on MaterialX row-major matrices (value lists, row by row) ----

/// Row-major product `a · b` of n×n matrices.
pub fn matmul(a: &[f32], b: &[f32], n: usize) -> Vec<f32> {
    let mut r = vec![0.0f32; n * n];
    for i in 0..n {
        for j in 0..n {
            let mut s = 0.0f64;
            for k in 0..n {
                s += a[i * n + k] as f64 * b[k * n + j] as f64;
            }
            r[i * n + j] = s as f32;
        }
    }
    r
}

pub fn transpose(a: &[f32], n: usize) -> Vec<f32> {
    (0..n * n).map(|k| a[(k % n) * n + k / n]).collect()
}

/// Determinant by Laplace expansion along the first row (f64).
pub fn det(a: &[f64], n: usize) -> f64 {
    if n == 1 {
        return a[0];
    }
    let mut s = 0.0;
    for j in 0..n {
        let minor: Vec<f64> =
            (1..n).flat_map(|i| (0..n).filter(move |&c| c != j).map(move |c| (i, c))).map(|(i, c)| a[i * n + c]).collect();
        let sign = if j % 2 == 0 { 1.0 } else { -1.0 };
        s += sign * a[j] * det(&minor, n - 1);
    }
    s
}

/// Inverse by the adjugate (f64): inv[i][j] = cofactor[j][i] / det.
pub fn inverse(a: &[f32], n: usize) -> Vec<f32> {
    let a: Vec<f64> = a.iter().map(|&v| v as f64).collect();
    let d = det(&a, n);
    let mut r = vec![0.0f32; n * n];
    for i in 0..n {
        for j in 0..n {
            let minor: Vec<f64> = (0..n)
                .filter(|&rr| rr != j)
                .flat_map(|rr| (0..n).filter(move |&cc| cc != i).map(move |cc| (rr, cc)))
                .map(|(rr, cc)| a[rr * n + cc])
                .collect();
            let sign = if (i + j) % 2 == 0 { 1.0 } else { -1.0 };
            r[i * n + j] = (sign * det(&minor, n - 1) / d) as f32;
        }
    }
    r
}

pub fn dot(a: &[f32], b: &[f32]) -> f32 {
    a.iter().zip(b).map(|(x, y)| (*x as f64) * (*y as f64)).sum::<f64>() as f32
}

pub fn length(a: &[f32]) -> f32 {
    dot(a, a).sqrt()
}

pub fn normalize(a: &[f32]) -> Vec<f32> {
    let l = length(a);
    a.iter().map(|v| v / l).collect()
}

pub fn cross(a: &[f32], b: &[f32]) -> Vec<f32> {
    vec![a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

pub fn b2f(b: bool) -> f32 {
    if b {
        1.0
    } else {
        0.0
    }
}
