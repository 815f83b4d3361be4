//! The viewer's GPU drawing: an egui paint callback that renders the escape-time image
//! straight into the egui frame with a fragment shader, one orbit per physical pixel.
//!
//! The fragment shader (`paint.wgsl`) is appended to the compute kernel's own text
//! (`src/gpu/escape.wgsl` after a precision's number prelude), so the viewer and `--engine
//! gpu` iterate identically. It colours by smooth iteration nu = N + NF through a palette
//! table (linear RGBA sampled from a [`Palette`] with [`palette_table`]) at position nu *
//! density + offset (the table repeats), and can multiply Inigo Quilez's soft distance
//! shading clamp((k d)^0.2, 0, 1) over it (d in physical pixels, the grey read as sRGB as
//! the CPU's distance layer does).
//! Output is opaque (premultiplied colour over black) and encoded for the target: linear
//! when the target format is sRGB (the hardware encodes), sRGB-encoded otherwise; egui-wgpu
//! prefers `Rgba8Unorm`/`Bgra8Unorm` targets, so the shader usually encodes.
//!
//! Use: call [`register`] once with eframe's `RenderState` (it builds the pipelines into
//! the renderer's `callback_resources`), then add [`paint_callback`] shapes each frame.
//! Several callbacks in one frame are fine: each gets its own uniform slot. The pipelines
//! assume egui's default pass (one sample, no depth buffer); [`PaintResources::new`]
//! takes other settings. [`render_offscreen`] draws the same pipeline into a texture and
//! reads it back (tests, thumbnails).

use std::sync::atomic::{AtomicUsize, Ordering};

use eframe::egui;
use eframe::egui_wgpu;
// wgpu through eframe's re-export (the same crate `crate::gpu` uses): the viewer depends on eframe alone.
use eframe::egui_wgpu::wgpu::{self, util::DeviceExt};

use crate::gpu::uniforms::{self, Uniforms};
use crate::gpu::{GpuContext, GpuError, MAX_ESCAPE_RADIUS, Precision, shaders};
use crate::palette::Palette;

/// The vertex and fragment shaders; the rest of the module is the escape-time compute
/// module's text ([`shaders::escape_module`]).
const PAINT_WGSL: &str = include_str!("paint.wgsl");
/// Vertex entry point.
const PAINT_VS_ENTRY: &str = "paint_vs";
/// Fragment entry point (either precision's module).
const PAINT_FS_ENTRY: &str = "paint_fs";

/// The paint module of `precision`: the escape-time module plus the vertex and fragment
/// shaders, so the image iterates with the compute kernel's own text.
fn paint_module(precision: Precision) -> String {
    [shaders::escape_module(precision).as_str(), PAINT_WGSL].concat()
}

/// What the paint callback draws.
#[derive(Debug, Clone, PartialEq)]
pub struct PaintParams {
    /// Point of the plane at the centre of the image.
    pub center: [f64; 2],
    /// Plane units per physical pixel.
    pub spacing: f64,
    /// Size of the image in physical pixels (the callback rectangle times pixels per point).
    pub size_px: [u32; 2],
    /// Julia parameter, or None for the Mandelbrot set.
    pub julia: Option<[f64; 2]>,
    /// Iteration limit.
    pub max_iter: u32,
    /// Escape radius R (clamped into [2, 2^60]).
    pub escape_radius: f64,
    /// Orbit arithmetic.
    pub precision: Precision,
    /// Palette table: linear RGBA (not premultiplied) at positions k / len, repeating.
    pub palette: Vec<[f32; 4]>,
    /// Palette cycles per iteration.
    pub density: f32,
    /// Palette offset in cycles.
    pub offset: f32,
    /// Soft distance shading clamp((k d)^0.2, 0, 1) multiplied over the colour, when set.
    pub distance_k: Option<f32>,
    /// Colour of interior pixels (linear RGBA).
    pub interior: [f32; 4],
}

