//! The `uplift_stack` closure kernels (for the builtin stack runtime/kernels/graphs/bsdf/uplift_stack.mtlx,
//! shipped as CPU kernels in every closure context; for a `--stack` library the document
//! [`Stack::kernel_document`] generates): one prepared kernel per context, on the CPU engine or
//! the wgpu engine, run on rows of the stack's parameters (`Stack::parameters` order)
//! with per-row directions in the local frame (normal +z). The training-data generator, the
//! renderer's reference material and the white furnace check evaluate the stack through it.

use crate::batch::{Columns, Geometry, PatternBatch};
use crate::cpu_engine::CpuEngine;
pub use crate::prepared_kernel::Engine;
use crate::prepared_kernel::PreparedKernel;
use crate::stack::Stack;
use std::sync::Arc;
use uplift_compiler::{ClosureContext, OutputSelection};

/// One closure context of the stack, prepared on an engine.
pub struct StackKernel {
    prepared: PreparedKernel,
    stack: Arc<Stack>,
    /// Each parameter's input column.
    columns: Vec<usize>,
}

impl StackKernel {
    /// The kernel on the CPU engine.
    pub fn new(engine: &CpuEngine, stack: &Arc<Stack>, context: ClosureContext) -> Result<StackKernel, String> {
        Self::on(Engine::Cpu(engine), stack, context)
    }

    /// The kernel on either engine.
    pub fn on(engine: Engine<'_>, stack: &Arc<Stack>, context: ClosureContext) -> Result<StackKernel, String> {
        Ok(Self::contexts(engine, stack, &[context])?.remove(0))
    }

    /// The kernels of several contexts, prepared together: on the CPU engine, a stack whose
    /// kernels are not shipped (`--stack`) builds them in one runner.
    pub fn contexts(engine: Engine<'_>, stack: &Arc<Stack>, contexts: &[ClosureContext]) -> Result<Vec<StackKernel>, String> {
        let (source, text) = stack.kernel_document();
        let mut kernels = Vec::new();
        for &context in contexts {
            let (doc, diags) = mtlx::read_str(&text, &source);
            let c = stack.compiler().compile_document_in(doc, diags, &source, &OutputSelection::AllNumeric, Some(context));
            kernels.push(c.kernel.ok_or_else(|| c.diagnostics.iter().map(|d| d.to_string()).collect::<Vec<_>>().join("\n"))?);
        }
        let mut columns_of = Vec::new();
        for kernel in &kernels {
            let mut columns = Vec::with_capacity(stack.len());
            for p in stack.parameters() {
                let input = kernel.inputs.iter().find(|i| i.input.name == p.input).ok_or_else(|| format!("{source}: the uplift_stack kernel has no input `{}`", p.input))?;
                columns.push(input.offset + p.component);
            }
            columns_of.push(columns);
        }
        let tables = stack.compiler().library.albedo_table_data.clone();
        let prepared = PreparedKernel::all(engine, kernels, tables.as_deref())?;
        Ok(prepared.into_iter().zip(columns_of).map(|(prepared, columns)| StackKernel { prepared, stack: stack.clone(), columns }).collect())
    }

    /// The stack this kernel shades.
    pub fn stack(&self) -> &Arc<Stack> {
        &self.stack
    }

    /// Where the kernel comes from (shipped or built; or the wgpu engine).
    pub fn describe(&self) -> String {
        self.prepared.describe()
    }

    /// The kernel as prepared (its pipeline on the wgpu engine; its input and output strides).
    pub fn prepared(&self) -> &PreparedKernel {
        &self.prepared
    }

    /// Each stack parameter's input column (`Stack::parameters` order).
    pub fn parameter_columns(&self) -> &[usize] {
        &self.columns
    }

    /// The first input column of direction input `name` (`wv`, `wl`, `u`).
    pub fn input_offset(&self, name: &str) -> usize {
        self.prepared.kernel.inputs.iter().find(|i| i.input.name == name).unwrap_or_else(|| panic!("uplift_stack kernel has no input `{name}`")).offset
    }

    /// The first column of output `name` (`response`, `throughput`, `albedo`, `wl`, `pdf`).
    pub fn output_offset(&self, name: &str) -> usize {
        self.prepared.output_offset(name).unwrap_or_else(|| panic!("uplift_stack kernel has no output `{name}`"))
    }

    /// Runs the kernel on `rows` (indices into `params`, rows × the stack's parameters) with per-row directions
    /// (`wv`, `wl` or `u`, indexed like `params`).
    pub fn run<'e>(&self, engine: impl Into<Engine<'e>>, params: &[f32], rows: &[usize], directions: &[(&str, &[[f32; 3]])]) -> Result<Columns, String> {
        self.run_on(engine.into(), params, rows, directions)
    }

    /// [`run`](Self::run) on a grouped batch (`PatternBatch::points_per_group`): runs of
    /// `per_group` consecutive entries of `rows` share their parameters and `wv` (the caller's
    /// promise), so the CPU engine runs the kernel's dependence-split form where it ships one.
    pub fn run_grouped<'e>(&self, engine: impl Into<Engine<'e>>, params: &[f32], rows: &[usize], directions: &[(&str, &[[f32; 3]])], per_group: usize) -> Result<Columns, String> {
        self.run_layout(engine.into(), params, rows, directions, per_group)
    }

    /// [`run`](Self::run) on the engine the kernel was prepared on (`engine` must be it).
    pub fn run_on(&self, engine: Engine<'_>, params: &[f32], rows: &[usize], directions: &[(&str, &[[f32; 3]])]) -> Result<Columns, String> {
        self.run_layout(engine, params, rows, directions, 1)
    }

    fn run_layout(&self, engine: Engine<'_>, params: &[f32], rows: &[usize], directions: &[(&str, &[[f32; 3]])], per_group: usize) -> Result<Columns, String> {
        let n = rows.len();
        let mut inputs = Columns::zeros(n, self.prepared.kernel.input_stride);
        for (name, dirs) in directions {
            let at = self.input_offset(name);
            for c in 0..3 {
                let col = inputs.column_mut(at + c);
                for (x, &r) in col.iter_mut().zip(rows) {
                    *x = dirs[r][c];
                }
            }
        }
        let stride = self.stack.len();
        for (k, &at) in self.columns.iter().enumerate() {
            let col = inputs.column_mut(at);
            for (x, &r) in col.iter_mut().zip(rows) {
                *x = params[r * stride + k];
            }
        }
        // The local frame for every row: uniform columns, not streamed from memory.
        let geometry = Geometry::default().repeated(n);
        let batch = PatternBatch { geometry, inputs, textures: vec![], points_per_group: per_group };
        self.prepared.run(engine, &batch)
    }
}

/// A `sample` kernel's direction `wl` with its `pdf`, normalised, when the sample is usable:
/// pdf positive and finite, wl a unit vector (within 1e-3) with cosine above `min_mu`.
pub fn usable_sample(wl: [f32; 3], pdf: f32, min_mu: f32) -> Option<[f32; 3]> {
    let len = (wl[0] * wl[0] + wl[1] * wl[1] + wl[2] * wl[2]).sqrt();
    (pdf > 0.0 && pdf.is_finite() && wl[2] > min_mu && (len - 1.0).abs() < 1e-3).then(|| wl.map(|x| x / len))
}

/// Three consecutive columns of `out` at row `k`.
pub fn vec3_at(out: &Columns, at: usize, k: usize) -> [f32; 3] {
    [0, 1, 2].map(|c| out.column(at + c)[k])
}
