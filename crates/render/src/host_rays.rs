//! Host intersection for the path tracer on CPU adapters. llvmpipe runs WGSL BVH traversal
//! several times slower than Embree runs on the same cores (`docs/benchmarks.md`), so where
//! Embree is found ([`crate::embree`]) and the scene allows (the plan's "host intersection"),
//! the path tracer's kernel takes every pixel's path one step at a time and the host
//! intersects the rays of each step in between: the kernel writes each path's next ray and
//! its shadow ray into the `wave` buffer, the host reads them back, traces them with Embree
//! on its threads and writes the hits back, and the kernel shades them in the next dispatch
//! (`wave_step` in `shaders/pathtrace/pathtrace.wgsl`). The random numbers and the shading
//! are the kernel's own; only the hits come from Embree.

use crate::context::GpuContext;
use crate::embree::{Embree, HostHit, HostRay, HostScene};
use crate::error::{RenderError, Result};
use crate::readback::map_read_after;

/// `wave` holds per pixel of the window: the path in flight (8 vec4), its next ray and its
/// shadow ray (2 vec4 each), the hit of its ray (1 vec4), and in the last section the
/// shadow ray's answer, a u32.
const STATE_VEC4S: u64 = 8;
const RAYS_AT: u64 = STATE_VEC4S;
const HITS_AT: u64 = RAYS_AT + 4;
const OCCLUDED_AT: u64 = HITS_AT + 1;

/// At most this many workgroups of 64 per step: each invocation steps every slot one
/// `64 * STEP_GROUPS` apart (see `main` in the shader).
const STEP_GROUPS: u32 = 64;

/// Lanes of slots traced in turn (see `HostRays`).
const LANES: u32 = 2;

/// At most this many slots (pixels) in the buffers: larger windows are traced in batches
/// of this many pixels, one after the other (its buffers take 212 bytes per slot and lane).
const MAX_SLOTS: u64 = 1 << 18;

/// What the kernel's step is to do, for the caller that records it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct WaveStep {
    /// The batch's first step: start each slot's first path.
    pub first: bool,
    /// The batch's first slot, and the slots the buffers hold.
    pub base: u32,
    pub capacity: u32,
    /// Workgroups to dispatch (1D, 64 invocations each).
    pub groups: u32,
}

/// Records a step of the kernel into the encoder, bound to the `wave` buffer given.
type StepFn<'a> = dyn FnMut(WaveStep, &mut wgpu::CommandEncoder, &wgpu::Buffer) -> Result<()> + 'a;

/// The scene in Embree and two lanes of slots traced in turn.
pub(crate) struct HostRays {
    scene: HostScene,
    /// The window's rows alternate between two lanes (even rows, odd rows), each with its
    /// own buffers: while the kernel steps one lane's paths, the host intersects the other
    /// lane's rays, so neither waits for the other (the driver's threads and the host's
    /// share the cores).
    lanes: Vec<Lane>,
    /// The window the buffers are for, and the slots they hold (all of its pixels, or a
    /// batch of [`MAX_SLOTS`]).
    extent: lumagraph_graph::Extent,
    capacity: u64,
    /// What was built, and how long it took, for the node's notes.
    pub(crate) note: String,
}

/// One lane: its `wave` buffer, the readback of its rays, the host's copies.
struct Lane {
    /// Paths in flight and the rays between kernel and host (`wave` in the shader).
    wave: wgpu::Buffer,
    /// `MAP_READ` copy of the step's rays.
    rays_read: wgpu::Buffer,
    /// The step's next rays, then its shadow rays.
    rays: Vec<HostRay>,
    hits: Vec<HostHit>,
    /// 1 where the shadow ray is occluded.
    occluded: Vec<u32>,
    /// The slots of the step being traced, in its order.
    order: Vec<u32>,
    /// The next step's slots: their count first, then each one; the hits of their rays
    /// and the answers for their shadow rays, in that order.
    list: Vec<u32>,
    list_hits: Vec<HostHit>,
    list_occluded: Vec<u32>,
    /// The submission of the step in flight and the bytes of rays it copies back.
    in_flight: Option<(wgpu::SubmissionIndex, u64)>,
    /// Steps submitted in this batch.
    steps: u64,
    /// Rays traced (next and shadow rays, not the "none" entries) since the last count.
    traced: u64,
}

