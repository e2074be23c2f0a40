//! The editor window: menus, canvas, inspector, preview, status line, file dialogs.
//!
//! [`Editor`] is independent of eframe (it draws into any [`egui::Ui`]), so the tests
//! drive exactly this type headless with `egui_kittest`; [`EditorApp`] adapts it to
//! eframe's `App`, adding the window title and the unsaved-changes prompt on close.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use egui::{Color32, Key, Modifiers, Ui, ViewportCommand};
use lumagraph_graph::{CompileOptions, Graph, Node, Params, Registry, split_port_ref};
use lumagraph_render::{GpuContext, source_extent};

use crate::canvas::{Canvas, CanvasEvent, NodeInfo};
use crate::document::Document;
use crate::files::{self, Recent};
use crate::preview::{Preview, PreviewScene};
use crate::{EditorError, inspector};

mod menus;

/// The largest preview side, in pixels, for nodes that render a scene, unless
/// [`EditorConfig::preview_max`] says otherwise.
pub const DEFAULT_PREVIEW_MAX: u32 = 256;

/// Settings that differ between the real window and the tests.
#[derive(Clone, Debug)]
pub struct EditorConfig {
    /// Where the recent-files list lives; `None` keeps it in memory only.
    pub recent_store: Option<PathBuf>,
    /// The scene to open with the graph, if any.
    pub scene: Option<PathBuf>,
    /// The preview renders scenes with their longer side at most this many pixels (the
    /// scene's aspect kept); `lumagraph render` uses the scene's full resolution.
    pub preview_max: u32,
}

impl Default for EditorConfig {
    fn default() -> Self {
        Self {
            recent_store: None,
            scene: None,
            preview_max: DEFAULT_PREVIEW_MAX,
        }
    }
}

/// A scene loaded in the editor.
#[derive(Clone, Debug)]
pub struct EditorScene {
    /// Its file.
    pub path: PathBuf,
    /// The resolution the scene file asks for.
    pub full: (u32, u32),
    /// The scene as the preview renders it (resolution capped).
    pub preview: PreviewScene,
}

/// What a file picked in the file dialog is for.
#[derive(Clone, Debug, PartialEq)]
pub enum Pick {
    /// A graph to open.
    OpenGraph,
    /// Where to save the graph.
    SaveGraph,
    /// A scene to render.
    Scene,
    /// A path param: node id and param name.
    Param(String, String),
}

/// A question waiting in a modal dialog.
#[derive(Clone, Debug, PartialEq)]
enum Dialog {
    /// Unsaved changes: save, discard or cancel before `then`.
    Unsaved(Then),
}

#[derive(Clone, Debug, PartialEq)]
enum Then {
    Quit,
    New,
    Open(PathBuf),
}

/// The editor: a document, its views and the preview.
pub struct Editor {
    /// The graph being edited and its file.
    pub doc: Document,
    /// The node canvas.
    pub canvas: Canvas,
    /// The live preview.
    pub preview: Preview,
    /// Selected node ids.
    pub selected: Vec<String>,
    /// The port chosen for preview (`"node.port"`); `None` follows the selection.
    pub preview_port: Option<String>,
    /// Compile errors per node id (messages without file locations).
    pub errors: BTreeMap<String, Vec<String>>,
    /// Compile errors not tied to a node.
    pub graph_errors: Vec<String>,
    errors_for: Option<(Graph, u64)>,
    /// The last status message and whether it is an error.
    pub message: Option<(String, bool)>,
    message_time: f64,
    /// Recently used files.
    pub recent: Recent,
    clipboard: Option<Graph>,
    dialog: Option<Dialog>,
    /// What to do once the graph is saved through the file dialog (Save in the
    /// unsaved-changes prompt of an untitled graph).
    after_save: Option<Then>,
    /// Set when the window may close even with unsaved changes.
    pub quit_confirmed: bool,
    /// Set when the editor asked the window to close.
    pub wants_close: bool,
    /// The scene nodes such as `PathTrace` render, when one is loaded.
    pub scene: Option<EditorScene>,
    /// Why the last scene could not be loaded.
    pub scene_error: Option<String>,
    scene_generation: u64,
    preview_max: u32,
    /// The open file dialog and what its pick is for.
    pub file_dialog: Option<(Pick, egui_file_dialog::FileDialog)>,
}

