//! A compiled kernel prepared on one engine — a CPU kernel (shipped or a built runner) or a wgpu
//! pipeline — and run there on batches. The `uplift_stack` kernels, the renderer's glint kernel
//! and its MaterialX materials' closure kernels all hold their kernels this way.

use crate::batch::{Columns, PatternBatch};
use crate::cpu_engine::{CpuEngine, CpuKernel};
use crate::wgpu_engine::{WgpuEngine, WgpuPipeline};
use uplift_compiler::PatternKernel;

/// The engine a kernel runs on.
#[derive(Clone, Copy)]
pub enum Engine<'a> {
    Cpu(&'a CpuEngine),
    Wgpu(&'a WgpuEngine),
}

impl<'a> From<&'a CpuEngine> for Engine<'a> {
    fn from(e: &'a CpuEngine) -> Self {
        Engine::Cpu(e)
    }
}

impl<'a> From<&'a WgpuEngine> for Engine<'a> {
    fn from(e: &'a WgpuEngine) -> Self {
        Engine::Wgpu(e)
    }
}

/// An engine owned by what runs kernels on it (the training-data generator, the renderer's
/// shading): the CPU engine or the wgpu engine. One or two exist per process, so the wgpu
/// engine's size is kept inline.
#[allow(clippy::large_enum_variant)]
pub enum AnyEngine {
    Cpu(CpuEngine),
    Wgpu(WgpuEngine),
}

impl AnyEngine {
    pub fn engine(&self) -> Engine<'_> {
        match self {
            AnyEngine::Cpu(e) => Engine::Cpu(e),
            AnyEngine::Wgpu(e) => Engine::Wgpu(e),
        }
    }

    /// `cpu` or `wgpu`.
    pub fn name(&self) -> &'static str {
        match self {
            AnyEngine::Cpu(_) => "cpu",
            AnyEngine::Wgpu(_) => "wgpu",
        }
    }
}

impl From<CpuEngine> for AnyEngine {
    fn from(e: CpuEngine) -> Self {
        AnyEngine::Cpu(e)
    }
}

impl From<WgpuEngine> for AnyEngine {
    fn from(e: WgpuEngine) -> Self {
        AnyEngine::Wgpu(e)
    }
}

enum Prepared {
    Cpu(CpuKernel),
    Wgpu(WgpuPipeline),
}

/// A kernel and its preparation on one engine.
pub struct PreparedKernel {
    pub kernel: PatternKernel,
    prepared: Prepared,
}

impl PreparedKernel {
    /// Prepares `kernel` on `engine` (the CPU engine finds a shipped kernel or builds a runner;
    /// wgpu compiles the pipeline).
    pub fn new(engine: Engine<'_>, kernel: PatternKernel) -> Result<PreparedKernel, String> {
        let prepared = match engine {
            Engine::Cpu(e) => Prepared::Cpu(e.prepare(&kernel)?),
            Engine::Wgpu(e) => {
                crate::batch::check_build_size(&kernel)?;
                Prepared::Wgpu(e.prepare(&kernel))
            }
        };
        Ok(PreparedKernel { kernel, prepared })
    }

    /// Prepares `kernels` on `engine` together: on the CPU engine the ones not shipped build in
    /// one runner (`CpuEngine::prepare_all`).
    pub fn all(engine: Engine<'_>, kernels: Vec<PatternKernel>, albedo_tables: Option<&[f32]>) -> Result<Vec<PreparedKernel>, String> {
        match engine {
            Engine::Cpu(e) => {
                let prepared = e.prepare_all(&kernels.iter().collect::<Vec<_>>(), albedo_tables)?;
                Ok(kernels.into_iter().zip(prepared).map(|(kernel, p)| PreparedKernel { kernel, prepared: Prepared::Cpu(p) }).collect())
            }
            Engine::Wgpu(_) => kernels.into_iter().map(|k| PreparedKernel::new(engine, k)).collect(),
        }
    }

    /// Where the kernel comes from (shipped or built; or the wgpu engine).
    pub fn describe(&self) -> String {
        match &self.prepared {
            Prepared::Cpu(k) => k.describe(),
            Prepared::Wgpu(_) => "the wgpu engine (generated WGSL)".into(),
        }
    }

    /// Runs the kernel on `batch`; `engine` must be the one it was prepared on.
    pub fn run(&self, engine: Engine<'_>, batch: &PatternBatch) -> Result<Columns, String> {
        match (&self.prepared, engine) {
            (Prepared::Cpu(k), Engine::Cpu(e)) => e.run_prepared(k, batch),
            (Prepared::Wgpu(p), Engine::Wgpu(e)) => e.run_prepared(p, batch),
            _ => Err("a kernel run on another engine than it was prepared on".into()),
        }
    }

    /// The wgpu pipeline, when prepared on the wgpu engine.
    pub fn wgpu_pipeline(&self) -> Option<&WgpuPipeline> {
        match &self.prepared {
            Prepared::Wgpu(p) => Some(p),
            Prepared::Cpu(_) => None,
        }
    }

    /// The offset of the output named `name` in an output row.
    pub fn output_offset(&self, name: &str) -> Option<usize> {
        self.kernel.outputs.iter().find(|o| o.name == name).map(|o| o.offset)
    }
}
