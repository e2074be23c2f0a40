//! The inspector: one widget per param of the selected node, chosen by the param's type
//! in the registry: sliders over the declared range (logarithmic for wide positive
//! ranges), combo boxes for enums, checkboxes for bools, and a path field that checks the
//! extension (and, for inputs, that the file exists: for a path with a frame pattern, a
//! file of the sequence), a `…` button opening the file dialog, and a `▾` menu listing the
//! matching files near the graph. Every param's doc is its tooltip.

use std::path::Path;

use egui::{Color32, RichText, Ui};
use lumagraph_graph::registry::ParamDef;
use lumagraph_graph::{ParamType, ParamValue};

use crate::document::Document;

/// What the inspector asks of the editor.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Request {
    /// Open the file dialog for the path param with this name.
    PickFile(String),
}

/// Shows the inspector for node `id`.
pub fn show(
    ui: &mut Ui,
    doc: &mut Document,
    id: &str,
    errors: Option<&Vec<String>>,
) -> Option<Request> {
    let Some(node) = doc.graph.node(id).cloned() else {
        ui.weak("no node selected");
        return None;
    };
    ui.heading(&node.id);
    let Some(kind) = doc.registry().get(&node.kind).cloned() else {
        ui.colored_label(
            Color32::from_rgb(230, 60, 60),
            format!("unknown node kind \"{}\"", node.kind),
        );
        return None;
    };
    ui.label(RichText::new(kind.name).strong())
        .on_hover_text(kind.doc);
    ui.add(egui::Label::new(RichText::new(kind.doc).weak()).wrap());
    if let Some(errs) = errors {
        for e in errs {
            ui.colored_label(Color32::from_rgb(230, 80, 80), e);
        }
    }
    ui.separator();
    if kind.params.is_empty() {
        ui.weak("no params");
    }
    let base = doc.base_dir();
    let mut request = None;
    egui::Grid::new("params")
        .num_columns(2)
        .spacing([8.0, 6.0])
        .show(ui, |ui| {
            for def in &kind.params {
                let current = node
                    .params
                    .get(def.name)
                    .cloned()
                    .unwrap_or_else(|| def.ty.default_value());
                let label = ui.label(def.name).on_hover_text(tooltip(def)).id;
                match param_widget(ui, def, &current, &base, kind.sink, label) {
                    Some(Change::Set(v)) => doc.set_param(id, def.name, v),
                    Some(Change::Pick) => request = Some(Request::PickFile(def.name.to_owned())),
                    None => {}
                }
                ui.end_row();
            }
        });
    request
}

/// What a param widget did.
enum Change {
    /// The user set a new value.
    Set(ParamValue),
    /// The user asked for the file dialog.
    Pick,
}

fn tooltip(def: &ParamDef) -> String {
    let range = match &def.ty {
        ParamType::Float { min, max, default } => {
            format!("float in [{min}, {max}], default {default}")
        }
        ParamType::Int { min, max, default } => format!("int in [{min}, {max}], default {default}"),
        ParamType::Bool { default } => format!("bool, default {default}"),
        ParamType::Enum { default, .. } => {
            format!("one of the listed names, default \"{default}\"")
        }
        ParamType::Path {
            default,
            extensions,
        } => format!("file ({}), default \"{default}\"", extensions.join(", ")),
        ParamType::Text { default } => format!("text, default \"{default}\""),
        _ => String::new(),
    };
    format!("{}\n{range}", def.doc)
}

/// The widget for one param; returns the new value when the user changed it.
fn param_widget(
    ui: &mut Ui,
    def: &ParamDef,
    current: &ParamValue,
    base: &Path,
    sink: bool,
    label: egui::Id,
) -> Option<Change> {
    if let ParamType::Path { extensions, .. } = &def.ty {
        return path_widget(ui, def, current, base, sink, extensions, label);
    }
    value_widget(ui, def, current, label).map(Change::Set)
}

fn value_widget(
    ui: &mut Ui,
    def: &ParamDef,
    current: &ParamValue,
    label: egui::Id,
) -> Option<ParamValue> {
    let tip = tooltip(def);
    if let (ParamType::Float { .. } | ParamType::Int { .. }, ParamValue::Str(text)) =
        (&def.ty, current)
    {
        return expression_widget(ui, def, text, &tip, label);
    }
    number_or_other(ui, def, current, &tip, label)
}

/// A number becomes a frame expression from its slider's context menu.
fn expression_menu(r: &egui::Response, current: &ParamValue) -> Option<ParamValue> {
    let mut to_expression = None;
    r.context_menu(|ui| {
        if ui
            .button("Frame expression")
            .on_hover_text("animate it: `frame` (or `$F`) is the frame number")
            .clicked()
        {
            to_expression = Some(ParamValue::Str(current.to_string()));
            ui.close();
        }
    });
    to_expression
}

