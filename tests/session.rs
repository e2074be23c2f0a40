//! The session API (`lumagraph::session`): the same files as `lumagraph render`, images
//! read back at the scene's size, a param change that re-runs only what is downstream, and
//! errors that name the file and line.

mod common;

use std::process::Command;

use lumagraph::session::{Session, SessionOptions};

fn open(out: &std::path::Path, write_outputs: bool, keep: &[&str]) -> Session {
    Session::open(
        &common::repo("graphs/pathtrace.ron"),
        Some(&common::repo("assets/cornell.ron")),
        SessionOptions {
            out: out.to_owned(),
            write_outputs,
            keep: keep.iter().map(|k| (*k).to_owned()).collect(),
            ..SessionOptions::default()
        },
    )
    .unwrap()
}

/// `lumagraph render graphs/pathtrace.ron --scene assets/cornell.ron --spp 16` into `out`,
/// with `more` arguments; it must succeed.
fn cli_render(out: &std::path::Path, more: &[&str]) {
    let o = Command::new(env!("CARGO_BIN_EXE_lumagraph"))
        .args([
            "render",
            "graphs/pathtrace.ron",
            "--scene",
            "assets/cornell.ron",
        ])
        .args(["--spp", "16", "--out", out.to_str().unwrap()])
        .args(more)
        .current_dir(common::root())
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// A session's render of `graphs/pathtrace.ron` on the Cornell box at 16 spp writes the
/// files `lumagraph render` writes for the same graph, scene and spp, byte for byte.
#[test]
fn a_session_renders_what_the_cli_renders() {
    if common::gpu().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let (cli, ours) = (dir.path().join("cli"), dir.path().join("session"));
    cli_render(&cli, &[]);
    let mut s = open(&ours, true, &[]);
    let report = s.render(16).unwrap();
    assert_eq!(s.spp(), 16);
    assert_eq!(report.written.len(), 2, "{:?}", report.written);
    for file in ["render.exr", "render.png"] {
        let (a, b) = (
            std::fs::read(cli.join(file)).unwrap(),
            std::fs::read(ours.join(file)).unwrap(),
        );
        assert!(a == b, "{file}: the session's differs from the CLI's");
    }
}

/// Ports read back as images of the scene's size; a port the plan does not keep is an
/// error naming it; files are written only where asked.
#[test]
fn ports_read_back_at_the_scenes_size() {
    if common::gpu().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let mut s = open(dir.path(), false, &["pathtrace.color"]);
    let report = s.render(8).unwrap();
    assert!(report.written.is_empty(), "{:?}", report.written);
    assert!(!dir.path().join("render.png").exists());
    for port in ["accumulate.color", "tonemap.color", "pathtrace.color"] {
        let img = s.read(port).unwrap();
        assert_eq!((img.width, img.height), (256, 256), "{port}");
        assert_eq!(img.pixels.len(), 256 * 256, "{port}");
        let mean: f32 =
            img.pixels.iter().map(|p| p[0] + p[1] + p[2]).sum::<f32>() / img.pixels.len() as f32;
        assert!(mean.is_finite() && mean > 0.01, "{port}: mean {mean}");
    }
    let e = s.read("pathtrace.albedo").unwrap_err().to_string();
    assert!(e.contains("pathtrace.albedo"), "{e}");
}

/// An exposure change re-runs exposure, tone mapping and the PNG output only (counted by
/// the passes that ran), over the accumulation as it is: the accumulation is unchanged,
/// the tone-mapped image brighter.
#[test]
fn a_param_change_reruns_only_what_is_downstream() {
    if common::gpu().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let mut s = open(dir.path(), false, &[]);
    s.render(8).unwrap();
    let (hdr, ldr) = (
        s.read("accumulate.color").unwrap(),
        s.read("tonemap.color").unwrap(),
    );
    let report = s.set_param("exposure.ev", "1.0").unwrap();
    assert_eq!(report.executed, ["exposure", "tonemap", "png"]);
    assert_eq!(s.read("accumulate.color").unwrap().pixels, hdr.pixels);
    let brighter = s.read("tonemap.color").unwrap();
    let sum = |i: &lumagraph::render::cpu::Image| i.pixels.iter().map(|p| p[1]).sum::<f32>();
    assert!(sum(&brighter) > 1.2 * sum(&ldr));
    assert_eq!(s.spp(), 8);
    let e = s.set_param("exposure.nope", "1").unwrap_err().to_string();
    assert!(e.contains("nope"), "{e}");
}

/// A graph file that does not parse: the error names the file and the line.
#[test]
fn a_bad_graph_names_its_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("broken.ron");
    std::fs::write(
        &path,
        "(\n    version: 1,\n    nodes: [\n        (id: \"a\" kind: \"Tonemap\"),\n    ],\n)\n",
    )
    .unwrap();
    let e = match Session::open(&path, None, SessionOptions::default()) {
        Ok(_) => panic!("a broken graph opened"),
        Err(e) => format!("{e:#}"),
    };
    assert!(e.contains("broken.ron"), "{e}");
    assert!(e.contains(":4:") || e.contains("line 4"), "{e}");
}

