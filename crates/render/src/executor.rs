//! Executes a plan: one command encoder per frame, every pass recorded in plan order,
//! one submission, then the sinks write their files.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use lumagraph_graph::{
    CompileOptions, Extent, Graph, GraphErrors, Node, Params, Plan, Registry, TextureId,
};

use crate::context::GpuContext;
use crate::cpu::Image;
use crate::error::{RenderError, Result};
use crate::nodes::{self, FrameIo, NodeExec, Paths};
use crate::pool::{PooledTexture, TexturePool};
use crate::timing::GpuTimer;

/// The image size each source kind produces; used by [`compile`].
///
/// # Errors
/// A message naming the file when a source cannot tell its size.
pub fn source_extent(
    base_dir: &Path,
    node: &Node,
    params: &Params,
) -> std::result::Result<Extent, String> {
    match node.kind.as_str() {
        "ImageInput" => crate::image_io::dimensions(&base_dir.join(params.str("path")))
            .map_err(|e| e.to_string()),
        other => Err(format!("{other} is not a source")),
    }
}

/// Compiles `graph` with the built-in registry, sizing sources from their files.
///
/// # Errors
/// Every problem found in the graph.
pub fn compile(graph: &Graph, keep: &[String]) -> std::result::Result<Plan, GraphErrors> {
    let base = graph.base_dir();
    let extent = |node: &Node, params: &Params| source_extent(&base, node, params);
    lumagraph_graph::compile(
        graph,
        Registry::builtin(),
        &CompileOptions {
            source_extent: &extent,
            keep,
        },
    )
}

/// What one frame did.
#[derive(Clone, Debug, Default)]
pub struct FrameReport {
    /// GPU milliseconds per pass, when the adapter has timestamp queries.
    pub pass_ms: Option<Vec<(String, f64)>>,
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
    frames: u64,
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
    /// Creates every pass's GPU resources and the plan's textures.
    ///
    /// # Errors
    /// When a node cannot be set up (missing input file, unwritable output, shader error);
    /// the error names the node.
    pub fn new(ctx: &GpuContext, plan: Plan, paths: &Paths) -> Result<Self> {
        let nodes = plan
            .passes
            .iter()
            .map(|pass| nodes::create(ctx, pass, paths))
            .collect::<Result<Vec<_>>>()?;
        let mut pool = TexturePool::new();
        let slots = pool.acquire(ctx, &plan);
        // Two timestamps per pass; nodes with several passes get room too.
        let capacity = u32::try_from(plan.passes.len() * 8)
            .unwrap_or(u32::MAX)
            .max(8);
        let timer = GpuTimer::new(ctx, capacity);
        Ok(Self {
            ctx: ctx.clone(),
            plan,
            nodes,
            slots,
            pool,
            timer,
            frames: 0,
        })
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
        let start = Instant::now();
        let mut encoder = self
            .ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("frame"),
            });
        if let Some(t) = &mut self.timer {
            t.begin_frame();
        }
        let io = FrameIo {
            plan: &self.plan,
            slots: &self.slots,
        };
        let mut executed = Vec::with_capacity(self.plan.passes.len());
        for (pass, node) in self.plan.passes.iter().zip(&mut self.nodes) {
            node.record(&self.ctx, &mut encoder, pass, &io, self.timer.as_mut())
                .map_err(|e| e.in_node(&pass.node))?;
            executed.push(pass.node.clone());
        }
        if let Some(t) = &self.timer {
            t.resolve(&mut encoder);
        }
        let scope = self
            .ctx
            .device
            .push_error_scope(wgpu::ErrorFilter::Validation);
        self.ctx.queue.submit([encoder.finish()]);
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(RenderError::Gpu(e.to_string()));
        }
        self.ctx.wait()?;
        let mut written = Vec::new();
        for (pass, node) in self.plan.passes.iter().zip(&mut self.nodes) {
            written.extend(
                node.finish(&self.ctx, pass)
                    .map_err(|e| e.in_node(&pass.node))?,
            );
        }
        let pass_ms = match &self.timer {
            Some(t) => Some(t.read(&self.ctx)?),
            None => None,
        };
        self.frames += 1;
        Ok(FrameReport {
            pass_ms,
            wall: start.elapsed(),
            written,
            executed,
        })
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

    /// Reads back the texture on output `"node.port"`, which must be kept alive by the plan
    /// (see [`lumagraph_graph::CompileOptions::keep`]) or be read by a later pass.
    ///
    /// # Errors
    /// When there is no such planned texture.
    pub fn read_port(&self, port: &str) -> Result<Image> {
        let t = self
            .plan
            .textures
            .iter()
            .find(|t| t.name == port)
            .ok_or_else(|| RenderError::Gpu(format!("no planned texture for {port}")))?;
        self.read(t.id)
    }
}

/// Whether two plans run the same passes on the same textures (params aside).
fn same_structure(a: &Plan, b: &Plan) -> bool {
    let passes = a.passes.len() == b.passes.len()
        && a.passes.iter().zip(&b.passes).all(|(p, q)| {
            p.node == q.node
                && p.kind == q.kind
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
