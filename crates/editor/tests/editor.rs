//! The editor driven headless through `egui_kittest` on the shared wgpu device (lavapipe on
//! a machine without a GPU): loading, editing through the UI, connection rules, undo,
//! files, snapshots, and the preview against a headless render of the saved graph.

mod common;

use egui::accesskit::Role;
use egui_kittest::kittest::Queryable as _;
use lumagraph_graph::{Graph, ParamValue};
use lumagraph_pathtrace::library::compile;
use lumagraph_render::Resources;

use common::{click_at, editor, harness, repo, snapshot_options, with_config};
use lumagraph_editor::{EditorConfig, Pick};

fn post_tonemap() -> std::path::PathBuf {
    repo("graphs/post_tonemap.ron")
}

/// The text of the shipped graph `name` with its asset paths made absolute, so a copy
/// works from any folder.
fn shipped_text(name: &str) -> String {
    std::fs::read_to_string(repo(&format!("graphs/{name}")))
        .unwrap()
        .replace("../assets/", &format!("{}/", repo("assets").display()))
}

#[test]
fn loads_a_graph_and_previews_it() {
    let Some(ed) = editor(Some(&post_tonemap()), None) else {
        return;
    };
    let mut h = harness(ed);
    let ed = h.state();
    assert_eq!(ed.doc.graph.nodes.len(), 4);
    assert!(ed.errors.is_empty(), "{:?}", ed.errors);
    assert_eq!(ed.effective_port().as_deref(), Some("tonemap.color"));
    let img = ed.preview.image.as_ref().expect("a preview image");
    assert_eq!((img.width, img.height), (512, 256));
    assert_eq!(ed.preview.stats.rebuilds, 1);
    assert!(!ed.title().starts_with('●'), "{}", ed.title());
    // Node titles from the graph, ports from the registry.
    h.get_by_label("exposure");
    h.get_by_label("Tonemap");
    h.run_ok();
}

#[test]
fn a_param_changed_in_the_inspector_changes_the_model_without_a_rebuild() {
    let Some(mut ed) = editor(Some(&post_tonemap()), None) else {
        return;
    };
    ed.select(vec!["tonemap".into()]);
    let mut h = harness(ed);
    let before = h.state().preview.image.clone().expect("preview");
    h.get_by_role_and_label(Role::ComboBox, "operator").click();
    h.run_ok();
    h.get_by_label("agx").click();
    h.run_ok();
    let ed = h.state();
    assert_eq!(
        ed.doc.graph.node("tonemap").unwrap().params.get("operator"),
        Some(&ParamValue::Str("agx".into()))
    );
    assert!(
        ed.title().starts_with('●'),
        "unsaved marker: {}",
        ed.title()
    );
    // Param only: the executor was updated in place, not rebuilt.
    assert_eq!(ed.preview.stats.rebuilds, 1);
    assert_eq!(ed.preview.stats.param_updates, 1);
    assert_ne!(ed.preview.image.as_ref().unwrap().rgba, before.rgba);
}

#[test]
fn add_a_node_from_the_menu_and_connect_it() {
    let Some(ed) = editor(Some(&post_tonemap()), None) else {
        return;
    };
    let mut h = harness(ed);
    h.get_by_label("Add node").click();
    h.run_ok();
    h.get_by_role_and_label(Role::Button, "Exposure").click();
    h.run_ok();
    let ed = h.state_mut();
    assert_eq!(ed.selected, vec!["exposure_2".to_owned()]);
    // Insert it between exposure and tonemap.
    ed.doc
        .connect("exposure.color", "exposure_2.color")
        .unwrap();
    ed.doc.connect("exposure_2.color", "tonemap.color").unwrap();
    ed.doc
        .set_param("exposure_2", "ev", ParamValue::Float(-1.0));
    h.run_ok();
    let ed = h.state();
    assert!(ed.errors.is_empty(), "{:?}", ed.errors);
    let edges: Vec<_> = ed
        .doc
        .graph
        .edges
        .iter()
        .map(|e| (e.from.as_str(), e.to.as_str()))
        .collect();
    assert!(edges.contains(&("exposure_2.color", "tonemap.color")));
    assert_eq!(
        edges.iter().filter(|(_, t)| *t == "tonemap.color").count(),
        1
    );
    // A new pass: the preview was rebuilt, and shows the new node's output.
    assert_eq!(ed.preview.stats.rebuilds, 2);
    assert_eq!(ed.effective_port().as_deref(), Some("exposure_2.color"));
}

#[test]
fn an_incompatible_connection_is_refused_with_the_reason() {
    let Some(ed) = editor(Some(&post_tonemap()), None) else {
        return;
    };
    let mut h = harness(ed);
    let ed = h.state_mut();
    let before = ed.doc.graph.clone();
    let err = ed
        .doc
        .connect("tonemap.color", "exposure.color")
        .unwrap_err();
    assert!(
        err.contains("tonemap.color produces ldr_color, but exposure.color accepts hdr_color"),
        "{err}"
    );
    let cycle = ed
        .doc
        .connect("tonemap.color", "tonemap.color")
        .unwrap_err();
    assert!(
        cycle.contains("cycle") || cycle.contains("produces"),
        "{cycle}"
    );
    assert_eq!(ed.doc.graph, before);
    assert!(!ed.doc.is_dirty());
}

#[test]
fn undo_and_redo_restore_the_graph() {
    let Some(mut ed) = editor(Some(&post_tonemap()), None) else {
        return;
    };
    ed.select(vec!["exposure".into()]);
    let original = ed.doc.graph.clone();
    ed.doc.set_param("exposure", "ev", ParamValue::Float(1.0));
    ed.doc.set_param("exposure", "ev", ParamValue::Float(2.0)); // same gesture
    ed.doc.end_gesture();
    let id = ed.doc.add_node("Tonemap", None).unwrap();
    ed.select(vec![id]);
    ed.delete_selection();
    let edited = ed.doc.graph.clone();
    let mut h = harness(ed);
    let cmd = egui::Modifiers::COMMAND;
    // Three steps back through the keyboard: delete, add, the ev drag.
    for _ in 0..3 {
        h.key_press_modifiers(cmd, egui::Key::Z);
        h.run_ok();
    }
    assert_eq!(h.state().doc.graph, original);
    assert!(!h.state_mut().doc.undo(), "nothing left to undo");
    for _ in 0..3 {
        h.key_press_modifiers(cmd | egui::Modifiers::SHIFT, egui::Key::Z);
        h.run_ok();
    }
    assert_eq!(h.state().doc.graph, edited);
    let ev = h.state().doc.graph.node("exposure").unwrap().params["ev"].clone();
    assert_eq!(ev, ParamValue::Float(2.0));
}

#[test]
fn copy_paste_and_delete() {
    let Some(mut ed) = editor(Some(&post_tonemap()), None) else {
        return;
    };
    // A reroute point on the copied wire travels with it.
    ed.doc
        .add_reroute("exposure.color", "tonemap.color", 0, (330.0, 10.0));
    ed.select(vec!["exposure".into(), "tonemap".into()]);
    let text = ed.copy_selection().unwrap();
    ed.paste(Some(&text));
    assert_eq!(
        ed.selected,
        vec!["exposure_2".to_owned(), "tonemap_2".to_owned()]
    );
    let g = &ed.doc.graph;
    assert_eq!(g.nodes.len(), 6);
    let pasted = g
        .edges
        .iter()
        .find(|e| e.from == "exposure_2.color" && e.to == "tonemap_2.color")
        .expect("the inner wire is pasted");
    let (a, b) = (
        g.node("exposure").unwrap().pos.unwrap(),
        g.node("exposure_2").unwrap().pos.unwrap(),
    );
    assert_eq!(pasted.via, [(330.0 + b.0 - a.0, 10.0 + b.1 - a.1)]);
    ed.delete_selection();
    assert_eq!(ed.doc.graph.nodes.len(), 4);
    assert_eq!(ed.doc.graph.edges.len(), 3);
}

#[test]
fn save_and_reload_round_trip() {
    let Some(mut ed) = editor(Some(&post_tonemap()), None) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let recent = dir.path().join("config/recent.ron");
    ed.recent = lumagraph_editor::files::Recent::load(Some(recent.clone()));
    ed.doc.set_param("exposure", "ev", ParamValue::Float(-0.5));
    assert!(ed.title().starts_with('●'));
    let path = dir.path().join("sub").join("edited.ron");
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    ed.save_as(&path).unwrap();
    assert!(!ed.title().starts_with('●'), "{}", ed.title());
    assert!(ed.title().contains("edited.ron"));
    let reloaded = Graph::load(&path).unwrap();
    assert_eq!(reloaded, ed.doc.graph);
    // The input path was rewritten to reach the same file from the new folder.
    let input = match &reloaded.node("input").unwrap().params["path"] {
        ParamValue::Str(s) => s.clone(),
        other => panic!("{other:?}"),
    };
    assert!(path.parent().unwrap().join(&input).is_file(), "{input}");
    // Saving again gives the same bytes (canonical layout).
    let bytes = std::fs::read(&path).unwrap();
    ed.save().unwrap();
    assert_eq!(std::fs::read(&path).unwrap(), bytes);
    // The recent-files list remembers it.
    let r = lumagraph_editor::files::Recent::load(Some(recent));
    assert_eq!(
        r.files.first().map(|p| p.ends_with("sub/edited.ron")),
        Some(true)
    );
    // And the editor opens it again.
    let ed2 = editor(Some(&path), None).unwrap();
    assert_eq!(ed2.doc.graph, reloaded);
    assert!(!ed2.doc.is_dirty());
}

#[test]
fn a_bad_file_opens_with_errors_not_a_crash() {
    let Some(_) = common::gpu() else { return };
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.ron");
    std::fs::write(&bad, "(version: 1, nodes: [ (id: \"a\", kind: ").unwrap();
    let ed = editor(Some(&bad), None).unwrap();
    let mut h = harness(ed);
    let (msg, is_err) = h.state().message.clone().unwrap();
    assert!(is_err && msg.contains("bad.ron"), "{msg}");
    // A file that parses but has unknown kinds and bad params: nodes are marked.
    let odd = dir.path().join("odd.ron");
    std::fs::write(
        &odd,
        "(version: 1, nodes: [(id: \"x\", kind: \"Smudge\"), (id: \"e\", kind: \"Exposure\", params: {\"ev\": 99.0})])",
    )
    .unwrap();
    h.state_mut().open(&odd);
    h.run_ok();
    let ed = h.state();
    assert!(
        ed.errors["x"][0].contains("unknown node kind \"Smudge\""),
        "{:?}",
        ed.errors
    );
    assert!(
        ed.errors["e"][0].contains("out of range"),
        "{:?}",
        ed.errors
    );
    h.get_by_label_contains("unknown node kind");
}

