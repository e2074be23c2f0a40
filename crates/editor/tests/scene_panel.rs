//! The scene panel driven headless through `egui_kittest`: a material edit restarts the
//! accumulation, the furnace view, saving the scene keeps the file's text, and Render to
//! file writes the full-resolution image without blocking the editor.

mod common;

use std::path::{Path, PathBuf};
use std::time::Duration;

use egui::accesskit::Role;
use egui_kittest::kittest::Queryable as _;
use lumagraph_editor::{Editor, EditorConfig, SideTab};
use lumagraph_scene::file::SceneFile;

use common::{harness_sized, repo, with_config};

type Harness = egui_kittest::Harness<'static, Editor>;

/// The path-traced graph with a copy of the Cornell box (so saving it is harmless), at a
/// tiny preview size.
fn cornell_editor(dir: &Path) -> Option<(Editor, PathBuf)> {
    let scene = dir.join("cornell.ron");
    std::fs::copy(repo("assets/cornell.ron"), &scene).unwrap();
    let ed = with_config(
        Some(&repo("graphs/pathtrace.ron")),
        &EditorConfig {
            scene: Some(scene.clone()),
            preview_max: 24,
            ..EditorConfig::default()
        },
    )?;
    Some((ed, scene))
}

/// Previewing the accumulation, with the scene tab open.
fn accumulating(ed: Editor) -> Harness {
    assert!(ed.scene_error.is_none(), "{:?}", ed.scene_error);
    // Tall enough for the whole scene panel without scrolling.
    let mut h = harness_sized(ed, egui::vec2(1100.0, 1600.0));
    h.state_mut().preview_port = Some("accumulate.color".into());
    h.state_mut().side_tab = SideTab::Scene;
    for _ in 0..4 {
        h.step();
    }
    h
}

fn mean(image: &lumagraph_render::cpu::Image) -> f32 {
    let n = image.pixels.len() as f32;
    image
        .pixels
        .iter()
        .map(|p| (p[0] + p[1] + p[2]) / 3.0)
        .sum::<f32>()
        / n
}

/// Clicking in the scene panel: the `white` material's specular slider. The edit reaches
/// the model, the preview's accumulation restarts once (when the click ends), and the
/// scene is marked as changed.
#[test]
fn a_material_edit_restarts_the_accumulation() {
    let dir = tempfile::tempdir().unwrap();
    let Some((ed, _)) = cornell_editor(dir.path()) else {
        return;
    };
    let mut h = accumulating(ed);
    let before = h.state().preview.samples.expect("a sample count");
    assert!(before >= 4, "{before} spp");
    let restarts = h.state().preview.stats.restarts;
    let image = h.state().preview.linear.clone().unwrap().0;

    h.get_by_label("white").click();
    h.run_ok();
    let rect = h.get_by_role_and_label(Role::Slider, "specular").rect();
    common::click_at(
        &mut h,
        egui::pos2(rect.left() + rect.width() * 0.9, rect.center().y),
    );
    h.step();
    let ed = h.state();
    let white = &ed.scene.as_ref().unwrap().doc.file.materials["white"];
    assert!(white.specular > 0.7, "specular {}", white.specular);
    assert!(ed.scene.as_ref().unwrap().doc.is_dirty());
    assert_eq!(ed.preview.stats.restarts, restarts + 1, "one restart");
    let after = ed.preview.samples.unwrap();
    assert!(
        after < before,
        "{after} spp after the edit, {before} before"
    );
    assert_ne!(ed.preview.linear.as_ref().unwrap().0.pixels, image.pixels);
    assert!(
        h.query_by_label_contains("Scene *").is_some(),
        "the tab shows the change"
    );
    // It goes on accumulating.
    h.step();
    h.step();
    assert!(h.state().preview.samples.unwrap() > after);
}

