//! Builds the graph IR from a document: finds each requested output, walks upstream through
//! `nodename`/`nodegraph`/`interfacename` connections, matches every node to its nodedef,
//! inlines nodegraph implementations, binds unauthored inputs to nodedef defaults and
//! geometric properties, turns filename inputs into texture bindings, and appends one IR value
//! per node output. Identity implementations fold away and equal values are shared (value
//! numbering). Every error carries the source position of the element at fault.

mod height_to_normal;

use crate::arena::Handle;
use crate::const_eval::Const;
use crate::ir::{GeomProp, Graph, GraphOutput, InterfaceInput, TextureBinding, Value, ValueKind};
use crate::node_library::{match_nodedef, Definitions, NodeLibrary, NodeQuery};
use mtlx::schema::{NodeDef, PortDef};
use mtlx::{DataType, Diagnostic, Document, ElementId, SourcePos, Value as Literal};
use std::borrow::Cow;
use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};
use std::sync::Arc;

type H = Handle<Value>;

/// The result of building one node: one value per output.
#[derive(Clone, Debug)]
enum NodeResult {
    Single(H),
    Multi(Vec<(String, H)>),
}

/// How a scope's `interfacename` references resolve.
#[derive(Clone, Debug)]
enum Interface {
    /// A nodegraph implementing a nodedef: names bind to the instantiating node's inputs.
    Functional(HashMap<String, H>),
    /// A compound nodegraph: names are the graph's own `<input>` elements. In the kernel's
    /// graph they become kernel interface inputs; elsewhere they resolve in the parent scope.
    Compound { kernel: bool },
    /// The document root.
    Root,
}

#[derive(Clone, Debug)]
struct Scope {
    doc: Arc<Document>,
    graph: ElementId,
    interface: Interface,
    parent: Option<usize>,
    path: String,
}

/// Application nodes whose value the host supplies for each evaluation (MaterialX's
/// `application` nodegroup, and nprlib's `viewdirection`): nodedef, the geomprop that names the
/// same value (`defaultgeomprop="Vworld"`), the kernel's interface input that carries it, and its
/// default (the nodedef's output default; one component: float, three: vector3). `time` is in
/// seconds (its nodedef's `fps` input is deprecated and unused), `frame` the frame number,
/// `viewdirection` the direction from the viewer to the shading point in world space (the
/// `space` input of the node is not applied: the host supplies world space).
pub const APPLICATION_INPUTS: &[(&str, Option<&str>, &str, &[f32])] = &[
    ("ND_time_float", None, "time", &[0.0]),
    ("ND_frame_float", None, "frame", &[1.0]),
    ("ND_viewdirection_vector3", Some("Vworld"), "viewdirection", &[0.0, 0.0, 1.0]),
];

/// The type of an APPLICATION_INPUTS entry's value, from its default's components.
fn application_type(default: &[f32]) -> DataType {
    if default.len() == 3 {
        DataType::Vector3
    } else {
        DataType::Float
    }
}

/// An output the caller asks for: a document-level `<output>` or a compound nodegraph's.
#[derive(Clone, Debug)]
pub struct OutputRef {
    /// `graph/output`, or just `output` at document level.
    pub name: String,
    /// The graph holding it (root or nodegraph element) and the `<output>` element.
    pub graph: ElementId,
    pub element: ElementId,
    pub ty: DataType,
    pub pos: SourcePos,
    /// When `element` is a node rather than an `<input>`/`<output>`: which of its outputs
    /// (empty for a single-output node).
    pub node_output: Option<String>,
}

/// Every output of `doc` that a pattern kernel could evaluate (numeric types), and the
/// others (closures, strings), in document order.
pub fn document_outputs(doc: &Document) -> Vec<OutputRef> {
    let mut out = Vec::new();
    let push = |out: &mut Vec<OutputRef>, graph: ElementId, prefix: &str| {
        for o in doc.children_of(graph, "output") {
            let e = doc.get(o);
            out.push(OutputRef {
                name: format!("{prefix}{}", e.name()),
                graph,
                element: o,
                ty: DataType::from_name(e.attr("type").unwrap_or("")),
                pos: e.pos.clone(),
                node_output: None,
            });
        }
    };
    let mut graphs = vec![(doc.root(), String::new())];
    for g in doc.children_of(doc.root(), "nodegraph") {
        let e = doc.get(g);
        if e.attr("nodedef").is_none() {
            graphs.push((g, format!("{}/", e.name())));
        }
    }
    for (g, prefix) in &graphs {
        push(&mut out, *g, prefix);
    }
    // Top-level numeric nodes that nothing consumes are renderable values too (MaterialX's
    // test documents often hold bare nodes): named by the node. So are unconsumed top-level
    // BSDFs, surface shaders and materials (a document's `surfacematerial`), for the closure
    // contexts.
    let root = doc.root();
    let consumed: std::collections::HashSet<&str> = doc
        .descendants(root)
        .into_iter()
        .filter_map(|i| doc.get(i).attr("nodename"))
        .collect();
    for &n in doc.children(root) {
        let ne = doc.get(n);
        let ty = DataType::from_name(ne.attr("type").unwrap_or(""));
        let closure = crate::wgsl_types::is_scattering(&ty);
        if mtlx::schema::is_node_category(&ne.category) && !consumed.contains(ne.name()) && (ty.is_numeric() || ty == DataType::Multioutput || closure) {
            let outs: Vec<ElementId> = doc.children_of(n, "output").collect();
            if ty == DataType::Multioutput {
                for o in outs {
                    let oe = doc.get(o);
                    let oty = DataType::from_name(oe.attr("type").unwrap_or(""));
                    out.push(OutputRef { name: format!("{}/{}", ne.name(), oe.name()), graph: root, element: n, ty: oty, pos: ne.pos.clone(), node_output: Some(oe.name().to_string()) });
                }
            } else {
                out.push(OutputRef { name: ne.name().to_string(), graph: root, element: n, ty, pos: ne.pos.clone(), node_output: Some(String::new()) });
            }
        }
    }
    // The connected numeric inputs of shader and closure nodes are pattern outputs too:
    // `node/input` (what a renderer binds as per-texel parameters).
    for (g, prefix) in &graphs {
        for n in doc.children(*g) {
            let ne = doc.get(*n);
            let is_closure_node = ne.attr("type").is_some_and(|t| DataType::from_name(t).is_closure());
            if !is_closure_node || !mtlx::schema::is_node_category(&ne.category) {
                continue;
            }
            for i in doc.children_of(*n, "input") {
                let ie = doc.get(i);
                let ty = DataType::from_name(ie.attr("type").unwrap_or(""));
                let connected = mtlx::schema::CONNECTION_ATTRIBUTES.iter().any(|a| ie.attr(a).is_some());
                if ty.is_numeric() && connected {
                    out.push(OutputRef { name: format!("{prefix}{}/{}", ne.name(), ie.name()), graph: *g, element: i, ty, pos: ie.pos.clone(), node_output: None });
                }
            }
        }
    }
    out
}

