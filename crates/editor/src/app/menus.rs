//! The menu bar and the modal dialog for unsaved changes. Files are picked with
//! `egui-file-dialog`, drawn by egui itself (a native dialog through `rfd` would pull a
//! D-Bus/GTK stack into the build).

use std::path::PathBuf;

use egui::Ui;

use super::{Dialog, Editor, Pick, Then};
use crate::canvas::{Frame, add_node_menu};

impl Editor {
    /// Adds a node of `kind` in the middle of the canvas's view and selects it (the Add
    /// node menu).
    pub fn add_node_in_view(&mut self, kind: &str) {
        match self.doc.add_node(kind, self.canvas.new_node_pos()) {
            Ok(id) => self.select(vec![id]),
            Err(e) => self.say(e, true),
        }
    }

    pub(super) fn menu_bar(&mut self, ui: &mut Ui) {
        egui::MenuBar::new().ui(ui, |ui| {
            ui.menu_button("File", |ui| {
                if ui.button("New").clicked() {
                    self.ask(Then::New);
                }
                if ui
                    .add(egui::Button::new("Open…").shortcut_text("Ctrl+O"))
                    .clicked()
                {
                    self.ask(Then::Open(PathBuf::new()));
                }
                ui.menu_button("Open recent", |ui| {
                    if self.recent.files.is_empty() {
                        ui.weak("nothing yet");
                    }
                    for f in self.recent.files.clone() {
                        if ui.button(f.display().to_string()).clicked() {
                            self.ask(Then::Open(f));
                        }
                    }
                });
                if ui
                    .add(egui::Button::new("Save").shortcut_text("Ctrl+S"))
                    .clicked()
                {
                    self.save_or_ask();
                }
                if ui.button("Save as…").clicked() {
                    self.open_file_dialog(Pick::SaveGraph);
                }
                ui.separator();
                if ui.button("Quit").clicked() {
                    self.ask(Then::Quit);
                }
            });
            ui.menu_button("Edit", |ui| self.edit_menu(ui));
            ui.menu_button("Scene", |ui| self.scene_menu(ui));
            ui.menu_button("View", |ui| {
                if ui
                    .add(egui::Button::new("Frame all").shortcut_text("Home"))
                    .clicked()
                {
                    self.canvas.request_frame(Frame::All);
                }
                let any = !self.selected.is_empty();
                if ui
                    .add_enabled(any, egui::Button::new("Frame selected").shortcut_text("F"))
                    .clicked()
                {
                    self.canvas
                        .request_frame(Frame::Nodes(self.selected.clone()));
                }
                if ui
                    .add(
                        egui::Button::selectable(self.big_viewer, "Large viewer")
                            .shortcut_text("Ctrl+Space"),
                    )
                    .clicked()
                {
                    self.big_viewer = !self.big_viewer;
                    self.viewer_window = false;
                    ui.close();
                }
                if ui
                    .add(egui::Button::selectable(
                        self.viewer_window,
                        "Viewer in a window",
                    ))
                    .clicked()
                {
                    self.viewer_window = !self.viewer_window;
                    self.big_viewer = false;
                    ui.close();
                }
                ui.checkbox(&mut self.snap, "Snap to grid")
                    .on_hover_text("a node let go after a drag lands on the grid");
                ui.separator();
                let mut on = self.preview.thumbnails_on;
                if ui
                    .checkbox(&mut on, "Node thumbnails")
                    .on_hover_text(
                        "a picture of each node's output on the node (off by default on a CPU \
                         adapter, where reading every output back costs)",
                    )
                    .changed()
                {
                    self.preview.set_thumbnails(on);
                }
            });
            ui.menu_button("Add node", |ui| {
                if let Some(kind) = add_node_menu(ui, self.doc.registry(), &mut self.canvas.search)
                {
                    self.add_node_in_view(kind);
                }
            });
        });
    }

    /// The Scene menu: open, edit, save, reload, close, furnace view, render to file.
    fn scene_menu(&mut self, ui: &mut Ui) {
        if ui.button("Open scene…").clicked() {
            self.open_file_dialog(Pick::Scene);
        }
        let loaded = self.scene.is_some();
        if ui
            .add_enabled(loaded, egui::Button::new("Edit scene"))
            .on_hover_text("materials, environment, camera and render settings")
            .clicked()
        {
            self.side_tab = super::SideTab::Scene;
        }
        let dirty = self.scene.as_ref().is_some_and(|s| s.doc.is_dirty());
        if ui
            .add_enabled(
                dirty,
                egui::Button::new("Save scene").shortcut_text("Ctrl+Shift+S"),
            )
            .clicked()
        {
            self.save_scene();
        }
        let path = self.scene.as_ref().map(|s| s.path.clone());
        if ui
            .add_enabled(path.is_some(), egui::Button::new("Reload scene"))
            .on_hover_text("reads the file again; unsaved scene edits are lost")
            .clicked()
            && let Some(p) = path
        {
            self.load_scene(&p);
        }
        if ui
            .add_enabled(loaded, egui::Button::new("Close scene"))
            .clicked()
        {
            self.close_scene();
        }
        ui.separator();
        if let Some(s) = &mut self.scene {
            ui.checkbox(&mut s.doc.furnace, "Furnace test");
        }
        if ui
            .add(egui::Button::new("Render to file…").shortcut_text("Ctrl+R"))
            .clicked()
        {
            self.side_tab = super::SideTab::Scene;
        }
    }