#[test]
fn snapshot_of_the_editor() {
    let Some(mut ed) = editor(Some(&post_tonemap()), None) else {
        return;
    };
    ed.select(vec!["tonemap".into()]);
    let mut h = harness(ed);
    // Timings vary from run to run; hide them.
    h.state_mut().preview.pass_ms.clear();
    h.state_mut().preview.stats = Default::default();
    h.state_mut().message = None; // holds the checkout's path
    h.run_ok();
    h.snapshot_options("editor_post_tonemap", &snapshot_options());
}

/// A post chain built through the editor's model, saved, then rendered as
/// `lumagraph render` does: the PNG equals the preview pixel for pixel.
#[test]
fn a_chain_built_in_the_editor_renders_headless_like_its_preview() {
    let Some(mut ed) = editor(None, None) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let chart = repo("assets/test_chart.exr");
    let input = ed.doc.add_node("ImageInput", None).unwrap();
    ed.doc
        .set_param(&input, "path", ParamValue::Str(chart.display().to_string()));
    let exposure = ed.doc.add_node("Exposure", None).unwrap();
    ed.doc.set_param(&exposure, "ev", ParamValue::Float(1.5));
    let tonemap = ed.doc.add_node("Tonemap", None).unwrap();
    ed.doc
        .set_param(&tonemap, "operator", ParamValue::Str("agx".into()));
    let out = ed.doc.add_node("Output", None).unwrap();
    ed.doc
        .set_param(&out, "path", ParamValue::Str("chain.png".into()));
    ed.doc
        .connect(&format!("{input}.color"), &format!("{exposure}.color"))
        .unwrap();
    ed.doc
        .connect(&format!("{exposure}.color"), &format!("{tonemap}.color"))
        .unwrap();
    ed.doc
        .connect(&format!("{tonemap}.color"), &format!("{out}.color"))
        .unwrap();
    ed.select(vec![out.clone()]);
    let mut h = harness(ed);
    let ed = h.state_mut();
    assert!(
        ed.errors.is_empty(),
        "{:?} {:?}",
        ed.errors,
        ed.graph_errors
    );
    assert_eq!(ed.effective_port(), Some(format!("{tonemap}.color")));
    let preview = ed.preview.image.clone().expect("preview");
    let path = dir.path().join("chain.ron");
    ed.save_as(&path).unwrap();

    // As `lumagraph render chain.ron --out DIR` does.
    let graph = Graph::load(&path).unwrap();
    let plan = compile(&graph, &[], None).unwrap();
    let paths = Resources {
        base_dir: graph.base_dir(),
        out_dir: dir.path().join("out"),
        ..Resources::default()
    };
    let mut exec =
        lumagraph_pathtrace::library::executor(h.state().preview.gpu(), plan, &paths).unwrap();
    let report = exec.run_frame().unwrap();
    assert_eq!(report.written, vec![dir.path().join("out/chain.png")]);
    let png = image::open(&report.written[0]).unwrap().to_rgba8();
    assert_eq!((png.width(), png.height()), (preview.width, preview.height));
    let max_diff = png
        .as_raw()
        .iter()
        .zip(&preview.rgba)
        .map(|(a, b)| a.abs_diff(*b))
        .max()
        .unwrap();
    assert!(max_diff <= 1, "preview and render differ by {max_diff}/255");
    assert_eq!(max_diff, 0, "expected identical pixels");
}

#[test]
fn clicking_a_node_selects_it() {
    let Some(ed) = editor(Some(&post_tonemap()), None) else {
        return;
    };
    let mut h = harness(ed);
    // The canvas is a transformed scene whose accesskit bounds kittest does not map, so
    // click where the node is drawn at the default zoom: the tonemap node's header.
    click_at(&mut h, egui::pos2(500.0, 316.0));
    assert_eq!(h.state().selected, vec!["tonemap".to_owned()]);
    h.get_by_role_and_label(Role::ComboBox, "operator");
}

/// Closing with unsaved changes asks first; a clean document closes at once.
#[test]
fn closing_with_unsaved_changes_asks_first() {
    let Some(mut ed) = editor(Some(&post_tonemap()), None) else {
        return;
    };
    assert!(ed.on_close_requested());
    ed.doc.set_param("exposure", "ev", ParamValue::Float(0.5));
    assert!(!ed.on_close_requested());
    let mut h = harness(ed);
    h.get_by_label("Unsaved changes");
    h.get_by_label("Discard").click();
    h.run_ok();
    assert!(h.state().quit_confirmed && h.state().wants_close);
}

/// Save in the unsaved-changes prompt of an untitled graph opens Save as; once the file is
/// written the quit goes on (and the file holds the graph).
#[test]
fn saving_an_untitled_graph_from_the_quit_prompt_then_quits() {
    let Some(mut ed) = editor(None, None) else {
        return;
    };
    ed.doc
        .add_node("Exposure", Some((0.0, 0.0)))
        .expect("an Exposure node");
    ed.doc.end_gesture();
    assert!(!ed.on_close_requested());
    let mut h = harness(ed);
    h.get_by_label("Unsaved changes");
    h.get_by_label("Save").click();
    h.run_ok();
    let pick = h.state().file_dialog.as_ref().map(|(p, _)| p.clone());
    assert_eq!(pick, Some(Pick::SaveGraph));
    assert!(!h.state().wants_close, "quit before the graph was saved");
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("untitled.ron");
    // What the dialog hands over when a file name is typed and confirmed.
    h.state_mut().file_dialog = None;
    h.state_mut().apply_pick(&Pick::SaveGraph, &path);
    h.run_ok();
    let ed = h.state();
    assert!(ed.quit_confirmed && ed.wants_close);
    let saved = Graph::load(&path).expect("the saved graph");
    assert_eq!(saved.nodes.len(), 1);
    assert_eq!(saved.nodes[0].kind, "Exposure");
}

/// Time of a param edit (compile, `update_params`, frame, readback) against a rebuild,
/// printed for the docs; asserts only that a param edit does not rebuild.
#[test]
fn param_edits_are_cheaper_than_rebuilds() {
    let Some(mut ed) = editor(Some(&post_tonemap()), None) else {
        return;
    };
    let base = ed.doc.base_dir();
    let port = Some("tonemap.color");
    let t = std::time::Instant::now();
    ed.preview
        .update(ed.doc.registry(), &ed.doc.graph, &base, port, None);
    let first = t.elapsed();
    let n: u32 = 10;
    let t = std::time::Instant::now();
    for i in 0..n {
        ed.doc
            .set_param("exposure", "ev", ParamValue::Float(f64::from(i + 1) * 0.1));
        assert!(
            ed.preview
                .update(ed.doc.registry(), &ed.doc.graph, &base, port, None)
        );
    }
    let per_edit = t.elapsed() / n;
    let s = &ed.preview.stats;
    eprintln!(
        "preview 512x256: first (build + shader compile) {:.1} ms; param edit {:.1} ms \
         (last frame {:.1} ms, readback+encode {:.1} ms); rebuilds {}, param updates {}",
        first.as_secs_f64() * 1e3,
        per_edit.as_secs_f64() * 1e3,
        s.frame_ms,
        s.readback_ms,
        s.rebuilds,
        s.param_updates
    );
    assert_eq!(s.rebuilds, 1);
    assert_eq!(s.param_updates, u64::from(n));
}

/// The path-traced graph with the Cornell box at a tiny preview size.
fn pathtrace_editor() -> Option<lumagraph_editor::Editor> {
    with_config(
        Some(&repo("graphs/pathtrace_denoise.ron")),
        &EditorConfig {
            scene: Some(repo("assets/cornell.ron")),
            preview_max: 24,
            ..EditorConfig::default()
        },
    )
}

/// With a scene, the path tracer's preview keeps accumulating while the editor runs; an
/// exposure edit through the inspector re-runs only exposure and tonemap over the
/// accumulation (no restart), which keeps growing; a `PathTrace` edit restarts it.
#[test]
fn accumulation_continues_through_a_post_edit() {
    let Some(mut ed) = pathtrace_editor() else {
        return;
    };
    assert!(ed.scene_error.is_none(), "{:?}", ed.scene_error);
    ed.select(vec!["exposure".into()]);
    let mut h = harness(ed);
    // As a click on tonemap's output pin label would: preview the end of the chain.
    h.state_mut().preview_port = Some("tonemap.color".into());
    for _ in 0..3 {
        h.step();
    }
    let ed = h.state();
    assert!(ed.errors.is_empty(), "{:?}", ed.errors);
    assert!(ed.preview.progressive);
    let img = ed.preview.image.as_ref().expect("a preview");
    assert_eq!((img.width, img.height), (24, 24), "capped preview size");
    assert_eq!(img.port, "tonemap.color");
    let before = ed.preview.samples.expect("a sample count");
    assert!(before >= 3, "{before} spp after the first frames");
    let restarts = ed.preview.stats.restarts;
    let updates = ed.preview.stats.param_updates;
    let picture = img.rgba.clone();

    // Click three quarters along the ev slider.
    let rect = h.get_by_role_and_label(Role::Slider, "ev").rect();
    click_at(
        &mut h,
        egui::pos2(rect.left() + rect.width() * 0.75, rect.center().y),
    );
    let ed = h.state();
    let ev = ed.doc.graph.node("exposure").unwrap().params["ev"]
        .as_f64()
        .unwrap();
    assert!(ev > 1.0, "ev {ev}");
    assert_eq!(ed.preview.stats.param_updates, updates + 1);
    assert_eq!(ed.preview.stats.last_update, ["exposure", "tonemap"]);
    assert_eq!(
        ed.preview.stats.restarts, restarts,
        "accumulation restarted"
    );
    let after = ed.preview.samples.unwrap();
    assert!(after >= before, "samples went from {before} to {after}");
    assert_ne!(ed.preview.image.as_ref().unwrap().rgba, picture);
    for _ in 0..2 {
        h.step();
    }
    let later = h.state().preview.samples.unwrap();
    assert!(later > after, "samples stuck at {after}");
    eprintln!("spp: {before} before the edit, {after} after it, {later} two frames later");

    // Selecting another node previews its output without restarting either.
    h.state_mut().select(vec!["denoise".into()]);
    h.step();
    assert_eq!(h.state().preview.stats.last_update, Vec::<String>::new());
    h.step();
    let ed = h.state();
    assert_eq!(ed.preview.image.as_ref().unwrap().port, "denoise.color");
    assert_eq!(
        ed.preview.stats.restarts, restarts,
        "accumulation restarted"
    );
    assert_eq!(ed.preview.stats.rebuilds, 1);
    assert!(ed.preview.samples.unwrap() > later);

    // A path tracer param feeds the accumulation: it restarts.
    h.state_mut()
        .doc
        .set_param("pathtrace", "samples_per_frame", ParamValue::Int(2));
    h.step();
    let ed = h.state();
    assert_eq!(ed.preview.stats.restarts, restarts + 1);
    assert!(
        ed.preview.samples.unwrap() <= 4,
        "{:?} spp after a restart",
        ed.preview.samples
    );
}