/// A number param written as a frame expression: a text field, with its value at the
/// default frame (or the error) beside it, and a button back to a plain number.
fn expression_widget(
    ui: &mut Ui,
    def: &ParamDef,
    text: &str,
    tip: &str,
    label: egui::Id,
) -> Option<ParamValue> {
    let mut edited = text.to_owned();
    let r = ui
        .add(egui::TextEdit::singleline(&mut edited).desired_width(140.0))
        .on_hover_text(format!(
            "{tip}\na frame expression: `frame` (or `$F`) is the frame number"
        ))
        .labelled_by(label);
    let value = lumagraph_graph::expr::evaluate(text, lumagraph_graph::expr::DEFAULT_FRAME);
    match &value {
        Ok(v) => ui.weak(format!(
            "= {v} at frame {}",
            lumagraph_graph::expr::DEFAULT_FRAME
        )),
        Err(e) => ui
            .colored_label(ui.visuals().error_fg_color, "error")
            .on_hover_text(e),
    };
    if ui
        .small_button("123")
        .on_hover_text("back to a plain number (its value at the default frame)")
        .clicked()
    {
        let v = value.unwrap_or(0.0);
        #[expect(clippy::cast_possible_truncation, reason = "a param's small integer")]
        return Some(match def.ty {
            ParamType::Int { .. } => ParamValue::Int(v.round() as i64),
            _ => ParamValue::Float(v),
        });
    }
    (r.lost_focus() && edited != text).then_some(ParamValue::Str(edited))
}

fn number_or_other(
    ui: &mut Ui,
    def: &ParamDef,
    current: &ParamValue,
    tip: &str,
    label: egui::Id,
) -> Option<ParamValue> {
    let tip = tip.to_owned();
    match &def.ty {
        ParamType::Float { min, max, .. } => {
            let mut v = current.as_f64().unwrap_or(*min);
            let log = *min > 0.0 && *max / *min > 1e3;
            let r = ui
                .add(
                    egui::Slider::new(&mut v, *min..=*max)
                        .logarithmic(log)
                        .clamping(egui::SliderClamping::Always),
                )
                .on_hover_text(tip)
                .labelled_by(label);
            if let Some(e) = expression_menu(&r, current) {
                return Some(e);
            }
            r.changed().then_some(ParamValue::Float(v))
        }
        ParamType::Int { min, max, .. } => {
            let mut v = match current {
                ParamValue::Int(v) => *v,
                _ => *min,
            };
            let r = ui
                .add(egui::Slider::new(&mut v, *min..=*max))
                .on_hover_text(tip)
                .labelled_by(label);
            if let Some(e) = expression_menu(&r, current) {
                return Some(e);
            }
            r.changed().then_some(ParamValue::Int(v))
        }
        ParamType::Bool { .. } => {
            let mut v = matches!(current, ParamValue::Bool(true));
            let r = ui
                .checkbox(&mut v, "")
                .on_hover_text(tip)
                .labelled_by(label);
            r.changed().then_some(ParamValue::Bool(v))
        }
        ParamType::Enum { options, .. } => {
            let selected = match current {
                ParamValue::Str(s) => s.clone(),
                other => other.to_string(),
            };
            let mut picked = None;
            egui::ComboBox::from_id_salt(def.name)
                .selected_text(&selected)
                .show_ui(ui, |ui| {
                    for (name, doc) in *options {
                        if ui
                            .selectable_label(selected == *name, *name)
                            .on_hover_text(*doc)
                            .clicked()
                            && selected != *name
                        {
                            picked = Some(ParamValue::Str((*name).to_owned()));
                        }
                    }
                })
                .response
                .on_hover_text(tip)
                .labelled_by(label);
            picked
        }
        ParamType::Text { .. } => {
            let committed = match current {
                ParamValue::Str(s) => s.clone(),
                other => other.to_string(),
            };
            // The text being typed lives in egui's memory while the field has focus; it
            // is set when the edit ends, so typing a layer's name does not reload the
            // file at every letter.
            let id = label.with("text");
            let mut text = ui
                .data_mut(|d| d.get_temp::<String>(id))
                .unwrap_or_else(|| committed.clone());
            let r = ui
                .add(egui::TextEdit::singleline(&mut text).desired_width(140.0))
                .on_hover_text(tip)
                .labelled_by(label);
            if r.has_focus() {
                ui.data_mut(|d| d.insert_temp(id, text.clone()));
            } else {
                ui.data_mut(|d| d.remove::<String>(id));
            }
            (r.lost_focus() && text != committed).then_some(ParamValue::Str(text))
        }
        _ => {
            ui.weak(current.to_string());
            None
        }
    }
}

