//! The indexed node library: nodedefs by name and category (with `inherit` merged), the
//! nodegraphs that implement nodedefs, and the WGSL items; plus nodedef matching as
//! MaterialX's `Node::getNodeDef` does it (category, output type, exact types of the authored
//! inputs, version).

use crate::const_eval::ConstEvaluator;
use crate::wgsl_items::{normalize_type, WgslItem, WgslItems};
use crate::wgsl_types::wgsl_type;
use mtlx::schema::NodeDef;
use mtlx::{DataType, Diagnostic, Document, ElementId, Library, SourcePos};
use std::collections::HashMap;
use std::sync::Arc;

/// Where a nodegraph lives: document index in [`Definitions::documents`] and element.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GraphRef {
    pub doc: usize,
    pub element: ElementId,
}

/// Nodedefs and nodegraph implementations from a set of documents.
#[derive(Clone, Debug, Default)]
pub struct Definitions {
    pub documents: Vec<Arc<Document>>,
    pub nodedefs: Vec<NodeDef>,
    by_name: HashMap<String, usize>,
    by_category: HashMap<String, Vec<usize>>,
    /// nodedef name → the nodegraph implementing it.
    pub graphs: HashMap<String, GraphRef>,
}

impl Definitions {
    /// Indexes `docs` in order; the first definition of a name wins. Names are indexed
    /// qualified by their namespace (`ns:ND_x`, category `ns:x`); references resolve as
    /// [`Definitions::resolve`] says.
    pub fn new(docs: Vec<Arc<Document>>) -> Definitions {
        let mut defs = Definitions { documents: docs, ..Default::default() };
        for di in 0..defs.documents.len() {
            let doc = defs.documents[di].clone();
            for &id in doc.top_level().iter().filter(|&&id| doc.get(id).category == "nodedef") {
                let nd = NodeDef::from_element(&doc, id);
                if defs.by_name.contains_key(&nd.name) {
                    continue;
                }
                let i = defs.nodedefs.len();
                defs.by_name.insert(nd.name.clone(), i);
                defs.by_category.entry(nd.node.clone()).or_default().push(i);
                defs.nodedefs.push(nd);
            }
        }
        // Implementations second: their `nodedef` references resolve against every nodedef.
        for di in 0..defs.documents.len() {
            let doc = defs.documents[di].clone();
            for &id in doc.top_level() {
                let e = doc.get(id);
                let (nodedef, graph) = match e.category.as_str() {
                    "nodegraph" => (e.attr("nodedef"), Some(id)),
                    "implementation" => (e.attr("nodedef"), e.attr("nodegraph").and_then(|ng| doc.resolve(id, doc.root(), ng))),
                    _ => continue,
                };
                if let (Some(nd), Some(g)) = (nodedef, graph) {
                    let key = defs.resolve(doc.namespace(id), nd).map_or_else(|| nd.to_string(), |x| x.name.clone());
                    defs.graphs.entry(key).or_insert(GraphRef { doc: di, element: g });
                }
            }
        }
        defs.resolve_inheritance();
        defs
    }

    /// The nodedef a reference `name` written in namespace `namespace` means: qualified by that
    /// namespace first, then as written (MaterialX's `resolveNameReference`).
    pub fn resolve(&self, namespace: Option<&str>, name: &str) -> Option<&NodeDef> {
        self.by_name.get(&mtlx::document::qualify(namespace, name)).or_else(|| self.by_name.get(name)).map(|&i| &self.nodedefs[i])
    }

    /// Prepends inherited inputs/outputs (`inherit="ND_parent"`) to each nodedef.
    fn resolve_inheritance(&mut self) {
        for i in 0..self.nodedefs.len() {
            let mut chain = Vec::new();
            let mut cur = self.nodedefs[i].inherit.clone().map(|p| (p, i));
            while let Some((p, from)) = cur {
                let ns = self.nodedefs[from].namespace.clone();
                let Some(&pi) = self.by_name.get(&mtlx::document::qualify(ns.as_deref(), &p)).or_else(|| self.by_name.get(&p)) else { break };
                if chain.contains(&pi) || pi == i {
                    break;
                }
                chain.push(pi);
                cur = self.nodedefs[pi].inherit.clone().map(|p| (p, pi));
            }
            for &pi in chain.iter() {
                let parent = self.nodedefs[pi].clone();
                let nd = &mut self.nodedefs[i];
                let mut inputs: Vec<_> = parent.inputs.into_iter().filter(|p| nd.input(&p.name).is_none()).collect();
                inputs.append(&mut nd.inputs);
                nd.inputs = inputs;
                let mut outputs: Vec<_> = parent.outputs.into_iter().filter(|p| nd.output(&p.name).is_none()).collect();
                outputs.append(&mut nd.outputs);
                nd.outputs = outputs;
            }
        }
    }