pub struct GraphBuilder<'a> {
    lib: &'a NodeLibrary,
    local: Definitions,
    graph: Graph,
    scopes: Vec<Scope>,
    scope_of_graph: HashMap<(usize, ElementId), usize>,
    memo: HashMap<(usize, ElementId), Option<NodeResult>>,
    /// Nodes being built, outermost first (for cycle paths), and as a set (for the cycle test).
    visiting: Vec<(usize, ElementId)>,
    visiting_set: HashSet<(usize, ElementId)>,
    /// Nodedefs whose nodegraphs are being inlined (for recursion).
    inlining: Vec<String>,
    consing: HashMap<(ConsKey, DataType), H>,
    kernel_inputs: HashMap<(usize, String), H>,
    /// Interface inputs bound to constants at compile time (`Compiler::constant_inputs`):
    /// name → MaterialX value text. They are no kernel inputs; what depends on them folds.
    pub constant_inputs: HashMap<String, String>,
    /// Bindings of `constant_inputs` used (an unused one is an error).
    constant_inputs_used: HashSet<String>,
    pub diagnostics: Vec<Diagnostic>,
    /// Folders besides the document's own where the files it names may lie (`Compiler::file_roots`);
    /// `None`: anywhere.
    pub file_roots: Option<Vec<PathBuf>>,
}

/// An error that stops building one output.
struct Fail;

/// The deepest chain of nodes (counting nodes inlined from nodegraphs) the builder follows
/// upstream of an output; deeper graphs get a positioned error instead of exhausting memory.
/// Real MaterialX graphs are tens to hundreds of nodes deep.
pub const MAX_GRAPH_DEPTH: usize = 100_000;

/// stacker's parameters: when less than the red zone is left, recursion continues on a new
/// heap-allocated segment of this size.
const STACK_RED_ZONE: usize = 128 * 1024;
const STACK_SEGMENT: usize = 4 * 1024 * 1024;

impl<'a> GraphBuilder<'a> {
    pub fn new(lib: &'a NodeLibrary, doc: Arc<Document>) -> Self {
        let local = Definitions::new(vec![doc.clone()]);
        let root = Scope { doc: doc.clone(), graph: doc.root(), interface: Interface::Root, parent: None, path: String::new() };
        let mut b = GraphBuilder {
            lib,
            local,
            graph: Graph::default(),
            scopes: vec![root],
            scope_of_graph: HashMap::new(),
            memo: HashMap::new(),
            visiting: Vec::new(),
            visiting_set: HashSet::new(),
            inlining: Vec::new(),
            consing: HashMap::new(),
            kernel_inputs: HashMap::new(),
            constant_inputs: HashMap::new(),
            constant_inputs_used: HashSet::new(),
            diagnostics: Vec::new(),
            file_roots: Some(Vec::new()),
        };
        b.check_names(&doc);
        b
    }

    fn doc(&self) -> &Arc<Document> {
        &self.scopes[0].doc
    }

    /// Reports duplicate element names within one parent.
    fn check_names(&mut self, doc: &Document) {
        for id in doc.descendants(doc.root()) {
            let mut seen: HashMap<&str, &SourcePos> = HashMap::new();
            for &c in doc.children(id) {
                let e = doc.get(c);
                let n = e.name();
                if n.is_empty() {
                    continue;
                }
                if let Some(first) = seen.insert(n, &e.pos) {
                    self.diagnostics.push(Diagnostic::error(
                        e.pos.clone(),
                        format!("duplicate name `{n}` (first defined at {first})"),
                    ));
                }
            }
        }
    }

    fn error(&mut self, pos: &SourcePos, msg: impl Into<String>) -> Fail {
        self.diagnostics.push(Diagnostic::error(pos.clone(), msg));
        Fail
    }

    /// Builds the requested outputs; outputs that fail are left out (their errors are in
    /// `diagnostics`). Returns the graph with dead values removed.
    pub fn build(mut self, outputs: &[OutputRef]) -> (Graph, Vec<Diagnostic>) {
        for o in outputs {
            let scope = if o.graph == self.doc().root() {
                0
            } else {
                self.compound_scope(0, o.graph, true)
            };
            let value = match &o.node_output {
                None => self.resolve_connection(scope, o.element, Some(&o.ty)),
                Some(which) => {
                    let name = self.doc().get(o.element).name().to_string();
                    let which = (!which.is_empty()).then_some(which.as_str());
                    self.build_node(scope, o.element).and_then(|r| self.pick_output(r, which, &name, &o.pos))
                }
            };
            if let Ok(h) = value {
                self.graph.outputs.push(GraphOutput { name: o.name.clone(), ty: o.ty.clone(), value: h, pos: o.pos.clone() });
            }
        }
        let mut unused: Vec<&String> = self.constant_inputs.keys().filter(|k| !self.constant_inputs_used.contains(*k)).collect();
        unused.sort();
        for name in unused {
            let pos = self.doc().get(self.doc().root()).pos.clone();
            self.diagnostics.push(Diagnostic::error(pos, format!("an input `{name}` was bound to a constant, but the document has no such interface input")));
        }
        self.graph.remove_dead();
        (self.graph, self.diagnostics)
    }

