//! The editor window: menus, canvas, inspector, preview, status line, file dialogs.
//!
//! [`Editor`] is independent of eframe (it draws into any [`egui::Ui`]), so the tests
//! drive exactly this type headless with `egui_kittest`; [`EditorApp`] adapts it to
//! eframe's `App`, adding the window title and the unsaved-changes prompt on close.
//!
//! This file holds the editor's state, its frame (`ui`), shortcuts and error marks; by
//! concern, `io` opens and saves graphs and scenes (file dialog, unsaved-changes prompt),
//! `selection` handles selection, copy, paste and the previewed port, `panels` draws the
//! side panel, scene line and status bar, and `menus` the menu bar.

use std::borrow::Cow;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use egui::{Key, Modifiers, Ui, ViewportCommand};
use lumagraph_graph::Graph;
use lumagraph_render::{GpuContext, NodeLibrary};

use crate::canvas::{Canvas, CanvasEvent, NodeInfo};
use crate::document::Document;
use crate::files::Recent;
use crate::preview::{Preview, PreviewScene};

mod groups;
mod io;
mod menus;
mod panels;
mod reload;
mod scene_panel;
mod selection;

pub use scene_panel::{RenderForm, SideTab};

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
    /// The node kinds the menus offer and the preview runs (with those a graph file
    /// declares); the default is the built-in ones.
    pub library: Arc<NodeLibrary>,
    /// Show a picture of each node's output on the node; `None`: on unless the adapter
    /// is a CPU one (reading every output back costs there).
    pub thumbnails: Option<bool>,
}

impl Default for EditorConfig {
    fn default() -> Self {
        Self {
            recent_store: None,
            scene: None,
            preview_max: DEFAULT_PREVIEW_MAX,
            library: Arc::new(lumagraph_pathtrace::library::builtins().clone()),
            thumbnails: None,
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
    /// The file's text and values, as edited in the scene panel.
    pub doc: crate::scene_doc::SceneDoc,
    /// The values and furnace view `preview` was built from.
    built: (lumagraph_scene::file::SceneFile, bool),
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
    /// The file of a group made from the selected nodes.
    GroupFile,
    /// The scene's environment map.
    EnvironmentMap,
    /// Where to write the live error plot's points (CSV).
    ErrorCsv,
    /// An OpenColorIO config (`config.ocio`) for the viewer's display transform.
    OcioConfig,
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
    /// The files the kinds come from, checked for changes (live reload).
    pub watch: reload::Watch,
    /// The graphs around the group being edited, the outermost first (empty when no
    /// group is open).
    pub outer: Vec<groups::Outer>,
    /// The node canvas.
    pub canvas: Canvas,
    /// The live preview.
    pub preview: Preview,
    /// The scope under the preview.
    pub scope: crate::scope::ScopeView,
    /// The preview's image viewer: zoom, readout, exposure, A/B compare.
    pub view: crate::viewer::ImageView,
    /// The frame the preview shows of an image sequence (view state: never saved).
    pub sequence: crate::sequence::Sequence,
    /// Selected node ids.
    pub selected: Vec<String>,
    /// The frame selected (its title clicked), shown in the inspector while no node is.
    pub selected_frame: Option<usize>,
    /// Node moves snap to a grid of [`crate::canvas::GRID`] graph units when a drag ends.
    pub snap: bool,
    /// The preview drawn large, in place of the canvas.
    pub big_viewer: bool,
    /// The preview drawn large in a window of its own (embedded as an egui window where
    /// the backend has one window only).
    pub viewer_window: bool,
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
    /// The tab shown under the preview.
    pub side_tab: SideTab,
    /// The Render to file settings.
    pub render_form: RenderForm,
    /// The last Render to file, running or ended.
    pub render_job: Option<crate::render_job::RenderJob>,
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
            doc: Document::with_library(Graph::new(), None, Arc::clone(&config.library)),
            outer: Vec::new(),
            watch: reload::Watch::default(),
            canvas: Canvas::default(),
            preview: Preview::with_library(gpu, Arc::clone(&config.library)),
            scope: crate::scope::ScopeView::default(),
            view: crate::viewer::ImageView::new(),
            sequence: crate::sequence::Sequence::default(),
            selected: Vec::new(),
            selected_frame: None,
            snap: false,
            big_viewer: false,
            viewer_window: false,
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
            side_tab: SideTab::default(),
            render_form: RenderForm::default(),
            render_job: None,
        };
        editor.preview.thumbnails_on = config.thumbnails.unwrap_or_else(|| {
            editor.preview.gpu().adapter.get_info().device_type != wgpu::DeviceType::Cpu
        });
        if let Some(p) = graph {
            editor.open(p);
        }
        if let Some(s) = &config.scene {
            editor.load_scene(s);
        }
        editor
    }

