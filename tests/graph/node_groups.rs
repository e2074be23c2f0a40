//! Node groups: a graph file used as a node. A grouped graph compiles to the plan of its
//! flattened copy and renders the same bits; groups nest, with params passed through and
//! files read relative to the group's own folder; a group that contains itself, an edge to
//! a port the group does not expose, an unknown param and a broken interface are refused
//! with one located error and a non-zero exit, never a panic.

use crate::common;

use std::path::{Path, PathBuf};

use lumagraph::graph::{Graph, Registry};
use lumagraph::pathtrace::library::compile;
use lumagraph::render::Resources;

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    if let Some(parent) = path.parent() {
        std::fs::create_dir_all(parent).unwrap();
    }
    std::fs::write(&path, text).unwrap();
    path
}

use common::cli as lumagraph;

/// `graphs/node_group.ron` written out by hand without its group: the Lens group's nodes
/// named `lens/…`, the group node's `vignette` param on `lens/vignette`.
const FLATTENED: &str = r#"(
    version: 1,
    nodes: [
        (id: "input", kind: "ImageInput", params: {"path": "../assets/hdri/venice_sunset_1k.hdr"}),
        (id: "exposure", kind: "Exposure", params: {"ev": -0.5}),
        (id: "lens/bloom", kind: "Bloom", params: {"intensity": 0.05, "levels": 7}),
        (id: "lens/fringes", kind: "ChromaticAberration", params: {"strength": 0.003}),
        (id: "lens/vignette", kind: "Vignette", params: {"strength": 0.5}),
        (id: "tonemap", kind: "Tonemap", params: {"operator": "agx"}),
        (id: "out", kind: "Output", params: {"path": "node_group.png"}),
    ],
    edges: [
        (from: "input.color", to: "exposure.color"),
        (from: "exposure.color", to: "lens/bloom.color"),
        (from: "lens/bloom.color", to: "lens/fringes.color"),
        (from: "lens/fringes.color", to: "lens/vignette.color"),
        (from: "lens/vignette.color", to: "tonemap.color"),
        (from: "tonemap.color", to: "out.color"),
    ],
)
"#;

/// The flattened copy, saved in `graphs/` (so its relative paths mean the same) under a
/// temporary name.
fn flattened_copy() -> (tempfile::NamedTempFile, Graph) {
    let file = tempfile::Builder::new()
        .prefix(".flattened-")
        .suffix(".ron")
        .tempfile_in(common::repo("graphs"))
        .unwrap();
    std::fs::write(file.path(), FLATTENED).unwrap();
    let graph = Graph::load(file.path()).unwrap();
    (file, graph)
}

#[test]
fn a_grouped_graph_compiles_to_the_plan_of_its_flattened_copy() {
    let grouped = Graph::load(&common::repo("graphs/node_group.ron")).unwrap();
    let (_file, flat) = flattened_copy();
    let a = compile(&grouped, &[], None).unwrap_or_else(|e| panic!("{e}"));
    let b = compile(&flat, &[], None).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(a.to_string(), b.to_string());
    assert_eq!(
        a.aliases,
        [("lens.color".to_owned(), "lens/vignette.color".to_owned())]
    );
    // Texture sharing crosses the boundary: the group's textures share allocations with
    // the outer graph's (6 textures in 3 allocations).
    assert!(a.slots.len() < a.textures.len(), "{a}");
    // A kept group output is its inner output.
    let kept = compile(&grouped, &["lens.color".to_owned()], None).unwrap();
    assert_eq!(
        kept.texture_named("lens.color").unwrap().name,
        "lens/vignette.color"
    );
}

#[test]
fn a_grouped_graph_renders_what_its_flattened_copy_renders() {
    let Some(ctx) = common::gpu() else { return };
    let grouped = Graph::load(&common::repo("graphs/node_group.ron")).unwrap();
    let (_file, flat) = flattened_copy();
    let run = |g: &Graph, port: &str| {
        let plan = compile(g, &[port.to_owned()], None).unwrap();
        let resources = Resources {
            base_dir: g.base_dir(),
            out_dir: tempfile::tempdir().unwrap().keep(),
            ..Resources::default()
        };
        let mut exec = lumagraph::pathtrace::library::executor(ctx, plan, &resources).unwrap();
        exec.run_frame().unwrap();
        exec.read_port(port).unwrap()
    };
    let a = run(&grouped, "lens.color");
    let b = run(&flat, "lens/vignette.color");
    assert_eq!((a.width, a.height), (b.width, b.height));
    assert!(
        a.pixels == b.pixels,
        "the group's output differs from the flattened graph's"
    );
}

