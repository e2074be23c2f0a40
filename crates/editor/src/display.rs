//! The viewer's display transform: an OpenColorIO display, view and look applied to what
//! the viewer shows of a scene-linear preview, as Nuke's viewer process does.
//!
//! The config is the one the `OCIO` environment variable names, else OpenColorIO's CG
//! config ([`lumagraph_color::DEFAULT_CONFIG`]), or a `config.ocio` picked in the viewer.
//! Off by default (the first entry of the display menu): the viewer then shows what the
//! node graph writes to a PNG.
//!
//! It is a view only: the graph, the files it writes, its undo history and the readout
//! (the port's scene-linear values) never see it. A display-encoded preview (`ldr_color`,
//! after a Tonemap or a `DisplayView` node) is shown as it is. The transform runs on the CPU
//! ([`lumagraph_color::Processor::apply`]) over the read-back floats, split over the
//! cores, only when the image, the display exposure or the menus change; the processor is
//! built again only when the menus change.

use std::hash::{DefaultHasher, Hash, Hasher};
use std::path::Path;

use egui::{Color32, Ui};
use lumagraph_color::{ColorConfig, Processor};
use lumagraph_render::cpu::Image;

/// The display menu's first entry: no display transform.
pub const NONE: &str = "(none: as the node graph shows)";

/// The looks menu's first entry: no look but the view's own.
pub const NO_LOOK: &str = "none";

/// The display menu's entry that picks another config.
pub const LOAD_CONFIG: &str = "load config.ocio…";

/// The display menu's entry back to the default config.
pub const DEFAULT_CONFIG_ENTRY: &str = "default config";

/// Why the menus are greyed out on a display-encoded preview.
pub const LDR_HOVER: &str = "the previewed port is display-encoded (ldr_color: after a \
     Tonemap or a DisplayView node): it is shown as it is, with no display transform";

/// What the display menus ask of the editor.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Request {
    /// Open the file dialog for a `config.ocio`.
    PickConfig,
    /// Say that a config could not be loaded (the current one stays).
    Failed(String),
}

/// The config, the display, view and look chosen, and the processor made from them.
#[derive(Default)]
pub struct DisplayTransform {
    /// The config: empty for the `OCIO` environment variable's, else
    /// [`lumagraph_color::DEFAULT_CONFIG`]; otherwise an `ocio://` name or a `config.ocio`
    /// file (see [`ColorConfig::load`]). Change it with [`DisplayTransform::load_config`].
    config_spec: String,
    /// The display; `None`: off, the image is shown as the node graph shows it.
    pub display: Option<String>,
    /// The view of `display`.
    pub view: String,
    /// A look applied before the view (`None`: only the view's own).
    pub look: Option<String>,
    /// Milliseconds the last image took to transform, and its size.
    pub last_cost: Option<(f64, u32, u32)>,
    /// The graph's working space, what the images shown are in (the app keeps it the
    /// document's).
    pub working_space: lumagraph_graph::WorkingSpace,
    config: Option<(String, Result<ColorConfig, String>)>,
    processor: Option<(u64, Result<Processor, String>)>,
}

impl std::fmt::Debug for DisplayTransform {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("DisplayTransform")
            .field("config", &self.config_spec)
            .field("display", &self.display)
            .field("view", &self.view)
            .field("look", &self.look)
            .finish_non_exhaustive()
    }
}

impl DisplayTransform {
    /// The config asked for (empty: `$OCIO`, else the default).
    pub fn config_spec(&self) -> &str {
        &self.config_spec
    }

    /// The config, loaded on first use.
    ///
    /// # Errors
    /// What [`ColorConfig::load`] says.
    pub fn config(&mut self) -> Result<&ColorConfig, String> {
        if self
            .config
            .as_ref()
            .is_some_and(|(s, _)| *s != self.config_spec)
        {
            self.config = None;
        }
        let spec = &self.config_spec;
        let (_, loaded) = self.config.get_or_insert_with(|| {
            (
                spec.clone(),
                ColorConfig::load(spec, Path::new(".")).map_err(|e| e.0),
            )
        });
        loaded.as_ref().map_err(Clone::clone)
    }

