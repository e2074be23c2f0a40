//! Copying textures and buffers back to the CPU.

use std::sync::mpsc;

use lumagraph_graph::{Extent, TexFormat};

use crate::context::GpuContext;
use crate::cpu::Image;
use crate::error::{RenderError, Result};

/// Maps the first `size` bytes of a `MAP_READ` buffer, waits, and passes them to `f`.
///
/// # Errors
/// When mapping fails or the GPU does not finish.
pub fn map_read<T>(
    ctx: &GpuContext,
    buffer: &wgpu::Buffer,
    size: u64,
    f: impl FnOnce(&[u8]) -> T,
) -> Result<T> {
    map_read_when(buffer, size, f, || ctx.wait())
}

/// [`map_read`] once submission `index` is done, not waiting for the work submitted after
/// it (so the host can read one step's results while the GPU runs the next).
///
/// # Errors
/// When mapping fails or the GPU does not finish.
pub fn map_read_after<T>(
    ctx: &GpuContext,
    buffer: &wgpu::Buffer,
    index: wgpu::SubmissionIndex,
    size: u64,
    f: impl FnOnce(&[u8]) -> T,
) -> Result<T> {
    map_read_when(buffer, size, f, || wait_for(ctx, index))
}

/// Waits until submission `index` is done.
///
/// # Errors
/// When the device is lost or the wait times out.
pub fn wait_for(ctx: &GpuContext, index: wgpu::SubmissionIndex) -> Result<()> {
    ctx.device
        .poll(wgpu::PollType::Wait {
            submission_index: Some(index),
            timeout: Some(crate::context::GPU_TIMEOUT),
        })
        .map(|_| ())
        .map_err(|e| ctx.error(e))
}

/// Maps `slice` in `mode`, `wait`s for the GPU, and checks that the mapping succeeded.
fn map_slice(
    slice: &wgpu::BufferSlice<'_>,
    mode: wgpu::MapMode,
    wait: impl FnOnce() -> Result<()>,
) -> Result<()> {
    let (tx, rx) = mpsc::channel();
    slice.map_async(mode, move |r| {
        let _ = tx.send(r);
    });
    wait()?;
    rx.recv()
        .map_err(|_| RenderError::Gpu("buffer map callback was dropped".into()))??;
    Ok(())
}

/// Maps a whole `MAP_WRITE` buffer once submission `index` (its last use) is done, passes
/// the mapping to `f` to write, and unmaps it (a persistent upload buffer: `Queue::write_buffer`
/// takes a fresh staging buffer per call, whose new pages the OS faults in one by one).
/// `index` `None`: the buffer is mapped already (`mapped_at_creation`).
///
/// # Errors
/// When mapping fails or the GPU does not finish.
pub fn map_write_after(
    ctx: &GpuContext,
    buffer: &wgpu::Buffer,
    index: Option<wgpu::SubmissionIndex>,
    f: impl FnOnce(&mut wgpu::BufferViewMut),
) -> Result<()> {
    let slice = buffer.slice(..);
    if let Some(index) = index {
        map_slice(&slice, wgpu::MapMode::Write, || wait_for(ctx, index))?;
    }
    {
        let mut view = slice
            .get_mapped_range_mut()
            .map_err(|e| RenderError::Gpu(e.to_string()))?;
        f(&mut view);
    }
    buffer.unmap();
    Ok(())
}

/// Maps the first `size` bytes of `buffer` for reading, `wait`s for the GPU, and passes the
/// bytes to `f`.
fn map_read_when<T>(
    buffer: &wgpu::Buffer,
    size: u64,
    f: impl FnOnce(&[u8]) -> T,
    wait: impl FnOnce() -> Result<()>,
) -> Result<T> {
    if size == 0 {
        return Ok(f(&[]));
    }
    let slice = buffer.slice(..size);
    map_slice(&slice, wgpu::MapMode::Read, wait)?;
    let out = {
        let view = slice
            .get_mapped_range()
            .map_err(|e| RenderError::Gpu(e.to_string()))?;
        f(&view)
    };
    buffer.unmap();
    Ok(out)
}

/// Copies a `COPY_SRC` buffer back after the work submitted so far and appends its bytes
/// to `out` (through a staging buffer that lives as long as the call).
///
/// # Errors
/// When mapping fails or the GPU does not finish.
pub fn append_buffer(ctx: &GpuContext, buffer: &wgpu::Buffer, out: &mut Vec<u8>) -> Result<()> {
    let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("state readback"),
        size: buffer.size(),
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("state readback"),
        });
    encoder.copy_buffer_to_buffer(buffer, 0, &staging, 0, buffer.size());
    ctx.queue.submit([encoder.finish()]);
    map_read(ctx, &staging, buffer.size(), |bytes| {
        out.extend_from_slice(bytes);
    })
}

