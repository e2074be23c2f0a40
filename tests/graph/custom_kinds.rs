//! Node kinds declared in graph files: a declared kind against the built-in it copies
//! (bit-identical), several outputs and an optional input against a CPU reference, the
//! shipped example, and every kind of bad declaration or WGSL refused with one located
//! error and a non-zero exit, never a panic.

use crate::common;

use std::path::Path;

use common::{map_pixels, repo};
use lumagraph::graph::{Graph, ParamValue};
use lumagraph::render::image_io;

const CHART: &str = "assets/test_chart.exr";

/// A version-2 graph declaring `kinds` (RON list items) with `body` (nodes and edges).
fn graph_text(kinds: &str, body: &str) -> String {
    format!("(\n    version: 2,\n    kinds: [\n{kinds}\n    ],\n{body}\n)\n")
}

fn write(dir: &Path, name: &str, text: &str) -> std::path::PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// Loads, compiles and runs one frame of the graph at `path`, returning the `keep` ports.
fn run(path: &Path, keep: &[&str]) -> Option<Vec<lumagraph::render::cpu::Image>> {
    use lumagraph::pathtrace::library::compile;
    use lumagraph::render::Resources;
    let ctx = common::gpu()?;
    let graph = Graph::load(path).unwrap();
    let keep: Vec<String> = keep.iter().map(|&k| k.to_owned()).collect();
    let plan = compile(&graph, &keep, None).unwrap_or_else(|e| panic!("{e}"));
    let resources = Resources {
        base_dir: graph.base_dir(),
        out_dir: graph.base_dir(),
        ..Resources::default()
    };
    let mut exec = lumagraph::pathtrace::library::executor(ctx, plan, &resources).unwrap();
    exec.run_frame().unwrap();
    Some(keep.iter().map(|k| exec.read_port(k).unwrap()).collect())
}

use common::cli as lumagraph;

const MY_EXPOSURE: &str = r#"        (
            name: "MyExposure",
            inputs: [(name: "color")],
            outputs: [(name: "color")],
            params: [(name: "ev", type: Float(default: 0.0, min: -20.0, max: 20.0))],
            code: r"
fn node(pixel: vec2u, size: vec2u) -> vec4f {
    let c = load_color(vec2i(pixel));
    return vec4f(c.rgb * exp2(params.ev), c.a);
}
",
        ),"#;

#[test]
fn a_declared_kind_matches_the_built_in_it_copies() {
    let dir = tempfile::tempdir().unwrap();
    let chart = repo(CHART).display().to_string();
    let body = format!(
        r#"    nodes: [
        (id: "in", kind: "ImageInput", params: {{"path": "{chart}"}}),
        (id: "mine", kind: "MyExposure", params: {{"ev": 1.7}}),
        (id: "builtin", kind: "Exposure", params: {{"ev": 1.7}}),
    ],
    edges: [
        (from: "in.color", to: "mine.color"),
        (from: "in.color", to: "builtin.color"),
    ],"#
    );
    let path = write(dir.path(), "g.ron", &graph_text(MY_EXPOSURE, &body));
    let Some(out) = run(&path, &["mine.color", "builtin.color"]) else {
        return;
    };
    assert_eq!(out[0], out[1]);
}