/// A render checkpointed at 8 spp goes on to 16 spp, in another session or in
/// `lumagraph render --resume`, to the image a render straight to 16 spp makes, byte for
/// byte; a checkpoint of another scene is refused, naming the file.
#[test]
fn a_checkpoint_goes_on_where_the_render_stopped() {
    if common::gpu().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let ck = dir.path().join("at8.checkpoint");
    let mut first = open(&dir.path().join("first"), false, &[]);
    first.render(8).unwrap();
    first.checkpoint(&ck).unwrap();
    drop(first);

    let straight_dir = dir.path().join("straight");
    let mut straight = open(&straight_dir, true, &[]);
    straight.render(16).unwrap();
    let expected = straight.read("accumulate.color").unwrap();
    drop(straight);

    let mut resumed = open(&dir.path().join("resumed"), false, &[]);
    resumed.resume(&ck).unwrap();
    assert_eq!(resumed.spp(), 8);
    resumed.render(16).unwrap();
    assert_eq!(resumed.spp(), 16);
    assert!(resumed.read("accumulate.color").unwrap().pixels == expected.pixels);

    // The command line goes on from the session's checkpoint too.
    let cli = dir.path().join("cli");
    cli_render(&cli, &["--resume", ck.to_str().unwrap()]);
    assert!(
        std::fs::read(cli.join("render.exr")).unwrap()
            == std::fs::read(straight_dir.join("render.exr")).unwrap(),
        "the command line's render from the checkpoint differs"
    );

    // Another scene's render does not take it.
    let mut other = Session::open(
        &common::repo("graphs/pathtrace.ron"),
        Some(&common::repo("assets/cornell_spheres.ron")),
        SessionOptions::default(),
    )
    .unwrap();
    let e = format!("{:#}", other.resume(&ck).unwrap_err());
    assert!(e.contains("at8.checkpoint"), "{e}");
    assert_eq!(other.spp(), 0);
}

