//! Files: opening and saving graphs (atomically), the file dialog, scenes, and the
//! unsaved-changes prompt before a graph is replaced or the window closed.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use lumagraph_graph::Graph;

use super::{Dialog, Editor, EditorScene, Pick, Then};
use crate::EditorError;
use crate::files;
use crate::preview::PreviewScene;
use crate::scene_doc::SceneDoc;
use lumagraph_scene::GpuScene;

impl Editor {
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
            Pick::GroupFile => (
                "Save the group as",
                start(self.doc.path.as_deref()),
                vec!["ron"],
            ),
            Pick::Scene => (
                "Open scene",
                start(self.scene.as_ref().map(|s| s.path.as_path())),
                vec!["ron"],
            ),
            Pick::EnvironmentMap => (
                "Pick the environment map",
                start(self.scene.as_ref().map(|s| s.path.as_path())),
                vec!["hdr", "exr"],
            ),
            Pick::ErrorCsv => (
                "Save the error curve as",
                start(self.doc.path.as_deref()),
                vec!["csv"],
            ),
            Pick::OcioConfig => {
                let current = Path::new(self.view.display.config_spec());
                let file = current.extension().is_some_and(|e| e == "ocio");
                (
                    "Pick an OpenColorIO config",
                    start(file.then_some(current)),
                    vec!["ocio"],
                )
            }
            Pick::Param(node, param) => {
                let extensions = self
                    .doc
                    .graph
                    .node(node)
                    .and_then(|n| self.doc.registry().get(&n.kind))
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
        if pick == Pick::ErrorCsv {
            dialog = dialog
                .add_save_extension("CSV", "csv")
                .default_save_extension("CSV")
                .default_file_name("error.csv");
            dialog.save_file();
        } else if matches!(pick, Pick::SaveGraph | Pick::GroupFile) {
            let name = if pick == Pick::GroupFile {
                "group.ron".to_owned()
            } else {
                self.doc
                    .path
                    .as_deref()
                    .and_then(Path::file_name)
                    .map_or_else(
                        || "untitled.ron".to_owned(),
                        |n| n.to_string_lossy().into_owned(),
                    )
            };
            dialog = dialog
                .add_save_extension("graph", "ron")
                .default_save_extension("graph")
                .default_file_name(&name);
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
            Pick::EnvironmentMap => {
                if let Some(s) = &mut self.scene {
                    let base = std::path::absolute(s.doc.base_dir()).unwrap_or_default();
                    let lumagraph_scene::Environment::Map { path: map, .. } =
                        &mut s.doc.file.environment
                    else {
                        return;
                    };
                    *map = path
                        .strip_prefix(&base)
                        .map_or_else(|_| path.display().to_string(), |p| p.display().to_string());
                }
            }
            Pick::GroupFile => self.group_selection(path),
            Pick::OcioConfig => {
                let spec = path.display().to_string();
                match self.view.display.load_config(&spec) {
                    Ok(()) => self.say(format!("viewer: OpenColorIO config {spec}"), false),
                    Err(e) => self.say(e, true),
                }
            }
            Pick::ErrorCsv => {
                let csv = self.preview.curve.csv();
                match lumagraph_graph::write_atomic(path, csv.as_bytes()) {
                    Ok(()) => self.say(format!("wrote {}", path.display()), false),
                    Err(e) => self.say(format!("{}: {e}", path.display()), true),
                }
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

    pub(super) fn file_dialog_ui(&mut self, ctx: &egui::Context) {
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

    /// Opens a graph file in place of the current one (no unsaved-changes check).
    pub fn open(&mut self, path: &Path) {
        self.outer.clear();
        match files::open(path) {
            Ok(graph) => {
                self.doc.replace(graph, Some(path.to_owned()));
                // The canvas frames the nodes by itself on its first draw; later it keeps
                // its view, so a graph opened in place is framed here.
                if self.canvas.visible_rect().is_some() {
                    self.canvas.request_frame(crate::canvas::Frame::All);
                }
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
        let saved = files::save(
            self.doc.registry(),
            &self.doc.graph,
            &self.doc.base_dir(),
            path,
        )?;
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
        // Inside a group: the graphs around it, outermost first.
        let around: String = self
            .outer
            .iter()
            .rev()
            .map(|o| {
                let file = o.doc.path.as_deref().and_then(Path::file_name).map_or_else(
                    || "untitled".to_owned(),
                    |n| n.to_string_lossy().into_owned(),
                );
                format!(" in {file} ({})", o.node)
            })
            .collect();
        format!("{dirty}{name}{around} — lumagraph editor")
    }

    pub(super) fn save_or_ask(&mut self) {
        if self.doc.path.is_some() {
            if let Err(e) = self.save() {
                self.say(e.to_string(), true);
            }
        } else {
            self.open_file_dialog(Pick::SaveGraph);
        }
    }

    /// Runs `then`, first asking about unsaved changes when there are some.
    pub(super) fn ask(&mut self, then: Then) {
        // Inside a group: leave it (saving it) first, so the question is about the graph
        // around it.
        while self.leave_group() {}
        if !self.outer.is_empty() {
            return;
        }
        let scene_dirty = self.scene.as_ref().is_some_and(|s| s.doc.is_dirty());
        if (self.doc.is_dirty() || (then == Then::Quit && scene_dirty))
            && then != Then::Open(PathBuf::new())
        {
            self.dialog = Some(Dialog::Unsaved(then));
        } else {
            self.proceed(then);
        }
    }

    pub(super) fn proceed(&mut self, then: Then) {
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

    /// Loads the scene that `PathTrace` and `GBuffer` nodes render, restarting the
    /// preview. A scene that cannot be loaded leaves the current one (if any) and the
    /// error in the status line and the side panel. Returns whether it loaded.
    pub fn load_scene(&mut self, path: &Path) -> bool {
        let loaded = SceneDoc::load(path).and_then(|doc| {
            let gpu = doc.build()?;
            Ok((doc, gpu))
        });
        match loaded {
            Ok((doc, gpu)) => {
                self.scene = Some(self.editor_scene(doc, gpu));
                self.scene_error = None;
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

    /// The scene `doc` built as `gpu` (full resolution), as the preview renders it: a new
    /// generation, so the preview restarts.
    fn editor_scene(&mut self, doc: SceneDoc, mut gpu: GpuScene) -> EditorScene {
        let full = (gpu.settings.width, gpu.settings.height);
        crate::scene_doc::cap_resolution(&mut gpu, self.preview_max);
        self.scene_generation += 1;
        self.errors_for = None;
        EditorScene {
            path: doc.path.clone(),
            full,
            preview: PreviewScene {
                gpu: Arc::new(gpu),
                generation: self.scene_generation,
                camera: None,
            },
            built: (doc.file.clone(), doc.furnace),
            doc,
        }
    }

    /// Rebuilds the preview's scene when the scene panel changed it (not while a drag is
    /// going on: the preview then restarts once, where the drag ends). A scene that
    /// cannot be built keeps the last good one in the preview and says why.
    pub fn apply_scene_edits(&mut self, dragging: bool) {
        let Some(s) = &mut self.scene else { return };
        // Compared in place: this runs every UI frame.
        if dragging || (s.built.0 == s.doc.file && s.built.1 == s.doc.furnace) {
            return;
        }
        s.built = (s.doc.file.clone(), s.doc.furnace);
        match s.doc.build() {
            Ok(gpu) => {
                let doc = s.doc.clone();
                self.scene = Some(self.editor_scene(doc, gpu));
                self.scene_error = None;
            }
            Err(e) => {
                self.scene_error = Some(format!("cannot use the edited scene: {e}"));
            }
        }
    }

    /// Moves the scene's camera by `g` (orbit, pan, dolly on the preview): the camera in the
    /// scene panel (and the file, when saved) moves, and the preview renders from there
    /// without rebuilding the scene ([`PreviewScene::camera`]). A glTF camera cannot move:
    /// the status bar says so.
    pub fn move_camera(&mut self, g: &crate::viewer::CameraGesture) {
        use lumagraph_scene::file::CameraDesc;
        use lumagraph_scene::orbit;
        let Some(s) = &mut self.scene else {
            self.say("load a scene to move its camera", true);
            return;
        };
        let CameraDesc::Perspective {
            position,
            target,
            up,
            fov_y,
            aperture_radius,
            focus_distance,
            autofocus,
        } = &mut s.doc.file.camera
        else {
            self.say(
                "a glTF camera cannot move in the preview: give the scene a Perspective \
                 camera (its numbers are in the glTF file)",
                true,
            );
            return;
        };
        let mut p = orbit::orbit(*position, *target, *up, g.yaw, g.pitch);
        let (np, nt) = orbit::pan(p, *target, *up, g.pan[0], g.pan[1]);
        p = orbit::dolly(np, nt, g.dolly);
        *position = p;
        *target = nt;
        let forward = glam::Vec3::from(nt) - glam::Vec3::from(p);
        let camera = lumagraph_scene::Camera {
            position: p.into(),
            forward: forward.normalize(),
            up: (*up).into(),
            fov_y_deg: *fov_y,
            aperture_radius: *aperture_radius,
            focus_distance: focus_distance.unwrap_or(forward.length()),
            autofocus: *autofocus,
        };
        let gpu = s.preview.gpu.camera_for(&camera);
        s.preview.camera = Some(gpu);
        // The preview's scene is the edited one but for the camera, which it follows.
        s.built.0.camera = s.doc.file.camera.clone();
    }

    /// Saves the edited scene into its file, keeping the file's comments and layout.
    pub fn save_scene(&mut self) -> bool {
        let Some(s) = &mut self.scene else {
            return false;
        };
        match s.doc.save() {
            Ok(()) => {
                let text = format!("saved {}", s.doc.path.display());
                self.say(text, false);
                true
            }
            Err(e) => {
                self.say(format!("cannot save the scene: {e}"), true);
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
}
