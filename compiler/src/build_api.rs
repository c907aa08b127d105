//! Build-script integration, in the spirit of prost-build: compile MaterialX graphs to Rust
//! modules in `OUT_DIR`, so a crate that ships graphs carries their CPU kernels. Adding a node
//! (a nodedef plus a WGSL function under a library folder) and rebuilding is all a new node
//! needs.
//!
//! ```no_run
//! // build.rs
//! uplift_compiler::build_api::Builder::new()
//!     .graph("graphs/marble.mtlx")
//!     .compile_to_out_dir()
//!     .unwrap();
//! // src/lib.rs: include!(concat!(env!("OUT_DIR"), "/marble.rs"));
//! ```

use crate::backend_rust::{write_albedo_table_static, write_rust_kernel, write_rust_kernel_with, RustOptions};
use crate::compile::{Compiler, OutputSelection};
use crate::kernel::ClosureContext;
use std::path::{Path, PathBuf};

/// Which graphs to compile and where their nodes come from.
#[derive(Clone, Debug, Default)]
pub struct Builder {
    libraries: Vec<PathBuf>,
    graphs: Vec<(PathBuf, OutputSelection, Option<ClosureContext>)>,
    /// Indices into `graphs` of those that also get a packet kernel.
    packet: Vec<usize>,
    /// Those among `packet` whose packet kernel is only its grouped (dependence-split) form.
    grouped_only: Vec<usize>,
    albedo_table_data: Option<String>,
}

/// One kernel [`Builder::compile_kernels`] wrote.
#[derive(Clone, Debug)]
pub struct BuiltKernel {
    /// `<stem>.rs` in the output folder.
    pub file: PathBuf,
    /// [`kernel_fingerprint`] of the kernel's Rust as [`write_rust_kernel`] writes it (with its
    /// own albedo tables): what a runtime computes for the same document to find this kernel.
    pub fingerprint: u64,
}

/// One kernel [`Builder::generate`] wrote, in memory.
#[derive(Clone, Debug)]
pub struct GeneratedKernel {
    /// The module name: the document's stem, `_<context>` for a closure kernel.
    pub stem: String,
    /// The document it came from.
    pub source: PathBuf,
    pub context: Option<ClosureContext>,
    /// The Rust module (its first line names the document by `source` as given).
    pub rust: String,
    /// The packet kernel's module (`packet_kernel.rs`), for graphs added with
    /// [`Builder::packet_closure_graph`].
    pub packet: Option<String>,
    /// As [`BuiltKernel::fingerprint`].
    pub fingerprint: u64,
}

impl Builder {
    pub fn new() -> Builder {
        Builder::default()
    }

    /// Adds a library folder (nodedefs + WGSL), searched after the builtin library.
    pub fn library(mut self, dir: impl Into<PathBuf>) -> Builder {
        self.libraries.push(dir.into());
        self
    }

    /// Adds a document; every numeric output becomes part of its kernel.
    pub fn graph(mut self, path: impl Into<PathBuf>) -> Builder {
        self.graphs.push((path.into(), OutputSelection::AllNumeric, None));
        self
    }

    /// Adds a document whose one BSDF-typed output is compiled in closure `context`; the
    /// module is `<stem>_<context>.rs`.
    pub fn closure_graph(mut self, path: impl Into<PathBuf>, context: ClosureContext) -> Builder {
        self.graphs.push((path.into(), OutputSelection::AllNumeric, Some(context)));
        self
    }

    /// [`Builder::closure_graph`], also writing the kernel as packet Rust
    /// ([`crate::packet_kernel::write_packet_kernel`]; [`GeneratedKernel::packet`]).
    pub fn packet_closure_graph(mut self, path: impl Into<PathBuf>, context: ClosureContext) -> Builder {
        self.packet.push(self.graphs.len());
        self.closure_graph(path, context)
    }

