//! Accumulate: progressive running mean with Kahan-compensated sums.
//!
//! The sums are history that outlives a frame, so they live in buffers the node owns, not
//! in the per-frame texture pool. [`NodeExec::reset`] clears them (scene or camera changed).
//!
//! When the `variance` output is read, a third buffer keeps what the variance of the mean
//! is estimated from (the Kahan sums, and so the mean, are computed exactly as without it):
//! the sum and count of the second half of the frames (`variance_estimate: halves`, every
//! other frame), or Welford's second moment over frames (`frames`). Otherwise that buffer
//! and output are 16-byte and 1×1 stand-ins and the shader skips the work.

use lumagraph_graph::{Extent, Pass, TexFormat};

use crate::context::GpuContext;
use crate::error::Result;
use crate::kernel::{Kernel, uniform_buffer};
use crate::nodes::{NodeExec, NodeImpl, Recording, boxed};
use crate::pool::{PooledTexture, create};

/// The `Accumulate` kind: it owns its history buffers.
pub(crate) const IMPL: NodeImpl = NodeImpl::new("Accumulate", |ctx, pass, _| {
    boxed(Accumulate::new(ctx, pass))
})
.owning(|pass| {
    let buffers = if pass.output("variance").is_some() {
        3
    } else {
        2
    };
    Some((
        buffers * 16 * pass.extent.pixels(),
        format!(
            "{buffers} history buffers of 16 B per pixel (sum, compensation{})",
            if buffers == 3 {
                ", half sum or second moment"
            } else {
                ""
            }
        ),
    ))
});

crate::param_block! {
    /// Accumulate's params: a 1.0 the compiler cannot fold away (it keeps the Kahan
    /// compensation), how to estimate the variance (0: not at all, 1: from the frames'
    /// spread, 2: from two halves), the image size, whether to present the history
    /// without adding to it, and the parity of the render's frame before the first one
    /// added (odd in a partial render that starts at an odd frame).
    pub(crate) struct AccumulateParams in "post/accumulate.wgsl" as "Params" {
        one: f32,
        variance: u32,
        size: [u32; 2],
        present: u32,
        parity: u32,
    }
}

/// `params.variance` when the variance is estimated from two halves of the frames.
const VARIANCE_HALVES: u32 = 2;

/// The shader's `params.variance` for `pass`: 0 when nothing reads the variance.
fn variance_mode(pass: &Pass) -> u32 {
    if pass.output("variance").is_none() {
        0
    } else if pass.params.str("variance_estimate") == "frames" {
        1
    } else {
        VARIANCE_HALVES
    }
}

pub(crate) struct Accumulate {
    kernel: Kernel,
    params: wgpu::Buffer,
    /// Size, sum, compensation and the variance's buffer (a stand-in without `variance`).
    history: Option<(Extent, wgpu::Buffer, wgpu::Buffer, wgpu::Buffer)>,
    clear: bool,
    /// The shader's `params.variance`: 0 (no `variance` output), 1 (frames) or 2 (halves).
    variance: u32,
    /// Write the mean of the history without adding a frame ([`NodeExec::set_present`]).
    present: bool,
    /// 1 when the first frame added is an odd frame of the render (the path tracer's second
    /// Sobol replicate): it then belongs to the second half.
    parity: u32,
    /// Stand-ins for an output nothing reads (color, variance).
    unused: [PooledTexture; 2],
}

/// The shader for variance mode `variance`: the code of the other modes is left out
/// (`post/accumulate_options.wgsl`).
fn kernel(ctx: &GpuContext, variance: u32) -> Result<Kernel> {
    let name = "post/accumulate.wgsl";
    let options = format!("const VARIANCE: u32 = {variance}u;\n");
    let source = crate::shader::resolve_with(name, &[("post/accumulate_options.wgsl", options)])?;
    Kernel::from_source(ctx, name, &source)
}

impl Accumulate {
    pub(crate) fn new(ctx: &GpuContext, pass: &Pass) -> Result<Self> {
        let variance = variance_mode(pass);
        let kernel = kernel(ctx, variance)?;
        let block = AccumulateParams {
            one: 1.0,
            variance,
            ..AccumulateParams::default()
        };
        let params = uniform_buffer(ctx, "accumulate params", bytemuck::bytes_of(&block));
        let one = Extent::new(1, 1);
        Ok(Self {
            kernel,
            params,
            history: None,
            clear: true,
            variance,
            present: false,
            parity: 0,
            unused: [
                create(ctx, "unused accumulate color", TexFormat::Rgba32Float, one),
                create(
                    ctx,
                    "unused accumulate variance",
                    TexFormat::Rgba32Float,
                    one,
                ),
            ],
        })
    }
}

impl Accumulate {
    /// New (uncleared) history buffers for `extent`.
    fn make_history(&mut self, ctx: &GpuContext, extent: Extent) {
        let make = |label, size| {
            ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_DST
                    | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            })
        };
        let bytes = extent.pixels() * 16;
        self.history = Some((
            extent,
            make("accumulate sum", bytes),
            make("accumulate compensation", bytes),
            make(
                "accumulate second moment",
                if self.variance > 0 { bytes } else { 16 },
            ),
        ));
    }

    /// Writes the params block for `extent` (done with every clear).
    fn write_params(&self, ctx: &GpuContext, extent: Extent) {
        // The image size rides with the params (outputs may be 1×1 stand-ins).
        let block = AccumulateParams {
            one: 1.0,
            variance: self.variance,
            size: [extent.width, extent.height],
            present: u32::from(self.present),
            parity: self.parity,
        };
        ctx.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&block));
    }
}

