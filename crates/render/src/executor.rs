//! Executes a plan: one command encoder per frame, every pass recorded in plan order,
//! one submission, then the sinks write their files.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use lumagraph_graph::registry::SAMPLES_PER_FRAME;
use lumagraph_graph::{ParamValue, Plan, TextureId};

use crate::context::GpuContext;
use crate::cpu::Image;
use crate::error::{RenderError, Result};
use crate::library::NodeLibrary;
use crate::nodes::{Counter, FrameIo, Measurement, NodeExec, Recording, Resources};
use crate::pool::{PooledTexture, TexturePool};
use crate::timing::GpuTimer;

/// Which passes a batch of frames records.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Mode {
    /// Progressive passes every frame; everything in the last frame, timed; sinks write.
    Finish,
    /// Progressive passes only.
    Progress,
    /// Everything once, untimed, no files.
    WarmUp,
    /// Only the passes that do not run every frame, timed; sinks write. No frame is added.
    Tail,
    /// Only the passes marked in `Executor::only`, timed; their sinks write. No frame is
    /// added.
    Only,
    /// Everything once, timed, nodes with history presenting it ([`crate::nodes::History::set_present`]);
    /// sinks write. No frame is added.
    Present,
}

/// How [`FrameReport::pass_ms`] was measured.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PassClock {
    /// Timestamp queries written at the beginning and end of each pass.
    #[default]
    Timestamps,
    /// Wall time of each pass submitted alone and waited for. Used on CPU adapters, whose
    /// timestamps do not wait for a dispatch to finish (lavapipe reports ~0.01 ms for a
    /// path-tracing dispatch of 250 ms and charges it to a later pass).
    Wall,
}

impl PassClock {
    /// How the times were measured, for reports.
    pub fn describe(self) -> &'static str {
        match self {
            Self::Timestamps => "GPU timestamps",
            Self::Wall => "wall time of each pass submitted alone (CPU adapter)",
        }
    }
}

/// What one frame did.
#[derive(Clone, Debug, Default)]
pub struct FrameReport {
    /// Milliseconds per pass (summed by node) in the timed frame; `None` when the adapter
    /// cannot time passes. [`FrameReport::pass_clock`] says how they were measured.
    pub pass_ms: Option<Vec<(String, f64)>>,
    /// How `pass_ms` was measured.
    pub pass_clock: PassClock,
    /// Wall time from recording to the last file written.
    pub wall: Duration,
    /// Files written by sinks.
    pub written: Vec<PathBuf>,
    /// Nodes whose passes were recorded, in order.
    pub executed: Vec<String>,
}

/// A plan bound to GPU resources, ready to run frames.
pub struct Executor {
    ctx: GpuContext,
    plan: Plan,
    nodes: Vec<Box<dyn NodeExec>>,
    slots: Vec<PooledTexture>,
    pool: TexturePool,
    timer: Option<GpuTimer>,
    /// Time passes by wall clock (CPU adapters) instead of `timer`.
    wall_clock: bool,
    frames: u64,
    /// Per pass: whether it feeds (or is) a node with history, and so runs every frame.
    every_frame: Vec<bool>,
    /// Per pass: whether a [`Mode::Only`] run records it.
    only: Vec<bool>,
    /// Sinks do not write their files (a tiled render assembles them).
    hold_sinks: bool,
    /// Where [`Executor::move_camera`] last put the camera.
    camera: Option<lumagraph_scene::GpuCamera>,
}

impl std::fmt::Debug for Executor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Executor")
            .field("passes", &self.plan.passes.len())
            .field("frames", &self.frames)
            .finish_non_exhaustive()
    }
}

