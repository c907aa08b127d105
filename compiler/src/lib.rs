//! uplift's compiler: MaterialX documents (through the `mtlx` crate) become a typed graph IR
//! (`ir`, built by `graph_builder` against the indexed `node_library`), which is lowered
//! (`lower`, askama templates in `templates/`) to WGSL text, parsed once by naga, validated,
//! compacted and emitted: as WGSL by naga's writer, and as Rust by `backend_rust` (from the
//! same naga module). This crate never touches wgpu, reads textures or runs kernels.

pub mod arena;
pub mod backend_neural;
pub mod backend_packet;
pub mod packet_guards;
pub mod packet_kernel;
pub mod packet_split;
pub mod backend_rust;
pub mod build_api;
pub mod compile;
pub mod closure_fold;
pub mod const_eval;
pub mod fuzz_entry;
pub mod fuzz_stable;
pub mod graph_builder;
pub mod ir;
pub mod kernel;
pub mod lower;
pub mod naga_import;
pub mod node_library;
pub mod variance;
pub mod wgsl_items;
pub mod wgsl_types;

pub use compile::{Compilation, Compiler, OutputSelection};
pub use kernel::{ClosureContext, PatternKernel};
