//! The compiler's front door: load the library once, then compile documents (read → graph IR
//! → WGSL pattern kernel) and report positioned diagnostics.

use crate::graph_builder::{document_outputs, GraphBuilder, OutputRef};
use crate::ir::Graph;
use crate::kernel::{ClosureContext, PatternKernel};
use crate::lower::{lower, LowerOptions};
use crate::node_library::NodeLibrary;
use mtlx::{has_errors, Diagnostic, Document, FileAccess, Library};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// A loaded node library, reused across documents.
pub struct Compiler {
    pub library: NodeLibrary,
    /// Folders besides a document's own where the files it names may lie: the library folders
    /// given and `MATERIALX_SEARCH_PATH` (each with its parent when it is a `libraries` folder,
    /// where a MaterialX install keeps `resources/`). `None`: files may lie anywhere
    /// (`--allow-any-path`).
    pub file_roots: Option<Vec<PathBuf>>,
    /// How lowering builds naga modules (library functions imported pre-parsed by default).
    pub lower_options: LowerOptions,
    /// Interface inputs bound to constants at compile time (name, MaterialX value text): a
    /// specialised kernel without those inputs, in which what depends on them folds — a lobe
    /// whose weight becomes a constant 0 leaves the kernel (closure_fold.rs).
    pub constant_inputs: Vec<(String, String)>,
}

/// What to compile: every numeric output, or the outputs named (`graph/output` or `output`).
#[derive(Clone, Debug, Default)]
pub enum OutputSelection {
    #[default]
    AllNumeric,
    Named(Vec<String>),
}

/// The outcome of compiling one document.
pub struct Compilation {
    pub kernel: Option<PatternKernel>,
    pub graph: Option<Graph>,
    pub diagnostics: Vec<Diagnostic>,
    /// Outputs skipped because their type is a closure or shader (not a pattern output).
    pub skipped_closures: Vec<String>,
}

impl Compiler {
    /// Loads the builtin library plus `extra` folders and `MATERIALX_SEARCH_PATH`.
    pub fn new(extra: &[PathBuf]) -> Compiler {
        Self::with_library(Library::load(extra), extra)
    }

    /// The library with `overrides` loaded before the builtin one, so that their definitions
    /// win over builtin ones of the same name (`Library::load_overriding`; the runtime's
    /// `--stack DIR`).
    pub fn overriding(overrides: &[PathBuf]) -> Compiler {
        Self::with_library(Library::load_overriding(overrides), overrides)
    }

    /// A compiler over `library`, loaded from the folders `dirs` (and the builtin library): files
    /// documents name may lie in those folders and `MATERIALX_SEARCH_PATH` (each with its parent
    /// when it is a `libraries` folder).
    fn with_library(library: Library, dirs: &[PathBuf]) -> Compiler {
        let roots = FileAccess::library_roots(dirs);
        Compiler { library: NodeLibrary::new(library), file_roots: Some(roots), lower_options: LowerOptions::default(), constant_inputs: Vec::new() }
    }

    /// `overrides` loaded before the builtin library (`--stack DIR`, as [`Compiler::overriding`])
    /// and `extra` folders after it (`--library DIR`, as [`Compiler::new`]).
    pub fn layered(overrides: &[PathBuf], extra: &[PathBuf]) -> Compiler {
        if overrides.is_empty() {
            return Self::new(extra);
        }
        let mut library = Library::load_overriding(overrides);
        for d in extra {
            library.add_dir(d);
        }
        let dirs: Vec<PathBuf> = overrides.iter().chain(extra).cloned().collect();
        Self::with_library(library, &dirs)
    }

    /// Where the files documents name may lie (`mtlx::file_access`): their own folder and
    /// `file_roots`, or anywhere.
    pub fn file_access(&self) -> FileAccess {
        match &self.file_roots {
            Some(roots) => FileAccess::within(roots.clone()),
            None => FileAccess::any(),
        }
    }

    /// Only the library embedded in the crate (tests, benchmarks).
    pub fn builtin() -> Compiler {
        Compiler { library: NodeLibrary::new(Library::builtin()), file_roots: Some(Vec::new()), lower_options: LowerOptions::default(), constant_inputs: Vec::new() }
    }

    /// Lets documents name files anywhere (`--allow-any-path`), not only in their own folder
    /// and the search paths.
    pub fn allow_any_path(mut self) -> Compiler {
        self.file_roots = None;
        self
    }

    /// Reads and checks a document by building exactly what `compile` builds: its pattern
    /// outputs (one kernel), and each BSDF, surfaceshader or material output on its own in the
    /// eval closure context (lowered and validated like any kernel). Returns every diagnostic,
    /// each once, in the order found.
    pub fn check_file(&self, path: &Path) -> Vec<Diagnostic> {
        let (doc, read_diags) = mtlx::read_file_with(path, &self.file_access());
        let source = path.display().to_string();
        let closures: Vec<String> = if has_errors(&read_diags) {
            Vec::new()
        } else {
            document_outputs(&doc).into_iter().filter(|o| crate::wgsl_types::is_scattering(&o.ty)).map(|o| o.name).collect()
        };
        let mut diagnostics = self.compile_document_in(doc.clone(), read_diags, &source, &OutputSelection::AllNumeric, None).diagnostics;
        if !closures.is_empty() {
            // A document of materials has no pattern output, and that is no news.
            diagnostics.retain(|d| d.is_error() || !d.message.starts_with("nothing to compile"));
        }
        for name in closures {
            for d in self.compile_document_in(doc.clone(), Vec::new(), &source, &OutputSelection::Named(vec![name]), Some(ClosureContext::Eval)).diagnostics {
                if !diagnostics.iter().any(|e| e.to_string() == d.to_string()) {
                    diagnostics.push(d);
                }
            }
        }
        diagnostics
    }

