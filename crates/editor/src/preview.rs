//! The live preview: the selected output port, rendered on the editor's own device.
//!
//! The preview runs a copy of the graph with its sinks removed (so editing never writes
//! files) and the previewed port kept alive (`CompileOptions::keep`). On every edit the
//! copy is compiled again — compiling is CPU work in microseconds — and the new plan is
//! compared with the running one: when only params differ, [`Executor::update_params`]
//! hands each changed node its params (a uniform write) and no pipeline, texture or node
//! is recreated; only a structural change (nodes, edges, sizes, the previewed port)
//! builds a new executor.
//!
//! The result is read back and uploaded as an egui texture. Encoding follows the Output
//! node's PNG path exactly (display-encoded data as is, linear data sRGB-encoded and
//! clipped), so the preview shows the pixels `lumagraph render` writes to a PNG.
//!
//! Scenes and progressive sources: with a scene (see [`PreviewScene`]), `PathTrace` and
//! `GBuffer` nodes render it, at a resolution capped for responsiveness. When the plan has
//! a node with history (`Accumulate`), the editor keeps calling [`Preview::step`], one
//! frame (one more sample per pixel per `samples_per_frame`) per UI frame, until the
//! scene's `spp` is reached. The preview compiles with every output upstream of the
//! previewed port kept alive, so no two of them share texture memory: a param edit then
//! re-runs only the edited node and what is downstream of it ([`Executor::rerun`]) over
//! the accumulation as it is. Editing a node that feeds the accumulation (`PathTrace`,
//! `GBuffer` when it feeds one), the scene, or the graph's structure restarts it.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use lumagraph_graph::{Graph, Plan, PortType, Registry};
use lumagraph_render::{Executor, FrameReport, GpuContext, NodeLibrary, Resources};
use lumagraph_scene::GpuScene;

/// The scene the preview renders, already at the preview's resolution.
#[derive(Clone, Debug)]
pub struct PreviewScene {
    /// The flattened scene.
    pub gpu: Arc<GpuScene>,
    /// Changes whenever another scene (or the same file again) is loaded, so the preview
    /// restarts.
    pub generation: u64,
    /// The camera moved in the preview (`gpu.camera` until then). A move is not a new
    /// scene: the preview keeps its executor, accumulation restarts, and a
    /// `TemporalReuse` node carries its history into the new view
    /// ([`Executor::move_camera`]).
    pub camera: Option<lumagraph_scene::GpuCamera>,
}

/// A preview image: 8-bit RGBA as a PNG written by an Output node would hold it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PreviewImage {
    /// The port shown, `"node.port"`.
    pub port: String,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Row-major RGBA8.
    pub rgba: Vec<u8>,
}

/// Counters and timings, for the status line and the tests.
#[derive(Clone, Debug, Default)]
pub struct PreviewStats {
    /// Executors built (structural changes).
    pub rebuilds: u64,
    /// Param-only updates (no pipeline or texture created).
    pub param_updates: u64,
    /// Frames run.
    pub frames: u64,
    /// Wall time of the last frame (record, submit, wait), ms.
    pub frame_ms: f64,
    /// Wall time of the last readback and conversion, ms.
    pub readback_ms: f64,
    /// Times progressive accumulation restarted (a new executor, or an edit upstream of
    /// the accumulation).
    pub restarts: u64,
    /// Nodes the last param update re-ran, in order.
    pub last_update: Vec<String>,
    /// Times the GPU device was lost and a new one opened.
    pub devices_reopened: u64,
    /// Camera moves handed to the running executor (no rebuild).
    pub camera_moves: u64,
}