    /// The scope of a compound nodegraph held by scope `parent` (the document or a graph).
    fn compound_scope(&mut self, parent: usize, graph: ElementId, kernel: bool) -> usize {
        if let Some(&s) = self.scope_of_graph.get(&(parent, graph)) {
            return s;
        }
        let doc = self.scopes[parent].doc.clone();
        let path = format!("{}{}/", self.scopes[parent].path, doc.get(graph).name());
        self.scopes.push(Scope { doc, graph, interface: Interface::Compound { kernel }, parent: Some(parent), path });
        let s = self.scopes.len() - 1;
        self.scope_of_graph.insert((parent, graph), s);
        s
    }

    // ---- values -----------------------------------------------------------------------

    fn add(&mut self, kind: ValueKind, ty: DataType, origin: String, pos: SourcePos) -> H {
        let key = (ConsKey::of(&kind), ty.clone());
        if let Some(&h) = self.consing.get(&key) {
            return h;
        }
        let h = self.graph.values.append(Value { kind, ty, origin, pos });
        self.consing.insert(key, h);
        h
    }

    fn constant(&mut self, ty: &DataType, text: &str, pos: &SourcePos, origin: &str) -> Result<H, Fail> {
        if ty.is_closure() {
            // A closure's only literal is the empty one (`value=""`).
            if !text.trim().is_empty() {
                return Err(self.error(pos, format!("a {ty} input takes a connection or the empty value, not `{text}`")));
            }
            return self.zero(ty, pos, origin);
        }
        match Literal::parse(ty, text) {
            Ok(v) => Ok(self.add(ValueKind::Constant(v), ty.clone(), origin.to_string(), pos.clone())),
            Err(m) => Err(self.error(pos, m)),
        }
    }

    fn zero(&mut self, ty: &DataType, pos: &SourcePos, origin: &str) -> Result<H, Fail> {
        let lit = match ty {
            DataType::Boolean => Literal::Boolean(false),
            DataType::Integer => Literal::Integer(0),
            DataType::String | DataType::Filename => Literal::String(String::new()),
            t if t.is_numeric() => Literal::Floats(vec![0.0; t.components().unwrap()]),
            t if crate::wgsl_types::wgsl_type(t, false).is_some() => Literal::String(String::new()),
            t => return Err(self.error(pos, format!("no default value for type {t}"))),
        };
        Ok(self.add(ValueKind::Constant(lit), ty.clone(), origin.to_string(), pos.clone()))
    }

    // ---- connections ---------------------------------------------------------------------

    /// Resolves an `<input>` or `<output>` element of scope `s`: its connection, or its value.
    /// `expected` is the type the consumer needs (checked against what is connected).
    fn resolve_connection(&mut self, s: usize, el: ElementId, expected: Option<&DataType>) -> Result<H, Fail> {
        let doc = self.scopes[s].doc.clone();
        let e = doc.get(el);
        let pos = e.pos.clone();
        let ty = e.attr("type").map(DataType::from_name).or_else(|| expected.cloned());
        let Some(ty) = ty else { return Err(self.error(&pos, format!("`{}` has no type", e.name()))) };
        if let Some(exp) = expected {
            if *exp != ty {
                return Err(self.error(&pos, format!("type mismatch: `{}` is declared {ty} but {exp} is expected", e.name())));
            }
        }
        let origin = match e.parent.map(|p| doc.get(p)).filter(|p| mtlx::schema::is_node_category(&p.category) && e.category == "input") {
            Some(node) => format!("{}{}.{}", self.scopes[s].path, node.name(), e.name()),
            None => format!("{}{}", self.scopes[s].path, e.name()),
        };
        if let Some(unit) = e.attr("unit") {
            self.diagnostics.push(Diagnostic::warning(pos.clone(), format!("unit `{unit}` on `{}` is recorded but no unit conversion is applied", e.name())));
        }
        // At document level MaterialX also lets `nodename` name a nodegraph.
        let graph_target = e.attr("nodegraph").or_else(|| {
            let n = e.attr("nodename")?;
            let g = doc.resolve(el, self.scopes[s].graph, n)?;
            (doc.get(g).category == "nodegraph").then_some(n)
        });
        let h = if let Some(graph_name) = graph_target {
            // A nodegraph nested in this scope, else one at the document's top level.
            let is_graph = |g: &ElementId| doc.get(*g).category == "nodegraph";
            let nested = doc.resolve(el, self.scopes[s].graph, graph_name).filter(is_graph);
            let Some(g) = nested.or_else(|| doc.resolve(el, doc.root(), graph_name).filter(is_graph)) else {
                return Err(self.error(&pos, format!("dangling reference: no nodegraph named `{graph_name}`")));
            };
            let outs: Vec<ElementId> = doc.children_of(g, "output").collect();
            let out = match (e.attr("output"), outs.as_slice()) {
                (Some(o), _) => doc.child(g, o).filter(|x| doc.get(*x).category == "output"),
                (None, [one]) => Some(*one),
                (None, _) => None,
            };
            let Some(out) = out else {
                return Err(self.error(&pos, format!("nodegraph `{graph_name}` has no output named `{}`", e.attr("output").unwrap_or("(unnamed; it has several)"))));
            };
            // A graph reached again from inside itself is a cycle: each reference would open a
            // fresh nested scope, so the node-level cycle test would never see a node twice.
            let mut up = Some(s);
            while let Some(u) = up {
                if self.scopes[u].graph == g && Arc::ptr_eq(&self.scopes[u].doc, &doc) {
                    return Err(self.error(&pos, format!("cycle: nodegraph `{graph_name}` is connected inside itself (through `{}`)", e.name())));
                }
                up = self.scopes[u].parent;
            }
            let gs = self.compound_scope(s, g, false);
            self.resolve_connection(gs, out, None)?
        } else if let Some(node_name) = e.attr("nodename") {
            let graph = self.scopes[s].graph;
            let Some(node) = doc.resolve(el, graph, node_name).filter(|n| mtlx::schema::is_node_category(&doc.get(*n).category)) else {
                return Err(self.error(&pos, format!("dangling reference: no node named `{node_name}` in this scope")));
            };
            let result = self.build_node(s, node)?;
            self.pick_output(result, e.attr("output"), node_name, &pos)?
        } else if let Some(iname) = e.attr("interfacename") {
            self.resolve_interface(s, iname, &pos)?
        } else if let Some(v) = e.attr("value") {
            if ty == DataType::Filename {
                self.texture(&doc, el, v, &origin)?
            } else {
                self.constant(&ty, v, &pos, &origin)?
            }
        } else {
            self.zero(&ty, &pos, &origin)?
        };
        let got = self.graph.values[h].ty.clone();
        if got != ty && !(ty == DataType::Filename && got == DataType::Filename) {
            return Err(self.error(&pos, format!("type mismatch: `{}` is declared {ty} but its source is {got}", e.name())));
        }
        Ok(h)
    }