/// A scene that cannot be loaded is an error in the UI, never a panic; without a scene,
/// the nodes that render one say so.
#[test]
fn scene_errors_are_shown() {
    let Some(_) = common::gpu() else { return };
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("broken_scene.ron");
    std::fs::write(&bad, "(version: 1, camera: ").unwrap();
    let ed = with_config(
        Some(&repo("graphs/pathtrace_denoise.ron")),
        &EditorConfig {
            scene: Some(bad),
            preview_max: 16,
            ..EditorConfig::default()
        },
    )
    .unwrap();
    let mut h = harness(ed);
    let ed = h.state();
    let err = ed.scene_error.clone().expect("a scene error");
    assert!(err.contains("broken_scene.ron"), "{err}");
    assert!(
        ed.errors["pathtrace"][0].contains("none was given"),
        "{:?}",
        ed.errors
    );
    // In the side panel and the status line.
    assert_eq!(
        h.query_all_by_label_contains("cannot load the scene")
            .count(),
        2
    );
    // Loading a good one clears the errors.
    assert!(h.state_mut().load_scene(&repo("assets/cornell.ron")));
    h.step();
    let ed = h.state();
    assert!(ed.errors.is_empty(), "{:?}", ed.errors);
    assert!(ed.scene_error.is_none());
}

/// The `…` button of a path param opens the file dialog; a file picked in it sets the
/// param as one undoable edit.
#[test]
fn a_file_picked_in_the_dialog_sets_the_path_param() {
    let Some(mut ed) = editor(Some(&post_tonemap()), None) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let dir = dir.path().canonicalize().unwrap();
    for name in ["first.exr", "second.exr"] {
        std::fs::copy(repo("assets/test_chart.exr"), dir.join(name)).unwrap();
    }
    let first = dir.join("first.exr").display().to_string();
    ed.doc
        .set_param("input", "path", ParamValue::Str(first.clone()));
    ed.doc.end_gesture();
    ed.select(vec!["input".into()]);
    // Tall enough that the inspector's path row is on screen under ImageInput's doc.
    let mut h = common::harness_sized(ed, egui::vec2(1100.0, 900.0));
    h.get_by_role_and_label(Role::Button, "…").click();
    h.run_ok();
    let pick = h.state().file_dialog.as_ref().map(|(p, _)| p.clone());
    assert_eq!(pick, Some(Pick::Param("input".into(), "path".into())));
    // The dialog opens in the folder of the current file and lists it on a thread of its
    // own: wait for the listing (at most 10 s), then pick the other file.
    let start = std::time::Instant::now();
    while h.query_by_label_contains("second.exr").is_none() {
        assert!(
            start.elapsed() < std::time::Duration::from_secs(10),
            "the dialog never listed the folder"
        );
        std::thread::sleep(std::time::Duration::from_millis(10));
        h.step();
    }
    h.get_by_label_contains("second.exr").click();
    h.run_ok();
    h.get_by_role_and_label(Role::Button, "🗀  Open").click();
    h.run_ok();
    let ed = h.state_mut();
    assert!(ed.file_dialog.is_none());
    let second = dir.join("second.exr").display().to_string();
    assert_eq!(
        ed.doc.graph.node("input").unwrap().params["path"],
        ParamValue::Str(second)
    );
    assert!(ed.doc.undo());
    assert_eq!(
        ed.doc.graph.node("input").unwrap().params["path"],
        ParamValue::Str(first)
    );
}

/// Drags with simulated pointer events from `from` to `to`, a few frames apart, as a
/// hand would.
fn drag(
    h: &mut egui_kittest::Harness<'_, lumagraph_editor::Editor>,
    from: egui::Pos2,
    to: egui::Pos2,
) {
    h.hover_at(from);
    h.run_ok();
    h.event(egui::Event::PointerButton {
        pos: from,
        button: egui::PointerButton::Primary,
        pressed: true,
        modifiers: egui::Modifiers::NONE,
    });
    h.step();
    for i in 1..=8 {
        let t = i as f32 / 8.0;
        h.event(egui::Event::PointerMoved(from + (to - from) * t));
        h.step();
    }
    h.event(egui::Event::PointerButton {
        pos: to,
        button: egui::PointerButton::Primary,
        pressed: false,
        modifiers: egui::Modifiers::NONE,
    });
    h.step();
    h.run_ok();
}

/// Wires drawn on the canvas with the pointer: from an output pin to an input pin makes
/// the edge (one undo step); between incompatible ports it is refused with the reason.
#[test]
fn dragging_from_an_output_pin_to_an_input_pin_connects_them() {
    let Some(mut ed) = editor(Some(&post_tonemap()), None) else {
        return;
    };
    assert!(ed.doc.disconnect("input.color", "exposure.color"));
    ed.doc.end_gesture();
    let mut h = harness(ed);
    // Where the pins are drawn at the default zoom (see the snapshot): input's output
    // pin, exposure's input pin, tonemap's output pin.
    let input_out = egui::pos2(204.0, 339.0);
    let exposure_in = egui::pos2(267.0, 339.0);
    let tonemap_out = egui::pos2(562.0, 339.0);
    drag(&mut h, input_out, exposure_in);
    let ed = h.state_mut();
    assert!(
        ed.doc
            .graph
            .edges
            .iter()
            .any(|e| e.from == "input.color" && e.to == "exposure.color"),
        "{:?}",
        ed.doc.graph.edges
    );
    assert!(ed.errors.is_empty(), "{:?}", ed.errors);
    let connected = ed.doc.graph.clone();
    // ldr_color into an hdr_color input: refused, the graph unchanged.
    drag(&mut h, tonemap_out, exposure_in);
    let ed = h.state_mut();
    assert_eq!(ed.doc.graph, connected);
    let (msg, is_err) = ed.message.clone().expect("a refusal");
    assert!(is_err && msg.contains("produces ldr_color"), "{msg}");
    // The wire was one edit.
    assert!(ed.doc.undo());
    assert!(!ed.doc.graph.edges.iter().any(|e| e.to == "exposure.color"));
}

/// The default graph on the Cornell box, paused after its first frame: nodes with several
/// outputs show every pin label in full.
#[test]
fn snapshot_of_the_path_traced_graph() {
    let Some(mut ed) = pathtrace_editor() else {
        return;
    };
    ed.select(vec!["denoise".into()]);
    ed.preview.paused = true;
    let mut h = harness(ed);
    h.run_ok();
    // Timings vary from run to run; hide them.
    h.state_mut().preview.pass_ms.clear();
    h.state_mut().preview.stats = Default::default();
    h.state_mut().message = None;
    h.run_ok();
    h.snapshot_options("editor_pathtrace_denoise", &snapshot_options());
}

/// What nodes measure shows under the preview (`AutoExposure`'s exposure, `Difference`'s
/// error), and the histogram scope counts the previewed image's pixels.
#[test]
fn measurements_and_the_histogram_scope_show_under_the_preview() {
    let Some(mut ed) = editor(None, None) else {
        return;
    };
    let chart = repo("assets/test_chart.exr").display().to_string();
    let input = ed.doc.add_node("ImageInput", None).unwrap();
    ed.doc
        .set_param(&input, "path", ParamValue::Str(chart.clone()));
    let auto = ed.doc.add_node("AutoExposure", None).unwrap();
    let tonemap = ed.doc.add_node("Tonemap", None).unwrap();
    let diff = ed.doc.add_node("Difference", None).unwrap();
    for (from, to) in [
        (format!("{input}.color"), format!("{auto}.color")),
        (format!("{auto}.color"), format!("{tonemap}.color")),
        (format!("{input}.color"), format!("{diff}.color")),
        (format!("{auto}.color"), format!("{diff}.reference")),
    ] {
        ed.doc.connect(&from, &to).unwrap();
    }
    ed.preview_port = Some(format!("{tonemap}.color"));
    let mut h = harness(ed);
    let ed = h.state();
    assert!(ed.errors.is_empty(), "{:?}", ed.errors);
    let ev = ed
        .preview
        .measurements
        .iter()
        .find(|(n, m)| *n == auto && m.name == "exposure_ev")
        .map(|(_, m)| m.value)
        .expect("the exposure is measured");
    let label = format!("{auto}.exposure_ev: {ev:.4e}");
    h.get_by_label(&label);

    // The histogram: every previewed pixel counted once per channel.
    h.get_by_role_and_label(Role::ComboBox, "scope").click();
    h.run_ok();
    h.get_by_label("histogram").click();
    h.run_ok();
    let ed = h.state();
    let img = ed.preview.image.as_ref().unwrap();
    let hist = ed.scope.drawn_histogram().expect("a histogram");
    for channel in hist {
        assert_eq!(
            u64::from(channel.iter().sum::<u32>()),
            u64::from(img.width) * u64::from(img.height)
        );
    }

    // The heat map previewed: the error of the chart against its exposed self.
    h.state_mut().preview_port = Some(format!("{diff}.heat"));
    h.run_ok();
    let ed = h.state();
    let relmse = ed
        .preview
        .measurements
        .iter()
        .find(|(n, m)| *n == diff && m.name == "relmse")
        .map(|(_, m)| m.value)
        .expect("the error is measured");
    assert!(relmse > 0.0, "{relmse}");
}

