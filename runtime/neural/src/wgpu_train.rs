//! Training on a wgpu device: the encoder and decoder's forward and backward passes, Eq. 3, the
//! weight gradients and Adam as the WGSL the compiler emits from `templates/neural_train.wgsl`
//! (`uplift_compiler::backend_neural::write_wgsl_trainer`). The networks' weights and Adam's
//! moments stay on the device between steps; a step uploads its batch's rows and reads back
//! three loss sums — or, with [`WgpuTrainer::step_on_device`], reads a batch that the
//! generator's kernels assembled on the device (`wgpu_batch`), so that nothing but the loss
//! crosses to the host. The CPU trainer (`trainer::train_step`) is the oracle: the same model,
//! loss, jitter and Adam; [`WgpuTrainer::download`] brings the state back for checkpoints and
//! the weights file.

use crate::inference::decoder_spec;
use crate::loss::{LossParts, LossWeights, OUTPUTS};
use crate::trainer::TrainState;
use uplift_compiler::backend_neural::{write_wgsl_trainer, TRAINER_ADAM_ENTRY_POINT, TRAINER_GRADS_ENTRY_POINT, TRAINER_ROWS_ENTRY_POINT, TRAINER_WORKGROUP_SIZE};
use uplift_engines::wgpu_engine::WgpuEngine;
use wgpu::util::DeviceExt;

/// Buffers sized for a batch of `rows` (the activations, deltas and row losses are the
/// kernels' alone: held here for the bind group).
#[allow(dead_code)]
struct RowBuffers {
    rows: usize,
    rows_in: wgpu::Buffer,
    acts: wgpu::Buffer,
    deltas: wgpu::Buffer,
    loss: wgpu::Buffer,
    group: wgpu::BindGroup,
}

/// The training step of one model on a device, with its weights and moments there.
pub struct WgpuTrainer {
    pipelines: [wgpu::ComputePipeline; 3],
    layout: wgpu::BindGroupLayout,
    weights: wgpu::Buffer,
    grad: wgpu::Buffer,
    moments: wgpu::Buffer,
    uniform: wgpu::Buffer,
    encoder_params: usize,
    total: usize,
    parameters: usize,
    latent: usize,
    /// Floats per row in the activations and deltas buffers.
    acts: usize,
    deltas: usize,
    buffers: Option<RowBuffers>,
}