    pub fn nodedef(&self, name: &str) -> Option<&NodeDef> {
        self.by_name.get(name).map(|&i| &self.nodedefs[i])
    }

    pub fn has_category(&self, category: &str) -> bool {
        self.by_category.contains_key(category)
    }

    /// Nodedefs of `category` in definition order.
    pub fn by_category(&self, category: &str) -> impl Iterator<Item = &NodeDef> {
        self.by_category.get(category).into_iter().flatten().map(|&i| &self.nodedefs[i])
    }
}

/// The library function every albedo-table read goes through, and the constant array it reads
/// on the CPU (pbrlib's `albedo_tables.wgsl`); lowering swaps the accessor for a storage-buffer
/// read in GPU kernels.
pub const TABLE_ACCESSOR: &str = "mx_albedo_table";
pub const TABLE_DATA: &str = "mx_albedo_table_data";

/// The library the compiler works with: definitions plus WGSL items, with library problems.
#[derive(Clone, Debug)]
pub struct NodeLibrary {
    pub defs: Definitions,
    pub wgsl: WgslItems,
    pub diagnostics: Vec<Diagnostic>,
    /// `check_signature` of every library nodedef that has a WGSL function, computed once.
    signatures: HashMap<String, Result<(), String>>,
    /// Interprets library functions on constant arguments (constant folding); `None` when the
    /// library's WGSL does not parse as one module (reported in `diagnostics`).
    pub evaluator: Option<ConstEvaluator>,
    /// The values of the library's albedo-table array (`mx_albedo_table_data`), which GPU
    /// kernels receive as a storage buffer.
    pub albedo_table_data: Option<std::sync::Arc<[f32]>>,
    /// `closure_fold` verdicts on this library's lobes (whether one at weight 0 is the empty
    /// BSDF), by function name, computed on first use (a clone of the library shares them).
    pub(crate) zero_weight_verdicts: std::sync::Arc<std::sync::Mutex<HashMap<String, bool>>>,
}

/// What a node's authored element says, for matching.
pub struct NodeQuery<'a> {
    pub category: &'a str,
    pub ty: &'a DataType,
    pub version: Option<&'a str>,
    /// (input name, type) for every authored input.
    pub inputs: &'a [(String, DataType)],
}

impl NodeLibrary {
    pub fn new(library: Library) -> NodeLibrary {
        let mut diagnostics = library.diagnostics;
        let defs = Definitions::new(library.documents.into_iter().map(Arc::new).collect());
        let mut wgsl = WgslItems::default();
        for src in &library.wgsl {
            for e in wgsl.add_source(&src.path, &src.text) {
                diagnostics.push(Diagnostic::error(SourcePos::new(e.file.into(), e.line, 1), e.message));
            }
        }
        wgsl.link();
        let all_wgsl: String = library.wgsl.iter().map(|w| w.text.as_str()).collect::<Vec<_>>().join("\n");
        let evaluator = match ConstEvaluator::new(&all_wgsl) {
            Ok(e) => Some(e),
            Err(m) => {
                diagnostics.push(Diagnostic::error(SourcePos::synthetic("<library WGSL>"), format!("the library's WGSL does not parse as one module: {m}")));
                None
            }
        };
        let albedo_table_data = wgsl.items.get(TABLE_DATA).and_then(|i| const_f32_array(&i.text)).map(std::sync::Arc::from);
        let mut lib = NodeLibrary { defs, wgsl, diagnostics, signatures: HashMap::new(), evaluator, albedo_table_data, zero_weight_verdicts: Default::default() };
        let checked: HashMap<String, Result<(), String>> = lib
            .defs
            .nodedefs
            .iter()
            .filter(|nd| lib.function(&nd.name).is_some())
            .map(|nd| (nd.name.clone(), lib.check_signature(nd)))
            .collect();
        lib.signatures = checked;
        lib
    }

    /// Whether `nd`'s WGSL function fits it (precomputed for library nodedefs).
    pub fn signature_fits(&self, nd: &NodeDef) -> Result<(), String> {
        match self.signatures.get(&nd.name) {
            Some(r) => r.clone(),
            None => self.check_signature(nd),
        }
    }

    /// The WGSL function implementing an atomic nodedef: `ND_x` → `mx_x`; a namespaced one
    /// `ns:ND_x` → `mx_ns_x`.
    pub fn function_name(nodedef: &str) -> String {
        let (namespace, local) = nodedef.rsplit_once(':').map_or((None, nodedef), |(ns, l)| (Some(ns), l));
        let local = local.strip_prefix("ND_").unwrap_or(local);
        match namespace {
            Some(ns) => format!("mx_{}_{local}", ns.replace(':', "_")),
            None => format!("mx_{local}"),
        }
    }