/// Ctrl+G's action on two selected nodes: they move to a group file, one group node takes
/// their place, and the graph renders the same image; Tab opens the group, where an edit
/// shows in the preview of the graph around it, and Tab leaves it, saving the file.
#[test]
fn group_nodes_open_the_group_edit_it_and_leave() {
    let Some(ed) = editor(None, None) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let main = dir.path().join("main.ron");
    let text = shipped_text("post_tonemap.ron");
    std::fs::write(&main, text).unwrap();
    let mut h = harness(ed);
    h.state_mut().open(&main);
    h.run_ok();
    let before = h.state().preview.image.clone().expect("preview");

    // Group exposure and tonemap.
    let ed = h.state_mut();
    ed.select(vec!["exposure".into(), "tonemap".into()]);
    let group_file = dir.path().join("groups/look.ron");
    std::fs::create_dir_all(group_file.parent().unwrap()).unwrap();
    ed.group_selection(&group_file);
    assert_eq!(ed.selected, ["look"], "{:?}", ed.message);
    let g = &ed.doc.graph;
    assert_eq!(g.groups[0].file, "groups/look.ron");
    let ids: Vec<&str> = g.nodes.iter().map(|n| n.id.as_str()).collect();
    assert_eq!(ids, ["input", "out", "look"]);
    let group = Graph::load(&group_file).unwrap();
    assert_eq!(group.nodes.len(), 2);
    assert_eq!(group.interface.inputs[0].to, ["exposure.color"]);
    assert_eq!(group.interface.outputs[0].from, "tonemap.color");
    let params: Vec<&str> = group
        .interface
        .params
        .iter()
        .map(|p| p.name.as_str())
        .collect();
    assert_eq!(params, ["exposure_ev", "tonemap_operator"]);
    h.run_ok();
    let ed = h.state();
    assert!(
        ed.errors.is_empty() && ed.graph_errors.is_empty(),
        "{:?} {:?}",
        ed.errors,
        ed.graph_errors
    );
    let grouped = ed.preview.image.clone().expect("preview");
    assert_eq!(grouped.rgba, before.rgba, "grouping changed the image");

    // Open it, raise the exposure inside, and the preview of the graph around it follows.
    let ed = h.state_mut();
    ed.select(vec!["look".into()]);
    ed.toggle_group();
    assert_eq!(ed.doc.path.as_deref(), Some(group_file.as_path()));
    assert!(
        ed.title().contains("look.ron in main.ron (look)"),
        "{}",
        ed.title()
    );
    ed.select(vec!["tonemap".into()]);
    ed.doc.set_param("exposure", "ev", ParamValue::Float(1.0));
    h.run_ok();
    let ed = h.state();
    assert!(ed.graph_errors.is_empty(), "{:?}", ed.graph_errors);
    let inside = ed
        .preview
        .image
        .clone()
        .expect("a preview inside the group");
    let mean = |i: &lumagraph_editor::preview::PreviewImage| {
        i.rgba.iter().map(|&p| f64::from(p)).sum::<f64>() / i.rgba.len() as f64
    };
    assert!(
        mean(&inside) > mean(&before) + 1.0,
        "{} vs {}",
        mean(&inside),
        mean(&before)
    );

    // Leave: the group file is saved with the edit, and the outer graph uses it.
    let ed = h.state_mut();
    ed.toggle_group();
    assert!(ed.outer.is_empty());
    assert_eq!(ed.doc.path.as_deref(), Some(main.as_path()));
    let saved = Graph::load(&group_file).unwrap();
    assert_eq!(
        saved.node("exposure").unwrap().params["ev"],
        ParamValue::Float(1.0)
    );
    h.run_ok();
    let ed = h.state();
    let after = ed.preview.image.clone().expect("preview");
    assert_eq!(after.rgba, inside.rgba);
    // Undo brings the nodes back (the group file stays).
    let ed = h.state_mut();
    assert!(ed.doc.undo());
    assert!(ed.doc.graph.node("exposure").is_some());
}

/// Live reload: a declared kind's `.wgsl` file changed on disk is read again and the
/// preview follows; a change that does not compile keeps the last good pipeline (the
/// preview stays as it was) and marks the kind's node with the located error; fixing the
/// file clears it.
#[test]
fn a_changed_wgsl_file_reloads_and_a_broken_one_keeps_the_last_good_pipeline() {
    let Some(ed) = editor(None, None) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let graph = dir.path().join("custom.ron");
    let text = shipped_text("custom_kinds.ron");
    std::fs::write(&graph, text).unwrap();
    let wgsl = dir.path().join("posterize.wgsl");
    let original = std::fs::read_to_string(repo("graphs/posterize.wgsl")).unwrap();
    std::fs::write(&wgsl, &original).unwrap();
    let mut h = harness(ed);
    h.state_mut().open(&graph);
    h.state_mut().select(vec!["posterize".into()]);
    h.run_ok();
    let first = h.state().preview.image.clone().expect("preview");
    assert!(h.state().errors.is_empty(), "{:?}", h.state().errors);

    // Touch the file with new content: the poll notices (its time changed) and reloads.
    let poll = |h: &mut egui_kittest::Harness<'static, lumagraph_editor::Editor>, at: f64| {
        assert!(h.state_mut().poll_files(at), "no change seen");
        h.run_ok();
    };
    let set = |text: &str, seconds: u64| {
        std::fs::write(&wgsl, text).unwrap();
        let t = std::time::SystemTime::UNIX_EPOCH + std::time::Duration::from_secs(seconds);
        std::fs::File::options()
            .write(true)
            .open(&wgsl)
            .unwrap()
            .set_modified(t)
            .unwrap();
    };
    set(&original.replace("round(", "floor("), 1_000_000);
    poll(&mut h, 1e9);
    let ed = h.state();
    assert!(ed.errors.is_empty(), "{:?}", ed.errors);
    let floored = ed.preview.image.clone().expect("preview");
    assert_ne!(
        floored.rgba, first.rgba,
        "the preview did not follow the new WGSL"
    );

    // Broken: the last good pipeline stays, the node shows where the error is.
    set(
        &original.replace("return vec4f(", "return vec3f("),
        2_000_000,
    );
    poll(&mut h, 2e9);
    let ed = h.state();
    let marks = ed
        .errors
        .get("posterize")
        .expect("an error on the node")
        .join("\n");
    assert!(marks.contains("posterize.wgsl:"), "{marks}");
    assert_eq!(
        ed.preview.image.as_ref().map(|i| &i.rgba),
        Some(&floored.rgba)
    );
    assert!(ed.preview.error.is_none(), "{:?}", ed.preview.error);

    // Fixed: the marks go, the original image is back.
    set(&original, 3_000_000);
    poll(&mut h, 3e9);
    let ed = h.state();
    assert!(ed.errors.is_empty(), "{:?}", ed.errors);
    assert_eq!(
        ed.preview.image.as_ref().map(|i| &i.rgba),
        Some(&first.rgba)
    );
}

/// A graph opens framed (every node in view); a node added from the menu bar appears in
/// the middle of the view, selected; Frame selected (F) brings a node far away into view,
/// Frame all (Home) every node (as far as the canvas zooms out: 1:5).
#[test]
fn new_nodes_appear_in_view_and_framing_brings_nodes_into_view() {
    let Some(ed) = editor(Some(&post_tonemap()), None) else {
        return;
    };
    let mut h = harness(ed);
    h.run_ok();
    let inside = |ed: &lumagraph_editor::Editor, id: &str| {
        let view = ed.canvas.visible_rect().expect("drawn");
        let (x, y) = ed
            .doc
            .graph
            .node(id)
            .and_then(|n| n.pos)
            .expect("a position");
        view.contains(egui::pos2(x, y))
    };
    let ed = h.state();
    for n in &ed.doc.graph.nodes {
        assert!(inside(ed, &n.id), "{} is out of view", n.id);
    }
    // Add from the menu bar: in view, selected.
    h.state_mut().add_node_in_view("Blur");
    h.run_ok();
    let ed = h.state();
    assert_eq!(ed.selected, ["blur"]);
    assert!(inside(ed, "blur"), "the new node is out of view");
    let view = ed.canvas.visible_rect().unwrap();
    let (x, y) = ed.doc.graph.node("blur").unwrap().pos.unwrap();
    assert!(
        (x - view.center().x).abs() < 200.0 && (y - view.center().y).abs() < 200.0,
        "not near the middle: ({x}, {y}) in {view:?}"
    );
    // A node far away: out of view until framed.
    let ed = h.state_mut();
    ed.doc
        .move_nodes(&[("blur".to_owned(), (2_500.0, 1_200.0))]);
    h.run_ok();
    assert!(!inside(h.state(), "blur"));
    h.state_mut().select(vec!["blur".into()]);
    h.key_press(egui::Key::F);
    h.run_ok();
    assert!(
        inside(h.state(), "blur"),
        "Frame selected did not bring it into view"
    );
    h.key_press(egui::Key::Home);
    h.run_ok();
    let ed = h.state();
    for n in &ed.doc.graph.nodes {
        assert!(inside(ed, &n.id), "Frame all left {} out", n.id);
    }
}

/// The keyboard shortcuts the menus show, sent as key presses: Ctrl+D duplicates, Delete
/// deletes, Ctrl+Z undoes, Ctrl+Y and Ctrl+Shift+Z redo, Ctrl+S saves.
#[test]
fn keyboard_shortcuts_work() {
    use egui::{Key, Modifiers};
    let Some(ed) = editor(None, None) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("g.ron");
    let text = shipped_text("post_tonemap.ron");
    std::fs::write(&path, text).unwrap();
    let mut h = harness(ed);
    h.state_mut().open(&path);
    h.state_mut().select(vec!["exposure".into()]);
    h.run_ok();
    let nodes = |h: &egui_kittest::Harness<'static, lumagraph_editor::Editor>| {
        h.state().doc.graph.nodes.len()
    };
    h.key_press_modifiers(Modifiers::COMMAND, Key::D);
    h.run_ok();
    assert_eq!(nodes(&h), 5, "Ctrl+D");
    assert_eq!(h.state().selected, ["exposure_2"]);
    h.key_press(Key::Delete);
    h.run_ok();
    assert_eq!(nodes(&h), 4, "Delete");
    h.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    h.run_ok();
    assert_eq!(nodes(&h), 5, "Ctrl+Z");
    h.key_press_modifiers(Modifiers::COMMAND, Key::Y);
    h.run_ok();
    assert_eq!(nodes(&h), 4, "Ctrl+Y");
    h.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    h.key_press_modifiers(Modifiers::COMMAND | Modifiers::SHIFT, Key::Z);
    h.run_ok();
    assert_eq!(nodes(&h), 4, "Ctrl+Shift+Z");
    h.state_mut()
        .doc
        .set_param("exposure", "ev", ParamValue::Float(0.75));
    assert!(h.state().title().starts_with('●'));
    h.key_press_modifiers(Modifiers::COMMAND, Key::S);
    h.run_ok();
    assert!(!h.state().title().starts_with('●'), "Ctrl+S did not save");
    let saved = Graph::load(&path).unwrap();
    assert_eq!(
        saved.node("exposure").unwrap().params["ev"],
        ParamValue::Float(0.75)
    );
}

