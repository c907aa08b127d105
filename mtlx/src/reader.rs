//! Reading `.mtlx` text into a [`Document`]: XML parsing (roxmltree) with a source position
//! for every element, `xi:include` merging, then the version upgrades of `crate::upgrade`.
//! Errors never stop the reader early: it returns the document it could build plus every
//! diagnostic, so one bad element does not hide the rest.

use crate::diagnostic::Diagnostic;
use crate::document::{Document, ElementId};
use crate::file_access::FileAccess;
use crate::position::SourcePos;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Root attributes that MaterialX copies onto the children of an included document.
const INHERITED_ROOT_ATTRIBUTES: [&str; 4] = ["fileprefix", "geomprefix", "colorspace", "namespace"];

/// Reads a document from a file; the file's path names every position. Its includes lie in its
/// folder (or are library documents): [`read_file_with`] the default [`FileAccess`].
pub fn read_file(path: &Path) -> (Document, Vec<Diagnostic>) {
    read_file_with(path, &FileAccess::default())
}

/// Reads a document from a file, following its `xi:include`s where `access` allows: an include
/// resolves relative to the including file, inside the top document's folder or a search path
/// (`crate::file_access`), else among the search paths, else as a builtin library document
/// (`crate::library::builtin_document`: `uplift/uplift_defs.mtlx`, as MaterialX resolves library
/// includes through its search path). An include outside is an error, the same whether or not the
/// file exists.
pub fn read_file_with(path: &Path, access: &FileAccess) -> (Document, Vec<Diagnostic>) {
    let mut diags = Vec::new();
    let mut includes = Includes { stack: Vec::new(), access, top: path.to_path_buf() };
    let doc = read_file_inner(path, &mut diags, &mut includes, None);
    (doc, diags)
}

/// The include chain being read and the rule for what it may name.
struct Includes<'a> {
    /// The documents being read, outermost first.
    stack: Vec<PathBuf>,
    access: &'a FileAccess,
    /// The top document, whose folder includes may name files in.
    top: PathBuf,
}

/// `text` with its `xi:include` lines emptied (lines kept, so positions stay the file's): for
/// documents that include the uplift library, which the builtin library holds anyway (the
/// rules, the training classes), read from any folder.
pub fn without_includes(text: &str) -> String {
    text.lines().map(|l| if l.trim_start().starts_with("<xi:include") { "\n".to_string() } else { format!("{l}\n") }).collect()
}

/// Reads a document from text; `name` stands for the file in positions, and relative
/// `xi:include` paths resolve against its folder.
pub fn read_str(text: &str, name: &str) -> (Document, Vec<Diagnostic>) {
    read_str_with(text, name, &FileAccess::default())
}

/// [`read_str`] with includes allowed where `access` says ([`read_file_with`]).
pub fn read_str_with(text: &str, name: &str, access: &FileAccess) -> (Document, Vec<Diagnostic>) {
    let mut diags = Vec::new();
    let mut includes = Includes { stack: vec![PathBuf::from(name)], access, top: PathBuf::from(name) };
    let doc = parse_text(text, Path::new(name), &mut diags, &mut includes);
    (doc, diags)
}

fn read_file_inner(
    path: &Path,
    diags: &mut Vec<Diagnostic>,
    stack: &mut Includes,
    included_from: Option<&SourcePos>,
) -> Document {
    let file: Arc<str> = Arc::from(path.display().to_string());
    let text = match std::fs::read_to_string(path) {
        Ok(t) => t,
        Err(e) => {
            let pos = included_from.cloned().unwrap_or_else(|| SourcePos::new(file.clone(), 0, 0));
            diags.push(Diagnostic::error(pos, format!("cannot read `{}`: {e}", path.display())));
            return Document::new(SourcePos::new(file, 1, 1));
        }
    };
    stack.stack.push(path.to_path_buf());
    let doc = parse_text(&text, path, diags, stack);
    stack.stack.pop();
    doc
}

