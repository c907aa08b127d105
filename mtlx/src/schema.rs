//! Typed views of a document's elements: nodedefs with their ports, and helpers to read
//! the attributes the compiler cares about (`type`, `value`, `nodename`, ...).

use crate::document::{Document, ElementId};
use crate::position::SourcePos;
use crate::types::DataType;

/// One `<input>` or `<output>` of a nodedef.
#[derive(Clone, Debug)]
pub struct PortDef {
    pub name: String,
    pub ty: DataType,
    /// The `value` attribute (inputs) or `default` attribute (outputs).
    pub value: Option<String>,
    pub defaultgeomprop: Option<String>,
    /// For outputs: the input passed through when the node is disabled.
    pub defaultinput: Option<String>,
    pub uniform: bool,
    /// The `enum` list of a string input, if any.
    pub enum_values: Option<Vec<String>>,
    pub pos: SourcePos,
}

/// A `<nodedef>`: the contract of a node (category, ports, version).
#[derive(Clone, Debug)]
pub struct NodeDef {
    /// The nodedef's name, qualified by its namespace (`ns:ND_x`) when it has one.
    pub name: String,
    /// The node category it defines, qualified likewise (`ns:x`): a node `<ns:x>` matches it.
    pub node: String,
    /// The MaterialX namespace in scope at the nodedef, against which its `inherit` resolves.
    pub namespace: Option<String>,
    pub nodegroup: Option<String>,
    pub version: Option<String>,
    pub is_default_version: bool,
    pub inherit: Option<String>,
    pub inputs: Vec<PortDef>,
    pub outputs: Vec<PortDef>,
    pub pos: SourcePos,
}

impl NodeDef {
    /// Reads the nodedef element `id` of `doc`.
    pub fn from_element(doc: &Document, id: ElementId) -> NodeDef {
        let e = doc.get(id);
        let port = |c: ElementId| {
            let p = doc.get(c);
            PortDef {
                name: p.name().to_string(),
                ty: DataType::from_name(p.attr("type").unwrap_or("")),
                value: p.attr("value").or_else(|| p.attr("default")).map(str::to_string),
                defaultgeomprop: p.attr("defaultgeomprop").map(str::to_string),
                defaultinput: p.attr("defaultinput").map(str::to_string),
                uniform: p.attr("uniform") == Some("true"),
                enum_values: p.attr("enum").map(|s| s.split(',').map(|v| v.trim().to_string()).collect()),
                pos: p.pos.clone(),
            }
        };
        NodeDef {
            name: doc.qualified_name(id, e.name()),
            node: doc.qualified_name(id, e.attr("node").unwrap_or("")),
            namespace: doc.namespace(id).map(str::to_string),
            nodegroup: e.attr("nodegroup").map(str::to_string),
            version: e.attr("version").map(str::to_string),
            is_default_version: e.attr("isdefaultversion") == Some("true"),
            inherit: e.attr("inherit").map(str::to_string),
            inputs: doc.children_of(id, "input").map(port).collect(),
            outputs: doc.children_of(id, "output").map(port).collect(),
            pos: e.pos.clone(),
        }
    }

    pub fn input(&self, name: &str) -> Option<&PortDef> {
        self.inputs.iter().find(|p| p.name == name)
    }

    pub fn output(&self, name: &str) -> Option<&PortDef> {
        self.outputs.iter().find(|p| p.name == name)
    }

    /// The node `type` this nodedef produces: its output's type, or `multioutput`.
    pub fn node_type(&self) -> DataType {
        match self.outputs.as_slice() {
            [one] => one.ty.clone(),
            [] => DataType::Other(String::new()),
            _ => DataType::Multioutput,
        }
    }
}

/// Attribute names that connect an input to something other than its own value.
pub const CONNECTION_ATTRIBUTES: [&str; 3] = ["nodename", "nodegraph", "interfacename"];

/// Element categories that are not nodes inside a nodegraph or document.
pub const NON_NODE_CATEGORIES: [&str; 31] = [
    "input", "output", "nodedef", "nodegraph", "implementation", "typedef", "member", "look", "lookgroup",
    "lookinherit", "materialassign", "visibility", "collection", "geominfo", "geomprop", "geompropdef",
    "variantset", "variant", "variantassign", "unittypedef", "unitdef", "unit", "propertyset",
    "propertyassign", "propertysetassign", "backdrop", "token", "attributedef", "targetdef", "comment",
    "include",
];

/// True when an element of this category is a node (an operation in a graph).
pub fn is_node_category(category: &str) -> bool {
    !NON_NODE_CATEGORIES.contains(&category)
}
