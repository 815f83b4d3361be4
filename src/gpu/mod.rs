//! GPU paths: WGSL versions of the 2D escape-time field, the IFS density field and the
//! viewer's paint callback, run through wgpu.
//!
//! The GPU computes the same per-sample quantities as [`crate::field`] (N, NF, T,
//! DEX/DEY, a bitmap trap's colour) for views that 24-bit floats can address, in two
//! precisions ([`Precision`]): plain f32, which is what a GPU does fast, and double-float
//! (an unevaluated sum of two f32s, about 46 bits), which reaches roughly 10^7 times
//! deeper at a fraction of the speed. Neither replaces the f64 or perturbation engines:
//! renders use the GPU only when asked (`--engine gpu` or `gpu-df`), and `auto` never
//! picks it. The viewer draws with it ([`paint`]) because it is interactive at any size.
//!
//! * [`GpuContext`]: a headless device (any backend, a software rasteriser such as
//!   lavapipe included) and the compute pipelines, built once and cached.
//! * [`uniforms`]: the single uniform block all pipelines share.
//! * [`shaders`]: the WGSL text and how modules are assembled from shared pieces.
//! * [`field`]: raw planes of a strip of the sample grid ([`field::compute_planes`]).
//! * [`ifs`]: the minimal IFS density field (p ← abs(p)/dot(p,p) + offset), on the CPU and on the GPU.
//! * [`paint`]: the egui paint callback that draws the escape-time image in the viewer.
//! * `runner`: chunked compute dispatches with readback.
//!
//! The GPU owns no maths types: planes come back as the same [`crate::field::Planes`] the
//! CPU kernels fill, and the rest of the program (colouring, files) cannot tell them apart.

pub mod field;
pub mod ifs;
pub mod paint;
mod runner;
pub mod shaders;
pub mod uniforms;

use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

/// Arithmetic of the GPU orbit loop.
///
/// A precision stops resolving a pixel when the spacing between samples falls below the
/// rounding unit of the coordinates, ulp ≈ `relative_ulp` × max(|centre|, 1)
/// ([`Precision::exhausted`]: neighbouring samples are then the same number). At
/// |centre| ≈ 1 and 1080 rows:
///
/// * [`Precision::F32`]: 24-bit significands, relative ulp 2^-23 ≈ 1.2e-7; exhausted past
///   zoom ≈ 3e4 (1e5 at 300 rows).
/// * [`Precision::DoubleFloat`]: hi + lo with 24 bits each, about 2^-46 ≈ 1.4e-14 relative
///   after the additions' roundings; exhausted past zoom ≈ 3e11 (1e12 at 300 rows). (Views
///   centred on short binary fractions, such as c = i, go deeper: the low parts then hold
///   the offsets exactly, as perturbation would.)
///
/// The picture degrades long before that, as the orbit amplifies rounding near the
/// boundary. `tests/integration/gpu.rs` measures, against the perturbation engine on a
/// 64x48 view of a Misiurewicz point, that N agrees on at least 99% of pixels down to
/// about [`AGREEMENT_ULPS`] rounding units per sample: zoom 1e3 in f32 and 1e10 in
/// double-float at 48 rows, i.e. about 50 and 5e8 at 1080 rows (the f64 engine, for
/// comparison, is refused below 1024 of its own ulps, past zoom ≈ 1e11 at 1080 rows).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Precision {
    /// Plain f32 arithmetic.
    F32,
    /// Double-float: each coordinate of z and c is an unevaluated sum of two f32s.
    DoubleFloat,
}

