//! Frames traced in steps (host intersection, the wavefront): the steps dispatched and
//! submitted in order, the rays of each traced by the host or a kernel, the sums finished
//! by one pass.

use lumagraph_graph::Pass;

use super::{Frame, PathTrace, stage_frame, storage};
use crate::host_rays::WaveStep;
use lumagraph_render::context::GpuContext;
use lumagraph_render::error::Result;
use lumagraph_render::nodes::FrameIo;
use lumagraph_render::shared::WAVE_STEP;

impl PathTrace {
    /// Traces a frame with host intersection: the steps of its paths are dispatched and
    /// submitted in order, the host intersecting the rays of each step, leaving the
    /// pixels' sums in `chunk_sums` for the pass [`Self::record_steps_finish`] records.
    pub(super) fn trace_host(
        &mut self,
        ctx: &GpuContext,
        io: &FrameIo<'_>,
        pass: &Pass,
        frame: Frame,
    ) -> Result<()> {
        // Taken out of the node while the steps borrow it.
        let mut backend = std::mem::replace(&mut self.backend, crate::intersect::nothing());
        let Some(host) = backend.host_mut() else {
            self.backend = backend;
            return Ok(());
        };
        host.fit(ctx, pass.extent);
        let sums = self.steps_sums(ctx, pass);
        let views = self.views(pass, io);
        let max_steps = self.max_steps(&frame);
        let result = host.trace_frame(ctx, max_steps, |step, enc, wave| {
            let f = Frame {
                wave: WAVE_STEP,
                wave_base: step.base,
                wave_capacity: step.capacity,
                wave_split: step.misses,
                ..frame
            };
            ctx.queue
                .write_buffer(&self.frame, 0, bytemuck::bytes_of(&f));
            let passes = if step.first {
                [("wave_start", step.misses), ("wave_hits", 0)]
            } else {
                [("wave_misses", step.misses), ("wave_hits", step.hits)]
            };
            for (entry, slots) in passes {
                if slots > 0 {
                    self.bind(&pass.node, views, &sums, wave)
                        .entry(entry)
                        .dispatch(ctx, enc, [WaveStep::groups(slots), 1, 1], None)?;
                }
            }
            Ok(())
        });
        self.backend = backend;
        result
    }

    /// Records the pass that writes the means (and AOVs) of a frame traced in steps, with
    /// the graph.
    pub(super) fn record_steps_finish(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        io: &FrameIo<'_>,
        pass: &Pass,
        frame: Frame,
        timer: Option<&mut lumagraph_render::timing::GpuTimer>,
    ) -> Result<()> {
        let sums = self.steps_sums(ctx, pass);
        let views = self.views(pass, io);
        let wave = match (self.backend.host(), &self.wavefront) {
            (Some(host), _) => host.wave().clone(),
            (None, Some(front)) => front.wave().clone(),
            (None, None) => return Ok(()),
        };
        self.record_finish(ctx, encoder, pass, frame, (views, &sums, &wave), timer)
    }
}

impl PathTrace {
    /// The per-pixel sums of a frame traced in steps: `chunk_sums`, grown to the window
    /// once, not a buffer per frame.
    pub(super) fn steps_sums(&mut self, ctx: &GpuContext, pass: &Pass) -> wgpu::Buffer {
        let size = 16 * pass.extent.pixels();
        if self.chunk_sums.size() < size {
            self.chunk_sums = storage(ctx, "pathtrace chunk sums", size);
        }
        self.chunk_sums.clone()
    }

    /// Traces a frame by the wavefront: its steps are recorded and submitted in order, all
    /// on the device, leaving the pixels' sums in `chunk_sums` for the pass
    /// [`Self::record_steps_finish`] records.
    pub(super) fn trace_wavefront(
        &mut self,
        ctx: &GpuContext,
        io: &FrameIo<'_>,
        pass: &Pass,
        frame: Frame,
    ) -> Result<()> {
        let Some(mut front) = self.wavefront.take() else {
            return Ok(());
        };
        front.fit(ctx, pass.extent);
        let sums = self.steps_sums(ctx, pass);
        let views = self.views(pass, io);
        let max_steps = self.max_steps(&frame);
        let list_at = std::mem::offset_of!(Frame, wave_list) as u64;
        let words = front.list_words().clone();
        let wave = front.wave().clone();
        let result = self
            .bind(&pass.node, views, &sums, &wave)
            .bound(ctx)
            .and_then(|bound| {
                front.trace_frame(ctx, &self.stats, max_steps, |step, enc| {
                    if step.first {
                        let f = Frame {
                            wave: WAVE_STEP,
                            wave_base: step.base,
                            wave_capacity: step.capacity,
                            wave_split: 0,
                            wave_list: step.list,
                            ..frame
                        };
                        stage_frame(ctx, enc, &f, &self.frame);
                    } else {
                        enc.copy_buffer_to_buffer(
                            &words,
                            4 * u64::from(step.list),
                            &self.frame,
                            list_at,
                            4,
                        );
                    }
                    let groups = [step.groups, 1, 1];
                    if step.first {
                        bound.dispatch(enc, Some("wave_start"), groups, None)?;
                    } else {
                        bound.dispatch(enc, Some("wave_misses"), groups, None)?;
                        bound.dispatch(enc, Some("wave_hits"), groups, None)?;
                    }
                    bound.dispatch(enc, Some("wave_trace"), groups, None)
                })
            });
        self.wavefront = Some(front);
        result
    }

    /// Traces a frame in steps, host intersection's or the wavefront's.
    pub(super) fn trace_steps(
        &mut self,
        ctx: &GpuContext,
        io: &FrameIo<'_>,
        pass: &Pass,
        frame: Frame,
    ) -> Result<()> {
        if self.backend.host().is_some() {
            self.trace_host(ctx, io, pass, frame)
        } else {
            self.trace_wavefront(ctx, io, pass, frame)
        }
    }
}

/// Submits what the graph recorded before this pass, so that the steps of a frame traced
/// in steps run after it, and after the previous frame's finish pass, which reads the sums
/// those steps overwrite (`chunk_sums`, kept from frame to frame). The executor does the
/// same before [`OwnWork::submit_own`](lumagraph_render::nodes::OwnWork::submit_own).
pub(super) fn submit_pending(ctx: &GpuContext, encoder: &mut wgpu::CommandEncoder) {
    let pending = std::mem::replace(
        encoder,
        ctx.device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("graph"),
            }),
    );
    ctx.queue.submit([pending.finish()]);
}
