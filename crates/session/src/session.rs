//! A render session: a graph, its scene and a device, rendered progressively and read back
//! as images, from a program rather than the command line. It renders what
//! `lumagraph render` renders (the same frames in the same order, so the same files, byte
//! for byte), and then goes on: more samples, another param (re-running only what is
//! downstream of it), an edited scene (a moved camera, another material: the accumulation
//! restarts), a checkpoint to resume from.
//!
//! ```no_run
//! use lumagraph_session::{Session, SessionOptions};
//! let mut s = Session::open("graphs/pathtrace.ron".as_ref(), Some("assets/cornell.ron".as_ref()),
//!     SessionOptions::default())?;
//! s.render(64)?;
//! let hdr = s.read("accumulate.color")?;
//! s.set_param("exposure.ev", "1.5")?; // re-runs exposure, tonemap and the outputs only
//! # anyhow::Ok(())
//! ```

use lumagraph_pathtrace::{Tracer as _, Tracing};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{Context as _, Result};

use crate::frames::FrameParams;
use lumagraph_graph::Graph;
use lumagraph_render::cpu::Image;
use lumagraph_render::{Checkpoint, Executor, FrameReport, GpuContext, NodeLibrary, Resources};
use lumagraph_scene::GpuScene;
use lumagraph_scene::edit::SceneText;
use lumagraph_scene::file::SceneFile;
use lumagraph_scene::gpu::GpuCamera;

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
    /// For a graph whose params hold a frame pattern (`####`: [`crate::frames`]), the
    /// frame to open at; such a graph cannot be opened without one.
    pub frame: Option<i64>,
    /// Let `Output` paths be absolute or climb out of `out` (by default they are refused).
    pub outputs_anywhere: bool,
    /// The path tracer's intersector ([`Tracing`]'s; `AUTO`: the scene and
    /// the adapter decide).
    pub intersector: lumagraph_pathtrace::specialize::Intersector,
    /// The path tracer's schedule ([`Tracing`]'s).
    pub schedule: lumagraph_pathtrace::specialize::Schedule,
}

impl Default for SessionOptions {
    fn default() -> Self {
        Self {
            out: PathBuf::from("out"),
            write_outputs: false,
            keep: Vec::new(),
            library: None,
            frame: None,
            outputs_anywhere: false,
            intersector: lumagraph_pathtrace::specialize::Intersector::AUTO,
            schedule: lumagraph_pathtrace::specialize::Schedule::Auto,
        }
    }
}

/// A session's sequence: the graph as written (patterns and all), its frame-numbered
/// params, and the frame it is at.
struct Sequence {
    template: Graph,
    params: FrameParams,
    frame: i64,
}