impl Executor {
    /// Creates every pass's GPU resources, each node by its kind's implementation in
    /// `library`, and the plan's textures.
    ///
    /// # Errors
    /// When a node cannot be set up (missing input file, unwritable output, shader error,
    /// a kind `library` has no implementation of); the error names the node.
    pub fn with_library(
        ctx: &GpuContext,
        plan: Plan,
        paths: &Resources,
        library: &NodeLibrary,
    ) -> Result<Self> {
        check_limits(ctx, &plan)?;
        // Allocation failures (out of memory) and what the limits above do not foresee
        // come back as errors, not as wgpu's panic.
        let memory = ctx.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let validation = ctx.device.push_error_scope(wgpu::ErrorFilter::Validation);
        // Nodes that read or write colour with a colour space (ImageInput, the
        // OpenColorIO nodes, the outputs) take the plan's working space.
        let paths = &Resources {
            working_space: plan.working_space,
            ..paths.clone()
        };
        let nodes = plan
            .passes
            .iter()
            .map(|pass| library.create(ctx, pass, paths))
            .collect::<Result<Vec<_>>>();
        let mut pool = TexturePool::new();
        let slots = pool.acquire(ctx, &plan);
        let invalid = pollster::block_on(validation.pop());
        let oom = pollster::block_on(memory.pop());
        if let Some(e) = oom {
            let textures: u64 = plan.slots.iter().map(lumagraph_graph::Slot::bytes).sum();
            return Err(RenderError::TooLarge {
                what: format!(
                    "{} images ({}) and the nodes' buffers",
                    plan.slots.len(),
                    crate::context::human_bytes(textures)
                ),
                adapter: ctx.info.name.clone(),
                message: format!("the device is out of memory ({e})"),
            });
        }
        let nodes = nodes?;
        if let Some(e) = invalid {
            return Err(ctx.error(e));
        }
        // Two timestamps per pass; nodes with several passes get room too.
        let capacity = u32::try_from(plan.passes.len() * 8)
            .unwrap_or(u32::MAX)
            .max(8);
        let wall_clock = ctx.is_cpu();
        let timer = if wall_clock {
            None
        } else {
            GpuTimer::new(ctx, capacity)
        };
        let every_frame = every_frame(&plan);
        Ok(Self {
            ctx: ctx.clone(),
            plan,
            nodes,
            slots,
            pool,
            timer,
            wall_clock,
            frames: 0,
            every_frame,
            only: Vec::new(),
            hold_sinks: false,
            camera: None,
        })
    }

    /// Frames run so far.
    pub fn frames(&self) -> u64 {
        self.frames
    }

    /// The plan being executed.
    pub fn plan(&self) -> &Plan {
        &self.plan
    }

    /// The GPU context.
    pub fn context(&self) -> &GpuContext {
        &self.ctx
    }

    /// The texture pool (for reporting allocations).
    pub fn pool(&self) -> &TexturePool {
        &self.pool
    }

    /// Moves the window the nodes that render the scene render: its left and top pixel in
    /// the whole image (its size is the plan's). For tiled renders.
    pub fn set_origin(&mut self, origin: [u32; 2]) {
        for view in self.nodes.iter_mut().filter_map(|n| n.view()) {
            view.set_origin(origin);
        }
    }

    /// Starts over: history reset and no frames run (the next tile of a tiled render).
    pub fn restart(&mut self) {
        self.reset_history();
        self.frames = 0;
    }

    /// With `hold`, sinks record as usual but write no files: the caller reads their inputs
    /// ([`Executor::read_raw`]) and writes them (tiled renders).
    pub fn hold_sinks(&mut self, hold: bool) {
        self.hold_sinks = hold;
    }

    /// Restarts progressive accumulation in every node that keeps history.
    pub fn reset_history(&mut self) {
        for node in &mut self.nodes {
            node.reset();
        }
    }

    /// Moves the camera of the nodes that render the scene to `camera`, the scene being
    /// otherwise the same: each node that follows the view gets
    /// [`crate::nodes::View::move_camera`] (a node that reprojects its history,
    /// `TemporalReuse`, keeps it), and every other node restarts its history. Returns whether anything moved (`false` when `camera` is where the nodes
    /// already are).
    pub fn move_camera(&mut self, camera: &lumagraph_scene::GpuCamera) -> bool {
        if self.camera.as_ref() == Some(camera) {
            return false;
        }
        self.camera = Some(*camera);
        for node in &mut self.nodes {
            match node.view() {
                Some(view) => view.move_camera(camera),
                None => node.reset(),
            }
        }
        true
    }