impl std::fmt::Debug for Editor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Editor")
            .field("path", &self.doc.path)
            .field("selected", &self.selected)
            .finish_non_exhaustive()
    }
}

impl Editor {
    /// An editor rendering on `gpu`, opening `graph` when given. A file that cannot be
    /// opened leaves an empty graph and the error in the status line.
    pub fn new(gpu: GpuContext, graph: Option<&Path>, config: &EditorConfig) -> Self {
        let mut editor = Self {
            doc: Document::default(),
            canvas: Canvas::default(),
            preview: Preview::new(gpu),
            selected: Vec::new(),
            preview_port: None,
            errors: BTreeMap::new(),
            graph_errors: Vec::new(),
            errors_for: None,
            message: None,
            message_time: 0.0,
            recent: Recent::load(config.recent_store.clone()),
            clipboard: None,
            dialog: None,
            quit_confirmed: false,
            wants_close: false,
            scene: None,
            scene_error: None,
            scene_generation: 0,
            preview_max: config.preview_max.max(1),
            file_dialog: None,
            after_save: None,
        };
        if let Some(p) = graph {
            editor.open(p);
        }
        if let Some(s) = &config.scene {
            editor.load_scene(s);
        }
        editor
    }

    /// Loads the scene that `PathTrace` and `GBuffer` nodes render, restarting the
    /// preview. A scene that cannot be loaded leaves the current one (if any) and the
    /// error in the status line and the side panel. Returns whether it loaded.
    pub fn load_scene(&mut self, path: &Path) -> bool {
        let loaded = lumagraph_scene::Scene::load(path)
            .and_then(|scene| lumagraph_scene::GpuScene::build(&scene));
        match loaded {
            Ok(mut gpu) => {
                let full = (gpu.settings.width, gpu.settings.height);
                let longest = full.0.max(full.1).max(1);
                if longest > self.preview_max {
                    let scale = |x: u32| {
                        u32::try_from(
                            u64::from(x) * u64::from(self.preview_max) / u64::from(longest),
                        )
                        .unwrap_or(1)
                        .max(1)
                    };
                    gpu.settings.width = scale(full.0);
                    gpu.settings.height = scale(full.1);
                }
                self.scene_generation += 1;
                self.scene = Some(EditorScene {
                    path: path.to_owned(),
                    full,
                    preview: PreviewScene {
                        gpu: Arc::new(gpu),
                        generation: self.scene_generation,
                    },
                });
                self.scene_error = None;
                self.errors_for = None;
                self.say(format!("scene {}", path.display()), false);
                true
            }
            Err(e) => {
                let text = format!("cannot load the scene: {e}");
                self.scene_error = Some(text.clone());
                self.say(text, true);
                false
            }
        }
    }

    /// Removes the scene; nodes that render one then show an error.
    pub fn close_scene(&mut self) {
        self.scene = None;
        self.scene_error = None;
        self.errors_for = None;
        self.scene_generation += 1;
    }

