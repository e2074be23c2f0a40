//! The `lumagraph` binary end to end: rendering, plans, and every kind of bad input
//! giving one clear error with a non-zero exit, no panic, and no file left behind.

mod common;

use std::path::Path;
use std::process::{Command, Output};

fn lumagraph(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_lumagraph"))
        .args(args)
        .current_dir(common::root())
        .output()
        .unwrap()
}

fn text(o: &Output) -> (String, String) {
    (
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// Runs `render` on a graph that must fail, and checks the failure is clean.
fn render_fails(graph: &Path, out: &Path) -> String {
    let o = lumagraph(&[
        "render",
        graph.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let (stdout, stderr) = text(&o);
    assert!(!o.status.success(), "should fail:\n{stdout}\n{stderr}");
    assert!(!stderr.contains("panicked"), "panic:\n{stderr}");
    assert!(stderr.contains("error: "), "{stderr}");
    if out.is_dir() {
        assert!(
            common::is_empty_dir(out),
            "files left behind in {}",
            out.display()
        );
    }
    stderr
}

const GOOD: &str = r#"(
    version: 1,
    nodes: [
        (id: "input", kind: "ImageInput", params: {"path": "INPUT"}),
        (id: "tonemap", kind: "Tonemap"),
        (id: "out", kind: "Output", params: {"path": "result.png"}),
    ],
    edges: [
        (from: "input.color", to: "tonemap.color"),
        (from: "tonemap.color", to: "out.color"),
    ],
)
"#;

/// Writes a graph reading `input` (absolute) into `dir`.
fn graph_file(dir: &Path, name: &str, text: &str, input: &Path) -> std::path::PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text.replace("INPUT", &input.display().to_string())).unwrap();
    path
}

fn chart() -> std::path::PathBuf {
    common::repo("assets/test_chart.exr")
}

#[test]
fn render_writes_png() {
    if common::gpu().is_none() {
        return;
    }
    let out = tempfile::tempdir().unwrap();
    let o = lumagraph(&[
        "render",
        "graphs/post_tonemap.ron",
        "--out",
        out.path().to_str().unwrap(),
    ]);
    let (stdout, stderr) = text(&o);
    assert!(o.status.success(), "{stdout}\n{stderr}");
    assert!(stdout.contains("adapter: "), "{stdout}");
    let png = image::open(out.path().join("post_tonemap.png")).unwrap();
    assert_eq!((png.width(), png.height()), (512, 256));
}

#[test]
fn render_with_overrides() {
    if common::gpu().is_none() {
        return;
    }
    let out = tempfile::tempdir().unwrap();
    let o = lumagraph(&[
        "render",
        "graphs/post_tonemap.ron",
        "--out",
        out.path().to_str().unwrap(),
        "--set",
        "tonemap.operator=agx",
        "--set",
        "exposure.ev=2",
    ]);
    assert!(o.status.success(), "{:?}", text(&o));
    let bad = lumagraph(&[
        "render",
        "graphs/post_tonemap.ron",
        "--set",
        "tonemap.operator=filmic",
    ]);
    let (_, stderr) = text(&bad);
    assert!(!bad.status.success());
    assert!(
        stderr.contains("node \"tonemap\"") && stderr.contains("\"filmic\" is not one of"),
        "{stderr}"
    );
}

#[test]
fn plan_reports_dead_branch() {
    let dir = tempfile::tempdir().unwrap();
    let dead = GOOD.replace(
        "    ],\n    edges: [\n",
        "        (id: \"debug\", kind: \"Exposure\"),\n    ],\n    edges: [\n        (from: \"input.color\", to: \"debug.color\"),\n",
    );
    let g = graph_file(dir.path(), "dead.ron", &dead, &chart());
    let o = lumagraph(&["plan", g.to_str().unwrap()]);
    let (stdout, stderr) = text(&o);
    assert!(o.status.success(), "{stderr}");
    assert!(
        stdout.contains("node \"debug\" (Exposure): feeds no output"),
        "{stdout}"
    );
    assert!(
        !stdout.contains("reads input.color  writes debug.color"),
        "{stdout}"
    );
}

#[test]
fn validate_and_nodes() {
    let o = lumagraph(&["validate", "graphs/post_tonemap.ron"]);
    assert!(o.status.success(), "{:?}", text(&o));
    // Left out: ImageInput's `scalar` and `vector` ports, which nothing reads.
    assert!(
        text(&o).0.contains("ok (4 passes, 2 left out)"),
        "{:?}",
        text(&o)
    );
    let o = lumagraph(&["nodes"]);
    let (stdout, _) = text(&o);
    for kind in ["ImageInput", "Exposure", "Tonemap", "Output"] {
        assert!(stdout.contains(kind), "{stdout}");
    }
    let help = text(&lumagraph(&["--help"])).0;
    assert!(help.contains("Examples:"), "{help}");
}

/// Output piped into a reader that stops (`lumagraph nodes --markdown | head`) ends the
/// process quietly: no panic message on stderr. The reader's end is closed before the
/// program writes its first line.
#[cfg(unix)]
#[test]
fn a_closed_pipe_ends_the_output_without_a_panic() {
    use std::process::Stdio;
    let mut child = Command::new(env!("CARGO_BIN_EXE_lumagraph"))
        .args(["nodes", "--markdown"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let o = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(stderr.is_empty(), "{stderr}");
}

#[test]
fn docs_node_reference_is_up_to_date() {
    let generated = lumagraph::graph::docs::markdown(&lumagraph::graph::Registry::with_builtins());
    let doc = std::fs::read_to_string(common::repo("docs/graph-format.md")).unwrap();
    let begin = "<!-- nodes:begin (generated by `lumagraph nodes --markdown`) -->\n";
    let end = "<!-- nodes:end -->";
    let start = doc.find(begin).expect("begin marker") + begin.len();
    let stop = doc.find(end).expect("end marker");
    assert!(
        doc[start..stop] == generated,
        "docs/graph-format.md is stale: regenerate the section with `lumagraph nodes --markdown`"
    );
}

#[test]
fn malformed_ron() {
    let dir = tempfile::tempdir().unwrap();
    let g = graph_file(
        dir.path(),
        "bad.ron",
        &GOOD.replace("(id: \"tonemap\", kind", "(id: \"tonemap\" kind"),
        &chart(),
    );
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    let e = render_fails(&g, &out);
    assert!(
        e.contains("bad.ron:5:") && e.contains("syntax error"),
        "{e}"
    );
}

#[test]
fn unknown_kind_port_and_param() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    let cases = [
        (
            GOOD.replace("\"Tonemap\"", "\"ToneMap\""),
            "unknown node kind \"ToneMap\"",
        ),
        (
            GOOD.replace("to: \"out.color\"", "to: \"out.rgb\""),
            "no input port \"rgb\"",
        ),
        (
            GOOD.replace(
                "kind: \"Tonemap\")",
                "kind: \"Tonemap\", params: {\"gamma\": 2.2})",
            ),
            "unknown param \"gamma\"",
        ),
        (
            GOOD.replace(
                "kind: \"Tonemap\")",
                "kind: \"Tonemap\", params: {\"white\": true})",
            ),
            "expected float, found bool",
        ),
        (
            GOOD.replace(
                "kind: \"Tonemap\")",
                "kind: \"Tonemap\", params: {\"white\": 0.0})",
            ),
            "out of range",
        ),
        (
            GOOD.replace("to: \"out.color\"", "to: \"nowhere.color\""),
            "no node \"nowhere\"",
        ),
        (
            GOOD.replace("(id: \"out\"", "(id: \"tonemap\""),
            "duplicate node id \"tonemap\"",
        ),
    ];
    for (i, (text, expected)) in cases.iter().enumerate() {
        let g = graph_file(dir.path(), &format!("case{i}.ron"), text, &chart());
        let e = render_fails(&g, &out);
        assert!(e.contains(expected), "case {i}: {e}");
        assert!(
            e.contains(&format!("case{i}.ron:")),
            "case {i} names no file and line: {e}"
        );
    }
}

#[test]
fn structural_errors() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    let incompatible = GOOD.replace(
        "    ],\n    edges: [\n",
        "        (id: \"exp\", kind: \"Exposure\"),\n        (id: \"out2\", kind: \"Output\"),\n    ],\n    edges: [\n        (from: \"tonemap.color\", to: \"exp.color\"),\n        (from: \"exp.color\", to: \"out2.color\"),\n",
    );
    let cycle = GOOD
        .replace("(id: \"tonemap\", kind: \"Tonemap\"),", "(id: \"a\", kind: \"Exposure\"),\n        (id: \"b\", kind: \"Exposure\"),\n        (id: \"tonemap\", kind: \"Tonemap\"),")
        .replace("(from: \"input.color\", to: \"tonemap.color\"),", "(from: \"a.color\", to: \"b.color\"),\n        (from: \"b.color\", to: \"a.color\"),\n        (from: \"b.color\", to: \"tonemap.color\"),");
    let no_output = GOOD
        .replace(
            "        (id: \"out\", kind: \"Output\", params: {\"path\": \"result.png\"}),\n",
            "",
        )
        .replace(
            "        (from: \"tonemap.color\", to: \"out.color\"),\n",
            "",
        );
    let two_into_one = GOOD.replace(
        "    ],\n    edges: [\n",
        "        (id: \"input2\", kind: \"ImageInput\", params: {\"path\": \"INPUT\"}),\n    ],\n    edges: [\n        (from: \"input2.color\", to: \"tonemap.color\"),\n",
    );
    let cases = [
        (
            incompatible,
            "tonemap.color produces ldr_color, but exp.color accepts hdr_color",
        ),
        (cycle, "cycle through nodes \"a\", \"b\""),
        (no_output, "no output node"),
        (two_into_one, "has two incoming edges"),
    ];
    for (i, (text, expected)) in cases.iter().enumerate() {
        let g = graph_file(dir.path(), &format!("s{i}.ron"), text, &chart());
        let e = render_fails(&g, &out);
        assert!(e.contains(expected), "case {i}: {e}");
        assert!(
            e.contains(&format!("s{i}.ron")),
            "case {i} names no file: {e}"
        );
    }
}

#[test]
fn missing_unreadable_and_corrupt_images() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();

    let missing = dir.path().join("missing.exr");
    let g = graph_file(dir.path(), "missing.ron", GOOD, &missing);
    let e = render_fails(&g, &out);
    assert!(
        e.contains("missing.ron:4:") && e.contains("node \"input\"") && e.contains("missing.exr"),
        "{e}"
    );

    let folder = dir.path().join("folder.exr");
    std::fs::create_dir(&folder).unwrap();
    let g = graph_file(dir.path(), "folder.ron", GOOD, &folder);
    let e = render_fails(&g, &out);
    assert!(
        e.contains("node \"input\"") && e.contains("folder.exr"),
        "{e}"
    );

    for ext in ["exr", "hdr", "png", "jpg"] {
        let corrupt = dir.path().join(format!("corrupt.{ext}"));
        std::fs::write(&corrupt, b"this is not an image at all, just some bytes").unwrap();
        let g = graph_file(dir.path(), &format!("corrupt_{ext}.ron"), GOOD, &corrupt);
        let e = render_fails(&g, &out);
        assert!(
            e.contains("node \"input\"") && e.contains(&format!("corrupt.{ext}")),
            "{ext}: {e}"
        );
    }

    // A truncated EXR: valid header, data cut off.
    let bytes = std::fs::read(chart()).unwrap();
    let truncated = dir.path().join("truncated.exr");
    std::fs::write(&truncated, &bytes[..bytes.len() / 2]).unwrap();
    let g = graph_file(dir.path(), "truncated.ron", GOOD, &truncated);
    let e = render_fails(&g, &out);
    assert!(e.contains("truncated.exr"), "{e}");
}