    /// The camera of the last [`Executor::move_camera`]; `None` before one.
    pub fn camera(&self) -> Option<&lumagraph_scene::GpuCamera> {
        self.camera.as_ref()
    }

    /// Takes a recompiled plan that differs from the current one only in params: each
    /// node whose params changed gets [`NodeExec::update`] (a uniform write, a file
    /// reload), and no pipeline, texture or node is recreated. Nodes whose params did not
    /// change are not touched, so state they keep across frames (a progressive
    /// accumulation) survives edits elsewhere in the graph.
    ///
    /// Returns `Ok(false)`, keeping the current plan, when the structure differs (other
    /// passes, ports, sizes or texture assignment): the caller must build a new executor.
    ///
    /// # Errors
    /// When a node cannot apply its new params; the error names the node. The plan is
    /// then left as it was for the nodes not yet updated, so build a new executor.
    pub fn update_params(&mut self, plan: Plan) -> Result<bool> {
        if !same_structure(&self.plan, &plan) {
            return Ok(false);
        }
        for ((old, new), node) in self
            .plan
            .passes
            .iter()
            .zip(&plan.passes)
            .zip(&mut self.nodes)
        {
            if old.params != new.params {
                node.update(&self.ctx, new)
                    .map_err(|e| e.in_node(&new.node))?;
            }
        }
        self.plan = plan;
        Ok(true)
    }

    /// Records, submits and finishes one frame.
    ///
    /// # Errors
    /// When a node fails; the error names the node.
    pub fn run_frame(&mut self) -> Result<FrameReport> {
        self.run_frames(1, true)
    }

    /// Runs `n` frames in one submission: passes that feed a node with history (and that
    /// node) run every frame. With `finish`, the rest of the graph runs once, in the last
    /// frame (the one timed), and sinks write their files; without it, only the progressive
    /// part runs (a long render's intermediate batches).
    ///
    /// # Errors
    /// When a node fails; the error names the node.
    pub fn run_frames(&mut self, n: u32, finish: bool) -> Result<FrameReport> {
        self.run(n, if finish { Mode::Finish } else { Mode::Progress })
    }

    /// Runs only the part of the graph downstream of history (what `run_frames(_, true)`
    /// adds in its last frame: G-buffer, denoiser, post nodes, sinks) over the history as it
    /// is, without adding a frame, so its cost can be timed apart from rendering. Call it
    /// after at least one progressive frame since the last finishing run: textures the
    /// progressive part writes may share memory with textures of the part it runs.
    ///
    /// # Errors
    /// When a node fails; the error names the node.
    pub fn run_tail(&mut self) -> Result<FrameReport> {
        self.run(1, Mode::Tail)
    }

    /// After a param edit ([`Executor::update_params`]), runs only the passes of `changed`
    /// and those downstream of them, reading the other passes' outputs as the last frame
    /// left them, without adding a frame: a tone-mapping or exposure edit re-runs the post
    /// chain over the accumulation as it is.
    ///
    /// When a changed node is progressive (it keeps history or feeds a node that does, such
    /// as a `PathTrace` before an `Accumulate`), its history no longer matches its params:
    /// accumulation restarts ([`Executor::reset_history`]) and a whole frame runs. A whole
    /// frame also runs, without a restart, when an output the partial run would read may
    /// have been overwritten because its texture shares memory with a later one (keep the
    /// upstream outputs alive with [`lumagraph_graph::CompileOptions::keep`] to avoid it),
    /// or before the first frame. [`FrameReport::executed`] tells which passes ran.
    ///
    /// # Errors
    /// When a node fails; the error names the node.
    pub fn rerun(&mut self, changed: &[String]) -> Result<FrameReport> {
        let plan = &self.plan;
        let mut only: Vec<bool> = plan
            .passes
            .iter()
            .map(|p| changed.contains(&p.node))
            .collect();
        for (p, pass) in plan.passes.iter().enumerate() {
            if pass
                .inputs
                .iter()
                .any(|(_, t)| only[plan.textures[t.0].first])
            {
                only[p] = true;
            }
        }
        if only.iter().zip(&self.every_frame).any(|(&o, &e)| o && e) {
            self.reset_history();
            return self.run(1, Mode::Finish);
        }
        // Every texture read by a rerun pass but written by a pass that does not rerun
        // must still hold what that pass wrote: no later texture may share its slot.
        let stale = plan.passes.iter().enumerate().any(|(p, pass)| {
            only[p]
                && pass.inputs.iter().any(|(_, t)| {
                    let desc = &plan.textures[t.0];
                    !only[desc.first]
                        && plan.slots[desc.slot]
                            .textures
                            .iter()
                            .any(|u| plan.textures[u.0].first > desc.first)
                })
        });
        if stale || self.frames == 0 {
            return self.run(1, Mode::Finish);
        }
        self.only = only;
        self.run(1, Mode::Only)
    }

