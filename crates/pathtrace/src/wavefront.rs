//! The wavefront: the path tracer's paths taken one bounce at a time by small kernels, all on
//! the device. Each step shades every listed slot's hit and writes its next ray and shadow
//! ray — the steps of host intersection (`wave_start`, `wave_misses`, `wave_hits` in
//! `shaders/pathtrace/integrator/wave.wgsl`) — and `wave_trace` then traces those rays through the
//! intersector the megakernel would use and lists each slot for the next step, those whose
//! ray missed from the start of the next list and those whose ray hit from its end. Nothing
//! is read back but the two counts of the last list, once per [`STEPS_PER_SUBMIT`] steps, to
//! know when every slot traced its samples; two submissions are kept in flight, so the
//! device does not wait for the host to read one.
//!
//! The random numbers, their order and the arithmetic are the megakernel's, and the rays
//! leave their surfaces by the same rules, so the images are the megakernel's
//! (`tests/pathtrace/wavefront.rs`). Whether the split pays depends on the adapter and the
//! scene: a kernel that only traverses may keep more paths in flight than the whole textured
//! shader does, at the cost of writing each path's state to memory between steps and of
//! four dispatches per step. On an NVIDIA H200 it paid on Sponza (1.11×) and lost 1.7× to
//! 6.7× on smaller or untextured scenes; where `Schedule::Auto` chooses it follows
//! (`specialize::WAVEFRONT_MIN_TRIANGLES`, `docs/benchmarks.md`).

use wgpu::util::DeviceExt as _;

use lumagraph_render::context::GpuContext;
use lumagraph_render::error::{RenderError, Result};
use lumagraph_render::readback::map_read_after;
use lumagraph_render::shared::{WAVE_COUNTS_AT, WAVE_FRONT_LISTS_AT};

/// At most this many slots (pixels) in the buffers: 216 bytes each, 216 MiB for a
/// million; larger windows (and buffers over the device's binding limit) are traced in
/// batches, one after the other.
const MAX_SLOTS: u64 = 1 << 20;

/// Bytes per slot of the `wave` buffer: the sections up to the lists, then a word in each.
const SLOT_BYTES: u64 = 16 * WAVE_FRONT_LISTS_AT as u64 + 8;

/// Steps recorded into one submission before the host reads whether any slot is left: a
/// step over a list that emptied costs a few empty dispatches.
const STEPS_PER_SUBMIT: u64 = 16;

/// Slots per workgroup of the steps and of `wave_trace` (1D dispatches).
const GROUP: u64 = 64;

/// One step, for the caller that records it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct FrontStep {
    /// The batch's first step (`wave_start`; else `wave_misses` then `wave_hits`), whose
    /// caller also sets the batch's slots in the frame's uniform block.
    pub first: bool,
    /// The batch's first slot, and the slots the buffers hold.
    pub base: u32,
    pub capacity: u32,
    /// Which of the two lists is the step's (`Frame::wave_list`).
    pub list: u32,
    /// Workgroups of [`GROUP`] slots to dispatch, for the steps and `wave_trace` alike.
    pub groups: u32,
}

/// The wavefront's buffers for one window.
pub(crate) struct Wavefront {
    /// Paths in flight, their rays and hits, and the two lists (`wave` in the shader).
    wave: wgpu::Buffer,
    /// `[0, 1]`: the word copied into `Frame::wave_list` before each step.
    list_words: wgpu::Buffer,
    /// The last list's counts, read back, for each of the two submissions in flight.
    counts_read: [wgpu::Buffer; 2],
    extent: lumagraph_graph::Extent,
    capacity: u64,
}