impl NodeExec for Accumulate {
    fn save_state(&mut self, ctx: &GpuContext) -> Result<Option<Vec<u8>>> {
        // Header: width, height, and the size of each buffer; then the buffers. No history
        // yet (or one to be cleared) is an empty state.
        let Some((extent, sum, comp, m2)) = self.history.as_ref().filter(|_| !self.clear) else {
            return Ok(Some(Vec::new()));
        };
        let mut out = Vec::new();
        out.extend_from_slice(&extent.width.to_le_bytes());
        out.extend_from_slice(&extent.height.to_le_bytes());
        for b in [sum, comp, m2] {
            out.extend_from_slice(&b.size().to_le_bytes());
        }
        for b in [sum, comp, m2] {
            crate::readback::append_buffer(ctx, b, &mut out)?;
        }
        Ok(Some(out))
    }

    fn load_state(&mut self, ctx: &GpuContext, pass: &Pass, state: &[u8]) -> Result<()> {
        if state.is_empty() {
            self.clear = true;
            return Ok(());
        }
        let bad =
            |why: String| crate::error::RenderError::Gpu(format!("accumulation state: {why}"));
        let u32_at = |i: usize| {
            state
                .get(i..i + 4)
                .and_then(|b| b.try_into().ok())
                .map(u32::from_le_bytes)
        };
        let u64_at = |i: usize| {
            state
                .get(i..i + 8)
                .and_then(|b| b.try_into().ok())
                .map(u64::from_le_bytes)
        };
        let (Some(w), Some(h)) = (u32_at(0), u32_at(4)) else {
            return Err(bad("truncated".into()));
        };
        if Extent::new(w, h) != pass.extent {
            return Err(bad(format!("{w}×{h}, but the image is {}", pass.extent)));
        }
        self.make_history(ctx, pass.extent);
        let Some((_, sum, comp, m2)) = &self.history else {
            return Err(bad("no buffers".into()));
        };
        let mut at = 8 + 3 * 8;
        for (i, b) in [sum, comp, m2].into_iter().enumerate() {
            let size = u64_at(8 + 8 * i).ok_or_else(|| bad("truncated".into()))?;
            if size != b.size() {
                return Err(bad(format!(
                    "a buffer of {size} bytes where {} are expected (variance on or off?)",
                    b.size()
                )));
            }
            let len = usize::try_from(size).map_err(|_| bad("too large".into()))?;
            let bytes = state
                .get(at..at + len)
                .ok_or_else(|| bad("truncated".into()))?;
            ctx.queue.write_buffer(b, 0, bytes);
            at += len;
        }
        if at != state.len() {
            return Err(bad(format!("{} bytes too many", state.len() - at)));
        }
        self.write_params(ctx, pass.extent);
        self.clear = false;
        Ok(())
    }

    fn update(&mut self, ctx: &GpuContext, pass: &Pass) -> Result<()> {
        // Another estimate keeps other numbers in the third buffer (and has its own
        // shader): start again.
        let variance = variance_mode(pass);
        if variance != self.variance {
            self.kernel = kernel(ctx, variance)?;
            self.variance = variance;
            self.history = None;
            self.clear = true;
        }
        Ok(())
    }

    fn reset(&mut self) {
        self.clear = true;
    }

    fn start_at_sample(&mut self, _first: u32, frames: u64) {
        self.parity = u32::from(frames % 2 == 1);
    }

    fn set_present(&mut self, ctx: &GpuContext, present: bool) {
        self.present = present;
        if let Some((extent, ..)) = &self.history {
            self.write_params(ctx, *extent);
        }
    }

    fn merge_states(&mut self, states: &[&[u8]]) -> Result<Vec<u8>> {
        crate::partial::merge_accumulations(states, self.variance == VARIANCE_HALVES)
            .map_err(|e| crate::error::RenderError::Gpu(format!("accumulation state: {e}")))
    }

    fn record(&mut self, pass: &Pass, rec: Recording<'_>) -> Result<()> {
        let (ctx, encoder, io, timer) = rec.parts();
        let input = io.input(pass, "color")?;
        let (out, var) = (pass.output("color"), pass.output("variance"));
        if out.is_none() && var.is_none() {
            return Ok(());
        }
        let extent = pass.extent;
        if self.present && (self.clear || self.history.as_ref().is_none_or(|(e, ..)| *e != extent))
        {
            return Err(crate::error::RenderError::Gpu(
                "no accumulated samples to present".into(),
            ));
        }
        let mut clear = std::mem::take(&mut self.clear);
        if self.history.as_ref().is_none_or(|(e, ..)| *e != extent) {
            self.make_history(ctx, extent);
            clear = true;
        }
        let Some((_, sum, comp, m2)) = &self.history else {
            return Ok(());
        };
        if clear {
            encoder.clear_buffer(sum, 0, None);
            encoder.clear_buffer(comp, 0, None);
            encoder.clear_buffer(m2, 0, None);
        }
        if clear {
            self.write_params(ctx, extent);
        }
        let view = |t: Option<lumagraph_graph::TextureId>, i: usize| {
            t.map_or(&self.unused[i].view, |t| &io.texture(t).view)
        };
        let color_view = view(out, 0);
        self.kernel
            .pass(&pass.node)
            .read(&input.view)
            .write(color_view)
            .buffer(sum)
            .buffer(comp)
            .uniform(&self.params)
            .buffer(m2)
            .write(view(var, 1))
            .dispatch_2d(ctx, encoder, pass.extent, timer)
    }
}