fn parse_text(text: &str, path: &Path, diags: &mut Vec<Diagnostic>, stack: &mut Includes) -> Document {
    let file: Arc<str> = Arc::from(path.display().to_string());
    let opts = || roxmltree::ParsingOptions { allow_dtd: true, ..Default::default() };
    // Strict XML first (one parse); only text it refuses goes through the repairs.
    let repaired;
    let parsed = match roxmltree::Document::parse_with_options(text, opts()) {
        Ok(x) => Ok((x, text)),
        Err(e) => {
            let check = |t: &str| roxmltree::Document::parse_with_options(t, roxmltree::ParsingOptions { allow_dtd: true, ..Default::default() }).map(|_| ());
            repaired = readable_text(text, e, &check);
            match &repaired {
                Ok(t) => roxmltree::Document::parse_with_options(t.as_str(), opts()).map(|x| (x, t.as_str())),
                Err(e) => Err(e.clone()),
            }
        }
    };
    let (xml, parsed_text) = match parsed {
        Ok(x) => x,
        Err(e) => {
            let p = e.pos();
            let mut at = SourcePos::new(file.clone(), p.row, p.col);
            let mut message = format!("malformed XML: {e}");
            // A close tag that does not match: point at the element left open.
            if let roxmltree::Error::UnexpectedCloseTag(expected, actual, _) = &e {
                if let Some(open) = unclosed_tag(text, expected, p) {
                    message = format!("malformed XML: <{expected}> is never closed (found </{actual}> at {}:{})", p.row, p.col);
                    at = SourcePos::new(file.clone(), open.0, open.1);
                }
            }
            diags.push(Diagnostic::error(at, message));
            return Document::new(SourcePos::new(file, 1, 1));
        }
    };
    let lines = Lines::new(parsed_text);
    let root = xml.root_element();
    let root_pos = lines.pos(root, &file);
    let mut doc = Document::new(root_pos.clone());
    if root.tag_name().name() != "materialx" {
        diags.push(Diagnostic::error(
            root_pos,
            format!("root element is <{}>, expected <materialx>", root.tag_name().name()),
        ));
        return doc;
    }
    let doc_root = doc.root();
    doc.get_mut(doc_root).attributes = attributes_of(root);
    // As MaterialX does: included documents are merged first, and then the document's own
    // top-level elements, skipping names an include already defined.
    let (includes, own): (Vec<_>, Vec<_>) = root.children().filter(|c| c.is_element()).partition(|c| is_include(*c));
    for child in includes {
        convert(&lines, child, &file, path, &mut doc, doc_root, diags, stack);
    }
    let included: std::collections::HashSet<String> = doc.top_level().iter().map(|&c| doc.get(c).name().to_string()).collect();
    for child in own {
        let name = child.attribute("name").unwrap_or("");
        if !name.is_empty() && included.contains(name) {
            diags.push(Diagnostic::warning(lines.pos(child, &file), format!("`{name}` is already defined by an included document; this definition is skipped")));
            continue;
        }
        convert(&lines, child, &file, path, &mut doc, doc_root, diags, stack);
    }
    crate::upgrade::upgrade(&mut doc, diags);
    doc
}

/// Byte offsets of line starts, for `line:column` of any offset in O(log n).
struct Lines<'a> {
    text: &'a str,
    starts: Vec<usize>,
}

impl<'a> Lines<'a> {
    fn new(text: &'a str) -> Self {
        let starts = std::iter::once(0).chain(text.match_indices('\n').map(|(i, _)| i + 1)).collect();
        Lines { text, starts }
    }

    fn pos(&self, node: roxmltree::Node, file: &Arc<str>) -> SourcePos {
        let offset = node.range().start;
        let line = self.starts.partition_point(|&s| s <= offset) - 1;
        let column = self.text[self.starts[line]..offset].chars().count() + 1;
        SourcePos::new(file.clone(), line as u32 + 1, column as u32)
    }
}

/// An `include` element in any XML namespace (or none) is an include: MaterialX matches the
/// qualified name `xi:include` and never looks at the namespace's URI, so `xi:` bound to a
/// mistyped URI still includes there. (The writer writes every include as `xi:include`; an
/// `include` element kept as a node would be written back as an include — found by fuzzing.)
fn is_include(node: roxmltree::Node) -> bool {
    node.tag_name().name() == "include"
}

/// `prefix:local` as written, for a name in an XML namespace (MaterialX's namespaced names,
/// read as pugixml reads them: the prefix is part of the name), else the plain name.
fn prefixed(node: roxmltree::Node, uri: Option<&str>, local: &str) -> String {
    match uri.and_then(|u| node.lookup_prefix(u)).filter(|p| !p.is_empty()) {
        Some(prefix) => format!("{prefix}:{local}"),
        None => local.to_string(),
    }
}

/// The element's category: its tag as written (`site_ops:mynoise` stays one name).
fn tag_of(node: roxmltree::Node) -> String {
    prefixed(node, node.tag_name().namespace(), node.tag_name().name())
}

