//! Adaptive sampling's pass and per-pixel state, owned by the path tracer's node.

use lumagraph_graph::Pass;
use wgpu::util::DeviceExt as _;

use super::{AdaptiveParams, storage};
use lumagraph_render::context::GpuContext;
use lumagraph_render::error::Result;
use lumagraph_render::kernel::{Kernel, uniform_buffer};

/// Adaptive sampling's pass and per-pixel state (16-byte stand-ins while it is off).
pub(super) struct Adaptive {
    pub(super) kernel: Kernel,
    pub(super) params: wgpu::Buffer,
    /// Per pixel of the window: the sums (rgb) and frame counts of the even and odd frames.
    pub(super) halves: wgpu::Buffer,
    /// Per pixel: 1 once it stopped.
    pub(super) stopped: wgpu::Buffer,
    /// This frame's pixels still sampling: their count, then each one's position.
    pub(super) active: wgpu::Buffer,
    /// The window size the buffers are for (0×0: stand-ins).
    pub(super) extent: lumagraph_graph::Extent,
    /// Clear the buffers before the next frame.
    pub(super) clear: bool,
    /// `adaptive_error` (0: off) and the frames every pixel takes first.
    pub(super) error: f32,
    pub(super) min_spp: u32,
}

impl Adaptive {
    pub(super) fn new(ctx: &GpuContext) -> Result<Self> {
        Ok(Self {
            kernel: Kernel::new(ctx, "pathtrace/integrator/adaptive.wgsl")?,
            params: uniform_buffer(
                ctx,
                "adaptive params",
                bytemuck::bytes_of(&AdaptiveParams::default()),
            ),
            halves: storage(ctx, "adaptive halves", 16),
            stopped: storage(ctx, "adaptive stopped", 16),
            active: storage(ctx, "adaptive active", 16),
            extent: lumagraph_graph::Extent::new(0, 0),
            clear: true,
            error: 0.0,
            min_spp: 16,
        })
    }

    pub(super) fn on(&self) -> bool {
        self.error > 0.0
    }

    /// Records the pass that stops pixels before a frame and writes `samples`; `frames` is
    /// the frames run before this one and the samples each takes.
    pub(super) fn record(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        pass: &Pass,
        [frames, samples_per_frame]: [u32; 2],
        samples: &wgpu::TextureView,
        timer: Option<&mut lumagraph_render::timing::GpuTimer>,
    ) -> Result<()> {
        self.fit(ctx, pass.extent);
        if self.clear && self.on() {
            encoder.clear_buffer(&self.halves, 0, None);
            encoder.clear_buffer(&self.stopped, 0, None);
            self.clear = false;
        }
        if self.on() {
            encoder.clear_buffer(&self.active, 0, Some(4));
        }
        let block = AdaptiveParams {
            size: [pass.extent.width, pass.extent.height],
            min_frames: self.min_spp.div_ceil(samples_per_frame).max(2),
            error2: if self.on() {
                self.error * self.error
            } else {
                -1.0
            },
            frames,
            samples_per_frame,
            ..AdaptiveParams::default()
        };
        let staging = ctx
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("adaptive params staging"),
                contents: bytemuck::bytes_of(&block),
                usage: wgpu::BufferUsages::COPY_SRC,
            });
        encoder.copy_buffer_to_buffer(&staging, 0, &self.params, 0, self.params.size());
        self.kernel
            .pass(&format!("{} (adaptive)", pass.node))
            .uniform(&self.params)
            .buffer(&self.halves)
            .buffer(&self.stopped)
            .write(samples)
            .buffer(&self.active)
            .dispatch_2d(ctx, encoder, pass.extent, timer)
    }

    /// Buffers for a window of `extent` (new ones, to be cleared, when it changed).
    pub(super) fn fit(&mut self, ctx: &GpuContext, extent: lumagraph_graph::Extent) {
        if self.on() && self.extent != extent {
            self.halves = storage(ctx, "adaptive halves", 32 * extent.pixels());
            self.stopped = storage(ctx, "adaptive stopped", 4 * extent.pixels());
            self.active = storage(ctx, "adaptive active", 4 + 4 * extent.pixels());
            self.extent = extent;
            self.clear = true;
        }
    }
}