    /// Opens the file dialog for `pick`, starting in the folder that fits it.
    pub fn open_file_dialog(&mut self, pick: Pick) {
        use egui_file_dialog::FileDialog;
        let base = self.doc.base_dir();
        let start = |p: Option<&Path>| {
            p.and_then(Path::parent)
                .filter(|d| !d.as_os_str().is_empty())
                .map_or_else(|| base.clone(), Path::to_path_buf)
        };
        let (title, dir, extensions): (&str, PathBuf, Vec<&'static str>) = match &pick {
            Pick::OpenGraph => ("Open graph", start(self.doc.path.as_deref()), vec!["ron"]),
            Pick::SaveGraph => (
                "Save graph as",
                start(self.doc.path.as_deref()),
                vec!["ron"],
            ),
            Pick::Scene => (
                "Open scene",
                start(self.scene.as_ref().map(|s| s.path.as_path())),
                vec!["ron"],
            ),
            Pick::Param(node, param) => {
                let extensions = self
                    .doc
                    .graph
                    .node(node)
                    .and_then(|n| Registry::builtin().get(&n.kind))
                    .and_then(|k| k.params.iter().find(|d| d.name == param))
                    .and_then(|d| match &d.ty {
                        lumagraph_graph::ParamType::Path { extensions, .. } => {
                            Some(extensions.to_vec())
                        }
                        _ => None,
                    })
                    .unwrap_or_default();
                let current = self
                    .doc
                    .graph
                    .node(node)
                    .and_then(|n| n.params.get(param.as_str()))
                    .and_then(|v| match v {
                        lumagraph_graph::ParamValue::Str(s) => Some(base.join(s)),
                        _ => None,
                    });
                ("Pick a file", start(current.as_deref()), extensions)
            }
        };
        let dir = std::path::absolute(&dir).unwrap_or(dir);
        let name = extensions
            .iter()
            .map(|e| format!(".{e}"))
            .collect::<Vec<_>>()
            .join(" ");
        let mut dialog = FileDialog::new()
            .title(title)
            .id(egui::Id::new("file_dialog"))
            .initial_directory(dir);
        if !extensions.is_empty() {
            dialog = dialog
                .add_file_filter_extensions(&name, extensions.clone())
                .default_file_filter(&name);
        }
        if pick == Pick::SaveGraph {
            dialog = dialog
                .add_save_extension("graph", "ron")
                .default_save_extension("graph")
                .default_file_name(
                    &self
                        .doc
                        .path
                        .as_deref()
                        .and_then(Path::file_name)
                        .map_or_else(
                            || "untitled.ron".to_owned(),
                            |n| n.to_string_lossy().into_owned(),
                        ),
                );
            dialog.save_file();
        } else {
            dialog.pick_file();
        }
        self.file_dialog = Some((pick, dialog));
    }

    /// Applies a path picked in the file dialog for `pick`: opens, saves, loads the scene,
    /// or sets the param (an undoable edit, relative to the graph's folder when inside it).
    pub fn apply_pick(&mut self, pick: &Pick, path: &Path) {
        match pick {
            Pick::OpenGraph => self.ask(Then::Open(path.to_owned())),
            Pick::SaveGraph => match self.save_as(path) {
                Ok(()) => {
                    if let Some(then) = self.after_save.take() {
                        self.proceed(then);
                    }
                }
                Err(e) => {
                    self.after_save = None;
                    self.say(e.to_string(), true);
                }
            },
            Pick::Scene => {
                self.load_scene(path);
            }
            Pick::Param(node, param) => {
                let base = std::path::absolute(self.doc.base_dir()).unwrap_or_default();
                let value = path
                    .strip_prefix(&base)
                    .map_or_else(|_| path.display().to_string(), |p| p.display().to_string());
                self.doc
                    .set_param(node, param, lumagraph_graph::ParamValue::Str(value));
                self.doc.end_gesture();
            }
        }
    }

    fn file_dialog_ui(&mut self, ctx: &egui::Context) {
        let Some((pick, dialog)) = &mut self.file_dialog else {
            return;
        };
        dialog.update(ctx);
        match dialog.state() {
            egui_file_dialog::DialogState::Picked(path) => {
                let (pick, path) = (pick.clone(), path.clone());
                self.file_dialog = None;
                self.apply_pick(&pick, &path);
            }
            egui_file_dialog::DialogState::Open => {}
            _ => {
                // Cancelled: whatever waited for a save does not happen.
                self.file_dialog = None;
                self.after_save = None;
            }
        }
    }

    fn say(&mut self, text: impl Into<String>, error: bool) {
        self.message = Some((text.into(), error));
        self.message_time = f64::NAN; // stamped with egui's clock on the next frame
    }

    /// Opens a graph file in place of the current one (no unsaved-changes check).
    pub fn open(&mut self, path: &Path) {
        match files::open(path) {
            Ok(graph) => {
                self.doc.replace(graph, Some(path.to_owned()));
                self.selected.clear();
                self.preview_port = None;
                if let Err(e) = self.recent.add(path) {
                    self.say(e.to_string(), true);
                } else {
                    self.say(format!("opened {}", path.display()), false);
                }
            }
            Err(e) => {
                self.doc.replace(Graph::new(), None);
                self.say(format!("cannot open: {e}"), true);
            }
        }
    }

