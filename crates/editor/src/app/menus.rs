//! The menu bar and the modal dialogs (open, save as, unsaved changes). File paths are
//! typed in a text field with validation (no native file dialog: `rfd` would pull a
//! D-Bus/GTK stack into the build for little gain here).

use std::path::PathBuf;

use egui::{Color32, RichText, Ui};

use super::{Dialog, Editor, Then};
use crate::canvas::add_node_menu;

impl Editor {
    pub(super) fn menu_bar(&mut self, ui: &mut Ui) {
        egui::MenuBar::new().ui(ui, |ui| {
            ui.menu_button("File", |ui| {
                if ui.button("New").clicked() {
                    self.ask(Then::New);
                }
                if ui.button("Open…").clicked() {
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
                if ui.button("Save").clicked() {
                    self.save_or_ask();
                }
                if ui.button("Save as…").clicked() {
                    self.path_input = self
                        .doc
                        .path
                        .as_ref()
                        .map_or_else(|| "untitled.ron".into(), |p| p.display().to_string());
                    self.dialog = Some(Dialog::SaveAs);
                }
                ui.separator();
                if ui.button("Quit").clicked() {
                    self.ask(Then::Quit);
                }
            });
            ui.menu_button("Edit", |ui| {
                let (can_undo, can_redo) = self.doc.can_undo_redo();
                if ui
                    .add_enabled(can_undo, egui::Button::new("Undo"))
                    .clicked()
                {
                    self.doc.undo();
                }
                if ui
                    .add_enabled(can_redo, egui::Button::new("Redo"))
                    .clicked()
                {
                    self.doc.redo();
                }
                ui.separator();
                let any = !self.selected.is_empty();
                if ui.add_enabled(any, egui::Button::new("Copy")).clicked()
                    && let Some(t) = self.copy_selection()
                {
                    ui.ctx().copy_text(t);
                }
                if ui.button("Paste").clicked() {
                    self.paste(None);
                }
                if ui.add_enabled(any, egui::Button::new("Delete")).clicked() {
                    self.delete_selection();
                }
            });
            ui.menu_button("Add node", |ui| {
                if let Some(kind) = add_node_menu(ui, &mut self.canvas.search) {
                    match self.doc.add_node(kind, None) {
                        Ok(id) => self.select(vec![id]),
                        Err(e) => self.say(e, true),
                    }
                }
            });
        });
    }

    pub(super) fn dialogs(&mut self, ui: &Ui) {
        let Some(dialog) = self.dialog.clone() else {
            return;
        };
        let ctx = ui.ctx().clone();
        let mut close = false;
        let modal = egui::Modal::new(egui::Id::new("dialog")).show(&ctx, |ui| {
            ui.set_width(420.0);
            match &dialog {
                Dialog::Open => close = self.open_dialog(ui),
                Dialog::SaveAs => close = self.save_as_dialog(ui),
                Dialog::Unsaved(then) => close = self.unsaved_dialog(ui, then),
            }
        });
        if (close || modal.should_close()) && self.dialog.as_ref() == Some(&dialog) {
            self.dialog = None;
        }
    }

    fn open_dialog(&mut self, ui: &mut Ui) -> bool {
        ui.heading("Open graph");
        ui.text_edit_singleline(&mut self.path_input);
        let path = PathBuf::from(self.path_input.trim());
        let problem = if !path.is_file() {
            Some("no such file")
        } else if path.extension().is_none_or(|e| e != "ron") {
            Some("graph files end in .ron")
        } else {
            None
        };
        if let Some(p) = problem {
            ui.colored_label(Color32::from_rgb(240, 90, 90), p);
        }
        let mut close = false;
        for f in self.recent.files.clone() {
            if ui
                .button(RichText::new(f.display().to_string()).weak())
                .clicked()
            {
                self.path_input = f.display().to_string();
            }
        }
        ui.horizontal(|ui| {
            if ui
                .add_enabled(problem.is_none(), egui::Button::new("Open"))
                .clicked()
            {
                self.open(&path);
                close = true;
            }
            if ui.button("Cancel").clicked() {
                close = true;
            }
        });
        close
    }

    fn save_as_dialog(&mut self, ui: &mut Ui) -> bool {
        ui.heading("Save graph as");
        ui.text_edit_singleline(&mut self.path_input);
        let path = PathBuf::from(self.path_input.trim());
        let dir = path.parent().filter(|d| !d.as_os_str().is_empty());
        let problem = if path.extension().is_none_or(|e| e != "ron") {
            Some("graph files end in .ron")
        } else if dir.is_some_and(|d| !d.is_dir()) {
            Some("the folder does not exist")
        } else {
            None
        };
        if let Some(p) = problem {
            ui.colored_label(Color32::from_rgb(240, 90, 90), p);
        } else if path.exists() {
            ui.weak("the file exists and will be replaced");
        }
        let mut close = false;
        ui.horizontal(|ui| {
            if ui
                .add_enabled(problem.is_none(), egui::Button::new("Save"))
                .clicked()
            {
                match self.save_as(&path) {
                    Ok(()) => close = true,
                    Err(e) => self.say(e.to_string(), true),
                }
            }
            if ui.button("Cancel").clicked() {
                close = true;
            }
        });
        close
    }

    fn unsaved_dialog(&mut self, ui: &mut Ui, then: &Then) -> bool {
        ui.heading("Unsaved changes");
        ui.label(format!(
            "Save the changes to {} first?",
            self.doc.path.as_ref().map_or_else(
                || "the untitled graph".to_owned(),
                |p| p.display().to_string()
            )
        ));
        let mut close = false;
        ui.horizontal(|ui| {
            if ui.button("Save").clicked() {
                if self.doc.path.is_some() {
                    match self.save() {
                        Ok(()) => {
                            close = true;
                            self.proceed(then.clone());
                        }
                        Err(e) => self.say(e.to_string(), true),
                    }
                } else {
                    self.path_input = "untitled.ron".into();
                    self.dialog = Some(Dialog::SaveAs);
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
