//! The node library as loaded files: MaterialX documents (nodedefs, nodegraphs) and WGSL
//! sources. The project's own library (`mtlx/libraries/`) is embedded in the crate; more
//! folders come from `--library DIR` or `MATERIALX_SEARCH_PATH` (a MaterialX install's
//! `libraries/`). Earlier sources win when two define the same name.

use crate::diagnostic::Diagnostic;
use crate::document::Document;
use crate::reader::read_str;
use std::path::{Path, PathBuf};

include!(concat!(env!("OUT_DIR"), "/builtin_library.rs"));

/// A WGSL source file of the library.
#[derive(Clone, Debug)]
pub struct WgslSource {
    /// Where it came from (`<builtin>/stdlib/wgsl/math.wgsl` for embedded files).
    pub path: String,
    pub text: String,
}

/// All library files, in search order (builtin first).
#[derive(Clone, Debug, Default)]
pub struct Library {
    pub documents: Vec<Document>,
    pub wgsl: Vec<WgslSource>,
    pub diagnostics: Vec<Diagnostic>,
}

/// The environment variable naming extra library folders, separated by `:` or `;`.
pub const SEARCH_PATH_VAR: &str = "MATERIALX_SEARCH_PATH";

impl Library {
    /// The library embedded in this crate (`mtlx/libraries/`).
    pub fn builtin() -> Library {
        let mut lib = Library::default();
        for (path, text) in BUILTIN_FILES {
            let name = format!("<builtin>/{path}");
            if path.ends_with(".mtlx") {
                let (doc, diags) = read_str(text, &name);
                lib.documents.push(doc);
                lib.diagnostics.extend(diags);
            } else {
                lib.wgsl.push(WgslSource { path: name, text: text.to_string() });
            }
        }
        lib
    }

    /// The builtin library plus every folder in `dirs`, then every folder in
    /// `MATERIALX_SEARCH_PATH`.
    pub fn load(dirs: &[PathBuf]) -> Library {
        let mut lib = Library::builtin();
        for d in dirs {
            lib.add_dir(d);
        }
        for d in search_path_from_env() {
            lib.add_dir(&d);
        }
        lib
    }

    /// Every folder in `overrides` first — their definitions win over the builtin ones of the
    /// same name (a redefined `uplift_stack`, `--stack DIR`) — then the builtin library, then
    /// every folder in `MATERIALX_SEARCH_PATH`.
    pub fn load_overriding(overrides: &[PathBuf]) -> Library {
        let mut lib = Library::default();
        for d in overrides {
            lib.add_dir(d);
        }
        let builtin = Library::builtin();
        lib.documents.extend(builtin.documents);
        lib.wgsl.extend(builtin.wgsl);
        lib.diagnostics.extend(builtin.diagnostics);
        for d in search_path_from_env() {
            lib.add_dir(&d);
        }
        lib
    }

    /// Adds every `.mtlx` and `.wgsl` file under `dir` (recursively, sorted by path).
    pub fn add_dir(&mut self, dir: &Path) {
        for f in files_under(dir) {
            match f.extension().and_then(|e| e.to_str()) {
                Some("mtlx") => {
                    // A library file may include what lies in its library folder.
                    let (doc, diags) = crate::reader::read_file_with(&f, &crate::FileAccess::within(vec![dir.to_path_buf()]));
                    self.documents.push(doc);
                    self.diagnostics.extend(diags);
                }
                Some("wgsl") => match std::fs::read_to_string(&f) {
                    Ok(text) => self.wgsl.push(WgslSource { path: f.display().to_string(), text }),
                    Err(e) => self.diagnostics.push(Diagnostic::error(
                        crate::SourcePos::new(f.display().to_string().into(), 0, 0),
                        format!("cannot read library file: {e}"),
                    )),
                },
                _ => {}
            }
        }
    }
}

/// The builtin library document an include names, as `(path under libraries/, text)`: `href`'s
/// path itself (`uplift/uplift_defs.mtlx`, as MaterialX names library files relative to its
/// search path) or what follows its last `libraries/` (`../../mtlx/libraries/uplift/uplift_defs.mtlx`,
/// as a rule written in the repository names it).
pub fn builtin_document(href: &str) -> Option<(&'static str, &'static str)> {
    let parts: Vec<&str> = href.split(['/', '\\']).filter(|p| !p.is_empty() && *p != ".").collect();
    let start = parts.iter().rposition(|p| *p == "libraries").map_or(0, |i| i + 1);
    let tail = parts[start..].join("/");
    BUILTIN_FILES.iter().find(|(path, _)| path.ends_with(".mtlx") && *path == tail).copied()
}

/// Folders named by `MATERIALX_SEARCH_PATH`.
pub fn search_path_from_env() -> Vec<PathBuf> {
    std::env::var(SEARCH_PATH_VAR)
        .map(|v| v.split([':', ';']).filter(|s| !s.is_empty()).map(PathBuf::from).collect())
        .unwrap_or_default()
}

/// Every file under `dir`, recursively, in sorted path order (nothing for a folder that cannot be
/// read). The library loader and the tests that walk document folders share it.
pub fn files_under(dir: &Path) -> Vec<PathBuf> {
    let mut files = Vec::new();
    collect_files(dir, &mut files);
    files
}

fn collect_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(rd) = std::fs::read_dir(dir) else { return };
    let mut entries: Vec<PathBuf> = rd.filter_map(|e| e.ok().map(|e| e.path())).collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            collect_files(&p, out);
        } else {
            out.push(p);
        }
    }
}
