//! Host intersection for the path tracer on CPU adapters. llvmpipe runs WGSL BVH traversal
//! several times slower than Embree runs on the same cores (`docs/benchmarks.md`), so where
//! Embree is found ([`crate::embree`]) and the scene allows (the plan's "intersector:
//! host", [`crate::intersect::host`]),
//! the path tracer's kernel takes every pixel's path one step at a time and the host
//! intersects the rays of each step in between: the kernel writes each path's next ray and
//! its shadow ray into the `wave` buffer, the host reads them back, traces them with Embree
//! on its threads and writes the hits back, and the kernel shades them in the next dispatch
//! (`wave_start`, `wave_misses` and `wave_hits` in `shaders/pathtrace/integrator/wave.wgsl`). The
//! random numbers and the shading are the kernel's own; only the hits come from Embree.

use crate::embree::{Embree, HostHit, HostRay, HostScene};
use lumagraph_render::context::GpuContext;
use lumagraph_render::error::{RenderError, Result};
use lumagraph_render::readback::{map_read_after, map_write_after};
use lumagraph_render::shared::{WAVE_FINISH_ME, WaveRays};

/// `wave`'s sections, in vec4 per slot of the batch (declared once in [`lumagraph_render::shared`]).
const RAYS_AT: u64 = lumagraph_render::shared::WAVE_RAYS_AT as u64;
const HITS_AT: u64 = lumagraph_render::shared::WAVE_HITS_AT as u64;
const LIST_AT: u64 = lumagraph_render::shared::WAVE_LIST_AT as u64;
const INSTS_AT: u64 = lumagraph_render::shared::WAVE_INSTS_AT as u64;
/// Bytes of one slot's rays.
const RAYS_BYTES: u64 = std::mem::size_of::<WaveRays>() as u64;

/// At most this many workgroups of 64 per step: each invocation steps every slot one
/// `64 * STEP_GROUPS` apart (see `main` in the shader).
const STEP_GROUPS: u32 = 64;

/// Lanes of slots traced in turn (see `HostRays`): one. With two (even and odd rows), the
/// host traced one lane's rays while the kernel stepped the other's, but on a 2-core machine
/// the four threads only contend for the cores and caches: one lane ran 1.09× the paths/s of
/// two (four alternating pairs of `bench` runs; `docs/benchmarks.md`).
const LANES: u32 = 1;

/// At most this many slots (pixels) in the buffers: larger windows are traced in batches
/// of this many pixels, one after the other (its buffers take 248 bytes per slot and lane,
/// with the upload and readback copies).
const MAX_SLOTS: u64 = 1 << 18;

/// What the kernel's step is to do, for the caller that records it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct WaveStep {
    /// The batch's first step: start each slot's first path (`wave_start` over all the
    /// listed slots); else `wave_misses` over the first `misses` listed slots and
    /// `wave_hits` over the `hits` after them.
    pub first: bool,
    /// The batch's first slot, and the slots the buffers hold.
    pub base: u32,
    pub capacity: u32,
    pub misses: u32,
    pub hits: u32,
}

impl WaveStep {
    /// Workgroups (1D, 64 invocations each) to dispatch over `slots` listed slots.
    pub(crate) fn groups(slots: u32) -> u32 {
        slots.div_ceil(64).clamp(1, STEP_GROUPS)
    }
}

/// Records a step of the kernel into the encoder, bound to the `wave` buffer given.
type StepFn<'a> = dyn FnMut(WaveStep, &mut wgpu::CommandEncoder, &wgpu::Buffer) -> Result<()> + 'a;