impl Lane {
    fn new(ctx: &GpuContext, slots: u64) -> Self {
        // The sections of `wave` (see the shader), the last the list of slots to step,
        // their count first.
        let vec4s = OCCLUDED_AT * slots + slots.div_ceil(4) + (slots + 1).div_ceil(4);
        let n = usize::try_from(slots).unwrap_or(usize::MAX);
        Self {
            wave: buffer(ctx, "pathtrace wave", 16 * vec4s, false),
            rays_read: buffer(ctx, "pathtrace wave rays readback", 64 * slots, true),
            rays: vec![HostRay::default(); 2 * n],
            hits: vec![HostHit::default(); n],
            occluded: vec![0; n],
            order: Vec::new(),
            list: Vec::new(),
            list_hits: Vec::new(),
            list_occluded: Vec::new(),
            in_flight: None,
            steps: 0,
            traced: 0,
        }
    }

    /// Writes the next step's list, hits and shadow answers into `wave`.
    fn upload(&mut self, ctx: &GpuContext, slots: u64) {
        let count = self.list.len() - 1;
        self.list[0] = u32::try_from(count).unwrap_or(u32::MAX);
        self.list.resize(self.list.len().next_multiple_of(4), 0);
        self.list_occluded.resize(count.next_multiple_of(4), 0);
        let q = &ctx.queue;
        if !self.list_hits.is_empty() {
            q.write_buffer(
                &self.wave,
                16 * HITS_AT * slots,
                bytemuck::cast_slice(&self.list_hits),
            );
            q.write_buffer(
                &self.wave,
                16 * OCCLUDED_AT * slots,
                bytemuck::cast_slice(&self.list_occluded),
            );
        }
        q.write_buffer(
            &self.wave,
            16 * (OCCLUDED_AT * slots + slots.div_ceil(4)),
            bytemuck::cast_slice(&self.list),
        );
        self.order.clear();
        self.order.extend_from_slice(&self.list[1..=count]);
    }

    /// Records and submits the lane's next step and the copy of the rays it writes.
    fn submit(
        &mut self,
        ctx: &GpuContext,
        [base, capacity]: [u64; 2],
        step: &mut StepFn<'_>,
    ) -> Result<()> {
        let c = self.order.len();
        let what = WaveStep {
            first: self.steps == 0,
            base: u32::try_from(base).unwrap_or(u32::MAX),
            capacity: u32::try_from(capacity).unwrap_or(u32::MAX),
            groups: u32::try_from(c.div_ceil(64))
                .unwrap_or(u32::MAX)
                .clamp(1, STEP_GROUPS),
        };
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("pathtrace step"),
            });
        step(what, &mut encoder, &self.wave)?;
        // Its next rays, then its shadow rays: the first `c` of each section.
        let bytes = 32 * c as u64;
        let at = 16 * RAYS_AT * capacity;
        encoder.copy_buffer_to_buffer(&self.wave, at, &self.rays_read, 0, bytes);
        encoder.copy_buffer_to_buffer(
            &self.wave,
            at + 32 * capacity,
            &self.rays_read,
            bytes,
            bytes,
        );
        self.in_flight = Some((ctx.queue.submit([encoder.finish()]), 2 * bytes));
        self.steps += 1;
        Ok(())
    }

    /// Waits for the step in flight, intersects its rays and lists the slots that wrote
    /// any for the next step; false when none did (the lane is done).
    fn trace(&mut self, ctx: &GpuContext, scene: &HostScene, capacity: u64) -> Result<bool> {
        let Some((index, bytes)) = self.in_flight.take() else {
            return Ok(false);
        };
        let c = self.order.len();
        let rays = &mut self.rays[..2 * c];
        map_read_after(ctx, &self.rays_read, index, bytes, |b| {
            rays.copy_from_slice(bytemuck::cast_slice(b));
        })?;
        let (next, shadow) = self.rays[..2 * c].split_at(c);
        self.traced += next.iter().chain(shadow).filter(|r| r.tfar >= 0.0).count() as u64;
        scene.intersect(next, &mut self.hits[..c]);
        scene.occluded(shadow, &mut self.occluded[..c]);
        // The next step's slots: those with a ray out, those whose ray hit nothing (or
        // that only await a shadow ray) first, then those that shade a hit. llvmpipe runs a
        // SIMD vector's lanes through every branch any of them takes, so lanes taking the
        // same branches should be neighbours.
        self.list.clear();
        self.list.push(0);
        self.list_hits.clear();
        self.list_occluded.clear();
        for shade in [false, true] {
            for (j, (a, b)) in next.iter().zip(shadow).enumerate() {
                let out = a.tfar >= 0.0 || b.tfar >= 0.0;
                if out && (a.tfar >= 0.0 && self.hits[j].is_hit()) == shade {
                    self.list.push(self.order[j]);
                    self.list_hits.push(self.hits[j]);
                    self.list_occluded.push(self.occluded[j]);
                }
            }
        }
        if self.list.len() == 1 {
            return Ok(false);
        }
        self.upload(ctx, capacity);
        Ok(true)
    }
}