    /// Saves to the current file.
    ///
    /// # Errors
    /// When there is no file yet or it cannot be written.
    pub fn save(&mut self) -> Result<(), EditorError> {
        let path = self.doc.path.clone().ok_or(EditorError::NoPath)?;
        self.save_as(&path)
    }

    /// Saves to `path` (atomically), which becomes the document's file.
    ///
    /// # Errors
    /// When the file cannot be written.
    pub fn save_as(&mut self, path: &Path) -> Result<(), EditorError> {
        let saved = files::save(&self.doc.graph, &self.doc.base_dir(), path)?;
        let origin = self.doc.graph.origin.take();
        self.doc.graph = saved;
        self.doc.graph.origin = origin;
        self.doc.mark_saved(path.to_owned());
        let _ = self.recent.add(path);
        self.say(format!("saved {}", path.display()), false);
        Ok(())
    }

    /// The window title: file name, a `●` when there are unsaved changes.
    pub fn title(&self) -> String {
        let name = self.doc.path.as_deref().map_or_else(
            || "untitled".to_owned(),
            |p| {
                p.file_name().map_or_else(
                    || p.display().to_string(),
                    |n| n.to_string_lossy().into_owned(),
                )
            },
        );
        let dirty = if self.doc.is_dirty() { "● " } else { "" };
        format!("{dirty}{name} — lumagraph editor")
    }

    /// Selects nodes (as a click on the canvas would) and previews the first one.
    pub fn select(&mut self, ids: Vec<String>) {
        if let Some(first) = ids.first() {
            // Keep a port of this node chosen by clicking its pin; else its first output.
            let chosen_here = self
                .preview_port
                .as_deref()
                .and_then(split_port_ref)
                .is_some_and(|(n, _)| n == first);
            if !chosen_here {
                self.preview_port = self.port_for_node(first);
            }
        }
        self.selected = ids;
    }

    /// The port previewed for node `id`: its first output, or what feeds a sink.
    fn port_for_node(&self, id: &str) -> Option<String> {
        let node = self.doc.graph.node(id)?;
        let kind = Registry::builtin().get(&node.kind)?;
        if let Some(o) = kind.outputs.first() {
            return Some(format!("{id}.{}", o.name));
        }
        let input = kind.inputs.first()?;
        let to = format!("{id}.{}", input.name);
        self.doc
            .graph
            .edges
            .iter()
            .find(|e| e.to == to)
            .map(|e| e.from.clone())
    }

    /// The port the preview shows: the chosen one if it still exists, else what feeds
    /// the first sink.
    pub fn effective_port(&self) -> Option<String> {
        let exists = |p: &str| {
            split_port_ref(p).is_some_and(|(n, port)| {
                self.doc
                    .graph
                    .node(n)
                    .and_then(|n| Registry::builtin().get(&n.kind))
                    .is_some_and(|k| k.output(port).is_some())
            })
        };
        if let Some(p) = self.preview_port.as_deref().filter(|p| exists(p)) {
            return Some(p.to_owned());
        }
        let reg = Registry::builtin();
        self.doc
            .graph
            .nodes
            .iter()
            .filter(|n| reg.get(&n.kind).is_some_and(|k| k.sink))
            .find_map(|n| self.port_for_node(&n.id))
    }

    /// Copies the selected nodes (and the edges between them) to the editor's clipboard;
    /// returns the copy as RON text for the system clipboard.
    pub fn copy_selection(&mut self) -> Option<String> {
        if self.selected.is_empty() {
            return None;
        }
        let clip = self.doc.copy(&self.selected);
        let text = clip.to_ron();
        self.clipboard = Some(clip);
        Some(text)
    }

    /// Pastes `text` when it is a graph, else the editor's clipboard; selects the copies.
    pub fn paste(&mut self, text: Option<&str>) {
        let clip = text
            .and_then(|t| Graph::from_ron(t).ok())
            .or_else(|| self.clipboard.clone());
        if let Some(clip) = clip {
            let ids = self.doc.paste(&clip, (40.0, 40.0));
            self.say(format!("pasted {}", ids.join(", ")), false);
            self.selected = ids;
        }
    }