/// Saving keeps what the user wrote: the header comment of a shipped graph survives an
/// edit and a save from the editor, and nodes stay one per line.
#[test]
fn save_keeps_the_comments_of_the_file() {
    let Some(ed) = editor(None, None) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("g.ron");
    let text = shipped_text("post_tonemap.ron").replace(
        "        (id: \"tonemap\"",
        "        // The curve: try agx.\n        (id: \"tonemap\"",
    );
    std::fs::write(&path, &text).unwrap();
    let mut h = harness(ed);
    h.state_mut().open(&path);
    h.state_mut()
        .doc
        .set_param("exposure", "ev", ParamValue::Float(0.5));
    h.state_mut().save().unwrap();
    let saved = std::fs::read_to_string(&path).unwrap();
    let header: Vec<&str> = text.lines().take_while(|l| l.starts_with("//")).collect();
    assert!(!header.is_empty());
    for line in header {
        assert!(saved.contains(line), "lost {line:?}:\n{saved}");
    }
    assert!(
        saved.contains("        // The curve: try agx.\n        (id: \"tonemap\""),
        "{saved}"
    );
    assert!(
        saved.contains("(id: \"exposure\", kind: \"Exposure\", params: {\"ev\": 0.5}"),
        "{saved}"
    );
    // Nothing else changed.
    assert_eq!(saved.replace("\"ev\": 0.5", "\"ev\": 0.0"), text);
}

/// The preview's viewer: the readout under the pointer is the port's linear value (the
/// chart × 2^ev, against the CPU, to 1e-5 relative); a pinned snapshot compared with a wipe shows the live
/// image left of the line and the snapshot right of it, on screen and in the readout.
#[test]
fn pixel_readout_and_a_b_wipe() {
    let Some(ed) = editor(Some(&post_tonemap()), None) else {
        return;
    };
    let chart = lumagraph_render::image_io::load(&repo("assets/test_chart.exr")).unwrap();
    let mut h = harness(ed);
    h.state_mut().select(vec!["exposure".into()]);
    h.state_mut()
        .doc
        .set_param("exposure", "ev", ParamValue::Float(-3.0));
    h.run_ok();
    // Zoomed in (nearest-neighbour pixels), centred on the image.
    let view = &mut h.state_mut().view;
    view.zoom = Some(4.0);
    view.center = egui::vec2(chart.width as f32 / 2.0, chart.height as f32 / 2.0);
    h.run_ok();
    // Where pixel (x, y) is on screen as the viewer last drew the image (the panel's
    // layout changes with its controls, so this is asked each time).
    let screen = |h: &egui_kittest::Harness<'static, lumagraph_editor::Editor>, x: u32, y: u32| {
        let rect = h.state().view.rect.expect("drawn");
        let scale = rect.width() / chart.width as f32;
        rect.min + egui::vec2(x as f32 + 0.5, y as f32 + 0.5) * scale
    };
    let (x, y) = (chart.width / 2 - 3, chart.height / 2 + 10);
    h.hover_at(screen(&h, x, y));
    h.run_ok();
    let r = h.state().view.hover.expect("a readout");
    assert_eq!((r.x, r.y), (x, y));
    let want = chart.pixels[(y * chart.width + x) as usize];
    for c in 0..3 {
        assert!(
            (r.rgba[c] - 0.125 * want[c]).abs() <= 1e-5 * want[c].abs().max(1.0),
            "channel {c}: {} vs 2^-3 × {}",
            r.rgba[c],
            want[c]
        );
    }
    assert!(!r.from_snapshot);

    // Pin at ev -3, go to ev -1: the live image is 4× the snapshot.
    let ed = h.state_mut();
    let (image, ty) = ed.preview.linear.clone().expect("an image");
    ed.view.pin("exposure.color", image, ty, None);
    ed.view.compare = lumagraph_editor::viewer::Compare::Wipe;
    ed.view.wipe = 0.5;
    ed.doc.set_param("exposure", "ev", ParamValue::Float(-1.0));
    h.run_ok();
    h.run_ok();
    let live = h.state().preview.linear.clone().unwrap().0;
    let snap = h.state().view.pinned.as_ref().unwrap().image.clone();
    let snap = &snap;
    // The wipe is at the middle of the view, which is centred on the image.
    let wipe_x = screen(&h, chart.width / 2, 0).x;
    let (xl, xr) = (chart.width / 2 - 4, chart.width / 2 + 3);
    assert!(screen(&h, xl, y).x < wipe_x && screen(&h, xr, y).x > wipe_x);
    h.hover_at(screen(&h, xr, y));
    h.run_ok();
    let right = h.state().view.hover.expect("a readout");
    assert!(right.from_snapshot);
    assert_eq!((right.x, right.y), (xr, y));
    assert_eq!(right.rgba, snap.pixels[(y * chart.width + xr) as usize]);
    h.hover_at(screen(&h, xl, y));
    h.run_ok();
    let left = h.state().view.hover.expect("a readout");
    assert!(!left.from_snapshot);
    assert_eq!(left.rgba, live.pixels[(y * chart.width + xl) as usize]);
    // On screen: the displayed bytes of each side.
    // The pointer away, so its arrow does not cover the pixels looked at.
    h.hover_at(egui::pos2(300.0, 500.0));
    h.run_ok();
    let (pl, pr) = (screen(&h, xl, y), screen(&h, xr, y));
    let shot = h.render().expect("a rendering");
    let shown = |p: egui::Pos2| {
        let px = shot.get_pixel(p.x as u32, p.y as u32).0;
        [px[0], px[1], px[2]]
    };
    let bytes = |img: &lumagraph_render::cpu::Image, x: u32| {
        let rgba = lumagraph_editor::viewer::display_rgba(img, ty, 0.0, false);
        let i = 4 * (y * chart.width + x) as usize;
        [rgba[i], rgba[i + 1], rgba[i + 2]]
    };
    let close = |a: [u8; 3], b: [u8; 3]| a.iter().zip(&b).all(|(a, b)| a.abs_diff(*b) <= 2);
    let (l_live, l_snap) = (bytes(&live, xl), bytes(snap, xl));
    let (r_live, r_snap) = (bytes(&live, xr), bytes(snap, xr));
    assert!(
        !close(r_live, r_snap),
        "pick pixels where the images differ"
    );
    assert!(
        close(shown(pl), l_live),
        "{:?} vs live {l_live:?} / snapshot {l_snap:?}",
        shown(pl)
    );
    assert!(
        close(shown(pr), r_snap),
        "{:?} vs snapshot {r_snap:?} / live {r_live:?}",
        shown(pr)
    );
}

/// Node thumbnails (View → Node thumbnails): off by default on a CPU adapter; on, every
/// node with an output shows a picture of it at most `THUMBNAIL_SIZE` wide, the output
/// shrunk and encoded as the preview encodes its image; a param edit refreshes them.
#[test]
fn node_thumbnails_show_each_output() {
    use lumagraph_editor::preview::{THUMBNAIL_SIZE, encode_rgba8, shrink};
    let Some(ed) = editor(Some(&post_tonemap()), None) else {
        return;
    };
    let mut h = harness(ed);
    let cpu = h.state().preview.gpu().adapter.get_info().device_type == wgpu::DeviceType::Cpu;
    assert_eq!(h.state().preview.thumbnails_on, !cpu);
    h.state_mut().preview.set_thumbnails(true);
    h.state_mut().select(vec!["tonemap".into()]);
    h.run_ok();
    let ed = h.state();
    let nodes: Vec<&str> = ed.preview.thumbnails.keys().map(String::as_str).collect();
    assert_eq!(
        nodes,
        ["exposure", "input", "tonemap"],
        "the Output node has no output"
    );
    let t = &ed.preview.thumbnails["tonemap"];
    assert_eq!(t.port, "tonemap.color");
    assert!(t.width.max(t.height) <= THUMBNAIL_SIZE && t.width.max(t.height) > THUMBNAIL_SIZE / 2);
    let (image, ty) = ed.preview.linear.clone().unwrap();
    assert_eq!(t.rgba, encode_rgba8(&shrink(&image, THUMBNAIL_SIZE), ty));
    let before = ed.preview.thumbnails["exposure"].rgba.clone();
    h.state_mut()
        .doc
        .set_param("exposure", "ev", ParamValue::Float(-2.0));
    h.run_ok();
    assert_ne!(h.state().preview.thumbnails["exposure"].rgba, before);
    h.state_mut().preview.set_thumbnails(false);
    assert!(h.state().preview.thumbnails.is_empty());
}