#[test]
fn several_outputs_and_an_optional_input() {
    let kinds = r#"        (
            name: "Spread",
            inputs: [(name: "a"), (name: "b", optional: true, types: ["hdr_color", "albedo"])],
            outputs: [(name: "sum"), (name: "shifted")],
            params: [
                (name: "gain", type: Float(default: 1.0, min: 0.0, max: 10.0)),
                (name: "mode", type: Enum(default: "plain", options: ["plain", "squared"])),
                (name: "flip", type: Bool(default: false)),
            ],
            code: "fn node(pixel: vec2u, size: vec2u) -> Outputs {
    let a = load_a(vec2i(pixel));
    var b = vec4f(0.25);
    if params.has_b != 0u {
        b = load_b(vec2i(pixel));
    }
    var s = params.gain * (a + b);
    if params.mode == 1u {
        s = s * s;
    }
    // The left neighbour (clamped at the edge); mirrored when flip is set.
    var q = vec2i(pixel) - vec2i(1, 0);
    if params.flip != 0u {
        q = vec2i(size) - 1 - vec2i(pixel);
    }
    return Outputs(s, load_a(q));
}",
        ),"#;
    let dir = tempfile::tempdir().unwrap();
    let chart = repo(CHART).display().to_string();
    let body = format!(
        r#"    nodes: [
        (id: "in", kind: "ImageInput", params: {{"path": "{chart}"}}),
        (id: "two", kind: "Spread", params: {{"gain": 0.5, "mode": "squared"}}),
        (id: "one", kind: "Spread", params: {{"flip": true}}),
    ],
    edges: [
        (from: "in.color", to: "two.a"),
        (from: "in.color", to: "two.b"),
        (from: "in.color", to: "one.a"),
    ],"#
    );
    let path = write(dir.path(), "g.ron", &graph_text(kinds, &body));
    let keep = ["two.sum", "two.shifted", "one.sum", "one.shifted"];
    let Some(out) = run(&path, &keep) else {
        return;
    };
    let image = image_io::load(&repo(CHART)).unwrap();
    let (w, h) = (image.width as usize, image.height as usize);
    let want_two_sum = map_pixels(&image, |_, p| p.map(|v| (0.5 * (v + v)).powi(2)));
    let want_shifted = map_pixels(&image, |i, _| {
        let (x, y) = (i % w, i / w);
        image.pixels[y * w + x.saturating_sub(1)].map(f64::from)
    });
    let want_one_sum = map_pixels(&image, |_, p| p.map(|v| v + 0.25));
    let want_flipped = map_pixels(&image, |i, _| {
        let (x, y) = (i % w, i / w);
        image.pixels[(h - 1 - y) * w + (w - 1 - x)].map(f64::from)
    });
    // f32 sums and products of chart values (up to ~16): a few ulps.
    let bound = |_: usize, _: usize| 4e-6;
    common::assert_within("two.sum", &out[0], &want_two_sum, bound);
    assert_eq!(out[1], want_shifted, "two.shifted");
    common::assert_within("one.sum", &out[2], &want_one_sum, bound);
    assert_eq!(out[3], want_flipped, "one.shifted");
}

/// A declared kind's WGSL runs with the runtime bounds checks wgpu compiles into every
/// shader (naga's `Restrict` policy for arrays, and for image loads where the driver has
/// no robust image access of its own): a table indexed far past its end and before its
/// start, an input read a million pixels outside the image (directly, not through the
/// clamping `load_<input>`) and a store far outside the output neither crash the device
/// nor read or write outside their memory. Each index is clamped to the table's last
/// element (4.0, where memory past the table would hold anything); the far read gives
/// zero (robust image access) or the clamped edge texel, and the stray store is dropped
/// (every pixel is what `node` returned).
#[test]
fn out_of_bounds_indices_in_a_declared_kind_stay_in_bounds() {
    let kinds = r#"        (
            name: "Peek",
            inputs: [(name: "color")],
            outputs: [(name: "color")],
            code: r"
fn node(pixel: vec2u, size: vec2u) -> vec4f {
    var table = array<f32, 4>(1.0, 2.0, 3.0, 4.0);
    let past = table[pixel.x * 1000u + pixel.y + 4u];
    let before = table[i32(pixel.y) - 1000000];
    let far = textureLoad(color, vec2i(pixel) + vec2i(1000000, -1000000), 0);
    textureStore(out_color, vec2i(-5, 1000000) - vec2i(pixel), vec4f(99.0));
    return vec4f(past, before, far.x, far.w);
}
",
        ),"#;
    let dir = tempfile::tempdir().unwrap();
    let chart = repo(CHART).display().to_string();
    let body = format!(
        r#"    nodes: [
        (id: "in", kind: "ImageInput", params: {{"path": "{chart}"}}),
        (id: "peek", kind: "Peek"),
    ],
    edges: [(from: "in.color", to: "peek.color")],"#
    );
    let path = write(dir.path(), "g.ron", &graph_text(kinds, &body));
    let Some(out) = run(&path, &["peek.color"]) else {
        return;
    };
    let image = image_io::load(&repo(CHART)).unwrap();
    assert_eq!(out[0].pixels.len(), image.pixels.len());
    // Restrict clamps (x + 1e6, y - 1e6) to the top right texel.
    let edge = image.pixels[image.width as usize - 1];
    let allowed = [[0.0, 0.0], [0.0, 1.0], [edge[0], edge[3]]];
    let mut far_kinds = std::collections::BTreeSet::new();
    for (i, p) in out[0].pixels.iter().enumerate() {
        assert_eq!(
            [p[0], p[1]],
            [4.0, 4.0],
            "pixel {i}: a table read out of bounds"
        );
        let far = [p[2], p[3]];
        let k = allowed.iter().position(|a| *a == far);
        assert!(
            k.is_some(),
            "pixel {i}: far read gave {far:?}, not one of {allowed:?}"
        );
        far_kinds.extend(k);
    }
    eprintln!("far reads gave {far_kinds:?} of {allowed:?}");
}