    /// The names of a document's BSDF, surfaceshader and material outputs — its renderable
    /// elements, as MaterialX's `generateshader.py` finds them — in document order (none when
    /// the document cannot be read; compiling it reports why).
    pub fn renderable_outputs(&self, path: &Path) -> Vec<String> {
        let (doc, diags) = mtlx::read_file_with(path, &self.file_access());
        if has_errors(&diags) {
            return Vec::new();
        }
        document_outputs(&doc).into_iter().filter(|o| crate::wgsl_types::is_scattering(&o.ty)).map(|o| o.name).collect()
    }

    pub fn compile_file(&self, path: &Path, selection: &OutputSelection) -> Compilation {
        self.compile_file_in(path, selection, None)
    }

    /// Compiles a document's pattern outputs (`context` None) or its one selected BSDF-typed
    /// output in a closure context.
    pub fn compile_file_in(&self, path: &Path, selection: &OutputSelection, context: Option<ClosureContext>) -> Compilation {
        let (doc, diags) = mtlx::read_file_with(path, &self.file_access());
        self.compile_document_in(doc, diags, &path.display().to_string(), selection, context)
    }

    /// Compiles an already-read document. `read_diags` are the reader's diagnostics.
    pub fn compile_document(&self, doc: Document, read_diags: Vec<Diagnostic>, source: &str, selection: &OutputSelection) -> Compilation {
        self.compile_document_in(doc, read_diags, source, selection, None)
    }

    /// [`Compiler::compile_document`] in an optional closure context.
    pub fn compile_document_in(&self, doc: Document, read_diags: Vec<Diagnostic>, source: &str, selection: &OutputSelection, context: Option<ClosureContext>) -> Compilation {
        let mut diagnostics = read_diags;
        let fail = |diagnostics| Compilation { kernel: None, graph: None, diagnostics, skipped_closures: Vec::new() };
        if has_errors(&diagnostics) {
            return fail(diagnostics);
        }
        let all = document_outputs(&doc);
        let wanted = |o: &OutputRef| match context {
            None => o.ty.is_numeric(),
            Some(_) => crate::wgsl_types::is_scattering(&o.ty),
        };
        let chosen: Vec<OutputRef> = match selection {
            OutputSelection::AllNumeric => all.iter().filter(|o| wanted(o)).cloned().collect(),
            OutputSelection::Named(names) => {
                let mut v = Vec::new();
                for n in names {
                    let found: Vec<&OutputRef> = all.iter().filter(|o| &o.name == n || o.name.rsplit('/').next() == Some(n.as_str())).collect();
                    match found.as_slice() {
                        [one] => v.push((*one).clone()),
                        [] => diagnostics.push(Diagnostic::error(doc.get(doc.root()).pos.clone(), format!("no output named `{n}`; outputs: {}", all.iter().map(|o| o.name.as_str()).collect::<Vec<_>>().join(", ")))),
                        _ => diagnostics.push(Diagnostic::error(doc.get(doc.root()).pos.clone(), format!("output name `{n}` is ambiguous; write it as graph/output"))),
                    }
                }
                v
            }
        };
        for o in &all {
            let e = doc.get(o.element);
            if e.category == "output" && e.attr("type").is_none() {
                diagnostics.push(Diagnostic::error(o.pos.clone(), format!("<output> `{}` has no type", e.name())));
            }
        }
        let skipped_closures: Vec<String> = all.iter().filter(|o| !wanted(o)).map(|o| o.name.clone()).collect();
        if chosen.is_empty() {
            if !has_errors(&diagnostics) {
                let what = match context {
                    None => "no pattern (non-closure) output",
                    Some(_) => "no BSDF, surfaceshader or material output",
                };
                diagnostics.push(Diagnostic::warning(doc.get(doc.root()).pos.clone(), format!("nothing to compile: the document has {what}")));
            }
            return Compilation { kernel: None, graph: None, diagnostics, skipped_closures };
        }
        for o in &chosen {
            if !wanted(o) {
                let msg = match context {
                    None => format!("output `{}` is {}, not a pattern value (compile it with a closure context)", o.name, o.ty),
                    Some(c) => format!("output `{}` is {}, not a BSDF, surfaceshader or material for the {} context", o.name, o.ty, c.name()),
                };
                diagnostics.push(Diagnostic::error(o.pos.clone(), msg));
            }
        }
        if context.is_some() && chosen.len() > 1 && !has_errors(&diagnostics) {
            let names: Vec<&str> = chosen.iter().map(|o| o.name.as_str()).collect();
            diagnostics.push(Diagnostic::error(doc.get(doc.root()).pos.clone(), format!("a closure kernel evaluates one output; choose one of: {}", names.join(", "))));
        }
        let mut builder = GraphBuilder::new(&self.library, Arc::new(doc));
        builder.file_roots = self.file_roots.clone();
        builder.constant_inputs = self.constant_inputs.iter().cloned().collect();
        let (graph, build_diags) = builder.build(&chosen);
        diagnostics.extend(build_diags);
        if has_errors(&diagnostics) {
            return Compilation { kernel: None, graph: Some(graph), diagnostics, skipped_closures };
        }
        match lower(&self.library, graph.clone(), source, context, self.lower_options) {
            Ok(k) => Compilation { kernel: Some(k), graph: Some(graph), diagnostics, skipped_closures },
            Err(e) => {
                let pos = graph.outputs.first().map(|o| o.pos.clone()).unwrap_or_else(|| mtlx::SourcePos::synthetic(source));
                diagnostics.push(Diagnostic::error(pos, e.0));
                Compilation { kernel: None, graph: Some(graph), diagnostics, skipped_closures }
            }
        }
    }
}