    fn pick_output(&mut self, result: NodeResult, output: Option<&str>, node: &str, pos: &SourcePos) -> Result<H, Fail> {
        match (result, output) {
            (NodeResult::Single(h), None) => Ok(h),
            (NodeResult::Single(h), Some("out")) => Ok(h),
            (NodeResult::Single(_), Some(o)) => Err(self.error(pos, format!("node `{node}` has a single output; `{o}` does not exist"))),
            (NodeResult::Multi(outs), Some(o)) => match outs.iter().find(|(n, _)| n == o) {
                Some((_, h)) => Ok(*h),
                None => Err(self.error(pos, format!("node `{node}` has no output named `{o}`"))),
            },
            (NodeResult::Multi(_), None) => Err(self.error(pos, format!("node `{node}` has several outputs: name one with `output=`"))),
        }
    }

    fn resolve_interface(&mut self, s: usize, name: &str, pos: &SourcePos) -> Result<H, Fail> {
        match self.scopes[s].interface.clone() {
            Interface::Functional(map) => match map.get(name) {
                Some(h) => Ok(*h),
                None => Err(self.error(pos, format!("dangling reference: interface input `{name}` does not exist on the nodedef"))),
            },
            Interface::Compound { kernel } => {
                let doc = self.scopes[s].doc.clone();
                let g = self.scopes[s].graph;
                let Some(inp) = doc.child(g, name).filter(|i| doc.get(*i).category == "input") else {
                    return Err(self.error(pos, format!("dangling reference: nodegraph has no input named `{name}`")));
                };
                let e = doc.get(inp);
                let ty = DataType::from_name(e.attr("type").unwrap_or(""));
                let connected = mtlx::schema::CONNECTION_ATTRIBUTES.iter().any(|a| e.attr(a).is_some());
                if kernel && ty.is_numeric() && !connected {
                    return self.kernel_input(s, inp, ty);
                }
                self.resolve_in_parent(s, inp)
            }
            Interface::Root => {
                // Document-level `<input>`s act as the document's interface.
                let doc = self.scopes[s].doc.clone();
                let Some(inp) = doc.child(doc.root(), name).filter(|i| doc.get(*i).category == "input") else {
                    return Err(self.error(pos, format!("dangling reference: `interfacename=\"{name}\"` outside a nodegraph names no document-level input")));
                };
                let ty = DataType::from_name(doc.get(inp).attr("type").unwrap_or(""));
                if ty.is_numeric() {
                    self.kernel_input(s, inp, ty)
                } else {
                    self.resolve_connection(s, inp, None)
                }
            }
        }
    }

    /// Resolves a compound graph's `<input>`: connections refer to the graph's parent scope.
    fn resolve_in_parent(&mut self, s: usize, inp: ElementId) -> Result<H, Fail> {
        let parent = self.scopes[s].parent.unwrap_or(0);
        let doc = self.scopes[s].doc.clone();
        let e = doc.get(inp);
        if mtlx::schema::CONNECTION_ATTRIBUTES.iter().any(|a| e.attr(a).is_some()) {
            self.resolve_connection(parent, inp, None)
        } else {
            self.resolve_connection(s, inp, None)
        }
    }

    fn kernel_input(&mut self, s: usize, inp: ElementId, ty: DataType) -> Result<H, Fail> {
        let doc = self.scopes[s].doc.clone();
        let e = doc.get(inp);
        let key = (s, e.name().to_string());
        if let Some(&h) = self.kernel_inputs.get(&key) {
            return Ok(h);
        }
        if let Some(text) = self.constant_inputs.get(e.name()).cloned() {
            self.constant_inputs_used.insert(e.name().to_string());
            let origin = format!("{}{}", self.scopes[s].path, e.name());
            let h = match Literal::parse(&ty, &text) {
                Ok(v) => self.add(ValueKind::Constant(v), ty.clone(), origin, e.pos.clone()),
                Err(m) => return Err(self.error(&e.pos, format!("the constant bound to input `{}`: {m}", e.name()))),
            };
            self.kernel_inputs.insert(key, h);
            return Ok(h);
        }
        let default = match e.attr("value") {
            Some(v) => match Literal::parse(&ty, v) {
                Ok(l) => l.components(),
                Err(m) => return Err(self.error(&e.pos, m)),
            },
            None => vec![0.0; ty.components().unwrap()],
        };
        let name = e.name().to_string();
        let index = self.graph.inputs.len();
        self.graph.inputs.push(InterfaceInput { name: name.clone(), ty: ty.clone(), default, pos: e.pos.clone() });
        let origin = format!("{}{}", self.scopes[s].path, name);
        let h = self.add(ValueKind::Input(index), ty, origin, e.pos.clone());
        self.kernel_inputs.insert(key, h);
        Ok(h)
    }