/// Runs a compute job that writes `count` values of `T` into a storage buffer and reads them
/// back: `record` gets a fresh encoder and the output buffer (`STORAGE | COPY_SRC`) and
/// records the dispatch; the copy, the submission and the wait follow.
///
/// # Errors
/// What `record` returns, or when mapping fails or the GPU does not finish.
pub fn compute_and_read<T: bytemuck::Pod>(
    ctx: &GpuContext,
    label: &str,
    count: usize,
    record: impl FnOnce(&mut wgpu::CommandEncoder, &wgpu::Buffer) -> Result<()>,
) -> Result<Vec<T>> {
    let size = (count * std::mem::size_of::<T>()) as u64;
    let output = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let readback = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("compute readback"),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(label) });
    record(&mut encoder, &output)?;
    encoder.copy_buffer_to_buffer(&output, 0, &readback, 0, size);
    ctx.queue.submit([encoder.finish()]);
    map_read(ctx, &readback, size, |bytes| {
        bytemuck::pod_collect_to_vec::<u8, T>(bytes)
    })
}

/// Workgroup counts for `count` invocations of a 1D kernel of `size` lanes, folded into a
/// second dimension past the 65 535-group limit.
pub fn groups_1d(count: u32, size: u32) -> [u32; 3] {
    let groups = count.div_ceil(size);
    [groups.min(65535), groups.div_ceil(65535), 1]
}

/// Reads a whole texture back as tightly packed rows of texels.
///
/// # Errors
/// When the GPU does not finish.
pub fn read_texture(
    ctx: &GpuContext,
    texture: &wgpu::Texture,
    format: TexFormat,
    extent: Extent,
) -> Result<Vec<u8>> {
    let bpp = u32::try_from(format.bytes_per_pixel()).unwrap_or(16);
    let row = extent.width * bpp;
    let padded = row.next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
    let size = u64::from(padded) * u64::from(extent.height);
    let buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("readback"),
        });
    encoder.copy_texture_to_buffer(
        texture.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded),
                rows_per_image: Some(extent.height),
            },
        },
        wgpu::Extent3d {
            width: extent.width,
            height: extent.height,
            depth_or_array_layers: 1,
        },
    );
    ctx.queue.submit([encoder.finish()]);
    map_read(ctx, &buffer, size, |bytes| {
        let mut out = Vec::with_capacity(row as usize * extent.height as usize);
        for r in bytes.chunks_exact(padded as usize) {
            out.extend_from_slice(&r[..row as usize]);
        }
        out
    })
}

/// Turns packed texels into an RGBA float image (8-bit values become \[0, 1\];
/// one-channel images are repeated into RGB with alpha 1).
pub fn to_image(bytes: &[u8], format: TexFormat, extent: Extent) -> Image {
    let pixels = match format {
        // One copy, straight into pixels (an image of 16384² is 4 GiB).
        TexFormat::Rgba32Float => bytemuck::pod_collect_to_vec::<u8, [f32; 4]>(bytes),
        TexFormat::Rgba8Unorm => bytes
            .chunks_exact(4)
            .map(|c| c.iter().map(|&b| f32::from(b) / 255.0).collect::<Vec<_>>())
            .map(|c| [c[0], c[1], c[2], c[3]])
            .collect(),
        TexFormat::R32Float => bytemuck::pod_collect_to_vec::<u8, f32>(bytes)
            .into_iter()
            .map(|v| [v, v, v, 1.0])
            .collect(),
    };
    Image {
        width: extent.width,
        height: extent.height,
        pixels,
    }
}

/// A storage buffer a node's passes write and the node reads back now and then (a
/// measurement): the buffer (`STORAGE | COPY_SRC | COPY_DST`) and its `MAP_READ` copy.
#[derive(Debug)]
pub struct ReadableBuffer {
    /// The buffer the passes bind.
    pub buffer: wgpu::Buffer,
    staging: wgpu::Buffer,
}

impl ReadableBuffer {
    /// A zeroed buffer of `size` bytes and its readback copy.
    pub fn new(ctx: &GpuContext, label: &str, size: u64) -> Self {
        use wgpu::BufferUsages as U;
        let make = |label: &str, usage| {
            ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage,
                mapped_at_creation: false,
            })
        };
        Self {
            buffer: make(label, U::STORAGE | U::COPY_SRC | U::COPY_DST),
            staging: make(&format!("{label} readback"), U::MAP_READ | U::COPY_DST),
        }
    }

    /// Copies the buffer back after the work submitted so far and passes its bytes to `f`.
    ///
    /// # Errors
    /// When mapping fails or the GPU does not finish.
    pub fn read<T>(&self, ctx: &GpuContext, f: impl FnOnce(&[u8]) -> T) -> Result<T> {
        let size = self.buffer.size();
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("readback"),
            });
        encoder.copy_buffer_to_buffer(&self.buffer, 0, &self.staging, 0, size);
        ctx.queue.submit([encoder.finish()]);
        map_read(ctx, &self.staging, size, f)
    }
}
