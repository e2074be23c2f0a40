//! A render session: a graph, its scene and a device, rendered progressively and read back
//! as images, from a program rather than the command line. It renders what
//! `lumagraph render` renders (the same frames in the same order, so the same files, byte
//! for byte), and then goes on: more samples, another param (re-running only what is
//! downstream of it), a checkpoint.
//!
//! ```no_run
//! use lumagraph::session::{Session, SessionOptions};
//! let mut s = Session::open("graphs/pathtrace.ron".as_ref(), Some("assets/cornell.ron".as_ref()),
//!     SessionOptions::default())?;
//! s.render(64)?;
//! let hdr = s.read("accumulate.color")?;
//! s.set_param("exposure.ev", "1.5")?; // re-runs exposure, tonemap and the outputs only
//! # anyhow::Ok(())
//! ```

use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{Context as _, Result};

use crate::graph::Graph;
use crate::render::cpu::Image;
use crate::render::{Executor, FrameReport, GpuContext, NodeLibrary, Resources};
use crate::scene::{GpuScene, Scene};

/// How a [`Session`] is set up.
#[derive(Clone, Debug)]
pub struct SessionOptions {
    /// Where `Output` nodes write their files (relative paths in the graph are under it).
    pub out: PathBuf,
    /// Whether `Output` nodes write their files when a render finishes.
    pub write_outputs: bool,
    /// Output ports (`"node.port"`) kept readable with [`Session::read`] besides those a
    /// later pass reads anyway.
    pub keep: Vec<String>,
    /// The node kinds: the built-in ones unless given.
    pub library: Option<Arc<NodeLibrary>>,
}

impl Default for SessionOptions {
    fn default() -> Self {
        Self {
            out: PathBuf::from("out"),
            write_outputs: false,
            keep: Vec::new(),
            library: None,
        }
    }
}

/// A graph and its scene on a device, rendered progressively.
pub struct Session {
    graph: Graph,
    library: Arc<NodeLibrary>,
    scene: Option<Arc<GpuScene>>,
    keep: Vec<String>,
    resources: Resources,
    write_outputs: bool,
    exec: Executor,
    /// What the last run reported (its passes' times).
    last: Option<FrameReport>,
    /// What loading the scene warned of.
    warnings: Vec<String>,
}

impl Session {
    /// Loads the graph file `graph` and the scene file `scene` (where the graph renders
    /// one) and sets them up on the default adapter.
    ///
    /// # Errors
    /// When a file does not load (the error names the file and line), the graph does not
    /// compile (it names the node), or no adapter is found.
    pub fn open(graph: &Path, scene: Option<&Path>, options: SessionOptions) -> Result<Self> {
        Self::open_graph(Graph::load(graph)?, scene, options)
    }

    /// [`Session::open`] for a graph already loaded or built in code.
    ///
    /// # Errors
    /// As [`Session::open`].
    pub fn open_graph(graph: Graph, scene: Option<&Path>, options: SessionOptions) -> Result<Self> {
        let mut warnings = Vec::new();
        let scene = scene
            .map(|path| -> Result<Arc<GpuScene>> {
                let scene = Scene::load(path)?;
                warnings = scene.report.lines();
                for w in &warnings {
                    eprintln!("scene warning: {w}");
                }
                Ok(Arc::new(GpuScene::build(&scene)?))
            })
            .transpose()?;
        let mut session = Self::with(graph, scene, options)?;
        session.warnings = warnings;
        Ok(session)
    }

    /// A session of `graph` (loaded or built in code) and `scene` (flattened).
    ///
    /// # Errors
    /// When the graph does not compile or no adapter is found.
    pub fn with(
        graph: Graph,
        scene: Option<Arc<GpuScene>>,
        options: SessionOptions,
    ) -> Result<Self> {
        let library = options
            .library
            .unwrap_or_else(|| Arc::new(NodeLibrary::with_builtins()));
        let plan = library.compile(&graph, &options.keep, scene.as_deref())?;
        let ctx = GpuContext::headless()?;
        let resources = Resources {
            base_dir: graph.base_dir(),
            out_dir: options.out,
            scene: scene.clone(),
            ..Resources::default()
        };
        let mut exec = Executor::with_library(&ctx, plan, &resources, &library)?;
        exec.hold_sinks(!options.write_outputs);
        exec.warm_up()?;
        Ok(Self {
            graph,
            library,
            scene,
            keep: options.keep,
            resources,
            write_outputs: options.write_outputs,
            exec,
            last: None,
            warnings: Vec::new(),
        })
    }

    /// Renders on to `spp` samples per pixel in all (whole frames of the path tracer's
    /// `samples_per_frame`), then runs the rest of the graph once; `Output` nodes write
    /// their files where the options say so.
    ///
    /// # Errors
    /// When a node fails; the error names the node.
    pub fn render(&mut self, spp: u32) -> Result<FrameReport> {
        self.render_with(spp, |_, _| true)?
            .context("the render stopped")
    }