impl Default for PaintParams {
    fn default() -> Self {
        Self {
            center: [-0.75, 0.0],
            spacing: 4.0 / 600.0,
            size_px: [800, 600],
            julia: None,
            max_iter: 1000,
            escape_radius: 65536.0,
            precision: Precision::F32,
            palette: vec![[0.0, 0.0, 0.0, 1.0], [1.0, 1.0, 1.0, 1.0]],
            density: 1.0 / 32.0,
            offset: 0.0,
            distance_k: None,
            interior: [0.0, 0.0, 0.0, 1.0],
        }
    }
}

/// Samples `palette` at `n` evenly spaced positions k / n (its own density, offset and
/// mode apply, as in [`Palette::at`]): the table [`PaintParams::palette`] wants.
pub fn palette_table(palette: &Palette, n: usize) -> Vec<[f32; 4]> {
    (0..n.max(1)).map(|k| palette.at(k as f64 / n.max(1) as f64)).collect()
}

/// The uniform block of a paint: `origin` is the image's top-left corner in target pixels.
pub fn paint_uniforms(params: &PaintParams, origin: [f32; 2], encode_srgb: bool) -> Uniforms {
    let mut u = Uniforms::default();
    let [w, h] = params.size_px;
    u.set_view(params.center, params.spacing, w.max(1), h.max(1));
    u.set_orbit(params.julia, params.max_iter, params.escape_radius.clamp(2.0, MAX_ESCAPE_RADIUS));
    if let Some(k) = params.distance_k {
        u.flags |= uniforms::FLAG_DERIVATIVE | uniforms::FLAG_DISTANCE_SHADE;
        u.distance_k = k;
    }
    u.palette_len = params.palette.len().max(1) as u32;
    u.palette_density = params.density;
    u.palette_offset = params.offset;
    u.origin_x = origin[0];
    u.origin_y = origin[1];
    u.encode_srgb = u32::from(encode_srgb);
    [u.interior_r, u.interior_g, u.interior_b, u.interior_a] = params.interior;
    u
}

/// Per-callback GPU state: a uniform buffer, a palette buffer and their bind group.
struct Slot {
    uniforms: wgpu::Buffer,
    palette: wgpu::Buffer,
    palette_len: usize,
    bind_group: wgpu::BindGroup,
}

/// The paint pipelines and per-callback slots, kept in egui-wgpu's `callback_resources`.
pub struct PaintResources {
    f32_pipeline: wgpu::RenderPipeline,
    df_pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    texels: wgpu::Buffer,
    slots: Vec<Slot>,
    next: usize,
    encode_srgb: bool,
}