    /// Deletes the selected nodes.
    pub fn delete_selection(&mut self) {
        let ids = std::mem::take(&mut self.selected);
        self.doc.remove_nodes(&ids);
    }

    /// Recompiles the full graph (with its sinks) for error marks when it changed.
    fn refresh_errors(&mut self) {
        let mut key = self.doc.graph.clone();
        key.origin = None;
        for n in &mut key.nodes {
            n.pos = None;
        }
        // Another scene changes what nodes that render one can do.
        let key = (key, self.scene_generation);
        if self.errors_for.as_ref() == Some(&key) {
            return;
        }
        self.errors.clear();
        self.graph_errors.clear();
        let base = self.doc.base_dir();
        let scene = self.scene.as_ref().map(|s| &*s.preview.gpu);
        let extent = |node: &Node, params: &Params| source_extent(&base, scene, node, params);
        let result = lumagraph_graph::compile(
            &key.0,
            Registry::builtin(),
            &CompileOptions {
                source_extent: &extent,
                keep: &[],
            },
        );
        if let Err(errs) = result {
            for e in errs.0 {
                match e.node {
                    Some(n) => self.errors.entry(n).or_default().push(e.kind.to_string()),
                    None => self.graph_errors.push(e.kind.to_string()),
                }
            }
        }
        self.errors_for = Some(key);
    }

    fn shortcuts(&mut self, ui: &Ui) {
        let ctx = ui.ctx().clone();
        let typing = ctx.egui_wants_keyboard_input();
        let cmd = Modifiers::COMMAND;
        let mut copy = false;
        let mut paste = None;
        ctx.input(|i| {
            for e in &i.events {
                match e {
                    egui::Event::Copy if !typing => copy = true,
                    egui::Event::Paste(t) if !typing => paste = Some(t.clone()),
                    _ => {}
                }
            }
        });
        if copy && let Some(text) = self.copy_selection() {
            ctx.copy_text(text);
        }
        if let Some(t) = paste {
            self.paste(Some(&t));
        }
        if ctx.input_mut(|i| i.consume_key(cmd | Modifiers::SHIFT, Key::Z))
            || ctx.input_mut(|i| i.consume_key(cmd, Key::Y))
        {
            self.doc.redo();
        }
        if ctx.input_mut(|i| i.consume_key(cmd, Key::Z)) {
            self.doc.undo();
        }
        if ctx.input_mut(|i| i.consume_key(cmd, Key::S)) {
            self.save_or_ask();
        }
        if ctx.input_mut(|i| i.consume_key(cmd, Key::O)) {
            self.ask(Then::Open(PathBuf::new()));
        }
        if !typing
            && ctx.input_mut(|i| {
                i.consume_key(Modifiers::NONE, Key::Delete)
                    || i.consume_key(Modifiers::NONE, Key::Backspace)
            })
        {
            self.delete_selection();
        }
    }

    fn save_or_ask(&mut self) {
        if self.doc.path.is_some() {
            if let Err(e) = self.save() {
                self.say(e.to_string(), true);
            }
        } else {
            self.open_file_dialog(Pick::SaveGraph);
        }
    }

    /// Runs `then`, first asking about unsaved changes when there are some.
    fn ask(&mut self, then: Then) {
        if self.doc.is_dirty() && then != Then::Open(PathBuf::new()) {
            self.dialog = Some(Dialog::Unsaved(then));
        } else {
            self.proceed(then);
        }
    }

    fn proceed(&mut self, then: Then) {
        match then {
            Then::Quit => {
                self.quit_confirmed = true;
                self.wants_close = true;
            }
            Then::New => {
                self.doc.replace(Graph::new(), None);
                self.selected.clear();
            }
            Then::Open(p) if p.as_os_str().is_empty() => self.open_file_dialog(Pick::OpenGraph),
            Then::Open(p) => self.open(&p),
        }
    }

