//! The scene panel: the open scene's materials, environment, camera and render settings,
//! the furnace view, saving the scene, and Render to file.
//!
//! Every widget edits the scene's values ([`crate::scene_doc::SceneDoc::file`]); the editor
//! rebuilds the preview's scene when they changed and no drag is going on
//! ([`Editor::apply_scene_edits`]), which restarts the accumulation.

use std::path::{Path, PathBuf};

use egui::{Color32, Ui};
use lumagraph_scene::file::{CameraDesc, Environment, MaterialDesc, RenderSettings, V3};

use super::{Editor, Pick};
use crate::render_job::{RenderJob, RenderRequest, Target};

/// The tabs under the preview.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SideTab {
    /// The selected node's params.
    #[default]
    Inspector,
    /// The scene panel.
    Scene,
}

/// The Render to file form.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RenderForm {
    /// Samples per pixel; 0 takes the scene's `spp`.
    pub spp: u32,
    /// Write the previewed port to [`Self::file`] (else every `Output` node into
    /// [`Self::dir`]).
    pub port_only: bool,
    /// The file for the previewed port, relative to the graph's folder or absolute.
    pub file: String,
    /// The folder for the `Output` nodes, relative to the graph's folder or absolute.
    pub dir: String,
}

impl Default for RenderForm {
    fn default() -> Self {
        Self {
            spp: 0,
            port_only: false,
            file: "render.exr".into(),
            dir: "render".into(),
        }
    }
}

const RED: Color32 = Color32::from_rgb(240, 90, 90);

/// Three drag values; returns whether one changed.
fn vec3(ui: &mut Ui, v: &mut V3, speed: f64) -> bool {
    ui.horizontal(|ui| {
        let mut changed = false;
        for x in v.iter_mut() {
            changed |= ui
                .add(egui::DragValue::new(x).speed(speed).max_decimals(4))
                .changed();
        }
        changed
    })
    .inner
}

/// A linear RGB colour: a picker for colours up to 1 and drag values for any positive
/// value (emission).
fn colour(ui: &mut Ui, v: &mut V3, max: f32) -> bool {
    ui.horizontal(|ui| {
        let mut changed = false;
        let mut c = v.map(|x| x.clamp(0.0, 1.0));
        if ui.color_edit_button_rgb(&mut c).changed() {
            *v = c;
            changed = true;
        }
        for x in v.iter_mut() {
            changed |= ui
                .add(
                    egui::DragValue::new(x)
                        .speed(0.01)
                        .range(0.0..=max)
                        .max_decimals(4),
                )
                .changed();
        }
        changed
    })
    .inner
}

/// One grid row: a label with its hint, then the widgets in one cell.
/// One grid row: a label with its hint, then the widgets in one cell; the closure gets the
/// label's id, for widgets it names (`Response::labelled_by`).
fn row(ui: &mut Ui, label: &str, hint: &str, widget: impl FnOnce(&mut Ui, egui::Id)) {
    let id = ui.label(label).on_hover_text(hint).id;
    ui.horizontal(|ui| widget(ui, id));
    ui.end_row();
}

impl Editor {
    /// The tabs under the preview and the chosen one.
    pub(super) fn side_tabs(&mut self, ui: &mut Ui, inspector: impl FnOnce(&mut Self, &mut Ui)) {
        ui.horizontal(|ui| {
            ui.selectable_value(&mut self.side_tab, SideTab::Inspector, "Inspector");
            let dirty = self.scene.as_ref().is_some_and(|s| s.doc.is_dirty());
            let label = if dirty { "Scene *" } else { "Scene" };
            ui.selectable_value(&mut self.side_tab, SideTab::Scene, label);
        });
        ui.separator();
        match self.side_tab {
            SideTab::Inspector => inspector(self, ui),
            SideTab::Scene => {
                egui::ScrollArea::vertical()
                    .id_salt("scene panel")
                    .show(ui, |ui| self.scene_panel(ui));
            }
        }
    }

    fn scene_panel(&mut self, ui: &mut Ui) {
        self.scene_values(ui);
        ui.separator();
        egui::CollapsingHeader::new("Render to file")
            .default_open(true)
            .show(ui, |ui| self.render_to_file(ui));
    }

