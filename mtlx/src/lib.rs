//! MaterialX 1.39 documents for uplift: the element-tree [`Document`] with a source position
//! on every element, the reader (roxmltree, `xi:include`, version upgrades), the writer, typed
//! views of nodedefs/nodes/nodegraphs, and the node library (nodedefs plus WGSL sources under
//! `mtlx/libraries/`). This crate never generates code and never touches naga.

pub mod diagnostic;
pub mod document;
pub mod file_access;
pub mod library;
pub mod position;
pub mod reader;
pub mod schema;
pub mod types;
pub mod upgrade;
pub mod writer;
pub mod value;

pub use diagnostic::{has_errors, Diagnostic, Severity};
pub use document::{Document, Element, ElementId};
pub use file_access::{FileAccess, OutsideInput, UriTarget};
pub use position::SourcePos;
pub use library::Library;
pub use reader::{read_file, read_file_with, read_str, read_str_with, without_includes};
pub use writer::{write_file, write_string};
pub use schema::{NodeDef, PortDef};
pub use types::DataType;
pub use value::Value;