    /// Frames that make `spp` samples per pixel: `spp / samples_per_frame` of the pass
    /// samples come from (rounded up, at least 1); 1 when the plan has no such pass.
    pub fn frames_for(&self, spp: u32) -> u32 {
        spp.div_ceil(self.samples_per_frame()).max(1)
    }

    /// Samples per pixel a frame adds: the `samples_per_frame` of the pass samples come
    /// from; 1 when the plan has no such pass.
    pub fn samples_per_frame(&self) -> u32 {
        self.plan
            .passes
            .iter()
            .find(|p| p.params.has(lumagraph_graph::registry::SAMPLES_PER_FRAME))
            .map_or(1, |p| {
                u32::try_from(p.params.int(lumagraph_graph::registry::SAMPLES_PER_FRAME))
                    .unwrap_or(1)
                    .max(1)
            })
    }

    /// Runs frames until `frames` ran since the last reset (counting those a
    /// [`Executor::restore`] put back), the last one finishing (the whole graph runs,
    /// sinks write): a long render. Frames go in batches that grow while a batch takes
    /// under 200 ms, so `progress(self, done, frames)` is called a few times a second
    /// (it may take a checkpoint); when it returns `false` the render stops there and
    /// `Ok(None)` is returned (nothing written).
    ///
    /// # Errors
    /// When a node fails; the error names the node.
    pub fn render(
        &mut self,
        frames: u32,
        mut progress: impl FnMut(&mut Self, u32, u32) -> bool,
    ) -> Result<Option<FrameReport>> {
        let frames = frames.max(1);
        let mut done = u32::try_from(self.frames)
            .unwrap_or(u32::MAX)
            .min(frames - 1);
        let mut batch = 1;
        while done + 1 < frames {
            if !progress(self, done, frames) {
                return Ok(None);
            }
            let n = batch.min(frames - 1 - done);
            let t = Instant::now();
            self.run_frames(n, false)?;
            done += n;
            if t.elapsed() < std::time::Duration::from_millis(200) {
                batch = (batch * 2).min(256);
            }
        }
        if !progress(self, done, frames) {
            return Ok(None);
        }
        let report = self.run_frames(1, true)?;
        progress(self, frames, frames);
        Ok(Some(report))
    }

    /// Where the render stands: the frames run and every node's history (read back).
    ///
    /// # Errors
    /// When a readback fails; the error names the node.
    pub fn checkpoint(&mut self, key: u64) -> Result<crate::Checkpoint> {
        let mut nodes = Vec::new();
        for (pass, node) in self.plan.passes.iter().zip(&mut self.nodes) {
            if let Some(history) = node.history() {
                let state = history
                    .save_state(&self.ctx)
                    .map_err(|e| e.in_node(&pass.node))?;
                nodes.push((pass.node.clone(), state));
            }
        }
        Ok(crate::Checkpoint {
            key,
            version: env!("CARGO_PKG_VERSION").to_owned(),
            adapter: self.ctx.info.name.clone(),
            frames: self.frames,
            nodes,
        })
    }