    /// The scene file's values: materials, environment, camera, render settings.
    fn scene_values(&mut self, ui: &mut Ui) {
        let Some(s) = &mut self.scene else {
            ui.weak("no scene: Scene → Open scene… loads one");
            return;
        };
        let mut save = false;
        ui.horizontal_wrapped(|ui| {
            let name = s.doc.path.file_name().map_or_else(
                || s.doc.path.display().to_string(),
                |n| n.to_string_lossy().into_owned(),
            );
            ui.strong(name)
                .on_hover_text(s.doc.path.display().to_string());
            let dirty = s.doc.is_dirty();
            save = ui
                .add_enabled(dirty, egui::Button::new("Save scene"))
                .on_hover_text("writes the changed values into the file; its comments stay")
                .clicked();
            if ui.add_enabled(dirty, egui::Button::new("Revert")).clicked() {
                s.doc.revert();
            }
        });
        ui.checkbox(&mut s.doc.furnace, "Furnace test")
            .on_hover_text(
                "every albedo 1, nothing emits, lit by a white environment of radiance 1: \
                 energy-conserving materials then look like the background (a view only, \
                 not saved)",
            );
        let file = &mut s.doc.file;
        let mut pick_map = false;
        egui::CollapsingHeader::new(format!("Materials ({})", file.materials.len()))
            .default_open(true)
            .show(ui, |ui| {
                if file.materials.is_empty() {
                    ui.weak("the scene file names no materials (meshes keep their own)");
                }
                for (name, m) in &mut file.materials {
                    egui::CollapsingHeader::new(name)
                        .id_salt(("material", name.as_str()))
                        .show(ui, |ui| material(ui, name, m));
                }
            });
        egui::CollapsingHeader::new("Environment")
            .default_open(true)
            .show(ui, |ui| pick_map = environment(ui, &mut file.environment));
        egui::CollapsingHeader::new("Camera").show(ui, |ui| camera(ui, &mut file.camera));
        egui::CollapsingHeader::new("Render settings")
            .show(ui, |ui| render_settings(ui, &mut file.render));
        if let Some(e) = &self.scene_error {
            ui.colored_label(RED, e);
        }
        if pick_map {
            self.open_file_dialog(Pick::EnvironmentMap);
        }
        if save {
            self.save_scene();
        }
    }

    /// The Render to file form, its progress bar and its result.
    fn render_to_file(&mut self, ui: &mut Ui) {
        let scene_spp = self.scene.as_ref().map(|s| s.doc.file.render.spp);
        let running = self.render_job.as_ref().is_some_and(|j| !j.is_finished());
        let form = &mut self.render_form;
        egui::Grid::new("render form grid")
            .num_columns(2)
            .spacing([8.0, 4.0])
            .show(ui, |ui| {
                row(
                    ui,
                    "samples",
                    "samples per pixel; 0: the scene's spp",
                    |ui, _| {
                        ui.add(egui::DragValue::new(&mut form.spp).range(0..=1_000_000));
                        if form.spp == 0
                            && let Some(n) = scene_spp
                        {
                            ui.weak(format!("(scene: {n})"));
                        }
                    },
                );
                row(ui, "write", "what the render writes", |ui, _| {
                    ui.radio_value(&mut form.port_only, false, "Output nodes")
                        .on_hover_text("every Output node's file, relative to the folder");
                    ui.radio_value(&mut form.port_only, true, "previewed port")
                        .on_hover_text("one file: .png (8-bit sRGB) or .exr (linear float)");
                });
                let (label, text) = if form.port_only {
                    ("file", &mut form.file)
                } else {
                    ("folder", &mut form.dir)
                };
                row(ui, label, "relative to the graph's folder", |ui, _| {
                    ui.add(egui::TextEdit::singleline(text).desired_width(200.0));
                });
            });
        ui.horizontal(|ui| {
            if ui
                .add_enabled(!running, egui::Button::new("▶ Render"))
                .on_hover_text("at the scene's full resolution, beside the preview")
                .clicked()
            {
                self.start_render();
            }
            if running
                && ui.button("Cancel").clicked()
                && let Some(j) = &self.render_job
            {
                j.cancel();
            }
        });
        let Some(job) = &self.render_job else { return };
        let p = job.progress();
        if p.finished.is_none() {
            ui.ctx()
                .request_repaint_after(std::time::Duration::from_millis(100));
        }
        let text = format!(
            "{}: {} of {} frames ({} spp), {:.1} s",
            p.stage,
            p.done,
            p.frames,
            p.spp,
            p.elapsed.as_secs_f64()
        );
        ui.add(egui::ProgressBar::new(p.fraction()).text(text));
        match &p.finished {
            Some(Ok(files)) => {
                for f in files {
                    ui.label(format!("wrote {}", f.display()));
                }
            }
            Some(Err(e)) => {
                ui.colored_label(RED, e);
            }
            None => {
                for f in &p.files {
                    ui.label(format!("writing {}", f.display()));
                }
            }
        }
    }