/// The live error plot on `graphs/compare_reference.ron` (the Cornell box against its
/// Mitsuba reference, raw and denoised, at full size): each frame of the accumulation
/// adds one point per `Difference` node, and the points are those nodes' measurements on
/// those frames; the plot shows beside the preview, and its CSV export has the header of
/// `converge.csv` and one row per point.
#[test]
fn the_live_error_plot_has_the_difference_nodes_measurements() {
    let Some(ed) = with_config(
        Some(&repo("graphs/compare_reference.ron")),
        &EditorConfig {
            scene: Some(repo("assets/cornell.ron")),
            preview_max: 256,
            ..EditorConfig::default()
        },
    ) else {
        return;
    };
    let mut h = harness(ed);
    let mut expected: Vec<(String, u64, f64)> = Vec::new();
    let mut last_spp = 0;
    for _ in 0..6 {
        h.step();
        let ed = h.state();
        assert!(ed.errors.is_empty(), "{:?}", ed.errors);
        let spp = ed.preview.samples.expect("a sample count");
        if spp == last_spp {
            continue;
        }
        last_spp = spp;
        for (node, m) in &ed.preview.measurements {
            if m.name == "relmse" {
                expected.push((node.clone(), spp, m.value));
            }
        }
    }
    let ed = h.state();
    let points: Vec<(String, u64, f64)> = ed
        .preview
        .curve
        .points
        .iter()
        .map(|p| (p.node.clone(), p.spp, p.relmse))
        .collect();
    // The first frames (before the loop) are in the curve too: compare its end.
    assert!(expected.len() >= 6, "{expected:?}");
    assert_eq!(points[points.len() - expected.len()..], expected[..]);
    assert_eq!(ed.preview.curve.nodes(), ["raw_error", "denoised_error"]);
    let raw: Vec<f64> = points
        .iter()
        .filter(|p| p.0 == "raw_error")
        .map(|p| p.2)
        .collect();
    assert!(raw.last() < raw.first(), "the raw error falls: {raw:?}");
    let seconds: Vec<f64> = ed.preview.curve.points.iter().map(|p| p.seconds).collect();
    assert!(seconds.windows(2).all(|w| w[0] <= w[1]), "{seconds:?}");
    h.get_by_label("error against");

    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("error.csv");
    h.state_mut().apply_pick(&Pick::ErrorCsv, &csv);
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some("output,spp,seconds,rmse,relmse,ssim,gpu_ms")
    );
    assert_eq!(lines.count(), h.state().preview.curve.points.len());
}

/// Wiring by search: a wire dragged from an output pin and dropped on empty canvas opens
/// Add node listing only the kinds with an input that takes it; the kind picked is placed
/// where the wire was dropped and wired to it, in one undo step. From an input pin, the
/// kinds with a fitting output. `Shift+A` opens Add node at the pointer; `Escape` closes it.
#[test]
fn a_wire_dropped_on_empty_canvas_adds_a_node_that_fits_it() {
    use egui::{Key, Modifiers};
    let Some(mut ed) = editor(Some(&post_tonemap()), None) else {
        return;
    };
    assert!(ed.doc.disconnect("input.color", "exposure.color"));
    ed.doc.end_gesture();
    let mut h = harness(ed);
    // Pins as drawn at the default zoom (see the snapshot), and empty canvas above them.
    let tonemap_out = egui::pos2(562.0, 339.0);
    let exposure_in = egui::pos2(267.0, 339.0);
    let empty = egui::pos2(450.0, 150.0);
    let nodes = h.state().doc.graph.nodes.len();
    drag(&mut h, tonemap_out, empty);
    h.get_by_label("Add node wired to tonemap.color");
    // An LDR image: no source (PathTrace has no input), no HDR-only input (Exposure).
    for absent in ["PathTrace", "Exposure", "ImageInput"] {
        assert!(
            h.query_by_role_and_label(Role::Button, absent).is_none(),
            "{absent} listed for an LDR wire"
        );
    }
    h.get_by_role_and_label(Role::Button, "Output").click();
    h.run_ok();
    let ed = h.state_mut();
    assert_eq!(ed.doc.graph.nodes.len(), nodes + 1);
    let new = ed.doc.graph.nodes.last().unwrap().clone();
    assert_eq!(new.kind, "Output");
    let tonemap_x = ed.doc.graph.node("tonemap").unwrap().pos.unwrap().0;
    let (x, y) = new.pos.expect("placed");
    assert!(x < tonemap_x + 60.0 && y < -100.0, "placed at ({x}, {y})");
    let wired = format!("{}.color", new.id);
    assert!(
        ed.doc
            .graph
            .edges
            .iter()
            .any(|e| e.from == "tonemap.color" && e.to == wired),
        "{:?}",
        ed.doc.graph.edges
    );
    assert!(ed.doc.undo(), "one undo step");
    assert_eq!(ed.doc.graph.nodes.len(), nodes);
    assert!(!ed.doc.graph.edges.iter().any(|e| e.to == wired));
    h.run_ok();

    // From exposure's free input: the kinds with an HDR output.
    drag(&mut h, exposure_in, egui::pos2(150.0, 150.0));
    h.get_by_label("Add node wired to exposure.color");
    assert!(h.query_by_role_and_label(Role::Button, "Tonemap").is_none());
    h.get_by_role_and_label(Role::Button, "ImageInput").click();
    h.run_ok();
    let ed = h.state();
    let new = ed.doc.graph.nodes.last().unwrap();
    assert_eq!(new.kind, "ImageInput");
    assert!(
        ed.doc
            .graph
            .edges
            .iter()
            .any(|e| e.from == format!("{}.color", new.id) && e.to == "exposure.color")
    );

    // Shift+A at the pointer.
    let count = h.state().doc.graph.nodes.len();
    h.hover_at(empty);
    h.run_ok();
    h.key_press_modifiers(Modifiers::SHIFT, Key::A);
    h.run_ok();
    h.get_by_role_and_label(Role::Button, "Blur");
    h.key_press(Key::Escape);
    h.run_ok();
    assert!(h.query_by_role_and_label(Role::Button, "Blur").is_none());
    h.hover_at(empty);
    h.key_press_modifiers(Modifiers::SHIFT, Key::A);
    h.run_ok();
    // The menu lists every kind, longer than the window: search for it, as a user would.
    h.event(egui::Event::Text("blur".into()));
    h.run_ok();
    h.get_by_role_and_label(Role::Button, "Blur").click();
    h.run_ok();
    let ed = h.state();
    assert_eq!(ed.doc.graph.nodes.len(), count + 1);
    let blur = ed.doc.graph.nodes.last().unwrap();
    assert_eq!(blur.kind, "Blur");
    let (x, y) = blur.pos.expect("placed");
    assert!(x < tonemap_x + 60.0 && y < -100.0, "placed at ({x}, {y})");
    assert_eq!(ed.selected, std::slice::from_ref(&blur.id));
}

/// A node dragged onto a wire goes into it where the types allow: a Blur dropped on the
/// exposure → tonemap wire (HDR) ends up between them, in one undo step after the move;
/// a Tonemap (HDR in, LDR out) dropped on it is refused with the reason.
#[test]
fn a_node_dropped_on_a_wire_goes_into_it() {
    let Some(ed) = editor(Some(&post_tonemap()), None) else {
        return;
    };
    let mut h = harness(ed);
    // Added after the graph was framed, so the view is the snapshot's: there graph
    // coordinates map to the screen by x' = 0.791 x + 98.5, y' = 0.791 y + 309.7 (from
    // the pins of exposure and tonemap). The node's box is about 105 by 60 graph units.
    let blur = h
        .state_mut()
        .doc
        .add_node("Blur", Some((300.0, -250.0)))
        .unwrap();
    h.state_mut().doc.end_gesture();
    h.run_ok();
    let to_screen = |x: f32, y: f32| egui::pos2(0.791 * x + 98.5, 0.791 * y + 309.7);
    let center = to_screen(345.0, -227.0);
    let header = to_screen(345.0, -245.0);
    // The wire between exposure's output (387, 339) and tonemap's input (441, 339).
    let on_wire = egui::pos2(414.0, 339.0);
    drag(&mut h, header, header + (on_wire - center));
    let wired = format!("{blur}.color");
    let ed = h.state_mut();
    let edges: Vec<(&str, &str)> = ed
        .doc
        .graph
        .edges
        .iter()
        .map(|e| (e.from.as_str(), e.to.as_str()))
        .collect();
    assert!(
        edges.contains(&("exposure.color", wired.as_str())),
        "{edges:?}"
    );
    assert!(
        edges.contains(&(wired.as_str(), "tonemap.color")),
        "{edges:?}"
    );
    assert!(
        !edges.contains(&("exposure.color", "tonemap.color")),
        "{edges:?}"
    );
    assert!(ed.errors.is_empty(), "{:?}", ed.errors);
    assert!(ed.doc.undo());
    assert!(
        ed.doc
            .graph
            .edges
            .iter()
            .any(|e| e.from == "exposure.color" && e.to == "tonemap.color")
    );
    assert!(!ed.doc.graph.edges.iter().any(|e| e.to == wired));

    // Types that do not fit: refused, with the reason.
    let before = ed.doc.graph.edges.clone();
    let err = ed
        .doc
        .insert_on_edge("input.color", "exposure.color", "tonemap")
        .unwrap_err();
    assert!(err.contains("does not go into the wire"), "{err}");
    let tm2 = ed.doc.add_node("Tonemap", Some((300.0, -250.0))).unwrap();
    let err = ed
        .doc
        .insert_on_edge("exposure.color", "tonemap.color", &tm2)
        .unwrap_err();
    assert!(err.contains("ldr") || err.contains("hdr"), "{err}");
    let _ = before;
}