    /// [`Builder::packet_closure_graph`] with only the grouped batch entry (the dependence-split
    /// passes, `packet_split.rs`): for a kernel whose scalar form beats its unsplit packet form.
    pub fn grouped_closure_graph(mut self, path: impl Into<PathBuf>, context: ClosureContext) -> Builder {
        self.grouped_only.push(self.graphs.len());
        self.packet_closure_graph(path, context)
    }

    /// Adds a document, compiling only the named outputs.
    pub fn graph_outputs(mut self, path: impl Into<PathBuf>, outputs: &[&str]) -> Builder {
        self.graphs.push((path.into(), OutputSelection::Named(outputs.iter().map(|s| s.to_string()).collect()), None));
        self
    }

    /// Kernels that read the albedo tables use the `static` at `path` (written by
    /// [`Builder::write_albedo_tables`] into a module of the same crate) instead of each holding
    /// its own copy of the array.
    pub fn shared_albedo_tables(mut self, path: impl Into<String>) -> Builder {
        self.albedo_table_data = Some(path.into());
        self
    }

    /// Writes the library's albedo tables as `pub static {name}: [f32; N]` into `file`, for
    /// [`Builder::shared_albedo_tables`].
    pub fn write_albedo_tables(&self, name: &str, file: &Path) -> Result<(), String> {
        std::fs::write(file, self.albedo_tables_source(name)?).map_err(|e| format!("{}: {e}", file.display()))
    }

    /// The text [`Builder::write_albedo_tables`] writes.
    pub fn albedo_tables_source(&self, name: &str) -> Result<String, String> {
        let compiler = Compiler::new(&self.libraries);
        let data = compiler.library.albedo_table_data.as_ref().ok_or("the library has no albedo tables (mx_albedo_table_data)")?;
        Ok(write_albedo_table_static(name, data))
    }

    /// Writes `<stem>.rs` for every graph into `out_dir`; returns the files written. Prints
    /// `cargo:rerun-if-changed` for the documents and library folders. Errors are the
    /// compiler's positioned diagnostics, one per line.
    pub fn compile(&self, out_dir: &Path) -> Result<Vec<PathBuf>, String> {
        Ok(self.compile_kernels(out_dir)?.into_iter().map(|k| k.file).collect())
    }

    /// [`Builder::compile`], also returning each kernel's fingerprint.
    pub fn compile_kernels(&self, out_dir: &Path) -> Result<Vec<BuiltKernel>, String> {
        for dir in &self.libraries {
            println!("cargo:rerun-if-changed={}", dir.display());
        }
        for (path, _, _) in &self.graphs {
            println!("cargo:rerun-if-changed={}", path.display());
        }
        let mut written = Vec::new();
        for k in self.generate()? {
            let out = out_dir.join(format!("{}.rs", k.stem));
            std::fs::write(&out, k.rust).map_err(|e| format!("{}: {e}", out.display()))?;
            written.push(BuiltKernel { file: out, fingerprint: k.fingerprint });
        }
        Ok(written)
    }

