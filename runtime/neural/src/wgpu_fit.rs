//! Latent fitting's heavy part on a wgpu device: the decoder's forward pass, the paper's Eq. 3
//! and the backward pass to the latents, per row, as the WGSL the compiler emits from
//! `templates/neural_fit.wgsl` (`uplift_compiler::backend_neural::write_wgsl_fitter`) — the
//! same network and loss as the CPU path (`model::latent_slice`), which is its oracle. The
//! fitter (`fit.rs`) runs it when its data generator runs on the wgpu engine, inside a
//! [`DeviceFit`]: the step's data, the groups' latents and Adam's moments on the device.

use crate::loss::{LossParts, LossWeights, OUTPUTS};
use crate::mlp::Mlp;
use crate::inference::decoder_spec;
use uplift_compiler::backend_neural::{write_wgsl_fitter, FITTER_ENTRY_POINT, FITTER_WORKGROUP_SIZE, FIT_STEP_WORKGROUP_SIZE};
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

/// A material's latent fit kept on a wgpu device: every step's rows assembled there from the
/// groups' parameters (`wgpu_batch::DeviceBatches::record_evaluation`), gathered into the
/// fitting kernel's rows with the groups' latents (`templates/neural_fit_step.wgsl`'s
/// `nfs_gather`), the kernel above, and Adam with the clamp (`nfs_adam`), in one command
/// buffer; the host uploads the step's direction draws and jitter and reads the loss's three
/// sums. The latents come back once, at the end. `fit_material` on the CPU is the oracle.
pub struct DeviceFit {
    gradients: WgpuLatentGradients,
    batches: crate::wgpu_batch::DeviceBatches,
    gather: wgpu::ComputePipeline,
    adam: wgpu::ComputePipeline,
    rows: usize,
    per_group: usize,
    groups: usize,
    batch_rows: wgpu::Buffer,
    latents: wgpu::Buffer,
    moments: wgpu::Buffer,
    input: wgpu::Buffer,
    target: wgpu::Buffer,
    output: wgpu::Buffer,
    loss: wgpu::Buffer,
    fit_uniform: wgpu::Buffer,
    step_uniform: wgpu::Buffer,
    t: u64,
}