/// What is wrong with a path value, if anything.
pub fn check_path(
    value: &str,
    extensions: &[&str],
    base: &Path,
    must_exist: bool,
) -> Option<String> {
    if value.trim().is_empty() {
        return Some("the path is empty".into());
    }
    let ext = Path::new(value)
        .extension()
        .map(|e| e.to_string_lossy().to_lowercase())
        .unwrap_or_default();
    if !extensions.contains(&ext.as_str()) {
        return Some(format!("use one of: .{}", extensions.join(" .")));
    }
    let path = base.join(value);
    if must_exist && lumagraph_footage::sequence::has_pattern(value) {
        // An image sequence: some frame's file must be there.
        if !any_frame(&path) {
            return Some(format!(
                "no file matches {} (the pattern with a frame's digits in its place)",
                path.display()
            ));
        }
    } else if must_exist && !path.is_file() {
        return Some(format!("no file {}", path.display()));
    }
    None
}

/// Whether a file of the sequence `pattern` (a path whose file name holds a frame pattern)
/// exists; stops at the first one.
fn any_frame(pattern: &Path) -> bool {
    let name = pattern
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let dir = match pattern.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    std::fs::read_dir(dir).is_ok_and(|entries| {
        entries.flatten().any(|e| {
            e.file_name()
                .to_str()
                .and_then(|n| lumagraph_footage::sequence::frame_of(&name, n))
                .is_some()
                && e.path().is_file()
        })
    })
}

fn path_widget(
    ui: &mut Ui,
    def: &ParamDef,
    current: &ParamValue,
    base: &Path,
    sink: bool,
    extensions: &[&str],
    label: egui::Id,
) -> Option<Change> {
    let value = match current {
        ParamValue::Str(s) => s.clone(),
        other => other.to_string(),
    };
    // The text being typed lives in egui's memory until it is valid and committed.
    let id = ui.id().with(("path", def.name));
    let mut text: String = ui.data(|d| d.get_temp(id)).unwrap_or_else(|| value.clone());
    let mut out = None;
    ui.vertical(|ui| {
        ui.horizontal(|ui| {
            let r = ui
                .add(egui::TextEdit::singleline(&mut text).desired_width(180.0))
                .labelled_by(label);
            let problem = check_path(&text, extensions, base, !sink);
            if r.changed() {
                ui.data_mut(|d| d.insert_temp(id, text.clone()));
            }
            if (r.lost_focus() || !r.has_focus()) && problem.is_none() && text != value {
                out = Some(Change::Set(ParamValue::Str(text.clone())));
                ui.data_mut(|d| d.remove::<String>(id));
            }
            if ui
                .button("…")
                .on_hover_text("choose a file in the file dialog")
                .clicked()
            {
                ui.data_mut(|d| d.remove::<String>(id));
                out = Some(Change::Pick);
            }
            if !sink {
                ui.menu_button("▾", |ui| {
                    let files = list_files(base, extensions);
                    if files.is_empty() {
                        ui.weak(format!(
                            "no .{} file in {}",
                            extensions.join(" ."),
                            base.display()
                        ));
                    }
                    for f in files {
                        if ui.button(&f).clicked() {
                            out = Some(Change::Set(ParamValue::Str(f.clone())));
                            ui.data_mut(|d| d.remove::<String>(id));
                            ui.close();
                        }
                    }
                })
                .response
                .on_hover_text("pick a file from the graph's folder and its neighbours");
            }
            if let Some(p) = &problem {
                ui.colored_label(Color32::from_rgb(230, 80, 80), "⚠")
                    .on_hover_text(p);
            }
        });
        if let Some(p) = check_path(&text, extensions, base, !sink) {
            ui.colored_label(Color32::from_rgb(230, 80, 80), p);
        }
    });
    out
}

/// Files with one of `extensions` in `base`, its subfolders and its parent's subfolders
/// (one level each), as paths relative to `base`.
fn list_files(base: &Path, extensions: &[&str]) -> Vec<String> {
    let base = if base.as_os_str().is_empty() {
        Path::new(".")
    } else {
        base
    };
    let mut out = Vec::new();
    let mut dirs = vec![(base.to_path_buf(), String::new())];
    for (sub, prefix) in [
        (base.to_path_buf(), String::new()),
        (base.join(".."), "../".to_owned()),
    ] {
        if let Ok(rd) = std::fs::read_dir(&sub) {
            for e in rd.flatten() {
                if e.path().is_dir() {
                    let name = e.file_name().to_string_lossy().into_owned();
                    if !name.starts_with('.') && name != "target" {
                        dirs.push((e.path(), format!("{prefix}{name}/")));
                    }
                }
            }
        }
    }
    for (dir, prefix) in dirs {
        let Ok(rd) = std::fs::read_dir(&dir) else {
            continue;
        };
        for e in rd.flatten() {
            let name = e.file_name().to_string_lossy().into_owned();
            let ext = Path::new(&name)
                .extension()
                .map(|x| x.to_string_lossy().to_lowercase())
                .unwrap_or_default();
            if e.path().is_file() && extensions.contains(&ext.as_str()) {
                out.push(format!("{prefix}{name}"));
            }
        }
    }
    out.sort();
    out.dedup();
    out.truncate(200);
    out
}
