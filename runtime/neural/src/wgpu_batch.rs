//! Training batches assembled on a wgpu device, so that a training step on the wgpu engine
//! never sends a kernel's output through the host. The host draws what `DataGenerator::batch`
//! draws (each group's class, tile and cell; each row's view, uniform light, sampler uniforms and
//! light kind; the classes' random scalars; the latent's jitter) and uploads it; on the device
//! the classes' graph kernels compute the parameters, the `uplift_stack` sample, eval and albedo
//! kernels (the same compiled WGSL as every other wgpu run) compute the lights and targets, and
//! the kernels of `templates/neural_batch.wgsl` join them into the trainer's rows buffer. The
//! host path (`DataGenerator::batch` on the wgpu engine) is the oracle: the rows agree
//! (tests/integration/neural_train_wgpu.rs).

use crate::classes::ClassDraw;
use crate::datagen::DataGenerator;
use uplift_compiler::backend_neural::{write_wgsl_batch, BATCH_ASSEMBLE_ENTRY_POINT, BATCH_DIRECTION_STRIDE, BATCH_GATHER_ENTRY_POINT, BATCH_SCATTER_ENTRY_POINT, BATCH_SELECT_ENTRY_POINT, BATCH_WORKGROUP_SIZE};
use uplift_compiler::kernel::GEOMETRY_STRIDE;
use uplift_engines::batch::Geometry;
use uplift_engines::stack::Encoding;
use uplift_engines::stack_kernel::StackKernel;
use uplift_engines::wgpu_engine::{WgpuEngine, WgpuPipeline};
use wgpu::util::DeviceExt;

/// Direction slots per row (`templates/neural_batch.wgsl`).
const WV: u32 = 0;
const WL_UNIFORM: u32 = 3;
const U: u32 = 6;
const WL: u32 = 9;
const SAMPLED: usize = 12;
/// A gather map's code for direction slot j (`nb_gather`).
const DIRECTION: u32 = 65536;

/// The batch-assembly kernels of one generator's stack, and the buffers of one batch size.
pub struct DeviceBatches {
    scatter: wgpu::ComputePipeline,
    gather: wgpu::ComputePipeline,
    select: wgpu::ComputePipeline,
    assemble: wgpu::ComputePipeline,
    parameters: usize,
    latent: usize,
    /// `nb_gather`'s maps for the sample, eval and albedo kernels.
    maps: [wgpu::Buffer; 3],
    /// The encoding table (per parameter: square root or not, a, b, 0), the head of `as_table`.
    table: Vec<f32>,
    buffers: Option<Buffers>,
}

/// The device buffers of a batch of `rows` rows.
struct Buffers {
    rows: usize,
    geometry: wgpu::Buffer,
    params: wgpu::Buffer,
    dirs: wgpu::Buffer,
    sel: wgpu::Buffer,
    table: wgpu::Buffer,
    /// Inputs and outputs of the sample, eval and albedo kernels.
    kernel_io: [(wgpu::Buffer, wgpu::Buffer); 3],
    /// Whether `params` holds rows given to `set_parameters` (not a drawn batch's).
    given: bool,
}

fn pipeline(engine: &WgpuEngine, module: &wgpu::ShaderModule, entry: &str) -> wgpu::ComputePipeline {
    engine.device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor { label: Some(entry), layout: None, module, entry_point: Some(entry), compilation_options: Default::default(), cache: None })
}

fn wgpu_pipeline(k: &StackKernel) -> Result<&WgpuPipeline, String> {
    k.prepared().wgpu_pipeline().ok_or_else(|| "batches are assembled on a device only for a generator on the wgpu engine".to_string())
}