    /// Every graph's kernel as Rust text, in the order the graphs were added, without writing
    /// anything (for generated code that is committed rather than built by a build script).
    pub fn generate(&self) -> Result<Vec<GeneratedKernel>, String> {
        let compiler = Compiler::new(&self.libraries);
        if mtlx::has_errors(&compiler.library.diagnostics) {
            return Err(lines(&compiler.library.diagnostics));
        }
        let mut kernels = Vec::new();
        for (index, (path, selection, context)) in self.graphs.iter().enumerate() {
            let c = compiler.compile_file_in(path, selection, *context);
            let Some(kernel) = c.kernel.filter(|_| !mtlx::has_errors(&c.diagnostics)) else {
                let mut msg = lines(&c.diagnostics);
                if msg.is_empty() {
                    msg = format!("{}: no numeric output to compile", path.display());
                }
                return Err(msg);
            };
            let rust = write_rust_kernel(&kernel).map_err(|e| format!("{}: {e}", path.display()))?;
            let fingerprint = kernel_fingerprint(&rust);
            let rust = match &self.albedo_table_data {
                Some(p) if kernel.albedo_tables.is_some() => {
                    let options = RustOptions { albedo_table_data: Some(p.clone()), ..RustOptions::default() };
                    write_rust_kernel_with(&kernel, &options).map_err(|e| format!("{}: {e}", path.display()))?
                }
                _ => rust,
            };
            let mut stem = path.file_stem().map(|s| s.to_string_lossy().to_string()).unwrap_or_else(|| "kernel".into());
            if let Some(c) = context {
                stem = format!("{stem}_{}", c.name());
            }
            let packet = match self.packet.contains(&index) {
                true => {
                    let options = crate::backend_packet::PacketOptions { table_data: self.albedo_table_data.clone(), grouped_only: self.grouped_only.contains(&index) };
                    Some(crate::packet_kernel::write_packet_kernel(&kernel, &options).map_err(|e| format!("{} (packet kernel): {e}", path.display()))?)
                }
                false => None,
            };
            kernels.push(GeneratedKernel { stem, source: path.clone(), context: *context, rust, fingerprint, packet });
        }
        Ok(kernels)
    }

    /// `compile` into the `OUT_DIR` cargo gives build scripts.
    pub fn compile_to_out_dir(&self) -> Result<Vec<PathBuf>, String> {
        let out = std::env::var_os("OUT_DIR").ok_or("OUT_DIR is not set: call this from a build script")?;
        self.compile(Path::new(&out))
    }
}

/// A fingerprint of a generated Rust kernel (FNV-1a, 64 bits, over the text after its first
/// line, which names the source file): equal fingerprints mean the same code. The runtime uses
/// it to find a kernel it was built with.
pub fn kernel_fingerprint(rust: &str) -> u64 {
    let body = rust.split_once('\n').map_or("", |(_, rest)| rest);
    fnv1a(FNV1A_START, body.as_bytes())
}

/// FNV-1a's 64-bit offset basis: the state [`fnv1a`] starts from.
pub const FNV1A_START: u64 = 0xcbf2_9ce4_8422_2325;

/// Continues a 64-bit FNV-1a hash from state `h` over `bytes`.
pub fn fnv1a(h: u64, bytes: &[u8]) -> u64 {
    bytes.iter().fold(h, |h, b| (h ^ *b as u64).wrapping_mul(0x0000_0100_0000_01b3))
}

fn lines(diagnostics: &[mtlx::Diagnostic]) -> String {
    diagnostics.iter().filter(|d| d.is_error()).map(|d| d.to_string()).collect::<Vec<_>>().join("\n")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_one_module_per_graph_and_reports_errors() {
        let dir = std::env::temp_dir().join(format!("uplift-build-api-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let good = dir.join("good.mtlx");
        std::fs::write(&good, r#"<materialx version="1.39"><nodegraph name="g"><input name="a" type="float" value="1"/><sin name="s" type="float"><input name="in" type="float" interfacename="a"/></sin><output name="out" type="float" nodename="s"/></nodegraph></materialx>"#).unwrap();
        let files = Builder::new().graph(&good).compile(&dir).unwrap();
        assert_eq!(files, vec![dir.join("good.rs")]);
        let text = std::fs::read_to_string(&files[0]).unwrap();
        assert!(text.contains("pub fn mx_pattern_batch") && text.contains("fn mx_sin_float"), "{text}");
        let bad = dir.join("bad.mtlx");
        std::fs::write(&bad, "<materialx version=\"1.39\">\n  <nodegraph name=\"g\"><output name=\"out\" type=\"float\" nodename=\"nope\"/></nodegraph>\n</materialx>").unwrap();
        let err = Builder::new().graph(&bad).compile(&dir).unwrap_err();
        assert!(err.contains("bad.mtlx:2:") && err.contains("dangling reference"), "{err}");
    }
}