/// Scene edits: a moved camera (the executor kept) renders what a session opened on the
/// edited file renders, byte for byte; a material edit builds the scene again; both
/// restart the accumulation; a bad value is refused and the session renders on.
#[test]
fn an_edited_scene_renders_as_the_file_with_those_values() {
    use lumagraph::scene::edit;
    use lumagraph::session::SceneChange;
    if common::gpu().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let mut s = open(dir.path(), false, &[]);
    s.render(4).unwrap();
    let before = s.read("accumulate.color").unwrap();

    let mut moved = s.scene().unwrap().clone();
    edit::set(&mut moved.file, "camera.position", "(0.4, 0.2, 3.5)").unwrap();
    edit::set(&mut moved.file, "camera.fov_y", "45").unwrap();
    assert_eq!(
        s.set_scene(moved.file.clone()).unwrap(),
        SceneChange::Camera
    );
    assert_eq!(s.spp(), 0);
    s.render(4).unwrap();
    let after = s.read("accumulate.color").unwrap();
    assert!(after.pixels != before.pixels);
    let mut fresh = Session::open_scene(
        lumagraph::graph::Graph::load(&common::repo("graphs/pathtrace.ron")).unwrap(),
        Some(moved.clone()),
        SessionOptions::default(),
    )
    .unwrap();
    fresh.render(4).unwrap();
    assert!(
        fresh.read("accumulate.color").unwrap().pixels == after.pixels,
        "the moved camera renders otherwise than the edited file"
    );
    drop(fresh);

    let mut blue = moved.clone();
    edit::set(
        &mut blue.file,
        "materials.red.base_color",
        "(0.05, 0.05, 0.6)",
    )
    .unwrap();
    assert_eq!(s.set_scene(blue.file.clone()).unwrap(), SceneChange::Scene);
    assert_eq!(
        s.set_scene(blue.file.clone()).unwrap(),
        SceneChange::Nothing
    );
    s.render(4).unwrap();
    let mean = |img: &lumagraph::render::cpu::Image, c: usize| {
        img.pixels.iter().map(|p| p[c]).sum::<f32>() / img.pixels.len() as f32
    };
    let recoloured = s.read("accumulate.color").unwrap();
    assert!(mean(&recoloured, 2) > 1.1 * mean(&after, 2) && mean(&recoloured, 0) < mean(&after, 0));

    let mut bad = blue.clone();
    edit::set(&mut bad.file, "camera.target", "(0.4, 0.2, 3.5)").unwrap();
    let e = format!("{:#}", s.set_scene(bad.file).unwrap_err());
    assert!(e.contains("cornell.ron") && e.contains("target"), "{e}");
    assert_eq!(s.scene().unwrap().file, blue.file);
    s.render(8).unwrap();
    assert_eq!(s.spp(), 8);
}

/// A sequence keeps the history of nodes that have one from frame to frame: over three
/// constant frames of luminance 0.18, 0.72, 0.72, `AutoExposure` (adaptation 0.25) takes
/// frame 1's target t1 at once, then moves a quarter of the way to frame 2's target t2 a
/// frame, where a session opened at frame 2 takes t2 at once (the targets as a fresh
/// session meters them: about 0 and −2 EV, to the histogram's bins).
#[test]
fn a_sequence_keeps_history_from_frame_to_frame() {
    if common::gpu().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    for (frame, value) in [(1, 0.18_f32), (2, 0.72), (3, 0.72)] {
        let image = lumagraph::render::cpu::Image::filled(8, 6, [value, value, value, 1.0]);
        let path = dir.path().join(format!("seq.{frame:04}.exr"));
        lumagraph::render::image_io::save(&path, &image, true).unwrap();
    }
    let graph = dir.path().join("seq.ron");
    std::fs::write(
        &graph,
        r#"(
    version: 1,
    nodes: [
        (id: "input", kind: "ImageInput", params: {"path": "seq.####.exr"}),
        (id: "auto", kind: "AutoExposure"),
        (id: "out", kind: "Output", params: {"path": "out.####.exr"}),
    ],
    edges: [
        (from: "input.color", to: "auto.color"),
        (from: "auto.color", to: "out.color"),
    ],
)
"#,
    )
    .unwrap();
    let options = |frame| SessionOptions {
        out: dir.path().join("out"),
        frame: Some(frame),
        ..SessionOptions::default()
    };
    let ev = |s: &mut Session| {
        let m = s.measurements().unwrap();
        m.iter()
            .find(|(node, name, _)| node == "auto" && name == "exposure_ev")
            .map(|(_, _, v)| *v)
            .unwrap()
    };
    let target = |frame| {
        let mut fresh = Session::open(&graph, None, options(frame)).unwrap();
        fresh.render(1).unwrap();
        ev(&mut fresh)
    };
    let (t1, t2) = (target(1), target(2));
    assert!(
        (t1 - 0.0).abs() < 0.1 && (t2 + 2.0).abs() < 0.1,
        "{t1} {t2}"
    );
    let mut s = Session::open(&graph, None, options(1)).unwrap();
    s.render(1).unwrap();
    let mut seen = vec![ev(&mut s)];
    for frame in [2, 3] {
        s.set_frame(frame).unwrap();
        assert_eq!(s.frame(), Some(frame));
        seen.push(ev(&mut s));
    }
    let ev2 = t1 + 0.25 * (t2 - t1);
    let want = [t1, ev2, ev2 + 0.25 * (t2 - ev2)];
    for (got, want) in seen.iter().zip(want) {
        assert!((got - want).abs() < 1e-3, "{seen:?}, want {want:?}");
    }
    let e = s.set_frame(4).unwrap_err().to_string();
    assert!(e.contains("frame 4") && e.contains("seq.0004.exr"), "{e}");
}