    /// The interface input `name` (`default` unless the caller sets it) that stands for an
    /// application node's value (APPLICATION_INPUTS) or a named geometry stream; one per
    /// kernel, however many nodes read it.
    fn application_input(&mut self, name: &str, ty: &DataType, default: &[f32], pos: &SourcePos) -> H {
        let key = (usize::MAX, name.to_string());
        if let Some(&h) = self.kernel_inputs.get(&key) {
            return h;
        }
        let index = self.graph.inputs.len();
        self.graph.inputs.push(InterfaceInput { name: name.to_string(), ty: ty.clone(), default: default.to_vec(), pos: pos.clone() });
        let h = self.add(ValueKind::Input(index), ty.clone(), name.to_string(), pos.clone());
        self.kernel_inputs.insert(key, h);
        h
    }

    // ---- textures ------------------------------------------------------------------------

    /// Nearest value of `attr` on `el` or its ancestors.
    fn scoped_attr(doc: &Document, mut el: ElementId, attr: &str) -> Option<String> {
        loop {
            let e = doc.get(el);
            if let Some(v) = e.attr(attr) {
                return Some(v.to_string());
            }
            el = e.parent?;
        }
    }

    /// A filename value: resolves it (fileprefix, the document's folder) and returns a texture
    /// value, or an empty-string constant when the file cannot be found (texture nodes then
    /// evaluate to their `default` input).
    fn texture(&mut self, doc: &Document, el: ElementId, value: &str, origin: &str) -> Result<H, Fail> {
        let pos = doc.get(el).pos.clone();
        let prefix = Self::scoped_attr(doc, el, "fileprefix").unwrap_or_default();
        let colorspace = Self::scoped_attr(doc, el, "colorspace");
        let rel = format!("{prefix}{value}");
        // The one containment rule (mtlx::file_access), decided before looking for the file, so
        // that a name outside reads the same whether or not something is there.
        let top = doc.get(doc.root()).pos.file.clone();
        let access = match &self.file_roots {
            Some(roots) => mtlx::FileAccess::within(roots.clone()),
            None => mtlx::FileAccess::any(),
        };
        let found = match value.is_empty() || rel.contains('<') || rel.contains('{') {
            true => None,
            false => match access.resolve(&rel, Path::new(&*pos.file), Path::new(&*top)) {
                Err(outside) => return Err(self.error(&pos, outside.to_string())),
                Ok(direct) if direct.is_file() => Some(direct),
                Ok(_) => resources_fallback(&rel, Path::new(&*pos.file)).find(|c| access.contains(c, Path::new(&*top)) && c.is_file()),
            },
        };
        match found {
            Some(path) => {
                let binding = TextureBinding { path, colorspace, pos: pos.clone() };
                let index = match self.graph.textures.iter().position(|t| t.path == binding.path && t.colorspace == binding.colorspace) {
                    Some(i) => i,
                    None => {
                        self.graph.textures.push(binding);
                        self.graph.textures.len() - 1
                    }
                };
                Ok(self.add(ValueKind::Texture(index), DataType::Filename, origin.to_string(), pos))
            }
            _ => {
                if !value.is_empty() {
                    self.diagnostics.push(Diagnostic::warning(pos.clone(), format!("file `{rel}` not found; texture nodes reading it return their `default`")));
                    self.graph.missing_files.push((rel.clone(), pos.clone()));
                }
                Ok(self.add(ValueKind::Constant(Literal::String(String::new())), DataType::Filename, origin.to_string(), pos))
            }
        }
    }

    // ---- nodes ---------------------------------------------------------------------------