impl PaintResources {
    /// Builds the pipelines for a target `format` with `samples` samples per pixel and an
    /// optional depth attachment format (egui's pass: 1 and None unless configured).
    pub fn new(
        device: &wgpu::Device,
        format: wgpu::TextureFormat,
        samples: u32,
        depth: Option<wgpu::TextureFormat>,
    ) -> Result<Self, GpuError> {
        crate::gpu::checked(device, || {
            let storage = |binding| wgpu::BindGroupLayoutEntry {
                binding,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Storage { read_only: true },
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            };
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("deepfield paint"),
                entries: &[crate::gpu::uniform_entry(0, wgpu::ShaderStages::FRAGMENT), storage(1), storage(3)],
            });
            let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("deepfield paint"),
                bind_group_layouts: &[Some(&layout)],
                immediate_size: 0,
            });
            let pipeline = |precision: Precision| {
                let label = Some(precision.describe());
                let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                    label,
                    source: wgpu::ShaderSource::Wgsl(paint_module(precision).into()),
                });
                device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label,
                    layout: Some(&pipeline_layout),
                    vertex: wgpu::VertexState {
                        module: &module,
                        entry_point: Some(PAINT_VS_ENTRY),
                        compilation_options: Default::default(),
                        buffers: &[],
                    },
                    primitive: wgpu::PrimitiveState::default(),
                    depth_stencil: depth.map(|format| wgpu::DepthStencilState {
                        format,
                        depth_write_enabled: Some(false),
                        depth_compare: Some(wgpu::CompareFunction::Always),
                        stencil: Default::default(),
                        bias: Default::default(),
                    }),
                    multisample: wgpu::MultisampleState { count: samples.max(1), ..Default::default() },
                    fragment: Some(wgpu::FragmentState {
                        module: &module,
                        entry_point: Some(PAINT_FS_ENTRY),
                        compilation_options: Default::default(),
                        targets: &[Some(wgpu::ColorTargetState {
                            format,
                            blend: None,
                            write_mask: wgpu::ColorWrites::ALL,
                        })],
                    }),
                    multiview_mask: None,
                    cache: None,
                })
            };
            let texels = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("deepfield paint texels"),
                contents: bytemuck::cast_slice(&[[0.0f32; 4]]),
                usage: wgpu::BufferUsages::STORAGE,
            });
            Self {
                f32_pipeline: pipeline(Precision::F32),
                df_pipeline: pipeline(Precision::DoubleFloat),
                layout,
                texels,
                slots: Vec::new(),
                next: 0,
                encode_srgb: !format.is_srgb(),
            }
        })
    }

    /// Writes `params` into the next free slot (growing its palette buffer as needed) and
    /// returns the slot's index.
    pub fn prepare(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        params: &PaintParams,
        origin: [f32; 2],
    ) -> usize {
        let index = self.next;
        self.next += 1;
        let palette: Vec<[f32; 4]> =
            if params.palette.is_empty() { vec![[0.5, 0.5, 0.5, 1.0]] } else { params.palette.clone() };
        let uniforms = paint_uniforms(params, origin, self.encode_srgb);
        let fits = self.slots.get(index).is_some_and(|s| s.palette_len >= palette.len());
        if !fits {
            let uniform_buf = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("deepfield paint uniforms"),
                size: uniforms::UNIFORMS_SIZE as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let palette_buf = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("deepfield paint palette"),
                size: (palette.len() * 16) as u64,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("deepfield paint"),
                layout: &self.layout,
                entries: &[
                    wgpu::BindGroupEntry { binding: 0, resource: uniform_buf.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 1, resource: self.texels.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 3, resource: palette_buf.as_entire_binding() },
                ],
            });
            let slot = Slot { uniforms: uniform_buf, palette: palette_buf, palette_len: palette.len(), bind_group };
            if index < self.slots.len() {
                self.slots[index] = slot;
            } else {
                self.slots.push(slot);
            }
        }
        let slot = &self.slots[index];
        queue.write_buffer(&slot.uniforms, 0, uniforms.bytes());
        queue.write_buffer(&slot.palette, 0, bytemuck::cast_slice(&palette));
        index
    }

    /// Marks every slot free again (after a frame's callbacks were prepared).
    pub fn end_frame(&mut self) {
        self.next = 0;
    }

    /// Draws slot `slot` into `pass` (the viewport and scissor are the caller's).
    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>, slot: usize, precision: Precision) {
        let Some(s) = self.slots.get(slot) else { return };
        pass.set_pipeline(match precision {
            Precision::F32 => &self.f32_pipeline,
            Precision::DoubleFloat => &self.df_pipeline,
        });
        pass.set_bind_group(0, &s.bind_group, &[]);
        pass.draw(0..3, 0..1);
    }
}

/// Builds the paint pipelines for eframe's render state (target format, one sample, no
/// depth) and stores them in the renderer's callback resources. Call once at start-up.
pub fn register(render_state: &egui_wgpu::RenderState) -> Result<(), GpuError> {
    let resources = PaintResources::new(&render_state.device, render_state.target_format, 1, None)?;
    render_state.renderer.write().callback_resources.insert(resources);
    Ok(())
}

