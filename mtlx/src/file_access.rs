//! The one containment rule for every file an input names — a MaterialX texture or `fileprefix`,
//! an `xi:include`, a glTF image or buffer URI: the name resolves relative to the folder of the
//! file that names it (URIs percent-decoded first; `data:` URIs never touch the file system) and
//! is accepted only inside the top input's folder or a search path (`--library`,
//! `MATERIALX_SEARCH_PATH`), unless the user allows any path (`--allow-any-path`).
//!
//! Containment is decided on the path the operating system would open, without asking whether
//! the file itself exists: the existing part of the path is canonicalised (symbolic links and `..`
//! resolved), the rest is appended lexically. So a name outside gets the same message whether or
//! not a file is there, and no message holds a byte of any file (it names only what the input
//! wrote).

use percent_encoding::percent_decode_str;
use std::path::{Component, Path, PathBuf};

/// Where the files an input names may lie.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FileAccess {
    /// Folders besides the top input's own; `None`: anywhere (`--allow-any-path`).
    search: Option<Vec<PathBuf>>,
}

/// A name that resolves outside the allowed folders. Its message names the file as the input
/// wrote it, nothing the file system said.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct OutsideInput {
    pub name: String,
}

impl std::fmt::Display for OutsideInput {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "`{}` lies outside the input's folder and the library search paths (--library, MATERIALX_SEARCH_PATH); pass --allow-any-path to read it", self.name)
    }
}

impl std::error::Error for OutsideInput {}

/// What a URI names: the text after `data:` (the caller decodes it), or a file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum UriTarget<'u> {
    Data(&'u str),
    File(PathBuf),
}

impl Default for FileAccess {
    /// The top input's folder only.
    fn default() -> Self {
        FileAccess::within(Vec::new())
    }
}

impl FileAccess {
    /// Files anywhere (`--allow-any-path`).
    pub fn any() -> FileAccess {
        FileAccess { search: None }
    }

    /// Files in the top input's folder or one of `search` (and what lies below them).
    pub fn within(search: Vec<PathBuf>) -> FileAccess {
        FileAccess { search: Some(search) }
    }

    /// The search folders of library folders `dirs`: `dirs`, then `MATERIALX_SEARCH_PATH`, then
    /// the parent of each of those named `libraries` (where a MaterialX install keeps
    /// `resources/`).
    pub fn library_roots(dirs: &[PathBuf]) -> Vec<PathBuf> {
        let mut roots: Vec<PathBuf> = dirs.iter().cloned().chain(crate::library::search_path_from_env()).collect();
        let parents: Vec<PathBuf> = roots.iter().filter(|r| r.file_name().is_some_and(|n| n == "libraries")).filter_map(|r| r.parent().map(Path::to_path_buf)).collect();
        roots.extend(parents);
        roots
    }

    /// [`FileAccess::within`] the library roots of `dirs`, or [`FileAccess::any`].
    pub fn for_libraries(dirs: &[PathBuf], allow_any_path: bool) -> FileAccess {
        if allow_any_path {
            FileAccess::any()
        } else {
            FileAccess::within(Self::library_roots(dirs))
        }
    }

    /// Whether every path is allowed.
    pub fn allows_any(&self) -> bool {
        self.search.is_none()
    }

    /// The search folders (`None` with any path allowed).
    pub fn search(&self) -> Option<&[PathBuf]> {
        self.search.as_deref()
    }

    /// `name` as named by the file `naming_file`, read for the top input `top_input`: the path to
    /// open, or an error when it lies outside. Whether the file exists is not looked at.
    pub fn resolve(&self, name: &str, naming_file: &Path, top_input: &Path) -> Result<PathBuf, OutsideInput> {
        let path = folder_of(naming_file).join(name);
        match self.contains(&path, top_input) {
            true => Ok(path),
            false => Err(OutsideInput { name: name.to_string() }),
        }
    }

    /// A URI (glTF's `uri`) as named by `naming_file`: `data:` URIs as they are, anything else
    /// percent-decoded and resolved as [`FileAccess::resolve`] does.
    pub fn resolve_uri<'u>(&self, uri: &'u str, naming_file: &Path, top_input: &Path) -> Result<UriTarget<'u>, OutsideInput> {
        if let Some(data) = uri.strip_prefix("data:") {
            return Ok(UriTarget::Data(data));
        }
        let decoded = percent_decode_str(uri).decode_utf8_lossy();
        self.resolve(&decoded, naming_file, top_input).map(UriTarget::File).map_err(|_| OutsideInput { name: uri.to_string() })
    }

    /// Whether `path` lies in the top input's folder or a search folder (always, with any path
    /// allowed).
    pub fn contains(&self, path: &Path, top_input: &Path) -> bool {
        let Some(search) = &self.search else { return true };
        let target = opened_path(path);
        std::iter::once(folder_of(top_input)).chain(search.iter().map(PathBuf::as_path)).filter_map(|r| r.canonicalize().ok()).any(|r| target.starts_with(r))
    }

    /// Whether `path` lies under `root` (and is allowed at all).
    pub fn contains_under(&self, path: &Path, root: &Path) -> bool {
        self.search.is_none() || root.canonicalize().is_ok_and(|r| opened_path(path).starts_with(r))
    }
}

/// The folder of a file (`.` for a bare file name).
pub fn folder_of(file: &Path) -> &Path {
    file.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."))
}

