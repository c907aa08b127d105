//! The wgpu engine: runs compiled pattern kernels as compute shaders. The adapter is chosen
//! automatically (a real GPU when present, else a software adapter such as Mesa's lavapipe);
//! a machine with no adapter at all gets a clear error. Buffers follow the kernel layout of
//! `uplift_compiler::kernel`: column-major geometry, interface inputs and outputs, the point
//! count, textures. A batch larger than one storage binding allows runs in several dispatches.

use crate::batch::{Columns, KernelShape, PatternBatch, PatternEngine, TextureData};
use uplift_compiler::kernel::*;
use uplift_compiler::PatternKernel;
use wgpu::util::DeviceExt;

/// A device and queue to run kernels on. A clone shares them (wgpu's handles are shared).
#[derive(Clone)]
pub struct WgpuEngine {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub adapter_info: wgpu::AdapterInfo,
}

/// Keeps a headless run quiet: Mesa's implicit Vulkan layer `VK_LAYER_MESA_device_select`
/// connects to a Wayland display whenever the instance enables `VK_KHR_wayland_surface` (wgpu
/// always does), and libwayland prints `error: XDG_RUNTIME_DIR is invalid or not set in the
/// environment.` when there is none. Without a display (no `WAYLAND_DISPLAY`, no usable
/// `XDG_RUNTIME_DIR`) the layer has no display to pick a device by, so it is switched off
/// (`NODEVICE_SELECT=1`, Mesa's own switch) unless the user chose a device with it
/// (`MESA_VK_DEVICE_SELECT`) or set the switch. Call at the start of `main`, before any thread
/// exists (it sets an environment variable).
pub fn quiet_headless_vulkan() {
    let var = |k: &str| std::env::var_os(k).filter(|v| !v.is_empty());
    let runtime_dir = var("XDG_RUNTIME_DIR").is_some_and(|d| std::path::Path::new(&d).is_dir());
    if var("WAYLAND_DISPLAY").is_none() && !runtime_dir && var("MESA_VK_DEVICE_SELECT").is_none() && var("NODEVICE_SELECT").is_none() {
        std::env::set_var("NODEVICE_SELECT", "1");
    }
}

impl WgpuEngine {
    /// Opens the best available adapter (falling back to a software one).
    pub fn new() -> Result<WgpuEngine, String> {
        pollster::block_on(Self::new_async())
    }

