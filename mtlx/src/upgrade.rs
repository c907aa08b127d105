//! Version upgrades applied on read, as MaterialX's `Document::upgradeVersion`
//! (source/MaterialXCore/Version.cpp) does: a chain of steps 1.22 → 1.23 → … → 1.38 → 1.39,
//! each rewriting the element tree in place. After [`upgrade`] the root says `version="1.39"`.
//!
//! Elements the upgrade creates carry the source position of the element they replace or came
//! from. Where MaterialX's upgrade silently produces something that no longer means what the old
//! document meant (or cannot be built at all), a positioned warning or error names the element;
//! nothing here panics on malformed input.
//!
//! Deliberate differences from MaterialX (each makes the result more faithful, never less):
//! * the upstream type of a `channels` connection is read from the connected node's output,
//!   nodegraph output or interface input before MaterialX's guess from the channel letters;
//! * separate/combine connections name the separate node's outputs after the source type's
//!   channels (`outr`… for colours, `outx`… for vectors) whatever letters the swizzle used;
//! * a connection created by the upgrade replaces any value or other binding on that input;
//! * `backdrop` parameters become backdrop attributes (MaterialX never reaches that branch);
//! * a thin film without `thickness` passes its 1.38 default (550 nm) on, where MaterialX leaves
//!   `thinfilm_thickness` at its 1.39 default of 0 (no film);
//! * a `base` bound to an interface input or nodegraph output is layered like one bound to a
//!   node (MaterialX drops it);
//! * versions between steps (1.27–1.33) take the next step instead of stopping.

use crate::diagnostic::Diagnostic;
use crate::document::{parse_version, Document, ElementId};
use crate::position::SourcePos;

/// The version every document is upgraded to.
pub const LATEST_VERSION: (u32, u32) = (1, 39);

/// Upgrades `doc` in place to version 1.39.
pub fn upgrade(doc: &mut Document, diags: &mut Vec<Diagnostic>) {
    let root = doc.root();
    let root_pos = doc.get(root).pos.clone();
    let version = doc.get(root).attr("version").map(str::to_owned);
    let (major, mut minor) = match version.as_deref() {
        None => {
            // MaterialX reads a document without a version as the current version.
            doc.get_mut(root).set_attr("version", "1.39");
            return;
        }
        Some(v) => match parse_version(v) {
            Some(x) => x,
            None => {
                diags.push(Diagnostic::warning(
                    root_pos,
                    format!("unrecognised MaterialX version `{v}`; read as 1.39 without upgrades"),
                ));
                doc.get_mut(root).set_attr("version", "1.39");
                return;
            }
        },
    };
    if (major, minor) >= LATEST_VERSION {
        if (major, minor) > LATEST_VERSION {
            diags.push(Diagnostic::warning(
                root_pos,
                format!(
                    "document version {} is newer than 1.39, the newest this reader knows; read as is",
                    version.unwrap_or_default()
                ),
            ));
        }
        return;
    }
    if major == 0 || minor < 22 {
        diags.push(Diagnostic::warning(
            root_pos,
            format!("document version {} predates MaterialX 1.22; upgraded as if it were 1.22", version.unwrap_or_default()),
        ));
        minor = 22;
    }

    let mut up = Up { doc, diags, root };
    if minor == 22 {
        up.v1_22_to_1_23();
        minor = 23;
    }
    if minor == 23 {
        up.v1_23_to_1_24();
        minor = 24;
    }
    if minor == 24 {
        up.v1_24_to_1_25();
        minor = 25;
    }
    if minor == 25 {
        up.v1_25_to_1_26();
        minor = 26;
    }
    if (26..34).contains(&minor) {
        up.v1_26_to_1_34();
        minor = 34;
    }
    if minor == 34 {
        up.v1_34_to_1_35();
        minor = 35;
    }
    if minor == 35 {
        up.v1_35_to_1_36();
        minor = 36;
    }
    if minor == 36 {
        up.v1_36_to_1_37();
        minor = 37;
    }
    if minor == 37 {
        up.v1_37_to_1_38();
        minor = 38;
    }
    if minor == 38 {
        up.v1_38_to_1_39();
    }
    up.doc.get_mut(root).set_attr("version", "1.39");
}

/// Categories that are never nodes, even as children of the document or of a nodegraph.
const NON_NODE_CATEGORIES: &[&str] = &[
    "nodedef",
    "nodegraph",
    "opgraph",
    "implementation",
    "input",
    "output",
    "parameter",
    "token",
    "backdrop",
    "collection",
    "comment",
    "geominfo",
    "geomprop",
    "geompropdef",
    "look",
    "lookgroup",
    "materialassign",
    "member",
    "newline",
    "propertyset",
    "propertysetassign",
    "targetdef",
    "typedef",
    "unitdef",
    "unittypedef",
    "variant",
    "variantset",
    "variantassign",
    "visibility",
    "attributedef",
    "material",
    "shader",
    "xi:include",
    "include",
];

/// The attributes that bind an input to something other than its own value.
const BINDING_ATTRIBUTES: [&str; 4] = ["nodename", "nodegraph", "output", "interfacename"];

const COLOR_CHANNELS: [char; 4] = ['r', 'g', 'b', 'a'];
const VECTOR_CHANNELS: [char; 4] = ['x', 'y', 'z', 'w'];

fn channel_count(ty: &str) -> Option<usize> {
    match ty {
        "float" => Some(1),
        "vector2" => Some(2),
        "color3" | "vector3" => Some(3),
        "color4" | "vector4" => Some(4),
        _ => None,
    }
}

fn channel_index(c: char) -> Option<usize> {
    COLOR_CHANNELS.iter().position(|&x| x == c).or_else(|| VECTOR_CHANNELS.iter().position(|&x| x == c))
}

fn channel_constant(c: char) -> Option<&'static str> {
    match c {
        '0' => Some("0"),
        '1' => Some("1"),
        _ => None,
    }
}

/// Splits a vector value into its components (commas and/or spaces separate them).
fn split_value(v: &str) -> Vec<String> {
    v.split([',', ' ']).filter(|t| !t.is_empty()).map(str::to_owned).collect()
}

/// MaterialX's `incrementName`: bump a trailing number, or append "2".
fn increment_name(name: &str) -> String {
    let digits = name.chars().rev().take_while(|c| c.is_ascii_digit()).count();
    if digits > 0 {
        let (prefix, suffix) = name.split_at(name.len() - digits);
        if let Ok(n) = suffix.parse::<u64>() {
            return format!("{prefix}{}", n + 1);
        }
    }
    format!("{name}2")
}

struct Up<'a> {
    doc: &'a mut Document,
    diags: &'a mut Vec<Diagnostic>,
    root: ElementId,
}