/// The absolute path the operating system would open for `path`: each leading component that
/// exists is canonicalised (links followed, so `..` after a link means what the OS makes of it);
/// from the first one that does not exist on, components are applied lexically. A link that
/// cannot be followed (dangling, or a loop) gives a path that no folder contains.
fn opened_path(path: &Path) -> PathBuf {
    let mut at = match path.is_absolute() {
        true => PathBuf::new(),
        false => std::env::current_dir().unwrap_or_default(),
    };
    let mut exists = true;
    for c in path.components() {
        match c {
            Component::Prefix(_) | Component::RootDir => {
                at.push(c.as_os_str());
                exists = true;
            }
            Component::CurDir => {}
            Component::ParentDir => {
                at.pop();
            }
            Component::Normal(part) => {
                let next = at.join(part);
                if exists {
                    match next.canonicalize() {
                        Ok(real) => {
                            at = real;
                            continue;
                        }
                        Err(_) if next.symlink_metadata().is_ok_and(|m| m.file_type().is_symlink()) => return PathBuf::from("\0unresolvable link"),
                        Err(_) => exists = false,
                    }
                }
                at = next;
            }
        }
    }
    at
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("uplift_file_access_{name}_{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(d.join("input/sub")).unwrap();
        std::fs::write(d.join("outside.png"), b"secret").unwrap();
        std::fs::write(d.join("input/inside.png"), b"ok").unwrap();
        d
    }

    #[test]
    fn names_inside_the_folder_resolve_and_outside_ones_are_refused_alike() {
        let d = temp("rule");
        let top = d.join("input/doc.mtlx");
        let access = FileAccess::default();
        assert_eq!(access.resolve("inside.png", &top, &top).unwrap(), d.join("input/inside.png"));
        assert_eq!(access.resolve("../inside.png", &d.join("input/sub/x.mtlx"), &top).unwrap(), d.join("input/sub/../inside.png"));
        // Inside but missing: allowed (the reader then says it is not found).
        assert!(access.resolve("sub/missing.png", &top, &top).is_ok());
        let existing = access.resolve("../outside.png", &top, &top).unwrap_err();
        let missing = access.resolve("../missing.png", &top, &top).unwrap_err();
        assert_eq!(existing.to_string().replace("../outside.png", "NAME"), missing.to_string().replace("../missing.png", "NAME"));
        assert!(existing.to_string().contains("--allow-any-path") && !existing.to_string().contains("secret"));
        let absolute = d.join("outside.png").display().to_string();
        assert!(access.resolve(&absolute, &top, &top).is_err());
        assert!(access.resolve("sub/../../outside.png", &top, &top).is_err());
        assert!(access.resolve("missing/../../outside.png", &top, &top).is_err());
        assert!(FileAccess::any().resolve("../outside.png", &top, &top).is_ok());
        // A search folder admits what lies below it.
        assert!(FileAccess::within(vec![d.clone()]).resolve("../outside.png", &top, &top).is_ok());
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn uris_are_percent_decoded_and_data_uris_pass() {
        let d = temp("uri");
        let top = d.join("input/a.gltf");
        let access = FileAccess::default();
        assert_eq!(access.resolve_uri("data:image/png;base64,AAAA", &top, &top).unwrap(), UriTarget::Data("image/png;base64,AAAA"));
        assert_eq!(access.resolve_uri("in%73ide.png", &top, &top).unwrap(), UriTarget::File(d.join("input/inside.png")));
        let e = access.resolve_uri("..%2Foutside.png", &top, &top).unwrap_err();
        assert_eq!(e.name, "..%2Foutside.png");
        assert!(access.resolve_uri("%2E%2E/outside.png", &top, &top).is_err());
        let _ = std::fs::remove_dir_all(&d);
    }

    #[cfg(unix)]
    #[test]
    fn links_are_followed_before_the_check() {
        let d = temp("link");
        let top = d.join("input/doc.mtlx");
        std::os::unix::fs::symlink(&d, d.join("input/up")).unwrap();
        std::os::unix::fs::symlink(d.join("nowhere"), d.join("input/dangling.png")).unwrap();
        let access = FileAccess::default();
        assert!(access.resolve("up/outside.png", &top, &top).is_err());
        assert!(access.resolve("up/missing.png", &top, &top).is_err());
        assert!(access.resolve("dangling.png", &top, &top).is_err());
        assert!(access.resolve("up/input/inside.png", &top, &top).is_ok());
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn the_reader_refuses_includes_outside_alike_and_finds_library_documents() {
        let d = temp("include");
        std::fs::write(d.join("outside.mtlx"), r#"<materialx version="1.39"><constant name="c" type="float"/></materialx>"#).unwrap();
        let top = d.join("input/doc.mtlx");
        let read = |href: &str, access: &FileAccess| {
            std::fs::write(&top, format!(r#"<materialx version="1.39"><xi:include href="{href}"/></materialx>"#)).unwrap();
            crate::reader::read_file_with(&top, access)
        };
        let (_, existing) = read("../outside.mtlx", &FileAccess::default());
        let (_, missing) = read("../missing.mtlx", &FileAccess::default());
        assert_eq!(existing.len(), 1);
        assert_eq!(existing[0].to_string().replace("outside.mtlx", "N"), missing[0].to_string().replace("missing.mtlx", "N"));
        assert!(existing[0].to_string().contains("doc.mtlx:1:") && existing[0].is_error(), "{}", existing[0]);
        let (doc, diags) = read("../outside.mtlx", &FileAccess::any());
        assert!(diags.is_empty() && doc.top_level().len() == 1);
        // A library document, named as MaterialX names it or through `libraries/`, from any folder.
        for href in ["uplift/uplift_defs.mtlx", "../../../mtlx/libraries/uplift/uplift_defs.mtlx"] {
            let (doc, diags) = read(href, &FileAccess::default());
            assert!(diags.is_empty(), "{href}: {diags:?}");
            assert!(doc.top_level().iter().any(|&c| doc.get(c).name() == "ND_uplift_stack"), "{href}");
        }
        let _ = std::fs::remove_dir_all(&d);
    }
}