/// A graph and its scene on a device, rendered progressively.
pub struct Session {
    graph: Graph,
    library: Arc<NodeLibrary>,
    scene: Option<Arc<GpuScene>>,
    /// The scene file's text and values as edited (none for a scene given flattened).
    scene_text: Option<SceneText>,
    /// Where [`Session::set_scene`] moved the camera to, the scene being otherwise the
    /// same (`scene` keeps the file's camera).
    camera: Option<GpuCamera>,
    keep: Vec<String>,
    resources: Resources,
    write_outputs: bool,
    exec: Executor,
    /// Whether the executor was warmed up ([`Session::warm_up`]).
    warm: bool,
    /// What the last run reported (its passes' times).
    last: Option<FrameReport>,
    /// What loading the scene warned of.
    warnings: Vec<String>,
    /// Where the graph holds frame patterns: the sequence and the frame it is at.
    sequence: Option<Sequence>,
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
        let scene = scene.map(SceneText::load).transpose()?;
        Self::open_scene(graph, scene, options)
    }

    /// [`Session::open`] for a graph and a scene file already loaded (and perhaps edited:
    /// [`lumagraph_scene::edit`]).
    ///
    /// # Errors
    /// As [`Session::open`].
    pub fn open_scene(
        graph: Graph,
        scene: Option<SceneText>,
        options: SessionOptions,
    ) -> Result<Self> {
        let (gpu, warnings) = match &scene {
            Some(text) => {
                let (gpu, warnings) = build_scene(text)?;
                (Some(gpu), warnings)
            }
            None => (None, Vec::new()),
        };
        let mut session = Self::with(graph, gpu, options)?;
        session.warnings = warnings;
        session.scene_text = scene;
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
            .unwrap_or_else(|| Arc::new(lumagraph_pathtrace::library::with_builtins()));
        let params = FrameParams::of(&graph, &library.registry_for(&graph)?);
        let (graph, sequence) = if params.is_empty() {
            (graph, None)
        } else {
            let frame = options.frame.with_context(|| {
                format!(
                    "the graph's params hold frame patterns ({}): open it at a frame",
                    params.describe()
                )
            })?;
            if let Some(missing) = params.missing_at(&graph, frame) {
                anyhow::bail!("frame {frame}: {} is missing", missing.display());
            }
            let at = params.at(&graph, frame);
            let sequence = Sequence {
                template: graph,
                params,
                frame,
            };
            (at, Some(sequence))
        };
        let plan = library.compile(&graph, &options.keep, scene.as_deref())?;
        let ctx = GpuContext::headless()?;
        let resources = Resources {
            base_dir: graph.base_dir(),
            out_dir: options.out,
            outputs_anywhere: options.outputs_anywhere,
            scene: scene.clone(),
            ..Resources::default()
        }
        .tracing(|t: &mut Tracing| {
            t.intersector = options.intersector;
            t.schedule = options.schedule;
        });
        let mut exec = Executor::with_library(&ctx, plan, &resources, &library)?;
        exec.hold_sinks(!options.write_outputs);
        let mut session = Self::from_executor(exec, graph, scene, resources, library);
        session.sequence = sequence;
        session.keep = options.keep;
        session.write_outputs = options.write_outputs;
        session.warm_up()?;
        Ok(session)
    }

    /// A session over an executor built by the caller (the command line, the editor's
    /// render job: their own device, registry or plan): `exec` runs `graph`, compiled with
    /// `library`, with `resources` (whose scene is `scene`). Its sinks write their files as
    /// the executor is set ([`Executor::hold_sinks`]); nothing is warmed up yet.
    pub fn from_executor(
        exec: Executor,
        graph: Graph,
        scene: Option<Arc<GpuScene>>,
        resources: Resources,
        library: Arc<NodeLibrary>,
    ) -> Self {
        Self {
            graph,
            library,
            scene,
            scene_text: None,
            camera: None,
            keep: Vec::new(),
            resources,
            write_outputs: true,
            exec,
            warm: false,
            last: None,
            warnings: Vec::new(),
            sequence: None,
        }
    }

    /// Runs the first frame's dispatches once, so that pipelines the driver compiles at
    /// their first use are compiled before anything is timed ([`Executor::warm_up`]);
    /// [`Session::render`] does it where it was not done.
    ///
    /// # Errors
    /// When a node fails.
    pub fn warm_up(&mut self) -> Result<()> {
        if !self.warm {
            self.exec.warm_up()?;
            self.warm = true;
        }
        Ok(())
    }

    /// The frames that make `spp` samples per pixel ([`Executor::frames_for`]) where the
    /// graph has a sample source or keeps history; 1 where it has neither (a post chain).
    pub fn frames_for(&self, spp: u32) -> u32 {
        let plan = self.exec.plan();
        let progressive = plan
            .passes
            .iter()
            .any(|p| p.kind.history || p.params.has(lumagraph_graph::registry::SAMPLES_PER_FRAME));
        if progressive {
            self.exec.frames_for(spp)
        } else {
            1
        }
    }

    /// Renders on to `spp` samples per pixel in all (whole frames of the path tracer's
    /// `samples_per_frame`), then runs the rest of the graph once; `Output` nodes write
    /// their files where the options say so.
    ///
    /// # Errors
    /// When a node fails; the error names the node.
    pub fn render(&mut self, spp: u32) -> Result<FrameReport> {
        self.render_with(spp, |_, _, _| true)?
            .context("the render stopped")
    }

    /// [`Session::render`], calling `progress(executor, frames done, frames in all)` a few
    /// times a second; where it returns `false` the render stops there (`Ok(None)`,
    /// nothing finished or written), and a later `render` goes on from the frames done.
    /// The executor lets the caller checkpoint between batches.
    ///
    /// # Errors
    /// When a node fails; the error names the node.
    pub fn render_with(
        &mut self,
        spp: u32,
        mut progress: impl FnMut(&mut Executor, u32, u32) -> bool,
    ) -> Result<Option<FrameReport>> {
        self.warm_up()?;
        let frames = self.frames_for(spp);
        let Some(report) = self.exec.render(frames, &mut progress)? else {
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

    /// The image on output `"node.port"` as a PNG file's bytes, for display: a display
    /// image (`LdrColor`, after tone mapping) as it is, a linear one sRGB-encoded (from
    /// Rec. 709, converted from the graph's working space); both clipped to [0, 1], as an
    /// `Output` node writes a PNG.
    ///
    /// # Errors
    /// As [`Session::read`].
    pub fn png(&self, port: &str) -> Result<Vec<u8>> {
        use lumagraph_graph::{PortType, TexFormat};
        use lumagraph_render::image_io::{encode_png, to_rgba8};
        let t = self
            .exec
            .plan()
            .texture_named(port)
            .with_context(|| format!("no planned texture for {port}"))?;
        let (w, h) = (t.extent.width, t.extent.height);
        let rgba8 = if t.format == TexFormat::Rgba8Unorm {
            // Stored as the PNG holds it.
            self.exec.read_raw(t.id)?
        } else {
            let mut image = self.exec.read(t.id)?;
            let linear = t.ty != PortType::LdrColor;
            if linear {
                lumagraph_render::nodes::ocio::working_to_rec709(
                    self.exec.plan().working_space,
                    &mut image,
                )?;
            }
            to_rgba8(&image, linear)
        };
        Ok(encode_png(w, h, &rgba8)?)
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
        if let Some(seq) = &mut self.sequence {
            // Later frames keep the edit (a pattern given here is taken as written).
            seq.template.apply_override(&format!("{target}={value}"))?;
            seq.params = FrameParams::of(&seq.template, &self.library.registry_for(&seq.template)?);
        }
        self.graph = graph;
        if self.exec.update_params(plan.clone())? {
            let report = self.exec.rerun(&[node])?;
            self.last = Some(report.clone());
            return Ok(report);
        }
        // Another structure: a new executor, rendered again to the samples so far.
        let spp = self.spp();
        self.rebuild(plan)?;
        let spp = u32::try_from(spp).unwrap_or(u32::MAX);
        self.render(spp.max(1))
    }

    /// A new executor of `plan` on the same device, at the moved camera if any, warmed up.
    fn rebuild(&mut self, plan: lumagraph_graph::Plan) -> Result<()> {
        let ctx = self.exec.context().clone();
        self.exec = Executor::with_library(&ctx, plan, &self.resources, &self.library)?;
        self.exec.hold_sinks(!self.write_outputs);
        if let Some(camera) = &self.camera {
            self.exec.move_camera(camera);
        }
        self.warm = false;
        self.warm_up()
    }

    /// The scene file as loaded and edited; `None` for a session without one or given a
    /// flattened scene ([`Session::with`]).
    pub fn scene(&self) -> Option<&SceneText> {
        self.scene_text.as_ref()
    }

    /// Renders `file` from now on: the scene file's values edited ([`lumagraph_scene::edit`]:
    /// camera, materials, environment, render settings). The accumulation restarts
    /// ([`Session::spp`] is 0). Where only the camera changed, the executor keeps its
    /// pipelines and buffers and only the camera moves; otherwise the scene is built
    /// again and the graph compiled for it (its size may have changed, and what the
    /// shaders leave out).
    ///
    /// # Errors
    /// When the session has no scene file, or the edited scene does not load (the error
    /// names the file and what is wrong); the session then renders the scene as it was.
    pub fn set_scene(&mut self, file: SceneFile) -> Result<SceneChange> {
        let current = self
            .scene_text
            .as_ref()
            .context("this session has no scene file to edit")?;
        if current.file == file {
            return Ok(SceneChange::Nothing);
        }
        let mut edited = current.clone();
        edited.file = file;
        let mut same_but_camera = current.file.clone();
        same_but_camera.camera = edited.file.camera.clone();
        if same_but_camera == edited.file
            && let Some(gpu) = &self.scene
        {
            // Only the camera is built: nothing is loaded again for a perspective camera.
            let camera = lumagraph_scene::Scene::camera_of(&edited.file, edited.base_dir())
                .map_err(|e| e.in_file(&edited.path))?;
            let camera = gpu.camera_for(&camera);
            self.camera = (camera != gpu.camera).then_some(camera);
            self.exec.move_camera(&camera);
            self.exec.restart();
            self.scene_text = Some(edited);
            return Ok(SceneChange::Camera);
        }
        let (gpu, warnings) = build_scene(&edited)?;
        let plan = self.library.compile(&self.graph, &self.keep, Some(&gpu))?;
        let old = (self.scene.replace(Arc::clone(&gpu)), self.camera.take());
        self.resources.scene = Some(gpu);
        if let Err(e) = self.rebuild(plan) {
            // Back to the scene as it was; its executor is gone, so build that again.
            self.resources.scene.clone_from(&old.0);
            (self.scene, self.camera) = old;
            let plan = self
                .library
                .compile(&self.graph, &self.keep, self.scene.as_deref())?;
            self.rebuild(plan)?;
            return Err(e);
        }
        self.warnings = warnings;
        self.scene_text = Some(edited);
        Ok(SceneChange::Scene)
    }

    /// The key of what this session renders ([`render_key`]): the graph as it stands and
    /// the scene as edited; its checkpoints carry it.
    pub fn key(&self) -> u64 {
        let scene = self
            .scene
            .as_deref()
            .map(|s| scene_digest(s, self.camera.as_ref().unwrap_or(&s.camera)));
        key_of(&self.graph, &scene.unwrap_or_default())
    }

    /// Writes where the render stands to `path` (atomically): the frames run and the
    /// history of every node that keeps one, as `lumagraph render --checkpoint` writes
    /// it, so either can go on from it.
    ///
    /// # Errors
    /// When a readback fails or the file cannot be written.
    pub fn checkpoint(&mut self, path: &Path) -> Result<()> {
        let key = self.key();
        self.exec.checkpoint(key)?.save(path)?;
        Ok(())
    }

    /// Goes on from the checkpoint at `path` (written by [`Session::checkpoint`] or by
    /// `lumagraph render`): the next [`Session::render`] renders on from its samples.
    ///
    /// # Errors
    /// When it does not load, or is of another graph, scene or lumagraph version (the
    /// error says which); the session is then unchanged.
    pub fn resume(&mut self, path: &Path) -> Result<()> {
        self.resume_from(&Checkpoint::load(path)?, path)
    }

    /// [`Session::resume`] from a checkpoint loaded from `path`.
    ///
    /// # Errors
    /// As [`Session::resume`].
    pub fn resume_from(&mut self, from: &Checkpoint, path: &Path) -> Result<()> {
        from.check(self.key())
            .map_err(|e| anyhow::anyhow!("cannot resume from {}: {e}", path.display()))?;
        if from.adapter != self.exec.context().info.name {
            println!(
                "warning: the checkpoint {} was made on {}, this is {}: the result may differ \
                 from an uninterrupted render in the last bits",
                path.display(),
                from.adapter,
                self.exec.context().info.name
            );
        }
        self.exec
            .restore(from)
            .with_context(|| format!("cannot resume from {}", path.display()))?;
        Ok(())
    }

    /// Each sink (`Output` node) of the plan and the port whose image it writes
    /// (`"node.port"`, readable with [`Session::read`]), in the order of the graph's nodes.
    pub fn outputs(&mut self) -> Vec<(String, String)> {
        let plan = self.exec.plan();
        let mut out: Vec<(String, String)> = plan
            .passes
            .iter()
            .filter(|p| p.kind.sink)
            .filter_map(|p| {
                let (_, t) = p.inputs.first()?;
                Some((p.node.clone(), plan.texture(*t).name.clone()))
            })
            .collect();
        let order = |node: &str| {
            self.graph
                .nodes
                .iter()
                .position(|n| n.id == node)
                .unwrap_or(usize::MAX)
        };
        out.sort_by_key(|(node, _)| order(node));
        out
    }

    /// The frame a graph with frame patterns is at (`None` for other graphs).
    pub fn frame(&self) -> Option<i64> {
        self.sequence.as_ref().map(|s| s.frame)
    }

    /// Moves a graph with frame patterns to frame `frame` and runs it once: each param
    /// with a pattern takes the frame's number, only the nodes whose params changed
    /// reload (an `ImageInput` its file) and the graph runs one frame, over the history
    /// of nodes that keep one (so `TemporalReuse` and `AutoExposure` see the frame
    /// before); where the frame's images are of another size, the graph is built again
    /// and history starts over. `Output` nodes write their files where the options say so.
    ///
    /// # Errors
    /// A graph without frame patterns; a frame whose input file is missing (named); a
    /// node that fails.
    pub fn set_frame(&mut self, frame: i64) -> Result<FrameReport> {
        let seq = self
            .sequence
            .as_mut()
            .context("the graph has no param with a frame pattern (`####`, `%04d`, `$F4`)")?;
        if let Some(missing) = seq.params.missing_at(&seq.template, frame) {
            anyhow::bail!("frame {frame}: {} is missing", missing.display());
        }
        let graph = seq.params.at(&seq.template, frame);
        let plan = self
            .library
            .compile(&graph, &self.keep, self.scene.as_deref())
            .with_context(|| format!("frame {frame}"))?;
        seq.frame = frame;
        self.graph = graph;
        let report = if self.exec.update_params(plan.clone())? {
            self.exec.run_frame()?
        } else {
            self.rebuild(plan)?;
            self.exec.run_frame()?
        };
        self.last = Some(report.clone());
        Ok(report)
    }

    /// The graph as it stands (with the params set since it was opened; at its frame).
    pub fn graph(&self) -> &Graph {
        &self.graph
    }

    /// The executor, for what this API does not cover.
    pub fn executor(&mut self) -> &mut Executor {
        &mut self.exec
    }
}

/// What [`Session::set_scene`] changed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SceneChange {
    /// Nothing: the values were those rendered.
    Nothing,
    /// The camera only: it moved, the executor stayed.
    Camera,
    /// More than the camera: the scene was built again.
    Scene,
}