/// The `white` material's diffuse roughness slider: the value reaches the model and the
/// preview, re-specialized with the rough diffuse base compiled in, changes.
#[test]
fn the_diffuse_roughness_slider_reshapes_the_preview() {
    let dir = tempfile::tempdir().unwrap();
    let Some((ed, _)) = cornell_editor(dir.path()) else {
        return;
    };
    let mut h = accumulating(ed);
    let image = h.state().preview.linear.clone().unwrap().0;
    h.get_by_label("white").click();
    h.run_ok();
    let rect = h
        .get_by_role_and_label(Role::Slider, "diffuse roughness")
        .rect();
    common::click_at(
        &mut h,
        egui::pos2(rect.left() + rect.width() * 0.9, rect.center().y),
    );
    h.step();
    h.step();
    let ed = h.state();
    let white = &ed.scene.as_ref().unwrap().doc.file.materials["white"];
    assert!(
        white.diffuse_roughness > 0.7,
        "diffuse roughness {}",
        white.diffuse_roughness
    );
    assert_ne!(ed.preview.linear.as_ref().unwrap().0.pixels, image.pixels);
}

/// The furnace view: every albedo 1 under a white environment. Inside the Cornell box
/// (open at the front) a path that escapes within the 20 bounces sees radiance 1, so the
/// image is at most 1 and nearly 1; without the furnace it is far darker. Turning it off
/// gives the scene back.
#[test]
fn the_furnace_view_is_white() {
    let dir = tempfile::tempdir().unwrap();
    let Some((ed, _)) = cornell_editor(dir.path()) else {
        return;
    };
    let mut h = accumulating(ed);
    let normal = mean(&h.state().preview.linear.clone().unwrap().0);
    h.get_by_label("Furnace test").click();
    for _ in 0..12 {
        h.step();
    }
    let ed = h.state();
    assert!(
        !ed.scene.as_ref().unwrap().doc.is_dirty(),
        "a view, not an edit"
    );
    let furnace = &ed.preview.linear.as_ref().unwrap().0;
    let m = mean(furnace);
    eprintln!(
        "mean {normal:.4} without the furnace, {m:.4} with it ({} spp)",
        ed.preview.samples.unwrap()
    );
    assert!((0.9..=1.0001).contains(&m), "furnace mean {m}");
    assert!(normal < 0.5, "scene mean {normal}");
    h.get_by_label("Furnace test").click();
    for _ in 0..3 {
        h.step();
    }
    let back = mean(&h.state().preview.linear.clone().unwrap().0);
    assert!(back < 0.5, "mean {back} after the furnace");
}

/// Save scene writes the edited values into the file and keeps everything else of its
/// text: the header comments, the lines of the materials not edited, the shapes. The saved
/// file reads back as the edited values.
#[test]
fn scene_save_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let Some((ed, path)) = cornell_editor(dir.path()) else {
        return;
    };
    let original = std::fs::read_to_string(&path).unwrap();
    let mut h = accumulating(ed);
    {
        let doc = &mut h.state_mut().scene.as_mut().unwrap().doc;
        doc.file.materials.get_mut("red").unwrap().roughness = 0.25;
        doc.file.environment = lumagraph_scene::Environment::Constant([0.5, 0.25, 0.125]);
        doc.file.render.spp = 64;
        if let lumagraph_scene::file::CameraDesc::Perspective { fov_y, .. } = &mut doc.file.camera {
            *fov_y = 45.0;
        }
    }
    h.step();
    let edited = h.state().scene.as_ref().unwrap().doc.file.clone();
    h.get_by_label("Save scene").click();
    h.run_ok();
    let ed = h.state();
    assert!(!ed.scene.as_ref().unwrap().doc.is_dirty());
    let saved = std::fs::read_to_string(&path).unwrap();
    assert!(
        SceneFile::from_ron(&saved).unwrap() == edited,
        "the saved file does not read back as the edited values:\n{saved}"
    );
    // Every line of the original that holds none of the edited values is still there.
    let changed = ["\"red\":", "environment:", "render:", "fov_y:"];
    for line in original.lines() {
        if !changed.iter().any(|c| line.contains(c)) {
            assert!(saved.contains(line), "lost: {line}");
        }
    }
    assert!(saved.starts_with("// Cornell box reproducing"));
    assert!(saved.contains("\"white\": (base_color: (0.885809, 0.698859, 0.666422)"));
    // The target spp is what the preview stops at.
    assert_eq!(ed.preview.target_spp, 64);

    // The keyboard: Ctrl+Shift+S saves the scene (not the graph), Ctrl+R opens the tab.
    h.state_mut().side_tab = SideTab::Inspector;
    h.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::R);
    h.run_ok();
    assert_eq!(h.state().side_tab, SideTab::Scene, "Ctrl+R");
    let doc = &mut h.state_mut().scene.as_mut().unwrap().doc;
    doc.file.materials.get_mut("green").unwrap().specular = 0.5;
    h.key_press_modifiers(
        egui::Modifiers::COMMAND | egui::Modifiers::SHIFT,
        egui::Key::S,
    );
    h.run_ok();
    let ed = h.state();
    assert!(!ed.scene.as_ref().unwrap().doc.is_dirty(), "Ctrl+Shift+S");
    let again = SceneFile::from_ron(&std::fs::read_to_string(&path).unwrap()).unwrap();
    assert!((again.materials["green"].specular - 0.5).abs() < 1e-6);
    assert!(
        !ed.doc.is_dirty()
            && ed
                .message
                .as_ref()
                .is_some_and(|(m, _)| m.contains("cornell.ron"))
    );
}

