//! Decoder inference: rows of [latent, direction features] → rows of (f RGB, T RGB, R).
//! - `decode_parallel`: the trainer's own forward pass (on AVX-512, the fused kernels of
//!   dense.rs), split over threads in contiguous slices, each slice in blocks so the activations
//!   stay in cache;
//! - the emitted kernels (`uplift_compiler::backend_neural`, askama templates): Rust (the
//!   shipped decoder is committed as `shipped_decoder.rs`; `uplift emit-decoder` writes any
//!   other) and WGSL, run here on a wgpu device by [`WgpuDecoder`].

use crate::loss::OUTPUTS;
use crate::mlp::{Activation, Mlp, Workspace};
use crate::model::BLOCK_ROWS as BLOCK;
use uplift_engines::wgpu_engine::WgpuEngine;
use uplift_compiler::backend_neural::{write_wgsl_decoder, DecoderSpec, NeuralActivation, DECODER_ENTRY_POINT, DECODER_WORKGROUP_SIZE};
use wgpu::util::DeviceExt;

/// Decodes `dec_in` (rows × the decoder's inputs) into `out` (rows × 7) on `threads` threads.
pub fn decode_parallel(decoder: &Mlp<f32>, dec_in: &[f32], out: &mut [f32], threads: usize) {
    decode_parallel_in(&mut Vec::new(), decoder, dec_in, out, threads);
}

/// [`decode_parallel`] with per-thread workspaces kept by the caller between calls (their
/// buffers and the packed weights of a frozen decoder are then reused).
pub fn decode_parallel_in(workspaces: &mut Vec<Workspace<f32>>, decoder: &Mlp<f32>, dec_in: &[f32], out: &mut [f32], threads: usize) {
    let inputs = decoder.shape.widths[0];
    let rows = dec_in.len() / inputs;
    assert_eq!(out.len(), rows * OUTPUTS, "output rows");
    let threads = threads.clamp(1, rows.div_ceil(BLOCK).max(1));
    let per = rows.div_ceil(threads);
    if workspaces.len() < threads {
        workspaces.resize_with(threads, Workspace::default);
    }
    std::thread::scope(|scope| {
        for ((t, chunk), ws) in out.chunks_mut(per * OUTPUTS).enumerate().zip(workspaces.iter_mut()) {
            let input = &dec_in[t * per * inputs..(t * per + chunk.len() / OUTPUTS) * inputs];
            scope.spawn(move || {
                for (i, o) in input.chunks(BLOCK * inputs).zip(chunk.chunks_mut(BLOCK * OUTPUTS)) {
                    o.copy_from_slice(decoder.forward(i, i.len() / inputs, ws));
                }
            });
        }
    });
}

/// The emitters' description of a network (`uplift_compiler::backend_neural`).
pub fn decoder_spec(net: &Mlp<f32>, source: &str) -> DecoderSpec {
    let map = |a: Activation| match a {
        Activation::Identity => NeuralActivation::Identity,
        Activation::LeakyRelu { slope } => NeuralActivation::LeakyRelu { slope },
        Activation::Sigmoid => NeuralActivation::Sigmoid,
        Activation::ExpHead { shift, clamp } => NeuralActivation::ExpHead { shift, clamp },
    };
    DecoderSpec { widths: net.shape.widths.clone(), hidden: map(net.shape.hidden), output: map(net.shape.output), params: net.params.clone(), source: source.to_string() }
}

/// The decoder as a WGSL compute pipeline on a wgpu device.
pub struct WgpuDecoder {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    weights: wgpu::Buffer,
    inputs: usize,
    outputs: usize,
}

impl WgpuDecoder {
    pub fn new(engine: &WgpuEngine, net: &Mlp<f32>, source: &str) -> Result<WgpuDecoder, String> {
        let wgsl = write_wgsl_decoder(&decoder_spec(net, source))?;
        let d = &engine.device;
        let module = d.create_shader_module(wgpu::ShaderModuleDescriptor { label: Some("neural decoder"), source: wgpu::ShaderSource::Wgsl(wgsl.into()) });
        let storage = |binding, read_only| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer { ty: wgpu::BufferBindingType::Storage { read_only }, has_dynamic_offset: false, min_binding_size: None },
            count: None,
        };
        let uniform = wgpu::BindGroupLayoutEntry {
            binding: 3,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer { ty: wgpu::BufferBindingType::Uniform, has_dynamic_offset: false, min_binding_size: None },
            count: None,
        };
        let layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: None, entries: &[storage(0, true), storage(1, true), storage(2, false), uniform] });
        let pl = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor { label: None, bind_group_layouts: &[Some(&layout)], immediate_size: 0 });
        let pipeline = d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("neural decoder"),
            layout: Some(&pl),
            module: &module,
            entry_point: Some(DECODER_ENTRY_POINT),
            compilation_options: Default::default(),
            cache: None,
        });
        let weights = d.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some("decoder weights"), contents: bytemuck::cast_slice(&net.params), usage: wgpu::BufferUsages::STORAGE });
        Ok(WgpuDecoder { pipeline, layout, weights, inputs: net.shape.inputs(), outputs: net.shape.outputs() })
    }

    /// Decodes rows (`input`: rows × inputs) on the device.
    pub fn decode(&self, engine: &WgpuEngine, input: &[f32]) -> Result<Vec<f32>, String> {
        let rows = input.len() / self.inputs;
        if rows == 0 {
            return Ok(Vec::new());
        }
        let d = &engine.device;
        let inp = d.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: None, contents: bytemuck::cast_slice(input), usage: wgpu::BufferUsages::STORAGE });
        let size = (rows * self.outputs * 4) as u64;
        let out = d.create_buffer(&wgpu::BufferDescriptor { label: None, size, usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC, mapped_at_creation: false });
        let params = d.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: None, contents: bytemuck::cast_slice(&[rows as u32, 0, 0, 0]), usage: wgpu::BufferUsages::UNIFORM });
        let group = d.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: self.weights.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: inp.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 2, resource: out.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 3, resource: params.as_entire_binding() },
            ],
        });
        let mut encoder = d.create_command_encoder(&Default::default());
        engine.record(&mut encoder, &self.pipeline, &group, rows, DECODER_WORKGROUP_SIZE)?;
        engine.submit_and_read(encoder, &out, size)
    }
}