    fn say(&mut self, text: impl Into<String>, error: bool) {
        self.message = Some((text.into(), error));
        self.message_time = f64::NAN; // stamped with egui's clock on the next frame
    }

    /// Finds the params with a frame pattern and the frames on disk (see
    /// [`crate::sequence`]) in the graph the preview runs; says when no frame is found.
    fn refresh_sequence(&mut self) {
        let said = match self.group_context() {
            Some(Ok(c)) => self.sequence.refresh(&c.graph, &c.registry, &c.base),
            Some(Err(_)) => None,
            None => {
                let base = self.doc.base_dir();
                self.sequence
                    .refresh(&self.doc.graph, self.doc.registry(), &base)
            }
        };
        if let Some(message) = said {
            self.say(message, true);
        }
    }

    /// `graph` (the document's or, in a group, the graph around it) at the sequence's
    /// current frame ([`crate::sequence`]).
    pub fn at_frame<'g>(&self, graph: &'g Graph) -> Cow<'g, Graph> {
        self.sequence.at(graph)
    }

    /// Recompiles the full graph (with its sinks) for error marks when it changed.
    fn refresh_errors(&mut self) {
        let mut key = self.at_frame(&self.doc.graph).into_owned();
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
        if !self.watch.errors.is_empty() {
            // A reload failed: the last good kinds are in use, the errors on their nodes.
            self.add_reload_errors();
        } else if !self.doc.graph.kinds.is_empty()
            && let Err(errs) = self.doc.library().registry_for(&self.doc.graph)
        {
            // Declared kinds that fail (their nodes are then of an unknown kind).
            self.graph_errors
                .extend(errs.0.iter().map(ToString::to_string));
        }
        let base = self.doc.base_dir();
        let scene = self.scene.as_ref().map(|s| &*s.preview.gpu);
        let library = self.doc.library().clone();
        let context = self.group_context();
        let result = match &context {
            Some(Ok(c)) => library
                .compile_with(&self.at_frame(&c.graph), &c.registry, &c.base, &[], scene)
                .map(|_| ()),
            Some(Err(e)) => {
                self.graph_errors.push(e.clone());
                Ok(())
            }
            None => library
                .compile_with(&key.0, self.doc.registry(), &base, &[], scene)
                .map(|_| ()),
        };
        let prefix = match &context {
            Some(Ok(c)) => c.prefix.as_str(),
            _ => "",
        };
        if let Err(errs) = result {
            for e in errs.0 {
                // Inside a group: errors of its nodes, by their ids in the group.
                let node = e.about.as_deref().map(|n| n.strip_prefix(prefix).ok_or(n));
                match node {
                    Some(Ok(n)) => self
                        .errors
                        .entry(n.to_owned())
                        .or_default()
                        .push(e.kind.to_string()),
                    Some(Err(n)) => self.graph_errors.push(format!("{n}: {}", e.kind)),
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
        if ctx.input_mut(|i| i.consume_key(cmd | Modifiers::SHIFT, Key::S)) {
            self.save_scene();
        }
        if ctx.input_mut(|i| i.consume_key(cmd, Key::R)) {
            self.side_tab = SideTab::Scene;
        }
        if ctx.input_mut(|i| i.consume_key(cmd, Key::S)) {
            self.save_or_ask();
        }
        if ctx.input_mut(|i| i.consume_key(cmd, Key::O)) {
            self.ask(Then::Open(PathBuf::new()));
        }
        if !typing && ctx.input_mut(|i| i.consume_key(Modifiers::NONE, Key::Home)) {
            self.canvas.request_frame(crate::canvas::Frame::All);
        }
        if !typing && ctx.input_mut(|i| i.consume_key(Modifiers::NONE, Key::F)) {
            self.canvas.request_frame(if self.selected.is_empty() {
                crate::canvas::Frame::All
            } else {
                crate::canvas::Frame::Nodes(self.selected.clone())
            });
        }
        if !typing && ctx.input_mut(|i| i.consume_key(cmd, Key::D)) {
            self.duplicate_selection();
        }
        if !typing && ctx.input_mut(|i| i.consume_key(cmd, Key::G)) {
            self.ask_group_selection();
        }
        if ctx.input_mut(|i| i.consume_key(cmd, Key::Space)) {
            self.big_viewer = !self.big_viewer;
            self.viewer_window = false;
        }
        if !typing && ctx.input_mut(|i| i.consume_key(cmd, Key::J)) {
            self.frame_selection();
        }
        if !typing && ctx.input_mut(|i| i.consume_key(Modifiers::NONE, Key::Tab)) {
            self.toggle_group();
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

    /// Draws the whole editor into `ui` and handles its input.
    pub fn ui(&mut self, ui: &mut Ui) {
        let now = ui.input(|i| i.time);
        if self.message_time.is_nan() {
            self.message_time = now;
        }
        self.shortcuts(ui);
        self.poll_files(now);
        let dragging = ui.input(|i| i.pointer.any_down());
        self.apply_scene_edits(dragging);
        self.refresh_sequence();
        if self.sequence.play(ui.ctx().cumulative_frame_nr()) {
            ui.ctx().request_repaint();
        }
        self.refresh_errors();
        let port = self.effective_port();
        let scene = self.scene.as_ref().map(|s| &s.preview);
        // Inside a group, the preview runs the graph around it.
        let ran = match self.group_context() {
            Some(Ok(c)) => {
                let inner = port.as_deref().map(|p| format!("{}{p}", c.prefix));
                let graph = self.sequence.at(&c.graph);
                let ran =
                    self.preview
                        .update(&c.registry, &graph, &c.base, inner.as_deref(), scene);
                if let Some(p) = inner.as_deref()
                    && !ran
                    && self.preview.wants_frames()
                {
                    let _ = self.preview.step(p);
                }
                true
            }
            _ => {
                let base = self.doc.base_dir();
                let graph = self.sequence.at(&self.doc.graph);
                self.preview
                    .update(self.doc.registry(), &graph, &base, port.as_deref(), scene)
            }
        };
        if let Some(p) = port.as_deref()
            && !ran
            && self.preview.wants_frames()
        {
            let _ = self.preview.step(p);
        }
        if let Some(message) = self.preview.reopen_if_lost() {
            self.message = Some((message, true));
            ui.ctx().request_repaint();
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
            if self.big_viewer && self.preview.linear.is_some() && self.preview.error.is_none() {
                self.large_viewer(ui, port.as_deref());
                return;
            }
            let thumbnails = self.preview.thumbnail_textures(ui.ctx());
            let info = NodeInfo {
                thumbnails: &thumbnails,
                errors: &self.errors,
                pass_ms: &self.preview.pass_ms,
                preview: port.as_deref(),
                selected: &self.selected,
                selected_frame: self.selected_frame,
            };
            self.canvas.snap = self.snap;
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
                    CanvasEvent::SelectFrame(i) => {
                        self.select(Vec::new());
                        self.selected_frame = Some(i);
                    }
                }
            }
        });
        if self.viewer_window && self.preview.linear.is_some() {
            let ctx = ui.ctx().clone();
            ctx.show_viewport_immediate(
                egui::ViewportId::from_hash_of("lumagraph viewer"),
                egui::ViewportBuilder::default()
                    .with_title("lumagraph viewer")
                    .with_inner_size([900.0, 640.0]),
                |ui, _class| {
                    egui::CentralPanel::default().show(ui, |ui| {
                        self.large_viewer(ui, port.as_deref());
                    });
                    if ui.input(|i| i.viewport().close_requested()) {
                        self.viewer_window = false;
                    }
                },
            );
        }
        self.refusal_tooltip(ui, now);
        self.dialogs(ui);
        self.file_dialog_ui(&ui.ctx().clone());
        // A gesture (a slider or node drag, a snap on release) ends after the frame in which
        // no pointer is down: its edits are one undo step.
        if !ui.input(|i| i.pointer.any_down()) {
            self.doc.end_gesture();
        }
    }

    /// Handles a close request from the window: returns whether to let it close.
    pub fn on_close_requested(&mut self) -> bool {
        let dirty = self.doc.is_dirty()
            || self.outer.iter().any(|o| o.doc.is_dirty())
            || self.scene.as_ref().is_some_and(|s| s.doc.is_dirty());
        if self.quit_confirmed || !dirty {
            return true;
        }
        while self.leave_group() {}
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
