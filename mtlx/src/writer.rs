//! Writing a [`Document`] back to `.mtlx` text: an XML declaration, the `<materialx>` root with
//! its attributes, two-space indentation, attributes in their stored order, XML-escaped values,
//! and self-closing empty elements. [`write_file`] replaces the target atomically.

use crate::document::{Document, ElementId};
use std::fmt::Write as _;
use std::io::Write as _;
use std::path::Path;

/// The document as `.mtlx` text (UTF-8, `\n` line ends, a final newline).
pub fn write_string(doc: &Document) -> String {
    let mut out = String::from("<?xml version=\"1.0\"?>\n");
    write_element(doc, doc.root(), 0, &mut out);
    out
}

/// Writes the document to `path` atomically: the text goes to a temporary file in the same
/// folder, which is flushed to disk and then renamed over `path`. On failure the temporary file
/// is removed and `path` is left as it was.
pub fn write_file(doc: &Document, path: &Path) -> std::io::Result<()> {
    let text = write_string(doc);
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => std::path::PathBuf::from("."),
    };
    let file_name = path
        .file_name()
        .ok_or_else(|| std::io::Error::new(std::io::ErrorKind::InvalidInput, format!("`{}` names no file", path.display())))?
        .to_string_lossy()
        .into_owned();
    let (tmp, mut file) = create_temp(&dir, &file_name)?;
    let result = (|| {
        file.write_all(text.as_bytes())?;
        file.sync_all()?;
        drop(file);
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Creates a new, uniquely named temporary file next to the target.
fn create_temp(dir: &Path, file_name: &str) -> std::io::Result<(std::path::PathBuf, std::fs::File)> {
    use std::sync::atomic::{AtomicU64, Ordering};
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let pid = std::process::id();
    loop {
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let tmp = dir.join(format!(".{file_name}.{pid}.{n}.tmp"));
        match std::fs::OpenOptions::new().write(true).create_new(true).open(&tmp) {
            Ok(f) => return Ok((tmp, f)),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(e),
        }
    }
}

/// Indentation stops growing at this depth, so that output stays linear in the document's size
/// however deep its elements nest (MaterialX documents nest two to four levels).
const MAX_INDENT: usize = 32;

/// Writes `id` and its descendants with an explicit work list (nesting is input-sized).
fn write_element(doc: &Document, id: ElementId, depth: usize, out: &mut String) {
    enum Step {
        Open(ElementId, usize),
        Close(ElementId, usize),
    }
    let indent = |out: &mut String, depth: usize| (0..depth.min(MAX_INDENT)).for_each(|_| out.push_str("  "));
    let mut work = vec![Step::Open(id, depth)];
    while let Some(step) = work.pop() {
        match step {
            Step::Open(id, depth) => {
                let e = doc.get(id);
                indent(out, depth);
                out.push('<');
                out.push_str(&e.category);
                for (k, v) in &e.attributes {
                    out.push(' ');
                    out.push_str(k);
                    out.push_str("=\"");
                    escape_into(v, out);
                    out.push('"');
                }
                if e.children.is_empty() {
                    out.push_str(" />\n");
                    continue;
                }
                out.push_str(">\n");
                work.push(Step::Close(id, depth));
                work.extend(e.children.iter().rev().map(|&c| Step::Open(c, depth + 1)));
            }
            Step::Close(id, depth) => {
                indent(out, depth);
                out.push_str("</");
                out.push_str(&doc.get(id).category);
                out.push_str(">\n");
            }
        }
    }
}

/// Escapes an attribute value: `&`, `<`, `>`, `"` as entities; tab, newline and carriage return
/// (which attribute-value normalisation would otherwise turn into spaces) and the C1 controls
/// as character references. Characters XML 1.0 cannot represent at all (other C0 controls,
/// U+FFFE, U+FFFF) become U+FFFD, so the output always parses.
pub fn escape_attribute(value: &str) -> String {
    let mut out = String::with_capacity(value.len());
    escape_into(value, &mut out);
    out
}

fn escape_into(value: &str, out: &mut String) {
    for c in value.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\t' | '\n' | '\r' | '\u{7f}'..='\u{9f}' => {
                let _ = write!(out, "&#x{:X};", c as u32);
            }
            '\u{0}'..='\u{1f}' | '\u{fffe}' | '\u{ffff}' => out.push('\u{fffd}'),
            _ => out.push(c),
        }
    }
}
