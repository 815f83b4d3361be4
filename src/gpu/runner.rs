//! Chunked compute dispatches with readback: the plumbing shared by the escape-time and
//! IFS kernels.
//!
//! One invocation computes one sample and writes `words` 32-bit words (plane-major within
//! the chunk: word w of sample k at `w * count + k`). The grid rows requested are cut into
//! chunks of whole rows that respect the device's storage-binding and buffer limits and a
//! fixed cap of [`CHUNK_SAMPLES`] (so no single dispatch runs long enough to trip a
//! desktop driver's watchdog at moderate iteration counts, and the readback buffers stay
//! small). Each chunk is dispatched (two-dimensionally when it needs more than the
//! per-dimension workgroup limit), copied to a mappable buffer, and read back before the
//! next one starts.

use std::ops::Range;

use wgpu::util::DeviceExt;

use super::uniforms::Uniforms;
use super::{GpuContext, GpuError};

/// Most samples per dispatch.
pub const CHUNK_SAMPLES: u64 = 1 << 20;
/// Invocations per workgroup (the shaders' `@workgroup_size`).
const WORKGROUP: u32 = 64;

/// One compute job over whole rows of a sample grid.
pub struct Job<'a> {
    /// The pipeline (its layout is the context's compute layout).
    pub pipeline: &'a wgpu::ComputePipeline,
    /// The uniform block; `row_offset` and `count` are set per chunk.
    pub uniforms: Uniforms,
    /// Read-only texels (binding 1); at least one.
    pub texels: &'a [[f32; 4]],
    /// Samples per row.
    pub width: u32,
    /// Grid rows to compute.
    pub rows: Range<u32>,
    /// Output words per sample.
    pub words: u32,
}

/// Runs `job`, handing each chunk's words to `sink(first row index into job.rows, rows,
/// words)`, in order.
pub fn run(ctx: &GpuContext, job: &Job<'_>, mut sink: impl FnMut(u32, u32, &[u32])) -> Result<(), GpuError> {
    if job.rows.is_empty() || job.width == 0 {
        return Ok(());
    }
    let device = ctx.device();
    let limits = device.limits();
    let bytes_per_sample = job.words as u64 * 4;
    let bytes_per_row = bytes_per_sample * job.width as u64;
    let max_bytes = limits.max_storage_buffer_binding_size.min(limits.max_buffer_size);
    if bytes_per_row > max_bytes {
        return Err(GpuError::Unsupported(format!(
            "a row of {} samples needs {bytes_per_row} bytes of output, more than this device's buffer limit of {max_bytes}",
            job.width
        )));
    }
    let max_rows = (max_bytes / bytes_per_row).min((CHUNK_SAMPLES / job.width as u64).max(1)).max(1) as u32;
    let chunk_rows = max_rows.min(job.rows.len() as u32);
    let chunk_bytes = chunk_rows as u64 * bytes_per_row;
    let max_groups = limits.max_compute_workgroups_per_dimension.max(1);

    let (uniform_buf, texel_buf, out_buf, staging, bind_group) = ctx.checked(|| {
        let uniform_buf = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("deepfield uniforms"),
            size: std::mem::size_of::<Uniforms>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let texel_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("deepfield texels"),
            contents: bytemuck::cast_slice(job.texels),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let out_buf = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("deepfield planes"),
            size: chunk_bytes,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let staging = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("deepfield readback"),
            size: chunk_bytes,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("deepfield compute"),
            layout: ctx.compute_layout(),
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: uniform_buf.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: texel_buf.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 2, resource: out_buf.as_entire_binding() },
            ],
        });
        (uniform_buf, texel_buf, out_buf, staging, bind_group)
    })?;

    let mut words = Vec::new();
    let mut row = job.rows.start;
    while row < job.rows.end {
        let rows = chunk_rows.min(job.rows.end - row);
        let count = rows * job.width;
        let bytes = count as u64 * bytes_per_sample;
        let mut uniforms = job.uniforms;
        uniforms.row_offset = row;
        uniforms.count = count;
        let groups = count.div_ceil(WORKGROUP);
        let gx = groups.min(max_groups);
        let gy = groups.div_ceil(gx);
        ctx.checked(|| {
            ctx.queue().write_buffer(&uniform_buf, 0, uniforms.bytes());
            let mut encoder =
                device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("deepfield compute") });
            {
                let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("deepfield compute"),
                    timestamp_writes: None,
                });
                pass.set_pipeline(job.pipeline);
                pass.set_bind_group(0, &bind_group, &[]);
                pass.dispatch_workgroups(gx, gy, 1);
            }
            encoder.copy_buffer_to_buffer(&out_buf, 0, &staging, 0, bytes);
            ctx.queue().submit(Some(encoder.finish()));
        })?;
        read_back(ctx, &staging, bytes, &mut words)?;
        sink(row - job.rows.start, rows, &words);
        row += rows;
    }
    drop(texel_buf);
    Ok(())
}

/// Maps the first `bytes` of `staging`, copies them out as words, unmaps.
pub(crate) fn read_back(
    ctx: &GpuContext,
    staging: &wgpu::Buffer,
    bytes: u64,
    words: &mut Vec<u32>,
) -> Result<(), GpuError> {
    let slice = staging.slice(0..bytes);
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    ctx.device().poll(wgpu::PollType::wait_indefinitely()).map_err(|e| GpuError::Map(e.to_string()))?;
    match rx.recv() {
        Ok(Ok(())) => {}
        Ok(Err(e)) => return Err(GpuError::Map(e.to_string())),
        Err(_) => return Err(GpuError::Map("the mapping callback never ran".into())),
    }
    {
        let view = slice.get_mapped_range().map_err(|e| GpuError::Map(e.to_string()))?;
        words.clear();
        words.extend(view.chunks_exact(4).map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]])));
    }
    staging.unmap();
    Ok(())
}