    /// Goes on from `checkpoint`: every node's history and the frame count as they were,
    /// so the next frames are those an uninterrupted render would run next. Check the
    /// checkpoint's key first ([`crate::Checkpoint::check`]).
    ///
    /// # Errors
    /// When a node that keeps history has no state in it, or the states do not fit (other
    /// image sizes); the error names the node.
    pub fn restore(&mut self, checkpoint: &crate::Checkpoint) -> Result<()> {
        let mut used = 0;
        for (pass, node) in self.plan.passes.iter().zip(&mut self.nodes) {
            let saved = checkpoint.nodes.iter().find(|(id, _)| *id == pass.node);
            match (saved, node.history()) {
                (Some((_, state)), Some(history)) => {
                    history
                        .load_state(&self.ctx, pass, state)
                        .map_err(|e| e.in_node(&pass.node))?;
                    used += 1;
                }
                (None, Some(_)) => {
                    return Err(RenderError::Gpu(
                        "the checkpoint has no state for this node".into(),
                    )
                    .in_node(&pass.node));
                }
                (Some(_), None) => {
                    return Err(RenderError::Gpu(
                        "the checkpoint has a state for this node, which keeps none".into(),
                    )
                    .in_node(&pass.node));
                }
                (None, None) => {}
            }
        }
        if used != checkpoint.nodes.len() {
            return Err(RenderError::Gpu(format!(
                "the checkpoint has states for {} nodes this graph does not run",
                checkpoint.nodes.len() - used
            )));
        }
        self.frames = checkpoint.frames;
        Ok(())
    }

    /// Starts a partial render of the samples from `first` on: history cleared, each pixel's
    /// sample sequence starting at index `first`, and `frames` counted as run (those that
    /// take the samples before `first`), so [`Executor::render`] and the checkpoints go on
    /// as in a render that took them. See [`crate::partial`].
    pub fn start_at_sample(&mut self, first: u32, frames: u64) {
        self.reset_history();
        for history in self.nodes.iter_mut().filter_map(|n| n.history()) {
            history.start_at_sample(first, frames);
        }
        self.frames = frames;
    }

    /// The history of one render of every sample range the checkpoints `parts` (of
    /// partial renders of this plan, in sample order) hold: each node's states merged
    /// ([`crate::nodes::History::merge_states`]). Its frames are the last part's; restore it
    /// ([`Executor::restore`]) and [`Executor::present`] it.
    ///
    /// # Errors
    /// When a part lacks a node's state or the states do not fit together; the error names
    /// the node.
    pub fn merge(&mut self, parts: &[crate::Checkpoint]) -> Result<crate::Checkpoint> {
        let first = parts
            .first()
            .ok_or_else(|| RenderError::Gpu("nothing to merge".into()))?;
        let mut nodes = Vec::new();
        for (pass, node) in self.plan.passes.iter().zip(&mut self.nodes) {
            let states: Vec<&[u8]> = parts
                .iter()
                .filter_map(|c| c.nodes.iter().find(|(id, _)| *id == pass.node))
                .map(|(_, state)| state.as_slice())
                .collect();
            if states.is_empty() {
                continue;
            }
            if states.len() != parts.len() {
                return Err(RenderError::Gpu(format!(
                    "{} of the {} partial renders have no state for this node",
                    parts.len() - states.len(),
                    parts.len()
                ))
                .in_node(&pass.node));
            }
            let merged = node
                .history()
                .ok_or_else(|| {
                    RenderError::Gpu(
                        "this node keeps no history to merge from partial renders".into(),
                    )
                })
                .and_then(|h| h.merge_states(&states))
                .map_err(|e| e.in_node(&pass.node))?;
            nodes.push((pass.node.clone(), merged));
        }
        Ok(crate::Checkpoint {
            key: first.key,
            version: first.version.clone(),
            adapter: first.adapter.clone(),
            frames: parts.iter().map(|c| c.frames).max().unwrap_or(0),
            nodes,
        })
    }

