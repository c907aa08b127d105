//! Splits the library's WGSL sources into top-level items (`fn`, `struct`, `const`, `alias`),
//! records each item's dependencies on other items and each function's signature, so that
//! lowering can copy exactly the transitive closure a kernel calls, in dependency order.
//! This is a lexical scan (comments, braces, identifiers); naga does the real parsing once,
//! on the assembled kernel.

use std::collections::{HashMap, HashSet};

/// One top-level WGSL item of the library.
#[derive(Clone, Debug)]
pub struct WgslItem {
    pub name: String,
    pub kind: ItemKind,
    /// Its code with comments removed and whitespace collapsed (what kernels include).
    pub text: String,
    /// The file the item came from and the line it starts on.
    pub file: String,
    pub line: u32,
    /// Names of other library items this item mentions.
    pub deps: Vec<String>,
    /// For functions: parameter (name, type text) and return type text.
    pub signature: Option<Signature>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ItemKind {
    Function,
    Struct,
    Const,
    Alias,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Signature {
    pub params: Vec<(String, String)>,
    pub result: Option<String>,
    /// When the body is just `return <param>;`, the index of that parameter: the compiler
    /// folds such calls away.
    pub identity_of: Option<usize>,
}

/// All items of the library by name.
#[derive(Clone, Debug, Default)]
pub struct WgslItems {
    pub items: HashMap<String, WgslItem>,
    /// Item names in library order, for deterministic output.
    pub order: Vec<String>,
}

/// A library-level problem (duplicate item name, unbalanced braces).
#[derive(Clone, Debug)]
pub struct ItemError {
    pub file: String,
    pub line: u32,
    pub message: String,
}

impl WgslItems {
    /// Scans one source file and adds its items. Items whose name already exists are kept
    /// from the earlier file (an error is returned for each duplicate).
    pub fn add_source(&mut self, file: &str, text: &str) -> Vec<ItemError> {
        let mut errors = Vec::new();
        for item in scan(file, text, &mut errors) {
            if let Some(prev) = self.items.get(&item.name) {
                errors.push(ItemError {
                    file: file.to_string(),
                    line: item.line,
                    message: format!("WGSL item `{}` is already defined at {}:{}", item.name, prev.file, prev.line),
                });
                continue;
            }
            self.order.push(item.name.clone());
            self.items.insert(item.name.clone(), item);
        }
        errors
    }

    /// Resolves dependencies: keeps only names that are items.
    pub fn link(&mut self) {
        let names: HashSet<String> = self.items.keys().cloned().collect();
        for item in self.items.values_mut() {
            let own = item.name.clone();
            item.deps.retain(|d| *d != own && names.contains(d));
        }
    }

    /// The items `roots` need, dependencies first, each once.
    pub fn closure(&self, roots: &[&str]) -> Vec<&WgslItem> {
        let mut out = Vec::new();
        let mut seen = HashSet::new();
        for r in roots {
            self.visit(r, &mut seen, &mut out);
        }
        out
    }

    fn visit<'a>(&'a self, name: &str, seen: &mut HashSet<String>, out: &mut Vec<&'a WgslItem>) {
        if !seen.insert(name.to_string()) {
            return;
        }
        if let Some(item) = self.items.get(name) {
            for d in &item.deps {
                self.visit(d, seen, out);
            }
            out.push(item);
        }
    }
}

/// Blanks comments (keeping newlines and byte offsets) so that braces and identifiers
/// inside comments are not seen.
fn strip_comments(text: &str) -> String {
    let b = text.as_bytes();
    let mut out = b.to_vec();
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'/' && i + 1 < b.len() && b[i + 1] == b'/' {
            while i < b.len() && b[i] != b'\n' {
                out[i] = b' ';
                i += 1;
            }
        } else if b[i] == b'/' && i + 1 < b.len() && b[i + 1] == b'*' {
            let mut depth = 0;
            while i < b.len() {
                if b[i] == b'/' && i + 1 < b.len() && b[i + 1] == b'*' {
                    depth += 1;
                    out[i] = b' ';
                    out[i + 1] = b' ';
                    i += 2;
                } else if b[i] == b'*' && i + 1 < b.len() && b[i + 1] == b'/' {
                    depth -= 1;
                    out[i] = b' ';
                    out[i + 1] = b' ';
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    if b[i] != b'\n' {
                        out[i] = b' ';
                    }
                    i += 1;
                }
            }
        } else {
            i += 1;
        }
    }
    String::from_utf8(out).unwrap_or_default()
}