/// The scene in Embree and the lanes of slots traced in turn.
pub struct HostRays {
    scene: HostScene,
    /// The window's rows alternate between the lanes (with two, even rows and odd rows),
    /// each with its own buffers: while the kernel steps one lane's paths, the host
    /// intersects another lane's rays.
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
    /// `MAP_WRITE` buffer of the next step's hits, list and (with instances) the hits'
    /// instances, copied into `wave` in its encoder; and the bytes of each, for that copy.
    upload: wgpu::Buffer,
    uploaded: (u64, u64, u64),
    /// The last submission that used `upload` (`None`: mapped since its creation).
    last: Option<wgpu::SubmissionIndex>,
    /// The step's next rays, then its shadow rays.
    rays: Vec<HostRay>,
    hits: Vec<HostHit>,
    /// The instance of each hit (its node slot, or `NO_INSTANCE`): kept where the scene has
    /// instances, else empty.
    insts: Vec<u32>,
    /// 1 where the shadow ray is occluded.
    occluded: Vec<u32>,
    /// The slots of the step being traced, in its order, and how many of them come first
    /// as those whose ray missed (or that only await a shadow ray).
    order: Vec<u32>,
    misses: usize,
    /// The next step's slots: their count first, then each one; the hits of their rays
    /// (with the answers for their shadow rays), in that order.
    list: Vec<u32>,
    list_hits: Vec<HostHit>,
    list_insts: Vec<u32>,
    /// The submission of the step in flight and the bytes of rays it copies back.
    in_flight: Option<(wgpu::SubmissionIndex, u64)>,
    /// Steps submitted in this batch.
    steps: u64,
    /// What was done since the last count.
    counts: HostCounts,
}

/// What host intersection did, for the node's counters: rays, steps, and where the host
/// thread's time went (nanoseconds).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct HostCounts {
    /// Rays traced (next and shadow rays, not the "none" entries).
    pub rays: u64,
    /// Kernel steps submitted.
    pub steps: u64,
    /// Waiting for a step's rays (the kernel running, or the driver's queue).
    pub wait_ns: u64,
    /// In Embree.
    pub embree_ns: u64,
    /// Reading rays back, listing the next step's slots, writing its hits and recording it.
    pub other_ns: u64,
}

impl std::ops::AddAssign for HostCounts {
    fn add_assign(&mut self, o: Self) {
        self.rays += o.rays;
        self.steps += o.steps;
        self.wait_ns += o.wait_ns;
        self.embree_ns += o.embree_ns;
        self.other_ns += o.other_ns;
    }
}

/// Nanoseconds since `t`, and `t` moved on to now.
fn lap(t: &mut std::time::Instant) -> u64 {
    let now = std::time::Instant::now();
    let ns = u64::try_from((now - *t).as_nanos()).unwrap_or(u64::MAX);
    *t = now;
    ns
}