impl DeviceBatches {
    /// The assembly kernels for `generator` (on the wgpu engine `engine`) and a latent of
    /// `latent` values.
    pub fn new(engine: &WgpuEngine, generator: &DataGenerator, latent: usize) -> Result<DeviceBatches, String> {
        let stack = generator.stack();
        let np = stack.len();
        let wgsl = write_wgsl_batch(np)?;
        let module = engine.device.create_shader_module(wgpu::ShaderModuleDescriptor { label: Some("training batches"), source: wgpu::ShaderSource::Wgsl(wgsl.into()) });
        let kernels = [generator.sample_kernel(), generator.eval_kernel(), generator.albedo_kernel()];
        let directions: [&[(&str, u32)]; 3] = [&[("wv", WV), ("u", U)], &[("wv", WV), ("wl", WL)], &[("wv", WV)]];
        let mut maps = Vec::new();
        for (k, dirs) in kernels.iter().zip(directions) {
            wgpu_pipeline(k)?;
            let mut map = vec![0u32; k.prepared().kernel.input_stride.max(1)];
            for (p, &column) in k.parameter_columns().iter().enumerate() {
                map[column] = 1 + p as u32;
            }
            for &(name, slot) in dirs {
                let at = k.input_offset(name);
                for c in 0..3 {
                    map[at + c] = DIRECTION + slot + c as u32;
                }
            }
            maps.push(engine.device.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some("gather map"), contents: bytemuck::cast_slice(&map), usage: wgpu::BufferUsages::STORAGE }));
        }
        let table = stack
            .parameters()
            .iter()
            .flat_map(|p| match p.encoding {
                Encoding::Linear => [0.0, p.lo, p.hi, 0.0],
                Encoding::Sqrt => [1.0, p.lo.sqrt(), p.hi.sqrt(), 0.0],
            })
            .collect();
        Ok(DeviceBatches {
            scatter: pipeline(engine, &module, BATCH_SCATTER_ENTRY_POINT),
            gather: pipeline(engine, &module, BATCH_GATHER_ENTRY_POINT),
            select: pipeline(engine, &module, BATCH_SELECT_ENTRY_POINT),
            assemble: pipeline(engine, &module, BATCH_ASSEMBLE_ENTRY_POINT),
            parameters: np,
            latent,
            maps: maps.try_into().map_err(|_| "three gather maps".to_string())?,
            table,
            buffers: None,
        })
    }

    /// Floats per row of the rows this writes (the trainer's input layout).
    pub fn row_stride(&self) -> usize {
        self.parameters + self.latent + 17
    }

    fn buffers(&mut self, engine: &WgpuEngine, generator: &DataGenerator, rows: usize) {
        if self.buffers.as_ref().is_some_and(|b| b.rows == rows) {
            return;
        }
        let d = &engine.device;
        let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC;
        let make = |floats: usize, label: &str| d.create_buffer(&wgpu::BufferDescriptor { label: Some(label), size: (floats.max(1) * 4) as u64, usage, mapped_at_creation: false });
        let kernels = [generator.sample_kernel(), generator.eval_kernel(), generator.albedo_kernel()];
        let kernel_io = kernels.map(|k| (make(rows * k.prepared().kernel.input_stride, "kernel inputs"), make(rows * k.prepared().kernel.output_stride, "kernel outputs")));
        let geometry = Geometry::default().repeated(rows);
        self.buffers = Some(Buffers {
            rows,
            geometry: d.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some("geometry"), contents: bytemuck::cast_slice(geometry.data()), usage }),
            params: make(rows * self.parameters, "parameter rows"),
            dirs: make(rows * BATCH_DIRECTION_STRIDE, "direction slots"),
            sel: make(rows * 4, "sampled responses"),
            table: make(self.table.len() + rows * self.latent, "encoding and jitter"),
            kernel_io,
            given: false,
        });
    }

    /// Records into `encoder` batch `index` of `rows` rows of `generator` (the rows
    /// `generator.batch(index, rows)` makes), with the latent jitter `jitter` (rows × latent),
    /// written into `out` in the trainer's input layout ([`row_stride`](Self::row_stride)
    /// floats per row). The host's part: the draws, uploaded; nothing is read back.
    #[allow(clippy::too_many_arguments)]
    pub fn record(&mut self, engine: &WgpuEngine, generator: &DataGenerator, index: u64, rows: usize, jitter: &[f32], encoder: &mut wgpu::CommandEncoder, out: &wgpu::Buffer) -> Result<(), String> {
        self.check(rows, jitter, out)?;
        let (key, k, picks) = generator.picks(index, rows)?;
        self.buffers(engine, generator, rows);
        self.buffers.as_mut().expect("made above").given = false;
        self.record_parameters(engine, generator, &picks, k, rows, encoder)?;
        self.record_rows(engine, generator, key, k, rows, jitter, encoder, out)
    }

    /// Sets the parameter rows (rows × the stack's parameters) that [`record_evaluation`]
    /// evaluates: uploaded once, kept on the device for every evaluation after (a fit's groups).
    ///
    /// [`record_evaluation`]: Self::record_evaluation
    pub fn set_parameters(&mut self, engine: &WgpuEngine, generator: &DataGenerator, params: &[f32]) -> Result<(), String> {
        let rows = params.len() / self.parameters;
        if rows == 0 || params.len() != rows * self.parameters {
            return Err(format!("{} parameter values are not whole rows of {}", params.len(), self.parameters));
        }
        self.buffers(engine, generator, rows);
        let b = self.buffers.as_mut().expect("made above");
        engine.queue.write_buffer(&b.params, 0, bytemuck::cast_slice(params));
        b.given = true;
        Ok(())
    }

    /// Records into `encoder` what `generator.evaluate(params, key)` computes for the parameter
    /// rows of [`set_parameters`](Self::set_parameters) — directions drawn from `key`, one light
    /// per view — written into `out` in the trainer's input layout with the jitter `jitter`.
    #[allow(clippy::too_many_arguments)]
    pub fn record_evaluation(&mut self, engine: &WgpuEngine, generator: &DataGenerator, key: u64, rows: usize, jitter: &[f32], encoder: &mut wgpu::CommandEncoder, out: &wgpu::Buffer) -> Result<(), String> {
        self.check(rows, jitter, out)?;
        if self.buffers.as_ref().is_none_or(|b| b.rows != rows || !b.given) {
            return Err(format!("no parameter rows set for an evaluation of {rows} rows"));
        }
        self.record_rows(engine, generator, key, 1, rows, jitter, encoder, out)
    }

    fn check(&self, rows: usize, jitter: &[f32], out: &wgpu::Buffer) -> Result<(), String> {
        if rows == 0 || jitter.len() != rows * self.latent {
            return Err(format!("a batch of {rows} rows with {} jitter values (a latent of {})", jitter.len(), self.latent));
        }
        if out.size() < (rows * self.row_stride() * 4) as u64 {
            return Err(format!("the rows buffer holds {} bytes, fewer than {rows} rows of {} floats", out.size(), self.row_stride()));
        }
        Ok(())
    }

    /// The parameter rows of a batch whose groups of `k` rows drew `picks`: the stack's
    /// defaults, a uniform class's rows as drawn, a graph class's inputs through its kernel and
    /// nb_scatter.
    fn record_parameters(&self, engine: &WgpuEngine, generator: &DataGenerator, picks: &[crate::datagen::GroupPick], k: usize, rows: usize, encoder: &mut wgpu::CommandEncoder) -> Result<(), String> {
        let np = self.parameters;
        let b = self.buffers.as_ref().expect("made by the caller");
        let (d, q) = (&engine.device, &engine.queue);
        let init = |contents: &[u8], usage: wgpu::BufferUsages| d.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: None, contents, usage });
        let uniform = |v: &[u32]| init(bytemuck::cast_slice(v), wgpu::BufferUsages::UNIFORM);
        let storage = |v: &[u8]| init(if v.is_empty() { &[0; 4] } else { v }, wgpu::BufferUsages::STORAGE);
        let group = |p: &wgpu::ComputePipeline, buffers: &[(u32, &wgpu::Buffer)]| engine.bind_buffers(&p.get_bind_group_layout(0), buffers);

        // The parameters: the stack's defaults, a uniform class's rows as drawn, a graph
        // class's inputs through its kernel and nb_scatter.
        let groups = rows / k;
        let defaults = generator.stack().defaults();
        let mut params: Vec<f32> = defaults.repeat(rows);
        let mut graph_runs = Vec::new();
        for c in 0..generator.classes().len() {
            let members: Vec<usize> = (0..groups).filter(|&g| picks[g].0 == c).collect();
            if members.is_empty() {
                continue;
            }
            let tiles: Vec<u64> = members.iter().map(|&g| picks[g].1).collect();
            let cells: Vec<u64> = members.iter().map(|&g| picks[g].2).collect();
            match generator.classes().draw(c, generator.seed, &tiles, &cells) {
                ClassDraw::Rows(p) => {
                    for (m, &g) in members.iter().enumerate() {
                        for r in g * k..(g + 1) * k {
                            params[r * np..(r + 1) * np].copy_from_slice(&p[m * np..(m + 1) * np]);
                        }
                    }
                }
                ClassDraw::Kernel { kernel, inputs, outputs } => graph_runs.push((members, kernel, inputs, outputs)),
            }
        }
        q.write_buffer(&b.params, 0, bytemuck::cast_slice(&params));
        for (members, kernel, inputs, outputs) in graph_runs {
            let n = members.len();
            let p = kernel.wgpu_pipeline().ok_or("a class kernel not prepared on the wgpu engine")?;
            let geometry = Geometry::default().repeated(n);
            let geometry = storage(bytemuck::cast_slice(geometry.data()));
            debug_assert_eq!(geometry.size() as usize, n * GEOMETRY_STRIDE * 4);
            let inputs = storage(bytemuck::cast_slice(inputs.data()));
            let class_out = d.create_buffer(&wgpu::BufferDescriptor { label: Some("class outputs"), size: (n * kernel.kernel.output_stride.max(1) * 4) as u64, usage: wgpu::BufferUsages::STORAGE, mapped_at_creation: false });
            engine.record_kernel(encoder, p, n, &geometry, &inputs, &class_out)?;
            let entries: Vec<u32> = members.iter().enumerate().flat_map(|(m, &g)| (g * k..(g + 1) * k).flat_map(move |r| [r as u32, m as u32])).collect();
            let map: Vec<u32> = outputs.iter().enumerate().filter_map(|(p, at)| at.map(|at| [p as u32, at as u32])).flatten().collect();
            let (entries_buf, map_buf) = (storage(bytemuck::cast_slice(&entries)), storage(bytemuck::cast_slice(&map)));
            let u = uniform(&[(entries.len() / 2) as u32, n as u32, (map.len() / 2) as u32, 0]);
            let g = group(&self.scatter, &[(0, &class_out), (1, &entries_buf), (2, &map_buf), (3, &b.params), (4, &u)]);
            engine.record(encoder, &self.scatter, &g, entries.len() / 2, BATCH_WORKGROUP_SIZE)?;
        }
        Ok(())
    }

    /// The rows from the parameter rows on the device: directions drawn from `key` in groups
    /// of `k`, the stack's kernels, the joins.
    #[allow(clippy::too_many_arguments)]
    fn record_rows(&self, engine: &WgpuEngine, generator: &DataGenerator, key: u64, k: usize, rows: usize, jitter: &[f32], encoder: &mut wgpu::CommandEncoder, out: &wgpu::Buffer) -> Result<(), String> {
        let b = self.buffers.as_ref().expect("made by the caller");
        let (d, q) = (&engine.device, &engine.queue);
        let init = |contents: &[u8], usage: wgpu::BufferUsages| d.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: None, contents, usage });
        let uniform = |v: &[u32]| init(bytemuck::cast_slice(v), wgpu::BufferUsages::UNIFORM);
        let group = |p: &wgpu::ComputePipeline, buffers: &[(u32, &wgpu::Buffer)]| engine.bind_buffers(&p.get_bind_group_layout(0), buffers);

        // The directions, the encoding table and the jitter.
        let mut dirs = vec![0.0f32; rows * BATCH_DIRECTION_STRIDE];
        for (r, row) in generator.draw_directions(key, rows, k).into_iter().enumerate() {
            let s = &mut dirs[r * BATCH_DIRECTION_STRIDE..(r + 1) * BATCH_DIRECTION_STRIDE];
            for (slot, v) in [(WV, row.wv), (WL_UNIFORM, row.wl), (U, row.u)] {
                s[slot as usize..slot as usize + 3].copy_from_slice(&v);
            }
            s[SAMPLED] = if row.sample { 1.0 } else { 0.0 };
        }
        q.write_buffer(&b.dirs, 0, bytemuck::cast_slice(&dirs));
        q.write_buffer(&b.table, 0, bytemuck::cast_slice(&self.table));
        q.write_buffer(&b.table, (self.table.len() * 4) as u64, bytemuck::cast_slice(jitter));

        // The stack's kernels, each fed by nb_gather.
        let kernels = [generator.sample_kernel(), generator.eval_kernel(), generator.albedo_kernel()];
        let run = |encoder: &mut wgpu::CommandEncoder, which: usize| -> Result<(), String> {
            let kernel = kernels[which];
            let columns = kernel.prepared().kernel.input_stride;
            let (inputs, outputs) = &b.kernel_io[which];
            let u = uniform(&[rows as u32, columns as u32, 0, 0]);
            let g = group(&self.gather, &[(5, &b.params), (6, &b.dirs), (7, &self.maps[which]), (8, inputs), (9, &u)]);
            engine.record(encoder, &self.gather, &g, rows, BATCH_WORKGROUP_SIZE)?;
            engine.record_kernel(encoder, wgpu_pipeline(kernel)?, rows, &b.geometry, inputs, outputs)
        };
        run(encoder, 0)?;
        let s = generator.sample_kernel();
        let u = uniform(&[rows as u32, s.output_offset("wl") as u32, s.output_offset("pdf") as u32, s.output_offset("response") as u32]);
        let g = group(&self.select, &[(10, &b.kernel_io[0].1), (11, &b.dirs), (12, &b.sel), (13, &u)]);
        engine.record(encoder, &self.select, &g, rows, BATCH_WORKGROUP_SIZE)?;
        run(encoder, 1)?;
        run(encoder, 2)?;
        let (e, a) = (generator.eval_kernel(), generator.albedo_kernel());
        let u = uniform(&[rows as u32, e.output_offset("response") as u32, a.output_offset("albedo") as u32, a.output_offset("throughput") as u32, self.latent as u32, 0, 0, 0]);
        let g = group(&self.assemble, &[(14, &b.params), (15, &b.dirs), (16, &b.sel), (17, &b.kernel_io[1].1), (18, &b.kernel_io[2].1), (19, &b.table), (20, out), (21, &u)]);
        engine.record(encoder, &self.assemble, &g, rows, BATCH_WORKGROUP_SIZE)
    }
}