/// Render to file: the graph's Output nodes at the scene's full resolution (256², where the
/// preview renders 24²) and the asked sample count, on a thread of its own while the
/// editor keeps drawing frames; then the previewed port alone to one EXR file.
#[test]
fn render_to_file_writes_the_full_resolution_image() {
    let dir = tempfile::tempdir().unwrap();
    let Some((ed, _)) = cornell_editor(dir.path()) else {
        return;
    };
    let mut h = accumulating(ed);
    let out = dir.path().join("out");
    {
        let form = &mut h.state_mut().render_form;
        form.spp = 8;
        form.dir = out.display().to_string();
    }
    h.run_ok();
    h.get_by_label("▶ Render").click();
    h.run_ok();
    let frames_before = h.state().preview.stats.frames;
    let start = std::time::Instant::now();
    while !h.state().render_job.as_ref().unwrap().is_finished() {
        assert!(
            start.elapsed() < Duration::from_secs(300),
            "the render hangs"
        );
        h.step();
        std::thread::sleep(Duration::from_millis(20));
    }
    let p = h.state().render_job.as_ref().unwrap().progress();
    let files = p.finished.clone().unwrap().expect("written");
    // The files shown while it rendered are those written.
    let mut shown = p.files.clone();
    shown.sort();
    let mut sorted = files.clone();
    sorted.sort();
    assert_eq!(shown, sorted);
    assert_eq!(p.done, p.frames);
    // pathtrace.ron: 4 samples per frame.
    assert_eq!((p.frames, p.spp), (2, 8));
    let mut names: Vec<_> = files
        .iter()
        .map(|f| f.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["render.exr", "render.png"]);
    let exr = lumagraph_render::image_io::load(&out.join("render.exr")).unwrap();
    assert_eq!((exr.width, exr.height), (256, 256));
    let m = mean(&exr);
    assert!((0.05..1.0).contains(&m), "mean {m}");
    assert!(
        h.state().preview.stats.frames > frames_before,
        "the editor kept running"
    );
    h.run_ok();
    assert_eq!(h.query_all_by_label_contains("wrote").count(), 2);

    // The previewed port to one file.
    let file = dir.path().join("port.exr");
    {
        let ed = h.state_mut();
        ed.render_form.port_only = true;
        ed.render_form.file = file.display().to_string();
        ed.render_form.spp = 4;
        assert!(ed.start_render());
    }
    let job = h.state().render_job.as_ref().unwrap();
    assert!(job.wait(Duration::from_secs(300)), "the render hangs");
    let written = job.progress().finished.unwrap().expect("written");
    assert_eq!(written, std::slice::from_ref(&file));
    let port = lumagraph_render::image_io::load(&file).unwrap();
    assert_eq!((port.width, port.height), (256, 256));
}