    /// The nodedef of node `e`: borrowed from the library (no copy per node), or a copy of the
    /// document's own.
    /// References resolve in the node's namespace first (`namespace`), then as written.
    fn find_nodedef(&self, e: &mtlx::Element, namespace: Option<&str>, ty: &DataType, authored: &[(String, DataType)]) -> Result<Cow<'a, NodeDef>, String> {
        let lib: &'a NodeLibrary = self.lib;
        let found = match e.attr("nodedef") {
            Some(name) => self.local.resolve(namespace, name).or_else(|| lib.defs.resolve(namespace, name)).ok_or_else(|| format!("missing nodedef `{name}`"))?,
            None => {
                let layers = [&self.local, &lib.defs];
                let qualified = mtlx::document::qualify(namespace, &e.category);
                let category = if layers.iter().any(|d| d.has_category(&qualified)) { qualified.as_str() } else { e.category.as_str() };
                match_nodedef(&layers, &NodeQuery { category, ty, version: e.attr("version"), inputs: authored })?
            }
        };
        Ok(match lib.defs.nodedef(&found.name) {
            Some(l) if std::ptr::eq(l, found) => Cow::Borrowed(l),
            _ => Cow::Owned(found.clone()),
        })
    }

    fn build_node(&mut self, s: usize, node: ElementId) -> Result<NodeResult, Fail> {
        let key = (s, node);
        if let Some(r) = self.memo.get(&key) {
            // A node that failed was reported once; its consumers fail silently.
            return r.clone().ok_or(Fail);
        }
        let doc = self.scopes[s].doc.clone();
        let e = doc.get(node);
        if let Some(start) = self.visiting_set.contains(&key).then(|| self.visiting.iter().position(|k| *k == key)).flatten() {
            let path: Vec<String> = self.visiting[start..]
                .iter()
                .map(|(vs, vn)| format!("`{}`", self.scopes[*vs].doc.get(*vn).name()))
                .chain(std::iter::once(format!("`{}`", e.name())))
                .collect();
            let msg = if path.len() == 2 { format!("cycle: node `{}` depends on itself", e.name()) } else { format!("cycle: {}", path.join(" -> ")) };
            return Err(self.error(&e.pos, msg));
        }
        if self.visiting.len() >= MAX_GRAPH_DEPTH {
            return Err(self.error(&e.pos, format!("`{}` lies more than {MAX_GRAPH_DEPTH} nodes upstream of the output being compiled: the graph is too deep", e.name())));
        }
        self.visiting.push(key);
        self.visiting_set.insert(key);
        // Each level of the graph is a few frames of build_node ↔ resolve_connection: the stack
        // grows on the heap when it runs low, so that any depth up to MAX_GRAPH_DEPTH builds on
        // any thread (stacker, as rustc does).
        let r = stacker::maybe_grow(STACK_RED_ZONE, STACK_SEGMENT, || self.build_node_inner(s, node));
        self.visiting_set.remove(&key);
        self.visiting.pop();
        self.memo.insert(key, r.as_ref().ok().cloned());
        r
    }

    fn build_node_inner(&mut self, s: usize, node: ElementId) -> Result<NodeResult, Fail> {
        let doc = self.scopes[s].doc.clone();
        let e = doc.get(node);
        let pos = e.pos.clone();
        let origin = format!("{}{}", self.scopes[s].path, e.name());
        let Some(ty) = e.attr("type").map(DataType::from_name) else {
            return Err(self.error(&pos, format!("node `{}` has no type", e.name())));
        };
        let inputs: Vec<ElementId> = doc.children_of(node, "input").collect();
        let authored: Vec<(String, DataType)> = inputs
            .iter()
            .map(|&i| {
                let ie = doc.get(i);
                (ie.name().to_string(), DataType::from_name(ie.attr("type").unwrap_or("")))
            })
            .collect();
        let nd = match self.find_nodedef(e, doc.namespace(node), &ty, &authored) {
            Ok(nd) => nd,
            Err(m) => {
                // Point at an input no nodedef of this category declares, when there is one.
                let all: Vec<&NodeDef> = self.local.by_category(&e.category).chain(self.lib.defs.by_category(&e.category)).collect();
                if !all.is_empty() {
                    for (&i, (name, _)) in inputs.iter().zip(&authored) {
                        if !all.iter().any(|nd| nd.input(name).is_some()) {
                            return Err(self.error(&doc.get(i).pos, format!("input `{name}` is not declared by any nodedef of `{}`", e.category)));
                        }
                    }
                }
                return Err(self.error(&pos, m));
            }
        };
        for (&i, (name, t)) in inputs.iter().zip(&authored) {
            match nd.input(name) {
                None => return Err(self.error(&doc.get(i).pos, format!("input `{name}` is not declared by nodedef `{}`", nd.name))),
                Some(p) if &p.ty != t => {
                    return Err(self.error(&doc.get(i).pos, format!("type mismatch: input `{name}` is {t} but nodedef `{}` declares {}", nd.name, p.ty)))
                }
                _ => {}
            }
        }
        if nd.node_type() != ty {
            return Err(self.error(&pos, format!("type mismatch: node is {ty} but nodedef `{}` produces {}", nd.name, nd.node_type())));
        }
        if nd.outputs.iter().any(|o| !o.ty.is_numeric() && !matches!(o.ty, DataType::String | DataType::Filename) && crate::wgsl_types::wgsl_type(&o.ty, false).is_none()) {
            return Err(self.error(&pos, format!("node `{}` produces {}, a closure/shader type that a pattern kernel cannot evaluate", e.name(), nd.node_type())));
        }
        // Bind every nodedef input: authored connection/value, or default.
        let mut bound: Vec<(&PortDef, H)> = Vec::new();
        for p in &nd.inputs {
            let h = match inputs.iter().find(|&&i| doc.get(i).name() == p.name) {
                Some(&i) => self.resolve_connection(s, i, Some(&p.ty))?,
                None => self.port_default(p, &origin)?,
            };
            bound.push((p, h));
        }
        // String and filename nodes (`dot`, `constant` of a filename) pass their
        // `defaultinput` through at compile time.
        if let [out] = nd.outputs.as_slice() {
            if matches!(out.ty, DataType::String | DataType::Filename) {
                let through = out.defaultinput.as_deref().and_then(|d| bound.iter().find(|(p, _)| p.name == d));
                return match through {
                    Some((_, h)) => Ok(NodeResult::Single(*h)),
                    None => Err(self.error(&pos, format!("node `{}` produces a {} without a `defaultinput` to pass through", e.name(), out.ty))),
                };
            }
        }
        // Application nodes (`time`, `frame`, `viewdirection`): the host's value, an interface
        // input of the kernel.
        if let Some(&(_, _, name, default)) = APPLICATION_INPUTS.iter().find(|(def, ..)| *def == nd.name) {
            let ty = application_type(default);
            return Ok(NodeResult::Single(self.application_input(name, &ty, default, &pos)));
        }
        // `heighttonormal`: differentiated along UV0 (height_to_normal.rs).
        if nd.node == "heighttonormal" && ty == DataType::Vector3 {
            let input = |name: &str| bound.iter().find(|(p, _)| p.name == name).map(|(_, h)| *h);
            if let (Some(height), Some(scale), Some(texcoord)) = (input("in"), input("scale"), input("texcoord")) {
                return Ok(self.height_to_normal(height, scale, texcoord, &origin, &pos));
            }
        }
        // Named geometry streams (`geompropvalue`, `geomcolor`): per-point values the caller
        // supplies, as interface inputs named after the stream.
        if ty.is_numeric() && matches!(nd.node.as_str(), "geompropvalue" | "geomcolor") {
            let authored = |name: &str| inputs.iter().map(|&i| doc.get(i)).find(|ie| ie.name() == name).and_then(|ie| ie.attr("value").map(str::to_string));
            let (stream, default) = if nd.node == "geomcolor" {
                let index = authored("index").or_else(|| nd.input("index").and_then(|p| p.value.clone())).unwrap_or_else(|| "0".into());
                (format!("geomcolor{}", index.trim()), nd.outputs.first().and_then(|o| o.value.clone()))
            } else {
                // (A `geomprop` attribute: a 1.37 document's form, as upgraded from 1.36's `attrname`.)
                let Some(name) = authored("geomprop").or_else(|| e.attr("geomprop").map(str::to_string)).filter(|n| !n.trim().is_empty()) else {
                    return Err(self.error(&pos, format!("geompropvalue `{}` names no `geomprop`", e.name())));
                };
                (name.trim().to_string(), authored("default").or_else(|| nd.input("default").and_then(|p| p.value.clone())))
            };
            let default = match default.as_deref().map(|d| Literal::parse(&ty, d)) {
                Some(Ok(v)) => v.components(),
                Some(Err(m)) => return Err(self.error(&pos, m)),
                None => vec![0.0; ty.components().unwrap_or(1)],
            };
            return Ok(NodeResult::Single(self.application_input(&stream, &ty, &default, &pos)));
        }
        // Nodegraph implementation: inline.
        let graph_ref = self.local.graphs.get(&nd.name).map(|g| (true, *g)).or_else(|| self.lib.defs.graphs.get(&nd.name).map(|g| (false, *g)));
        if let Some((is_local, g)) = graph_ref {
            if self.inlining.contains(&nd.name) {
                return Err(self.error(&pos, format!("recursive definition: node `{}` instantiates `{}` inside the nodegraph that implements `{}`", e.name(), nd.node, nd.name)));
            }
            self.inlining.push(nd.name.clone());
            let r = self.inline_graph(s, &nd, is_local, g, &bound, &origin);
            self.inlining.pop();
            return r;
        }
        self.call(&nd, bound, &origin, &pos)
    }

    /// Inlines the nodegraph `g` implementing `nd` for a node of scope `s` whose inputs are `bound`.
    fn inline_graph(&mut self, s: usize, nd: &NodeDef, is_local: bool, g: crate::node_library::GraphRef, bound: &[(&PortDef, H)], origin: &str) -> Result<NodeResult, Fail> {
        {
            let gdoc = if is_local { self.local.documents[g.doc].clone() } else { self.lib.defs.documents[g.doc].clone() };
            let map: HashMap<String, H> = bound.iter().map(|(p, h)| (p.name.clone(), *h)).collect();
            self.scopes.push(Scope { doc: gdoc.clone(), graph: g.element, interface: Interface::Functional(map), parent: Some(s), path: format!("{origin}/") });
            let gs = self.scopes.len() - 1;
            let mut outs = Vec::new();
            for o in &nd.outputs {
                let Some(oe) = gdoc.child(g.element, &o.name).filter(|x| gdoc.get(*x).category == "output") else {
                    return Err(self.error(&gdoc.get(g.element).pos, format!("nodegraph implementing `{}` has no output `{}`", nd.name, o.name)));
                };
                outs.push((o.name.clone(), self.resolve_connection(gs, oe, Some(&o.ty))?));
            }
            Ok(match outs.len() {
                1 => NodeResult::Single(outs[0].1),
                _ => NodeResult::Multi(outs),
            })
        }
    }

    fn port_default(&mut self, p: &PortDef, origin: &str) -> Result<H, Fail> {
        if let Some(g) = &p.defaultgeomprop {
            if let Some(&(_, _, name, default)) = APPLICATION_INPUTS.iter().find(|(_, alias, ..)| *alias == Some(g.as_str())) {
                let ty = application_type(default);
                return Ok(self.application_input(name, &ty, default, &p.pos));
            }
            let Some(gp) = GeomProp::from_name(g) else {
                return Err(self.error(&p.pos, format!("unknown defaultgeomprop `{g}`")));
            };
            let ty = gp.data_type();
            let h = self.add(ValueKind::Geometry(gp), ty.clone(), gp.name().to_string(), p.pos.clone());
            if ty != p.ty {
                return Err(self.error(&p.pos, format!("defaultgeomprop `{g}` is {ty}, input `{}` is {}", p.name, p.ty)));
            }
            return Ok(h);
        }
        let o = format!("{origin}.{}", p.name);
        match &p.value {
            Some(v) if p.ty != DataType::Filename => self.constant(&p.ty, v, &p.pos, &o),
            _ => self.zero(&p.ty, &p.pos, &o),
        }
    }

    /// A call of the nodedef's WGSL function.
    fn call(&mut self, nd: &NodeDef, bound: Vec<(&PortDef, H)>, origin: &str, pos: &SourcePos) -> Result<NodeResult, Fail> {
        let fname = NodeLibrary::function_name(&nd.name);
        if let Err(m) = self.lib.signature_fits(nd) {
            return Err(self.error(pos, m));
        }
        let lib: &'a NodeLibrary = self.lib;
        let sig = lib.wgsl.items[&fname].signature.as_ref().unwrap();
        let geometry = sig.params.first().is_some_and(|(_, t)| t == "mx_geometry");
        let closure = sig.params.get(usize::from(geometry)).is_some_and(|(_, t)| t == "mx_closure");
        let mut args = Vec::new();
        let mut missing_file = None;
        let mut weight_arg = None;
        for (p, h) in &bound {
            if p.name == "weight" && p.ty == DataType::Float {
                weight_arg = Some(args.len());
            }
            match (&p.ty, &p.enum_values) {
                (DataType::String, None) => continue,
                (DataType::String, Some(options)) => {
                    let v = self.graph.values[*h].clone();
                    let ValueKind::Constant(Literal::String(text)) = &v.kind else {
                        return Err(self.error(pos, format!("input `{}` must be a constant string", p.name)));
                    };
                    let Some(index) = options.iter().position(|o| o == text) else {
                        return Err(self.error(&v.pos, format!("value `{text}` of input `{}` is not one of {}", p.name, options.join(", "))));
                    };
                    args.push(self.add(ValueKind::Constant(Literal::Integer(index as i32)), DataType::Integer, format!("{origin}.{}", p.name), v.pos.clone()));
                }
                (DataType::Filename, _) => match self.graph.values[*h].kind {
                    ValueKind::Texture(_) => args.push(*h),
                    _ => missing_file = Some(p.name.clone()),
                },
                _ => args.push(*h),
            }
        }
        if let Some(input) = missing_file {
            // Unresolved file: the node returns its `default` input, as MaterialX does.
            let fallback = bound.iter().find(|(q, _)| q.name == "default" && nd.outputs.len() == 1 && q.ty == nd.outputs[0].ty);
            return match fallback {
                Some((_, d)) => Ok(NodeResult::Single(*d)),
                None => Err(self.error(pos, format!("input `{input}` names no readable file and `{}` has no `default` input", nd.name))),
            };
        }
        if let (Some(k), [out]) = (sig.identity_of, nd.outputs.as_slice()) {
            let k = k.wrapping_sub(usize::from(geometry) + usize::from(closure));
            if let Some(&a) = args.get(k) {
                if self.graph.values[a].ty == out.ty {
                    return Ok(NodeResult::Single(a));
                }
            }
        }
        if !geometry && !closure {
            if let Some(folded) = self.fold(&fname, nd, &args, origin, pos) {
                return Ok(folded);
            }
        }
        // A lobe whose weight is a constant at or below 0 that is then the empty BSDF
        // (closure_fold.rs): the empty BSDF, and the lobe leaves the kernel.
        if let (true, false, Some(w), [out]) = (closure, geometry, weight_arg, nd.outputs.as_slice()) {
            let dead = matches!(&self.graph.values[args[w]].kind, ValueKind::Constant(Literal::Floats(f)) if f.len() == 1 && f[0].partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater));
            // The weight's position among the function's parameters (the closure first).
            if dead && out.ty.is_closure() && crate::closure_fold::vanishes_at_zero_weight(self.lib, &fname, &sig.params, w + 1) {
                return self.zero(&out.ty, pos, origin).map(NodeResult::Single);
            }
        }
        let ty = nd.node_type();
        let h = self.add(ValueKind::Call { function: fname, args, geometry, closure }, ty, origin.to_string(), pos.clone());
        if nd.outputs.len() == 1 {
            return Ok(NodeResult::Single(h));
        }
        let outs = nd
            .outputs
            .iter()
            .map(|o| {
                let f = self.add(ValueKind::Field { base: h, field: o.name.clone() }, o.ty.clone(), format!("{origin}.{}", o.name), pos.clone());
                (o.name.clone(), f)
            })
            .collect();
        Ok(NodeResult::Multi(outs))
    }
}