/// The preview state.
pub struct Preview {
    gpu: GpuContext,
    library: Arc<NodeLibrary>,
    exec: Option<Executor>,
    key: Option<(Graph, String, PathBuf, u64)>,
    scene: Option<Arc<GpuScene>>,
    /// The camera moved in the preview ([`PreviewScene::camera`]).
    camera: Option<lumagraph_scene::GpuCamera>,
    /// Samples per pixel accumulated so far, when the plan path-traces.
    pub samples: Option<u64>,
    /// Whether the plan has a node with history, so frames keep coming.
    pub progressive: bool,
    /// Accumulation stops at this many samples per pixel (the scene's `spp`).
    pub target_spp: u64,
    /// Set to stop adding frames.
    pub paused: bool,
    /// The last image.
    pub image: Option<PreviewImage>,
    /// The last image as read back (linear values for HDR ports) with its port type: what
    /// the viewer shows and reads values from.
    pub linear: Option<(lumagraph_render::cpu::Image, PortType)>,
    texture: Option<egui::TextureHandle>,
    texture_stale: bool,
    /// Milliseconds per node of the last frame (see `FrameReport::pass_clock`; empty when
    /// the adapter cannot time passes).
    pub pass_ms: BTreeMap<String, f64>,
    /// What the nodes measured on the last frame (`(node id, measurement)`: a `Difference`
    /// node's error, an `AutoExposure` node's exposure).
    pub measurements: Vec<(String, lumagraph_render::Measurement)>,
    /// Each `Difference` node's error at each frame of this accumulation, against the
    /// samples and the wall time so far ([`crate::error_plot`]).
    pub curve: crate::error_plot::ErrorCurve,
    /// Why there is no preview, when there is none.
    pub error: Option<String>,
    /// Counters.
    pub stats: PreviewStats,
    /// Read back a small picture of every node's output (see [`Thumbnail`]).
    pub thumbnails_on: bool,
    /// The pictures, by node id.
    pub thumbnails: BTreeMap<String, Thumbnail>,
    thumbnails_at: Option<Instant>,
    thumbnails_due: bool,
}

/// The longest side of a node thumbnail, in pixels.
pub const THUMBNAIL_SIZE: u32 = 96;

/// A small picture of a node's first output, encoded as the preview encodes its image,
/// read back after a change and then at most once a second while a render accumulates.
#[derive(Clone)]
pub struct Thumbnail {
    /// The port shown.
    pub port: String,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Row-major RGBA8.
    pub rgba: Vec<u8>,
    texture: Option<egui::TextureHandle>,
}

impl std::fmt::Debug for Thumbnail {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Thumbnail({} {}×{})", self.port, self.width, self.height)
    }
}

/// `image` shrunk by an integer factor (the mean of each block of pixels) so its longer
/// side is at most `max`.
pub fn shrink(image: &lumagraph_render::cpu::Image, max: u32) -> lumagraph_render::cpu::Image {
    let f = image.width.max(image.height).div_ceil(max.max(1)).max(1);
    let (w, h) = (image.width.div_ceil(f), image.height.div_ceil(f));
    let mut out = lumagraph_render::cpu::Image::filled(w, h, [0.0; 4]);
    for y in 0..h {
        for x in 0..w {
            let mut sum = [0.0f32; 4];
            let mut n = 0.0f32;
            for yy in y * f..((y + 1) * f).min(image.height) {
                for xx in x * f..((x + 1) * f).min(image.width) {
                    let p = image.pixels[(yy * image.width + xx) as usize];
                    for c in 0..4 {
                        sum[c] += p[c];
                    }
                    n += 1.0;
                }
            }
            out.pixels[(y * w + x) as usize] = sum.map(|v| v / n.max(1.0));
        }
    }
    out
}

impl std::fmt::Debug for Preview {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Preview")
            .field("stats", &self.stats)
            .field("error", &self.error)
            .finish_non_exhaustive()
    }
}

/// The graph the preview runs: `graph` without its sinks (nothing is written to disk).
pub fn preview_graph(reg: &Registry, graph: &Graph) -> Graph {
    let mut g = graph.clone();
    g.remove_sinks(reg);
    for n in &mut g.nodes {
        n.pos = None;
    }
    g
}

/// The outputs the preview keeps alive: `port` and every output an edge reads from a
/// node that feeds a sink or `port` (sinks included, though the preview leaves them out).
/// So the preview runs what `lumagraph render` runs, no two of those outputs share
/// texture memory (a param edit can re-run only what is downstream of it), and previewing
/// another of them is not a structural change (accumulation goes on).
pub fn preview_keep(reg: &Registry, graph: &Graph, port: &str) -> Vec<String> {
    let node_of = |p: &str| lumagraph_graph::split_port_ref(p).map(|(n, _)| n.to_owned());
    let mut upstream = BTreeSet::new();
    let mut stack: Vec<String> = graph
        .nodes
        .iter()
        .filter(|n| reg.get(&n.kind).is_some_and(|k| k.sink))
        .map(|n| n.id.clone())
        .chain(node_of(port))
        .collect();
    while let Some(n) = stack.pop() {
        if !upstream.insert(n.clone()) {
            continue;
        }
        for e in &graph.edges {
            if node_of(&e.to).as_deref() == Some(n.as_str())
                && let Some(from) = node_of(&e.from)
            {
                stack.push(from);
            }
        }
    }
    let mut keep = vec![port.to_owned()];
    for e in &graph.edges {
        if node_of(&e.from).is_some_and(|n| upstream.contains(&n)) && !keep.contains(&e.from) {
            keep.push(e.from.clone());
        }
    }
    keep
}