// ---------------------------------------------------------------------------------------------
// Element helpers
// ---------------------------------------------------------------------------------------------
impl Up<'_> {
    fn attr(&self, id: ElementId, k: &str) -> Option<String> {
        self.doc.get(id).attr(k).map(str::to_owned)
    }

    /// The attribute, or "" when absent.
    fn attr_or_empty(&self, id: ElementId, k: &str) -> String {
        self.doc.get(id).attr(k).unwrap_or("").to_owned()
    }

    fn has(&self, id: ElementId, k: &str) -> bool {
        self.doc.get(id).attr(k).is_some()
    }

    fn set(&mut self, id: ElementId, k: &str, v: impl Into<String>) {
        self.doc.get_mut(id).set_attr(k, v);
    }

    fn unset(&mut self, id: ElementId, k: &str) {
        self.doc.get_mut(id).remove_attr(k);
    }

    /// Moves attribute `from` to `to` (appended, as MaterialX's set-then-remove does).
    fn move_attr(&mut self, id: ElementId, from: &str, to: &str) {
        if let Some(v) = self.doc.get_mut(id).remove_attr(from) {
            self.set(id, to, v);
        }
    }

    fn cat(&self, id: ElementId) -> &str {
        &self.doc.get(id).category
    }

    fn set_cat(&mut self, id: ElementId, c: &str) {
        self.doc.get_mut(id).category = c.to_owned();
    }

    fn name(&self, id: ElementId) -> String {
        self.doc.get(id).name().to_owned()
    }

    fn pos(&self, id: ElementId) -> SourcePos {
        self.doc.get(id).pos.clone()
    }

    fn parent(&self, id: ElementId) -> Option<ElementId> {
        self.doc.get(id).parent
    }

    fn children(&self, id: ElementId) -> Vec<ElementId> {
        self.doc.children(id).to_vec()
    }

    fn children_of(&self, id: ElementId, category: &str) -> Vec<ElementId> {
        self.doc.children_of(id, category).collect()
    }

    fn child(&self, id: ElementId, name: &str) -> Option<ElementId> {
        self.doc.child(id, name)
    }

    /// Every element reachable from the root, parents first (MaterialX's `traverseTree`).
    fn all(&self) -> Vec<ElementId> {
        self.doc.descendants(self.root)
    }

    /// Whether `id` is still in the tree (not removed, directly or through an ancestor).
    fn attached(&self, mut id: ElementId) -> bool {
        loop {
            if id == self.root {
                return true;
            }
            match self.parent(id) {
                Some(p) => id = p,
                None => return false,
            }
        }
    }

    fn warn(&mut self, id: ElementId, msg: impl Into<String>) {
        let pos = self.pos(id);
        self.diags.push(Diagnostic::warning(pos, msg));
    }

    fn error(&mut self, id: ElementId, msg: impl Into<String>) {
        let pos = self.pos(id);
        self.diags.push(Diagnostic::error(pos, msg));
    }

    fn is_graph(&self, id: ElementId) -> bool {
        id == self.root || matches!(self.cat(id), "nodegraph" | "opgraph")
    }

    /// A node: a child of the document or of a nodegraph whose category is not one of the
    /// structural element kinds.
    fn is_node(&self, id: ElementId) -> bool {
        match self.parent(id) {
            Some(p) => self.is_graph(p) && !NON_NODE_CATEGORIES.contains(&self.cat(id)),
            None => false,
        }
    }

    /// The nearest enclosing graph (document or nodegraph), not counting `id` itself.
    fn graph_of(&self, id: ElementId) -> ElementId {
        let mut cur = self.parent(id);
        while let Some(p) = cur {
            if self.is_graph(p) {
                return p;
            }
            cur = self.parent(p);
        }
        self.root
    }

    fn top_level(&self, category: &str) -> Vec<ElementId> {
        self.children_of(self.root, category)
    }

    fn input(&self, node: ElementId, name: &str) -> Option<ElementId> {
        self.doc.children_of(node, "input").find(|&c| self.doc.get(c).name() == name)
    }

    fn inputs(&self, node: ElementId) -> Vec<ElementId> {
        self.children_of(node, "input")
    }

    fn node_named(&self, graph: ElementId, name: &str) -> Option<ElementId> {
        self.doc.children(graph).iter().copied().find(|&c| self.doc.get(c).name() == name && self.is_node(c))
    }

    fn is_bound(&self, input: ElementId) -> bool {
        BINDING_ATTRIBUTES.iter().any(|k| self.has(input, k))
    }

    /// The node a port (input or output) is connected to, as MaterialX's
    /// `Input::getConnectedNode` resolves it: through a compound graph's interface input,
    /// through a nodegraph's output, or by `nodename` in the port's graph.
    fn connected_node(&self, port: ElementId) -> Option<ElementId> {
        self.connected_node_depth(port, 0)
    }

    fn connected_node_depth(&self, port: ElementId, depth: u32) -> Option<ElementId> {
        if depth > 16 {
            return None;
        }
        let parent = self.parent(port)?;
        let graph = self.graph_of(port);
        if let Some(iname) = self.attr(port, "interfacename") {
            if graph != self.root {
                if let Some(gi) = self.input(graph, &iname) {
                    if self.has(gi, "nodename") || self.has(gi, "nodegraph") {
                        if let Some(n) = self.connected_node_depth(gi, depth + 1) {
                            return Some(n);
                        }
                    }
                }
            }
        }
        if let Some(ng) = self.attr(port, "nodegraph").filter(|_| self.cat(port) == "input") {
            let g = self.find_nodegraph(graph, &ng)?;
            let out = match self.attr(port, "output") {
                Some(o) => self.doc.children_of(g, "output").find(|&c| self.doc.get(c).name() == o),
                None => self.doc.children_of(g, "output").next(),
            }?;
            return self.connected_node_depth(out, depth + 1);
        }
        let nodename = self.attr(port, "nodename")?;
        // The inputs of a compound nodegraph connect to nodes beside the graph.
        let scope = if self.cat(port) == "input" && self.is_graph(parent) && parent != self.root {
            self.graph_of(parent)
        } else {
            graph
        };
        self.node_named(scope, &nodename)
    }

    fn find_nodegraph(&self, scope: ElementId, name: &str) -> Option<ElementId> {
        let find = |s: ElementId| self.doc.children_of(s, "nodegraph").find(|&c| self.doc.get(c).name() == name);
        find(scope).or_else(|| find(self.root))
    }

    /// Inputs and outputs anywhere in the document connected to `node` by `nodename`.
    fn downstream_ports(&self, node: ElementId) -> Vec<ElementId> {
        let name = self.name(node);
        self.all()
            .into_iter()
            .filter(|&p| {
                matches!(self.cat(p), "input" | "output")
                    && self.doc.get(p).attr("nodename") == Some(name.as_str())
                    && self.connected_node(p) == Some(node)
            })
            .collect()
    }

    /// MaterialX's `createValidChildName`: invalid characters become `_`, then the name is
    /// incremented until no child of `parent` has it.
    fn valid_child_name(&self, parent: ElementId, base: &str) -> String {
        let mut name: String =
            base.chars().map(|c| if c.is_ascii_alphanumeric() || c == '_' || c == ':' { c } else { '_' }).collect();
        if name.is_empty() {
            name = "node1".into();
        }
        while self.child(parent, &name).is_some() {
            name = increment_name(&name);
        }
        name
    }

    fn add(&mut self, parent: ElementId, category: &str, attrs: &[(&str, &str)], pos: SourcePos) -> ElementId {
        let attributes = attrs.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect();
        self.doc.add_child(parent, category, attributes, pos)
    }

    fn insert(
        &mut self,
        parent: ElementId,
        index: usize,
        category: &str,
        attrs: &[(&str, &str)],
        pos: SourcePos,
    ) -> ElementId {
        let attributes = attrs.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect();
        self.doc.insert_child(parent, index, category, attributes, pos)
    }

    fn index_in_parent(&self, id: ElementId) -> Option<usize> {
        let p = self.parent(id)?;
        self.doc.children(p).iter().position(|&c| c == id)
    }

    /// Sets an input's value (and type), adding the input when missing.
    fn set_input_value(&mut self, node: ElementId, name: &str, ty: &str, value: &str, pos: SourcePos) -> ElementId {
        match self.input(node, name) {
            Some(i) => {
                self.set(i, "type", ty);
                self.set(i, "value", value);
                i
            }
            None => self.add(node, "input", &[("name", name), ("type", ty), ("value", value)], pos),
        }
    }

    /// Makes `input` a plain connection to `node` (any value or other binding is dropped).
    fn connect(&mut self, input: ElementId, node: ElementId, output: Option<&str>) {
        let node_name = self.name(node);
        for k in ["value", "nodegraph", "interfacename", "output"] {
            self.unset(input, k);
        }
        self.set(input, "nodename", node_name);
        if let Some(o) = output {
            self.set(input, "output", o);
        }
    }

    /// Copies the subtree under `src`'s children to `dst`, replacing `dst`'s attributes (but not
    /// its name) and children: MaterialX's `copyContentFrom`.
    fn copy_content(&mut self, dst: ElementId, src: ElementId) {
        let name = self.name(dst);
        let mut attrs = vec![("name".to_string(), name)];
        attrs.extend(self.doc.get(src).attributes.iter().filter(|(k, _)| k != "name").cloned());
        self.doc.get_mut(dst).attributes = attrs;
        for c in self.children(dst) {
            self.doc.remove(c);
        }
        for c in self.children(src) {
            self.clone_subtree(c, dst);
        }
    }

    /// A work list, not recursion: subtrees are as deep as the input makes them.
    fn clone_subtree(&mut self, src: ElementId, parent: ElementId) -> ElementId {
        let mut root = None;
        let mut work = vec![(src, parent)];
        while let Some((from, to)) = work.pop() {
            let e = self.doc.get(from).clone();
            let id = self.doc.add_child(to, e.category, e.attributes, e.pos);
            root.get_or_insert(id);
            work.extend(e.children.iter().rev().map(|&c| (c, id)));
        }
        root.expect("the work list starts with the subtree's root")
    }

    /// MaterialX's `copyInputWithBindings`: copies input `src_name` of `src_node` (value and
    /// connections) to input `dst_name` of `dst_node`, creating it when needed.
    fn copy_input(&mut self, src_node: ElementId, src_name: &str, dst_node: ElementId, dst_name: &str) -> Option<ElementId> {
        let src = self.input(src_node, src_name)?;
        let dst = match self.input(dst_node, dst_name) {
            Some(d) => d,
            None => {
                let ty = self.attr_or_empty(src, "type");
                let pos = self.pos(src);
                self.add(dst_node, "input", &[("name", dst_name), ("type", &ty)], pos)
            }
        };
        self.copy_content(dst, src);
        Some(dst)
    }

    /// The nodedef a legacy `<shaderref>` refers to, when this document defines it.
    fn shader_nodedef(&self, shaderref: ElementId) -> Option<ElementId> {
        if let Some(nd) = self.attr(shaderref, "nodedef") {
            return self.top_level("nodedef").into_iter().find(|&d| self.name(d) == nd);
        }
        let node = self.attr(shaderref, "node")?;
        let ty = self.attr_or_empty(shaderref, "type");
        let target = self.attr_or_empty(shaderref, "target");
        let version = self.attr_or_empty(shaderref, "version");
        self.top_level("nodedef").into_iter().find(|&d| {
            self.attr(d, "node").as_deref() == Some(node.as_str())
                && targets_match(&self.attr_or_empty(d, "target"), &target)
                && (self.attr_or_empty(d, "version") == version
                    || (version.is_empty() && self.attr(d, "isdefaultversion").as_deref() == Some("true")))
                && (ty.is_empty() || self.nodedef_type(d) == ty)
        })
    }

    /// A nodedef's output type: the type of its one output, "multioutput" for several, or its
    /// legacy `type` attribute.
    fn nodedef_type(&self, nd: ElementId) -> String {
        let outs = self.children_of(nd, "output");
        match outs.len() {
            0 => self.attr_or_empty(nd, "type"),
            1 => self.attr_or_empty(outs[0], "type"),
            _ => "multioutput".into(),
        }
    }
}

