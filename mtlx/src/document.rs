//! The document model: an arena of elements (category, ordered attributes, children, source
//! position), rooted at `<materialx>`. Typed views (nodedefs, nodes, inputs) are read off it by
//! `crate::schema`; the reader builds it, the writer prints it.

use std::collections::HashMap;
use std::sync::Mutex;

use crate::position::SourcePos;

/// Index of an element in its document's arena.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ElementId(pub u32);

/// One XML element of a MaterialX document. `category` is the tag name (`nodedef`, `input`,
/// `add`, `nodegraph`, ...). Attributes keep their source order.
#[derive(Clone, Debug)]
pub struct Element {
    pub category: String,
    pub attributes: Vec<(String, String)>,
    pub children: Vec<ElementId>,
    pub parent: Option<ElementId>,
    pub pos: SourcePos,
}

impl Element {
    pub fn attr(&self, name: &str) -> Option<&str> {
        self.attributes.iter().find(|(k, _)| k == name).map(|(_, v)| v.as_str())
    }

    /// The `name` attribute, or "" when absent.
    pub fn name(&self) -> &str {
        self.attr("name").unwrap_or("")
    }

    pub fn set_attr(&mut self, name: &str, value: impl Into<String>) {
        let value = value.into();
        match self.attributes.iter_mut().find(|(k, _)| k == name) {
            Some(slot) => slot.1 = value,
            None => self.attributes.push((name.to_string(), value)),
        }
    }

    pub fn remove_attr(&mut self, name: &str) -> Option<String> {
        let i = self.attributes.iter().position(|(k, _)| k == name)?;
        Some(self.attributes.remove(i).1)
    }
}

/// A MaterialX document: elements in an arena; `root` is the `<materialx>` element.
#[derive(Clone, Debug)]
pub struct Document {
    elements: Vec<Element>,
    root: ElementId,
    names: NameIndex,
}

/// Above this many children, `Document::child` looks names up in a per-parent hash map instead
/// of scanning: documents with thousands of top-level nodes would otherwise resolve their
/// connections in quadratic time (20,000 nodes: 20 s).
const INDEXED_CHILDREN: usize = 32;

/// Per-parent maps from a child's name to the first child of that name, built on first use and
/// dropped by every mutation (`&mut self` methods of `Document`).
#[derive(Default)]
struct NameIndex(Mutex<HashMap<ElementId, HashMap<String, ElementId>>>);

impl NameIndex {
    fn clear(&mut self) {
        self.0.get_mut().unwrap_or_else(|e| e.into_inner()).clear();
    }
}

impl Clone for NameIndex {
    fn clone(&self) -> Self {
        NameIndex::default()
    }
}

impl std::fmt::Debug for NameIndex {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("NameIndex")
    }
}

impl Document {
    /// An empty document whose root `<materialx version="1.39">` sits at `pos`.
    pub fn new(pos: SourcePos) -> Self {
        let root = Element {
            category: "materialx".into(),
            attributes: vec![("version".into(), "1.39".into())],
            children: Vec::new(),
            parent: None,
            pos,
        };
        Document { elements: vec![root], root: ElementId(0), names: NameIndex::default() }
    }

    pub fn root(&self) -> ElementId {
        self.root
    }

    pub fn get(&self, id: ElementId) -> &Element {
        &self.elements[id.0 as usize]
    }

    pub fn get_mut(&mut self, id: ElementId) -> &mut Element {
        self.names.clear();
        &mut self.elements[id.0 as usize]
    }

    /// Appends a new element as the last child of `parent`.
    pub fn add_child(
        &mut self,
        parent: ElementId,
        category: impl Into<String>,
        attributes: Vec<(String, String)>,
        pos: SourcePos,
    ) -> ElementId {
        self.names.clear();
        let id = ElementId(self.elements.len() as u32);
        self.elements.push(Element {
            category: category.into(),
            attributes,
            children: Vec::new(),
            parent: Some(parent),
            pos,
        });
        self.elements[parent.0 as usize].children.push(id);
        id
    }

    /// Inserts a new element as child of `parent` at `index`.
    pub fn insert_child(
        &mut self,
        parent: ElementId,
        index: usize,
        category: impl Into<String>,
        attributes: Vec<(String, String)>,
        pos: SourcePos,
    ) -> ElementId {
        let id = self.add_child(parent, category, attributes, pos);
        let children = &mut self.elements[parent.0 as usize].children;
        children.pop();
        children.insert(index.min(children.len()), id);
        id
    }

    /// Detaches `id` from its parent (the element stays in the arena, unreachable).
    pub fn remove(&mut self, id: ElementId) {
        self.names.clear();
        if let Some(parent) = self.get(id).parent {
            self.elements[parent.0 as usize].children.retain(|c| *c != id);
        }
        self.elements[id.0 as usize].parent = None;
    }