/// Compiles the preview graph of `graph` against `registry` (`library`'s kinds and those
/// the graph declares), keeping `port` (and the outputs upstream of it, see
/// [`preview_keep`]), with `scene` for the nodes that render one.
///
/// # Errors
/// The compiler's messages, one a line.
pub fn compile_preview(
    library: &NodeLibrary,
    registry: &Registry,
    graph: &Graph,
    base: &Path,
    port: &str,
    scene: Option<&GpuScene>,
) -> Result<Plan, String> {
    let messages = |e: lumagraph_graph::GraphErrors| {
        e.0.iter()
            .map(|e| match e.about.as_deref() {
                Some(n) => format!("{n}: {}", e.kind),
                None => e.kind.to_string(),
            })
            .collect::<Vec<_>>()
            .join("\n")
    };
    // Groups are flattened first, so the sinks inside them are left out too.
    let flat = lumagraph_graph::group::flatten(graph, registry).map_err(messages)?;
    let port = flat.resolve(port);
    let g = preview_graph(&flat.registry, &flat.graph);
    let keep = preview_keep(&flat.registry, &flat.graph, port);
    let mut plan = library
        .compile_with(&g, &flat.registry, base, &keep, scene)
        .map_err(messages)?;
    plan.aliases.clone_from(&flat.aliases);
    Ok(plan)
}

/// Converts read-back texels to 8-bit RGBA the way the Output node writes a PNG.
pub fn encode_rgba8(image: &lumagraph_render::cpu::Image, ty: PortType) -> Vec<u8> {
    lumagraph_render::image_io::to_rgba8(image, ty != PortType::LdrColor)
}

impl Preview {
    /// A preview rendering on `gpu` (the editor's device) with the built-in node kinds.
    pub fn new(gpu: GpuContext) -> Self {
        Self::with_library(
            gpu,
            Arc::new(lumagraph_pathtrace::library::builtins().clone()),
        )
    }

    /// A preview rendering on `gpu`, running nodes with the implementations of `library`.
    pub fn with_library(gpu: GpuContext, library: Arc<NodeLibrary>) -> Self {
        Self {
            gpu,
            library,
            exec: None,
            key: None,
            scene: None,
            camera: None,
            samples: None,
            progressive: false,
            target_spp: 0,
            paused: false,
            image: None,
            linear: None,
            texture: None,
            texture_stale: false,
            pass_ms: BTreeMap::new(),
            measurements: Vec::new(),
            curve: crate::error_plot::ErrorCurve::default(),
            error: None,
            stats: PreviewStats::default(),
            thumbnails_on: false,
            thumbnails: BTreeMap::new(),
            thumbnails_at: None,
            thumbnails_due: false,
        }
    }

    /// The GPU context.
    pub fn gpu(&self) -> &GpuContext {
        &self.gpu
    }

    /// When the device was lost (a driver reset, the GPU removed): opens a new one on the
    /// same adapter and drops everything made on the old one, so the next update builds the
    /// preview again and accumulation starts over; returns what happened, for the status
    /// line. `None` while the device is fine.
    pub fn reopen_if_lost(&mut self) -> Option<String> {
        let reason = self.gpu.lost()?;
        let adapter = self.gpu.info.name.clone();
        match self.gpu.reopen() {
            Ok(gpu) => {
                self.gpu = gpu;
                self.exec = None;
                self.clear(None);
                self.stats.devices_reopened += 1;
                Some(format!(
                    "the GPU device ({adapter}) was lost ({reason}); the preview goes on on a \
                     new one, from the first sample"
                ))
            }
            Err(e) => {
                self.clear(Some(format!(
                    "the GPU device ({adapter}) was lost ({reason}), and a new one could not \
                     be opened: {e}"
                )));
                None
            }
        }
    }