impl Wavefront {
    pub(crate) fn new(ctx: &GpuContext) -> Self {
        Self {
            wave: wave_buffer(ctx, 1),
            list_words: ctx
                .device
                .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("pathtrace wavefront list words"),
                    contents: bytemuck::cast_slice(&[0u32, 1u32]),
                    usage: wgpu::BufferUsages::COPY_SRC,
                }),
            counts_read: [0, 1].map(|_| {
                ctx.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("pathtrace wavefront counts readback"),
                    size: 8,
                    usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                })
            }),
            extent: lumagraph_graph::Extent::new(0, 0),
            capacity: GROUP,
        }
    }

    /// The `wave` buffer.
    pub(crate) fn wave(&self) -> &wgpu::Buffer {
        &self.wave
    }

    /// `[0, 1]`, a word each: what a step copies into `Frame::wave_list`.
    pub(crate) fn list_words(&self) -> &wgpu::Buffer {
        &self.list_words
    }

    /// Sizes the buffers for a window of `extent`: all its pixels at once where they fit,
    /// else batches as large as [`MAX_SLOTS`] and the device's storage binding allow.
    pub(crate) fn fit(&mut self, ctx: &GpuContext, extent: lumagraph_graph::Extent) {
        if extent == self.extent {
            return;
        }
        let limits = ctx.device.limits();
        let binding = limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size);
        let most = (binding / SLOT_BYTES / GROUP * GROUP).clamp(GROUP, MAX_SLOTS);
        self.capacity = extent.pixels().next_multiple_of(GROUP).clamp(GROUP, most);
        self.wave = wave_buffer(ctx, self.capacity);
        self.extent = extent;
    }

    /// Traces a frame: `step` records each step (its kernels); every
    /// [`STEPS_PER_SUBMIT`] steps are submitted and the host reads whether any slot is left;
    /// batch after batch of slots.
    ///
    /// # Errors
    /// When `step` fails, a readback fails, or the paths are not done after `max_steps`.
    pub(crate) fn trace_frame(
        &mut self,
        ctx: &GpuContext,
        stats: &wgpu::Buffer,
        max_steps: u64,
        mut step: impl FnMut(FrontStep, &mut wgpu::CommandEncoder) -> Result<()>,
    ) -> Result<()> {
        let pixels = self.extent.pixels();
        let capacity = self.capacity;
        let groups = u32::try_from(capacity / GROUP).unwrap_or(u32::MAX);
        let lists_at = 16 * u64::from(WAVE_FRONT_LISTS_AT) * capacity;
        let counts_at = 4 * u64::from(WAVE_COUNTS_AT);
        let mut base = 0;
        while base < pixels {
            let end = (base + capacity).min(pixels);
            // The first list: the batch's slots, every one a "miss" (nothing to shade yet).
            let slots: Vec<u32> = (base..end)
                .map(|s| u32::try_from(s).unwrap_or(u32::MAX))
                .collect();
            ctx.queue
                .write_buffer(&self.wave, lists_at, bytemuck::cast_slice(&slots));
            let count = u32::try_from(end - base).unwrap_or(u32::MAX);
            ctx.queue
                .write_buffer(stats, counts_at, bytemuck::cast_slice(&[count, 0]));
            // Two submissions in flight: while the device runs one, the host records the
            // next, then reads the counts the first left (the last one may step over empty
            // lists: a few dispatches that find no slot).
            let mut n: u64 = 0;
            let mut in_flight: Option<(wgpu::SubmissionIndex, usize)> = None;
            for chunk in 0usize.. {
                let mut encoder =
                    ctx.device
                        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                            label: Some("pathtrace wavefront steps"),
                        });
                for _ in 0..STEPS_PER_SUBMIT {
                    step(
                        FrontStep {
                            first: n == 0,
                            base: u32::try_from(base).unwrap_or(u32::MAX),
                            capacity: u32::try_from(capacity).unwrap_or(u32::MAX),
                            list: u32::from(n % 2 == 1),
                            groups,
                        },
                        &mut encoder,
                    )?;
                    n += 1;
                }
                // The list the last step's `wave_trace` filled: the next step's.
                let read = &self.counts_read[chunk % 2];
                encoder.copy_buffer_to_buffer(stats, counts_at + 8 * (n % 2), read, 0, 8);
                let index = ctx.queue.submit([encoder.finish()]);
                let Some((before, which)) = in_flight.replace((index, chunk % 2)) else {
                    continue;
                };
                let left = self.left(ctx, before, which)?;
                if left == 0 {
                    // The chunk just submitted steps over empty lists; wait for it, so the
                    // next batch's first list is written after it ran.
                    if let Some((index, _)) = in_flight.take() {
                        lumagraph_render::readback::wait_for(ctx, index)?;
                    }
                    break;
                }
                if n > max_steps + STEPS_PER_SUBMIT {
                    return Err(RenderError::Gpu(format!(
                        "wavefront: the paths were not done after {max_steps} steps \
                         ({left} slots left)"
                    )));
                }
            }
            base = end;
        }
        Ok(())
    }
}

impl Wavefront {
    /// The slots left in the list that submission `index` ended on (read back into
    /// `counts_read[which]`).
    fn left(&self, ctx: &GpuContext, index: wgpu::SubmissionIndex, which: usize) -> Result<u64> {
        map_read_after(ctx, &self.counts_read[which], index, 8, |b| {
            let c: &[u32] = bytemuck::cast_slice(b);
            c.iter().map(|&x| u64::from(x)).sum()
        })
    }
}

fn wave_buffer(ctx: &GpuContext, slots: u64) -> wgpu::Buffer {
    use wgpu::BufferUsages as U;
    ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("pathtrace wavefront"),
        size: (SLOT_BYTES * slots).max(16),
        usage: U::STORAGE | U::COPY_DST,
        mapped_at_creation: false,
    })
}