/// A render that cannot start says why in the panel, never panics: a graph without an
/// Output node asked to write its Output nodes.
#[test]
fn a_render_without_outputs_says_why() {
    let dir = tempfile::tempdir().unwrap();
    let Some((mut ed, _)) = cornell_editor(dir.path()) else {
        return;
    };
    let ids: Vec<String> = ed
        .doc
        .graph
        .nodes
        .iter()
        .filter(|n| n.kind == "Output")
        .map(|n| n.id.clone())
        .collect();
    ed.doc.remove_nodes(&ids);
    ed.render_form.dir = dir.path().display().to_string();
    assert!(ed.start_render());
    let job = ed.render_job.as_ref().unwrap();
    assert!(job.wait(Duration::from_secs(120)));
    let err = job.progress().finished.unwrap().unwrap_err();
    assert!(err.contains("no output node"), "{err}");
}

/// An Output path that climbs out of the folder Render to file writes into is refused,
/// naming the node, the path and the folder, and nothing is written (as `lumagraph
/// render` refuses it).
#[test]
fn an_output_outside_the_folder_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let Some((mut ed, _)) = cornell_editor(dir.path()) else {
        return;
    };
    let id = ed
        .doc
        .graph
        .nodes
        .iter()
        .find(|n| n.kind == "Output")
        .map(|n| n.id.clone())
        .unwrap();
    ed.doc.set_param(
        &id,
        "path",
        lumagraph_graph::ParamValue::Str("../escaped.png".into()),
    );
    let out = dir.path().join("out");
    ed.render_form.dir = out.display().to_string();
    ed.render_form.spp = 1;
    assert!(ed.start_render());
    let job = ed.render_job.as_ref().unwrap();
    assert!(job.wait(Duration::from_secs(120)));
    let err = job.progress().finished.unwrap().unwrap_err();
    assert!(
        err.contains(&format!("node \"{id}\""))
            && err.contains("\"../escaped.png\" is outside the output folder")
            && err.contains(&out.display().to_string()),
        "{err}"
    );
    assert!(!dir.path().join("escaped.png").exists());
    assert!(is_empty_dir(&out), "nothing written in the folder");
}

fn is_empty_dir(dir: &Path) -> bool {
    std::fs::read_dir(dir).map_or(true, |mut d| d.next().is_none())
}

/// A lost GPU device (here destroyed, as a driver reset would lose it) does not end the
/// editor: the preview opens a new device on the same adapter, says so in the status line,
/// and accumulates again from the first sample. The preview gets a device of its own, so
/// the harness's painter (on the shared one) is not lost with it.
#[test]
fn the_preview_goes_on_after_the_device_is_lost() {
    if common::gpu().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("cornell.ron");
    std::fs::copy(repo("assets/cornell.ron"), &scene).unwrap();
    let own = lumagraph_render::GpuContext::headless_prefer_cpu().unwrap();
    let ed = Editor::new(
        own.clone(),
        Some(&repo("graphs/pathtrace.ron")),
        &EditorConfig {
            scene: Some(scene),
            preview_max: 24,
            ..EditorConfig::default()
        },
    );
    let mut h = accumulating(ed);
    assert!(h.state().preview.samples.expect("a sample count") >= 4);
    own.device.destroy();
    for _ in 0..8 {
        h.step();
    }
    let ed = h.state();
    assert_eq!(ed.preview.stats.devices_reopened, 1);
    let (message, _) = ed.message.clone().expect("a status message");
    assert!(message.contains("was lost (destroyed"), "{message}");
    assert!(ed.preview.error.is_none(), "{:?}", ed.preview.error);
    assert!(ed.preview.gpu().lost().is_none());
    let samples = ed.preview.samples.expect("a sample count");
    assert!(samples >= 1, "{samples} spp after the new device");
    assert!(ed.preview.linear.is_some());
}