    /// Brings the preview up to date with `graph` showing `port`, rendering `scene` when
    /// given; does nothing when none of them changed (node positions do not count).
    /// Returns whether a frame ran.
    pub fn update(
        &mut self,
        registry: &Registry,
        graph: &Graph,
        base: &Path,
        port: Option<&str>,
        scene: Option<&PreviewScene>,
    ) -> bool {
        let Some(port) = port else {
            self.clear(Some("select a node with an output to preview it".into()));
            return false;
        };
        // With groups, flattened, so an edit inside a group changes the key (this runs
        // every UI frame: a graph without groups is not copied for it).
        let flat = if lumagraph_graph::group::has_groups(graph, registry) {
            match lumagraph_graph::group::flatten(graph, registry) {
                Ok(flat) => Some(flat),
                Err(e) => {
                    self.clear(Some(e.to_string()));
                    return false;
                }
            }
        } else {
            None
        };
        let mut g = match &flat {
            Some(flat) => preview_graph(&flat.registry, &flat.graph),
            None => preview_graph(registry, graph),
        };
        g.origin = None;
        let generation = scene.map_or(0, |s| s.generation);
        let key = (g, port.to_owned(), base.to_owned(), generation);
        let camera = scene.and_then(|s| s.camera);
        if self.key.as_ref() == Some(&key) {
            return self.follow_camera(camera, port);
        }
        let scene_changed = self.key.as_ref().is_none_or(|k| k.3 != generation);
        self.key = Some(key);
        if scene_changed {
            // Another scene: nothing of the old executor (buffers, accumulation) applies.
            self.exec = None;
            self.scene = scene.map(|s| Arc::clone(&s.gpu));
        }
        self.camera = camera;
        match self.render(registry, graph, base, port) {
            Ok(()) => {
                self.error = None;
                true
            }
            Err(e) => {
                self.clear(Some(e));
                false
            }
        }
    }

    /// Moves the running executor's camera to `camera` when it moved, and runs a frame
    /// from there. Returns whether a frame ran.
    fn follow_camera(&mut self, camera: Option<lumagraph_scene::GpuCamera>, port: &str) -> bool {
        if camera == self.camera {
            return false;
        }
        self.camera = camera;
        let to = camera.or_else(|| self.scene.as_ref().map(|s| s.camera));
        let (Some(exec), Some(to)) = (&mut self.exec, to) else {
            return false;
        };
        if !exec.move_camera(&to) {
            return false;
        }
        self.stats.camera_moves += 1;
        self.stats.restarts += u64::from(self.progressive);
        self.step(port).is_ok()
    }

    /// Drops the executor, so the next update builds every pipeline again (the kinds
    /// were read again and a shader may have changed).
    pub fn rebuild(&mut self) {
        self.key = None;
        self.exec = None;
    }

    fn clear(&mut self, error: Option<String>) {
        self.key = None;
        self.image = None;
        self.linear = None;
        self.texture = None;
        self.pass_ms.clear();
        self.measurements.clear();
        self.samples = None;
        self.progressive = false;
        self.error = error;
        self.thumbnails.clear();
    }