    /// Starts Render to file with the form's settings (the previewed port, when the form
    /// asks for it). Returns whether it started.
    pub fn start_render(&mut self) -> bool {
        if self.render_job.as_ref().is_some_and(|j| !j.is_finished()) {
            self.say("a render is running", true);
            return false;
        }
        let form = self.render_form.clone();
        let (graph, registry, base, prefix) = match self.group_context() {
            Some(Ok(c)) => (c.graph, c.registry, c.base, c.prefix),
            Some(Err(e)) => {
                self.say(e, true);
                return false;
            }
            None => (
                self.doc.graph.clone(),
                self.doc.registry().clone(),
                self.doc.base_dir(),
                String::new(),
            ),
        };
        // An image sequence renders the frame the preview shows.
        let graph = self.at_frame(&graph).into_owned();
        let resolve = |p: &str| -> PathBuf {
            let p = Path::new(p);
            if p.is_absolute() {
                p.to_owned()
            } else {
                base.join(p)
            }
        };
        let target = if form.port_only {
            let Some(port) = self.effective_port() else {
                self.say("nothing previewed: select a node with an output", true);
                return false;
            };
            Target::Port {
                port: format!("{prefix}{port}"),
                file: resolve(&form.file),
            }
        } else {
            Target::Outputs(resolve(&form.dir))
        };
        // The scene at its full resolution (the preview's is capped).
        let scene = match &self.scene {
            Some(s) => match s.doc.build() {
                Ok(gpu) => Some(std::sync::Arc::new(gpu)),
                Err(e) => {
                    self.say(format!("cannot render: {e}"), true);
                    return false;
                }
            },
            None => None,
        };
        let spp = match form.spp {
            0 => scene.as_ref().map_or(1, |s| s.settings.spp),
            n => n,
        };
        let request = RenderRequest {
            graph,
            registry,
            base,
            scene,
            spp,
            target,
        };
        let gpu = self.preview.gpu().clone();
        self.render_job = Some(RenderJob::start(gpu, self.doc.library().clone(), request));
        true
    }
}

fn render_settings(ui: &mut Ui, r: &mut RenderSettings) {
    egui::Grid::new("render settings grid")
        .num_columns(2)
        .spacing([8.0, 4.0])
        .show(ui, |ui| {
            row(
                ui,
                "size",
                "image width and height, pixels (the preview is capped)",
                |ui, _| {
                    ui.add(egui::DragValue::new(&mut r.width).range(1..=16384));
                    ui.add(egui::DragValue::new(&mut r.height).range(1..=16384));
                },
            );
            row(ui, "bounces", "most scattering events per path", |ui, l| {
                ui.add(egui::Slider::new(&mut r.max_bounces, 0..=64))
                    .labelled_by(l);
            });
            row(
                ui,
                "spp",
                "the preview stops, and Render to file renders, at this many samples per pixel",
                |ui, _| {
                    ui.add(
                        egui::Slider::new(&mut r.spp, 1..=65536)
                            .logarithmic(true)
                            .text("target spp"),
                    );
                },
            );
            row(ui, "seed", "random seed", |ui, _| {
                ui.add(egui::DragValue::new(&mut r.seed));
            });
            row(
                ui,
                "texture mips",
                "mip levels for the textures, each lookup's level from a ray cone (off: every texture at full resolution)",
                |ui, _| {
                    ui.checkbox(&mut r.texture_mips, "");
                },
            );
        });
}