    /// Uses the config `spec` names (empty: `$OCIO`, else the default). A display, view
    /// or look the new config lacks is replaced by its default display and view, and no
    /// look.
    ///
    /// # Errors
    /// When it cannot be loaded: the current config stays.
    pub fn load_config(&mut self, spec: &str) -> Result<(), String> {
        let config = ColorConfig::load(spec, Path::new(".")).map_err(|e| e.0)?;
        let displays = config.displays();
        if let Some(d) = &self.display {
            match displays.iter().find(|(name, _)| name == d) {
                Some((_, views)) if views.contains(&self.view) => {}
                Some((_, views)) => self.view = views.first().cloned().unwrap_or_default(),
                None => {
                    let (d, v) = config.default_display_view();
                    self.display = Some(d);
                    self.view = v;
                }
            }
        }
        if self
            .look
            .as_ref()
            .is_some_and(|l| !config.looks().contains(l))
        {
            self.look = None;
        }
        self.config_spec = spec.to_owned();
        self.config = Some((spec.to_owned(), Ok(config)));
        Ok(())
    }

    /// Chooses `display` (`None`: off), keeping the view when the display has it, else
    /// taking the display's default view.
    pub fn choose_display(&mut self, display: Option<String>) {
        if let Some(d) = &display
            && let Ok(config) = self.config()
        {
            let (default_display, default_view) = config.default_display_view();
            let views = config
                .displays()
                .into_iter()
                .find(|(name, _)| name == d)
                .map(|(_, views)| views)
                .unwrap_or_default();
            if !views.contains(&self.view) {
                self.view = if *d == default_display {
                    default_view
                } else {
                    views.first().cloned().unwrap_or_default()
                };
            }
        }
        self.display = display;
    }

    /// Changes whenever what is shown through it changes; 0 when off.
    pub fn key(&self) -> u64 {
        let Some(display) = &self.display else {
            return 0;
        };
        let mut h = DefaultHasher::new();
        (
            &self.config_spec,
            display,
            &self.view,
            &self.look,
            self.working_space,
        )
            .hash(&mut h);
        h.finish() | 1
    }

    /// The processor from the graph's working space to the chosen display and view (with the
    /// look), made when the choice changed; `None` when off or when it cannot be made
    /// (see [`DisplayTransform::error`]).
    pub fn processor(&mut self) -> Option<&Processor> {
        let display = self.display.clone()?;
        let key = self.key();
        if self.processor.as_ref().is_none_or(|(k, _)| *k != key) {
            let (view, look) = (self.view.clone(), self.look.clone().unwrap_or_default());
            let names = self.working_space.ocio_names();
            let made = self.config().and_then(|c| {
                c.clone()
                    .with_working_space(names)
                    .and_then(|c| c.display_processor("", &display, &view, &look))
                    .map_err(|e| e.0)
            });
            self.processor = Some((key, made));
        }
        self.processor.as_ref()?.1.as_ref().ok()
    }

    /// Why the chosen transform cannot be applied (the config or the processor failed).
    pub fn error(&self) -> Option<&str> {
        let key = self.key();
        match (&self.config, &self.processor) {
            (Some((s, Err(e))), _) if *s == self.config_spec => Some(e),
            (_, Some((k, Err(e)))) if *k == key && key != 0 => Some(e),
            _ => None,
        }
    }