/// The callback behind [`paint_callback`].
struct EscapeCallback {
    rect: egui::Rect,
    params: PaintParams,
    slot: AtomicUsize,
}

impl egui_wgpu::CallbackTrait for EscapeCallback {
    fn prepare(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        screen: &egui_wgpu::ScreenDescriptor,
        _encoder: &mut wgpu::CommandEncoder,
        resources: &mut egui_wgpu::CallbackResources,
    ) -> Vec<wgpu::CommandBuffer> {
        if let Some(r) = resources.get_mut::<PaintResources>() {
            // The image's corner in target pixels, rounded as egui rounds the viewport.
            let ppp = screen.pixels_per_point;
            let origin = [(self.rect.min.x * ppp).round(), (self.rect.min.y * ppp).round()];
            self.slot.store(r.prepare(device, queue, &self.params, origin), Ordering::Relaxed);
        }
        Vec::new()
    }

    fn finish_prepare(
        &self,
        _device: &wgpu::Device,
        _queue: &wgpu::Queue,
        _encoder: &mut wgpu::CommandEncoder,
        resources: &mut egui_wgpu::CallbackResources,
    ) -> Vec<wgpu::CommandBuffer> {
        if let Some(r) = resources.get_mut::<PaintResources>() {
            r.end_frame();
        }
        Vec::new()
    }

    fn paint(
        &self,
        _info: egui::PaintCallbackInfo,
        pass: &mut wgpu::RenderPass<'static>,
        resources: &egui_wgpu::CallbackResources,
    ) {
        if let Some(r) = resources.get::<PaintResources>() {
            r.draw(pass, self.slot.load(Ordering::Relaxed), self.params.precision);
        }
    }
}

/// A paint callback that draws the escape-time image of `params` into `rect` (points).
/// [`register`] must have run; without it the callback draws nothing.
pub fn paint_callback(rect: egui::Rect, params: PaintParams) -> egui::PaintCallback {
    egui_wgpu::Callback::new_paint_callback(rect, EscapeCallback { rect, params, slot: AtomicUsize::new(0) })
}

/// Renders `params` with the paint pipeline into a `size_px` texture of `format`
/// (`Rgba8Unorm` or `Rgba8UnormSrgb`) and reads it back: RGBA bytes, row-major.
pub fn render_offscreen(
    ctx: &GpuContext,
    params: &PaintParams,
    format: wgpu::TextureFormat,
) -> Result<Vec<[u8; 4]>, GpuError> {
    if !matches!(format, wgpu::TextureFormat::Rgba8Unorm | wgpu::TextureFormat::Rgba8UnormSrgb) {
        return Err(GpuError::Unsupported(format!("offscreen paint into {format:?}; use Rgba8Unorm(Srgb)")));
    }
    let (device, queue) = (ctx.device(), ctx.queue());
    let mut resources = PaintResources::new(device, format, 1, None)?;
    let [w, h] = params.size_px;
    let padded = (w * 4).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let bytes = padded as u64 * h as u64;
    let staging = ctx.checked(|| {
        let slot = resources.prepare(device, queue, params, [0.0, 0.0]);
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("deepfield offscreen"),
            size: wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
        let staging = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("deepfield offscreen readback"),
            size: bytes,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder =
            device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("deepfield offscreen") });
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("deepfield offscreen"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                ..Default::default()
            });
            resources.draw(&mut pass, slot, params.precision);
        }
        encoder.copy_texture_to_buffer(
            texture.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: &staging,
                layout: wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(padded), rows_per_image: Some(h) },
            },
            wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
        );
        queue.submit(Some(encoder.finish()));
        staging
    })?;
    let mut words = Vec::new();
    crate::gpu::read_back(ctx, &staging, bytes, &mut words)?;
    let row_words = (padded / 4) as usize;
    Ok(words.chunks(row_words).flat_map(|row| row[..w as usize].iter().map(|v| v.to_le_bytes())).collect())
}
