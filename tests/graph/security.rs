//! What a graph file from someone else can do (docs/security.md). It writes only inside
//! `--out`: an Output path that is absolute, climbs out with `..` or leaves through a
//! symbolic link is refused before anything is rendered, with one error naming the node,
//! the path and the folder, and nothing is written anywhere; `--allow-outputs-outside`
//! lets it. `render`, `merge` of partial renders and `merge` of tile sets alike. The
//! files it names are read only when they are regular files (a device would be read
//! without end).
//!
//! Each test renders into a folder a few levels inside a temporary parent, so that an
//! escaping path lands inside the parent and the test can see it.

use crate::common;

use std::path::{Path, PathBuf};

/// A graph reading the test chart, tone mapping it and writing it to each `(node, path)`.
fn chart_graph(dir: &Path, outputs: &[(&str, &str)]) -> PathBuf {
    let chart = common::repo("assets/test_chart.exr");
    let mut nodes = format!(
        "        (id: \"input\", kind: \"ImageInput\", params: {{\"path\": {:?}}}),\n        \
         (id: \"tonemap\", kind: \"Tonemap\"),\n",
        chart.display().to_string()
    );
    let mut edges = String::from("        (from: \"input.color\", to: \"tonemap.color\"),\n");
    for (id, path) in outputs {
        nodes +=
            &format!("        (id: {id:?}, kind: \"Output\", params: {{\"path\": {path:?}}}),\n");
        edges += &format!("        (from: \"tonemap.color\", to: \"{id}.color\"),\n");
    }
    let path = dir.join("graph.ron");
    std::fs::write(
        &path,
        format!(
            "(\n    version: 1,\n    nodes: [\n{nodes}    ],\n    edges: [\n{edges}    ],\n)\n"
        ),
    )
    .unwrap();
    path
}

/// Every file and folder under `dir`, relative to it, sorted.
fn tree(dir: &Path) -> Vec<String> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_owned()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            out.push(p.strip_prefix(dir).unwrap().display().to_string());
            if p.is_dir() && !p.is_symlink() {
                stack.push(p);
            }
        }
    }
    out.sort();
    out
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The failure is clean: a non-zero exit, `error:` lines, no panic; returns stderr.
fn fails(args: &[&str]) -> String {
    let (ok, stdout, stderr) = common::cli(args);
    assert!(!ok, "should fail:\n{stdout}\n{stderr}");
    assert!(
        stderr.contains("error: ") && !stderr.contains("panicked"),
        "{stderr}"
    );
    stderr
}

/// `error:` naming `node`, `path` and `folder`.
fn assert_refused(stderr: &str, node: &str, path: &str, folder: &Path) {
    let want = format!(
        "node \"{node}\": output path \"{path}\" is outside the output folder {}",
        folder.display()
    );
    assert!(stderr.contains(&want), "no `{want}` in:\n{stderr}");
}

/// The two paths of the issue: an absolute one and one that climbs out with `..`. Both
/// refused (no GPU needed: before the device is opened), nothing written; the flag writes
/// them where they say.
#[test]
fn escaping_output_paths_are_refused_unless_allowed() {
    let parent = tempfile::tempdir().unwrap();
    let p = parent.path();
    let graphs = tempfile::tempdir().unwrap();
    let out = p.join("work/outdir");
    let absolute = p.join("elsewhere.exr");
    let climbing = "../../tmp/x/evil.png";
    let g = chart_graph(
        graphs.path(),
        &[
            ("fine", "fine.png"),
            ("absolute", s(&absolute)),
            ("climbing", climbing),
        ],
    );
    let stderr = fails(&["render", s(&g), "--out", s(&out)]);
    assert_refused(&stderr, "absolute", s(&absolute), &out);
    assert_refused(&stderr, "climbing", climbing, &out);
    assert!(stderr.contains("it is absolute") && stderr.contains("climb out"));
    // Located at the param in the graph file.
    assert!(stderr.contains(&format!("{}:", g.display())), "{stderr}");
    assert!(!stderr.contains("node \"fine\""), "{stderr}");
    assert!(tree(p).is_empty(), "written: {:?}", tree(p));

    if common::gpu().is_none() {
        return;
    }
    let (ok, stdout, stderr) =
        common::cli(&["render", s(&g), "--out", s(&out), "--allow-outputs-outside"]);
    assert!(ok, "{stdout}\n{stderr}");
    for f in [out.join("fine.png"), absolute, p.join("tmp/x/evil.png")] {
        assert!(f.is_file(), "{} not written:\n{stdout}", f.display());
    }
}

/// A folder inside `--out` that is a symbolic link out of it is refused like `..`.
#[cfg(unix)]
#[test]
fn an_output_through_a_link_out_of_the_folder_is_refused() {
    let parent = tempfile::tempdir().unwrap();
    let p = parent.path();
    let out = p.join("out");
    let elsewhere = p.join("elsewhere");
    std::fs::create_dir_all(&out).unwrap();
    std::fs::create_dir_all(&elsewhere).unwrap();
    std::os::unix::fs::symlink(&elsewhere, out.join("link")).unwrap();
    let graphs = tempfile::tempdir().unwrap();
    let g = chart_graph(graphs.path(), &[("linked", "link/sub/x.png")]);
    let stderr = fails(&["render", s(&g), "--out", s(&out)]);
    assert_refused(&stderr, "linked", "link/sub/x.png", &out);
    assert!(stderr.contains("through a symbolic link"), "{stderr}");
    assert_eq!(tree(p), ["elsewhere", "out", "out/link"]);
}