    /// The menus, drawn into `ui` (a horizontal row) as the last thing in it: display
    /// (first entry off; its popup also loads another config), and once a display is
    /// chosen its view and a look. `scene_linear`: the previewed port holds scene-linear
    /// values; else they are greyed out, with the rest of `ui`.
    pub fn menus(&mut self, ui: &mut Ui, scene_linear: bool) -> Option<Request> {
        if !scene_linear {
            ui.disable();
        }
        let cost = self.last_cost.map_or_else(String::new, |(ms, w, h)| {
            format!(" The last image, {w}×{h}, took {ms:.1} ms on the CPU.")
        });
        let tip = format!(
            "OpenColorIO display transform of what is shown, as Nuke's viewer: not the \
             graph, not the files written, not the readout (scene-linear values). \
             {NONE}: what an Output node writes to a PNG.{cost}"
        );
        let mut pick = None;
        let mut request = None;
        // Each label before its menu, both on a new row where they do not fit, the selected
        // text truncated at the row's end: the menus never widen the side panel.
        let label = labelled(ui, "display", 110.0);
        egui::ComboBox::from_id_salt("display")
            .selected_text(self.display.as_deref().unwrap_or("(none)"))
            .width(110.0)
            .truncate()
            // Every display and the config entries without scrolling, where there is room.
            .height(480.0)
            .show_ui(ui, |ui| {
                if ui.selectable_label(self.display.is_none(), NONE).clicked() {
                    pick = Some(None);
                }
                match self.config().map(ColorConfig::displays) {
                    Ok(displays) => {
                        for (d, _) in displays {
                            let on = self.display.as_ref() == Some(&d);
                            if ui.selectable_label(on, &d).clicked() {
                                pick = Some(Some(d));
                            }
                        }
                    }
                    Err(e) => {
                        ui.colored_label(Color32::from_rgb(240, 90, 90), e);
                    }
                }
                ui.separator();
                request = self.config_entries(ui);
            })
            .response
            .labelled_by(label)
            .on_hover_text(tip)
            .on_disabled_hover_text(LDR_HOVER);
        if let Some(d) = pick {
            self.choose_display(d);
        }
        let Some(display) = self.display.clone() else {
            return request;
        };
        let label = labelled(ui, "view", 110.0);
        egui::ComboBox::from_id_salt("view")
            .selected_text(self.view.as_str())
            .width(110.0)
            .truncate()
            .show_ui(ui, |ui| {
                let views = self
                    .config()
                    .map(ColorConfig::displays)
                    .unwrap_or_default()
                    .into_iter()
                    .find(|(d, _)| *d == display)
                    .map(|(_, v)| v)
                    .unwrap_or_default();
                for v in views {
                    let selected = self.view == v;
                    if ui.selectable_label(selected, &v).clicked() {
                        self.view = v;
                    }
                }
            })
            .response
            .labelled_by(label)
            .on_hover_text("the views of the display")
            .on_disabled_hover_text(LDR_HOVER);
        let label = labelled(ui, "look", 80.0);
        egui::ComboBox::from_id_salt("look")
            .selected_text(self.look.as_deref().unwrap_or(NO_LOOK))
            .width(80.0)
            .truncate()
            .show_ui(ui, |ui| {
                if ui.selectable_label(self.look.is_none(), NO_LOOK).clicked() {
                    self.look = None;
                }
                for l in self.config().map(ColorConfig::looks).unwrap_or_default() {
                    let selected = self.look.as_ref() == Some(&l);
                    if ui.selectable_label(selected, &l).clicked() {
                        self.look = Some(l);
                    }
                }
            })
            .response
            .labelled_by(label)
            .on_hover_text("a look of the config, applied before the view")
            .on_disabled_hover_text(LDR_HOVER);
        request
    }

    /// Why the transform cannot be applied, in red, when it cannot.
    pub fn error_label(&self, ui: &mut Ui) {
        if let Some(e) = self.error() {
            ui.colored_label(Color32::from_rgb(240, 90, 90), e.to_owned());
        }
    }

    /// The display menu's config entries: load a `config.ocio`, back to the default.
    fn config_entries(&mut self, ui: &mut Ui) -> Option<Request> {
        let source = match &self.config {
            Some((_, Ok(c))) => c.source.clone(),
            _ if self.config_spec.is_empty() => "$OCIO, else the default".to_owned(),
            _ => self.config_spec.clone(),
        };
        let mut request = None;
        if ui
            .selectable_label(false, LOAD_CONFIG)
            .on_hover_text(format!(
                "the OpenColorIO config: {source}; pick another config.ocio"
            ))
            .clicked()
        {
            request = Some(Request::PickConfig);
        }
        if !self.config_spec.is_empty()
            && ui
                .selectable_label(false, DEFAULT_CONFIG_ENTRY)
                .on_hover_text("$OCIO's config, else OpenColorIO's CG config")
                .clicked()
            && let Err(e) = self.load_config("")
        {
            request = Some(Request::Failed(e));
        }
        request
    }
}