fn attributes_of(node: roxmltree::Node) -> Vec<(String, String)> {
    node.attributes().map(|a| (prefixed(node, a.namespace(), a.name()), a.value().to_string())).collect()
}

/// The text to hand roxmltree for MaterialX text that strict parsing refused with `error`,
/// found by repairing and retrying `parse`: each undeclared prefix (MaterialX's `ns:name`
/// categories, read by pugixml as plain names) is declared on the root element with a private
/// URI, and a raw `<` inside attribute values (`value="grid.<UDIM>.png"`, also accepted by
/// pugixml) is escaped. Declarations go right after `<materialx`, so lines never move (columns
/// on the root's own line do; so do columns on lines with an escaped `<`, by 3 per escape).
/// Returns the first error that neither repair explains.
fn readable_text(text: &str, error: roxmltree::Error, parse: &dyn Fn(&str) -> Result<(), roxmltree::Error>) -> Result<String, roxmltree::Error> {
    let mut current = text.to_string();
    let mut first_error: Option<roxmltree::Error> = None;
    let mut escaped = false;
    let mut result = Err(error);
    // Each retry repairs one thing; a document cannot need more repairs than it has prefixes.
    for _ in 0..256 {
        match result {
            Ok(()) => return Ok(current),
            Err(roxmltree::Error::UnknownNamespace(prefix, pos)) => match declare_prefix(&current, &prefix) {
                Some(t) => current = t,
                None => return Err(first_error.unwrap_or(roxmltree::Error::UnknownNamespace(prefix, pos))),
            },
            Err(e) => {
                let first = first_error.get_or_insert(e).clone();
                if escaped {
                    return Err(first);
                }
                escaped = true;
                let t = escape_lt_in_attributes(&current);
                if t == current {
                    return Err(first);
                }
                current = t;
            }
        }
        result = parse(&current);
    }
    Err(first_error.unwrap_or(roxmltree::Error::NodesLimitReached))
}

/// `text` with `xmlns:prefix` declared on its `<materialx` root; `None` when there is no such
/// root or the prefix is already declared there (then the error is real).
fn declare_prefix(text: &str, prefix: &str) -> Option<String> {
    let at = text.match_indices("<materialx").map(|(i, _)| i + "<materialx".len()).find(|&i| {
        text[i..].chars().next().is_some_and(|c| c.is_whitespace() || c == '>' || c == '/')
    })?;
    let declaration = format!(" xmlns:{prefix}=\"{PREFIX_URI}{prefix}\"");
    if text[at..].split('>').next().is_some_and(|tag| tag.contains(declaration.trim_start())) {
        return None;
    }
    Some(format!("{}{declaration}{}", &text[..at], &text[at..]))
}

/// The URI under which an undeclared MaterialX name prefix is declared for the XML parser.
const PREFIX_URI: &str = "urn:uplift:materialx-prefix:";

/// Converts `node` and its element descendants under `parent`, in document order, with an
/// explicit work list: element nesting is input-sized (a document may nest 20,000 nodegraphs),
/// so it must not become call depth.
#[allow(clippy::too_many_arguments)]
fn convert(
    lines: &Lines,
    node: roxmltree::Node,
    file: &Arc<str>,
    path: &Path,
    doc: &mut Document,
    parent: ElementId,
    diags: &mut Vec<Diagnostic>,
    stack: &mut Includes,
) {
    let mut work = vec![(node, parent)];
    while let Some((node, parent)) = work.pop() {
        let pos = lines.pos(node, file);
        if is_include(node) {
            include(node, &pos, path, doc, parent, diags, stack);
            continue;
        }
        let id = doc.add_child(parent, tag_of(node), attributes_of(node), pos);
        // Reversed onto the stack, so that the first child is converted (with its subtree) first.
        let children: Vec<_> = node.children().filter(|c| c.is_element()).collect();
        work.extend(children.into_iter().rev().map(|c| (c, id)));
    }
}