impl GraphBuilder<'_> {
    /// Constant folding: when every argument is a constant, runs the library's own WGSL
    /// function through the naga IR interpreter and returns constants for its outputs.
    /// Anything the interpreter declines (NaN/Inf results, unsupported operations) stays a call.
    fn fold(&mut self, function: &str, nd: &NodeDef, args: &[H], origin: &str, pos: &SourcePos) -> Option<NodeResult> {
        let evaluator = self.lib.evaluator.as_ref()?;
        let mut consts = Vec::with_capacity(args.len());
        for &a in args {
            let v = &self.graph.values[a];
            let ValueKind::Constant(lit) = &v.kind else { return None };
            consts.push(Const::from_literal(&v.ty, lit)?);
        }
        let result = evaluator.eval(function, &consts)?;
        let literals: Vec<(String, DataType, Literal)> = match nd.outputs.as_slice() {
            [one] => vec![(one.name.clone(), one.ty.clone(), result.to_literal(&one.ty)?)],
            outs => outs
                .iter()
                .enumerate()
                .map(|(i, o)| Some((o.name.clone(), o.ty.clone(), result.field(i)?.to_literal(&o.ty)?)))
                .collect::<Option<Vec<_>>>()?,
        };
        let mut values: Vec<(String, H)> = literals
            .into_iter()
            .map(|(name, ty, lit)| {
                let h = self.add(ValueKind::Constant(lit), ty, origin.to_string(), pos.clone());
                (name, h)
            })
            .collect();
        Some(if values.len() == 1 { NodeResult::Single(values.pop().unwrap().1) } else { NodeResult::Multi(values) })
    }
}