impl WgpuTrainer {
    /// Uploads `state`'s networks and Adam moments.
    pub fn new(engine: &WgpuEngine, state: &TrainState) -> Result<WgpuTrainer, String> {
        let (enc, dec) = (&state.model.encoder, &state.model.decoder);
        let wgsl = write_wgsl_trainer(&decoder_spec(enc, "encoder"), &decoder_spec(dec, "decoder"), "the model in training")?;
        let d = &engine.device;
        let module = d.create_shader_module(wgpu::ShaderModuleDescriptor { label: Some("training"), source: wgpu::ShaderSource::Wgsl(wgsl.into()) });
        let storage = |binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer { ty: wgpu::BufferBindingType::Storage { read_only: false }, has_dynamic_offset: false, min_binding_size: None },
            count: None,
        };
        let mut entries: Vec<wgpu::BindGroupLayoutEntry> = (0..7).map(storage).collect();
        entries.push(wgpu::BindGroupLayoutEntry {
            binding: 7,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer { ty: wgpu::BufferBindingType::Uniform, has_dynamic_offset: false, min_binding_size: None },
            count: None,
        });
        let layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: None, entries: &entries });
        let pl = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor { label: None, bind_group_layouts: &[Some(&layout)], immediate_size: 0 });
        let pipeline = |entry: &str| {
            d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor { label: Some(entry), layout: Some(&pl), module: &module, entry_point: Some(entry), compilation_options: Default::default(), cache: None })
        };
        let pipelines = [pipeline(TRAINER_ROWS_ENTRY_POINT), pipeline(TRAINER_GRADS_ENTRY_POINT), pipeline(TRAINER_ADAM_ENTRY_POINT)];
        let total = enc.params.len() + dec.params.len();
        let weights: Vec<f32> = enc.params.iter().chain(&dec.params).copied().collect();
        let moments: Vec<f32> = state.adam_enc.m.iter().chain(&state.adam_dec.m).chain(&state.adam_enc.v).chain(&state.adam_dec.v).copied().collect();
        let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST;
        let weights = d.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some("weights"), contents: bytemuck::cast_slice(&weights), usage });
        let moments = d.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some("adam moments"), contents: bytemuck::cast_slice(&moments), usage });
        let grad = d.create_buffer(&wgpu::BufferDescriptor { label: Some("gradients"), size: ((total + 3) * 4) as u64, usage, mapped_at_creation: false });
        let uniform = d.create_buffer(&wgpu::BufferDescriptor { label: Some("step"), size: 32, usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST, mapped_at_creation: false });
        let widths = |w: &[usize]| w.iter().skip(1).sum::<usize>();
        let (parameters, latent) = (enc.shape.widths[0], state.model.latent());
        let deltas = widths(&enc.shape.widths) + widths(&dec.shape.widths);
        let acts = parameters + deltas + dec.shape.widths[0];
        Ok(WgpuTrainer { pipelines, layout, weights, grad, moments, uniform, encoder_params: enc.params.len(), total, parameters, latent, acts, deltas, buffers: None })
    }

    fn buffers(&mut self, engine: &WgpuEngine, rows: usize) {
        if self.buffers.as_ref().is_none_or(|b| b.rows != rows) {
            let d = &engine.device;
            let make = |floats: usize, label: &str| d.create_buffer(&wgpu::BufferDescriptor { label: Some(label), size: (floats.max(1) * 4) as u64, usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC, mapped_at_creation: false });
            let rows_in = make(rows * (self.parameters + self.latent + 9 + 8), "rows");
            let acts = make(rows * self.acts, "activations");
            let deltas = make(rows * self.deltas, "deltas");
            let loss = make(rows * 3, "row losses");
            let buffers = [&self.weights, &rows_in, &acts, &deltas, &loss, &self.grad, &self.moments, &self.uniform];
            let entries: Vec<wgpu::BindGroupEntry> = buffers.iter().enumerate().map(|(k, b)| wgpu::BindGroupEntry { binding: k as u32, resource: b.as_entire_binding() }).collect();
            let group = d.create_bind_group(&wgpu::BindGroupDescriptor { label: None, layout: &self.layout, entries: &entries });
            self.buffers = Some(RowBuffers { rows, rows_in, acts, deltas, loss, group });
        }
    }

    /// One step on `rows` rows: `encoded` (rows × the stack's parameters), `jitter` (rows ×
    /// latent), `features` (rows × 9), `target` (rows × 7), `mu_l`; Adam at learning rate `lr`
    /// as step `t` (from 1). Returns the batch's Eq. 3.
    #[allow(clippy::too_many_arguments)]
    pub fn step(&mut self, engine: &WgpuEngine, encoded: &[f32], jitter: &[f32], features: &[f32], target: &[f32], mu_l: &[f32], lr: f32, t: u64, w: LossWeights) -> Result<LossParts, String> {
        let rows = mu_l.len();
        let (np, latent) = (self.parameters, self.latent);
        if rows == 0 || encoded.len() != rows * np || jitter.len() != rows * latent || features.len() != rows * 9 || target.len() != rows * OUTPUTS {
            return Err(format!("a training batch of {rows} rows with {} encoded, {} jitter, {} feature and {} target values", encoded.len(), jitter.len(), features.len(), target.len()));
        }
        let mut packed = Vec::with_capacity(rows * (np + latent + 17));
        for r in 0..rows {
            packed.extend_from_slice(&encoded[r * np..(r + 1) * np]);
            packed.extend_from_slice(&jitter[r * latent..(r + 1) * latent]);
            packed.extend_from_slice(&features[r * 9..(r + 1) * 9]);
            packed.extend_from_slice(&target[r * OUTPUTS..(r + 1) * OUTPUTS]);
            packed.push(mu_l[r]);
        }
        self.buffers(engine, rows);
        let b = self.buffers.as_ref().expect("made above");
        engine.queue.write_buffer(&b.rows_in, 0, bytemuck::cast_slice(&packed));
        let encoder = engine.device.create_command_encoder(&Default::default());
        self.finish_step(engine, encoder, rows, lr, t, w)
    }

    /// One step on a batch assembled on the device: `assemble` records into the step's command
    /// encoder the writing of `rows` rows into the trainer's rows buffer (given; the layout of
    /// [`step`](Self::step)'s packed rows), as `wgpu_batch::DeviceBatches::record` does. The
    /// batch never leaves the device; the three loss sums come back. Returns the batch's Eq. 3.
    pub fn step_on_device(&mut self, engine: &WgpuEngine, rows: usize, lr: f32, t: u64, w: LossWeights, assemble: impl FnOnce(&mut wgpu::CommandEncoder, &wgpu::Buffer) -> Result<(), String>) -> Result<LossParts, String> {
        if rows == 0 {
            return Err("a training batch of 0 rows".into());
        }
        self.buffers(engine, rows);
        let b = self.buffers.as_ref().expect("made above");
        let mut encoder = engine.device.create_command_encoder(&Default::default());
        assemble(&mut encoder, &b.rows_in)?;
        self.finish_step(engine, encoder, rows, lr, t, w)
    }

    /// Records the step's three kernels after `encoder`'s batch, submits, and reads the loss.
    fn finish_step(&mut self, engine: &WgpuEngine, mut encoder: wgpu::CommandEncoder, rows: usize, lr: f32, t: u64, w: LossWeights) -> Result<LossParts, String> {
        let (nf, nr) = (3.0 * rows as f64, rows as f64);
        // Adam's bias corrections as the CPU's Adam computes them (f32).
        let (b1, b2) = (0.9f32, 0.999f32);
        let t32 = t.min(i32::MAX as u64) as i32;
        let (c1, c2) = (1.0 - b1.powi(t32), 1.0 - b2.powi(t32));
        let params: [u32; 8] = [rows as u32, ((w.f / nf) as f32).to_bits(), ((w.t / nf) as f32).to_bits(), ((w.r / nr) as f32).to_bits(), (lr / c1).to_bits(), c2.sqrt().to_bits(), self.total as u32, 0];
        engine.queue.write_buffer(&self.uniform, 0, bytemuck::cast_slice(&params));
        let total = self.total;
        let b = self.buffers.as_ref().expect("made by the caller");
        for (pipeline, n) in self.pipelines.iter().zip([rows, total + 3, total]) {
            engine.record(&mut encoder, pipeline, &b.group, n, TRAINER_WORKGROUP_SIZE)?;
        }
        let sums = engine.submit_and_read_at(encoder, &self.grad, (total * 4) as u64, 12)?;
        let mut parts = LossParts { total: 0.0, f: sums[0] as f64 / nf, t: sums[1] as f64 / nf, r: sums[2] as f64 / nr };
        parts.total = w.f * parts.f + w.t * parts.t + w.r * parts.r;
        Ok(parts)
    }

    /// Copies the device's weights and Adam moments into `state` (its Adam step counts are the
    /// caller's).
    pub fn download(&self, engine: &WgpuEngine, state: &mut TrainState) -> Result<(), String> {
        let copy = |source: &wgpu::Buffer, floats: usize| engine.submit_and_read(engine.device.create_command_encoder(&Default::default()), source, (floats * 4) as u64);
        let (weights, moments) = (copy(&self.weights, self.total)?, copy(&self.moments, 2 * self.total)?);
        let ne = self.encoder_params;
        state.model.encoder.params.copy_from_slice(&weights[..ne]);
        state.model.decoder.params.copy_from_slice(&weights[ne..]);
        let (m, v) = moments.split_at(self.total);
        state.adam_enc.m.copy_from_slice(&m[..ne]);
        state.adam_dec.m.copy_from_slice(&m[ne..]);
        state.adam_enc.v.copy_from_slice(&v[..ne]);
        state.adam_dec.v.copy_from_slice(&v[ne..]);
        Ok(())
    }
}