    /// Draws the whole editor into `ui` and handles its input.
    pub fn ui(&mut self, ui: &mut Ui) {
        let now = ui.input(|i| i.time);
        if self.message_time.is_nan() {
            self.message_time = now;
        }
        self.shortcuts(ui);
        if !ui.input(|i| i.pointer.any_down()) {
            self.doc.end_gesture();
        }
        self.refresh_errors();
        let port = self.effective_port();
        let base = self.doc.base_dir();
        let scene = self.scene.as_ref().map(|s| &s.preview);
        let ran = self
            .preview
            .update(&self.doc.graph, &base, port.as_deref(), scene);
        if let Some(p) = port.as_deref()
            && !ran
            && self.preview.wants_frames()
        {
            let _ = self.preview.step(p);
        }
        if self.preview.wants_frames() {
            ui.ctx().request_repaint();
        }

        egui::Panel::top("menu").show(ui, |ui| self.menu_bar(ui));
        egui::Panel::bottom("status").show(ui, |ui| self.status_bar(ui));
        egui::Panel::right("side")
            .default_size(380.0)
            .resizable(true)
            .show(ui, |ui| self.side_panel(ui, port.as_deref()));
        egui::CentralPanel::default().show(ui, |ui| {
            let info = NodeInfo {
                errors: &self.errors,
                pass_ms: &self.preview.pass_ms,
                preview: port.as_deref(),
                selected: &self.selected,
            };
            let events = self.canvas.show(ui, &mut self.doc, &info);
            for e in events {
                match e {
                    CanvasEvent::Select(ids) => self.select(ids),
                    CanvasEvent::Preview(p) => self.preview_port = Some(p),
                    CanvasEvent::Refused(why) => self.say(why, true),
                    CanvasEvent::Delete(ids) => {
                        self.doc.remove_nodes(&ids);
                        self.selected.retain(|s| !ids.contains(s));
                    }
                    CanvasEvent::Added(id) => self.select(vec![id]),
                }
            }
        });
        self.refusal_tooltip(ui, now);
        self.dialogs(ui);
        self.file_dialog_ui(&ui.ctx().clone());
    }

    fn refusal_tooltip(&self, ui: &Ui, now: f64) {
        if let Some((text, true)) = &self.message
            && now - self.message_time < 4.0
            && let Some(pos) = ui.input(|i| i.pointer.latest_pos())
        {
            egui::Area::new(egui::Id::new("refusal"))
                .order(egui::Order::Tooltip)
                .fixed_pos(pos + egui::vec2(16.0, 16.0))
                .show(ui.ctx(), |ui| {
                    egui::Frame::popup(ui.style()).show(ui, |ui| {
                        ui.set_max_width(360.0);
                        ui.colored_label(Color32::from_rgb(240, 90, 90), text);
                    });
                });
            ui.ctx().request_repaint();
        }
    }

    fn status_bar(&self, ui: &mut Ui) {
        ui.horizontal_wrapped(|ui| {
            if let Some((text, error)) = &self.message {
                let color = if *error {
                    Color32::from_rgb(240, 90, 90)
                } else {
                    ui.visuals().text_color()
                };
                ui.colored_label(color, text);
                ui.separator();
            }
            for e in &self.graph_errors {
                ui.colored_label(Color32::from_rgb(240, 90, 90), e);
                ui.separator();
            }
            let n = self.errors.values().map(Vec::len).sum::<usize>();
            if n > 0 {
                ui.colored_label(Color32::from_rgb(240, 90, 90), format!("{n} node error(s)"));
                ui.separator();
            }
            let s = &self.preview.stats;
            ui.weak(format!(
                "preview: frame {:.1} ms, readback {:.1} ms · {} rebuilds, {} param updates, \
                 {} accumulation restarts",
                s.frame_ms, s.readback_ms, s.rebuilds, s.param_updates, s.restarts
            ));
        });
    }