/// Frames: Ctrl+J puts the selected nodes in a frame (selected, one undo step); dragging
/// its title moves its nodes and only them (one undo step); the frame and a node's colour
/// survive save and load (graph version 4, the file's comments kept), and the command
/// line's compiler ignores them (the same plan).
#[test]
fn a_frame_moves_its_nodes_and_survives_save_and_load() {
    use egui::{Key, Modifiers};
    let Some(ed) = editor(None, None) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("g.ron");
    std::fs::write(&path, shipped_text("post_tonemap.ron")).unwrap();
    let mut h = harness(ed);
    h.state_mut().open(&path);
    h.run_ok();
    h.state_mut()
        .select(vec!["exposure".into(), "tonemap".into()]);
    h.key_press_modifiers(Modifiers::COMMAND, Key::J);
    h.run_ok();
    let pos = |h: &egui_kittest::Harness<'static, lumagraph_editor::Editor>, id: &str| {
        h.state().doc.graph.node(id).unwrap().pos.unwrap()
    };
    let ed = h.state();
    assert_eq!(ed.doc.graph.frames.len(), 1);
    assert_eq!(ed.doc.graph.frames[0].nodes, ["exposure", "tonemap"]);
    assert_eq!(ed.selected_frame, Some(0));
    h.get_by_label("Frame");
    let before: Vec<(f32, f32)> = ["input", "exposure", "tonemap", "out"]
        .iter()
        .map(|id| pos(&h, id))
        .collect();

    // The title bar's centre on screen, and the zoom.
    let ed = h.state();
    let boxes = ed.canvas.frame_boxes(&ed.doc.graph, None);
    let title = boxes[0].title_rect().center();
    let on_screen = ed.canvas.to_screen(title).unwrap();
    let zoom = ed.canvas.to_screen(title + egui::vec2(0.0, 1.0)).unwrap().y - on_screen.y;
    drag(&mut h, on_screen, on_screen + egui::vec2(0.0, 100.0));
    let after: Vec<(f32, f32)> = ["input", "exposure", "tonemap", "out"]
        .iter()
        .map(|id| pos(&h, id))
        .collect();
    assert_eq!(after[0], before[0], "input is not in the frame");
    assert_eq!(after[3], before[3], "out is not in the frame");
    for i in [1, 2] {
        let dy = after[i].1 - before[i].1;
        assert!((dy - 100.0 / zoom).abs() < 3.0, "moved by {dy}");
        assert_eq!(after[i].0, before[i].0);
    }
    // The drag was one step; the frame another.
    assert!(h.state_mut().doc.undo());
    assert_eq!(pos(&h, "exposure"), before[1]);
    assert_eq!(h.state().doc.graph.frames.len(), 1);
    assert!(h.state_mut().doc.redo());

    // Label, comment and colour, and a node's colour; saved, loaded, compiled.
    let ed = h.state_mut();
    ed.doc
        .set_frame(0, "grade", "exposure, then the curve", Some((200, 120, 40)));
    ed.doc.set_node_color("input", Some((40, 160, 90)));
    h.key_press_modifiers(Modifiers::COMMAND, Key::S);
    h.run_ok();
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.contains("version: 4"), "{text}");
    let original = shipped_text("post_tonemap.ron");
    let header: Vec<&str> = original
        .lines()
        .take_while(|l| l.starts_with("//"))
        .collect();
    assert!(!header.is_empty() && header.iter().all(|l| text.contains(l)));
    let loaded = Graph::load(&path).unwrap();
    assert_eq!(loaded, h.state().doc.graph);
    assert_eq!(loaded.frames[0].label, "grade");
    assert_eq!(loaded.node("input").unwrap().color, Some((40, 160, 90)));
    let mut plain = loaded.clone();
    plain.frames.clear();
    for n in &mut plain.nodes {
        n.color = None;
    }
    let (a, b) = (
        compile(&loaded, &[], None).unwrap(),
        compile(&plain, &[], None).unwrap(),
    );
    assert_eq!(format!("{:?}", a.passes), format!("{:?}", b.passes));

    // Deleting a node takes it out of its frame.
    let ed = h.state_mut();
    ed.doc.remove_nodes(&["exposure".into()]);
    assert_eq!(ed.doc.graph.frames[0].nodes, ["tonemap"]);
}

/// Grid snap (View → Snap to grid): a node let go after a drag lands on the grid, and the
/// drag with its snap is one undo step.
#[test]
fn nodes_snap_to_the_grid_when_let_go() {
    let Some(ed) = editor(Some(&post_tonemap()), None) else {
        return;
    };
    let mut h = harness(ed);
    h.state_mut().snap = true;
    h.run_ok();
    let before = h.state().doc.graph.node("tonemap").unwrap().pos.unwrap();
    // Tonemap's header, a little right of and below the node's corner.
    let header = h
        .state()
        .canvas
        .to_screen(egui::pos2(before.0 + 75.0, before.1 + 4.0))
        .unwrap();
    drag(&mut h, header, header + egui::vec2(37.0, 53.0));
    let grid = lumagraph_editor::canvas::GRID;
    let (x, y) = h.state().doc.graph.node("tonemap").unwrap().pos.unwrap();
    assert!(x != before.0 && y != before.1, "not moved: ({x}, {y})");
    assert_eq!((x % grid, y % grid), (0.0, 0.0), "({x}, {y}) off the grid");
    assert!(h.state_mut().doc.undo());
    assert_eq!(
        h.state().doc.graph.node("tonemap").unwrap().pos.unwrap(),
        before
    );
}

/// The large viewer (Ctrl+Space): the preview takes the canvas's place at several times
/// the side panel's size, and its readout under the pointer is the port's value computed
/// on the CPU (the test chart at −3 EV); Ctrl+Space again brings the canvas back.
#[test]
fn the_large_viewer_reads_out_the_cpu_value() {
    use egui::{Key, Modifiers};
    let Some(ed) = editor(Some(&post_tonemap()), None) else {
        return;
    };
    let chart = lumagraph_render::image_io::load(&repo("assets/test_chart.exr")).unwrap();
    let mut h = harness(ed);
    h.state_mut().select(vec!["exposure".into()]);
    h.state_mut()
        .doc
        .set_param("exposure", "ev", ParamValue::Float(-3.0));
    h.run_ok();
    let small = h.state().view.rect.expect("drawn").width();
    h.key_press_modifiers(Modifiers::COMMAND, Key::Space);
    h.run_ok();
    assert!(h.state().big_viewer);
    let rect = h.state().view.rect.expect("drawn");
    assert!(
        rect.width() > 1.5 * small,
        "{} against {small}",
        rect.width()
    );
    assert!(
        h.query_by_label("input").is_none(),
        "the canvas is still drawn"
    );
    h.get_by_label("in the large viewer");
    // Fitted: pixel (x, y) on screen.
    let fit = (rect.width() / chart.width as f32).min(rect.height() / chart.height as f32);
    let shown = egui::vec2(chart.width as f32, chart.height as f32) * fit;
    let origin = rect.center() - shown / 2.0;
    let (x, y) = (chart.width / 3, chart.height / 2 + 7);
    h.hover_at(origin + egui::vec2(x as f32 + 0.5, y as f32 + 0.5) * fit);
    h.run_ok();
    let r = h.state().view.hover.expect("a readout");
    assert_eq!((r.x, r.y), (x, y));
    let want = chart.pixels[(y * chart.width + x) as usize];
    for c in 0..3 {
        assert!(
            (r.rgba[c] - 0.125 * want[c]).abs() <= 1e-5 * want[c].abs().max(1.0),
            "channel {c}: {} vs 2^-3 × {}",
            r.rgba[c],
            want[c]
        );
    }
    h.key_press_modifiers(Modifiers::COMMAND, Key::Space);
    h.run_ok();
    assert!(!h.state().big_viewer);
    h.get_by_label("input");
}

/// Reroute points: a double-click on a wire adds one there (the edge, its ports and types,
/// unchanged: the same plan); the point is a small node that drags, and a wire dragged
/// from it carries its wire's type: into an input that does not take it it is refused
/// with the reason, into one that does it is a new edge from the same output. Saved and
/// loaded with the edge (version 4); undoable.
#[test]
#[expect(clippy::too_many_lines, reason = "one user's sequence of steps")]
fn a_reroute_point_keeps_its_wires_type() {
    let Some(ed) = editor(None, None) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("g.ron");
    std::fs::write(&path, shipped_text("post_tonemap.ron")).unwrap();
    let mut h = common::harness_stepped(ed, 1.0 / 30.0);
    h.state_mut().open(&path);
    h.run_ok();
    let plan_before = format!(
        "{:?}",
        compile(&h.state().doc.graph, &[], None).unwrap().passes
    );
    let edge = |h: &egui_kittest::Harness<'static, lumagraph_editor::Editor>| {
        h.state()
            .doc
            .graph
            .edges
            .iter()
            .position(|e| e.from == "tonemap.color" && e.to == "out.color")
            .expect("the tonemap → out wire")
    };
    // The middle of the tonemap → out wire, on screen.
    let t = h.state().doc.graph.node("tonemap").unwrap().pos.unwrap();
    // Where the canvas drew the two pins.
    let ed = h.state();
    let pin_at = |node: &str, output: bool| {
        let p = ed.canvas.pin_pos(node, output, "color").expect("drawn");
        ed.canvas.to_screen(p).unwrap()
    };
    let (tonemap_out, out_in, exposure_in) = (
        pin_at("tonemap", true),
        pin_at("out", false),
        pin_at("exposure", false),
    );
    let mid = tonemap_out + (out_in - tonemap_out) * 0.5;
    h.hover_at(mid);
    h.run_ok();
    // Two clicks a frame apart (a double click is two within 0.3 s).
    for _ in 0..2 {
        for pressed in [true, false] {
            h.event(egui::Event::PointerButton {
                pos: mid,
                button: egui::PointerButton::Primary,
                pressed,
                modifiers: egui::Modifiers::NONE,
            });
        }
        h.step();
    }
    h.run_ok();
    let e = edge(&h);
    let ed = h.state();
    assert_eq!(
        ed.doc.graph.edges[e].via.len(),
        1,
        "{:?}",
        ed.doc.graph.edges
    );
    assert_eq!(
        format!("{:?}", compile(&ed.doc.graph, &[], None).unwrap().passes),
        plan_before,
        "a reroute changes the plan"
    );
    // Its output pin, on the right edge of its small node.
    assert!(ed.canvas.reroute_rect(e, 0).is_some());
    let pin = ed
        .canvas
        .to_screen(ed.canvas.reroute_pin_pos(e, 0, true).expect("drawn"))
        .unwrap();
    // ldr_color into exposure's input (hdr_color only): refused, in the compiler's words.
    let before = h.state().doc.graph.clone();
    drag(&mut h, pin, exposure_in);
    let ed = h.state();
    assert_eq!(ed.doc.graph, before);
    let (msg, is_err) = ed.message.clone().expect("a refusal");
    assert!(is_err && msg.contains("produces ldr_color"), "{msg}");
    // Into a second Output: a new edge from tonemap's output.
    let out2 = h
        .state_mut()
        .doc
        .add_node("Output", Some((t.0 + 150.0, t.1 + 150.0)))
        .unwrap();
    h.state_mut().doc.end_gesture();
    h.run_ok();
    let out2_in = {
        let ed = h.state();
        let p = ed.canvas.pin_pos(&out2, false, "color").expect("drawn");
        ed.canvas.to_screen(p).unwrap()
    };
    drag(&mut h, pin, out2_in);
    let wired = format!("{out2}.color");
    assert!(
        h.state()
            .doc
            .graph
            .edges
            .iter()
            .any(|e| e.from == "tonemap.color" && e.to == wired),
        "{:?}",
        h.state().doc.graph.edges
    );
    // Dragged, the point moves; the edge stays.
    let (e, body) = {
        let ed = h.state();
        let e = edge(&h);
        let r = ed.canvas.reroute_rect(e, 0).unwrap();
        (
            e,
            ed.canvas
                .to_screen(egui::pos2(r.center().x, r.top() + 3.0))
                .unwrap(),
        )
    };
    let was = h.state().doc.graph.edges[e].via[0];
    drag(&mut h, body, body + egui::vec2(0.0, 40.0));
    let now = h.state().doc.graph.edges[edge(&h)].via[0];
    assert!(
        now.1 > was.1 + 20.0 && (now.0 - was.0).abs() < 1.0,
        "{was:?} -> {now:?}"
    );
    // Saved and loaded with its point.
    h.state_mut().save_as(&path).unwrap();
    let loaded = Graph::load(&path).unwrap();
    assert_eq!(loaded.edges[edge(&h)].via.len(), 1);
    assert!(
        std::fs::read_to_string(&path)
            .unwrap()
            .contains("version: 4")
    );
    // Undo: the move, the new edge, the output, the reroute.
    let ed = h.state_mut();
    assert!(ed.doc.undo() && ed.doc.undo() && ed.doc.undo() && ed.doc.undo());
    assert!(ed.doc.graph.edges.iter().all(|e| e.via.is_empty()));
}