#[test]
fn unwritable_output_path() {
    let dir = tempfile::tempdir().unwrap();
    // The output folder would have to be inside a regular file.
    let blocker = dir.path().join("blocker");
    std::fs::write(&blocker, b"a file, not a folder").unwrap();
    let g = graph_file(dir.path(), "g.ron", GOOD, &chart());
    let e = render_fails(&g, &blocker.join("sub"));
    assert!(
        e.contains("node \"out\"") && e.contains("cannot write output"),
        "{e}"
    );
    assert_eq!(std::fs::read(&blocker).unwrap(), b"a file, not a folder");
}

#[test]
fn missing_graph_file() {
    let o = lumagraph(&["render", "no/such/graph.ron"]);
    let (_, stderr) = text(&o);
    assert!(!o.status.success());
    assert!(
        stderr.contains("no/such/graph.ron") && stderr.contains("cannot read graph file"),
        "{stderr}"
    );
}

#[test]
fn path_traced_render_reports_its_figures() {
    if common::gpu().is_none() {
        return;
    }
    let out = tempfile::tempdir().unwrap();
    let o = lumagraph(&[
        "render",
        "graphs/pathtrace.ron",
        "--scene",
        "assets/cornell.ron",
        "--spp",
        "8",
        "--out",
        out.path().to_str().unwrap(),
    ]);
    let (stdout, stderr) = text(&o);
    assert!(o.status.success(), "{stdout}\n{stderr}");
    for expected in [
        "rendered 8 spp at 256x256",
        "M paths/s",
        "M rays/s",
        "0 NaN/Inf samples dropped",
        "intersection inlined",
    ] {
        assert!(
            stdout.contains(expected),
            "missing {expected:?} in:\n{stdout}"
        );
    }
    let exr = lumagraph::render::image_io::load(&out.path().join("render.exr")).unwrap();
    assert_eq!((exr.width, exr.height), (256, 256));
    assert!(out.path().join("render.png").is_file());

    // Per-pass times: the path tracer is the cost of a frame. On a CPU adapter they are
    // wall times of each pass alone (lavapipe's timestamps reported ~0.01 ms for a 250 ms
    // path-tracing dispatch); there it must account for a good part of a frame (2 frames
    // of 4 spp here; measured ~90 %, 25 % leaves room for a loaded machine).
    let pass_ms = |name: &str| -> f64 {
        let line = stdout
            .lines()
            .find(|l| l.trim_start().starts_with(&format!("{name} ")))
            .unwrap_or_else(|| panic!("no time for {name} in:\n{stdout}"));
        line.split_whitespace().nth(1).unwrap().parse().unwrap()
    };
    let trace = pass_ms("pathtrace");
    for other in ["accumulate", "exposure", "tonemap"] {
        assert!(
            trace > pass_ms(other),
            "pathtrace not the largest:\n{stdout}"
        );
    }
    if stdout.contains("wall time of each pass") {
        let seconds: f64 = stdout
            .lines()
            .find(|l| l.starts_with("rendered "))
            .and_then(|l| l.split(" in ").nth(1))
            .and_then(|t| t.split(' ').next())
            .and_then(|t| t.parse().ok())
            .unwrap_or_else(|| panic!("no render time in:\n{stdout}"));
        let frame_ms = seconds * 1e3 / 2.0;
        assert!(
            trace > 0.25 * frame_ms,
            "pathtrace {trace} ms of a {frame_ms} ms frame:\n{stdout}"
        );
    }
}