/// Whether `path` lies inside one of `roots` (both resolved: `..` and links cannot leave a root).
/// Whether `path` lies inside one of `roots` once both are canonical (`..` and links resolved):
/// the path rule for files a document names.
/// Where MaterialX's own test documents, which name files from the repository root
/// (`resources/Images/…`), find a file named at `doc_file`: relative to each ancestor folder with
/// `resources/` removed. Each candidate still goes through the containment rule.
fn resources_fallback<'n>(name: &'n str, doc_file: &'n Path) -> impl Iterator<Item = PathBuf> + 'n {
    let dir = mtlx::file_access::folder_of(doc_file);
    name.strip_prefix("resources/").into_iter().flat_map(move |stripped| dir.ancestors().map(move |a| a.join(stripped)))
}

/// What makes two IR values one for hash-consing (with their type): the kind, floats compared
/// by their bits (so 0.0 and −0.0 stay apart).
#[derive(PartialEq, Eq, Hash)]
enum ConsKey {
    Boolean(bool),
    Integer(i32),
    Floats(Vec<u32>),
    String(String),
    Geometry(GeomProp),
    Input(usize),
    Texture(usize),
    Call { function: String, args: Vec<H>, geometry: bool, closure: bool },
    Field { base: H, field: String },
}

impl ConsKey {
    fn of(kind: &ValueKind) -> ConsKey {
        match kind {
            ValueKind::Constant(Literal::Boolean(b)) => ConsKey::Boolean(*b),
            ValueKind::Constant(Literal::Integer(i)) => ConsKey::Integer(*i),
            ValueKind::Constant(Literal::Floats(f)) => ConsKey::Floats(f.iter().map(|x| x.to_bits()).collect()),
            ValueKind::Constant(Literal::String(s)) => ConsKey::String(s.clone()),
            ValueKind::Geometry(g) => ConsKey::Geometry(*g),
            ValueKind::Input(i) => ConsKey::Input(*i),
            ValueKind::Texture(t) => ConsKey::Texture(*t),
            ValueKind::Call { function, args, geometry, closure } => ConsKey::Call { function: function.clone(), args: args.clone(), geometry: *geometry, closure: *closure },
            ValueKind::Field { base, field } => ConsKey::Field { base: *base, field: field.clone() },
        }
    }
}