    /// [`Session::render`], calling `progress(frames done, frames in all)` a few times a
    /// second; where it returns `false` the render stops there (`Ok(None)`, nothing
    /// finished or written), and a later `render` goes on from the frames done.
    ///
    /// # Errors
    /// When a node fails; the error names the node.
    pub fn render_with(
        &mut self,
        spp: u32,
        mut progress: impl FnMut(u32, u32) -> bool,
    ) -> Result<Option<FrameReport>> {
        let frames = self.exec.frames_for(spp);
        let Some(report) = self
            .exec
            .render(frames, |_, done, all| progress(done, all))?
        else {
            return Ok(None);
        };
        self.last = Some(report.clone());
        Ok(Some(report))
    }

    /// Milliseconds per pass (summed by node) in the last run's timed frame, as the
    /// command line prints them; `None` before a run or where the adapter cannot time
    /// passes.
    pub fn timings(&self) -> Option<&[(String, f64)]> {
        self.last.as_ref()?.pass_ms.as_deref()
    }

    /// What the graph's nodes measured in the last run (`Difference`'s relMSE, auto
    /// exposure's EV, the path tracer's paths and rays): `(node, name, value)`.
    ///
    /// # Errors
    /// When a readback fails.
    pub fn measurements(&mut self) -> Result<Vec<(String, String, f64)>> {
        Ok(self
            .exec
            .measurements()?
            .into_iter()
            .map(|(node, m)| (node, m.name.to_owned(), m.value))
            .collect())
    }

    /// The samples per pixel accumulated so far: the frames run since the accumulation
    /// (re)started times the path tracer's `samples_per_frame` (a render asked for fewer
    /// than that is already past them, and a stopped one has the frames it ran).
    pub fn spp(&self) -> u64 {
        self.exec.frames() * u64::from(self.exec.samples_per_frame())
    }

    /// What loading the scene warned of (dropped triangles, what the scene's files hold
    /// that lumagraph does not use), one line each; also printed to standard error as
    /// `scene warning: …` when the session opens.
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    /// The image on output `"node.port"` as the last frame left it: a port another pass
    /// reads, or one kept ([`SessionOptions::keep`]).
    ///
    /// # Errors
    /// When the plan has no such texture.
    pub fn read(&self, port: &str) -> Result<Image> {
        Ok(self.exec.read_port(port)?)
    }

    /// Sets param `target` (`"node.param"`) to `value` (as `--set` takes it) and re-runs
    /// the passes it changes: only the node and what is downstream of it, over the
    /// accumulation as it is, or a restarted accumulation where the node is progressive
    /// ([`Executor::rerun`]; [`FrameReport::executed`] names the passes that ran).
    ///
    /// # Errors
    /// When there is no such node or param, or the value does not fit it.
    pub fn set_param(&mut self, target: &str, value: &str) -> Result<FrameReport> {
        let node = target
            .split_once('.')
            .map(|(node, _)| node.to_owned())
            .with_context(|| format!("{target}: give node.param"))?;
        let mut graph = self.graph.clone();
        graph.apply_override(&format!("{target}={value}"))?;
        let plan = self
            .library
            .compile(&graph, &self.keep, self.scene.as_deref())?;
        self.graph = graph;
        if self.exec.update_params(plan.clone())? {
            let report = self.exec.rerun(&[node])?;
            self.last = Some(report.clone());
            return Ok(report);
        }
        // Another structure: a new executor, rendered again to the samples so far.
        let spp = self.spp();
        let ctx = self.exec.context().clone();
        self.exec = Executor::with_library(&ctx, plan, &self.resources, &self.library)?;
        self.exec.hold_sinks(!self.write_outputs);
        self.exec.warm_up()?;
        let spp = u32::try_from(spp).unwrap_or(u32::MAX);
        self.render(spp.max(1))
    }

    /// Each sink (`Output` node) of the plan and the port whose image it writes
    /// (`"node.port"`, readable with [`Session::read`]).
    pub fn outputs(&mut self) -> Vec<(String, String)> {
        let plan = self.exec.plan();
        plan.passes
            .iter()
            .filter(|p| p.kind.sink)
            .filter_map(|p| {
                let (_, t) = p.inputs.first()?;
                Some((p.node.clone(), plan.texture(*t).name.clone()))
            })
            .collect()
    }

    /// The graph as it stands (with the params set since it was opened).
    pub fn graph(&self) -> &Graph {
        &self.graph
    }

    /// The executor, for what this API does not cover.
    pub fn executor(&mut self) -> &mut Executor {
        &mut self.exec
    }
}