#[test]
fn scene_graph_without_scene_is_a_clear_error() {
    let o = lumagraph(&["render", "graphs/pathtrace.ron"]);
    let (_, stderr) = text(&o);
    assert!(!o.status.success());
    assert!(
        stderr.contains("node \"pathtrace\"") && stderr.contains("--scene"),
        "{stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
}

#[test]
fn bad_scene_file_names_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("bad.ron");
    std::fs::write(&scene, "(\n    version: 1,\n    camera: Perspective(position: (0, 0, 1), target: (0, 0, 0), fov_y: 40),\n    shapes: [Sphere(center: (0, 0, 0), radius: 1, material: \"nope\")],\n    render: (width: 8, height: 8),\n)\n").unwrap();
    let o = lumagraph(&[
        "plan",
        "graphs/pathtrace.ron",
        "--scene",
        scene.to_str().unwrap(),
    ]);
    let (_, stderr) = text(&o);
    assert!(!o.status.success());
    assert!(
        stderr.contains("bad.ron:4:") && stderr.contains("\"nope\""),
        "{stderr}"
    );
}

#[test]
fn default_denoise_graph_renders_and_reports_denoise_time() {
    if common::gpu().is_none() {
        return;
    }
    let out = tempfile::tempdir().unwrap();
    let o = lumagraph(&[
        "render",
        "graphs/pathtrace_denoise.ron",
        "--scene",
        "assets/cornell.ron",
        "--spp",
        "4",
        "--out",
        out.path().to_str().unwrap(),
    ]);
    let (stdout, stderr) = text(&o);
    assert!(o.status.success(), "{stdout}\n{stderr}");
    assert!(stdout.contains("rendered 4 spp at 256x256"), "{stdout}");
    for name in ["render.png", "render.exr", "raw.exr"] {
        assert!(out.path().join(name).is_file(), "{name} missing");
    }
    let plan = lumagraph(&[
        "plan",
        "graphs/pathtrace_denoise.ron",
        "--scene",
        "assets/cornell.ron",
    ]);
    let (stdout, _) = text(&plan);
    assert!(
        stdout.contains("2097152 bytes") && stdout.contains("2 rgba32f ping-pong images"),
        "{stdout}"
    );
}