fn camera(ui: &mut Ui, c: &mut CameraDesc) {
    egui::Grid::new("camera grid")
        .num_columns(2)
        .spacing([8.0, 4.0])
        .show(ui, |ui| {
            let (aperture_radius, focus_distance, autofocus) = match c {
                CameraDesc::Perspective {
                    position,
                    target,
                    up,
                    fov_y,
                    aperture_radius,
                    focus_distance,
                    autofocus,
                } => {
                    row(ui, "position", "eye position", |ui, _| {
                        vec3(ui, position, 0.01);
                    });
                    row(ui, "target", "the point looked at", |ui, _| {
                        vec3(ui, target, 0.01);
                    });
                    row(ui, "up", "up direction", |ui, _| {
                        vec3(ui, up, 0.01);
                    });
                    row(ui, "field of view", "vertical, degrees", |ui, l| {
                        ui.add(egui::Slider::new(fov_y, 1.0..=170.0)).labelled_by(l);
                    });
                    (aperture_radius, focus_distance, autofocus)
                }
                CameraDesc::Gltf {
                    shape,
                    index,
                    aperture_radius,
                    focus_distance,
                    autofocus,
                } => {
                    row(ui, "glTF camera", "placed by the file", |ui, _| {
                        ui.weak(format!("camera {index} of shape \"{shape}\""));
                    });
                    (aperture_radius, focus_distance, autofocus)
                }
                _ => {
                    ui.weak("this camera has no settings here");
                    return;
                }
            };
            row(ui, "aperture", "lens radius; 0 is a pinhole", |ui, _| {
                ui.add(
                    egui::DragValue::new(aperture_radius)
                        .speed(0.001)
                        .range(0.0..=10.0)
                        .max_decimals(4),
                );
            });
            row(ui, "focus", "distance to the plane in focus", |ui, _| {
                let mut set = focus_distance.is_some();
                if ui.checkbox(&mut set, "").changed() {
                    *focus_distance = set.then_some(1.0);
                }
                match focus_distance {
                    Some(d) => {
                        ui.add(egui::DragValue::new(d).speed(0.01).range(0.001..=1e6));
                    }
                    None => {
                        ui.weak("at the target");
                    }
                }
            });
            row(
                ui,
                "autofocus",
                "focus on what the image centre sees",
                |ui, _| {
                    ui.checkbox(autofocus, "");
                },
            );
        });
}

/// Returns whether the map's file should be picked in the file dialog.
fn environment(ui: &mut Ui, env: &mut Environment) -> bool {
    let mut pick = false;
    let kind = match env {
        Environment::None => "none (black)",
        Environment::Constant(_) => "constant",
        Environment::Map { .. } => "map",
        _ => "other",
    };
    egui::ComboBox::from_label("environment")
        .selected_text(kind)
        .show_ui(ui, |ui| {
            if ui
                .selectable_label(kind == "none (black)", "none (black)")
                .clicked()
            {
                *env = Environment::None;
            }
            if ui
                .selectable_label(kind == "constant", "constant")
                .clicked()
                && kind != "constant"
            {
                *env = Environment::Constant([1.0; 3]);
            }
            if ui.selectable_label(kind == "map", "map").clicked() && kind != "map" {
                *env = Environment::Map {
                    path: String::new(),
                    intensity: 1.0,
                    azimuth: 0.0,
                    elevation: 0.0,
                    show_background: true,
                };
                pick = true;
            }
        });
    egui::Grid::new("environment grid")
        .num_columns(2)
        .spacing([8.0, 4.0])
        .show(ui, |ui| match env {
            Environment::Constant(c) => {
                row(ui, "radiance", "linear RGB", |ui, _| {
                    colour(ui, c, 1e6);
                });
            }
            Environment::Map {
                path,
                intensity,
                azimuth,
                elevation,
                show_background,
            } => {
                row(
                    ui,
                    "file",
                    "equirectangular .hdr or .exr, relative to the scene file",
                    |ui, _| {
                        ui.add(egui::TextEdit::singleline(path).desired_width(180.0));
                        pick |= ui.button("…").on_hover_text("pick the file").clicked();
                    },
                );
                row(ui, "intensity", "radiance scale", |ui, l| {
                    ui.add(egui::Slider::new(intensity, 0.0..=100.0).logarithmic(true))
                        .labelled_by(l);
                });
                row(ui, "rotation", "about the up axis, degrees", |ui, l| {
                    ui.add(egui::Slider::new(azimuth, -180.0..=180.0))
                        .labelled_by(l);
                });
                row(ui, "tilt", "of the horizon, degrees", |ui, l| {
                    ui.add(egui::Slider::new(elevation, -90.0..=90.0))
                        .labelled_by(l);
                });
                row(
                    ui,
                    "background",
                    "camera rays that miss see the map (else black)",
                    |ui, _| {
                        ui.checkbox(show_background, "visible");
                    },
                );
            }
            _ => {}
        });
    pick
}