/// Camera mode on the preview of `graphs/pathtrace_temporal.ron`: a drag on the image
/// orbits the scene's camera (the scene panel's numbers move, the scene is marked as
/// changed), the running preview takes the move without a rebuild, accumulation restarts,
/// and `TemporalReuse` keeps the reprojected history (its `weight` output, previewed here,
/// is the history's weight in frames: far from 0 after the move). The wheel dollies.
#[test]
fn dragging_on_the_preview_orbits_the_camera_and_keeps_the_history() {
    use lumagraph_scene::file::CameraDesc;
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("cornell.ron");
    std::fs::copy(repo("assets/cornell.ron"), &scene).unwrap();
    let Some(ed) = with_config(
        Some(&repo("graphs/pathtrace_temporal.ron")),
        &EditorConfig {
            scene: Some(scene),
            preview_max: 32,
            ..EditorConfig::default()
        },
    ) else {
        return;
    };
    let mut h = harness_sized(ed, egui::vec2(1100.0, 900.0));
    h.state_mut().preview_port = Some("temporal.weight".into());
    for _ in 0..8 {
        h.step();
    }
    let position = |h: &Harness| match &h.state().scene.as_ref().unwrap().doc.file.camera {
        CameraDesc::Perspective { position, .. } => *position,
        other => panic!("{other:?}"),
    };
    let before = position(&h);
    let samples = h.state().preview.samples.unwrap();
    let rebuilds = h.state().preview.stats.rebuilds;
    assert!(samples >= 8, "{samples} spp");

    h.get_by_label("🎥 camera").click();
    h.run_ok();
    assert!(h.state().view.camera_mode);
    let rect = h.state().view.rect.expect("the preview image");
    let start = rect.center();
    h.hover_at(start);
    h.run_ok();
    let press = |pressed, pos| egui::Event::PointerButton {
        pos,
        button: egui::PointerButton::Primary,
        pressed,
        modifiers: egui::Modifiers::NONE,
    };
    h.event(press(true, start));
    h.step();
    // 10 points: 3° of orbit.
    let end = start + egui::vec2(10.0, 0.0);
    h.event(egui::Event::PointerMoved(end));
    h.step();
    h.event(press(false, end));
    h.step();

    let ed = h.state();
    let after = position(&h);
    let turned = (before[0] * after[0] + before[2] * after[2])
        / (before[0].hypot(before[2]) * after[0].hypot(after[2]));
    let degrees = turned.clamp(-1.0, 1.0).acos().to_degrees();
    assert!(
        (degrees - 3.0).abs() < 0.5,
        "orbited {degrees}°: {before:?} → {after:?}"
    );
    assert!(ed.scene.as_ref().unwrap().doc.is_dirty());
    assert!(ed.preview.stats.camera_moves >= 1);
    assert_eq!(
        ed.preview.stats.rebuilds, rebuilds,
        "the move rebuilt the preview"
    );
    let now = ed.preview.samples.unwrap();
    assert!(now < samples, "{now} spp after the move, {samples} before");
    let weight = &ed.preview.linear.as_ref().unwrap().0;
    let kept = weight
        .pixels
        .iter()
        .filter(|p| p[0] >= samples as f32 * 0.9)
        .count();
    // Measured: 690 of 1024 (at 32², pixels beside the light, a wall edge or a box's
    // silhouette are dropped, and those are many).
    assert!(
        kept * 2 >= weight.pixels.len(),
        "{kept} of {} pixels kept their history",
        weight.pixels.len()
    );

    // The wheel dollies: the camera comes closer to the target (the origin).
    let d0 = after.iter().map(|x| x * x).sum::<f32>().sqrt();
    h.event(egui::Event::MouseWheel {
        unit: egui::MouseWheelUnit::Point,
        delta: egui::vec2(0.0, 40.0),
        phase: egui::TouchPhase::Move,
        modifiers: egui::Modifiers::NONE,
    });
    h.step();
    h.step();
    let d1 = position(&h).iter().map(|x| x * x).sum::<f32>().sqrt();
    assert!(d1 < d0 * 0.99, "distance {d0} → {d1}");
}