impl Lane {
    fn new(ctx: &GpuContext, slots: u64, instanced: bool) -> Self {
        // The sections of `wave` (see the shader), the last the list of slots to step,
        // their count first; or, with instances, the hits' instances after it.
        let vec4s = if instanced {
            INSTS_AT * slots + slots.div_ceil(4)
        } else {
            LIST_AT * slots + (slots + 1).div_ceil(4)
        };
        let insts_bytes = if instanced {
            4 * slots.next_multiple_of(4)
        } else {
            0
        };
        let n = usize::try_from(slots).unwrap_or(usize::MAX);
        Self {
            wave: buffer(ctx, "pathtrace wave", 16 * vec4s, false),
            rays_read: buffer(
                ctx,
                "pathtrace wave rays readback",
                RAYS_BYTES * slots,
                true,
            ),
            upload: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("pathtrace wave upload"),
                size: 16 * slots + 4 * (slots + 1).next_multiple_of(4) + insts_bytes,
                usage: wgpu::BufferUsages::MAP_WRITE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: true,
            }),
            uploaded: (0, 0, 0),
            last: None,
            rays: vec![HostRay::default(); 2 * n],
            hits: vec![HostHit::default(); n],
            insts: if instanced { vec![0; n] } else { Vec::new() },
            occluded: vec![0; n],
            order: Vec::new(),
            misses: 0,
            list: Vec::new(),
            list_hits: Vec::new(),
            list_insts: Vec::new(),
            in_flight: None,
            steps: 0,
            counts: HostCounts::default(),
        }
    }

    /// Writes the next step's hits (with the shadow answers) and list into `upload`, for
    /// `submit` to copy into `wave`.
    fn upload(&mut self, ctx: &GpuContext) -> Result<()> {
        let count = self.list.len() - 1;
        self.list[0] = u32::try_from(count).unwrap_or(u32::MAX);
        self.list.resize(self.list.len().next_multiple_of(4), 0);
        let hits: &[u8] = bytemuck::cast_slice(&self.list_hits);
        let list: &[u8] = bytemuck::cast_slice(&self.list);
        let insts: &[u8] = bytemuck::cast_slice(&self.list_insts);
        map_write_after(ctx, &self.upload, self.last.take(), |view| {
            view.slice(..hits.len()).copy_from_slice(hits);
            let end = hits.len() + list.len();
            view.slice(hits.len()..end).copy_from_slice(list);
            if !insts.is_empty() {
                view.slice(end..end + insts.len()).copy_from_slice(insts);
            }
        })?;
        self.uploaded = (hits.len() as u64, list.len() as u64, insts.len() as u64);
        self.order.clear();
        self.order.extend_from_slice(&self.list[1..=count]);
        Ok(())
    }

    /// Records and submits the lane's next step and the copy of the rays it writes.
    fn submit(
        &mut self,
        ctx: &GpuContext,
        [base, capacity]: [u64; 2],
        step: &mut StepFn<'_>,
    ) -> Result<()> {
        let mut t = std::time::Instant::now();
        let c = self.order.len();
        let first = self.steps == 0;
        let misses = if first { c } else { self.misses.min(c) };
        let what = WaveStep {
            first,
            base: u32::try_from(base).unwrap_or(u32::MAX),
            capacity: u32::try_from(capacity).unwrap_or(u32::MAX),
            misses: u32::try_from(misses).unwrap_or(u32::MAX),
            hits: u32::try_from(c - misses).unwrap_or(u32::MAX),
        };
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("pathtrace step"),
            });
        let (hits, list, insts) = self.uploaded;
        if hits > 0 {
            encoder.copy_buffer_to_buffer(
                &self.upload,
                0,
                &self.wave,
                16 * HITS_AT * capacity,
                hits,
            );
        }
        encoder.copy_buffer_to_buffer(
            &self.upload,
            hits,
            &self.wave,
            16 * LIST_AT * capacity,
            list,
        );
        if insts > 0 {
            encoder.copy_buffer_to_buffer(
                &self.upload,
                hits + list,
                &self.wave,
                16 * INSTS_AT * capacity,
                insts,
            );
        }
        step(what, &mut encoder, &self.wave)?;
        // The rays of its first `c` slots.
        let bytes = RAYS_BYTES * c as u64;
        encoder.copy_buffer_to_buffer(
            &self.wave,
            16 * RAYS_AT * capacity,
            &self.rays_read,
            0,
            bytes,
        );
        let index = ctx.queue.submit([encoder.finish()]);
        self.last = Some(index.clone());
        self.in_flight = Some((index, bytes));
        self.steps += 1;
        self.counts.steps += 1;
        self.counts.other_ns += lap(&mut t);
        Ok(())
    }

    /// Waits for the step in flight, intersects its rays and lists the slots that wrote
    /// any for the next step; false when none did (the lane is done).
    fn trace(&mut self, ctx: &GpuContext, scene: &HostScene) -> Result<bool> {
        let Some((index, bytes)) = self.in_flight.take() else {
            return Ok(false);
        };
        let c = self.order.len();
        let (next, shadow) = self.rays[..2 * c].split_at_mut(c);
        let mut t = std::time::Instant::now();
        let mut wait = 0;
        map_read_after(ctx, &self.rays_read, index, bytes, |b| {
            wait = lap(&mut t);
            let rays: &[WaveRays] = bytemuck::cast_slice(b);
            for ((w, n), s) in rays.iter().zip(next.iter_mut()).zip(shadow.iter_mut()) {
                *n = HostRay {
                    origin: w.origin,
                    tnear: w.next_near,
                    dir: w.next_dir,
                    tfar: if w.next_near < 0.0 { -1.0 } else { f32::MAX },
                };
                *s = HostRay {
                    origin: w.origin,
                    tnear: w.shadow_near,
                    dir: w.shadow_dir,
                    tfar: w.shadow_far,
                };
            }
        })?;
        self.counts.wait_ns += wait;

        let (next, shadow) = self.rays[..2 * c].split_at(c);
        self.counts.rays += next.iter().chain(shadow).filter(|r| r.tfar >= 0.0).count() as u64;
        self.counts.other_ns += lap(&mut t);
        if self.insts.is_empty() {
            scene.intersect(next, &mut self.hits[..c]);
        } else {
            scene.intersect_instances(next, &mut self.hits[..c], &mut self.insts[..c]);
        }
        scene.occluded(shadow, &mut self.occluded[..c]);
        self.counts.embree_ns += lap(&mut t);
        // The next step's slots: those with a ray out, those whose ray hit nothing (or
        // that only await a shadow ray) first, then those that shade a hit. llvmpipe runs a
        // SIMD vector's lanes through every branch any of them takes, so lanes taking the
        // same branches should be neighbours.
        self.list.clear();
        self.list.push(0);
        self.list_hits.clear();
        self.list_insts.clear();
        for shade in [false, true] {
            self.misses = self.list.len() - 1;
            for (j, (a, b)) in next.iter().zip(shadow).enumerate() {
                // A ray out, or none but a path that ended at a surface to finish.
                let out = a.tfar >= 0.0 || b.tfar >= 0.0 || a.tnear == WAVE_FINISH_ME;
                if out && (a.tfar >= 0.0 && self.hits[j].is_hit()) == shade {
                    let mut hit = self.hits[j];
                    if self.occluded[j] != 0 {
                        hit.t = -hit.t;
                    }
                    self.list.push(self.order[j]);
                    self.list_hits.push(hit);
                    if let Some(&inst) = self.insts.get(j) {
                        self.list_insts.push(inst);
                    }
                }
            }
        }
        if self.list.len() == 1 {
            self.counts.other_ns += lap(&mut t);
            return Ok(false);
        }
        self.upload(ctx)?;
        self.counts.other_ns += lap(&mut t);
        Ok(true)
    }
}