/// The label `text` of a menu at least `width` points wide that follows it, on a new row
/// of the wrapping `ui` unless both fit in this one; its id.
fn labelled(ui: &mut Ui, text: &str, width: f32) -> egui::Id {
    let galley = egui::WidgetText::from(text).into_galley(
        ui,
        Some(egui::TextWrapMode::Extend),
        f32::INFINITY,
        egui::TextStyle::Body,
    );
    let needed = galley.size().x + width + 2.0 * ui.spacing().item_spacing.x;
    if ui.available_size_before_wrap().x < needed {
        ui.end_row();
    }
    ui.label(text).id
}

/// What the viewer shows of scene-linear `image` through `processor`: the values scaled by
/// 2^`exposure` (the display exposure), converted to the display, then 8-bit as a
/// display-encoded image is written (clipped to \[0, 1\], rounded); alpha as it is.
pub fn encode(image: &Image, exposure: f32, processor: &Processor) -> Vec<u8> {
    let gain = exposure.exp2();
    let mut values: Vec<f32> = image
        .pixels
        .iter()
        .flat_map(|p| [p[0] * gain, p[1] * gain, p[2] * gain, p[3]])
        .collect();
    let threads = std::thread::available_parallelism().map_or(1, std::num::NonZero::get);
    // Whole pixels, at least 4096 of them a thread.
    let chunk = 4 * image.pixels.len().div_ceil(threads).max(4096);
    if values.len() <= chunk {
        processor.apply(&mut values);
    } else {
        std::thread::scope(|s| {
            for part in values.chunks_mut(chunk) {
                s.spawn(|| processor.apply(part));
            }
        });
    }
    values
        .into_iter()
        .map(lumagraph_render::cpu::to_u8)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn default() -> DisplayTransform {
        let mut t = DisplayTransform::default();
        t.load_config(lumagraph_color::DEFAULT_CONFIG).unwrap();
        t
    }

    #[test]
    fn off_by_default_and_a_display_takes_its_default_view() {
        let mut t = default();
        assert_eq!(t.key(), 0);
        assert!(t.processor().is_none());
        t.choose_display(Some("sRGB - Display".into()));
        assert_eq!(t.view, "ACES 2.0 - SDR 100 nits (Rec.709)");
        t.view = "Un-tone-mapped".into();
        t.choose_display(Some("Display P3 - Display".into()));
        assert_eq!(t.view, "Un-tone-mapped", "kept: the display has it");
        assert_ne!(t.key(), 0);
        assert!(t.processor().is_some(), "{:?}", t.error());
    }

    #[test]
    fn encode_is_the_processor_then_8_bit() {
        let mut t = default();
        t.choose_display(Some("sRGB - Display".into()));
        let image = Image {
            width: 300,
            height: 100,
            pixels: (0..30_000)
                .map(|i| {
                    let v = i as f32 / 3000.0;
                    [v, 0.5 * v, 0.1, 1.0]
                })
                .collect(),
        };
        let p = t.processor().unwrap().clone();
        let bytes = encode(&image, 1.0, &p);
        for i in [0, 777, 15_000, 29_999] {
            let q = image.pixels[i];
            let want = p.apply_rgb([2.0 * q[0], 2.0 * q[1], 2.0 * q[2]]);
            let got = &bytes[4 * i..4 * i + 4];
            for c in 0..3 {
                assert_eq!(got[c], lumagraph_render::cpu::to_u8(want[c]), "pixel {i}");
            }
            assert_eq!(got[3], 255);
        }
    }

    #[test]
    fn a_config_that_cannot_load_keeps_the_current_one() {
        let mut t = default();
        t.choose_display(Some("sRGB - Display".into()));
        let e = t.load_config("no/such/config.ocio").unwrap_err();
        assert!(e.contains("no file"), "{e}");
        assert_eq!(t.config_spec(), lumagraph_color::DEFAULT_CONFIG);
        assert!(t.processor().is_some());
        assert_eq!(t.error(), None);
    }
}