/// Loads what `text` references and flattens it; returns the scene with the lines loading
/// warned of (also printed to standard error as `scene warning: …`).
fn build_scene(text: &SceneText) -> Result<(Arc<GpuScene>, Vec<String>)> {
    let scene = text.build()?;
    let warnings = scene.report.lines();
    for w in &warnings {
        eprintln!("scene warning: {w}");
    }
    Ok((Arc::new(GpuScene::build(&scene)?), warnings))
}

/// The key of a render, which a checkpoint carries so that only the same render goes on
/// from it: lumagraph's version, the graph as run (overrides applied, without layout and
/// comments) and every number of the flattened scene.
pub fn render_key(graph: &Graph, scene: Option<&GpuScene>) -> u64 {
    key_of(
        graph,
        &scene.map_or_else(String::new, |s| scene_digest(s, &s.camera)),
    )
}

/// [`render_key`] of `graph` and a scene's digest. What only the editor draws (positions,
/// colours, frames, reroute points) and the file's comments are left out.
fn key_of(graph: &Graph, scene: &str) -> u64 {
    let mut g = graph.clone();
    g.origin = None;
    g.frames.clear();
    for n in &mut g.nodes {
        n.pos = None;
        n.color = None;
    }
    for e in &mut g.edges {
        e.via.clear();
    }
    lumagraph_render::checkpoint::render_key(&g.to_ron(), scene)
}