#[test]
fn converge_writes_csv_and_plot() {
    if common::gpu().is_none() {
        return;
    }
    let out = tempfile::tempdir().unwrap();
    let o = lumagraph(&[
        "converge",
        "graphs/pathtrace_denoise.ron",
        "--scene",
        "assets/cornell.ron",
        "--reference",
        "tests/reference/cornell_ref.exr",
        "--seconds",
        "0.5",
        "--compare",
        "tests/reference/cornell_converge.csv",
        "--out",
        out.path().to_str().unwrap(),
    ]);
    let (stdout, stderr) = text(&o);
    assert!(o.status.success(), "{stdout}\n{stderr}");
    assert!(
        stdout.contains("denoise") && stdout.contains("ms per frame"),
        "{stdout}"
    );
    let csv = std::fs::read_to_string(out.path().join("converge.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next(),
        Some("output,spp,seconds,rmse,relmse,ssim,gpu_ms")
    );
    assert!(lines.any(|l| l.starts_with("denoise,1,")), "{csv}");
    if !stdout.contains("plot not written") {
        assert!(out.path().join("converge.png").is_file());
    }
}

/// `--intersector` and `--schedule` on `plan` (and the `PathTrace` params, which win): the
/// choice is printed with why, and one the scene cannot have is an error naming why.
#[test]
fn plan_shows_the_intersector_asked_for_or_refuses_it() {
    let plan = |extra: &[&str]| {
        let mut args = vec!["plan", "graphs/pathtrace.ron", "--scene"];
        args.extend_from_slice(extra);
        let o = lumagraph(&args);
        let (stdout, stderr) = text(&o);
        (o.status.success(), stdout, stderr)
    };
    let (ok, stdout, stderr) = plan(&["assets/cornell.ron", "--intersector", "wide"]);
    assert!(ok, "{stderr}");
    assert!(
        stdout.contains("  intersector: wide (asked for)"),
        "{stdout}"
    );
    assert!(stdout.contains("  schedule: megakernel ("), "{stdout}");
    let (ok, stdout, stderr) = plan(&[
        "assets/cornell.ron",
        "--intersector",
        "wide",
        "--set",
        "pathtrace.intersector=binary",
    ]);
    assert!(ok, "{stderr}");
    assert!(stdout.contains("  intersector: binary ("), "{stdout}");
    let (ok, _, stderr) = plan(&["assets/cornell_spheres.ron", "--intersector", "host"]);
    assert!(!ok);
    assert!(
        stderr.contains("host intersection, cannot trace this scene here: analytic shapes"),
        "{stderr}"
    );
    let (ok, _, stderr) = plan(&["assets/cornell.ron", "--schedule", "sideways"]);
    assert!(
        !ok && stderr.contains("auto, megakernel or wavefront"),
        "{stderr}"
    );
}

#[test]
fn plan_lists_shader_features_for_the_scene() {
    let o = lumagraph(&[
        "plan",
        "graphs/pathtrace.ron",
        "--scene",
        "assets/cornell.ron",
    ]);
    let (stdout, stderr) = text(&o);
    assert!(o.status.success(), "{stderr}");
    let left_out = stdout.split("left out:\n").last().unwrap();
    for f in [
        "shape tests",
        "environment",
        "metal lobe",
        "glass lobe",
        "rough diffuse (EON)",
        "participating media",
        "first-hit AOVs",
    ] {
        assert!(
            left_out.contains(f),
            "{f} not listed as left out:\n{stdout}"
        );
    }
    let o = lumagraph(&[
        "plan",
        "graphs/pathtrace.ron",
        "--scene",
        "assets/diffuse_roughness.ron",
    ]);
    let (rough, stderr) = text(&o);
    assert!(o.status.success(), "{stderr}");
    let compiled_in = rough.split("left out:\n").next().unwrap();
    assert!(
        compiled_in.contains("8 materials with diffuse_roughness > 0"),
        "{rough}"
    );
    // The intersector chosen, why, and why not each of the others.
    assert!(
        stdout.contains("  intersector: inline (36 primitives, "),
        "{stdout}"
    );
    for other in ["host", "wide", "binary"] {
        assert!(
            stdout.contains(&format!(
                "    not {other}: inline intersection traces the scene"
            )),
            "{stdout}"
        );
    }
    // Where the adapter has no ray queries, that is the reason given instead.
    assert!(stdout.contains("    not rays: "), "{stdout}");
    assert!(
        stdout.contains(
            "    inline materials and lights  4 materials, 2 lights, 36 primitives' shading data"
        ),
        "{stdout}"
    );
}

#[test]
fn firefly_clamp_is_reported_when_on() {
    if common::gpu().is_none() {
        return;
    }
    let out = tempfile::tempdir().unwrap();
    let dir = out.path().to_str().unwrap();
    let args = [
        "render",
        "graphs/pathtrace.ron",
        "--scene",
        "assets/cornell.ron",
        "--spp",
        "4",
        "--out",
        dir,
    ];
    let o = lumagraph(&args);
    assert!(o.status.success());
    assert!(
        !text(&o).0.contains("firefly clamp"),
        "clamp reported while off"
    );
    let mut on = args.to_vec();
    on.extend(["--set", "pathtrace.firefly_clamp=10"]);
    let o = lumagraph(&on);
    let (stdout, stderr) = text(&o);
    assert!(o.status.success(), "{stderr}");
    assert!(stdout.contains("firefly clamp ON"), "{stdout}");
}

/// The gallery in the docs has one image per registry kind and no image of a kind that is
/// gone: a kind added without running `lumagraph gallery --out docs` fails here.
#[test]
fn docs_gallery_is_complete() {
    let page = std::fs::read_to_string(common::repo("docs/gallery.md")).unwrap();
    let registry = lumagraph::graph::Registry::with_builtins();
    for k in registry.kinds() {
        let image = format!("gallery/{}.png", k.name);
        assert!(
            page.contains(&format!("![{}]({image})", k.name)),
            "docs/gallery.md does not show {}: run `lumagraph gallery --out docs`",
            k.name
        );
        assert!(
            common::repo("docs").join(&image).is_file(),
            "docs/{image} is missing"
        );
    }
    for entry in std::fs::read_dir(common::repo("docs/gallery")).unwrap() {
        let name = entry.unwrap().file_name().into_string().unwrap();
        let kind = name.strip_suffix(".png").unwrap_or(&name);
        assert!(
            registry.get(kind).is_some(),
            "docs/gallery/{name}: no such kind"
        );
    }
}

/// `gallery --kind` renders the kinds named, one PNG each, and refuses an unknown one.
#[test]
fn gallery_renders_the_kinds_asked_for() {
    if common::gpu().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().to_str().unwrap();
    let o = lumagraph(&[
        "gallery", "--out", out, "--kind", "Bloom", "--kind", "Output",
    ]);
    assert!(o.status.success(), "{:?}", text(&o));
    for k in ["Bloom", "Output"] {
        let png = dir.path().join("gallery").join(format!("{k}.png"));
        let img = lumagraph::render::image_io::load(&png).unwrap();
        assert_eq!((img.width, img.height), (384, 192), "{k}");
    }
    assert!(!dir.path().join("gallery.md").exists());
    let o = lumagraph(&["gallery", "--out", out, "--kind", "Nope"]);
    assert!(!o.status.success());
    assert!(
        text(&o).1.contains("no node kind called \"Nope\""),
        "{:?}",
        text(&o)
    );
}

/// `gltf-gallery` renders each model of the folders given into a PNG of the size asked for
/// and lists it on the contact sheet with what it tests and what loading said; a model that
/// does not load is listed with its error, and the rest still render.
#[test]
fn gltf_gallery_lists_each_model_with_what_it_tests() {
    if common::gpu().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let models = dir.path().join("models");
    let vc = models.join("VertexColorTest");
    std::fs::create_dir_all(&vc).unwrap();
    for f in ["VertexColorTest.glb", "metadata.json"] {
        std::fs::copy(
            common::repo("assets/gltf-conformance/VertexColorTest").join(f),
            vc.join(f),
        )
        .unwrap();
    }
    std::fs::write(
        models.join("Iridescent.gltf"),
        r#"{"asset": {"version": "2.0"}, "extensionsUsed": ["KHR_materials_iridescence"],
  "extensionsRequired": ["KHR_materials_iridescence"]}"#,
    )
    .unwrap();
    // A file that loads but holds nothing to render.
    std::fs::write(
        models.join("Empty.gltf"),
        r#"{"asset": {"version": "2.0"}}"#,
    )
    .unwrap();
    let out = dir.path().join("out");
    let o = lumagraph(&[
        "gltf-gallery",
        models.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--size",
        "40x30",
        "--spp",
        "1",
    ]);
    assert!(o.status.success(), "{:?}", text(&o));
    let img =
        lumagraph::render::image_io::load(&out.join("gltf-gallery/VertexColorTest.png")).unwrap();
    assert_eq!((img.width, img.height), (40, 30));
    let page = std::fs::read_to_string(out.join("gltf-gallery.md")).unwrap();
    for want in [
        "## VertexColorTest\n\nTests if vertex colors are supported.",
        "![VertexColorTest](gltf-gallery/VertexColorTest.png)",
        "## Iridescent",
        "Does not load: `",
        "requires the extension KHR_materials_iridescence",
        "## Empty",
        "the scene has no triangle or analytic shape",
    ] {
        assert!(page.contains(want), "missing «{want}» in:\n{page}");
    }
    let o = lumagraph(&[
        "gltf-gallery",
        "--size",
        "40by30",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(
        text(&o).1.contains("--size 40by30: expected WIDTHxHEIGHT"),
        "{:?}",
        text(&o)
    );
}

/// The docs' glTF gallery shows every model of `assets/gltf-conformance/`: a model added
/// without running `lumagraph gltf-gallery --out docs` fails here.
#[test]
fn docs_gltf_gallery_shows_every_model() {
    let page = std::fs::read_to_string(common::repo("docs/gltf-gallery.md")).unwrap();
    for entry in std::fs::read_dir(common::repo("assets/gltf-conformance")).unwrap() {
        let path = entry.unwrap().path();
        if !path.is_dir() {
            continue;
        }
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let image = format!("gltf-gallery/{name}.png");
        assert!(
            page.contains(&format!("![{name}]({image})")),
            "docs/gltf-gallery.md does not show {name}: run `lumagraph gltf-gallery --out docs`"
        );
        assert!(
            common::repo("docs").join(&image).is_file(),
            "docs/{image} is missing"
        );
    }
}

/// Every graph shipped under `graphs/` validates (with the Cornell box for those that
/// render a scene).
#[test]
fn every_shipped_graph_validates() {
    let mut checked = 0;
    for entry in std::fs::read_dir(common::repo("graphs")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "ron") {
            let o = lumagraph(&[
                "validate",
                path.to_str().unwrap(),
                "--scene",
                "assets/cornell.ron",
            ]);
            let (stdout, stderr) = text(&o);
            assert!(
                o.status.success(),
                "{}:\n{stdout}\n{stderr}",
                path.display()
            );
            checked += 1;
        }
    }
    assert!(checked >= 5, "{checked} graphs");
}

/// `graphs/compare_reference.ron`: the render prints each Difference node's error against
/// the Mitsuba reference and writes its heat map; at 16 spp the denoised image is closer
/// to the reference than the raw accumulation (measured: relMSE 9.5e-4 against 1.4e-2 on
/// lavapipe, deterministic with the Sobol sampler).
#[test]
fn render_prints_the_error_against_a_reference() {
    if common::gpu().is_none() {
        return;
    }
    let out = tempfile::tempdir().unwrap();
    let o = lumagraph(&[
        "render",
        "graphs/compare_reference.ron",
        "--scene",
        "assets/cornell.ron",
        "--spp",
        "16",
        "--out",
        out.path().to_str().unwrap(),
    ]);
    let (stdout, stderr) = text(&o);
    assert!(o.status.success(), "{stdout}\n{stderr}");
    let measured = |node: &str| -> f64 {
        let prefix = format!("measured {node}.relmse: ");
        stdout
            .lines()
            .find_map(|l| l.strip_prefix(&prefix))
            .and_then(|v| v.trim().parse().ok())
            .unwrap_or_else(|| panic!("no {prefix} in:\n{stdout}"))
    };
    let (raw, denoised) = (measured("raw_error"), measured("denoised_error"));
    assert!(
        denoised > 0.0 && denoised < raw,
        "denoised {denoised} vs raw {raw}"
    );
    for heat in ["raw_error.png", "denoised_error.png"] {
        assert!(out.path().join(heat).is_file(), "{heat}");
    }
}

/// A successful render prints no line starting with `error:`, also where the session has
/// no `XDG_RUNTIME_DIR` (Mesa's device-select layer asks Wayland for a display there, and
/// libwayland complains on stderr; the CLI switches that layer off).
#[test]
fn a_successful_render_prints_no_error_line() {
    if common::gpu().is_none() {
        return;
    }
    let out = tempfile::tempdir().unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_lumagraph"))
        .args(["render", "graphs/post_tonemap.ron", "--out"])
        .arg(out.path())
        .current_dir(common::root())
        .env_remove("XDG_RUNTIME_DIR")
        .env_remove("NODEVICE_SELECT")
        .output()
        .unwrap();
    let (stdout, stderr) = text(&o);
    assert!(o.status.success(), "{stdout}\n{stderr}");
    let errors: Vec<&str> = stderr.lines().filter(|l| l.starts_with("error:")).collect();
    assert!(errors.is_empty(), "{errors:?}");
}

/// The editor's Render to file writes what `lumagraph render` writes for the same graph,
/// scene and sample count: the same frames in the same order, so the EXR files are
/// identical (8 spp of the Cornell box at its full 256×256).
#[test]
fn render_to_file_in_the_editor_equals_the_cli_render() {
    use lumagraph::editor::render_job::{RenderJob, RenderRequest, Target};
    let Some(gpu) = common::gpu() else { return };
    let dir = tempfile::tempdir().unwrap();
    let (cli_dir, editor_dir) = (dir.path().join("cli"), dir.path().join("editor"));
    let (ok, out, err) = common::cli(&[
        "render",
        "graphs/pathtrace.ron",
        "--scene",
        "assets/cornell.ron",
        "--spp",
        "8",
        "--out",
        cli_dir.to_str().unwrap(),
    ]);
    assert!(ok, "{out}\n{err}");
    let graph = lumagraph::graph::Graph::load(&common::repo("graphs/pathtrace.ron")).unwrap();
    let request = RenderRequest {
        registry: lumagraph::pathtrace::library::builtins().registry().clone(),
        base: graph.base_dir(),
        graph,
        scene: Some(common::gpu_scene("assets/cornell.ron", None)),
        spp: 8,
        target: Target::Outputs(editor_dir.clone()),
    };
    let library = std::sync::Arc::new(lumagraph::pathtrace::library::builtins().clone());
    let job = RenderJob::start(gpu.clone(), library, request);
    assert!(
        job.wait(std::time::Duration::from_secs(300)),
        "the render hangs"
    );
    let written = job.progress().finished.unwrap().expect("written");
    assert_eq!(written.len(), 2);
    let read = |d: &Path| lumagraph::render::image_io::load(&d.join("render.exr")).unwrap();
    let (a, b) = (read(&cli_dir), read(&editor_dir));
    assert_eq!((b.width, b.height), (256, 256));
    assert!(
        a.pixels == b.pixels,
        "the editor's render differs from the CLI's"
    );
}

/// An image larger than the device holds is rendered in tiles, unless `--tile 0`: then it is
/// one clear error naming the port, the size, the adapter and its limit, before anything is
/// allocated; never wgpu's panic. At 100000×100000 the tiled render's images do not fit this
/// machine's memory: one clear error before the first tile.
#[test]
fn an_image_larger_than_the_device_holds_is_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("huge.ron");
    let text = std::fs::read_to_string(common::repo("assets/cornell.ron"))
        .unwrap()
        .replace("width: 256, height: 256", "width: 100000, height: 100000");
    std::fs::write(&scene, text).unwrap();
    let render = |extra: &[&str]| {
        let mut args = vec![
            "render",
            "graphs/pathtrace.ron",
            "--scene",
            scene.to_str().unwrap(),
            "--out",
            dir.path().to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        let (ok, out, err) = common::cli(&args);
        assert!(!ok, "{out}");
        assert!(!err.contains("panicked"), "{err}");
        let line = err
            .lines()
            .find(|l| l.starts_with("error:"))
            .expect("an error line")
            .to_owned();
        (out, line)
    };
    let (_, line) = render(&["--tile", "0"]);
    assert!(
        line.contains("pathtrace.color: 100000×100000 image")
            && line.contains("the largest image this device holds is"),
        "{line}"
    );
    // Tiled, but no tile is rendered: the images it writes (a PNG of 4 and an EXR of 16
    // bytes a pixel) do not fit this machine.
    let (out, line) = render(&[]);
    assert!(out.contains("tiled: "), "{out}");
    assert!(
        line.contains(
            "the 2 images this render writes (100000×100000: 186.3 GiB, and 298.0 GiB more \
             while one is written) on this machine:"
        ) && line.contains("of memory is available; render smaller"),
        "{line}"
    );
}

/// The Cornell box at 64×64 and 1024 spp (256 frames of 4 samples): a few seconds on
/// lavapipe.
fn small_cornell(dir: &Path) -> std::path::PathBuf {
    let scene = dir.join("small.ron");
    let text = std::fs::read_to_string(common::repo("assets/cornell.ron"))
        .unwrap()
        .replace(
            "width: 256, height: 256, max_bounces: 20, spp: 256",
            "width: 64, height: 64, max_bounces: 20, spp: 1024",
        );
    std::fs::write(&scene, text).unwrap();
    scene
}

/// Ctrl-C (SIGINT) during a render writes the outputs of the samples so far and a
/// checkpoint, and exits non-zero saying so; `--resume` goes on to the full sample count
/// and writes exactly (bit for bit) what an uninterrupted render writes. A checkpoint of
/// another scene is refused.
#[test]
fn an_interrupted_render_resumes_bit_identically() {
    use std::io::BufRead as _;
    if common::gpu().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let scene = small_cornell(dir.path());
    let out = |name: &str| dir.path().join(name);
    let args = |o: &Path| {
        vec![
            "render".to_owned(),
            "graphs/pathtrace.ron".into(),
            "--scene".into(),
            scene.display().to_string(),
            "--out".into(),
            o.display().to_string(),
        ]
    };
    let mut child = Command::new(env!("CARGO_BIN_EXE_lumagraph"))
        .args(args(&out("stopped")))
        .current_dir(common::root())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Once the shaders are compiled, frames are running: interrupt.
    let mut stdout = std::io::BufReader::new(child.stdout.take().unwrap());
    let mut line = String::new();
    while stdout.read_line(&mut line).unwrap() > 0 && !line.contains("warm-up") {
        line.clear();
    }
    std::thread::sleep(std::time::Duration::from_millis(300));
    let kill = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    let mut rest = String::new();
    std::io::Read::read_to_string(&mut stdout, &mut rest).unwrap();
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    if o.status.success() {
        eprintln!("the render finished before the signal (a fast device): nothing to resume");
        return;
    }
    assert!(!err.contains("panicked"), "{err}");
    assert!(err.contains("error: interrupted at frame"), "{err}");
    assert!(
        rest.contains("wrote") && rest.contains("render.exr"),
        "{rest}"
    );
    let checkpoint = out("stopped").join("render.checkpoint");
    let saved = lumagraph::render::Checkpoint::load(&checkpoint).unwrap();
    assert!((1..256).contains(&saved.frames), "{} frames", saved.frames);
    let partial = lumagraph::render::image_io::load(&out("stopped").join("render.exr")).unwrap();
    assert!(
        partial.pixels.iter().any(|p| p[0] > 0.0),
        "the samples so far"
    );

    let mut resume = args(&out("resumed"));
    resume.extend(["--resume".to_owned(), checkpoint.display().to_string()]);
    let resume: Vec<&str> = resume.iter().map(String::as_str).collect();
    let (ok, stdout, stderr) = common::cli(&resume);
    assert!(ok, "{stdout}\n{stderr}");
    assert!(
        stdout.contains(&format!("at frame {} of 256", saved.frames)),
        "{stdout}"
    );
    let whole = args(&out("whole"));
    let whole: Vec<&str> = whole.iter().map(String::as_str).collect();
    let (ok, stdout, stderr) = common::cli(&whole);
    assert!(ok, "{stdout}\n{stderr}");
    let read = |d: &str| std::fs::read(out(d).join("render.exr")).unwrap();
    assert!(
        read("resumed") == read("whole"),
        "the resumed render differs"
    );

    // Another scene (the full-size box) is refused, naming why.
    let (ok, _, stderr) = common::cli(&[
        "render",
        "graphs/pathtrace.ron",
        "--scene",
        "assets/cornell.ron",
        "--out",
        out("other").to_str().unwrap(),
        "--resume",
        checkpoint.to_str().unwrap(),
    ]);
    assert!(!ok);
    assert!(
        stderr.contains("cannot resume from") && stderr.contains("another graph or scene"),
        "{stderr}"
    );
}

/// `--checkpoint-every` writes the checkpoint while rendering and at the end; a finished
/// render goes on from its last checkpoint to more samples, exactly as a render of that many
/// samples from the start; asking for no more samples than it has is refused.
#[test]
fn checkpoints_every_few_seconds_and_at_the_end() {
    if common::gpu().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let scene = small_cornell(dir.path());
    let out = |name: &str| dir.path().join(name);
    let checkpoint = dir.path().join("ck.bin");
    let run = |o: &str, spp: &str, extra: &[&str]| {
        let o = out(o);
        let mut args = vec![
            "render",
            "graphs/pathtrace.ron",
            "--scene",
            scene.to_str().unwrap(),
            "--spp",
            spp,
            "--out",
            o.to_str().unwrap(),
        ];
        args.extend(extra);
        common::cli(&args)
    };
    let ck = checkpoint.to_str().unwrap();
    let (ok, stdout, stderr) = run(
        "a",
        "64",
        &["--checkpoint", ck, "--checkpoint-every", "0.01"],
    );
    assert!(ok, "{stdout}\n{stderr}");
    let saved = lumagraph::render::Checkpoint::load(&checkpoint).unwrap();
    assert_eq!(saved.frames, 16, "64 spp in frames of 4");
    let (ok, stdout, stderr) = run("b", "128", &["--resume", ck]);
    assert!(ok, "{stdout}\n{stderr}");
    assert!(stdout.contains("at frame 16 of 32"), "{stdout}");
    let (ok, stdout, stderr) = run("c", "128", &[]);
    assert!(ok, "{stdout}\n{stderr}");
    let read = |d: &str| std::fs::read(out(d).join("render.exr")).unwrap();
    assert!(read("b") == read("c"), "64 + 64 spp differ from 128 spp");
    let (ok, _, stderr) = run("d", "64", &["--resume", ck]);
    assert!(!ok && stderr.contains("nothing to resume"), "{stderr}");
}

/// `bench --specialized-only` measures the specialized shader alone and, where the host
/// intersects the rays (a CPU adapter with Embree), says where the host thread's time went:
/// a number of steps per frame and milliseconds that add up to no more than the frame.
#[test]
fn bench_reports_where_host_intersection_spends_its_time() {
    let Some(gpu) = common::gpu() else { return };
    let o = lumagraph(&[
        "bench",
        "--scene",
        "tests/scenes/mesh_env.ron",
        "--spp",
        "2",
        "--runs",
        "1",
        "--specialized-only",
    ]);
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    assert!(out.contains("specialized"), "{out}");
    assert!(!out.contains("general"), "{out}");
    if !gpu.is_cpu() || !out.contains("rays intersected on the host") {
        return;
    }
    let line = out
        .lines()
        .find(|l| l.contains("host thread, per frame of"))
        .unwrap_or_else(|| panic!("no host thread line: {out}"));
    let numbers: Vec<f64> = line
        .split_whitespace()
        .filter_map(|w| w.trim_end_matches([',', ':', ')']).parse().ok())
        .collect();
    // Steps, waiting, Embree, the rest, and the frame.
    assert_eq!(numbers.len(), 5, "{line}");
    assert!(numbers[0] >= 2.0, "{line}");
    assert!(
        numbers[1] + numbers[2] + numbers[3] <= numbers[4] * 1.01 + 1.0,
        "{line}"
    );
    assert!(numbers[2] > 0.0, "{line}");
}

/// `bench --traversal` times closest-hit queries alone through both BVHs: a line each with
/// primary and diffuse M rays/s (positive), and their ratio.
#[test]
fn bench_traversal_times_both_bvhs() {
    let Some(_) = common::gpu() else { return };
    let o = lumagraph(&[
        "bench",
        "--scene",
        "tests/scenes/mesh_env.ron",
        "--traversal",
        "--runs",
        "1",
    ]);
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    for name in ["binary BVH", "8-wide BVH"] {
        let line = out
            .lines()
            .find(|l| l.trim_start().starts_with(name) && l.contains("M rays/s"))
            .unwrap_or_else(|| panic!("no {name} line: {out}"));
        let rates: Vec<f64> = line
            .split_whitespace()
            .filter_map(|w| w.parse().ok())
            .collect();
        assert_eq!(rates.len(), 2, "{line}");
        assert!(rates.iter().all(|&r| r > 0.0), "{line}");
    }
    assert!(out.contains("8-wide / binary: primary"), "{out}");
}

/// The reduced Crytek Sponza (24 textures of 128², 6 atlas pages of 256², 1.5 MiB) at 16×16
/// with a texture memory budget of 1 MiB: refused with one error naming the textures, their
/// size and the budget, nothing written; with `--fit-textures`, rendered, each image made
/// smaller named in a warning and the atlas within the budget.
#[test]
fn textures_over_the_budget_are_refused_or_downscaled_when_asked() {
    if common::gpu().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("sponza.ron");
    let described = std::fs::read_to_string(common::repo("tests/scenes/sponza_diffuse.ron"))
        .unwrap()
        .replace(
            "../../assets/sponza-small/Sponza.gltf",
            common::repo("assets/sponza-small/Sponza.gltf")
                .to_str()
                .unwrap(),
        )
        .replace(
            "../../assets/hdri/venice_sunset_1k.hdr",
            common::repo("assets/hdri/venice_sunset_1k.hdr")
                .to_str()
                .unwrap(),
        )
        .replace("width: 128, height: 128", "width: 16, height: 16");
    std::fs::write(&scene, described).unwrap();
    let out = dir.path().join("out");
    let args = |more: &[&'static str]| {
        let mut a = vec![
            "render".to_owned(),
            "graphs/pathtrace.ron".to_owned(),
            "--scene".to_owned(),
            scene.to_str().unwrap().to_owned(),
            "--out".to_owned(),
            out.to_str().unwrap().to_owned(),
            "--spp".to_owned(),
            "4".to_owned(),
            "--texture-memory".to_owned(),
            "1".to_owned(),
        ];
        a.extend(more.iter().map(|s| (*s).to_owned()));
        a
    };
    let refused = args(&[]);
    let o = lumagraph(&refused.iter().map(String::as_str).collect::<Vec<_>>());
    let (stdout, stderr) = text(&o);
    assert!(!o.status.success(), "{stdout}\n{stderr}");
    assert!(
        stderr.contains(
            "error: scene textures: 24 textures in 6 pages of 256x256 texels (1.5 MiB): over the \
             texture memory budget of 1 MiB (--texture-memory); pass --fit-textures"
        ),
        "{stderr}"
    );
    assert!(!out.exists() || common::is_empty_dir(&out));
    let fitted = args(&["--fit-textures"]);
    let o = lumagraph(&fitted.iter().map(String::as_str).collect::<Vec<_>>());
    let (stdout, stderr) = text(&o);
    assert!(o.status.success(), "{stdout}\n{stderr}");
    let warnings = stdout
        .lines()
        .filter(|l| {
            l.starts_with("scene warning: texture ")
                && l.contains(" downscaled from 128x128 to 64x64")
        })
        .count();
    assert!(
        stdout.contains(&format!(
            "now 4 pages of 256x256 (1.0 MiB), {warnings} images downscaled"
        )) && warnings > 0,
        "{stdout}"
    );
    assert!(out.join("render.png").is_file());
}

/// On a terminal, a render names each stage before its first frame with a spinner on
/// standard error (loading the scene, the GPU layout, pipelines and uploads, the warm-up),
/// cleared when the stage ends; elsewhere (as in every other test here) nothing of it is
/// written. The terminal is `script`'s pseudo-terminal (util-linux).
#[test]
fn a_render_on_a_terminal_names_the_stage_it_is_in() {
    let Some(_) = common::gpu() else { return };
    let out = tempfile::tempdir().unwrap();
    let log = out.path().join("typescript");
    let command = format!(
        "{} render graphs/pathtrace.ron --scene assets/cornell.ron --spp 4 --out {}",
        env!("CARGO_BIN_EXE_lumagraph"),
        out.path().display()
    );
    let status = std::process::Command::new("script")
        .args(["-q", "-e", "-c", &command])
        .arg(&log)
        .current_dir(common::root())
        .stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::null())
        .status()
        .expect("`script` (util-linux) runs the render on a pseudo-terminal");
    assert!(status.success(), "{status}");
    let text = std::fs::read_to_string(&log).unwrap();
    for stage in [
        "loading assets/cornell.ron (meshes, textures)",
        "GPU layout (BVH, triangles, lights, texture atlas)",
        "pipelines and uploads (",
        "warm-up (the first frame",
    ] {
        assert!(text.contains(stage), "no stage {stage:?} in {text}");
    }
    // Each spinner line is erased when its stage ends.
    assert!(text.contains("\u{1b}[2K"), "{text}");
    // Not on a terminal: none of it.
    let (ok, stdout, stderr) = common::cli(&[
        "render",
        "graphs/pathtrace.ron",
        "--scene",
        "assets/cornell.ron",
        "--spp",
        "4",
        "--out",
        &out.path().join("plain").to_string_lossy(),
    ]);
    assert!(ok, "{stderr}");
    assert!(!stderr.contains("(meshes, textures)") && !stdout.contains("(meshes, textures)"));
}
