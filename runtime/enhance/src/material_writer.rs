//! Writing an enhanced material: a self-contained MaterialX document built from a rule.
//!
//! The document holds, in order: the uplift node library (`uplift_stack` and the rules' helper
//! nodes, definitions and nodegraphs, copied from the embedded `mtlx/libraries/uplift/`); the
//! rule's nodegraph renamed [`MATERIAL_GRAPH`], its random scalars set to the drawn values, its
//! PBR inputs set to the material's constants or replaced by `image` nodes reading the
//! material's textures (paths relative to the document); a `surface` shader on the graph's
//! `bsdf` output; and a `surfacematerial`. Mask inputs keep the rule's `masks/<kind>.png`, which
//! is where `uplift enhance` writes the material's masks.

use crate::rules::{RuleInterface, PBR_INPUTS, RULE_GRAPH};
use mtlx::{Document, ElementId, SourcePos};

/// The enhanced material's nodegraph.
pub const MATERIAL_GRAPH: &str = "uplift_material";

/// A PBR input's source in the written document.
#[derive(Clone, Debug, PartialEq)]
pub enum PbrValue {
    /// A constant (1 or 3 components).
    Constant(Vec<f32>),
    /// A texture file, relative to the document, and its colour space.
    Texture { file: String, colorspace: String },
}

/// Everything the written document depends on.
#[derive(Clone, Debug)]
pub struct MaterialSpec<'a> {
    pub rule: &'a RuleInterface,
    /// Rule options merged into the rule's graph.
    pub options: &'a [crate::rule_option::RuleOption],
    /// The rule's random scalars, drawn.
    pub scalars: &'a [(String, f64)],
    /// A value per PBR input name ([`PBR_INPUTS`]); inputs not given keep the rule's default.
    pub pbr: &'a [(String, PbrValue)],
    /// Glints on the stack (`crate::glints`), if any.
    pub glint: Option<&'a uplift_material::GlintRecord>,
}

fn attrs(pairs: &[(&str, &str)]) -> Vec<(String, String)> {
    pairs.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect()
}

/// A number as MaterialX writes it: the shortest text that reads back to the same f32.
pub fn format_value(components: &[f32]) -> String {
    components.iter().map(|c| format!("{c:?}")).collect::<Vec<_>>().join(", ")
}

/// Builds the enhanced material's document.
pub fn material_document(spec: &MaterialSpec) -> Result<Document, String> {
    let pos = || SourcePos::synthetic("uplift enhance");
    let mut doc = Document::new(pos());
    let root = doc.root();
    doc.get_mut(root).set_attr("colorspace", "lin_rec709");

    // The stack's definitions: a `--stack` library's first, then the builtin uplift library's
    // (an element both define is the first one's, as the compiler resolves it).
    let mut defined: std::collections::HashSet<String> = std::collections::HashSet::new();
    for lib in spec.rule.stack.definition_documents() {
        for &id in lib.top_level() {
            let name = lib.get(id).name().to_string();
            if name.is_empty() || defined.insert(name) {
                doc.import_subtree(root, &lib, id);
            }
        }
    }

    let rule = &spec.rule.document;
    let rule_graph = rule
        .top_level()
        .iter()
        .copied()
        .find(|&id| rule.get(id).category == "nodegraph" && rule.get(id).name() == RULE_GRAPH)
        .ok_or_else(|| format!("rule {}: no nodegraph `{RULE_GRAPH}`", spec.rule.kind.name()))?;
    let graph = doc.import_subtree(root, rule, rule_graph);
    doc.get_mut(graph).set_attr("name", MATERIAL_GRAPH);
    for o in spec.options {
        o.merge_into(&mut doc, graph)?;
    }

    for (name, value) in spec.scalars {
        let input = interface_input(&doc, graph, name)?;
        doc.get_mut(input).set_attr("value", format_value(&[*value as f32]));
    }
    for (name, value) in spec.pbr {
        let ty = PBR_INPUTS.iter().find(|(n, _)| n == name).map(|(_, t)| *t).ok_or_else(|| format!("`{name}` is not a PBR input of the rules"))?;
        let input = interface_input(&doc, graph, name)?;
        match value {
            PbrValue::Constant(v) => {
                let want = if ty == "float" { 1 } else { 3 };
                if v.len() != want {
                    return Err(format!("PBR input `{name}` ({ty}) given {} components", v.len()));
                }
                doc.get_mut(input).set_attr("value", format_value(v));
            }
            PbrValue::Texture { file, colorspace } => {
                let node_name = format!("{name}_texture");
                // After the interface inputs, before the first node.
                let first_node = doc.children(graph).iter().position(|&c| doc.get(c).category != "input").unwrap_or(0);
                let image = doc.insert_child(graph, first_node, "image", attrs(&[("name", &node_name), ("type", ty)]), pos());
                doc.add_child(
                    image,
                    "input",
                    attrs(&[("name", "file"), ("type", "filename"), ("value", file), ("colorspace", colorspace)]),
                    pos(),
                );
                for id in doc.descendants(graph) {
                    let e = doc.get(id);
                    if e.category == "input" && e.parent != Some(graph) && e.attr("interfacename") == Some(name.as_str()) {
                        let e = doc.get_mut(id);
                        e.remove_attr("interfacename");
                        e.set_attr("nodename", node_name.clone());
                    }
                }
                doc.remove(input);
            }
        }
    }

    if let Some(g) = spec.glint {
        crate::glints::insert(&mut doc, graph, g)?;
    }

    let surface = doc.add_child(root, "surface", attrs(&[("name", "uplift_surface"), ("type", "surfaceshader")]), pos());
    doc.add_child(
        surface,
        "input",
        attrs(&[("name", "bsdf"), ("type", "BSDF"), ("nodegraph", MATERIAL_GRAPH), ("output", "bsdf_out")]),
        pos(),
    );
    let material = doc.add_child(root, "surfacematerial", attrs(&[("name", "uplift_material_surface"), ("type", "material")]), pos());
    doc.add_child(
        material,
        "input",
        attrs(&[("name", "surfaceshader"), ("type", "surfaceshader"), ("nodename", "uplift_surface")]),
        pos(),
    );
    Ok(doc)
}

fn interface_input(doc: &Document, graph: ElementId, name: &str) -> Result<ElementId, String> {
    doc.children_of(graph, "input")
        .find(|&id| doc.get(id).name() == name)
        .ok_or_else(|| format!("the rule has no interface input `{name}`"))
}
