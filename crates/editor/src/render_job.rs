//! Render to file: the graph at the scene's full resolution and a target sample count, on
//! a thread of its own so the editor keeps running, with progress and cancel.
//!
//! The render is what `lumagraph render` does with the same graph, scene and `--spp`: a
//! [`Session`] over the editor's device renders the same frames in the same order. Either
//! every `Output` node of the graph writes its file into a folder, or one port is written
//! to one file.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, PoisonError};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use lumagraph_graph::{Edge, Graph, Node, ParamValue, Registry};
use lumagraph_render::{Executor, GpuContext, NodeLibrary, Resources};
use lumagraph_scene::GpuScene;
use lumagraph_session::Session;

/// What a render writes.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Target {
    /// Every `Output` node's file, relative to this folder (as `lumagraph render --out`).
    Outputs(PathBuf),
    /// One port (`"node.port"`) to one file (`.png` or `.exr`); the graph's own `Output`
    /// nodes write nothing.
    Port {
        /// The port.
        port: String,
        /// The file.
        file: PathBuf,
    },
}

/// A render to start.
#[derive(Clone, Debug)]
pub struct RenderRequest {
    /// The graph (groups included; `registry` knows them).
    pub graph: Graph,
    /// Its kinds.
    pub registry: Registry,
    /// The folder its input paths are relative to.
    pub base: PathBuf,
    /// The scene at full resolution, when the graph renders one.
    pub scene: Option<Arc<GpuScene>>,
    /// Samples per pixel.
    pub spp: u32,
    /// What to write.
    pub target: Target,
}

/// Where a render stands.
#[derive(Clone, Debug, Default)]
pub struct Progress {
    /// What it does now (`compiling shaders`, `rendering`, `done`, …).
    pub stage: &'static str,
    /// Frames run.
    pub done: u32,
    /// Frames in all.
    pub frames: u32,
    /// Samples per pixel asked for.
    pub spp: u32,
    /// Time since the start (frozen when it ends).
    pub elapsed: Duration,
    /// The files it writes (each Output path resolved in the folder), once compiled.
    pub files: Vec<PathBuf>,
    /// How it ended: the files written, or why not.
    pub finished: Option<Result<Vec<PathBuf>, String>>,
}

impl Progress {
    /// The fraction done, in [0, 1].
    pub fn fraction(&self) -> f32 {
        if self.frames == 0 {
            0.0
        } else {
            self.done as f32 / self.frames as f32
        }
    }
}

/// A render running on its own thread.
#[derive(Debug)]
pub struct RenderJob {
    state: Arc<Mutex<Progress>>,
    cancel: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl RenderJob {
    /// Starts `request` on `gpu` (the editor's device: the preview keeps running beside
    /// it).
    pub fn start(gpu: GpuContext, library: Arc<NodeLibrary>, request: RenderRequest) -> Self {
        let state = Arc::new(Mutex::new(Progress {
            stage: "compiling",
            spp: request.spp,
            ..Progress::default()
        }));
        let cancel = Arc::new(AtomicBool::new(false));
        let thread = {
            let (state, cancel) = (Arc::clone(&state), Arc::clone(&cancel));
            std::thread::Builder::new()
                .name("render to file".into())
                .spawn(move || {
                    let start = Instant::now();
                    let set = |f: &dyn Fn(&mut Progress)| {
                        let mut s = state.lock().unwrap_or_else(PoisonError::into_inner);
                        f(&mut s);
                        s.elapsed = start.elapsed();
                    };
                    let result = run(&gpu, &library, request, &cancel, &set);
                    set(&|s| {
                        s.stage = if result.is_ok() { "done" } else { "stopped" };
                        s.finished = Some(result.clone());
                    });
                })
                .ok()
        };
        if thread.is_none() {
            let mut s = state.lock().unwrap_or_else(PoisonError::into_inner);
            s.finished = Some(Err("cannot start a thread for the render".into()));
        }
        Self {
            state,
            cancel,
            thread,
        }
    }

    /// Where it stands.
    pub fn progress(&self) -> Progress {
        self.state
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .clone()
    }

    /// Asks it to stop at the next batch of frames (nothing is written).
    pub fn cancel(&self) {
        self.cancel.store(true, Ordering::Relaxed);
    }

    /// Whether it ended (done, failed or cancelled).
    pub fn is_finished(&self) -> bool {
        self.progress().finished.is_some()
    }

    /// Waits until it ends, at most `timeout`; returns whether it ended.
    pub fn wait(&self, timeout: Duration) -> bool {
        let start = Instant::now();
        while !self.is_finished() {
            if start.elapsed() > timeout {
                return false;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        true
    }
}

impl Drop for RenderJob {
    fn drop(&mut self) {
        self.cancel();
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// Applies a change to the shared progress.
type Update<'a> = dyn Fn(&dyn Fn(&mut Progress)) + 'a;

/// The id of the `Output` node a port render adds.
const PORT_OUTPUT: &str = "render_to_file";

fn run(
    gpu: &GpuContext,
    library: &Arc<NodeLibrary>,
    request: RenderRequest,
    cancel: &AtomicBool,
    set: &Update<'_>,
) -> Result<Vec<PathBuf>, String> {
    let RenderRequest {
        mut graph,
        registry,
        base,
        scene,
        spp,
        target,
    } = request;
    let out_dir = match &target {
        Target::Outputs(dir) => {
            std::fs::create_dir_all(dir)
                .map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
            dir.clone()
        }
        Target::Port { port, file } => {
            // The file the user chose: its folder is the output folder.
            let name = file
                .file_name()
                .ok_or_else(|| format!("{} names no file", file.display()))?;
            graph.remove_sinks(&registry);
            let mut out = Node::new(PORT_OUTPUT, "Output");
            out.params.insert(
                "path".into(),
                ParamValue::Str(name.to_string_lossy().into_owned()),
            );
            graph.nodes.push(out);
            graph
                .edges
                .push(Edge::new(port.clone(), format!("{PORT_OUTPUT}.color")));
            file.parent().map_or_else(|| base.clone(), PathBuf::from)
        }
    };
    let plan = library
        .compile_with(&graph, &registry, &base, &[], scene.as_deref())
        .map_err(|e| e.to_string())?;
    if !plan.passes.iter().any(|p| p.kind.sink) {
        return Err("the graph has no Output node: nothing to write".into());
    }
    // The graph's Output paths stay in the folder, as `lumagraph render` keeps them; the
    // files are shown before anything is written.
    let files = lumagraph_graph::outputs::output_files(&plan, &graph, &out_dir, false)
        .map_err(|e| e.to_string())?;
    set(&|s| s.files = files.iter().map(|f| f.path.clone()).collect());
    let resources = Resources {
        base_dir: base,
        out_dir,
        scene: scene.clone(),
        ..Resources::default()
    };
    let exec = Executor::with_library(gpu, plan, &resources, library).map_err(|e| e.to_string())?;
    let mut session = Session::from_executor(exec, graph, scene, resources, Arc::clone(library));
    let frames = session.frames_for(spp);
    set(&|s| {
        s.stage = "compiling shaders";
        s.frames = frames;
    });
    session.warm_up().map_err(|e| e.to_string())?;
    set(&|s| s.stage = "rendering");
    let report = session
        .render_with(spp, |_, done, _| {
            set(&|s| s.done = done);
            !cancel.load(Ordering::Relaxed)
        })
        .map_err(|e| format!("{e:#}"))?;
    match report {
        Some(r) => Ok(r.written),
        None => Err("cancelled: nothing written".into()),
    }
}