/// `merge` writes the graph's outputs too: the partial renders and the tile sets name a
/// graph (or carry its paths) that may come from someone else, so their escaping paths
/// are refused the same way, and the flag lets them.
#[test]
fn merges_refuse_escaping_paths_unless_allowed() {
    if common::gpu().is_none() {
        return;
    }
    let parent = tempfile::tempdir().unwrap();
    let p = parent.path();
    let work = p.join("work");
    std::fs::create_dir_all(&work).unwrap();
    let scene = work.join("tiny.ron");
    let text = std::fs::read_to_string(common::repo("assets/cornell.ron"))
        .unwrap()
        .replace(
            "width: 256, height: 256, max_bounces: 20, spp: 256",
            "width: 16, height: 16, max_bounces: 2, spp: 4",
        );
    assert!(
        text.contains("width: 16"),
        "assets/cornell.ron changed its render line"
    );
    std::fs::write(&scene, text).unwrap();
    let graph = work.join("escaping.ron");
    std::fs::write(
        &graph,
        r#"(
    version: 1,
    nodes: [
        (id: "pathtrace", kind: "PathTrace"),
        (id: "accumulate", kind: "Accumulate"),
        (id: "escaping", kind: "Output", params: {"path": "../merged.exr"}),
    ],
    edges: [
        (from: "pathtrace.color", to: "accumulate.color"),
        (from: "accumulate.color", to: "escaping.color"),
    ],
)"#,
    )
    .unwrap();
    let parts = work.join("parts");
    let base = [
        "render",
        s(&graph),
        "--scene",
        s(&scene),
        "--out",
        s(&parts),
    ];
    let allow = "--allow-outputs-outside";
    // The partial render itself is refused without the flag: the graph would write there.
    let stderr = fails(&[&base[..], &["--samples", "0..4"]].concat());
    assert_refused(&stderr, "escaping", "../merged.exr", &parts);
    for extra in [
        &["--samples", "0..4", allow][..],
        &["--tile", "8", "--tiles", "0..4", allow],
    ] {
        let (ok, stdout, stderr) = common::cli(&[&base[..], extra].concat());
        assert!(ok, "{stdout}\n{stderr}");
    }
    let before = tree(p);
    for file in ["samples-0-4.partial", "tiles-0-4.tiles"] {
        let merged = work.join("merged");
        let input = parts.join(file);
        let stderr = fails(&["merge", s(&input), "--out", s(&merged)]);
        assert_refused(&stderr, "escaping", "../merged.exr", &merged);
        assert_eq!(tree(p), before, "{file}: something was written");
        let (ok, stdout, stderr) = common::cli(&["merge", s(&input), "--out", s(&merged), allow]);
        assert!(ok, "{stdout}\n{stderr}");
        let written = work.join("merged.exr");
        assert!(written.is_file(), "{file}: {stdout}");
        std::fs::remove_file(written).unwrap();
        let _ = std::fs::remove_dir_all(&merged);
    }
}

/// A device named where a graph names a file (a declared kind's `.wgsl`, a group file, a
/// LUT) is refused at once, not read without end.
#[cfg(unix)]
#[test]
fn a_device_named_as_a_file_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let wgsl = dir.path().join("wgsl.ron");
    std::fs::write(
        &wgsl,
        r#"(
    version: 2,
    kinds: [(name: "Z", inputs: [(name: "color")], outputs: [(name: "color")], wgsl: "/dev/zero")],
    nodes: [],
)"#,
    )
    .unwrap();
    let group = dir.path().join("group.ron");
    std::fs::write(
        &group,
        r#"(version: 3, groups: [(name: "Z", file: "/dev/zero")], nodes: [])"#,
    )
    .unwrap();
    for g in [&wgsl, &group] {
        let stderr = fails(&["validate", s(g)]);
        assert!(
            stderr.contains("/dev/zero") && stderr.contains("not a regular file"),
            "{stderr}"
        );
    }
    if common::gpu().is_none() {
        return;
    }
    let graph = dir.path().join("lut.ron");
    let chart = common::repo("assets/test_chart.exr");
    std::fs::write(
        &graph,
        format!(
            r#"(
    version: 1,
    nodes: [
        (id: "input", kind: "ImageInput", params: {{"path": {:?}}}),
        (id: "lut", kind: "LUT", params: {{"path": "/dev/zero"}}),
        (id: "out", kind: "Output", params: {{"path": "x.exr"}}),
    ],
    edges: [(from: "input.color", to: "lut.color"), (from: "lut.color", to: "out.color")],
)"#,
            chart.display().to_string()
        ),
    )
    .unwrap();
    let out = dir.path().join("out");
    let stderr = fails(&["render", s(&graph), "--out", s(&out)]);
    assert!(
        stderr.contains("node \"lut\"") && stderr.contains("not a regular file"),
        "{stderr}"
    );
}