/// Merges the top-level elements of an included document under `parent`, as MaterialX does:
/// elements whose name already exists are skipped, and the included root's fileprefix,
/// colorspace, geomprefix and namespace are copied onto its children that lack them.
fn include(
    node: roxmltree::Node,
    pos: &SourcePos,
    path: &Path,
    doc: &mut Document,
    parent: ElementId,
    diags: &mut Vec<Diagnostic>,
    stack: &mut Includes,
) {
    let Some(href) = node.attribute("href") else {
        diags.push(Diagnostic::error(pos.clone(), "xi:include without an `href` attribute"));
        return;
    };
    // Where the include lies (crate::file_access): beside the including file, in a search path,
    // or in the builtin library; else the file beside it (to say it cannot be read) or an error.
    let relative = stack.access.resolve(href, path, &stack.top);
    let beside = relative.as_ref().ok().filter(|t| t.is_file()).cloned();
    let searched = || stack.access.search()?.iter().find_map(|root| Some(root.join(href)).filter(|t| stack.access.contains_under(t, root) && t.is_file()));
    let target = match beside.or_else(searched) {
        Some(t) => t,
        None => match (crate::library::builtin_document(href), relative) {
            (Some((lib_path, text)), _) => {
                let name = PathBuf::from(format!("<builtin>/{lib_path}"));
                if stack.stack.contains(&name) {
                    diags.push(Diagnostic::error(pos.clone(), format!("xi:include cycle: `{href}` includes itself")));
                    return;
                }
                stack.stack.push(name.clone());
                let included = parse_text(text, &name, diags, stack);
                stack.stack.pop();
                merge_included(&included, doc, parent);
                return;
            }
            (None, Ok(t)) => t,
            (None, Err(outside)) => {
                diags.push(Diagnostic::error(pos.clone(), format!("xi:include: {outside}")));
                return;
            }
        },
    };
    let canonical = target.canonicalize().unwrap_or_else(|_| target.clone());
    if stack.stack.iter().any(|p| p.canonicalize().unwrap_or_else(|_| p.clone()) == canonical) {
        diags.push(Diagnostic::error(pos.clone(), format!("xi:include cycle: `{href}` includes itself")));
        return;
    }
    let included = read_file_inner(&target, diags, stack, Some(pos));
    merge_included(&included, doc, parent);
}

/// The top-level elements of `included` merged under `parent` (see [`include`]).
fn merge_included(included: &Document, doc: &mut Document, parent: ElementId) {
    let inc_root = included.get(included.root());
    let inherited: Vec<(String, String)> = INHERITED_ROOT_ATTRIBUTES
        .iter()
        .filter_map(|k| inc_root.attr(k).map(|v| (k.to_string(), v.to_string())))
        .collect();
    for &child in included.top_level() {
        // An included element is imported under its qualified name (`ns:name` when its
        // document or itself declares a namespace), as MaterialX's `importLibrary` does.
        let written = included.get(child).name().to_string();
        let name = if written.is_empty() { written } else { included.qualified_name(child, &written) };
        if !name.is_empty() && doc.child(parent, &name).is_some() {
            continue;
        }
        let id = doc.import_subtree(parent, included, child);
        for (k, v) in &inherited {
            if doc.get(id).attr(k).is_none() {
                doc.get_mut(id).set_attr(k, v.clone());
            }
        }
        if doc.get(id).name() != name {
            doc.get_mut(id).set_attr("name", name);
        }
    }
}

/// Replaces `<` inside quoted attribute values of tags with `&lt;`.
fn escape_lt_in_attributes(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut in_tag = false;
    let mut quote: Option<char> = None;
    let mut chars = text.chars().peekable();
    while let Some(c) = chars.next() {
        match (in_tag, quote, c) {
            (_, Some(q), '<') if in_tag && q != '\0' => out.push_str("&lt;"),
            (true, Some(q), c) if c == q => {
                quote = None;
                out.push(c);
            }
            (true, None, '"' | '\'') => {
                quote = Some(c);
                out.push(c);
            }
            (true, None, '>') => {
                in_tag = false;
                out.push(c);
            }
            (false, _, '<') => {
                in_tag = !matches!(chars.peek(), Some('!' | '?'));
                out.push(c);
            }
            _ => out.push(c),
        }
    }
    out
}

/// Line and column of the last `<tag` opened before `before` (a roxmltree position).
fn unclosed_tag(text: &str, tag: &str, before: roxmltree::TextPos) -> Option<(u32, u32)> {
    let lines: Vec<&str> = text.split('\n').collect();
    let mut offset = 0;
    for l in lines.iter().take(before.row.saturating_sub(1) as usize) {
        offset += l.len() + 1;
    }
    let needle = format!("<{tag}");
    let start = text[..offset.min(text.len())].rfind(&needle)?;
    let line = text[..start].matches('\n').count() as u32 + 1;
    let column = text[..start].rsplit('\n').next().map_or(0, |l| l.chars().count()) as u32 + 1;
    Some((line, column))
}