    /// Runs the whole graph once over the history as it stands (after a
    /// [`Executor::restore`]), adding nothing to it: nodes with history write what the frame
    /// that added their last sample wrote ([`crate::nodes::History::set_present`]), the rest of the
    /// graph runs on that, and sinks write their files. A merge of partial renders ends
    /// with it.
    ///
    /// # Errors
    /// When a node fails (one with no history to present among them); the error names the
    /// node.
    pub fn present(&mut self) -> Result<FrameReport> {
        for history in self.nodes.iter_mut().filter_map(|n| n.history()) {
            history.set_present(&self.ctx, true);
        }
        let report = self.run(1, Mode::Present);
        for history in self.nodes.iter_mut().filter_map(|n| n.history()) {
            history.set_present(&self.ctx, false);
        }
        report
    }

    /// Records every pass once without writing files or keeping history, so drivers that
    /// compile pipelines at their first dispatch do it here rather than in a timed frame.
    ///
    /// # Errors
    /// When a node fails; the error names the node.
    pub fn warm_up(&mut self) -> Result<()> {
        // One sample per pixel: the frame dispatches every pipeline as a whole frame does,
        // and is thrown away, so its other samples would only delay the first frame kept
        // (on a CPU adapter most of the warm-up was tracing them).
        let full = self.plan.clone();
        let mut one = full.clone();
        for p in &mut one.passes {
            if p.params.has(SAMPLES_PER_FRAME) {
                p.params
                    .0
                    .insert(SAMPLES_PER_FRAME.to_owned(), ParamValue::Int(1));
            }
        }
        self.update_params(one)?;
        let run = self.run(1, Mode::WarmUp);
        self.update_params(full)?;
        run?;
        self.reset_history();
        self.counters()?;
        self.reset_history();
        self.frames = 0;
        Ok(())
    }

    fn run(&mut self, n: u32, mode: Mode) -> Result<FrameReport> {
        let start = Instant::now();
        let mut encoder = new_encoder(&self.ctx);
        if let Some(t) = &mut self.timer {
            t.begin_frame();
        }
        let io = FrameIo {
            plan: &self.plan,
            slots: &self.slots,
        };
        let mut executed = Vec::with_capacity(self.plan.passes.len());
        let timed = matches!(mode, Mode::Finish | Mode::Tail | Mode::Only | Mode::Present);
        let mut wall_ms: Vec<(String, f64)> = Vec::new();
        let n = n.max(1);
        for frame in 0..n {
            let last = mode != Mode::Progress && frame + 1 == n;
            for (p, (pass, node)) in self.plan.passes.iter().zip(&mut self.nodes).enumerate() {
                if (!last && !self.every_frame[p])
                    || (mode == Mode::Tail && self.every_frame[p])
                    || (mode == Mode::Only && !self.only[p])
                {
                    continue;
                }
                let timer = if last && timed {
                    self.timer.as_mut()
                } else {
                    None
                };
                if last && timed && self.wall_clock {
                    // Everything before this pass finishes first; then the pass alone.
                    let before = std::mem::replace(&mut encoder, new_encoder(&self.ctx));
                    submit_and_wait(&self.ctx, before)?;
                    let t = Instant::now();
                    if let Some(own) = node.own_work().filter(|o| o.submits_own()) {
                        own.submit_own(&self.ctx, pass, &io)
                            .map_err(|e| e.in_node(&pass.node))?;
                    }
                    let rec = Recording {
                        ctx: &self.ctx,
                        encoder: &mut encoder,
                        io: &io,
                        timer: None,
                    };
                    node.record(pass, rec).map_err(|e| e.in_node(&pass.node))?;
                    let this = std::mem::replace(&mut encoder, new_encoder(&self.ctx));
                    submit_and_wait(&self.ctx, this).map_err(|e| e.in_node(&pass.node))?;
                    let ms = t.elapsed().as_secs_f64() * 1e3;
                    match wall_ms.iter_mut().find(|(l, _)| *l == pass.node) {
                        Some((_, total)) => *total += ms,
                        None => wall_ms.push((pass.node.clone(), ms)),
                    }
                } else {
                    if let Some(own) = node.own_work().filter(|o| o.submits_own()) {
                        // What the graph recorded so far runs before the node's own work.
                        let before = std::mem::replace(&mut encoder, new_encoder(&self.ctx));
                        self.ctx.queue.submit([before.finish()]);
                        own.submit_own(&self.ctx, pass, &io)
                            .map_err(|e| e.in_node(&pass.node))?;
                    }
                    let rec = Recording {
                        ctx: &self.ctx,
                        encoder: &mut encoder,
                        io: &io,
                        timer,
                    };
                    node.record(pass, rec).map_err(|e| e.in_node(&pass.node))?;
                }
                if last {
                    executed.push(pass.node.clone());
                }
            }
        }
        if let Some(t) = &self.timer {
            t.resolve(&mut encoder);
        }
        submit_and_wait(&self.ctx, encoder)?;
        let mut written = Vec::new();
        if timed {
            for (p, (pass, node)) in self.plan.passes.iter().zip(&mut self.nodes).enumerate() {
                if (mode == Mode::Only && !self.only[p]) || (self.hold_sinks && pass.kind.sink) {
                    continue;
                }
                written.extend(
                    node.finish(&self.ctx, pass)
                        .map_err(|e| e.in_node(&pass.node))?,
                );
            }
        }
        let pass_ms = match &self.timer {
            _ if timed && self.wall_clock => Some(wall_ms),
            Some(t) if timed => Some(t.read(&self.ctx)?),
            _ => None,
        };
        if !matches!(mode, Mode::Tail | Mode::Only | Mode::Present) {
            self.frames += u64::from(n);
        }
        Ok(FrameReport {
            pass_ms,
            pass_clock: if self.wall_clock {
                PassClock::Wall
            } else {
                PassClock::Timestamps
            },
            wall: start.elapsed(),
            written,
            executed,
        })
    }

