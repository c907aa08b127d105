//! A compiled pattern kernel: the validated naga Module, its WGSL text, and the interface the
//! runtime binds (buffer layouts, interface inputs, outputs, textures).

use crate::ir::{Graph, InterfaceInput, TextureBinding};
use mtlx::DataType;

/// Geometry components per point — the columns of the column-major geometry buffer: texcoord
/// (2), then position, normal and tangent, each in object and world space (3 each). Every kernel
/// buffer is column-major: component `c` of point `i` at `[c * n + i]` for a batch of `n`.
pub const GEOMETRY_STRIDE: usize = 20;

/// The first geometry column of each geometric property (bitangents are computed as
/// normal × tangent in the kernel).
pub const GEOMETRY_LAYOUT: [(crate::ir::GeomProp, usize); 7] = {
    use crate::ir::GeomProp::*;
    [(Texcoord, 0), (PositionObject, 2), (PositionWorld, 5), (NormalObject, 8), (NormalWorld, 11), (TangentObject, 14), (TangentWorld, 17)]
};

/// Binding numbers of the kernel's resources (group 0).
pub const BINDING_GEOMETRY: u32 = 0;
pub const BINDING_INPUTS: u32 = 1;
pub const BINDING_OUTPUTS: u32 = 2;
pub const BINDING_PARAMS: u32 = 3;
pub const BINDING_FIRST_TEXTURE: u32 = 4;
/// The pbrlib albedo tables (a read-only storage buffer of f32), for kernels that read them.
pub const BINDING_ALBEDO_TABLES: u32 = 100;

/// Invocations per workgroup of `mx_main`.
pub const WORKGROUP_SIZE: u32 = 64;

/// The name of the compute entry point.
pub const ENTRY_POINT: &str = "mx_main";

/// The closure context a BSDF-typed output (BSDF, surfaceshader, material) is compiled for
/// (mtlx/libraries/pbrlib/wgsl/closure.wgsl). The kernel reads its directions as the first
/// interface inputs and writes the context's outputs instead of the closure value.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ClosureContext {
    /// inputs wv, wl → response = f·cos θl, throughput.
    Eval,
    /// input wv → albedo = ∫ f cos dωl, throughput.
    Albedo,
    /// inputs wv, u (three uniforms) → wl, pdf, and response and throughput at wl.
    Sample,
    /// inputs wv, wl → the pdf with which the sample context draws wl, response, throughput.
    Pdf,
}

impl ClosureContext {
    pub const ALL: [ClosureContext; 4] = [ClosureContext::Eval, ClosureContext::Albedo, ClosureContext::Sample, ClosureContext::Pdf];

    pub fn name(self) -> &'static str {
        match self {
            ClosureContext::Eval => "eval",
            ClosureContext::Albedo => "albedo",
            ClosureContext::Sample => "sample",
            ClosureContext::Pdf => "pdf",
        }
    }

    pub fn from_name(name: &str) -> Option<ClosureContext> {
        Self::ALL.into_iter().find(|c| c.name() == name)
    }

    /// The direction (and random-number) inputs, in kernel order, before the graph's own.
    pub fn direction_inputs(self) -> &'static [&'static str] {
        match self {
            ClosureContext::Eval => &["wv", "wl"],
            ClosureContext::Albedo => &["wv"],
            ClosureContext::Sample => &["wv", "u"],
            ClosureContext::Pdf => &["wv", "wl"],
        }
    }

    /// The outputs, in kernel order: (name, type).
    pub fn outputs(self) -> Vec<(&'static str, DataType)> {
        match self {
            ClosureContext::Eval => vec![("response", DataType::Color3), ("throughput", DataType::Color3)],
            ClosureContext::Albedo => vec![("albedo", DataType::Color3), ("throughput", DataType::Color3)],
            ClosureContext::Sample => vec![("wl", DataType::Vector3), ("pdf", DataType::Float), ("response", DataType::Color3), ("throughput", DataType::Color3)],
            ClosureContext::Pdf => vec![("pdf", DataType::Float), ("response", DataType::Color3), ("throughput", DataType::Color3)],
        }
    }
}

/// One output of the kernel and where its components sit in an output row.
#[derive(Clone, Debug)]
pub struct KernelOutput {
    pub name: String,
    pub ty: DataType,
    pub offset: usize,
}

/// One interface input and where its components sit in an input row.
#[derive(Clone, Debug)]
pub struct KernelInput {
    pub input: InterfaceInput,
    pub offset: usize,
}

/// The result of compiling a graph.
#[derive(Debug)]
pub struct PatternKernel {
    pub graph: Graph,
    pub module: naga::Module,
    pub info: naga::valid::ModuleInfo,
    /// WGSL written by naga's writer, with a header line naming the template.
    pub wgsl: String,
    pub inputs: Vec<KernelInput>,
    pub input_stride: usize,
    pub outputs: Vec<KernelOutput>,
    pub output_stride: usize,
    pub textures: Vec<TextureBinding>,
    /// The closure context of a BSDF-typed output; `None` for pattern outputs.
    pub context: Option<ClosureContext>,
    /// For kernels that read the albedo tables: the module the Rust backend translates, which
    /// reads them from the library's constant array (`module` reads the storage buffer at
    /// [`BINDING_ALBEDO_TABLES`]).
    pub cpu_module: Option<(naga::Module, naga::valid::ModuleInfo)>,
    /// The albedo-table data the GPU kernel's storage buffer must hold.
    pub albedo_tables: Option<std::sync::Arc<[f32]>>,
}

impl PatternKernel {
    /// The document the kernel was compiled from, as its WGSL header names it (the generated
    /// Rust files name it too).
    pub fn source_name(&self) -> &str {
        self.wgsl.lines().next().and_then(|l| l.split(" from ").nth(1)).and_then(|l| l.strip_suffix(". Do not edit.")).unwrap_or("an unnamed document")
    }
}