    pub fn function(&self, nodedef: &str) -> Option<&WgslItem> {
        self.wgsl.items.get(&Self::function_name(nodedef))
    }

    /// Checks that the WGSL function of `nd` has the parameters and result its nodedef implies
    /// (README rules 2–5). Returns a message naming the first difference.
    pub fn check_signature(&self, nd: &NodeDef) -> Result<(), String> {
        let name = Self::function_name(&nd.name);
        let item = self.wgsl.items.get(&name).ok_or_else(|| format!("no WGSL implementation `{name}` for nodedef `{}`", nd.name))?;
        let sig = item.signature.as_ref().ok_or_else(|| format!("`{name}` is not a function"))?;
        let mut expected: Vec<String> = Vec::new();
        for p in &nd.inputs {
            if p.ty == DataType::String && p.enum_values.is_none() {
                continue;
            }
            match wgsl_type(&p.ty, p.enum_values.is_some()) {
                Some(t) => expected.push(t.to_string()),
                None => return Err(format!("input `{}` of `{}` has type {}, which has no WGSL form", p.name, nd.name, p.ty)),
            }
        }
        let params: Vec<&str> = sig.params.iter().map(|(_, t)| t.as_str()).collect();
        let params = match params.first() {
            Some(&"mx_geometry") => &params[1..],
            _ => &params[..],
        };
        let params = match params.first() {
            Some(&"mx_closure") => &params[1..],
            _ => params,
        };
        if params != expected.iter().map(String::as_str).collect::<Vec<_>>().as_slice() {
            return Err(format!(
                "`{name}` ({}:{}) takes ({}) but nodedef `{}` implies ({})",
                item.file,
                item.line,
                params.join(", "),
                nd.name,
                expected.join(", ")
            ));
        }
        let result = match nd.outputs.as_slice() {
            [one] => wgsl_type(&one.ty, false).map(str::to_string),
            _ => Some(format!("{name}_outputs")),
        };
        if sig.result.as_deref().map(normalize_type) != result {
            return Err(format!(
                "`{name}` returns {} but nodedef `{}` implies {}",
                sig.result.as_deref().unwrap_or("nothing"),
                nd.name,
                result.as_deref().unwrap_or("no WGSL type")
            ));
        }
        Ok(())
    }

    /// Atomic nodedefs (no implementing nodegraph).
    pub fn atomic_nodedefs(&self) -> impl Iterator<Item = &NodeDef> {
        self.defs.nodedefs.iter().filter(|nd| !self.defs.graphs.contains_key(&nd.name))
    }
}

/// The values of `const name = array<f32, N>(v0, v1, …);` (comments already stripped or not).
fn const_f32_array(text: &str) -> Option<Vec<f32>> {
    let open = text.find("array<f32")?;
    let body = &text[open..];
    let start = body.find('(')? + 1;
    let end = body.rfind(')')?;
    let values: Vec<f32> = body[start..end]
        .lines()
        .map(|l| l.split("//").next().unwrap_or(""))
        .flat_map(|l| l.split(','))
        .map(str::trim)
        .filter(|t| !t.is_empty())
        .map(|t| t.trim_end_matches('f').parse::<f32>())
        .collect::<Result<_, _>>()
        .ok()?;
    Some(values)
}

/// Finds the nodedef for a node among `layers` (searched in order: a document's own
/// definitions before the library's). Returns `Err` with a message naming what was asked.
pub fn match_nodedef<'a>(layers: &[&'a Definitions], q: &NodeQuery) -> Result<&'a NodeDef, String> {
    if !layers.iter().any(|d| d.has_category(q.category)) {
        return Err(format!("unknown node category `{}`: no nodedef in the loaded libraries", q.category));
    }
    let fits = |nd: &NodeDef| {
        let out_ok = match q.ty {
            DataType::Multioutput => nd.outputs.len() > 1,
            t => nd.outputs.len() == 1 && &nd.outputs[0].ty == t,
        };
        out_ok && q.inputs.iter().all(|(n, t)| nd.input(n).is_some_and(|p| &p.ty == t))
    };
    let version_ok = |nd: &NodeDef| match q.version {
        Some(v) => nd.version.as_deref() == Some(v),
        None => nd.version.is_none() || nd.is_default_version,
    };
    for layer in layers {
        if let Some(nd) = layer.by_category(q.category).find(|nd| fits(nd) && version_ok(nd)) {
            return Ok(nd);
        }
    }
    for layer in layers {
        if let Some(nd) = layer.by_category(q.category).find(|nd| fits(nd)) {
            return Ok(nd);
        }
    }
    let inputs: Vec<String> = q.inputs.iter().map(|(n, t)| format!("{n}: {t}")).collect();
    Err(format!(
        "no nodedef for `{}` of type {} with inputs ({})",
        q.category,
        q.ty,
        inputs.join(", ")
    ))
}