/// A number param written as a frame expression (`ev: "frame - 1"`) takes each frame's
/// value: through the session's frames and `render --frames`, over a constant input
/// (0.5 grey), frame f comes out 0.5 · 2^(f − 1); a bad expression is one error naming the
/// node, the param and the expression.
#[test]
fn a_frame_expression_animates_a_number() {
    if common::gpu().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let image = lumagraph::render::cpu::Image::filled(4, 3, [0.5, 0.5, 0.5, 1.0]);
    lumagraph::render::image_io::save(&dir.path().join("grey.exr"), &image, true).unwrap();
    let write = |ev: &str| {
        let graph = dir.path().join("anim.ron");
        std::fs::write(
            &graph,
            format!(
                r#"(
    version: 1,
    nodes: [
        (id: "input", kind: "ImageInput", params: {{"path": "grey.exr"}}),
        (id: "exposure", kind: "Exposure", params: {{"ev": {ev:?}}}),
        (id: "out", kind: "Output", params: {{"path": "e.####.exr"}}),
    ],
    edges: [
        (from: "input.color", to: "exposure.color"),
        (from: "exposure.color", to: "out.color"),
    ],
)
"#
            ),
        )
        .unwrap();
        graph
    };
    let graph = write("frame - 1");
    let out = dir.path().join("out");
    let mut s = Session::open(
        &graph,
        None,
        SessionOptions {
            out: out.clone(),
            frame: Some(1),
            ..SessionOptions::default()
        },
    )
    .unwrap();
    s.render(1).unwrap();
    for frame in 1..=3_i32 {
        if frame > 1 {
            s.set_frame(i64::from(frame)).unwrap();
        }
        let got = s.read("exposure.color").unwrap();
        let want = 0.5 * 2_f32.powi(frame - 1);
        assert!(
            (got.pixels[0][0] - want).abs() < 1e-6,
            "frame {frame}: {:?}",
            got.pixels[0]
        );
    }
    // The command line, frames 2 and 3.
    let (ok, _, err) = common::cli(&[
        "render",
        graph.to_str().unwrap(),
        "--frames",
        "2-3",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    for (frame, want) in [(2, 1.0_f32), (3, 2.0)] {
        let got =
            lumagraph::render::image_io::load(&out.join(format!("e.{frame:04}.exr"))).unwrap();
        assert!(
            (got.pixels[0][0] - want).abs() < 1e-3,
            "frame {frame}: {:?}",
            got.pixels[0]
        );
    }
    // A bad expression.
    let graph = write("fram - 1");
    let (ok, _, err) = common::cli(&[
        "render",
        graph.to_str().unwrap(),
        "--frames",
        "1",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(!ok);
    assert!(
        err.contains("exposure") && err.contains("ev") && err.contains("fram - 1"),
        "{err}"
    );
}
