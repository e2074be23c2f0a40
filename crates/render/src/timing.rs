//! Per-pass GPU time from timestamp queries.
//!
//! Each compute pass gets a begin and an end timestamp; after the frame the values are
//! read back and summed by pass name (a node that runs several passes, like the à-trous
//! filter, is reported once). Adapters without timestamp queries report nothing, and
//! callers say so rather than print zeros.

use crate::context::GpuContext;
use crate::error::{RenderError, Result};

/// Timestamp queries for up to `capacity` passes a frame.
#[derive(Debug)]
pub struct GpuTimer {
    query_set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    readback: wgpu::Buffer,
    capacity: u32,
    labels: Vec<String>,
    period_ns: f64,
}

impl GpuTimer {
    /// A timer for up to `capacity` passes, or `None` when the device cannot time passes.
    pub fn new(ctx: &GpuContext, capacity: u32) -> Option<Self> {
        if !ctx.timestamps {
            return None;
        }
        let count = capacity * 2;
        let size = u64::from(count) * 8;
        Some(Self {
            query_set: ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("pass timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count,
            }),
            resolve: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamp resolve"),
                size,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
            readback: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamp readback"),
                size,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            capacity,
            labels: Vec::new(),
            period_ns: f64::from(ctx.queue.get_timestamp_period()),
        })
    }

    /// Forgets the previous frame's passes.
    pub fn begin_frame(&mut self) {
        self.labels.clear();
    }

    /// Timestamp writes for the next pass, named `label`; `None` once full.
    pub fn writes(&mut self, label: &str) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        let i = u32::try_from(self.labels.len()).ok()?;
        if i >= self.capacity {
            return None;
        }
        self.labels.push(label.to_owned());
        Some(wgpu::ComputePassTimestampWrites {
            query_set: &self.query_set,
            beginning_of_pass_write_index: Some(2 * i),
            end_of_pass_write_index: Some(2 * i + 1),
        })
    }

    /// Timestamp writes for the next render pass, named `label`; `None` once full.
    pub fn render_writes(&mut self, label: &str) -> Option<wgpu::RenderPassTimestampWrites<'_>> {
        self.writes(label).map(|w| wgpu::RenderPassTimestampWrites {
            query_set: w.query_set,
            beginning_of_pass_write_index: w.beginning_of_pass_write_index,
            end_of_pass_write_index: w.end_of_pass_write_index,
        })
    }

    /// Records the copy of this frame's timestamps; call after the last pass.
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        let n = u32::try_from(self.labels.len()).unwrap_or(self.capacity) * 2;
        if n == 0 {
            return;
        }
        encoder.resolve_query_set(&self.query_set, 0..n, &self.resolve, 0);
        encoder.copy_buffer_to_buffer(&self.resolve, 0, &self.readback, 0, u64::from(n) * 8);
    }

    /// GPU milliseconds per pass name, in first-use order; call after the frame finished.
    ///
    /// # Errors
    /// When the readback fails.
    pub fn read(&self, ctx: &GpuContext) -> Result<Vec<(String, f64)>> {
        let n = self.labels.len() as u64 * 2;
        if n == 0 {
            return Ok(Vec::new());
        }
        let ticks: Vec<u64> = crate::readback::map_read(ctx, &self.readback, n * 8, |bytes| {
            bytes
                .chunks_exact(8)
                .map(|c| u64::from_le_bytes(c.try_into().unwrap_or([0; 8])))
                .collect()
        })?;
        let mut out: Vec<(String, f64)> = Vec::new();
        for (label, pair) in self.labels.iter().zip(ticks.chunks_exact(2)) {
            #[expect(clippy::cast_precision_loss, reason = "tick deltas are small")]
            let ms = pair[1].saturating_sub(pair[0]) as f64 * self.period_ns / 1e6;
            match out.iter_mut().find(|(l, _)| l == label) {
                Some((_, total)) => *total += ms,
                None => out.push((label.clone(), ms)),
            }
        }
        Ok(out)
    }
}

impl From<wgpu::BufferAsyncError> for RenderError {
    fn from(e: wgpu::BufferAsyncError) -> Self {
        Self::Gpu(format!("buffer map failed: {e}"))
    }
}
