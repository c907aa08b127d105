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

/// Invocations per workgroup of `mx_main`.
pub const WORKGROUP_SIZE: u32 = 64;

/// The name of the compute entry point.
pub const ENTRY_POINT: &str = "mx_main";

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
}