#[test]
fn the_shipped_example_renders() {
    if common::gpu().is_none() {
        return;
    }
    let out = tempfile::tempdir().unwrap();
    let (ok, stdout, stderr) = lumagraph(&[
        "render",
        "graphs/custom_kinds.ron",
        "--out",
        out.path().to_str().unwrap(),
    ]);
    assert!(ok, "{stdout}\n{stderr}");
    let png = image_io::load(&out.path().join("custom_kinds.png")).unwrap();
    assert_eq!((png.width, png.height), (1024, 512));
    // `lumagraph nodes --graph` lists the declared kinds with the built-in ones.
    let (ok, stdout, stderr) = lumagraph(&["nodes", "--graph", "graphs/custom_kinds.ron"]);
    assert!(ok, "{stderr}");
    assert!(
        stdout.contains("Posterize") && stdout.contains("Duotone"),
        "{stdout}"
    );
}

/// Runs `validate` on a graph that must fail and returns its one-line error.
fn refused(path: &Path) -> String {
    let (ok, stdout, stderr) = lumagraph(&["validate", path.to_str().unwrap()]);
    assert!(!ok, "should fail:\n{stdout}\n{stderr}");
    assert!(!stderr.contains("panicked"), "panic:\n{stderr}");
    assert!(stderr.contains("error: "), "{stderr}");
    stderr
}

#[test]
fn bad_wgsl_in_a_file_is_located_in_that_file() {
    let dir = tempfile::tempdir().unwrap();
    // Line 4, column 12: a vec3f returned where a vec4f belongs.
    write(
        dir.path(),
        "bad.wgsl",
        "// a broken function\nfn node(pixel: vec2u, size: vec2u) -> vec4f {\n    let c = load_color(vec2i(pixel));\n    return c.rgb;\n}\n",
    );
    let kinds = r#"        (
            name: "Broken",
            inputs: [(name: "color")],
            outputs: [(name: "color")],
            wgsl: "bad.wgsl",
        ),"#;
    let body = r#"    nodes: [(id: "in", kind: "ImageInput", params: {"path": "x.exr"}), (id: "b", kind: "Broken")],
    edges: [(from: "in.color", to: "b.color")],"#;
    let path = write(dir.path(), "g.ron", &graph_text(kinds, body));
    let e = refused(&path);
    assert!(e.contains("bad.wgsl:4:"), "{e}");
    assert!(e.contains("kind \"Broken\" (used by node b)"), "{e}");

    // A syntax error, in a function written in the graph file (a raw string: the file's
    // own line and column).
    let kinds = "        (\n            name: \"Typo\",\n            inputs: [(name: \"color\")],\n            outputs: [(name: \"color\")],\n            code: r\"\nfn node(pixel: vec2u, size: vec2u) -> vec4f {\n    return load_color(vec2i(pixel)) +;\n}\n\",\n        ),";
    let body = r#"    nodes: [(id: "in", kind: "ImageInput", params: {"path": "x.exr"}), (id: "t", kind: "Typo")],
    edges: [(from: "in.color", to: "t.color")],"#;
    let text = graph_text(kinds, body);
    let line = text.lines().position(|l| l.contains("+;")).unwrap() + 1;
    let path = write(dir.path(), "typo.ron", &text);
    let e = refused(&path);
    assert!(e.contains(&format!("typo.ron:{line}:")), "line {line}: {e}");
}

