//! Source positions (`file:line:column`) carried by every element read from a document.

use std::fmt;
use std::sync::Arc;

/// Where an element starts in its source file; lines and columns count from 1.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct SourcePos {
    pub file: Arc<str>,
    pub line: u32,
    pub column: u32,
}

impl SourcePos {
    pub fn new(file: Arc<str>, line: u32, column: u32) -> Self {
        SourcePos { file, line, column }
    }

    /// A position for elements that were not read from a file (built in code).
    pub fn synthetic(what: &str) -> Self {
        SourcePos { file: Arc::from(what), line: 0, column: 0 }
    }
}

impl fmt::Display for SourcePos {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}:{}", self.file, self.line, self.column)
    }
}