fn material(ui: &mut Ui, name: &str, m: &mut MaterialDesc) {
    // The lobe parameters: the roughnesses before `metallic`, the rest after `conductor`.
    let params = lumagraph_scene::lobes::PARAMS;
    let (first, rest) = params.split_at(
        params
            .iter()
            .position(|p| p.name == "specular")
            .unwrap_or(0),
    );
    egui::Grid::new(("material grid", name))
        .num_columns(2)
        .spacing([8.0, 4.0])
        .show(ui, |ui| {
            row(
                ui,
                "base colour",
                "diffuse albedo or metal reflectance, linear RGB",
                |ui, _| {
                    colour(ui, &mut m.base_color, 1.0);
                },
            );
            row(ui, "emission", "emitted radiance, linear RGB", |ui, _| {
                colour(ui, &mut m.emission, 1e6);
            });
            lobe_rows(ui, m, first);
            row(ui, "metallic", "0 dielectric, 1 metal", |ui, l| {
                let auto = m.conductor.is_some() || m.eta.is_some() || m.k.is_some();
                let mut v = m.metallic.unwrap_or(if auto { 1.0 } else { 0.0 });
                if ui
                    .add(egui::Slider::new(&mut v, 0.0..=1.0))
                    .labelled_by(l)
                    .changed()
                {
                    m.metallic = Some(v);
                }
            });
            row(
                ui,
                "conductor",
                "a measured metal: exact conductor Fresnel",
                |ui, _| {
                    let shown = m.conductor.clone().unwrap_or_else(|| "none".into());
                    egui::ComboBox::from_id_salt(("conductor", name))
                        .selected_text(shown)
                        .show_ui(ui, |ui| {
                            if ui.selectable_label(m.conductor.is_none(), "none").clicked() {
                                m.conductor = None;
                            }
                            for (preset, _, _, what) in lumagraph_scene::conductor::PRESETS {
                                let on = m.conductor.as_deref() == Some(*preset);
                                if ui
                                    .selectable_label(on, format!("{preset} ({what})"))
                                    .clicked()
                                {
                                    m.conductor = Some((*preset).to_owned());
                                    m.eta = None;
                                    m.k = None;
                                }
                            }
                        });
                },
            );
            lobe_rows(ui, m, rest);
            row(ui, "ior", "index of refraction", |ui, l| {
                ui.add(egui::Slider::new(&mut m.ior, 1.0..=3.0))
                    .labelled_by(l);
            });
            row(ui, "two-sided", "emission leaves both sides", |ui, _| {
                ui.checkbox(&mut m.two_sided, "");
            });
            row(
                ui,
                "multiscatter",
                "compensate the energy microfacet lobes lose",
                |ui, _| {
                    ui.checkbox(&mut m.multiscatter, "");
                },
            );
        });
}

/// The rows of the lobe parameters `params` ([`lumagraph_scene::lobes::PARAMS`]) in
/// [`material`]'s grid: a slider from 0 to the parameter's maximum, or a colour.
fn lobe_rows(ui: &mut Ui, m: &mut MaterialDesc, params: &[lumagraph_scene::lobes::Param]) {
    use lumagraph_scene::lobes::ParamMut;
    for p in params {
        row(ui, p.label, p.tip, |ui, l| match (p.edit)(m) {
            ParamMut::Scalar(x) => {
                ui.add(egui::Slider::new(x, 0.0..=p.max)).labelled_by(l);
            }
            ParamMut::Rgb(c) => {
                colour(ui, c, p.max);
            }
        });
    }
}