/// A group inside a group: the outer group exposes the inner group's param under another
/// name, the inner group reads a file relative to its own folder, and a graph in another
/// folder uses the outer group.
#[test]
fn groups_nest_pass_params_through_and_read_files_beside_themselves() {
    let dir = tempfile::tempdir().unwrap();
    let chart = common::repo("assets/test_chart.exr");
    std::fs::create_dir_all(dir.path().join("lib/inner")).unwrap();
    std::fs::copy(&chart, dir.path().join("lib/inner/chart.exr")).unwrap();
    write(
        dir.path(),
        "lib/inner/source.ron",
        r#"(
    version: 3,
    interface: (
        outputs: [(name: "color", from: "scale.color")],
        params: [(name: "gain", to: ["scale.value"])],
    ),
    nodes: [
        (id: "chart", kind: "ImageInput", params: {"path": "chart.exr"}),
        (id: "scale", kind: "Math", params: {"operation": "multiply", "value": 2.0}),
    ],
    edges: [(from: "chart.color", to: "scale.color")],
)"#,
    );
    write(
        dir.path(),
        "lib/outer.ron",
        r#"(
    version: 3,
    groups: [(name: "Source", file: "inner/source.ron")],
    interface: (
        outputs: [(name: "image", from: "src.color")],
        params: [(name: "brightness", to: ["src.gain"])],
    ),
    nodes: [(id: "src", kind: "Source", params: {"gain": 3.0})],
)"#,
    );
    let main = write(
        dir.path(),
        "work/main.ron",
        r#"(
    version: 3,
    groups: [(name: "Outer", file: "../lib/outer.ron")],
    nodes: [
        (id: "a", kind: "Outer"),
        (id: "b", kind: "Outer", params: {"brightness": 0.5}),
        (id: "out", kind: "Output", params: {"path": "b.exr"}),
    ],
    edges: [(from: "b.image", to: "out.color")],
)"#,
    );
    let graph = Graph::load(&main).unwrap();
    let plan = compile(&graph, &["a.image".to_owned()], None).unwrap_or_else(|e| panic!("{e}"));
    let scale = |node: &str| {
        plan.pass(node)
            .unwrap_or_else(|| panic!("no pass {node} in\n{plan}"))
            .params
            .0["value"]
            .as_f64()
            .unwrap()
    };
    // The outer group's default (3) reaches `a`; `b` sets 0.5 through two interfaces.
    assert!((scale("a/src/scale") - 3.0).abs() < 1e-12);
    assert!((scale("b/src/scale") - 0.5).abs() < 1e-12);
    let Some(ctx) = common::gpu() else { return };
    let resources = Resources {
        base_dir: graph.base_dir(),
        out_dir: dir.path().to_owned(),
        ..Resources::default()
    };
    let mut exec = lumagraph::pathtrace::library::executor(ctx, plan, &resources).unwrap();
    exec.run_frame().unwrap();
    let a = exec.read_port("a.image").unwrap();
    let source = lumagraph::render::image_io::load(&chart).unwrap();
    for (got, want) in a.pixels.iter().zip(&source.pixels).take(64) {
        for c in 0..3 {
            let (g, w) = (got[c], want[c]);
            assert!(
                (g - 3.0 * w).abs() <= 1e-5 * w.abs().max(1.0),
                "{g} vs 3 × {w}"
            );
        }
    }
}

#[test]
fn a_group_that_contains_itself_is_refused_naming_the_files() {
    let dir = tempfile::tempdir().unwrap();
    let group = |other: &str| {
        format!(
            r#"(
    version: 3,
    groups: [(name: "Other", file: "{other}")],
    interface: (outputs: [(name: "color", from: "x.color")]),
    nodes: [(id: "x", kind: "Other")],
)"#
        )
    };
    write(dir.path(), "a.ron", &group("b.ron"));
    write(dir.path(), "b.ron", &group("a.ron"));
    let main = write(
        dir.path(),
        "main.ron",
        r#"(
    version: 3,
    groups: [(name: "A", file: "a.ron")],
    nodes: [(id: "a", kind: "A"), (id: "out", kind: "Output")],
    edges: [(from: "a.color", to: "out.color")],
)"#,
    );
    let (ok, _, stderr) = lumagraph(&["validate", main.to_str().unwrap()]);
    assert!(!ok);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(stderr.contains("contains itself"), "{stderr}");
    let chain = ["main.ron", "a.ron", "b.ron", "a.ron"];
    let positions: Vec<usize> = chain
        .iter()
        .scan(0, |from, f| {
            let at = stderr[*from..].find(f).map(|i| i + *from)?;
            *from = at + f.len();
            Some(at)
        })
        .collect();
    assert_eq!(
        positions.len(),
        chain.len(),
        "the chain of files in order: {stderr}"
    );
    // A group naming its own file.
    write(dir.path(), "self.ron", &group("self.ron"));
    let g = Graph::load(&dir.path().join("self.ron")).unwrap();
    let e = lumagraph::render::custom::registry(&g)
        .unwrap_err()
        .to_string();
    assert!(e.contains("contains itself"), "{e}");
}