impl Precision {
    /// The engine name (`gpu`, `gpu-df`).
    pub fn name(self) -> &'static str {
        match self {
            Precision::F32 => "gpu",
            Precision::DoubleFloat => "gpu-df",
        }
    }

    /// What `--stats` prints as the precision.
    pub fn describe(self) -> &'static str {
        match self {
            Precision::F32 => "GPU f32",
            Precision::DoubleFloat => "GPU double-float (two f32)",
        }
    }

    /// Rounding unit of a coordinate relative to its magnitude.
    pub fn relative_ulp(self) -> f64 {
        match self {
            Precision::F32 => 2f64.powi(-23),
            Precision::DoubleFloat => 2f64.powi(-46),
        }
    }

    /// Rounding units of the coordinates per sample spacing at a view centred on `center`
    /// (magnitudes below 1 count as 1: orbits meet values of size ~1 whatever the view).
    pub fn ulps_per_sample(self, spacing: f64, center: [f64; 2]) -> f64 {
        let magnitude = center[0].abs().max(center[1].abs()).max(1.0);
        spacing / (self.relative_ulp() * magnitude)
    }

    /// True when neighbouring samples at this spacing are no longer distinct numbers in
    /// this precision (less than one rounding unit apart), or the spacing is not a normal,
    /// positive number f32 can hold (the double-float's low part must be representable).
    pub fn exhausted(self, spacing: f64, center: [f64; 2]) -> bool {
        if !(spacing.is_finite() && spacing > 1e-30 && spacing < 1e30) {
            return true;
        }
        let ulps = self.ulps_per_sample(spacing, center);
        ulps.is_nan() || ulps < 1.0
    }
}

/// Rounding units per sample below which N stops agreeing with exact arithmetic on 99% of
/// pixels (measured at a Misiurewicz point, both precisions: 590 to 700 suffice, 60 to 70
/// do not; see [`Precision`]).
pub const AGREEMENT_ULPS: f64 = 600.0;

/// Largest escape radius the GPU accepts: z_n^2 must stay finite in f32 (2^120 < 2^128).
pub const MAX_ESCAPE_RADIUS: f64 = 1.152_921_504_606_847e18; // 2^60

/// What went wrong on the GPU side.
#[derive(Debug, Clone, thiserror::Error)]
pub enum GpuError {
    /// No usable adapter (no GPU, no software rasteriser, or no compute shaders).
    #[error("no GPU adapter: {0}")]
    NoAdapter(String),
    /// The device could not be created or reported an error (validation, out of memory).
    #[error("GPU device error: {0}")]
    Device(String),
    /// The request is outside what the GPU paths implement.
    #[error("not supported on the GPU: {0}")]
    Unsupported(String),
    /// Reading results back failed.
    #[error("GPU readback failed: {0}")]
    Map(String),
}

/// How to install a software Vulkan rasteriser where there is no GPU.
pub const INSTALL_HINT: &str = "install a Vulkan driver; without a GPU, the software rasteriser lavapipe: \
     `apt-get install mesa-vulkan-drivers libvulkan1` (Debian/Ubuntu)";

/// A headless wgpu device and queue, with the compute pipelines built on first use.
pub struct GpuContext {
    device: wgpu::Device,
    queue: wgpu::Queue,
    adapter_name: String,
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

    /// The device.
    pub fn device(&self) -> &wgpu::Device {
        &self.device
    }

    /// The queue.
    pub fn queue(&self) -> &wgpu::Queue {
        &self.queue
    }

    /// The compute pipeline of `entry` in the module `source` builds, built once.
    pub(crate) fn compute_pipeline(
        &self,
        source: fn() -> String,
        entry: &'static str,
    ) -> Result<Arc<wgpu::ComputePipeline>, GpuError> {
        let mut cache = self.pipelines.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(p) = cache.get(entry) {
            return Ok(p.clone());
        }
        let pipeline = self.checked(|| {
            let module = self.device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(entry),
                source: wgpu::ShaderSource::Wgsl(source().into()),
            });
            let layout = self.device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(entry),
                bind_group_layouts: &[Some(&self.layout)],
                immediate_size: 0,
            });
            self.device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: Some(&layout),
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            })
        })?;
        let pipeline = Arc::new(pipeline);
        cache.insert(entry, pipeline.clone());
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
