//! The wgpu device the compute paths run on ([`GpuContext`]): opened once per process,
//! with the compute pipelines built on first use and cached. Only in builds with the `gpu`
//! feature; without it, `gpu::absent` stands in.

use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

use super::{GpuError, INSTALL_HINT, uniforms};

/// A headless wgpu device and queue, with the compute pipelines built on first use.
pub struct GpuContext {
    device: wgpu::Device,
    queue: wgpu::Queue,
    adapter_name: String,
    /// The adapter is a CPU (a software rasteriser such as lavapipe).
    software: bool,
    /// Binding layout of every compute pipeline (uniforms, texels, output words).
    layout: wgpu::BindGroupLayout,
    pipelines: Mutex<HashMap<&'static str, Arc<wgpu::ComputePipeline>>>,
}

impl std::fmt::Debug for GpuContext {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GpuContext").field("adapter", &self.adapter_name).finish_non_exhaustive()
    }
}

impl GpuContext {
    /// Opens a device on the first adapter that runs compute shaders: the primary backends
    /// (Vulkan, Metal, DX12) first, then OpenGL (probing GL opens a display connection and
    /// is noisy, so it is only tried when nothing else exists), or exactly the backends
    /// named by `WGPU_BACKEND`; for each, a hardware adapter first, then a fallback
    /// (software) one. Blocks until the device is ready.
    pub fn new() -> Result<Self, GpuError> {
        let tiers = match wgpu::Backends::from_env() {
            Some(chosen) => vec![chosen],
            None => vec![wgpu::Backends::PRIMARY, wgpu::Backends::SECONDARY],
        };
        let mut why = Vec::new();
        for backends in tiers {
            let mut descriptor = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
            descriptor.backends = backends;
            let instance = wgpu::Instance::new(descriptor);
            for fallback in [false, true] {
                let options = wgpu::RequestAdapterOptions {
                    power_preference: wgpu::PowerPreference::HighPerformance,
                    force_fallback_adapter: fallback,
                    ..Default::default()
                };
                match pollster::block_on(instance.request_adapter(&options)) {
                    Ok(adapter) => {
                        let info = adapter.get_info();
                        let flags = adapter.get_downlevel_capabilities().flags;
                        if flags.contains(wgpu::DownlevelFlags::COMPUTE_SHADERS) {
                            return Self::open(&adapter);
                        }
                        why.push(format!("{} ({:?}) has no compute shaders", info.name, info.backend));
                    }
                    Err(e) => {
                        // The fallback request usually fails the same way: say it once.
                        let line = format!("{backends:?}: {e}");
                        if why.last() != Some(&line) {
                            why.push(line);
                        }
                    }
                }
            }
        }
        Err(GpuError::NoAdapter(format!("{}; {INSTALL_HINT}", why.join("; "))))
    }

    fn open(adapter: &wgpu::Adapter) -> Result<Self, GpuError> {
        let info = adapter.get_info();
        let descriptor = wgpu::DeviceDescriptor {
            label: Some("deepfield"),
            required_limits: adapter.limits(),
            ..Default::default()
        };
        let (device, queue) =
            pollster::block_on(adapter.request_device(&descriptor)).map_err(|e| GpuError::Device(e.to_string()))?;
        let layout = compute_layout(&device);
        Ok(Self {
            device,
            queue,
            adapter_name: format!("{} ({:?})", info.name, info.backend),
            software: info.device_type == wgpu::DeviceType::Cpu,
            layout,
            pipelines: Mutex::new(HashMap::new()),
        })
    }

    /// The process-wide context, opened on first use; a failure is remembered (the same
    /// error comes back every time).
    pub fn shared() -> Result<Arc<GpuContext>, GpuError> {
        static SHARED: OnceLock<Result<Arc<GpuContext>, GpuError>> = OnceLock::new();
        SHARED.get_or_init(|| GpuContext::new().map(Arc::new)).clone()
    }

    /// The adapter's name and backend, e.g. "llvmpipe (LLVM 15.0.6, 256 bits) (Vulkan)".
    pub fn adapter_name(&self) -> &str {
        &self.adapter_name
    }

    /// True when the adapter runs on the CPU (lavapipe): its f32 arithmetic is the CPU's,
    /// correctly rounded, where WGSL lets a GPU divide to 2.5 ULP and fuse a multiply with
    /// an add.
    pub fn software(&self) -> bool {
        self.software
    }

    /// The device.
    pub fn device(&self) -> &wgpu::Device {
        &self.device
    }

    /// The queue.
    pub fn queue(&self) -> &wgpu::Queue {
        &self.queue
    }

    /// The compute pipeline of `entry` in the module `source` builds, built once and cached
    /// under `name` (one name per module and entry point).
    pub(crate) fn compute_pipeline(
        &self,
        name: &'static str,
        source: impl FnOnce() -> String,
        entry: &'static str,
    ) -> Result<Arc<wgpu::ComputePipeline>, GpuError> {
        let mut cache = self.pipelines.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(p) = cache.get(name) {
            return Ok(p.clone());
        }
        let pipeline = self.checked(|| {
            let module = self.device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(name),
                source: wgpu::ShaderSource::Wgsl(source().into()),
            });
            let layout = self.device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(name),
                bind_group_layouts: &[Some(&self.layout)],
                immediate_size: 0,
            });
            self.device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(name),
                layout: Some(&layout),
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            })
        })?;
        let pipeline = Arc::new(pipeline);
        cache.insert(name, pipeline.clone());
        Ok(pipeline)
    }

    /// Runs `work` inside validation and out-of-memory error scopes, turning what they
    /// catch into [`GpuError::Device`] instead of wgpu's default panic.
    pub(crate) fn checked<T>(&self, work: impl FnOnce() -> T) -> Result<T, GpuError> {
        checked(&self.device, work)
    }

    pub(crate) fn compute_layout(&self) -> &wgpu::BindGroupLayout {
        &self.layout
    }
}

/// [`GpuContext::checked`] for any device.
pub(crate) fn checked<T>(device: &wgpu::Device, work: impl FnOnce() -> T) -> Result<T, GpuError> {
    let memory = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let validation = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let out = work();
    let v = pollster::block_on(validation.pop());
    let m = pollster::block_on(memory.pop());
    match v.or(m) {
        Some(e) => Err(GpuError::Device(e.to_string())),
        None => Ok(out),
    }
}

/// Binding 0: the uniform block; 1: read-only texels (the bitmap trap, or one dummy texel);
/// 2: the output words.
fn compute_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    let storage = |binding, read_only| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    };
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("deepfield compute"),
        entries: &[uniform_entry(0, wgpu::ShaderStages::COMPUTE), storage(1, true), storage(2, false)],
    })
}

/// The layout entry of the uniform block, sized so that wgpu rejects a shader whose
/// `Params` is larger than [`uniforms::Uniforms`].
pub(crate) fn uniform_entry(binding: u32, visibility: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: wgpu::BufferSize::new(uniforms::UNIFORMS_SIZE as u64),
        },
        count: None,
    }
}