/// Each mistake in using or writing a group: (what, group interface, node params, edge
/// from the group, expected message).
#[test]
fn mistakes_with_groups_give_one_located_error() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        (
            "edge from a port the group does not expose",
            r#"outputs: [(name: "color", from: "v.color")]"#,
            "",
            "lens.colour",
            "has no output \"colour\"",
        ),
        (
            "unknown param on the group node",
            r#"outputs: [(name: "color", from: "v.color")]"#,
            r#"params: {"strength": 0.2},"#,
            "lens.color",
            "unknown param \"strength\"",
        ),
        (
            "interface naming a missing node",
            r#"outputs: [(name: "color", from: "nothing.color")]"#,
            "",
            "lens.color",
            "names node \"nothing\"",
        ),
        (
            "interface naming a missing param",
            r#"outputs: [(name: "color", from: "v.color")], params: [(name: "s", to: ["v.strenght"])]"#,
            "",
            "lens.color",
            "has no param \"strenght\"",
        ),
        (
            "a group that shows nothing",
            r#"doc: "nothing out""#,
            "",
            "lens.color",
            "exposes no output",
        ),
    ];
    for (what, interface, params, from, expected) in cases {
        write(
            dir.path(),
            "g.ron",
            &format!(
                r#"(
    version: 3,
    interface: ({interface}),
    nodes: [(id: "v", kind: "Vignette")],
)"#
            ),
        );
        let main = write(
            dir.path(),
            "main.ron",
            &format!(
                r#"(
    version: 3,
    groups: [(name: "Lens", file: "g.ron")],
    nodes: [
        (id: "input", kind: "ImageInput", params: {{"path": "{}"}}),
        (id: "lens", kind: "Lens", {params}),
        (id: "out", kind: "Output"),
    ],
    edges: [(from: "input.color", to: "lens.color"), (from: "{from}", to: "out.color")],
)"#,
                common::repo("assets/test_chart.exr").display()
            ),
        );
        let (ok, _, stderr) = lumagraph(&["validate", main.to_str().unwrap()]);
        assert!(!ok, "{what}: accepted");
        assert!(!stderr.contains("panicked"), "{what}: {stderr}");
        assert!(stderr.contains(expected), "{what}: {stderr}");
        assert!(stderr.contains(".ron:"), "{what}: not located: {stderr}");
    }
}

#[test]
fn group_files_check_on_their_own_and_need_version_3() {
    let (ok, stdout, stderr) = lumagraph(&["validate", "graphs/groups/lens.ron"]);
    assert!(ok, "{stdout}{stderr}");
    assert!(
        stdout.contains("a node group (1 input, 1 output, 3 params, 3 nodes)"),
        "{stdout}"
    );
    let text = std::fs::read_to_string(common::repo("graphs/node_group.ron")).unwrap();
    let e = Graph::from_ron(&text.replace("version: 3", "version: 2")).unwrap_err();
    assert!(e.to_string().contains("need `version: 3`"), "{e}");
    // Saved as version 3, loaded back the same.
    let g = Graph::from_ron(&text).unwrap();
    assert!(g.to_ron().contains("version: 3"));
    assert_eq!(Graph::from_ron(&g.to_ron()).unwrap(), g);
    // The group kind lists in `nodes --graph` with its params' inner ranges.
    let (ok, stdout, _) = lumagraph(&["nodes", "--graph", "graphs/node_group.ron"]);
    assert!(ok);
    assert!(stdout.contains("Lens [Group]"), "{stdout}");
    assert!(
        stdout.contains("param vignette  float  default 0.35 in [0, 1]"),
        "{stdout}"
    );
    // Built-ins do not know it.
    assert!(Registry::with_builtins().get("Lens").is_none());
}