#[test]
fn bad_declarations_are_refused_at_the_kind() {
    let dir = tempfile::tempdir().unwrap();
    let cases: [(&str, &str); 7] = [
        (
            r#"(name: "A", outputs: [(name: "color", type: "rainbow")], code: "")"#,
            "unknown port type \"rainbow\"",
        ),
        (
            r#"(name: "A", outputs: [(name: "Color")], code: "")"#,
            "output name \"Color\" must be a lower-case identifier",
        ),
        (r#"(name: "A", outputs: [(name: "color")])"#, "one of them"),
        (
            r#"(name: "A", outputs: [], code: "")"#,
            "at least one output",
        ),
        (
            r#"(name: "A", outputs: [(name: "c")], params: [(name: "x", type: Float(default: 5.0, min: 0.0, max: 1.0))], code: "")"#,
            "default 5 is not in [0, 1]",
        ),
        (
            r#"(name: "Exposure", outputs: [(name: "color")], code: "fn node(pixel: vec2u, size: vec2u) -> vec4f { return vec4f(0.0); }")"#,
            "already registered",
        ),
        (
            r#"(name: "A", outputs: [(name: "c")], wgsl: "missing.wgsl")"#,
            "cannot read",
        ),
    ];
    for (i, (kind, expected)) in cases.into_iter().enumerate() {
        let text = graph_text(&format!("        {kind},"), "    nodes: [],");
        let path = write(dir.path(), &format!("case{i}.ron"), &text);
        let e = refused(&path);
        assert!(e.contains(expected), "case {i}: want {expected:?} in {e}");
        assert!(
            e.contains(&format!("case{i}.ron:4:")),
            "case {i}: located at the kind: {e}"
        );
    }
}

#[test]
fn versions() {
    // Version 1 files load as they are (every shipped graph but one is version 1, and is
    // written back as version 1); kinds need version 2; a newer version is refused.
    let v1 = std::fs::read_to_string(repo("graphs/post_tonemap.ron")).unwrap();
    let g = Graph::from_ron(&v1).unwrap();
    assert!(g.to_ron().contains("version: 1,"));
    let newer = lumagraph::graph::VERSION + 1;
    let e = Graph::from_ron(&v1.replace("version: 1", &format!("version: {newer}")))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains(&format!("version {newer}")) && e.contains("newer"),
        "{e}"
    );
    let with_kinds = graph_text(MY_EXPOSURE, "    nodes: [],").replace("version: 2", "version: 1");
    let e = Graph::from_ron(&with_kinds).unwrap_err().to_string();
    assert!(e.contains("version: 2"), "{e}");
    // A graph with kinds round-trips, as version 2.
    let shipped = Graph::load(&repo("graphs/custom_kinds.ron")).unwrap();
    let text = shipped.to_ron();
    assert!(text.contains("version: 2,"));
    let again = Graph::from_ron(&text).unwrap();
    assert_eq!(again, shipped);
    assert_eq!(again.kinds[1].code, shipped.kinds[1].code);
    let _ = ParamValue::Int(0);
}