impl HostRays {
    /// Puts the scene's triangles into Embree.
    ///
    /// # Errors
    /// When Embree cannot be loaded or refuses the scene.
    pub(crate) fn new(
        ctx: &GpuContext,
        scene: &std::sync::Arc<lumagraph_scene::GpuScene>,
    ) -> Result<Self> {
        let fail = |e: String| RenderError::Gpu(format!("host intersection: {e}"));
        let embree = Embree::load().map_err(fail)?;
        let version = embree.version();
        let start = std::time::Instant::now();
        let (instances, meshes) = (scene.instances.len(), scene.mesh_triangles.len());
        let scene = HostScene::of_scene(embree, scene).map_err(fail)?;
        let note = format!(
            "host intersection: {version}, {} triangles{} built in {:.0} ms",
            scene.len(),
            if scene.has_instances() {
                format!(" ({instances} instances of {meshes} meshes)")
            } else {
                String::new()
            },
            start.elapsed().as_secs_f64() * 1e3
        );
        let extent = lumagraph_graph::Extent::new(1, 1);
        let instanced = scene.has_instances();
        Ok(Self {
            scene,
            lanes: (0..LANES).map(|_| Lane::new(ctx, 1, instanced)).collect(),
            extent,
            capacity: 1,
            note,
        })
    }

    /// What was done since the last call (the kernel counts no rays).
    pub(crate) fn take_counts(&mut self) -> HostCounts {
        let mut all = HostCounts::default();
        for lane in &mut self.lanes {
            all += std::mem::take(&mut lane.counts);
        }
        all
    }

    /// A `wave` buffer (for the pass that reads none).
    pub(crate) fn wave(&self) -> &wgpu::Buffer {
        &self.lanes[0].wave
    }

    /// Sizes the buffers for a window of `extent`.
    pub(crate) fn fit(&mut self, ctx: &GpuContext, extent: lumagraph_graph::Extent) {
        if extent != self.extent {
            self.capacity = extent.pixels().clamp(1, MAX_SLOTS);
            let instanced = self.scene.has_instances();
            self.lanes = (0..LANES)
                .map(|_| Lane::new(ctx, self.capacity, instanced))
                .collect();
            self.extent = extent;
        }
    }

    /// Traces a frame: `step` records a lane's next step, which is submitted; the host
    /// intersects the rays it wrote (while another lane's step runs, where there are
    /// several), and lists the slots that wrote any for the lane's next step, until no slot
    /// of any lane did; batch after batch of slots.
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
                lane.list_insts.clear();
                lane.list.extend(
                    (base..end)
                        .filter(|s| (s / width) % u64::from(LANES) == l)
                        .map(|s| u32::try_from(s).unwrap_or(u32::MAX)),
                );
                if lane.list.len() > 1 {
                    lane.upload(ctx)?;
                    lane.submit(ctx, [base, capacity], &mut step)?;
                }
            }
            let mut live: Vec<bool> = self.lanes.iter().map(|l| l.in_flight.is_some()).collect();
            while live.iter().any(|&l| l) {
                for (l, lane) in self.lanes.iter_mut().enumerate() {
                    if !live[l] {
                        continue;
                    }
                    live[l] = lane.trace(ctx, &self.scene)?;
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