    /// Copies the subtree rooted at `src` of `other` under `parent` of this document.
    /// A work list, not recursion: subtrees are as deep as the input makes them.
    pub fn import_subtree(&mut self, parent: ElementId, other: &Document, src: ElementId) -> ElementId {
        let e = other.get(src);
        let root = self.add_child(parent, e.category.clone(), e.attributes.clone(), e.pos.clone());
        let mut work: Vec<(ElementId, ElementId)> = e.children.iter().rev().map(|&c| (c, root)).collect();
        while let Some((from, to)) = work.pop() {
            let e = other.get(from);
            let id = self.add_child(to, e.category.clone(), e.attributes.clone(), e.pos.clone());
            work.extend(e.children.iter().rev().map(|&c| (c, id)));
        }
        root
    }

    pub fn children(&self, id: ElementId) -> &[ElementId] {
        &self.get(id).children
    }

    /// Children of `id` whose category is `category`.
    pub fn children_of<'a>(&'a self, id: ElementId, category: &'a str) -> impl Iterator<Item = ElementId> + 'a {
        self.children(id).iter().copied().filter(move |c| self.get(*c).category == category)
    }

    /// The child of `id` named `name`.
    pub fn child(&self, id: ElementId, name: &str) -> Option<ElementId> {
        let children = self.children(id);
        if children.len() <= INDEXED_CHILDREN {
            return children.iter().copied().find(|c| self.get(*c).name() == name);
        }
        let mut index = self.names.0.lock().unwrap_or_else(|e| e.into_inner());
        let by_name = index.entry(id).or_insert_with(|| {
            let mut m = HashMap::with_capacity(children.len());
            for &c in children {
                m.entry(self.get(c).name().to_string()).or_insert(c);
            }
            m
        });
        by_name.get(name).copied()
    }

    /// The MaterialX namespace in scope at `id`: its own `namespace` attribute or its nearest
    /// ancestor's (MaterialX's `Element::getQualifiedName` walk).
    pub fn namespace(&self, id: ElementId) -> Option<&str> {
        let mut cur = Some(id);
        while let Some(c) = cur {
            let e = self.get(c);
            if let Some(ns) = e.attr("namespace").filter(|ns| !ns.is_empty()) {
                return Some(ns);
            }
            cur = e.parent;
        }
        None
    }

    /// `name` qualified by the namespace in scope at `id` (`ns:name`), unless it already is.
    pub fn qualified_name(&self, id: ElementId, name: &str) -> String {
        qualify(self.namespace(id), name)
    }

    /// The child of `scope` named `name`, as a reference written on element `at` means it
    /// (MaterialX's `resolveNameReference`): the name qualified by `at`'s namespace first, then
    /// as written; and `ns:local` also finds a child `local` declared in namespace `ns` (a
    /// namespaced definition read in place rather than imported keeps its unqualified name).
    pub fn resolve(&self, at: ElementId, scope: ElementId, name: &str) -> Option<ElementId> {
        let qualified = self.qualified_name(at, name);
        if qualified != name {
            if let Some(c) = self.child(scope, &qualified) {
                return Some(c);
            }
        }
        self.child(scope, name).or_else(|| {
            let (ns, local) = name.split_once(':')?;
            self.children(scope).iter().copied().find(|&c| self.get(c).name() == local && self.namespace(c) == Some(ns))
        })
    }

    /// Top-level elements (children of the root).
    pub fn top_level(&self) -> &[ElementId] {
        self.children(self.root)
    }

    /// Every reachable element, depth-first, parents before children.
    pub fn descendants(&self, id: ElementId) -> Vec<ElementId> {
        let mut out = Vec::new();
        let mut stack = vec![id];
        while let Some(e) = stack.pop() {
            out.push(e);
            stack.extend(self.children(e).iter().rev().copied());
        }
        out
    }

    /// Structural equality: categories, attributes (in order) and children, ignoring positions.
    pub fn same_content(&self, other: &Document) -> bool {
        // An explicit work list of element pairs: nesting is input-sized.
        fn eq(a: &Document, x: ElementId, b: &Document, y: ElementId) -> bool {
            let mut work = vec![(x, y)];
            while let Some((x, y)) = work.pop() {
                let (ex, ey) = (a.get(x), b.get(y));
                if ex.category != ey.category || ex.attributes != ey.attributes || ex.children.len() != ey.children.len() {
                    return false;
                }
                work.extend(ex.children.iter().copied().zip(ey.children.iter().copied()));
            }
            true
        }
        eq(self, self.root, other, other.root)
    }

    /// The document's `version` attribute as (major, minor); (1, 39) when absent.
    pub fn version(&self) -> (u32, u32) {
        parse_version(self.get(self.root).attr("version").unwrap_or("1.39")).unwrap_or((1, 39))
    }
}

/// Parses "1.38" (or "1.38.2") into (1, 38).
pub fn parse_version(v: &str) -> Option<(u32, u32)> {
    let mut it = v.trim().split('.');
    let major = it.next()?.parse().ok()?;
    let minor = it.next().unwrap_or("0").parse().ok()?;
    Some((major, minor))
}

/// `name` qualified by `namespace` as MaterialX qualifies it: `namespace:name`, unless `name`
/// already carries that prefix.
pub fn qualify(namespace: Option<&str>, name: &str) -> String {
    match namespace {
        Some(ns) if !ns.is_empty() && !name.is_empty() && name.split_once(':').map(|(p, _)| p) != Some(ns) => format!("{ns}:{name}"),
        _ => name.to_string(),
    }
}