/// The viewer in a window of its own (🗗 window): the canvas stays, the side panel says
/// where the image went, and the window's readout is the CPU value. (The harness has one
/// window, so egui embeds the viewer's as a window inside it, as on such backends.)
#[test]
fn the_viewer_window_reads_out_the_cpu_value() {
    let Some(ed) = editor(Some(&post_tonemap()), None) else {
        return;
    };
    let chart = lumagraph_render::image_io::load(&repo("assets/test_chart.exr")).unwrap();
    let mut h = harness(ed);
    h.state_mut().select(vec!["exposure".into()]);
    h.state_mut()
        .doc
        .set_param("exposure", "ev", ParamValue::Float(-3.0));
    h.run_ok();
    h.get_by_label("🗗 window").click();
    h.run_ok();
    assert!(h.state().viewer_window && !h.state().big_viewer);
    h.get_by_label("lumagraph viewer");
    h.get_by_label("in the viewer window");
    h.get_by_label("input");
    let rect = h.state().view.rect.expect("drawn");
    let fit = (rect.width() / chart.width as f32).min(rect.height() / chart.height as f32);
    let shown = egui::vec2(chart.width as f32, chart.height as f32) * fit;
    let origin = rect.center() - shown / 2.0;
    let (x, y) = (chart.width / 4, chart.height / 2 - 5);
    h.hover_at(origin + egui::vec2(x as f32 + 0.5, y as f32 + 0.5) * fit);
    h.run_ok();
    let r = h.state().view.hover.expect("a readout");
    assert_eq!((r.x, r.y), (x, y));
    let want = chart.pixels[(y * chart.width + x) as usize];
    for c in 0..3 {
        assert!(
            (r.rgba[c] - 0.125 * want[c]).abs() <= 1e-5 * want[c].abs().max(1.0),
            "channel {c}: {} vs 2^-3 × {}",
            r.rgba[c],
            want[c]
        );
    }
    // Closed (the embedded window may lie over the side panel's button here).
    h.get_by_label("🗗 back here");
    h.state_mut().viewer_window = false;
    h.run_ok();
    assert!(h.query_by_label("lumagraph viewer").is_none());
}

/// An image sequence loaded by pattern plays through a chain with its frame slider:
/// three 8×6 EXR frames of different constant colours, `ImageInput(path: "seq.####.exr")
/// → Exposure (+1 EV) → Output`. The frame control finds frames 1–3 on disk; the slider
/// and the ◀ ▶ steps show each frame's colour (doubled) through the chain, each change a
/// param update of the one executor re-running `input` and `exposure`; ▶ play advances a
/// frame per repaint and wraps from 3 to 1. No frame change enters the graph or its undo
/// history: saving writes the pattern. A pattern with no file says so.
#[test]
#[expect(clippy::too_many_lines, reason = "one user's sequence of steps")]
fn a_sequence_plays_through_a_chain_with_its_frame_slider() {
    let Some(ed) = editor(None, None) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let colours = [
        [0.25, 0.5, 1.0, 1.0],
        [1.0, 0.125, 0.0, 1.0],
        [0.0, 0.75, 0.375, 1.0],
    ];
    for (i, c) in colours.iter().enumerate() {
        let image = lumagraph_render::cpu::Image::filled(8, 6, *c);
        let file = dir.path().join(format!("seq.{:04}.exr", i + 1));
        lumagraph_render::image_io::save(&file, &image, true).unwrap();
    }
    // Not frames of `seq.####.exr`: another padding, another name.
    std::fs::write(dir.path().join("seq.12.exr"), b"").unwrap();
    std::fs::write(dir.path().join("other.0004.exr"), b"").unwrap();
    let path = dir.path().join("seq.ron");
    std::fs::write(
        &path,
        r#"(version: 1, nodes: [
            (id: "input", kind: "ImageInput", params: {"path": "seq.####.exr"}),
            (id: "exposure", kind: "Exposure", params: {"ev": 1.0}),
            (id: "out", kind: "Output", params: {"path": "out.####.exr"}),
        ], edges: [
            (from: "input.color", to: "exposure.color"),
            (from: "exposure.color", to: "out.color"),
        ])"#,
    )
    .unwrap();
    let mut h = harness(ed);
    h.state_mut().open(&path);
    h.run_ok();
    // The previewed image (exposure.color) is frame `frame`'s colour, twice as bright.
    let shows = |h: &egui_kittest::Harness<'static, lumagraph_editor::Editor>, frame: i64| {
        let ed = h.state();
        assert_eq!(ed.sequence.frame, frame);
        assert!(ed.preview.error.is_none(), "{:?}", ed.preview.error);
        let (image, _) = ed.preview.linear.as_ref().expect("a preview");
        assert_eq!((image.width, image.height), (8, 6));
        let want = colours[usize::try_from(frame - 1).unwrap()];
        for p in &image.pixels {
            for c in 0..3 {
                assert!(
                    (p[c] - 2.0 * want[c]).abs() < 1e-6,
                    "frame {frame}: {p:?} against 2 × {want:?}"
                );
            }
        }
    };
    {
        let ed = h.state();
        assert!(ed.errors.is_empty(), "{:?}", ed.errors);
        assert!(ed.sequence.is_active(), "{:?}", ed.message);
        assert_eq!(ed.sequence.frames, [1, 2, 3]);
        assert_eq!(ed.effective_port().as_deref(), Some("exposure.color"));
        assert_eq!(ed.preview.stats.rebuilds, 1);
    }
    h.get_by_label("3 frames, 1–3");
    shows(&h, 1);
    // The inspector takes the pattern as a path to an existing sequence.
    let check = |p: &str| lumagraph_editor::inspector::check_path(p, &["exr"], dir.path(), true);
    assert_eq!(check("seq.####.exr"), None);
    assert_eq!(check("seq.%04d.exr"), None);
    assert!(check("seq.###.exr").unwrap().contains("no file matches"));

    // ▶ steps to frame 2: a param update through the chain, not a rebuild.
    let updates = h.state().preview.stats.param_updates;
    h.get_by_label("▶").click();
    h.run_ok();
    shows(&h, 2);
    let s = &h.state().preview.stats;
    assert_eq!(s.rebuilds, 1);
    assert_eq!(s.param_updates, updates + 1);
    assert_eq!(s.last_update, ["input", "exposure"]);

    // The slider's right end is the last frame; ▶ from there wraps, ◀ goes back.
    let rect = h.get_by_role_and_label(Role::Slider, "frame").rect();
    click_at(&mut h, egui::pos2(rect.right() - 2.0, rect.center().y));
    shows(&h, 3);
    h.get_by_label("▶").click();
    h.run_ok();
    shows(&h, 1);
    h.get_by_label("◀").click();
    h.run_ok();
    shows(&h, 3);
    let rect = h.get_by_role_and_label(Role::Slider, "frame").rect();
    click_at(&mut h, egui::pos2(rect.left() + 2.0, rect.center().y));
    shows(&h, 1);

    // ▶ play: a frame more at each repaint, 3 wrapping to 1.
    h.get_by_label("▶ play").click();
    h.step();
    assert!(h.state().sequence.playing);
    let mut seen = vec![h.state().sequence.frame];
    for _ in 0..4 {
        h.step();
        let frame = h.state().sequence.frame;
        shows(&h, frame);
        seen.push(frame);
    }
    for pair in seen.windows(2) {
        assert_eq!(pair[1], pair[0] % 3 + 1, "frames played: {seen:?}");
    }
    eprintln!("played: {seen:?}");
    h.get_by_label("⏸ pause").click();
    h.run_ok();
    let stopped = h.state().sequence.frame;
    assert!(!h.state().sequence.playing);
    h.run_ok();
    assert_eq!(h.state().sequence.frame, stopped);
    h.get_by_label("▶ play");
    assert_eq!(h.state().preview.stats.rebuilds, 1);

    // Frames are view state: the graph is as opened, with nothing to undo; saving keeps
    // the patterns.
    let ed = h.state_mut();
    assert!(!ed.doc.is_dirty());
    assert_eq!(ed.doc.can_undo_redo(), (false, false));
    ed.save().unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.contains("\"seq.####.exr\""), "{text}");
    assert!(text.contains("\"out.####.exr\""), "{text}");
    assert!(!text.contains(".000"), "{text}");
    assert_eq!(
        Graph::load(&path).unwrap().node("input").unwrap().params["path"],
        ParamValue::Str("seq.####.exr".into())
    );

    // A pattern no file matches: the status line says so.
    h.state_mut()
        .doc
        .set_param("input", "path", ParamValue::Str("none.####.exr".into()));
    h.run_ok();
    let ed = h.state();
    assert!(ed.sequence.frames.is_empty());
    let (message, error) = ed.message.clone().expect("a status message");
    assert!(error && message.contains("no frames found"), "{message}");
    assert!(message.contains("none.####.exr"), "{message}");
    h.get_by_label("no frames found");
}