    /// How each node was set up, as `(node id, line)`.
    pub fn notes(&self) -> Vec<(String, String)> {
        self.plan
            .passes
            .iter()
            .zip(&self.nodes)
            .flat_map(|(pass, node)| node.notes().into_iter().map(|n| (pass.node.clone(), n)))
            .collect()
    }

    /// The GPU side of node `id` (the crate that defines its kind reaches its state through
    /// [`AsAny`](crate::AsAny)).
    pub fn node(&self, id: &str) -> Option<&dyn NodeExec> {
        self.plan
            .passes
            .iter()
            .zip(&self.nodes)
            .find(|(pass, _)| pass.node == id)
            .map(|(_, node)| node.as_ref())
    }

    /// Every node's counters since its last reset, as `(node id, counter)`.
    ///
    /// # Errors
    /// When a readback fails.
    pub fn counters(&mut self) -> Result<Vec<(String, Counter)>> {
        let mut out = Vec::new();
        for (pass, node) in self.plan.passes.iter().zip(&mut self.nodes) {
            for c in node
                .counters(&self.ctx)
                .map_err(|e| e.in_node(&pass.node))?
            {
                out.push((pass.node.clone(), c));
            }
        }
        Ok(out)
    }

    /// What every node measured on the last frame it ran, as `(node id, measurement)`.
    ///
    /// # Errors
    /// When a readback fails.
    pub fn measurements(&mut self) -> Result<Vec<(String, Measurement)>> {
        let mut out = Vec::new();
        for (pass, node) in self.plan.passes.iter().zip(&mut self.nodes) {
            for m in node
                .measurements(&self.ctx)
                .map_err(|e| e.in_node(&pass.node))?
            {
                out.push((pass.node.clone(), m));
            }
        }
        Ok(out)
    }

    /// Reads back the current contents of a planned texture (after a frame).
    ///
    /// # Errors
    /// When the GPU does not finish.
    pub fn read(&self, id: TextureId) -> Result<Image> {
        let desc = &self.plan.textures[id.0];
        let texture = &self.slots[desc.slot];
        let bytes =
            crate::readback::read_texture(&self.ctx, &texture.texture, desc.format, desc.extent)?;
        Ok(crate::readback::to_image(&bytes, desc.format, desc.extent))
    }

