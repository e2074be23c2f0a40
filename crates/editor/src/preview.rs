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
//! Progressive sources: a future `PathTrace` node keeps its accumulation inside its own
//! `NodeExec`. Because a param edit downstream only calls `update` on the nodes whose
//! params changed, the executor (and the accumulation) survives; the editor then only has
//! to keep calling [`Preview::run_frame`] while a node reports it is still converging.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use lumagraph_graph::{CompileOptions, Graph, Node, Params, Plan, PortType, Registry};
use lumagraph_render::cpu::{srgb_encode, to_u8};
use lumagraph_render::{Executor, GpuContext, Resources, source_extent};

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
}

/// The preview state.
pub struct Preview {
    gpu: GpuContext,
    exec: Option<Executor>,
    key: Option<(Graph, String, PathBuf)>,
    /// The last image.
    pub image: Option<PreviewImage>,
    texture: Option<egui::TextureHandle>,
    texture_stale: bool,
    /// GPU ms per node of the last frame (empty without timestamp queries).
    pub pass_ms: BTreeMap<String, f64>,
    /// Why there is no preview, when there is none.
    pub error: Option<String>,
    /// Counters.
    pub stats: PreviewStats,
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
pub fn preview_graph(graph: &Graph) -> Graph {
    let reg = Registry::builtin();
    let is_sink = |id: &str| {
        graph
            .node(id)
            .and_then(|n| reg.get(&n.kind))
            .is_some_and(|k| k.sink)
    };
    let mut g = graph.clone();
    g.nodes.retain(|n| !is_sink(&n.id));
    g.edges
        .retain(|e| lumagraph_graph::split_port_ref(&e.to).is_some_and(|(n, _)| !is_sink(n)));
    for n in &mut g.nodes {
        n.pos = None;
    }
    g
}

/// Compiles the preview graph of `graph`, keeping `port`.
///
/// # Errors
/// The compiler's messages, one a line.
pub fn compile_preview(graph: &Graph, base: &Path, port: &str) -> Result<Plan, String> {
    let g = preview_graph(graph);
    let extent = |node: &Node, params: &Params| source_extent(base, None, node, params);
    let keep = [port.to_owned()];
    lumagraph_graph::compile(
        &g,
        Registry::builtin(),
        &CompileOptions {
            source_extent: &extent,
            keep: &keep,
        },
    )
    .map_err(|e| {
        e.0.iter()
            .map(|e| match &e.node {
                Some(n) => format!("{n}: {}", e.kind),
                None => e.kind.to_string(),
            })
            .collect::<Vec<_>>()
            .join("\n")
    })
}

/// Converts read-back texels to 8-bit RGBA the way the Output node writes a PNG.
pub fn encode_rgba8(image: &lumagraph_render::cpu::Image, ty: PortType) -> Vec<u8> {
    let linear = ty != PortType::LdrColor;
    let encode = |x: f32| if linear { srgb_encode(x) } else { x };
    image
        .pixels
        .iter()
        .flat_map(|p| {
            [
                to_u8(encode(p[0])),
                to_u8(encode(p[1])),
                to_u8(encode(p[2])),
                to_u8(p[3]),
            ]
        })
        .collect()
}

impl Preview {
    /// A preview rendering on `gpu` (the editor's device).
    pub fn new(gpu: GpuContext) -> Self {
        Self {
            gpu,
            exec: None,
            key: None,
            image: None,
            texture: None,
            texture_stale: false,
            pass_ms: BTreeMap::new(),
            error: None,
            stats: PreviewStats::default(),
        }
    }

    /// The GPU context.
    pub fn gpu(&self) -> &GpuContext {
        &self.gpu
    }

    /// Brings the preview up to date with `graph` showing `port`; does nothing when
    /// neither changed (node positions do not count). Returns whether a frame ran.
    pub fn update(&mut self, graph: &Graph, base: &Path, port: Option<&str>) -> bool {
        let Some(port) = port else {
            self.clear(Some("select a node with an output to preview it".into()));
            return false;
        };
        let mut g = preview_graph(graph);
        g.origin = None;
        let key = (g, port.to_owned(), base.to_owned());
        if self.key.as_ref() == Some(&key) {
            return false;
        }
        self.key = Some(key);
        match self.render(graph, base, port) {
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

    fn clear(&mut self, error: Option<String>) {
        self.key = None;
        self.image = None;
        self.texture = None;
        self.pass_ms.clear();
        self.error = error;
    }

    fn render(&mut self, graph: &Graph, base: &Path, port: &str) -> Result<(), String> {
        let plan = compile_preview(graph, base, port)?;
        let updated = match &mut self.exec {
            Some(exec) => exec
                .update_params(plan.clone())
                .map_err(|e| e.to_string())?,
            None => false,
        };
        if updated {
            self.stats.param_updates += 1;
        } else {
            self.exec = None;
            let paths = Resources {
                base_dir: base.to_owned(),
                out_dir: base.to_owned(),
                ..Resources::default()
            };
            let exec = Executor::new(&self.gpu, plan, &paths).map_err(|e| e.to_string())?;
            self.exec = Some(exec);
            self.stats.rebuilds += 1;
        }
        self.run_frame(port)
    }

    /// Runs one frame of the current executor and reads `port` back.
    ///
    /// # Errors
    /// When the frame or the readback fails.
    pub fn run_frame(&mut self, port: &str) -> Result<(), String> {
        let Some(exec) = &mut self.exec else {
            return Err("nothing to run".into());
        };
        let result = (|| {
            let report = exec.run_frame().map_err(|e| e.to_string())?;
            let t = Instant::now();
            let ty = exec
                .plan()
                .textures
                .iter()
                .find(|t| t.name == port)
                .map(|t| t.ty)
                .ok_or_else(|| format!("{port} is not computed"))?;
            let image = exec.read_port(port).map_err(|e| e.to_string())?;
            let rgba = encode_rgba8(&image, ty);
            Ok::<_, String>((report, image.width, image.height, rgba, t.elapsed()))
        })();
        let (report, width, height, rgba, readback) = match result {
            Ok(r) => r,
            Err(e) => {
                // A failed frame leaves the executor in an unknown state: rebuild next time.
                self.exec = None;
                return Err(e);
            }
        };
        self.stats.frames += 1;
        self.stats.frame_ms = report.wall.as_secs_f64() * 1e3;
        self.stats.readback_ms = readback.as_secs_f64() * 1e3;
        self.pass_ms = report.pass_ms.unwrap_or_default().into_iter().collect();
        self.image = Some(PreviewImage {
            port: port.to_owned(),
            width,
            height,
            rgba,
        });
        self.texture_stale = true;
        Ok(())
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