    fn render(
        &mut self,
        registry: &Registry,
        graph: &Graph,
        base: &Path,
        port: &str,
    ) -> Result<(), String> {
        let plan = compile_preview(
            &self.library,
            registry,
            graph,
            base,
            port,
            self.scene.as_deref(),
        )?;
        self.thumbnails_due = true;
        let changed: Vec<String> = match &self.exec {
            Some(exec) => exec
                .plan()
                .passes
                .iter()
                .zip(&plan.passes)
                .filter(|(a, b)| a.params != b.params)
                .map(|(a, _)| a.node.clone())
                .collect(),
            None => Vec::new(),
        };
        let updated = match &mut self.exec {
            Some(exec) => exec
                .update_params(plan.clone())
                .map_err(|e| e.to_string())?,
            None => false,
        };
        let report = if updated {
            self.stats.param_updates += u64::from(!changed.is_empty());
            let before = self.samples;
            let exec = self.exec.as_mut().ok_or("no executor")?;
            let report = exec.rerun(&changed).map_err(|e| e.to_string());
            self.stats.last_update = report
                .as_ref()
                .map(|r| r.executed.clone())
                .unwrap_or_default();
            let report = report?;
            self.read_samples()?;
            if self.samples < before {
                self.stats.restarts += 1;
            }
            report
        } else {
            self.exec = None;
            let paths = Resources {
                base_dir: base.to_owned(),
                out_dir: base.to_owned(),
                scene: self.scene.clone(),
                ..Resources::default()
            };
            let mut exec = Executor::with_library(&self.gpu, plan, &paths, &self.library)
                .map_err(|e| e.to_string())?;
            if let Some(camera) = &self.camera {
                exec.move_camera(camera);
            }
            self.progressive = exec.plan().passes.iter().any(|p| p.kind.history);
            self.target_spp = self
                .scene
                .as_ref()
                .filter(|_| self.progressive)
                .map_or(0, |s| u64::from(s.settings.spp));
            self.exec = Some(exec);
            self.curve.clear();
            self.stats.rebuilds += 1;
            self.stats.restarts += u64::from(self.progressive);
            let report = self.frame()?;
            self.read_samples()?;
            report
        };
        self.show(&report, port)
    }

    /// Whether the preview wants another frame: the plan accumulates, it is not paused,
    /// and the scene's sample count is not reached yet.
    pub fn wants_frames(&self) -> bool {
        self.exec.is_some()
            && self.error.is_none()
            && self.progressive
            && !self.paused
            && self.samples.is_none_or(|s| s < self.target_spp)
    }

    /// Runs one more frame (one more sample per pixel for a path tracer) and reads `port`
    /// back.
    ///
    /// # Errors
    /// When the frame or the readback fails.
    pub fn step(&mut self, port: &str) -> Result<(), String> {
        let result = self.frame().and_then(|report| {
            self.read_samples()?;
            self.show(&report, port)
        });
        if let Err(e) = &result {
            self.error = Some(e.clone());
        }
        result
    }

    /// Runs one frame of the current executor and reads `port` back.
    ///
    /// # Errors
    /// When the frame or the readback fails.
    pub fn run_frame(&mut self, port: &str) -> Result<(), String> {
        let report = self.frame()?;
        self.read_samples()?;
        self.show(&report, port)
    }

    fn frame(&mut self) -> Result<FrameReport, String> {
        let exec = self.exec.as_mut().ok_or("nothing to run")?;
        exec.run_frame().map_err(|e| {
            // A failed frame leaves the executor in an unknown state: rebuild next time.
            self.exec = None;
            self.key = None;
            e.to_string()
        })
    }

    /// Reads the path tracer's sample count (a small readback) when the plan has one.
    fn read_samples(&mut self) -> Result<(), String> {
        let Some(exec) = &mut self.exec else {
            return Ok(());
        };
        if !exec
            .plan()
            .passes
            .iter()
            .any(|p| p.params.has(lumagraph_graph::registry::SAMPLES_PER_FRAME))
        {
            self.samples = None;
            return Ok(());
        }
        let counters = exec.counters().map_err(|e| e.to_string())?;
        self.samples = counters
            .iter()
            .find(|(_, c)| c.name == "samples_per_pixel")
            .map(|(_, c)| c.value);
        Ok(())
    }

    /// Reads `port` back after `report`'s frame and keeps it as the image to show, with what
    /// the nodes measured.
    fn show(&mut self, report: &FrameReport, port: &str) -> Result<(), String> {
        let exec = self.exec.as_ref().ok_or("nothing to run")?;
        let t = Instant::now();
        let ty = exec
            .plan()
            .texture_named(port)
            .map(|t| t.ty)
            .ok_or_else(|| format!("{port} is not computed"))?;
        let image = exec.read_port(port).map_err(|e| e.to_string())?;
        let rgba = encode_rgba8(&image, ty);
        self.stats.frames += 1;
        self.stats.frame_ms = report.wall.as_secs_f64() * 1e3;
        self.stats.readback_ms = t.elapsed().as_secs_f64() * 1e3;
        self.pass_ms = report
            .pass_ms
            .clone()
            .unwrap_or_default()
            .into_iter()
            .collect();
        self.image = Some(PreviewImage {
            port: port.to_owned(),
            width: image.width,
            height: image.height,
            rgba,
        });
        self.linear = Some((image, ty));
        self.texture_stale = true;
        if let Some(exec) = &mut self.exec {
            self.measurements = exec.measurements().map_err(|e| e.to_string())?;
        }
        let spp = self.samples.filter(|_| self.progressive);
        self.curve.record(
            spp,
            report.wall,
            self.measurements
                .iter()
                .map(|(node, m)| (node.as_str(), m.name, m.value)),
        );
        self.read_thumbnails()
    }