    /// The images the sinks would have written in the last finishing frame, as `(pass
    /// index, image)` ([`Executor::hold_sinks`]).
    ///
    /// # Errors
    /// When a readback fails; the error names the node.
    pub fn held_images(&mut self) -> Result<Vec<(usize, crate::nodes::HeldImage)>> {
        let mut out = Vec::new();
        for (p, (pass, node)) in self.plan.passes.iter().zip(&mut self.nodes).enumerate() {
            let Some(sink) = node.sink() else {
                continue;
            };
            if let Some(image) = sink
                .held_image(&self.ctx)
                .map_err(|e| e.in_node(&pass.node))?
            {
                out.push((p, image));
            }
        }
        Ok(out)
    }

    /// Reads back the current contents of a planned texture as stored: rows of
    /// `extent.width × format.bytes_per_pixel()` bytes, no padding.
    ///
    /// # Errors
    /// When the GPU does not finish.
    pub fn read_raw(&self, id: TextureId) -> Result<Vec<u8>> {
        let desc = &self.plan.textures[id.0];
        let texture = &self.slots[desc.slot];
        crate::readback::read_texture(&self.ctx, &texture.texture, desc.format, desc.extent)
    }

    /// Reads back the texture on output `"node.port"`, which must be kept alive by the plan
    /// (see [`lumagraph_graph::CompileOptions::keep`]) or be read by a later pass.
    ///
    /// # Errors
    /// When there is no such planned texture.
    pub fn read_port(&self, port: &str) -> Result<Image> {
        let t = self
            .plan
            .texture_named(port)
            .ok_or_else(|| RenderError::Gpu(format!("no planned texture for {port}")))?;
        self.read(t.id)
    }
}

/// For each pass, whether it is a node with history or feeds one.
fn every_frame(plan: &Plan) -> Vec<bool> {
    let mut flags: Vec<bool> = plan.passes.iter().map(|p| p.kind.history).collect();
    // Walk backwards: a pass runs every frame if a later pass that does reads its output.
    for i in (0..plan.passes.len()).rev() {
        if !flags[i] {
            continue;
        }
        for (_, t) in &plan.passes[i].inputs {
            flags[plan.textures[t.0].first] = true;
        }
    }
    flags
}

/// Whether two plans run the same passes on the same textures (params aside).
fn same_structure(a: &Plan, b: &Plan) -> bool {
    let passes = a.working_space == b.working_space
        && a.passes.len() == b.passes.len()
        && a.passes.iter().zip(&b.passes).all(|(p, q)| {
            p.node == q.node
                && p.kind.name == q.kind.name
                // A kind declared in a file whose WGSL changed needs its pipeline again.
                && p.kind.shader == q.kind.shader
                && p.inputs == q.inputs
                && p.outputs == q.outputs
                && p.extent == q.extent
        });
    let textures = a.textures.len() == b.textures.len()
        && a.textures.iter().zip(&b.textures).all(|(s, t)| {
            s.name == t.name
                && s.ty == t.ty
                && s.format == t.format
                && s.extent == t.extent
                && s.first == t.first
                && s.last == t.last
                && s.slot == t.slot
        });
    let slots = a.slots.len() == b.slots.len()
        && a.slots
            .iter()
            .zip(&b.slots)
            .all(|(s, t)| s.format == t.format && s.extent == t.extent && s.textures == t.textures);
    passes && textures && slots
}

fn new_encoder(ctx: &GpuContext) -> wgpu::CommandEncoder {
    ctx.device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("frame"),
        })
}

/// Checks the plan's images (and so the nodes' own images of the same sizes) against the
/// device's limits, before anything is allocated.
fn check_limits(ctx: &GpuContext, plan: &Plan) -> Result<()> {
    for t in &plan.textures {
        ctx.check_extent(&t.name, t.extent.width, t.extent.height)?;
    }
    Ok(())
}

/// Submits `encoder`, turning validation errors into [`RenderError::Gpu`], and waits for
/// the queue.
fn submit_and_wait(ctx: &GpuContext, encoder: wgpu::CommandEncoder) -> Result<()> {
    let scope = ctx.device.push_error_scope(wgpu::ErrorFilter::Validation);
    ctx.queue.submit([encoder.finish()]);
    if let Some(e) = pollster::block_on(scope.pop()) {
        return Err(ctx.error(e));
    }
    ctx.wait()
}
