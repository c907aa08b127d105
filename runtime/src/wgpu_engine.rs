//! The wgpu engine: runs compiled pattern kernels as compute shaders. The adapter is chosen
//! automatically (a real GPU when present, else a software adapter such as Mesa's lavapipe);
//! a machine with no adapter at all gets a clear error. Buffers follow the kernel layout of
//! `uplift_compiler::kernel` (geometry, interface inputs, outputs, point count, textures).

use uplift_compiler::kernel::*;
use uplift_compiler::PatternKernel;
use wgpu::util::DeviceExt;

/// A device and queue to run kernels on.
pub struct WgpuEngine {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub adapter_info: wgpu::AdapterInfo,
}

/// An RGBA float image bound to a kernel texture; row 0 is the top of the image.
#[derive(Clone, Debug)]
pub struct TextureData {
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<f32>,
}

/// Per-point inputs of a pattern kernel, structure of rows: `geometry` holds
/// [`GEOMETRY_STRIDE`] floats per point, `inputs` the kernel's `input_stride` floats per point.
#[derive(Clone, Debug, Default)]
pub struct PatternBatch {
    pub geometry: Vec<f32>,
    pub inputs: Vec<f32>,
    pub textures: Vec<TextureData>,
}

/// One shading point's geometry; object space equals world space.
#[derive(Clone, Copy, Debug)]
pub struct Geometry {
    pub texcoord: [f32; 2],
    pub position: [f32; 3],
    pub normal: [f32; 3],
    pub tangent: [f32; 3],
}

impl Default for Geometry {
    fn default() -> Self {
        Geometry { texcoord: [0.0; 2], position: [0.0; 3], normal: [0.0, 0.0, 1.0], tangent: [1.0, 0.0, 0.0] }
    }
}

impl Geometry {
    /// The point's row in the geometry buffer.
    pub fn row(&self) -> [f32; GEOMETRY_STRIDE] {
        let mut r = [0.0; GEOMETRY_STRIDE];
        r[0..2].copy_from_slice(&self.texcoord);
        for (k, v) in [self.position, self.normal, self.tangent].iter().enumerate() {
            r[2 + 6 * k..5 + 6 * k].copy_from_slice(v);
            r[5 + 6 * k..8 + 6 * k].copy_from_slice(v);
        }
        r
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

    /// Evaluates `kernel` for `n` points; returns `n * kernel.output_stride` floats.
    pub fn run_pattern(&self, kernel: &PatternKernel, n: usize, batch: &PatternBatch) -> Result<Vec<f32>, String> {
        if batch.geometry.len() != n * GEOMETRY_STRIDE {
            return Err(format!("geometry has {} floats; {n} points need {}", batch.geometry.len(), n * GEOMETRY_STRIDE));
        }
        if batch.inputs.len() != n * kernel.input_stride {
            return Err(format!("inputs have {} floats; {n} points need {}", batch.inputs.len(), n * kernel.input_stride));
        }
        if batch.textures.len() != kernel.textures.len() {
            return Err(format!("kernel reads {} textures, {} given", kernel.textures.len(), batch.textures.len()));
        }
        if n == 0 {
            return Ok(Vec::new());
        }
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
        let layout_entries: Vec<wgpu::BindGroupLayoutEntry> = entries
            .iter()
            .map(|(b, ty)| wgpu::BindGroupLayoutEntry { binding: *b, visibility: wgpu::ShaderStages::COMPUTE, ty: *ty, count: None })
            .collect();
        let bgl = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: None, entries: &layout_entries });
        let pl = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor { label: None, bind_group_layouts: &[Some(&bgl)], immediate_size: 0 });
        let pipeline = d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("pattern kernel"),
            layout: Some(&pl),
            module: &module,
            entry_point: Some(ENTRY_POINT),
            compilation_options: Default::default(),
            cache: None,
        });
        let buf = |data: &[f32], usage| {
            // Storage bindings may not be empty.
            let data: &[f32] = if data.is_empty() { &[0.0] } else { data };
            d.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: None, contents: bytemuck::cast_slice(data), usage })
        };
        let geometry = buf(&batch.geometry, wgpu::BufferUsages::STORAGE);
        let inputs = buf(&batch.inputs, wgpu::BufferUsages::STORAGE);
        let out_len = (n * kernel.output_stride) as u64 * 4;
        let outputs = d.create_buffer(&wgpu::BufferDescriptor { label: None, size: out_len, usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC, mapped_at_creation: false });
        let readback = d.create_buffer(&wgpu::BufferDescriptor { label: None, size: out_len, usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST, mapped_at_creation: false });
        let params = d.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: None, contents: bytemuck::cast_slice(&[n as u32, 0, 0, 0]), usage: wgpu::BufferUsages::UNIFORM });
        let views: Vec<wgpu::TextureView> = batch.textures.iter().map(|t| self.upload_texture(t)).collect::<Result<_, _>>()?;
        let mut group_entries = vec![
            wgpu::BindGroupEntry { binding: BINDING_GEOMETRY, resource: geometry.as_entire_binding() },
            wgpu::BindGroupEntry { binding: BINDING_OUTPUTS, resource: outputs.as_entire_binding() },
            wgpu::BindGroupEntry { binding: BINDING_PARAMS, resource: params.as_entire_binding() },
        ];
        if kernel.input_stride > 0 {
            group_entries.push(wgpu::BindGroupEntry { binding: BINDING_INPUTS, resource: inputs.as_entire_binding() });
        }
        for (k, v) in views.iter().enumerate() {
            group_entries.push(wgpu::BindGroupEntry { binding: BINDING_FIRST_TEXTURE + k as u32, resource: wgpu::BindingResource::TextureView(v) });
        }
        let group = d.create_bind_group(&wgpu::BindGroupDescriptor { label: None, layout: &bgl, entries: &group_entries });
        let mut encoder = d.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &group, &[]);
            let groups = (n as u32).div_ceil(WORKGROUP_SIZE);
            let max = d.limits().max_compute_workgroups_per_dimension;
            if groups > max {
                return Err(format!("{n} points exceed one dispatch ({max} workgroups); split the batch"));
            }
            pass.dispatch_workgroups(groups, 1, 1);
        }
        encoder.copy_buffer_to_buffer(&outputs, 0, &readback, 0, out_len);
        self.queue.submit([encoder.finish()]);
        let slice = readback.slice(..);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        d.poll(wgpu::PollType::wait_indefinitely()).map_err(|e| format!("wgpu poll: {e}"))?;
        rx.recv().map_err(|e| e.to_string())?.map_err(|e| format!("map readback: {e}"))?;
        let data = slice.get_mapped_range().map_err(|e| format!("map readback: {e}"))?;
        let result: Vec<f32> = bytemuck::cast_slice(&data).to_vec();
        drop(data);
        readback.unmap();
        Ok(result)
    }

    fn upload_texture(&self, t: &TextureData) -> Result<wgpu::TextureView, String> {
        if t.rgba.len() != (t.width * t.height * 4) as usize || t.width == 0 || t.height == 0 {
            return Err(format!("texture data has {} floats for {}x{} RGBA", t.rgba.len(), t.width, t.height));
        }
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