fn targets_match(a: &str, b: &str) -> bool {
    if a.is_empty() || b.is_empty() {
        return true;
    }
    let bs: Vec<&str> = b.split(',').map(str::trim).collect();
    a.split(',').map(str::trim).any(|t| bs.contains(&t))
}

// ---------------------------------------------------------------------------------------------
// 1.22 … 1.36
// ---------------------------------------------------------------------------------------------
impl Up<'_> {
    /// `type="vector"` became `vector3`.
    fn v1_22_to_1_23(&mut self) {
        for id in self.all() {
            if self.doc.get(id).attr("type") == Some("vector") {
                self.set(id, "type", "vector3");
            }
        }
    }

    /// `<shader shadername>` → `node`; `<assign>` → `<materialassign>`.
    fn v1_23_to_1_24(&mut self) {
        for id in self.all() {
            if self.cat(id) == "shader" {
                self.move_attr(id, "shadername", "node");
            }
            if self.cat(id) == "assign" {
                self.set_cat(id, "materialassign");
            }
        }
    }

    /// Input `graphname` → `opgraph`.
    fn v1_24_to_1_25(&mut self) {
        for id in self.all() {
            if self.cat(id) == "input" {
                self.move_attr(id, "graphname", "opgraph");
            }
        }
    }

    /// The `color` parameter of `constant` nodes became `value`.
    fn v1_25_to_1_26(&mut self) {
        for id in self.all() {
            if self.cat(id) == "constant" {
                if let Some(c) = self.child(id, "color") {
                    self.set(c, "name", "value");
                }
            }
        }
    }

    /// opgraph → nodegraph, shader → nodedef, opgraphnode parameters → connections, shaderref
    /// nodedef names, nodedef graph connections → bindinputs, geomattr → geomprop, udim sets.
    fn v1_26_to_1_34(&mut self) {
        for elem in self.all() {
            if !self.attached(elem) {
                continue;
            }
            for child in self.children(elem) {
                match self.cat(child) {
                    "opgraph" => self.set_cat(child, "nodegraph"),
                    "shader" => {
                        self.set_cat(child, "nodedef");
                        if self.has(child, "shadertype") {
                            self.set(child, "type", "surfaceshader");
                        }
                        if let Some(p) = self.attr(child, "shaderprogram") {
                            self.set(child, "node", p);
                        }
                    }
                    "shaderref" if self.has(child, "shadertype") => {
                        self.set(child, "type", "surfaceshader");
                        self.unset(child, "shadertype");
                    }
                    "parameter" if self.doc.get(child).attr("type") == Some("opgraphnode") => {
                        if self.is_node(elem) {
                            self.set_cat(child, "input");
                            let target = self.doc.get_mut(child).remove_attr("value").unwrap_or_default();
                            self.set(child, "nodename", target);
                            let ty = self
                                .connected_node(child)
                                .and_then(|n| self.attr(n, "type"))
                                .unwrap_or_else(|| "color3".into());
                            self.set(child, "type", ty);
                        } else if self.cat(elem) == "output" {
                            if self.name(child) == "in" {
                                let target = self.attr_or_empty(child, "value");
                                self.set(elem, "nodename", target);
                            }
                            self.doc.remove(child);
                        }
                    }
                    _ => {}
                }
            }
        }

        // Name the nodedef of shaderrefs that refer to a document-level shader by name.
        let materials = self.top_level("material");
        for &mat in &materials {
            for sr in self.children_of(mat, "shaderref") {
                if self.shader_nodedef(sr).is_none() {
                    let name = self.name(sr);
                    if let Some(nd) = self.top_level("nodedef").into_iter().find(|&d| self.name(d) == name) {
                        self.set(sr, "nodedef", name);
                        if let Some(node) = self.attr(nd, "node") {
                            self.set(sr, "node", node);
                        }
                    }
                }
            }
        }

        // Move graph connections from nodedef inputs to bindinputs on the shaderrefs.
        for nd in self.top_level("nodedef") {
            for input in self.inputs(nd) {
                let (Some(graph), Some(output)) = (self.attr(input, "opgraph"), self.attr(input, "graphoutput")) else {
                    continue;
                };
                let name = self.name(input);
                let ty = self.attr_or_empty(input, "type");
                for &mat in &materials {
                    for sr in self.children_of(mat, "shaderref") {
                        if self.shader_nodedef(sr) == Some(nd) && self.child(sr, &name).is_none() {
                            let pos = self.pos(input);
                            self.add(
                                sr,
                                "bindinput",
                                &[("name", &name), ("type", &ty), ("nodegraph", &graph), ("output", &output)],
                                pos,
                            );
                        }
                    }
                }
                self.unset(input, "opgraph");
                self.unset(input, "graphoutput");
            }
        }

        // geomattr → geomprop, and udim values gathered into a udimset.
        let geominfos = self.top_level("geominfo");
        for &gi in &geominfos {
            for ga in self.children_of(gi, "geomattr") {
                self.set_cat(ga, "geomprop");
            }
        }
        let props = |up: &Self, name: &str| -> Vec<ElementId> {
            geominfos
                .iter()
                .flat_map(|&gi| up.children_of(gi, "geomprop"))
                .filter(|&p| up.name(p) == name)
                .collect()
        };
        let udims = props(self, "udim");
        if !udims.is_empty() && props(self, "udimset").is_empty() {
            let mut set: Vec<String> = udims.iter().map(|&p| self.attr_or_empty(p, "value")).collect();
            set.sort();
            set.dedup();
            let pos = self.pos(udims[0]);
            let name = self.valid_child_name(self.root, "geominfo1");
            let root = self.root;
            let gi = self.add(root, "geominfo", &[("name", &name), ("geom", "/")], pos.clone());
            self.add(gi, "geomprop", &[("name", "udimset"), ("type", "stringarray"), ("value", &set.join(", "))], pos);
        }
    }

    /// `matrix` → `matrix44`, `default` → `value`, materialassign names its material.
    fn v1_34_to_1_35(&mut self) {
        for id in self.all() {
            if self.doc.get(id).attr("type") == Some("matrix") {
                self.set(id, "type", "matrix44");
            }
            if self.has(id, "default") && !self.has(id, "value") {
                self.move_attr(id, "default", "value");
            }
            if self.cat(id) == "materialassign" {
                let name = self.name(id);
                self.set(id, "material", name);
            }
        }
    }

    /// Geomname `*` → `/`, `%UDIM`/`%UVTILE` tokens, material overrides → bindings,
    /// materialinherit/lookinherit → `inherit` attributes.
    fn v1_35_to_1_36(&mut self) {
        for elem in self.all() {
            if !self.attached(elem) {
                continue;
            }
            let ty = self.attr_or_empty(elem, "type");
            if ty == "geomname" && self.doc.get(elem).attr("value") == Some("*") {
                self.set(elem, "value", "/");
            }
            if ty == "filename" {
                if let Some(v) = self.attr(elem, "value") {
                    self.set(elem, "value", v.replace("%UDIM", "<UDIM>").replace("%UVTILE", "<UVTILE>"));
                }
            }
            let elem_cat = self.cat(elem).to_owned();
            for child in self.children(elem) {
                match (elem_cat.as_str(), self.cat(child)) {
                    ("material", "override") => {
                        let public = self.name(child);
                        let value = self.attr_or_empty(child, "value");
                        let mut used = false;
                        for sr in self.children_of(elem, "shaderref") {
                            let Some(nd) = self.shader_nodedef(sr) else { continue };
                            for ve in self.children(nd) {
                                let ve_cat = self.cat(ve).to_owned();
                                if !matches!(ve_cat.as_str(), "input" | "parameter")
                                    || self.doc.get(ve).attr("publicname") != Some(public.as_str())
                                {
                                    continue;
                                }
                                let ve_name = self.name(ve);
                                used = true;
                                if self.child(sr, &ve_name).is_some() {
                                    continue;
                                }
                                let category = if ve_cat == "parameter" { "bindparam" } else { "bindinput" };
                                let ve_type = self.attr_or_empty(ve, "type");
                                let pos = self.pos(child);
                                self.add(sr, category, &[("name", &ve_name), ("type", &ve_type), ("value", &value)], pos);
                            }
                        }
                        if !used {
                            self.warn(
                                child,
                                format!("override `{public}` matches no publicname of the material's shader; dropped"),
                            );
                        }
                        self.doc.remove(child);
                    }
                    ("material", "materialinherit") => {
                        let m = self.attr_or_empty(child, "material");
                        self.set(elem, "inherit", m);
                        self.doc.remove(child);
                    }
                    ("look", "lookinherit") => {
                        let l = self.attr_or_empty(child, "look");
                        self.set(elem, "inherit", l);
                        self.doc.remove(child);
                    }
                    _ => {}
                }
            }
        }
    }

    /// Nodedef types → outputs, legacy shader nodedefs removed, geomattr → geomprop, and the
    /// node renames: invert(matrix) → invertmatrix, rotate → rotate2d/3d, compare →
    /// ifgreatereq, transform* → transformmatrix, combine/separate → numbered.
    fn v1_36_to_1_37(&mut self) {
        for nd in self.top_level("nodedef") {
            let Some(ty) = self.attr(nd, "type") else { continue };
            let mut out = None;
            if !ty.is_empty() && ty != "multioutput" {
                out = self.doc.children_of(nd, "output").find(|&o| self.doc.get(o).name() == "out");
                if out.is_none() {
                    let pos = self.pos(nd);
                    out = Some(self.add(nd, "output", &[("name", "out"), ("type", &ty)], pos));
                }
            }
            self.unset(nd, "type");
            if let Some(di) = self.doc.get_mut(nd).remove_attr("defaultinput") {
                if let (Some(o), false) = (out, di.is_empty()) {
                    self.set(o, "defaultinput", di);
                }
            }
        }

        // Legacy shader nodedefs go; shaderrefs stop naming them.
        for nd in self.top_level("nodedef") {
            if !self.has(nd, "shadertype") {
                continue;
            }
            let name = self.name(nd);
            let mut users = Vec::new();
            for mat in self.top_level("material") {
                for sr in self.children_of(mat, "shaderref") {
                    if self.doc.get(sr).attr("nodedef") == Some(name.as_str()) {
                        self.unset(sr, "nodedef");
                        users.push(sr);
                    }
                }
            }
            // The legacy declaration's defaults die with it: the shader node made from each
            // shaderref takes its defaults from the library's nodedef instead.
            for input in self.children(nd) {
                if !matches!(self.cat(input), "input" | "parameter") || !self.has(input, "value") {
                    continue;
                }
                let input_name = self.name(input);
                if users.iter().any(|&sr| self.child(sr, &input_name).is_none()) {
                    let value = self.attr_or_empty(input, "value");
                    self.warn(
                        input,
                        format!(
                            "the default `{input_name}` = \"{value}\" of legacy shader `{name}` is dropped with its declaration; \
                             the shader's library definition supplies the default instead"
                        ),
                    );
                }
            }
            self.doc.remove(nd);
        }

        for gi in self.top_level("geominfo") {
            for ga in self.children_of(gi, "geomattr") {
                self.set_cat(ga, "geomprop");
            }
        }

        for id in self.all() {
            if self.cat(id) == "backdrop" {
                // Legacy backdrop parameters become the backdrop's attributes.
                for p in self.children_of(id, "parameter") {
                    if let Some(v) = self.attr(p, "value") {
                        let k = self.name(p);
                        if is_element_name(&k) {
                            self.set(id, &k, v);
                        } else {
                            self.error(p, format!("backdrop parameter `{k}` cannot become an attribute: not a valid attribute name; dropped"));
                        }
                    }
                    self.doc.remove(p);
                }
                continue;
            }
            if !self.is_node(id) {
                continue;
            }
            let ty = self.attr_or_empty(id, "type");
            match self.cat(id) {
                "geomattrvalue" => {
                    self.set_cat(id, "geompropvalue");
                    self.move_attr(id, "attrname", "geomprop");
                }
                "invert" if ty == "matrix33" || ty == "matrix44" => self.set_cat(id, "invertmatrix"),
                "rotate" => self.set_cat(id, if ty == "vector2" { "rotate2d" } else { "rotate3d" }),
                "compare" => {
                    self.set_cat(id, "ifgreatereq");
                    if let Some(i) = self.input(id, "intest") {
                        self.set(i, "name", "value1");
                    }
                    if let Some(c) = self.child(id, "cutoff") {
                        self.set_cat(c, "input");
                        self.set(c, "name", "value2");
                    }
                    if let (Some(a), Some(b)) = (self.input(id, "in1"), self.input(id, "in2")) {
                        self.set(a, "name", "in2");
                        self.set(b, "name", "in1");
                    }
                }
                "transformpoint" | "transformvector" | "transformnormal"
                    if self.child(id, "fromspace").is_none() && self.child(id, "tospace").is_none() =>
                {
                    self.set_cat(id, "transformmatrix");
                }
                "combine" => {
                    let c = if self.child(id, "in4").is_some() {
                        "combine4"
                    } else if self.child(id, "in3").is_some() {
                        "combine3"
                    } else {
                        "combine2"
                    };
                    self.set_cat(id, c);
                }
                "separate" => {
                    if let Some(i) = self.input(id, "in") {
                        let c = match self.attr_or_empty(i, "type").as_str() {
                            "vector4" | "color4" => "separate4",
                            "vector3" | "color3" => "separate3",
                            _ => "separate2",
                        };
                        self.set_cat(id, c);
                    }
                }
                _ => {}
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// 1.37 → 1.38
// ---------------------------------------------------------------------------------------------
impl Up<'_> {
    fn v1_37_to_1_38(&mut self) {
        self.color2_to_vector2();
        self.materials_to_nodes();
        self.bsdf_nodes_1_38();
        self.nodegraph_names_1_38();

        // Parameters become inputs; on nodedefs they are marked uniform.
        for elem in self.all() {
            let c = self.cat(elem).to_owned();
            let interface = self.is_node(elem) || matches!(c.as_str(), "nodedef" | "nodegraph" | "implementation");
            if !interface {
                continue;
            }
            for p in self.children_of(elem, "parameter") {
                self.set_cat(p, "input");
                if c == "nodedef" {
                    self.set(p, "uniform", "true");
                }
            }
        }
    }

    /// `color2` → `vector2`; channel letters r/a of downstream `channels` and `outr`/`outa`
    /// outputs become x/y.
    fn color2_to_vector2(&mut self) {
        let rename = |s: &str| s.replace('r', "x").replace('a', "y");
        for id in self.all() {
            if self.doc.get(id).attr("type") != Some("color2") {
                continue;
            }
            self.set(id, "type", "vector2");
            let node = if self.is_node(id) {
                id
            } else {
                match self.parent(id) {
                    Some(p) if self.is_node(p) => p,
                    _ => continue,
                }
            };
            for port in self.downstream_ports(node) {
                if let Some(ch) = self.attr(port, "channels") {
                    self.set(port, "channels", rename(&ch));
                }
                if let Some(o) = self.attr(port, "output") {
                    if o == "outr" || o == "outa" {
                        self.set(port, "output", rename(&o));
                    }
                }
            }
            if let Some(ch) = self.child(node, "channels") {
                if let Some(v) = self.attr(ch, "value") {
                    self.set(ch, "value", rename(&v));
                }
            }
        }
    }

    /// `<material>` elements with `<shaderref>`s become shader nodes plus a surfacematerial (or
    /// volumematerial) node of the material's name.
    fn materials_to_nodes(&mut self) {
        let root = self.root;
        for mat in self.top_level("material") {
            let mat_name = self.name(mat);
            let mut shader_inputs: Vec<(String, String)> = Vec::new(); // (shader type, node name)
            let mut new_nodes = Vec::new();
            let shaderrefs = self.children_of(mat, "shaderref");
            let had_shaderrefs = !shaderrefs.is_empty();
            for sr in shaderrefs {
                let nd = self.shader_nodedef(sr);
                let (ty, category) = match nd {
                    Some(nd) => (self.nodedef_type(nd), self.attr_or_empty(nd, "node")),
                    None => (
                        self.attr(sr, "type").filter(|t| !t.is_empty()).unwrap_or_else(|| "surfaceshader".into()),
                        self.attr_or_empty(sr, "node"),
                    ),
                };
                if category.is_empty() {
                    self.error(
                        sr,
                        format!(
                            "shaderref `{}` of material `{mat_name}` names no shader node (no `node` attribute and no nodedef in this document); dropped",
                            self.name(sr)
                        ),
                    );
                    continue;
                }
                if !is_element_name(&category) {
                    self.error(sr, format!("shaderref `{}` of material `{mat_name}` names the shader node `{category}`, which is not a valid element name; dropped", self.name(sr)));
                    continue;
                }
                let name = self.valid_child_name(root, &self.name(sr));
                let pos = self.pos(sr);
                let node = self.add(root, &category, &[("name", &name), ("type", &ty)], pos);
                for k in ["nodedef", "target", "version"] {
                    if let Some(v) = self.attr(sr, k).filter(|v| !v.is_empty()) {
                        self.set(node, k, v);
                    }
                }
                for child in self.children(sr) {
                    let c = match self.cat(child) {
                        "bindinput" | "bindparam" => "input",
                        "bindtoken" => "token",
                        other => {
                            let other = other.to_owned();
                            self.warn(child, format!("<{other}> in shaderref `{}` has no 1.38 equivalent; dropped", self.name(sr)));
                            continue;
                        }
                    };
                    let new_child = self.clone_subtree(child, node);
                    self.set_cat(new_child, c);
                }
                new_nodes.push(node);
                if shader_inputs.iter().any(|(t, _)| *t == ty) {
                    self.warn(
                        sr,
                        format!(
                            "material `{mat_name}` has a second {ty} shaderref `{}`; the surfacematerial connects only the first",
                            self.name(sr)
                        ),
                    );
                } else {
                    shader_inputs.push((ty, name));
                }
            }
            let pos = self.pos(mat);
            let mat_attrs: Vec<(String, String)> =
                self.doc.get(mat).attributes.iter().filter(|(k, _)| k != "name").cloned().collect();
            self.doc.remove(mat);
            if shader_inputs.is_empty() {
                if had_shaderrefs {
                    // Each unusable shaderref was reported already.
                    continue;
                }
                self.diags.push(Diagnostic::warning(
                    pos,
                    format!("material `{mat_name}` has no shaderref; removed (materials are nodes since 1.38)"),
                ));
                continue;
            }
            let category = if shader_inputs[0].0 == "volumeshader" { "volumematerial" } else { "surfacematerial" };
            let m = self.add(root, category, &[("name", &mat_name), ("type", "material")], pos.clone());
            for (ty, node) in &shader_inputs {
                self.add(m, "input", &[("name", ty), ("type", ty), ("nodename", node)], pos.clone());
            }
            for (k, v) in mat_attrs {
                if !self.has(m, &k) {
                    self.set(m, &k, v);
                }
            }
        }
    }

    /// The BSDF renames of 1.38 (`*_brdf`/`*_btdf` → `*_bsdf`), nested `base` inputs → `layer`
    /// nodes, artistic conductor inputs → an `artistic_ior` node, atan2 input order, rotate3d
    /// axis parameter, and color3 outputs of artistic_ior.
    fn bsdf_nodes_1_38(&mut self) {
        let mut artistic_connections: Vec<(ElementId, &'static str)> = Vec::new();
        for node in self.all() {
            if !self.is_node(node) || !self.attached(node) {
                continue;
            }
            let category = self.cat(node).to_owned();
            match category.as_str() {
                "atan2" => {
                    let (a, b) = (self.input(node, "in1"), self.input(node, "in2"));
                    if let Some(a) = a {
                        self.set(a, "name", "in2");
                    }
                    if let Some(b) = b {
                        self.set(b, "name", "in1");
                    }
                }
                "rotate3d" => {
                    if let Some(axis) = self.child(node, "axis") {
                        self.set_cat(axis, "input");
                    }
                }
                "dielectric_brdf" | "generalized_schlick_brdf" | "sheen_brdf" | "thin_film_brdf" => {
                    let new = category.replace("_brdf", "_bsdf");
                    self.set_cat(node, &new);
                    self.layer_from_base(node);
                }
                "dielectric_btdf" => {
                    self.set_cat(node, "dielectric_bsdf");
                    if let Some(i) = self.input(node, "interior") {
                        self.doc.remove(i);
                    }
                    let pos = self.pos(node);
                    self.set_input_value(node, "scatter_mode", "string", "T", pos);
                }
                "conductor_brdf" => self.conductor_1_38(node),
                "diffuse_brdf" => self.set_cat(node, "oren_nayar_diffuse_bsdf"),
                "burley_diffuse_brdf" => self.set_cat(node, "burley_diffuse_bsdf"),
                "diffuse_btdf" => self.set_cat(node, "translucent_bsdf"),
                "subsurface_brdf" => self.set_cat(node, "subsurface_bsdf"),
                "artistic_ior" => {
                    for o in self.children_of(node, "output") {
                        if matches!(self.doc.get(o).name(), "ior" | "extinction") {
                            self.set(o, "type", "color3");
                        }
                    }
                }
                _ => {}
            }
            // Vector3 connections to artistic_ior outputs (color3 since 1.38) need a convert.
            for input in self.inputs(node) {
                if self.doc.get(input).attr("type") != Some("vector3") {
                    continue;
                }
                let which = match self.doc.get(input).attr("output") {
                    Some("ior") => "ior",
                    Some("extinction") => "extinction",
                    _ => continue,
                };
                if self.connected_node(input).is_some_and(|n| self.cat(n) == "artistic_ior") {
                    artistic_connections.push((input, which));
                }
            }
        }
        for (input, which) in artistic_connections {
            let Some(artistic) = self.connected_node(input) else { continue };
            let Some(node) = self.parent(input) else { continue };
            let graph = self.graph_of(node);
            let name = format!("{}__convert_{which}", self.name(node));
            let artistic_name = self.name(artistic);
            let pos = self.pos(input);
            let convert = self.add(graph, "convert", &[("name", &name), ("type", "vector3")], pos.clone());
            self.add(
                convert,
                "input",
                &[("name", "in"), ("type", "color3"), ("nodename", &artistic_name), ("output", which)],
                pos,
            );
            self.set(input, "nodename", name);
            self.unset(input, "output");
        }
    }

    /// A BSDF with a connected `base` input becomes `layer(top = the BSDF, base = base)`; the
    /// layer takes the BSDF's name so downstream connections need no change.
    fn layer_from_base(&mut self, node: ElementId) {
        let Some(base) = self.input(node, "base") else { return };
        // MaterialX layers only a base connected to a node; a base bound to an interface input
        // or a nodegraph output is layered the same way here instead of being dropped.
        if self.is_bound(base) {
            let Some(graph) = self.parent(node) else { return };
            let old = self.name(node);
            let top_name = self.valid_child_name(graph, &format!("{old}__layer_top"));
            self.set(node, "name", top_name.as_str());
            let pos = self.pos(node);
            let layer = self.add(graph, "layer", &[("name", &old), ("type", "BSDF")], pos.clone());
            self.add(layer, "input", &[("name", "top"), ("type", "BSDF"), ("nodename", &top_name)], pos.clone());
            let layer_base = self.add(layer, "input", &[("name", "base"), ("type", "BSDF")], pos);
            self.copy_content(layer_base, base);
            self.unset(layer_base, "value");
        }
        self.doc.remove(base);
    }

    /// conductor_brdf (artistic reflectivity/edge_color) → conductor_bsdf (ior/extinction) fed
    /// by a new artistic_ior node.
    fn conductor_1_38(&mut self, node: ElementId) {
        self.set_cat(node, "conductor_bsdf");
        let Some(graph) = self.parent(node) else { return };
        let name = self.name(node);
        let ai_name = format!("{name}__artistic_ior");
        let pos = self.pos(node);
        let ai = self.add(graph, "artistic_ior", &[("name", &ai_name), ("type", "multioutput")], pos.clone());
        self.add(ai, "output", &[("name", "ior"), ("type", "color3")], pos.clone());
        self.add(ai, "output", &[("name", "extinction"), ("type", "color3")], pos.clone());
        self.copy_input(node, "reflectivity", ai, "reflectivity");
        self.copy_input(node, "edge_color", ai, "edge_color");
        for k in ["reflectivity", "edge_color"] {
            if let Some(i) = self.input(node, k) {
                self.doc.remove(i);
            }
        }
        self.add(node, "input", &[("name", "ior"), ("type", "color3"), ("nodename", &ai_name), ("output", "ior")], pos.clone());
        self.add(
            node,
            "input",
            &[("name", "extinction"), ("type", "color3"), ("nodename", &ai_name), ("output", "extinction")],
            pos,
        );
    }

    /// Nodegraphs lose any `version`, and nodes named like an interface input are renamed.
    fn nodegraph_names_1_38(&mut self) {
        for ng in self.top_level("nodegraph") {
            self.unset(ng, "version");
            let mut interface_names: Vec<String> = Vec::new();
            for n in self.children(ng) {
                if !self.is_node(n) {
                    continue;
                }
                for c in self.children(n) {
                    if let Some(i) = self.attr(c, "interfacename").filter(|i| !i.is_empty()) {
                        if !interface_names.contains(&i) {
                            interface_names.push(i);
                        }
                    }
                }
            }
            for iname in interface_names {
                let Some(node) = self.node_named(ng, &iname) else { continue };
                let new_name = self.valid_child_name(ng, &iname);
                for port in self.downstream_ports(node) {
                    if self.doc.get(port).attr("nodename") == Some(iname.as_str()) {
                        self.set(port, "nodename", new_name.as_str());
                    }
                }
                self.set(node, "name", new_name);
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// 1.38 → 1.39
// ---------------------------------------------------------------------------------------------
impl Up<'_> {
    fn v1_38_to_1_39(&mut self) {
        self.channels_to_swizzles();

        // An input of a node may carry one binding only: a connection wins over a value.
        for id in self.all() {
            if self.cat(id) == "input" && self.parent(id).is_some_and(|p| self.is_node(p)) && self.has(id, "value") && self.is_bound(id)
            {
                self.unset(id, "value");
            }
        }

        let mut unused = Vec::new();
        for node in self.all() {
            if !self.is_node(node) || !self.attached(node) {
                continue;
            }
            match self.cat(node) {
                "layer" => self.thin_film_layer(node, &mut unused),
                "subsurface_bsdf" => self.subsurface_radius(node),
                "switch" => self.switch_which(node),
                "swizzle" => self.swizzle(node),
                "atan2" => {
                    if let Some(i) = self.input(node, "in1") {
                        self.set(i, "name", "iny");
                    }
                    if let Some(i) = self.input(node, "in2") {
                        self.set(i, "name", "inx");
                    }
                }
                "normalmap" => self.normalmap(node),
                _ => {}
            }
        }
        for n in unused {
            self.doc.remove(n);
        }

        for node in self.all() {
            if self.is_node(node) && self.cat(node) == "thin_film_bsdf" {
                self.warn(
                    node,
                    format!(
                        "thin_film_bsdf `{}` is not the top of a layer; MaterialX 1.39 has no thin_film_bsdf node \
                         (thin films are the thinfilm_thickness/thinfilm_ior inputs of the BSDFs below them)",
                        self.name(node)
                    ),
                );
            }
        }
    }

    /// Each port with a `channels` attribute gets a swizzle node between it and its source;
    /// the swizzles are then rewritten like authored ones.
    fn channels_to_swizzles(&mut self) {
        for port in self.all() {
            if !matches!(self.cat(port), "input" | "output") {
                continue;
            }
            let Some(channels) = self.attr(port, "channels").filter(|c| !c.is_empty()) else { continue };
            let Some(parent) = self.parent(port) else { continue };
            if !self.is_node(parent) && !self.is_graph(parent) {
                let (port_name, parent_cat) = (self.name(port), self.cat(parent).to_owned());
                self.warn(
                    port,
                    format!("`channels` on `{port_name}` of a <{parent_cat}> selects nothing (only node inputs and graph outputs connect); dropped"),
                );
                self.unset(port, "channels");
                continue;
            }
            let port_type = self.attr_or_empty(port, "type");
            let upstream = match self.upstream_type(port) {
                Some(t) => t,
                None => {
                    let guess = match channels.as_str() {
                        "xx" | "xxx" | "xxxx" => "float",
                        "xyz" | "x" | "y" | "z" => "vector3",
                        "rgba" | "a" => "color4",
                        _ if port_type == "color3" => "color4",
                        _ => "color3",
                    };
                    self.warn(
                        port,
                        format!(
                            "the type upstream of `channels=\"{channels}\"` on `{}` is unknown here; assumed {guess}",
                            self.name(port)
                        ),
                    );
                    guess.to_string()
                }
            };
            if upstream == "float" && port_type == "float" {
                self.unset(port, "channels");
                continue;
            }
            let graph = self.graph_of(port);
            let anchor = if self.parent(parent) == Some(graph) { parent } else { port };
            let index = self.index_in_parent(anchor).unwrap_or(usize::MAX);
            let name = self.valid_child_name(graph, "swizzle");
            let pos = self.pos(port);
            let swizzle = self.insert(graph, index, "swizzle", &[("name", &name), ("type", &port_type)], pos.clone());
            let input = self.add(swizzle, "input", &[("name", "in")], pos.clone());
            self.copy_content(input, port);
            self.unset(input, "channels");
            if self.cat(port) == "output" {
                // An output connects by nodename in its own graph.
                self.unset(input, "nodegraph");
            }
            self.set(input, "type", upstream);
            self.add(swizzle, "input", &[("name", "channels"), ("type", "string"), ("value", &channels)], pos);
            self.unset(port, "channels");
            self.connect(port, swizzle, None);
        }
    }

    /// The type a port receives from its connection, when this document says.
    fn upstream_type(&self, port: ElementId) -> Option<String> {
        let non_empty = |t: Option<String>| t.filter(|t| !t.is_empty() && t != "multioutput");
        if let Some(ng) = self.attr(port, "nodegraph").filter(|_| self.cat(port) == "input") {
            let g = self.find_nodegraph(self.graph_of(port), &ng)?;
            let out = match self.attr(port, "output") {
                Some(o) => self.doc.children_of(g, "output").find(|&c| self.doc.get(c).name() == o),
                None => self.doc.children_of(g, "output").next(),
            }?;
            return non_empty(self.attr(out, "type"));
        }
        if self.has(port, "nodename") {
            let node = self.connected_node(port)?;
            if let Some(t) = non_empty(self.attr(node, "type")) {
                return Some(t);
            }
            if matches!(self.cat(node), "separate2" | "separate3" | "separate4") {
                return Some("float".into());
            }
            let o = self.attr(port, "output")?;
            let out = self.doc.children_of(node, "output").find(|&c| self.doc.get(c).name() == o)?;
            return non_empty(self.attr(out, "type"));
        }
        if let Some(iname) = self.attr(port, "interfacename") {
            let graph = self.graph_of(port);
            if graph == self.root {
                return None;
            }
            if let Some(i) = self.input(graph, &iname) {
                return non_empty(self.attr(i, "type"));
            }
            let nd_name = self.attr(graph, "nodedef")?;
            let nd = self.top_level("nodedef").into_iter().find(|&d| self.name(d) == nd_name)?;
            let i = self.input(nd, &iname)?;
            return non_empty(self.attr(i, "type"));
        }
        None
    }

    /// `layer(top = thin_film_bsdf, base)` → the film's thickness and ior move onto the
    /// dielectric/conductor/generalized_schlick BSDFs upstream of the layer, and the layer is
    /// bypassed.
    fn thin_film_layer(&mut self, layer: ElementId, unused: &mut Vec<ElementId>) {
        let top = self.input(layer, "top").and_then(|i| self.connected_node(i));
        let base = self.input(layer, "base").and_then(|i| self.connected_node(i));
        let (Some(top), Some(base)) = (top, base) else { return };
        if self.cat(top) != "thin_film_bsdf" {
            return;
        }
        let film_scope = self.graph_of(top);
        let film_bound = ["thickness", "ior"].iter().any(|k| self.input(top, k).is_some_and(|i| self.is_bound(i)));
        for up in self.upstream_nodes(layer) {
            if !matches!(self.cat(up), "dielectric_bsdf" | "conductor_bsdf" | "generalized_schlick_bsdf") {
                continue;
            }
            if self.input(up, "scatter_mode").and_then(|i| self.attr(i, "value")).as_deref() == Some("T") {
                continue;
            }
            if film_bound && self.graph_of(up) != film_scope {
                self.warn(
                    up,
                    format!(
                        "thin film `{}` is connected in another graph than `{}`; its connections were copied unchanged",
                        self.name(top),
                        self.name(up)
                    ),
                );
            }
            if self.copy_input(top, "thickness", up, "thinfilm_thickness").is_none() {
                // 1.38's thin_film_bsdf defaulted to 550 nm; 1.39's thinfilm_thickness defaults
                // to 0 (no film), so the old default is written out.
                let pos = self.pos(top);
                self.set_input_value(up, "thinfilm_thickness", "float", "550", pos);
            }
            self.copy_input(top, "ior", up, "thinfilm_ior");
        }
        let base_name = self.name(base);
        for port in self.downstream_ports(layer) {
            self.set(port, "nodename", base_name.as_str());
        }
        let other_uses: Vec<ElementId> =
            self.downstream_ports(top).into_iter().filter(|&p| self.parent(p) != Some(layer)).collect();
        if !other_uses.is_empty() {
            self.warn(
                top,
                format!(
                    "thin_film_bsdf `{}` is used outside layer `{}`; it is removed with the layer, leaving those connections dangling",
                    self.name(top),
                    self.name(layer)
                ),
            );
        }
        unused.push(layer);
        unused.push(top);
    }

    /// Every node upstream of `start` (MaterialX's `traverseGraph`), each once.
    fn upstream_nodes(&self, start: ElementId) -> Vec<ElementId> {
        let mut seen = vec![start];
        let mut stack = vec![start];
        let mut out = Vec::new();
        while let Some(n) = stack.pop() {
            for i in self.inputs(n) {
                if let Some(u) = self.connected_node(i) {
                    if !seen.contains(&u) {
                        seen.push(u);
                        out.push(u);
                        stack.push(u);
                    }
                }
            }
        }
        out
    }

    /// subsurface_bsdf's `radius` became color3: a vector3 radius goes through a convert node.
    fn subsurface_radius(&mut self, node: ElementId) {
        let Some(radius) = self.input(node, "radius") else { return };
        if self.doc.get(radius).attr("type") != Some("vector3") {
            return;
        }
        let graph = self.graph_of(node);
        let name = self.valid_child_name(graph, "convert");
        let pos = self.pos(radius);
        let convert = self.add(graph, "convert", &[("name", &name), ("type", "color3")], pos);
        self.copy_input(node, "radius", convert, "in");
        self.connect(radius, convert, None);
        self.set(radius, "type", "color3");
    }

    /// switch went from 5 to 10 inputs: a constant `which` ≥ 5 (out of range, selecting in1)
    /// becomes 0.
    fn switch_which(&mut self, node: ElementId) {
        let Some(which) = self.input(node, "which") else { return };
        if self.is_bound(which) {
            if (6..=10).all(|k| self.input(node, &format!("in{k}")).is_none()) {
                self.warn(
                    which,
                    format!(
                        "`which` of switch `{}` is connected: where it reaches 5 or more, 1.38 fell back to in1 while \
                         1.39 selects in6..in10 (unset here)",
                        self.name(node)
                    ),
                );
            }
            return;
        }
        let ty = self.attr_or_empty(which, "type");
        let Some(v) = self.attr(which, "value") else { return };
        let out_of_range = match ty.as_str() {
            "integer" => v.trim().parse::<i64>().is_ok_and(|x| x >= 5),
            "float" => v.trim().parse::<f64>().is_ok_and(|x| x >= 5.0),
            _ => false,
        };
        if out_of_range {
            self.set(which, "value", "0");
        }
    }

    /// Legacy swizzle nodes become constant, extract, convert, combine, or separate + combine.
    fn swizzle(&mut self, node: ElementId) {
        let in_input = self.input(node, "in");
        let source_type = in_input.map(|i| self.attr_or_empty(i, "type")).unwrap_or_else(|| "float".into());
        let dest_type = self.attr_or_empty(node, "type");
        let (Some(src_n), Some(dst_n)) = (channel_count(&source_type), channel_count(&dest_type)) else {
            self.warn(
                node,
                format!(
                    "swizzle `{}` from {source_type} to {dest_type} has no 1.39 equivalent (swizzle nodes were removed); left as is",
                    self.name(node)
                ),
            );
            return;
        };
        let channels_input = self.input(node, "channels");
        let channels: Vec<char> =
            channels_input.and_then(|c| self.attr(c, "value")).unwrap_or_default().chars().collect();
        let has_nodedef = self.has(node, "nodedef");
        let name = self.name(node);

        if let Some(i) = in_input {
            if self.has(i, "value") && ["nodename", "nodegraph", "interfacename"].iter().any(|k| self.has(i, k)) {
                self.unset(i, "value");
            }
        }
        let channel_at = |k: usize| channels.get(k).copied();
        let constant = in_input.is_none_or(|i| self.has(i, "value"))
            || (0..dst_n).all(|k| channel_at(k).is_some_and(|c| channel_constant(c).is_some()));
        let channel_string: String = channels.iter().collect();
        const CONVERT_PATTERNS: [(&str, usize); 10] = [
            ("rgb", 3),
            ("rgb", 4),
            ("rgba", 4),
            ("xyz", 3),
            ("xyz", 4),
            ("xyzw", 4),
            ("rr", 1),
            ("rrr", 1),
            ("xx", 1),
            ("xxx", 1),
        ];
        let convert = !constant
            && dst_n != 1
            && source_type != dest_type
            && CONVERT_PATTERNS.contains(&(channel_string.as_str(), src_n));
        // Channels missing, or naming no channel of the source type, take the first channel
        // (a convert needs none: it fills alpha itself).
        let valid = |c: char| channel_constant(c).is_some() || channel_index(c).is_some_and(|k| k < src_n);
        if !convert && (channels.len() < dst_n || channels.iter().take(dst_n).any(|&c| !valid(c))) {
            self.warn(
                node,
                format!(
                    "swizzle `{name}`: channels \"{channel_string}\" do not name {dst_n} channels of a {source_type}; \
                     missing or invalid ones take the first channel"
                ),
            );
        }
        let pos = self.pos(node);
        if constant {
            self.set_cat(node, "constant");
            if has_nodedef {
                self.set(node, "nodedef", format!("ND_constant_{dest_type}"));
            }
            let value = in_input.and_then(|i| self.attr(i, "value")).unwrap_or_else(|| "0".into());
            let tokens = split_value(&value);
            let first = tokens.first().cloned().unwrap_or_else(|| "0".into());
            let out: Vec<String> = (0..dst_n)
                .map(|k| match channel_at(k) {
                    Some(c) if channel_constant(c).is_some() => channel_constant(c).unwrap().to_string(),
                    Some(c) => channel_index(c).and_then(|x| tokens.get(x).cloned()).unwrap_or_else(|| first.clone()),
                    None => first.clone(),
                })
                .collect();
            self.add(node, "input", &[("name", "value"), ("type", &dest_type), ("value", &out.join(", "))], pos);
            if let Some(i) = in_input {
                self.doc.remove(i);
            }
        } else if dst_n == 1 {
            self.set_cat(node, "extract");
            if has_nodedef {
                self.set(node, "nodedef", format!("ND_extract_{source_type}"));
            }
            if let Some(k) = channel_at(0).and_then(channel_index) {
                self.set_input_value(node, "index", "integer", &k.to_string(), pos);
            }
        } else if convert {
            self.set_cat(node, "convert");
            if has_nodedef {
                self.set(node, "nodedef", format!("ND_convert_{source_type}_{dest_type}"));
            }
        } else if src_n == 1 {
            let in_name = self.name(in_input.unwrap());
            self.set_cat(node, &format!("combine{dst_n}"));
            if has_nodedef {
                self.set(node, "nodedef", format!("ND_combine{dst_n}_{dest_type}"));
            }
            for k in 0..dst_n {
                let input_name = format!("in{}", k + 1);
                match channel_at(k).and_then(channel_constant) {
                    Some(v) => {
                        self.add(node, "input", &[("name", &input_name), ("type", "float"), ("value", v)], pos.clone());
                    }
                    None => {
                        self.add(node, "input", &[("name", &input_name), ("type", "float")], pos.clone());
                        self.copy_input(node, &in_name, node, &input_name);
                    }
                }
            }
            if let Some(i) = self.input(node, &in_name) {
                self.doc.remove(i);
            }
        } else {
            let in_input = in_input.unwrap();
            let graph = self.graph_of(node);
            let sep_name = self.valid_child_name(graph, "separate");
            let index = self.index_in_parent(node).unwrap_or(usize::MAX);
            let sep = self.insert(
                graph,
                index,
                &format!("separate{src_n}"),
                &[("name", &sep_name), ("type", "multioutput")],
                pos.clone(),
            );
            self.set_cat(node, &format!("combine{dst_n}"));
            if has_nodedef {
                self.set(node, "nodedef", format!("ND_combine{dst_n}_{dest_type}"));
            }
            let letters = if source_type.starts_with("color") { COLOR_CHANNELS } else { VECTOR_CHANNELS };
            for k in 0..dst_n {
                let input_name = format!("in{}", k + 1);
                if let Some(v) = channel_at(k).and_then(channel_constant) {
                    self.add(node, "input", &[("name", &input_name), ("type", "float"), ("value", v)], pos.clone());
                    continue;
                }
                let idx = channel_at(k).and_then(channel_index).filter(|&x| x < src_n).unwrap_or(0);
                let output = format!("out{}", letters[idx]);
                self.add(
                    node,
                    "input",
                    &[("name", &input_name), ("type", "float"), ("nodename", &sep_name), ("output", &output)],
                    pos.clone(),
                );
            }
            let in_name = self.name(in_input);
            self.copy_input(node, &in_name, sep, "in");
            self.doc.remove(in_input);
        }
        if let Some(c) = channels_input {
            self.doc.remove(c);
        }
    }

    /// normalmap lost its `space` input: object-space maps become normalize(in·2 − 1); tangent
    /// space ones drop `space`, unbound frame inputs, and get a bitangent when N or T is bound.
    fn normalmap(&mut self, node: ElementId) {
        let graph = self.graph_of(node);
        let pos = self.pos(node);
        let space = self.input(node, "space");
        if space.and_then(|s| self.attr(s, "value")).as_deref() == Some("object") {
            let mul_name = self.valid_child_name(graph, "multiply");
            let mul = self.add(graph, "multiply", &[("name", &mul_name), ("type", "vector3")], pos.clone());
            self.copy_input(node, "in", mul, "in1");
            self.set_input_value(mul, "in2", "float", "2", pos.clone());
            let sub_name = self.valid_child_name(graph, "subtract");
            let sub = self.add(graph, "subtract", &[("name", &sub_name), ("type", "vector3")], pos.clone());
            self.add(sub, "input", &[("name", "in1"), ("type", "vector3"), ("nodename", &mul_name)], pos.clone());
            self.set_input_value(sub, "in2", "float", "1", pos.clone());
            self.set_cat(node, "normalize");
            for i in self.inputs(node) {
                self.doc.remove(i);
            }
            self.add(node, "input", &[("name", "in"), ("type", "vector3"), ("nodename", &sub_name)], pos);
            if self.has(node, "nodedef") {
                self.set(node, "nodedef", "ND_normalize_vector3");
            }
            return;
        }
        if let Some(s) = space {
            if self.is_bound(s) {
                self.warn(
                    s,
                    format!(
                        "`space` of normalmap `{}` is connected; 1.39 normalmaps are tangent-space only, so it is read as tangent",
                        self.name(node)
                    ),
                );
            }
            self.doc.remove(s);
        }
        let keep = |up: &mut Self, k: &str| -> bool {
            match up.input(node, k) {
                Some(i) if up.is_bound(i) => true,
                Some(i) => {
                    up.doc.remove(i);
                    false
                }
                None => false,
            }
        };
        let normal = keep(self, "normal");
        let tangent = keep(self, "tangent");
        let bitangent = keep(self, "bitangent");
        if (normal || tangent) && !bitangent {
            let cross_name = self.valid_child_name(graph, "normalmap_cross");
            let cross = self.add(graph, "crossproduct", &[("name", &cross_name), ("type", "vector3")], pos.clone());
            for (src, dst, geom) in [("normal", "in1", "normal"), ("tangent", "in2", "tangent")] {
                if self.input(node, src).is_some() {
                    self.copy_input(node, src, cross, dst);
                } else {
                    let geom_name = self.valid_child_name(graph, &format!("normalmap_{geom}"));
                    let g = self.add(graph, geom, &[("name", &geom_name), ("type", "vector3")], pos.clone());
                    self.set_input_value(g, "space", "string", "world", pos.clone());
                    self.add(cross, "input", &[("name", dst), ("type", "vector3"), ("nodename", &geom_name)], pos.clone());
                }
            }
            let norm_name = self.valid_child_name(graph, "normalmap_cross_norm");
            let norm = self.add(graph, "normalize", &[("name", &norm_name), ("type", "vector3")], pos.clone());
            self.add(norm, "input", &[("name", "in"), ("type", "vector3"), ("nodename", &cross_name)], pos.clone());
            self.add(node, "input", &[("name", "bitangent"), ("type", "vector3"), ("nodename", &norm_name)], pos);
        }
        if self.doc.get(node).attr("nodedef") == Some("ND_normalmap") {
            self.set(node, "nodedef", "ND_normalmap_float");
        }
    }
}

/// Whether `s` can be an element's tag or an attribute's name (an XML name without a namespace
/// prefix: a letter or `_` and then letters, digits, `_`, `-`, `.`; a `:` would read back as an
/// undeclared prefix). Upgrades that turn a value into a category or a name into an attribute
/// check it, so that the writer never writes a document that does not read back (found by
/// fuzzing, three times).
fn is_element_name(s: &str) -> bool {
    let mut chars = s.chars();
    chars.next().is_some_and(|c| c.is_alphabetic() || c == '_') && chars.all(|c| c.is_alphanumeric() || matches!(c, '_' | '-' | '.'))
}