impl DeviceFit {
    /// A fit of `z0` (groups × the decoder's latent) against `decoder`, whose rows are the
    /// parameter rows `params` (rows × the stack's parameters), `per_group` consecutive rows
    /// per group.
    pub fn new(engine: &WgpuEngine, generator: &crate::datagen::DataGenerator, decoder: &Mlp<f32>, latent: usize, params: &[f32], per_group: usize, z0: &[f32]) -> Result<DeviceFit, String> {
        let np = generator.stack().len();
        let rows = params.len() / np.max(1);
        let groups = z0.len() / latent.max(1);
        if rows == 0 || per_group == 0 || rows != groups * per_group || z0.len() != groups * latent {
            return Err(format!("a device fit of {rows} rows for {groups} groups of {per_group} rows and {} latent values", z0.len()));
        }
        let gradients = WgpuLatentGradients::new(engine, decoder, latent, "the fitted decoder")?;
        let mut batches = crate::wgpu_batch::DeviceBatches::new(engine, generator, latent)?;
        batches.set_parameters(engine, generator, params)?;
        let d = &engine.device;
        let wgsl = uplift_compiler::backend_neural::write_wgsl_fit_step(np, latent)?;
        let module = d.create_shader_module(wgpu::ShaderModuleDescriptor { label: Some("fitting step"), source: wgpu::ShaderSource::Wgsl(wgsl.into()) });
        let pipeline = |entry: &str| d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor { label: Some(entry), layout: None, module: &module, entry_point: Some(entry), compilation_options: Default::default(), cache: None });
        let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC;
        let make = |floats: usize, label: &str| d.create_buffer(&wgpu::BufferDescriptor { label: Some(label), size: (floats.max(1) * 4) as u64, usage: storage, mapped_at_creation: false });
        let uniform = |bytes: u64| d.create_buffer(&wgpu::BufferDescriptor { label: None, size: bytes, usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST, mapped_at_creation: false });
        let latents = d.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some("group latents"), contents: bytemuck::cast_slice(z0), usage: storage });
        Ok(DeviceFit {
            batch_rows: make(rows * batches.row_stride(), "fit rows"),
            moments: d.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some("Adam moments"), contents: bytemuck::cast_slice(&vec![0.0f32; 2 * z0.len()]), usage: storage }),
            input: make(rows * gradients.inputs, "fitting inputs"),
            target: make(rows * 8, "fitting targets"),
            output: make(rows * (3 + latent), "fitting outputs"),
            loss: make(3, "loss sums"),
            fit_uniform: uniform(16),
            step_uniform: uniform(32),
            gather: pipeline(uplift_compiler::backend_neural::FIT_STEP_GATHER_ENTRY_POINT),
            adam: pipeline(uplift_compiler::backend_neural::FIT_STEP_ADAM_ENTRY_POINT),
            gradients,
            batches,
            rows,
            per_group,
            groups,
            latents,
            t: 0,
        })
    }

    /// One step: the rows `generator.evaluate(params, key)` gives, jittered by `jitter` (rows ×
    /// latent), Eq. 3 and its gradient, Adam at learning rate `lr` (Adam's step count advances),
    /// the clamp. Returns Eq. 3 over the step's rows.
    pub fn step(&mut self, engine: &WgpuEngine, generator: &crate::datagen::DataGenerator, key: u64, jitter: &[f32], lr: f32, w: LossWeights) -> Result<LossParts, String> {
        let (rows, latent) = (self.rows, self.gradients.latent);
        self.t += 1;
        let t32 = self.t.min(i32::MAX as u64) as i32;
        let (c1, c2) = (1.0 - 0.9f32.powi(t32), 1.0 - 0.999f32.powi(t32));
        let (nf, nr) = (3.0 * rows as f64, rows as f64);
        let q = &engine.queue;
        q.write_buffer(&self.fit_uniform, 0, bytemuck::cast_slice(&[rows as u32, ((w.f / nf) as f32).to_bits(), ((w.t / nf) as f32).to_bits(), ((w.r / nr) as f32).to_bits()]));
        q.write_buffer(&self.step_uniform, 0, bytemuck::cast_slice(&[rows as u32, self.per_group as u32, self.groups as u32, 0, (lr / c1).to_bits(), c2.sqrt().to_bits(), 0, 0]));
        let d = &engine.device;
        let mut encoder = d.create_command_encoder(&Default::default());
        self.batches.record_evaluation(engine, generator, key, rows, jitter, &mut encoder, &self.batch_rows)?;
        let group = |layout: &wgpu::BindGroupLayout, buffers: &[(u32, &wgpu::Buffer)]| engine.bind_buffers(layout, buffers);
        let g = group(&self.gather.get_bind_group_layout(0), &[(0, &self.batch_rows), (1, &self.latents), (2, &self.input), (3, &self.target), (4, &self.step_uniform)]);
        engine.record(&mut encoder, &self.gather, &g, rows, FIT_STEP_WORKGROUP_SIZE)?;
        let g = group(&self.gradients.layout, &[(0, &self.gradients.weights), (1, &self.input), (2, &self.target), (3, &self.output), (4, &self.fit_uniform)]);
        engine.record(&mut encoder, &self.gradients.pipeline, &g, rows, FITTER_WORKGROUP_SIZE)?;
        let g = group(&self.adam.get_bind_group_layout(0), &[(5, &self.output), (6, &self.latents), (7, &self.moments), (8, &self.loss), (9, &self.step_uniform)]);
        engine.record(&mut encoder, &self.adam, &g, self.groups * latent + 3, FIT_STEP_WORKGROUP_SIZE)?;
        let sums = engine.submit_and_read(encoder, &self.loss, 12)?;
        let mut parts = LossParts { f: sums[0] as f64 / nf, t: sums[1] as f64 / nf, r: sums[2] as f64 / nr, ..Default::default() };
        parts.total = w.f * parts.f + w.t * parts.t + w.r * parts.r;
        Ok(parts)
    }

    /// The groups' latents (groups × latent), read back.
    pub fn latents(&self, engine: &WgpuEngine) -> Result<Vec<f32>, String> {
        engine.submit_and_read(engine.device.create_command_encoder(&Default::default()), &self.latents, (self.groups * self.gradients.latent * 4) as u64)
    }
}
