//! The side panel (inspector and preview), the scene line, the status bar and the
//! refusal tooltip.

use egui::{Color32, Ui};

use super::{Editor, Pick};
use crate::inspector;

impl Editor {
    pub(super) fn refusal_tooltip(&self, ui: &Ui, now: f64) {
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

    pub(super) fn status_bar(&self, ui: &mut Ui) {
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

    pub(super) fn side_panel(&mut self, ui: &mut Ui, port: Option<&str>) {
        ui.horizontal(|ui| {
            ui.heading("Preview");
            if ui
                .toggle_value(&mut self.big_viewer, "⛶ large")
                .on_hover_text("the viewer in place of the canvas (Ctrl+Space); again to go back")
                .clicked()
            {
                self.viewer_window = false;
            }
            if ui
                .toggle_value(&mut self.viewer_window, "🗗 window")
                .on_hover_text("the viewer in a window of its own; close it to go back")
                .clicked()
            {
                self.big_viewer = false;
            }
        });
        self.scene_line(ui);
        if self.sequence.is_active() {
            self.sequence.ui(ui);
        }
        match port {
            Some(p) => ui.weak(p),
            None => ui.weak("nothing to preview"),
        };
        if let Some(err) = &self.preview.error {
            ui.colored_label(Color32::from_rgb(240, 90, 90), err);
        } else if (self.big_viewer || self.viewer_window) && self.preview.linear.is_some() {
            ui.horizontal(|ui| {
                if self.viewer_window {
                    ui.weak("in the viewer window");
                    if ui.button("🗗 back here").clicked() {
                        self.viewer_window = false;
                    }
                } else {
                    ui.weak("in the large viewer");
                    if ui.button("⛶ back to the canvas").clicked() {
                        self.big_viewer = false;
                    }
                }
            });
            self.preview_status(ui);
        } else if let Some((image, ty)) = &self.preview.linear {
            // Fitted, an image is shown at most at twice its size, in at most 320 points.
            let aspect = image.height as f32 / image.width.max(1) as f32;
            let w = ui.available_width().min(2.0 * image.width as f32);
            let h = (w * aspect).clamp(64.0, 320.0);
            self.view.display.working_space = self.doc.graph.working_space;
            if let Some(g) = self.view.show(ui, image, *ty, self.preview.stats.frames, h) {
                self.move_camera(&g);
            }
            self.viewer_controls(ui, port);
            self.preview_status(ui);
        }
        ui.separator();
        self.side_tabs(ui, |ed, ui| {
            egui::ScrollArea::vertical().show(ui, |ui| match ed.selected.as_slice() {
                [] => match ed.selected_frame {
                    Some(i) if i < ed.doc.graph.frames.len() => ed.frame_inspector(ui, i),
                    _ => {
                        ui.weak("select a node");
                    }
                },
                [one] => {
                    let id = one.clone();
                    let errs = ed.errors.get(&id).cloned();
                    if let Some(inspector::Request::PickFile(param)) =
                        inspector::show(ui, &mut ed.doc, &id, errs.as_ref())
                    {
                        ed.open_file_dialog(Pick::Param(id.clone(), param));
                    }
                    ui.separator();
                    node_color(ui, &mut ed.doc, &id);
                }
                many => {
                    ui.label(format!("{} nodes selected", many.len()));
                    if ui
                        .button("Join in new frame")
                        .on_hover_text("Ctrl+J: a labelled box around them")
                        .clicked()
                    {
                        ed.frame_selection();
                    }
                }
            });
        });
    }

    /// Under the preview image: zoom, display exposure and false colour (HDR ports), the
    /// snapshot and compare mode, and the values under the pointer.
    /// Under the preview (small or large): size, samples, pause, what the nodes measured,
    /// the live error plot and the scopes.
    fn preview_status(&mut self, ui: &mut Ui) {
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
        for (node, m) in &self.preview.measurements {
            ui.label(format!("{node}.{}: {:.4e}", m.name, m.value))
                .on_hover_text("measured by the node on the last frame");
        }
        if !self.preview.curve.points.is_empty() {
            self.error_plot(ui);
        }
        let frame = self.preview.stats.frames;
        let width = ui.available_width();
        self.scope
            .show(ui, self.preview.image.as_ref(), frame, width);
    }

    /// The large viewer, in place of the canvas: the preview image over the whole central
    /// area with the viewer's controls (readout, exposure, false colour, compare, scopes).
    pub(super) fn large_viewer(&mut self, ui: &mut Ui, port: Option<&str>) {
        let Some((image, ty)) = &self.preview.linear else {
            return;
        };
        ui.horizontal(|ui| {
            ui.strong(port.unwrap_or_default());
            if let Some(n) = self.preview.samples {
                ui.label(format!("{n} spp"));
            }
        });
        // Room for the controls and the readout under the image.
        let h = (ui.available_height() - 110.0).max(64.0);
        self.view.display.working_space = self.doc.graph.working_space;
        if let Some(g) = self.view.show(ui, image, *ty, self.preview.stats.frames, h) {
            self.move_camera(&g);
        }
        self.viewer_controls(ui, port);
    }

    /// A selected frame: its label, comment and colour, its nodes, and removing it.
    fn frame_inspector(&mut self, ui: &mut Ui, index: usize) {
        let Some(f) = self.doc.graph.frames.get(index).cloned() else {
            return;
        };
        ui.heading("Frame");
        let (mut label, mut comment) = (f.label.clone(), f.comment.clone());
        let mut color = f.color.map_or([120, 130, 150], |(r, g, b)| [r, g, b]);
        let mut changed = false;
        egui::Grid::new("frame grid").num_columns(2).show(ui, |ui| {
            ui.label("label");
            changed |= ui
                .add(egui::TextEdit::singleline(&mut label).hint_text("label"))
                .changed();
            ui.end_row();
            ui.label("comment");
            changed |= ui
                .add(
                    egui::TextEdit::multiline(&mut comment)
                        .hint_text("comment")
                        .desired_rows(2),
                )
                .changed();
            ui.end_row();
            ui.label("colour");
            let picked = ui.color_edit_button_srgb(&mut color).changed();
            changed |= picked;
            ui.end_row();
        });
        if changed {
            let color = (f.color.is_some() || color != [120, 130, 150])
                .then_some((color[0], color[1], color[2]));
            self.doc.set_frame(index, &label, &comment, color);
        }
        ui.label(format!("holds {}", f.nodes.join(", ")))
            .on_hover_text("dragging the frame's title moves them");
        if ui
            .button("Remove frame")
            .on_hover_text("its nodes stay")
            .clicked()
        {
            self.doc.remove_frame(index);
            self.selected_frame = None;
        }
    }

    /// The live error plot ([`crate::error_plot`]) with its export.
    fn error_plot(&mut self, ui: &mut Ui) {
        let width = ui.available_width();
        self.preview.curve.show(ui, width);
        ui.horizontal(|ui| {
            if ui
                .button("save CSV…")
                .on_hover_text("the points as `lumagraph converge` writes converge.csv")
                .clicked()
            {
                self.open_file_dialog(crate::Pick::ErrorCsv);
            }
            if ui.button("copy CSV").clicked() {
                ui.ctx().copy_text(self.preview.curve.csv());
            }
        });
    }

    fn viewer_controls(&mut self, ui: &mut Ui, port: Option<&str>) {
        use crate::viewer::Compare;
        let hdr = self
            .preview
            .linear
            .as_ref()
            .is_some_and(|(_, ty)| *ty != lumagraph_graph::PortType::LdrColor);
        let v = &mut self.view;
        let mut request = None;
        ui.horizontal_wrapped(|ui| {
            let zoom = v
                .zoom
                .map_or_else(|| "fit".to_owned(), |z| format!("{:.0} %", z * 100.0));
            ui.toggle_value(&mut v.camera_mode, "🎥 camera")
                .on_hover_text(
                    "on: drag orbits the scene's camera about its target, Shift- or middle-drag \
                 pans it, the wheel dollies it; off: they zoom and pan the image",
                );
            ui.weak(zoom)
                .on_hover_text("scroll to zoom, drag to pan, double-click to fit");
            if ui.small_button("fit").clicked() {
                v.zoom = None;
            }
            if ui.small_button("1:1").clicked() {
                v.zoom = Some(1.0);
            }

            if hdr {
                ui.add(
                    egui::Slider::new(&mut v.exposure, -10.0..=10.0)
                        .step_by(0.25)
                        .text("EV"),
                )
                .on_hover_text("display exposure: changes what is shown, not the graph");
                ui.checkbox(&mut v.false_colour, "false colour")
                    .on_hover_text(
                        "luminance in stops around middle grey: blue −6, green 0, red +4, white +6",
                    );
            }
            // Last: greyed out with what follows in the row on a display-encoded port.
            request = v.display.menus(ui, hdr);
        });
        if hdr {
            self.view.display.error_label(ui);
        }
        match request {
            Some(crate::display::Request::PickConfig) => self.open_file_dialog(Pick::OcioConfig),
            Some(crate::display::Request::Failed(e)) => self.say(e, true),
            None => {}
        }
        ui.horizontal_wrapped(|ui| {
            if ui
                .button("📌 pin")
                .on_hover_text("keep this image to compare the live one against")
                .clicked()
                && let (Some((image, ty)), Some(p)) = (&self.preview.linear, port)
            {
                self.view.pin(p, image.clone(), *ty, self.preview.samples);
            }
            let v = &mut self.view;
            if let Some(s) = &v.pinned {
                ui.weak(format!(
                    "snapshot: {}{}",
                    s.port,
                    s.spp.map_or_else(String::new, |n| format!(", {n} spp"))
                ));
                egui::ComboBox::from_id_salt("compare")
                    .selected_text(match v.compare {
                        Compare::Off => "live only",
                        Compare::Wipe => "wipe",
                        Compare::SideBySide => "side by side",
                    })
                    .show_ui(ui, |ui| {
                        ui.selectable_value(&mut v.compare, Compare::Off, "live only");
                        ui.selectable_value(&mut v.compare, Compare::Wipe, "wipe");
                        ui.selectable_value(&mut v.compare, Compare::SideBySide, "side by side");
                    });
                if v.compare == Compare::Wipe {
                    ui.add(egui::Slider::new(&mut v.wipe, 0.0..=1.0).show_value(false))
                        .on_hover_text("where the live image (left) gives way to the snapshot");
                }
                if ui.small_button("unpin").clicked() {
                    v.pinned = None;
                    v.compare = Compare::Off;
                }
            }
        });
        match self.view.hover {
            Some(r) => {
                let [red, g, b, a] = r.rgba;
                let from = if r.from_snapshot { " (snapshot)" } else { "" };
                let spp = self
                    .preview
                    .samples
                    .filter(|_| !r.from_snapshot)
                    .map_or_else(String::new, |n| format!("  {n} spp"));
                let text = format!(
                    "({}, {}){from}  R {red:.5}  G {g:.5}  B {b:.5}  A {a:.3}  Y {:.5}{spp}",
                    r.x, r.y, r.luminance
                );
                ui.add(egui::Label::new(egui::RichText::new(text).monospace()).wrap());
            }
            None => {
                ui.weak("point at the image for its values");
            }
        }
    }

    pub(super) fn scene_line(&mut self, ui: &mut Ui) {
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
}

/// A node's header colour: a picker, and back to none.
fn node_color(ui: &mut Ui, doc: &mut crate::document::Document, id: &str) {
    let current = doc.graph.node(id).and_then(|n| n.color);
    ui.horizontal(|ui| {
        ui.label("colour")
            .on_hover_text("the node's header in the editor; saved in the file");
        let mut c = current.map_or([128, 128, 128], |(r, g, b)| [r, g, b]);
        if ui.color_edit_button_srgb(&mut c).changed() {
            doc.set_node_color(id, Some((c[0], c[1], c[2])));
        }
        if current.is_some() && ui.button("none").clicked() {
            doc.set_node_color(id, None);
        }
    });
}