    /// Turns the node thumbnails on or off; on, they are read back now.
    pub fn set_thumbnails(&mut self, on: bool) {
        self.thumbnails_on = on;
        self.thumbnails_due = true;
        if let Err(e) = self.read_thumbnails() {
            self.error = Some(e);
        }
    }

    /// Reads the node thumbnails back when they are on and due: after a change, or a
    /// second after the last ones while frames keep coming.
    fn read_thumbnails(&mut self) -> Result<(), String> {
        if !self.thumbnails_on {
            self.thumbnails.clear();
            return Ok(());
        }
        let due = self.thumbnails_due
            || self
                .thumbnails_at
                .is_none_or(|t| t.elapsed() >= std::time::Duration::from_secs(1));
        let Some(exec) = self.exec.as_ref().filter(|_| due) else {
            return Ok(());
        };
        let plan = exec.plan();
        let n = plan.passes.len();
        let mut thumbnails = BTreeMap::new();
        for (i, pass) in plan.passes.iter().enumerate() {
            // The first output kept alive to the end of the frame (the preview keeps every
            // output that feeds a sink or the previewed port).
            let Some(t) = plan.textures.iter().find(|t| t.first == i && t.last >= n) else {
                continue;
            };
            let image = shrink(&exec.read(t.id).map_err(|e| e.to_string())?, THUMBNAIL_SIZE);
            let mut thumbnail = Thumbnail {
                port: t.name.clone(),
                width: image.width,
                height: image.height,
                rgba: encode_rgba8(&image, t.ty),
                texture: None,
            };
            // Keep the texture handle: it is updated in place.
            if let Some(old) = self.thumbnails.get_mut(&pass.node) {
                thumbnail.texture = old.texture.take();
            }
            thumbnails.insert(pass.node.clone(), thumbnail);
        }
        // Textures of the old pictures are re-uploaded from the new ones.
        for t in thumbnails.values_mut() {
            if let Some(tex) = &mut t.texture {
                let color = egui::ColorImage::from_rgba_unmultiplied(
                    [t.width as usize, t.height as usize],
                    &t.rgba,
                );
                tex.set(color, egui::TextureOptions::LINEAR);
            }
        }
        self.thumbnails = thumbnails;
        self.thumbnails_at = Some(Instant::now());
        self.thumbnails_due = false;
        Ok(())
    }

    /// The node thumbnails as egui textures (uploaded on first use), by node id: texture
    /// and size in points.
    pub fn thumbnail_textures(
        &mut self,
        ctx: &egui::Context,
    ) -> BTreeMap<String, (egui::TextureId, egui::Vec2)> {
        self.thumbnails
            .iter_mut()
            .map(|(node, t)| {
                let tex = t.texture.get_or_insert_with(|| {
                    let color = egui::ColorImage::from_rgba_unmultiplied(
                        [t.width as usize, t.height as usize],
                        &t.rgba,
                    );
                    ctx.load_texture(
                        format!("thumbnail {node}"),
                        color,
                        egui::TextureOptions::LINEAR,
                    )
                });
                let size = egui::vec2(t.width as f32, t.height as f32);
                (node.clone(), (tex.id(), size))
            })
            .collect()
    }

    /// The egui texture of the last image, uploaded when it changed.
    pub fn texture(&mut self, ctx: &egui::Context) -> Option<&egui::TextureHandle> {
        let image = self.image.as_ref()?;
        if self.texture_stale || self.texture.is_none() {
            let color = egui::ColorImage::from_rgba_unmultiplied(
                [image.width as usize, image.height as usize],
                &image.rgba,
            );
            let options = egui::TextureOptions::LINEAR;
            match &mut self.texture {
                Some(t) => t.set(color, options),
                None => self.texture = Some(ctx.load_texture("preview", color, options)),
            }
            self.texture_stale = false;
        }
        self.texture.as_ref()
    }
}