/// Every number of the flattened scene seen from `camera`, hashed: what the GPU gets and
/// the CPU data that shapes the render (the host intersector's corners, the orders, the
/// environment map's file). Hashing the bytes rather than the scene's `Debug` text keeps a large scene's key
/// cheap (the Crytek Sponza's text was over a gigabyte and took most of a minute).
pub(crate) fn scene_digest(s: &GpuScene, camera: &GpuCamera) -> String {
    use bytemuck::{bytes_of, cast_slice};
    let h = lumagraph_render::checkpoint::Fnv::default()
        .write(bytes_of(&s.header))
        .write(bytes_of(camera))
        .write(bytes_of(&s.settings))
        .write(cast_slice(&s.bvh_nodes))
        .write(cast_slice(&s.bvh_skips))
        .write(cast_slice(&s.tri_positions))
        .write(cast_slice(&s.tri_corners))
        .write(cast_slice(&s.tri_shading))
        .write(cast_slice(&s.shapes))
        .write(cast_slice(&s.materials))
        .write(cast_slice(&s.lights))
        .write(cast_slice(&s.light_alias))
        .write(cast_slice(&s.tri_texcoords))
        .write(cast_slice(&s.atlas.descriptors))
        .write(cast_slice(&s.atlas.texels))
        .write(&s.atlas.page_size.to_le_bytes())
        .write(&s.atlas.pages.to_le_bytes())
        .write(&s.vertex_alpha_min)
        .write(cast_slice(&s.tri_source))
        .write(cast_slice(&s.shape_source))
        .write(cast_slice(&s.instances))
        .write(cast_slice(&s.instance_mesh))
        .write(cast_slice(&s.mesh_triangles))
        .write(format!("{:?}", s.environment_map).as_bytes());
    format!("{:016x}", h.finish())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The key of a render's checkpoint follows the instances: a moved instance (its mesh
    /// and everything else the same) is another scene.
    /// A render's key ignores what only the editor draws (positions, colours, frames,
    /// reroute points), so a checkpoint survives tidying the graph, and follows params.
    #[test]
    fn the_key_ignores_the_editors_drawing() {
        use lumagraph_graph::{Edge, FrameDecl, Node, ParamValue};
        let mut g = Graph::new();
        g.nodes
            .push(Node::new("a", "ImageInput").with("path", ParamValue::Str("x.exr".into())));
        g.nodes.push(Node::new("b", "Output"));
        g.edges.push(Edge::new("a.color", "b.color"));
        let key = render_key(&g, None);
        let mut drawn = g.clone();
        drawn.nodes[0].pos = Some((10.0, 20.0));
        drawn.nodes[1].color = Some((200, 40, 40));
        drawn.edges[0].via.push((5.0, 5.0));
        drawn.frames.push(FrameDecl {
            label: "f".into(),
            comment: String::new(),
            color: None,
            nodes: vec!["a".into()],
        });
        assert_eq!(render_key(&drawn, None), key);
        let mut other = g.clone();
        other.nodes[0] = other.nodes[0]
            .clone()
            .with("path", ParamValue::Str("y.exr".into()));
        assert_ne!(render_key(&other, None), key);
    }

    #[test]
    fn the_scene_key_follows_the_instances() {
        let text = |x: f32| {
            format!(
                "(version: 2, camera: Perspective(position: (0, 0, 9), target: (0, 0, 0), fov_y: 40),
                  materials: {{ \"m\": () }},
                  shapes: [Mesh(path: \"CornellBox/CornellBox.gltf\", material: \"m\",
                                instances: [(), (translate: ({x}, 0, 0))])],
                  render: (width: 8, height: 8), instancing: On)"
            )
        };
        let assets = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets");
        let digest = |x: f32| {
            let scene = lumagraph_scene::Scene::from_ron(&text(x), &assets).unwrap();
            let gpu = GpuScene::build(&scene).unwrap();
            assert_eq!(gpu.instances.len(), 2);
            scene_digest(&gpu, &gpu.camera)
        };
        assert_eq!(digest(3.0), digest(3.0));
        assert_ne!(digest(3.0), digest(3.5));
    }
}