    async fn new_async() -> Result<WgpuEngine, String> {
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let mut adapter = instance
            .request_adapter(&wgpu::RequestAdapterOptions { power_preference: wgpu::PowerPreference::HighPerformance, ..Default::default() })
            .await
            .ok();
        if adapter.is_none() {
            adapter = instance
                .request_adapter(&wgpu::RequestAdapterOptions { force_fallback_adapter: true, ..Default::default() })
                .await
                .ok();
        }
        let adapter = adapter.ok_or_else(|| {
            "no wgpu adapter found: install a Vulkan driver (on Debian without a GPU: apt-get install mesa-vulkan-drivers libvulkan1)".to_string()
        })?;
        let adapter_info = adapter.get_info();
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("uplift"),
                required_limits: adapter.limits(),
                ..Default::default()
            })
            .await
            .map_err(|e| format!("cannot open wgpu device on {}: {e}", adapter_info.name))?;
        Ok(WgpuEngine { device, queue, adapter_info })
    }

    /// Builds the compute pipeline for `kernel` (shader compilation happens here), so that
    /// several batches can run without compiling again.
    pub fn prepare(&self, kernel: &PatternKernel) -> WgpuPipeline {
        let d = &self.device;
        let module = d.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("pattern kernel"),
            source: wgpu::ShaderSource::Wgsl(kernel.wgsl.as_str().into()),
        });
        let storage = |read_only| wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        };
        let mut entries = vec![(BINDING_GEOMETRY, storage(true)), (BINDING_OUTPUTS, storage(false))];
        if kernel.input_stride > 0 {
            entries.push((BINDING_INPUTS, storage(true)));
        }
        entries.push((
            BINDING_PARAMS,
            wgpu::BindingType::Buffer { ty: wgpu::BufferBindingType::Uniform, has_dynamic_offset: false, min_binding_size: None },
        ));
        for k in 0..kernel.textures.len() {
            entries.push((
                BINDING_FIRST_TEXTURE + k as u32,
                wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: false },
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: false,
                },
            ));
        }
        if kernel.albedo_tables.is_some() {
            entries.push((BINDING_ALBEDO_TABLES, storage(true)));
        }
        let layout_entries: Vec<wgpu::BindGroupLayoutEntry> = entries
            .iter()
            .map(|(b, ty)| wgpu::BindGroupLayoutEntry { binding: *b, visibility: wgpu::ShaderStages::COMPUTE, ty: *ty, count: None })
            .collect();
        let layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: None, entries: &layout_entries });
        let pl = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor { label: None, bind_group_layouts: &[Some(&layout)], immediate_size: 0 });
        let pipeline = d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("pattern kernel"),
            layout: Some(&pl),
            module: &module,
            entry_point: Some(ENTRY_POINT),
            compilation_options: Default::default(),
            cache: None,
        });
        // The albedo tables, uploaded once per pipeline.
        let albedo_tables = kernel.albedo_tables.as_ref().map(|data| {
            d.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some("albedo tables"), contents: bytemuck::cast_slice(data), usage: wgpu::BufferUsages::STORAGE })
        });
        WgpuPipeline {
            pipeline,
            layout,
            shape: crate::batch::kernel_shape(kernel),
            albedo_tables,
        }
    }

    /// The most points one dispatch takes: every buffer within one storage binding, and the
    /// workgroups within a two-dimensional dispatch.
    pub fn max_points_per_dispatch(&self, p: &WgpuPipeline) -> usize {
        let limits = self.device.limits();
        let widest = GEOMETRY_STRIDE.max(p.shape.input_columns).max(p.shape.output_columns) as u64 * 4;
        let binding = limits.max_storage_buffer_binding_size.min(limits.max_buffer_size) / widest;
        let groups = limits.max_compute_workgroups_per_dimension as u64;
        binding.min(groups * groups * WORKGROUP_SIZE as u64).max(1) as usize
    }

    /// Evaluates a prepared kernel for every point of `batch` (checked against its shape), in as
    /// many dispatches as the limits need.
    pub fn run_prepared(&self, p: &WgpuPipeline, batch: &PatternBatch) -> Result<Columns, String> {
        self.run_chunked(p, batch, self.max_points_per_dispatch(p))
    }

    /// [`run_prepared`](Self::run_prepared) with at most `chunk` points per dispatch (textures
    /// are uploaded once for all of them).
    pub fn run_chunked(&self, p: &WgpuPipeline, batch: &PatternBatch, chunk: usize) -> Result<Columns, String> {
        let n = batch.check_shape(&p.shape)?;
        if n == 0 {
            return Ok(Columns::zeros(0, p.shape.output_columns));
        }
        let views: Vec<wgpu::TextureView> = batch.textures.iter().map(|t| self.upload_texture(t)).collect::<Result<_, _>>()?;
        let chunk = chunk.clamp(1, self.max_points_per_dispatch(p));
        if n <= chunk {
            return self.dispatch(p, &batch.geometry, &batch.inputs, &views);
        }
        let mut out = Columns::zeros(n, p.shape.output_columns);
        let mut start = 0;
        while start < n {
            let m = chunk.min(n - start);
            out.write_at(start, &self.dispatch(p, &batch.geometry.slice(start, m), &batch.inputs.slice(start, m), &views)?);
            start += m;
        }
        Ok(out)
    }

    /// One dispatch over every point of `geometry` and `inputs` (at least one point).
    fn dispatch(&self, p: &WgpuPipeline, geometry: &Columns, inputs: &Columns, views: &[wgpu::TextureView]) -> Result<Columns, String> {
        let n = geometry.n();
        let d = &self.device;
        let buf = |data: &[f32], usage| {
            // Storage bindings may not be empty.
            let data: &[f32] = if data.is_empty() { &[0.0] } else { data };
            d.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: None, contents: bytemuck::cast_slice(data), usage })
        };
        let geometry = buf(geometry.data(), wgpu::BufferUsages::STORAGE);
        let inputs = buf(inputs.data(), wgpu::BufferUsages::STORAGE);
        let out_len = (n * p.shape.output_columns) as u64 * 4;
        let outputs = d.create_buffer(&wgpu::BufferDescriptor { label: None, size: out_len, usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC, mapped_at_creation: false });
        let group = self.kernel_group(p, n, &geometry, &inputs, &outputs, views);
        let mut encoder = d.create_command_encoder(&Default::default());
        self.record(&mut encoder, &p.pipeline, &group, n, WORKGROUP_SIZE)?;
        let result = self.submit_and_read(encoder, &outputs, out_len)?;
        Columns::from_column_major(n, p.shape.output_columns, result)
    }

    /// Records into `encoder` one dispatch of a prepared kernel that reads no textures over the
    /// caller's device buffers (the layout of `uplift_compiler::kernel`, column-major for `n`
    /// points): so that one kernel's outputs can feed the next without leaving the device.
    #[allow(clippy::too_many_arguments)]
    pub fn record_kernel(&self, encoder: &mut wgpu::CommandEncoder, p: &WgpuPipeline, n: usize, geometry: &wgpu::Buffer, inputs: &wgpu::Buffer, outputs: &wgpu::Buffer) -> Result<(), String> {
        if p.shape.texture_count > 0 {
            return Err(format!("a kernel reading {} textures cannot run on device buffers alone", p.shape.texture_count));
        }
        let need = |b: &wgpu::Buffer, columns: usize, what: &str| {
            if b.size() < (n * columns.max(1) * 4) as u64 {
                return Err(format!("the {what} buffer holds {} bytes, fewer than {n} points × {columns} columns", b.size()));
            }
            Ok(())
        };
        need(geometry, GEOMETRY_STRIDE, "geometry")?;
        need(inputs, p.shape.input_columns, "inputs")?;
        need(outputs, p.shape.output_columns, "outputs")?;
        let group = self.kernel_group(p, n, geometry, inputs, outputs, &[]);
        self.record(encoder, &p.pipeline, &group, n, WORKGROUP_SIZE)
    }

    /// A compiled kernel's bind group over `n` points: its geometry, inputs (bound when it has
    /// input columns), outputs, point count, textures and albedo tables.
    fn kernel_group(&self, p: &WgpuPipeline, n: usize, geometry: &wgpu::Buffer, inputs: &wgpu::Buffer, outputs: &wgpu::Buffer, views: &[wgpu::TextureView]) -> wgpu::BindGroup {
        let params = self.device.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: None, contents: bytemuck::cast_slice(&[n as u32, 0, 0, 0]), usage: wgpu::BufferUsages::UNIFORM });
        let mut entries = vec![
            wgpu::BindGroupEntry { binding: BINDING_GEOMETRY, resource: geometry.as_entire_binding() },
            wgpu::BindGroupEntry { binding: BINDING_OUTPUTS, resource: outputs.as_entire_binding() },
            wgpu::BindGroupEntry { binding: BINDING_PARAMS, resource: params.as_entire_binding() },
        ];
        if p.shape.input_columns > 0 {
            entries.push(wgpu::BindGroupEntry { binding: BINDING_INPUTS, resource: inputs.as_entire_binding() });
        }
        for (k, v) in views.iter().enumerate() {
            entries.push(wgpu::BindGroupEntry { binding: BINDING_FIRST_TEXTURE + k as u32, resource: wgpu::BindingResource::TextureView(v) });
        }
        if let Some(t) = &p.albedo_tables {
            entries.push(wgpu::BindGroupEntry { binding: BINDING_ALBEDO_TABLES, resource: t.as_entire_binding() });
        }
        self.device.create_bind_group(&wgpu::BindGroupDescriptor { label: None, layout: &p.layout, entries: &entries })
    }

    /// A bind group of whole buffers at their bindings in `layout` (the small joining shaders'
    /// groups: `(binding, buffer)` pairs).
    pub fn bind_buffers(&self, layout: &wgpu::BindGroupLayout, buffers: &[(u32, &wgpu::Buffer)]) -> wgpu::BindGroup {
        let entries: Vec<wgpu::BindGroupEntry> = buffers.iter().map(|(binding, b)| wgpu::BindGroupEntry { binding: *binding, resource: b.as_entire_binding() }).collect();
        self.device.create_bind_group(&wgpu::BindGroupDescriptor { label: None, layout, entries: &entries })
    }

    /// The workgroup grid for `n` invocations in workgroups of `size`: (groups, 1) while one
    /// dimension holds them, else (max, ⌈groups / max⌉). Every uplift shader numbers its
    /// invocations id.x + id.y × (workgroups in x) × size.
    pub fn grid(&self, n: usize, size: u32) -> Result<(u32, u32), String> {
        let groups = (n as u64).div_ceil(size as u64).max(1);
        let max = self.device.limits().max_compute_workgroups_per_dimension as u64;
        let (x, y) = if groups <= max { (groups, 1) } else { (max, groups.div_ceil(max)) };
        if y > max {
            return Err(format!("{n} invocations exceed one dispatch ({max} × {max} workgroups of {size}); split the batch"));
        }
        Ok((x as u32, y as u32))
    }

    /// Records a compute pass of `pipeline` with bind group 0 over [`grid`](Self::grid)`(n, size)`.
    pub fn record(&self, encoder: &mut wgpu::CommandEncoder, pipeline: &wgpu::ComputePipeline, group: &wgpu::BindGroup, n: usize, size: u32) -> Result<(), String> {
        let (x, y) = self.grid(n, size)?;
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, group, &[]);
        pass.dispatch_workgroups(x, y, 1);
        Ok(())
    }

    /// Finishes `encoder` with a copy of `source`'s first `size` bytes into a mappable buffer,
    /// submits it, waits, and returns those bytes as floats.
    pub fn submit_and_read(&self, encoder: wgpu::CommandEncoder, source: &wgpu::Buffer, size: u64) -> Result<Vec<f32>, String> {
        self.submit_and_read_at(encoder, source, 0, size)
    }

    /// [`submit_and_read`](Self::submit_and_read) of the `size` bytes at `offset`.
    pub fn submit_and_read_at(&self, mut encoder: wgpu::CommandEncoder, source: &wgpu::Buffer, offset: u64, size: u64) -> Result<Vec<f32>, String> {
        let readback = self.device.create_buffer(&wgpu::BufferDescriptor { label: None, size, usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST, mapped_at_creation: false });
        encoder.copy_buffer_to_buffer(source, offset, &readback, 0, size);
        self.queue.submit([encoder.finish()]);
        let slice = readback.slice(..);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        self.device.poll(wgpu::PollType::wait_indefinitely()).map_err(|e| format!("wgpu poll: {e}"))?;
        rx.recv().map_err(|e| e.to_string())?.map_err(|e| format!("map readback: {e}"))?;
        let data = slice.get_mapped_range().map_err(|e| format!("map readback: {e}"))?;
        let result: Vec<f32> = bytemuck::cast_slice(&data).to_vec();
        drop(data);
        readback.unmap();
        Ok(result)
    }

    fn upload_texture(&self, t: &TextureData) -> Result<wgpu::TextureView, String> {
        t.check()?;
        let size = wgpu::Extent3d { width: t.width, height: t.height, depth_or_array_layers: 1 };
        let tex = self.device.create_texture_with_data(
            &self.queue,
            &wgpu::TextureDescriptor {
                label: None,
                size,
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::Rgba32Float,
                usage: wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            },
            wgpu::util::TextureDataOrder::LayerMajor,
            bytemuck::cast_slice(&t.rgba),
        );
        Ok(tex.create_view(&Default::default()))
    }
}

/// A kernel's compute pipeline and bind-group layout on one device ([`WgpuEngine::prepare`]).
pub struct WgpuPipeline {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    shape: KernelShape,
    albedo_tables: Option<wgpu::Buffer>,
}

impl PatternEngine for WgpuEngine {
    fn describe(&self) -> String {
        format!("wgpu on {} ({:?})", self.adapter_info.name, self.adapter_info.backend)
    }

    fn run_pattern(&self, kernel: &PatternKernel, batch: &PatternBatch) -> Result<Columns, String> {
        batch.check(kernel)?; // before compiling the shader
        crate::batch::check_build_size(kernel)?;
        let p = self.prepare(kernel);
        self.run_prepared(&p, batch)
    }
}