    /// The Edit menu: undo, clipboard, duplicate, delete, groups.
    fn edit_menu(&mut self, ui: &mut Ui) {
        let (can_undo, can_redo) = self.doc.can_undo_redo();
        if ui
            .add_enabled(can_undo, egui::Button::new("Undo").shortcut_text("Ctrl+Z"))
            .clicked()
        {
            self.doc.undo();
        }
        if ui
            .add_enabled(
                can_redo,
                egui::Button::new("Redo").shortcut_text("Ctrl+Shift+Z"),
            )
            .clicked()
        {
            self.doc.redo();
        }
        ui.separator();
        ui.menu_button("Working space", |ui| {
            for space in lumagraph_graph::WorkingSpace::ALL {
                let on = self.doc.graph.working_space == space;
                if ui
                    .radio(on, space.name())
                    .on_hover_text(
                        "the colour space of the graph's images (docs/compositing.md); \
                         saved in the graph file",
                    )
                    .clicked()
                {
                    self.doc.set_working_space(space);
                    ui.close();
                }
            }
        });
        ui.separator();
        let any = !self.selected.is_empty();
        if ui
            .add_enabled(
                any,
                egui::Button::new("Join in new frame").shortcut_text("Ctrl+J"),
            )
            .on_hover_text(
                "a labelled box around the selected nodes; dragging its title moves them",
            )
            .clicked()
        {
            self.frame_selection();
            ui.close();
        }
        if ui
            .add_enabled(any, egui::Button::new("Copy").shortcut_text("Ctrl+C"))
            .clicked()
            && let Some(t) = self.copy_selection()
        {
            ui.ctx().copy_text(t);
        }
        if ui
            .add(egui::Button::new("Paste").shortcut_text("Ctrl+V"))
            .clicked()
        {
            self.paste(None);
        }
        if ui
            .add_enabled(any, egui::Button::new("Delete").shortcut_text("Del"))
            .clicked()
        {
            self.delete_selection();
        }
        ui.separator();
        if ui
            .add_enabled(
                any,
                egui::Button::new("Group selected nodes…").shortcut_text("Ctrl+G"),
            )
            .clicked()
        {
            self.ask_group_selection();
        }
        let group = match self.selected.as_slice() {
            [one] => self.group_file(one).map(|_| one.clone()),
            _ => None,
        };
        if ui
            .add_enabled(
                group.is_some(),
                egui::Button::new("Open group").shortcut_text("Tab"),
            )
            .clicked()
            && let Some(id) = group
        {
            self.open_group(&id);
        }
        if ui
            .add_enabled(
                !self.outer.is_empty(),
                egui::Button::new("Leave group").shortcut_text("Tab"),
            )
            .clicked()
        {
            self.leave_group();
        }
    }

    pub(super) fn dialogs(&mut self, ui: &Ui) {
        let Some(dialog) = self.dialog.clone() else {
            return;
        };
        let ctx = ui.ctx().clone();
        let mut close = false;
        let modal = egui::Modal::new(egui::Id::new("dialog")).show(&ctx, |ui| {
            ui.set_width(420.0);
            let Dialog::Unsaved(then) = &dialog;
            close = self.unsaved_dialog(ui, then);
        });
        if (close || modal.should_close()) && self.dialog.as_ref() == Some(&dialog) {
            self.dialog = None;
        }
    }

    fn unsaved_dialog(&mut self, ui: &mut Ui, then: &Then) -> bool {
        ui.heading("Unsaved changes");
        let graph_dirty = self.doc.is_dirty();
        let scene = self
            .scene
            .as_ref()
            .filter(|s| *then == Then::Quit && s.doc.is_dirty())
            .map(|s| s.doc.path.display().to_string());
        let mut what = Vec::new();
        if graph_dirty {
            what.push(self.doc.path.as_ref().map_or_else(
                || "the untitled graph".to_owned(),
                |p| p.display().to_string(),
            ));
        }
        what.extend(scene.clone().map(|s| format!("the scene {s}")));
        ui.label(format!("Save the changes to {} first?", what.join(" and ")));
        let mut close = false;
        ui.horizontal(|ui| {
            if ui.button("Save").clicked() {
                if scene.is_some() && !self.save_scene() {
                    return;
                }
                if !graph_dirty {
                    close = true;
                    self.proceed(then.clone());
                } else if self.doc.path.is_some() {
                    match self.save() {
                        Ok(()) => {
                            close = true;
                            self.proceed(then.clone());
                        }
                        Err(e) => self.say(e.to_string(), true),
                    }
                } else {
                    // Save as first; the quit, new or open goes on once it is saved.
                    close = true;
                    self.after_save = Some(then.clone());
                    self.open_file_dialog(Pick::SaveGraph);
                }
            }
            if ui.button("Discard").clicked() {
                close = true;
                self.proceed(then.clone());
            }
            if ui.button("Cancel").clicked() {
                close = true;
            }
        });
        close
    }
}
