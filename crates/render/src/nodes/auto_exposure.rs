//! `AutoExposure`: three passes. `shaders/post/histogram.wgsl` counts the input's luminance
//! into 256 bins (workgroup atomics, then one global add per bin and tile);
//! `shaders/post/auto_exposure.wgsl` (one invocation) turns the histogram into the target
//! exposure and adapts the node's state towards it; `shaders/post/auto_exposure_apply.wgsl`
//! scales the image. The exposure stays on the GPU: nothing is read back unless it is
//! measured. The CPU reference is `render::cpu::auto_exposure_target`.

use lumagraph_graph::Pass;

use crate::context::GpuContext;
use crate::error::Result;
use crate::kernel::{Kernel, uniform_buffer};
use crate::nodes::{Measurement, NodeExec, NodeImpl, Recording, boxed};
use crate::readback::ReadableBuffer;

/// The `AutoExposure` kind.
pub(crate) const IMPL: NodeImpl = NodeImpl::new("AutoExposure", |ctx, pass, _| {
    boxed(AutoExposure::new(ctx, pass))
})
.owning(|_| {
    Some((
        BINS * 4 + STATE,
        "the histogram (256 u32) and the exposure state".to_owned(),
    ))
});

crate::param_block! {
    /// The adaptation pass's params.
    pub(crate) struct AutoExposureParams in "post/auto_exposure.wgsl" as "Params" {
        key: f32,
        low: f32,
        high: f32,
        min_ev: f32,
        max_ev: f32,
        adaptation: f32,
        pad0: f32,
        pad1: f32,
    }
}

const BINS: u64 = crate::cpu::HISTOGRAM_BINS as u64;
/// `struct State { ev: f32, valid: u32 }`.
const STATE: u64 = 8;

struct AutoExposure {
    histogram: Kernel,
    adapt: Kernel,
    apply: Kernel,
    params: wgpu::Buffer,
    bins: wgpu::Buffer,
    state: ReadableBuffer,
    /// The state must be cleared before the next frame (a new node, or history reset).
    fresh: bool,
    ran: bool,
}

impl AutoExposure {
    fn new(ctx: &GpuContext, pass: &Pass) -> Result<Self> {
        let mut node = Self {
            histogram: Kernel::new(ctx, "post/histogram.wgsl")?,
            adapt: Kernel::new(ctx, "post/auto_exposure.wgsl")?,
            apply: Kernel::new(ctx, "post/auto_exposure_apply.wgsl")?,
            params: uniform_buffer(
                ctx,
                "auto exposure params",
                bytemuck::bytes_of(&AutoExposureParams::default()),
            ),
            bins: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("luminance histogram"),
                size: BINS * 4,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            state: ReadableBuffer::new(ctx, "auto exposure state", STATE),
            fresh: true,
            ran: false,
        };
        node.update(ctx, pass)?;
        Ok(node)
    }
}

impl NodeExec for AutoExposure {
    fn update(&mut self, ctx: &GpuContext, pass: &Pass) -> Result<()> {
        #[expect(clippy::cast_possible_truncation, reason = "GPU math is f32")]
        let f = |name: &str| pass.params.float(name) as f32;
        let [[low, high], [min_ev, max_ev]] =
            crate::cpu::auto_exposure_ranges(f("low"), f("high"), f("min_ev"), f("max_ev"));
        let block = AutoExposureParams {
            key: f("key"),
            low,
            high,
            min_ev,
            max_ev,
            adaptation: f("adaptation"),
            pad0: 0.0,
            pad1: 0.0,
        };
        ctx.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&block));
        Ok(())
    }

    fn reset(&mut self) {
        self.fresh = true;
    }

    fn record(&mut self, pass: &Pass, rec: Recording<'_>) -> Result<()> {
        let (ctx, encoder, io, mut timer) = rec.parts();
        let Some(out) = pass.output("color") else {
            return Ok(());
        };
        let input = io.input(pass, "color")?;
        if self.fresh {
            encoder.clear_buffer(&self.state.buffer, 0, None);
            self.fresh = false;
        }
        encoder.clear_buffer(&self.bins, 0, None);
        self.histogram
            .pass(&pass.node)
            .read(&input.view)
            .buffer(&self.bins)
            .dispatch_2d(ctx, encoder, pass.extent, timer.as_deref_mut())?;
        self.adapt
            .pass(&pass.node)
            .buffer(&self.bins)
            .buffer(&self.state.buffer)
            .uniform(&self.params)
            .dispatch(ctx, encoder, [1, 1, 1], timer.as_deref_mut())?;
        self.apply
            .pass(&pass.node)
            .read(&input.view)
            .write(&io.texture(out).view)
            .buffer(&self.state.buffer)
            .dispatch_2d(ctx, encoder, pass.extent, timer)?;
        self.ran = true;
        Ok(())
    }

    fn measurements(&mut self, ctx: &GpuContext) -> Result<Vec<Measurement>> {
        if !self.ran {
            return Ok(Vec::new());
        }
        let ev = self.state.read(ctx, |bytes| {
            f64::from(bytemuck::pod_read_unaligned::<f32>(&bytes[..4]))
        })?;
        Ok(vec![Measurement::new("exposure_ev", ev)])
    }
}
