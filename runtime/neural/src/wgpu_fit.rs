//! Latent fitting's heavy part on a wgpu device: the decoder's forward pass, the paper's Eq. 3
//! and the backward pass to the latents, per row, as the WGSL the compiler emits from
//! `templates/neural_fit.wgsl` (`uplift_compiler::backend_neural::write_wgsl_fitter`) — the
//! same network and loss as the CPU path (`model::latent_slice`), which is its oracle. The
//! fitter (`fit.rs`) runs it when its data generator runs on the wgpu engine.

use crate::loss::{LossParts, LossWeights, OUTPUTS};
use crate::mlp::Mlp;
use crate::inference::decoder_spec;
use uplift_compiler::backend_neural::{write_wgsl_fitter, FITTER_ENTRY_POINT, FITTER_WORKGROUP_SIZE};
use uplift_engines::wgpu_engine::WgpuEngine;
use wgpu::util::DeviceExt;

/// The fitting kernel of one decoder, with its weights on the device.
pub struct WgpuLatentGradients {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    weights: wgpu::Buffer,
    inputs: usize,
    latent: usize,
}

impl WgpuLatentGradients {
    /// The kernel for `decoder`, whose first `latent` inputs are the latent.
    pub fn new(engine: &WgpuEngine, decoder: &Mlp<f32>, latent: usize, source: &str) -> Result<WgpuLatentGradients, String> {
        let wgsl = write_wgsl_fitter(&decoder_spec(decoder, source), latent)?;
        let d = &engine.device;
        let module = d.create_shader_module(wgpu::ShaderModuleDescriptor { label: Some("latent fitting"), source: wgpu::ShaderSource::Wgsl(wgsl.into()) });
        let storage = |binding, read_only| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer { ty: wgpu::BufferBindingType::Storage { read_only }, has_dynamic_offset: false, min_binding_size: None },
            count: None,
        };
        let uniform = wgpu::BindGroupLayoutEntry {
            binding: 4,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer { ty: wgpu::BufferBindingType::Uniform, has_dynamic_offset: false, min_binding_size: None },
            count: None,
        };
        let layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: None, entries: &[storage(0, true), storage(1, true), storage(2, true), storage(3, false), uniform] });
        let pl = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor { label: None, bind_group_layouts: &[Some(&layout)], immediate_size: 0 });
        let pipeline = d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("latent fitting"),
            layout: Some(&pl),
            module: &module,
            entry_point: Some(FITTER_ENTRY_POINT),
            compilation_options: Default::default(),
            cache: None,
        });
        let weights = d.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some("decoder weights"), contents: bytemuck::cast_slice(&decoder.params), usage: wgpu::BufferUsages::STORAGE });
        Ok(WgpuLatentGradients { pipeline, layout, weights, inputs: decoder.shape.inputs(), latent })
    }

    /// Eq. 3 of the decoder on `dec_in` (rows × inputs: latent + jitter, features) against
    /// `target` (rows × 7: f·μl RGB, T RGB, R) at light cosines `mu_l`, normalised over the
    /// rows; and ∂loss/∂latent (rows × latent).
    pub fn run(&self, engine: &WgpuEngine, dec_in: &[f32], target: &[f32], mu_l: &[f32], w: LossWeights) -> Result<(LossParts, Vec<f32>), String> {
        let rows = mu_l.len();
        if rows == 0 {
            return Ok((LossParts::default(), Vec::new()));
        }
        if dec_in.len() != rows * self.inputs || target.len() != rows * OUTPUTS {
            return Err(format!("latent fitting on wgpu: {} inputs and {} targets for {rows} rows of {} inputs", dec_in.len(), target.len(), self.inputs));
        }
        let mut targets = Vec::with_capacity(rows * 8);
        for r in 0..rows {
            targets.extend_from_slice(&target[r * OUTPUTS..(r + 1) * OUTPUTS]);
            targets.push(mu_l[r]);
        }
        let per_row = 3 + self.latent;
        let d = &engine.device;
        let buffer = |data: &[f32]| d.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: None, contents: bytemuck::cast_slice(data), usage: wgpu::BufferUsages::STORAGE });
        let (inp, tgt) = (buffer(dec_in), buffer(&targets));
        let size = (rows * per_row * 4) as u64;
        let out = d.create_buffer(&wgpu::BufferDescriptor { label: None, size, usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC, mapped_at_creation: false });
        let (nf, nr) = (3.0 * rows as f64, rows as f64);
        let params = [rows as u32, ((w.f / nf) as f32).to_bits(), ((w.t / nf) as f32).to_bits(), ((w.r / nr) as f32).to_bits()];
        let uniform = d.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: None, contents: bytemuck::cast_slice(&params), usage: wgpu::BufferUsages::UNIFORM });
        let group = d.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: self.weights.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: inp.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 2, resource: tgt.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 3, resource: out.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 4, resource: uniform.as_entire_binding() },
            ],
        });
        let mut encoder = d.create_command_encoder(&Default::default());
        engine.record(&mut encoder, &self.pipeline, &group, rows, FITTER_WORKGROUP_SIZE)?;
        let result = engine.submit_and_read(encoder, &out, size)?;
        let mut parts = LossParts::default();
        let mut grad = Vec::with_capacity(rows * self.latent);
        for r in 0..rows {
            let o = &result[r * per_row..(r + 1) * per_row];
            parts.f += o[0] as f64 / nf;
            parts.t += o[1] as f64 / nf;
            parts.r += o[2] as f64 / nr;
            grad.extend_from_slice(&o[3..]);
        }
        parts.total = w.f * parts.f + w.t * parts.t + w.r * parts.r;
        Ok((parts, grad))
    }
}