impl HostRays {
    /// Puts the scene's triangles into Embree.
    ///
    /// # Errors
    /// When Embree cannot be loaded or refuses the scene.
    pub(crate) fn new(ctx: &GpuContext, scene: &lumagraph_scene::GpuScene) -> Result<Self> {
        let fail = |e: String| RenderError::Gpu(format!("host intersection: {e}"));
        let embree = Embree::load().map_err(fail)?;
        let version = embree.version();
        let start = std::time::Instant::now();
        let scene = HostScene::new(embree, &scene.tri_corners).map_err(fail)?;
        let note = format!(
            "host intersection: {version}, {} triangles built in {:.0} ms",
            scene.len(),
            start.elapsed().as_secs_f64() * 1e3
        );
        let extent = lumagraph_graph::Extent::new(1, 1);
        Ok(Self {
            scene,
            lanes: (0..LANES).map(|_| Lane::new(ctx, 1)).collect(),
            extent,
            capacity: 1,
            note,
        })
    }

    /// The rays traced since the last call: the kernel counts none.
    pub(crate) fn take_rays(&mut self) -> u64 {
        self.lanes
            .iter_mut()
            .map(|l| std::mem::take(&mut l.traced))
            .sum()
    }

    /// A `wave` buffer (for the pass that reads none).
    pub(crate) fn wave(&self) -> &wgpu::Buffer {
        &self.lanes[0].wave
    }

    /// Sizes the buffers for a window of `extent`.
    pub(crate) fn fit(&mut self, ctx: &GpuContext, extent: lumagraph_graph::Extent) {
        if extent != self.extent {
            self.capacity = extent.pixels().clamp(1, MAX_SLOTS);
            self.lanes = (0..LANES).map(|_| Lane::new(ctx, self.capacity)).collect();
            self.extent = extent;
        }
    }

    /// Traces a frame: `step` records a lane's next step, which is submitted; the host
    /// intersects the rays it wrote while the other lane's step runs, and lists the slots
    /// that wrote any for the lane's next step, until no slot of either lane did; batch
    /// after batch of slots.
    ///
    /// # Errors
    /// When `step` fails, a readback fails, or the paths are not done after `max_steps`.
    pub(crate) fn trace_frame(
        &mut self,
        ctx: &GpuContext,
        max_steps: u64,
        mut step: impl FnMut(WaveStep, &mut wgpu::CommandEncoder, &wgpu::Buffer) -> Result<()>,
    ) -> Result<()> {
        let pixels = self.extent.pixels();
        let capacity = self.capacity;
        let width = u64::from(self.extent.width.max(1));
        let mut base = 0;
        while base < pixels {
            let end = (base + capacity).min(pixels);
            for (l, lane) in (0u64..).zip(&mut self.lanes) {
                lane.steps = 0;
                lane.list.clear();
                lane.list.push(0);
                lane.list_hits.clear();
                lane.list_occluded.clear();
                lane.list.extend(
                    (base..end)
                        .filter(|s| (s / width) % u64::from(LANES) == l)
                        .map(|s| u32::try_from(s).unwrap_or(u32::MAX)),
                );
                if lane.list.len() > 1 {
                    lane.upload(ctx, capacity);
                    lane.submit(ctx, [base, capacity], &mut step)?;
                }
            }
            let mut live: Vec<bool> = self.lanes.iter().map(|l| l.in_flight.is_some()).collect();
            while live.iter().any(|&l| l) {
                for (l, lane) in self.lanes.iter_mut().enumerate() {
                    if !live[l] {
                        continue;
                    }
                    live[l] = lane.trace(ctx, &self.scene, capacity)?;
                    if live[l] {
                        if lane.steps > max_steps {
                            return Err(RenderError::Gpu(format!(
                                "host intersection: the paths were not done after {max_steps} steps"
                            )));
                        }
                        lane.submit(ctx, [base, capacity], &mut step)?;
                    }
                }
            }
            base = end;
        }
        Ok(())
    }
}

fn buffer(ctx: &GpuContext, label: &str, size: u64, read: bool) -> wgpu::Buffer {
    use wgpu::BufferUsages as U;
    ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size.max(16),
        usage: if read {
            U::MAP_READ | U::COPY_DST
        } else {
            U::STORAGE | U::COPY_SRC | U::COPY_DST
        },
        mapped_at_creation: false,
    })
}