    fn side_panel(&mut self, ui: &mut Ui, port: Option<&str>) {
        ui.heading("Preview");
        self.scene_line(ui);
        match port {
            Some(p) => ui.weak(p),
            None => ui.weak("nothing to preview"),
        };
        let ctx = ui.ctx().clone();
        if let Some(err) = &self.preview.error {
            ui.colored_label(Color32::from_rgb(240, 90, 90), err);
        } else if let Some(tex) = self.preview.texture(&ctx) {
            let size = tex.size_vec2();
            let w = ui.available_width().min(size.x.max(1.0) * 2.0);
            let h = w * size.y / size.x.max(1.0);
            ui.add(egui::Image::new((tex.id(), egui::vec2(w, h))));
            let size = self
                .preview
                .image
                .as_ref()
                .map(|img| format!("{}×{}", img.width, img.height));
            ui.horizontal(|ui| {
                if let Some(size) = size {
                    ui.weak(size);
                }
                if let Some(n) = self.preview.samples {
                    ui.label(format!("{n} spp"))
                        .on_hover_text("samples per pixel accumulated so far");
                }
                if self.preview.progressive {
                    let label = if self.preview.paused {
                        "▶ resume"
                    } else {
                        "⏸ pause"
                    };
                    if ui.button(label).clicked() {
                        self.preview.paused = !self.preview.paused;
                    }
                    if self
                        .preview
                        .samples
                        .is_some_and(|s| s >= self.preview.target_spp)
                    {
                        ui.weak(format!("done (scene spp {})", self.preview.target_spp));
                    }
                }
            });
        }
        ui.separator();
        ui.heading("Inspector");
        egui::ScrollArea::vertical().show(ui, |ui| match self.selected.as_slice() {
            [] => {
                ui.weak("select a node");
            }
            [one] => {
                let id = one.clone();
                let errs = self.errors.get(&id).cloned();
                if let Some(inspector::Request::PickFile(param)) =
                    inspector::show(ui, &mut self.doc, &id, errs.as_ref())
                {
                    self.open_file_dialog(Pick::Param(id, param));
                }
            }
            many => {
                ui.label(format!("{} nodes selected", many.len()));
            }
        });
    }

    fn scene_line(&mut self, ui: &mut Ui) {
        ui.horizontal_wrapped(|ui| {
            match &self.scene {
                Some(s) => {
                    let name = s.path.file_name().map_or_else(
                        || s.path.display().to_string(),
                        |n| n.to_string_lossy().into_owned(),
                    );
                    let g = &s.preview.gpu.settings;
                    ui.label(format!("scene {name}"))
                        .on_hover_text(s.path.display().to_string());
                    ui.weak(format!(
                        "{}×{}, previewed at {}×{}",
                        s.full.0, s.full.1, g.width, g.height
                    ));
                }
                None => {
                    ui.weak("no scene");
                }
            }
            if ui
                .button("Open scene…")
                .on_hover_text("the scene PathTrace and GBuffer nodes render")
                .clicked()
            {
                self.open_file_dialog(Pick::Scene);
            }
        });
        if let Some(e) = &self.scene_error {
            ui.colored_label(Color32::from_rgb(240, 90, 90), e);
        }
    }

    /// Handles a close request from the window: returns whether to let it close.
    pub fn on_close_requested(&mut self) -> bool {
        if self.quit_confirmed || !self.doc.is_dirty() {
            return true;
        }
        self.dialog = Some(Dialog::Unsaved(Then::Quit));
        false
    }
}

/// The eframe application around an [`Editor`].
pub struct EditorApp {
    /// The editor.
    pub editor: Editor,
    title: String,
}

impl EditorApp {
    /// Wraps an editor.
    pub fn new(editor: Editor) -> Self {
        Self {
            editor,
            title: String::new(),
        }
    }
}

impl eframe::App for EditorApp {
    fn ui(&mut self, ui: &mut Ui, _frame: &mut eframe::Frame) {
        let ctx = ui.ctx().clone();
        if ctx.input(|i| i.viewport().close_requested()) && !self.editor.on_close_requested() {
            ctx.send_viewport_cmd(ViewportCommand::CancelClose);
        }
        self.editor.ui(ui);
        if std::mem::take(&mut self.editor.wants_close) {
            ctx.send_viewport_cmd(ViewportCommand::Close);
        }
        let title = self.editor.title();
        if title != self.title {
            ctx.send_viewport_cmd(ViewportCommand::Title(title.clone()));
            self.title = title;
        }
    }
}