/// Collapses whitespace (comments are already blanked): one space for a run within a line, one
/// newline for a run that spans lines. The kernel's parse time in naga grows with its length.
fn compact_whitespace(code: &str) -> String {
    let mut out = String::with_capacity(code.len() / 2);
    let mut pending: Option<char> = None;
    for c in code.chars() {
        if c.is_whitespace() {
            if c == '\n' || pending.is_none() {
                pending = Some(if c == '\n' { '\n' } else { ' ' });
            }
        } else {
            if let Some(p) = pending.take() {
                if !out.is_empty() {
                    out.push(p);
                }
            }
            out.push(c);
        }
    }
    out
}

fn is_ident_start(c: u8) -> bool {
    c.is_ascii_alphabetic() || c == b'_'
}

fn is_ident(c: u8) -> bool {
    c.is_ascii_alphanumeric() || c == b'_'
}

/// Identifiers in `text`.
fn identifiers(text: &str) -> Vec<&str> {
    let b = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        if is_ident_start(b[i]) && (i == 0 || !is_ident(b[i - 1])) {
            let s = i;
            while i < b.len() && is_ident(b[i]) {
                i += 1;
            }
            out.push(&text[s..i]);
        } else {
            i += 1;
        }
    }
    out
}

fn scan(file: &str, text: &str, errors: &mut Vec<ItemError>) -> Vec<WgslItem> {
    let clean = strip_comments(text);
    let b = clean.as_bytes();
    let line_starts: Vec<usize> = std::iter::once(0).chain(clean.match_indices('\n').map(|(i, _)| i + 1)).collect();
    let line_of = |pos: usize| line_starts.partition_point(|&s| s <= pos) as u32;
    let mut items = Vec::new();
    let mut i = 0;
    while i < b.len() {
        if b[i].is_ascii_whitespace() || b[i] == b';' {
            i += 1;
            continue;
        }
        // An item: optional attributes, then a keyword, a name, and a body ending at the
        // matching `}` (fn, struct) or at `;` (const, alias).
        let start = i;
        let mut depth = 0i32;
        let mut end = None;
        let mut j = i;
        let head_ids: Vec<&str>;
        {
            while j < b.len() {
                match b[j] {
                    b'{' | b'(' | b'[' => depth += 1,
                    b'}' | b')' | b']' => {
                        depth -= 1;
                        if depth == 0 && b[j] == b'}' {
                            end = Some(j + 1);
                            break;
                        }
                    }
                    b';' if depth == 0 => {
                        end = Some(j + 1);
                        break;
                    }
                    _ => {}
                }
                j += 1;
            }
            let stop = end.unwrap_or(b.len());
            head_ids = identifiers(&clean[start..stop]);
        }
        let Some(stop) = end else {
            errors.push(ItemError { file: file.into(), line: line_of(start), message: "unterminated item".into() });
            break;
        };
        let item_clean = &clean[start..stop];
        let (kind, name) = match head_ids.iter().position(|w| matches!(*w, "fn" | "struct" | "const" | "alias")) {
            Some(k) if k + 1 < head_ids.len() => {
                let kind = match head_ids[k] {
                    "fn" => ItemKind::Function,
                    "struct" => ItemKind::Struct,
                    "const" => ItemKind::Const,
                    _ => ItemKind::Alias,
                };
                (kind, head_ids[k + 1].to_string())
            }
            _ => {
                errors.push(ItemError {
                    file: file.into(),
                    line: line_of(start),
                    message: "expected `fn`, `struct`, `const` or `alias` at top level".into(),
                });
                i = stop;
                continue;
            }
        };
        let deps: Vec<String> = {
            let mut seen = HashSet::new();
            identifiers(item_clean).into_iter().filter(|w| seen.insert(*w)).map(str::to_string).collect()
        };
        let signature = (kind == ItemKind::Function).then(|| parse_signature(item_clean)).flatten();
        items.push(WgslItem {
            name,
            kind,
            text: compact_whitespace(item_clean),
            file: file.to_string(),
            line: line_of(start),
            deps,
            signature,
        });
        i = stop;
    }
    items
}

