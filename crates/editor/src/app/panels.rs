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
            for (node, m) in &self.preview.measurements {
                ui.label(format!("{node}.{}: {:.4e}", m.name, m.value))
                    .on_hover_text("measured by the node on the last frame");
            }
            let frame = self.preview.stats.frames;
            let width = ui.available_width();
            self.scope
                .show(ui, self.preview.image.as_ref(), frame, width);
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