/// Splits `text` at commas that are not nested in <>, (), [].
fn split_top_level(text: &str) -> Vec<&str> {
    let mut out = Vec::new();
    let mut depth = 0i32;
    let mut s = 0;
    for (i, c) in text.char_indices() {
        match c {
            '<' | '(' | '[' => depth += 1,
            '>' | ')' | ']' => depth -= 1,
            ',' if depth == 0 => {
                out.push(&text[s..i]);
                s = i + 1;
            }
            _ => {}
        }
    }
    out.push(&text[s..]);
    out.into_iter().map(str::trim).filter(|p| !p.is_empty()).collect()
}

/// Normalises a WGSL type text: removes spaces (`vec3< f32 >` → `vec3<f32>`) and expands the
/// predeclared aliases (`vec3f` → `vec3<f32>`).
pub fn normalize_type(t: &str) -> String {
    let t: String = t.chars().filter(|c| !c.is_whitespace()).collect();
    let alias = |n: &str, s: &str| -> Option<String> {
        let rest = t.strip_prefix(n)?;
        match rest {
            "f" => Some(format!("{n}<f32>{s}")),
            "i" => Some(format!("{n}<i32>{s}")),
            "u" => Some(format!("{n}<u32>{s}")),
            _ => None,
        }
    };
    for n in ["vec2", "vec3", "vec4", "mat2x2", "mat3x3", "mat4x4"] {
        if let Some(x) = alias(n, "") {
            return x;
        }
    }
    t
}

fn parse_signature(item: &str) -> Option<Signature> {
    let open = item.find('(')?;
    let mut depth = 0;
    let mut close = None;
    for (i, c) in item[open..].char_indices() {
        match c {
            '(' => depth += 1,
            ')' => {
                depth -= 1;
                if depth == 0 {
                    close = Some(open + i);
                    break;
                }
            }
            _ => {}
        }
    }
    let close = close?;
    let params: Vec<(String, String)> = split_top_level(&item[open + 1..close])
        .into_iter()
        .filter_map(|p| {
            let (n, t) = p.split_once(':')?;
            let n = n.split_whitespace().last()?.to_string();
            Some((n, normalize_type(t)))
        })
        .collect();
    let body_start = item[close..].find('{')? + close;
    let between = item[close + 1..body_start].trim();
    let result = between.strip_prefix("->").map(|r| normalize_type(r.trim()));
    let body: Vec<&str> = identifiers(&item[body_start..]);
    let identity_of = match body.as_slice() {
        ["return", p] => {
            let compact: String = item[body_start..].chars().filter(|c| !c.is_whitespace()).collect();
            if compact == format!("{{return{p};}}") {
                params.iter().position(|(n, _)| n == p)
            } else {
                None
            }
        }
        _ => None,
    };
    Some(Signature { params, result, identity_of })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn items_signatures_and_closure() {
        let src = "// a comment with fn fake() {}\nstruct mx_s { a: f32 }\nfn mx_helper(x: vec3f) -> f32 { return x.x; }\n\
                   /* block { */ fn mx_top(a: mx_s, b: vec3<f32>) -> f32 { return mx_helper(b) + a.a; }\n\
                   fn mx_id(in1: f32) -> f32 {\n  return in1;\n}\nconst mx_k: f32 = 1.0;";
        let mut items = WgslItems::default();
        assert!(items.add_source("t.wgsl", src).is_empty());
        items.link();
        let top = &items.items["mx_top"];
        assert_eq!(top.line, 4);
        let sig = top.signature.as_ref().unwrap();
        assert_eq!(sig.params, vec![("a".into(), "mx_s".into()), ("b".into(), "vec3<f32>".into())]);
        assert_eq!(sig.result.as_deref(), Some("f32"));
        assert_eq!(sig.identity_of, None);
        assert_eq!(items.items["mx_helper"].signature.as_ref().unwrap().params[0].1, "vec3<f32>");
        assert_eq!(items.items["mx_id"].signature.as_ref().unwrap().identity_of, Some(0));
        let names: Vec<&str> = items.closure(&["mx_top"]).iter().map(|i| i.name.as_str()).collect();
        assert_eq!(names, ["mx_s", "mx_helper", "mx_top"]);
        assert_eq!(items.items["mx_k"].kind, ItemKind::Const);
    }

    #[test]
    fn duplicate_items_are_reported() {
        let mut items = WgslItems::default();
        items.add_source("a.wgsl", "fn mx_a() {}");
        let errs = items.add_source("b.wgsl", "fn mx_a() {}");
        assert_eq!(errs.len(), 1);
        assert!(errs[0].message.contains("already defined at a.wgsl:1"));
    }
}
