//! EXR round trip: every layer of every valid flat file of the OpenEXR project's sample
//! images (`../shared/assets/openexr-images`, or `LUMAGRAPH_OPENEXR_IMAGES`) read by
//! `ImageInput` and written back by `Output` (`data_window: source`, `type: source`), and
//! files of up to five layers whole through `MultiLayerOutput`, re-read and held to
//! `tests/exr/openexr_reference.json` (what OpenEXR's own reader reads of the sources):
//!
//! - the same part name and view, display window, channel names and types;
//! - the same data window, or the data window cut to the display window where the source
//!   has overscan (which `ImageInput` crops when it reads);
//! - the same values, bit for bit (each channel's SHA-256 against the reference's), where
//!   they are not converted; converted colour (other primaries than Rec. 709) and
//!   luminance/chroma images (written as `R G B`) as lumagraph's reader gives them,
//!   rounded to the type written.
//!
//! With `LUMAGRAPH_ROUND_TRIP_OUT` set the files written and a manifest stay in that
//! folder, for `scripts/exr/round_trip.py` to check through OpenEXR's own reader. Without
//! the images the test fails where `CI` is set and says so elsewhere.

mod checks;
#[path = "../common/mod.rs"]
mod common;

use std::path::{Path, PathBuf};

use lumagraph::footage::exr::{self, Layer, Selection, Want};
use lumagraph::graph::{Edge, Graph, Node, ParamValue};
use lumagraph::pathtrace::library::compile;
use lumagraph::render::Resources;
use serde_json::{Value, json};

use checks::{Kind, check_part, expect, selection_of};

fn images() -> Option<PathBuf> {
    lumagraph::footage::testing::openexr_images(&common::repo("../shared/assets/openexr-images"))
}

/// Runs `graph` (its files relative to `out`), returning the first line of an error.
fn run(graph: &Graph, out: &Path) -> Result<(), String> {
    let ctx = common::gpu().ok_or("no GPU")?;
    let plan = compile(graph, &[], None).map_err(|e| e.to_string())?;
    let resources = Resources {
        out_dir: out.to_owned(),
        ..Resources::default()
    };
    let mut exec = lumagraph::pathtrace::library::executor(ctx, plan, &resources)
        .map_err(|e| e.to_string())?;
    exec.run_frame().map(|_| ()).map_err(|e| e.to_string())
}

fn input(id: &str, path: &Path, selection: &Selection) -> Node {
    Node::new(id, "ImageInput")
        .with("path", ParamValue::Str(path.to_string_lossy().into_owned()))
        .with("layer", ParamValue::Str(selection.layer.clone()))
        .with("view", ParamValue::Str(selection.view.clone()))
}

fn text(s: &str) -> ParamValue {
    ParamValue::Str(s.to_owned())
}

/// Where the files written go: `LUMAGRAPH_ROUND_TRIP_OUT`, or a temporary folder.
fn out_dir() -> (PathBuf, Option<tempfile::TempDir>) {
    match std::env::var_os("LUMAGRAPH_ROUND_TRIP_OUT") {
        Some(dir) => {
            let dir = PathBuf::from(dir);
            std::fs::create_dir_all(&dir).unwrap();
            (dir, None)
        }
        None => {
            let tmp = tempfile::tempdir().unwrap();
            (tmp.path().to_owned(), Some(tmp))
        }
    }
}

/// One layer through `ImageInput` → `Output` into `out/name`.
fn through_output(
    src: &Path,
    layer: &Layer,
    selection: &Selection,
    out: &Path,
    name: &str,
) -> Result<(), String> {
    let port = Want::of(layer.kind).port();
    let graph = Graph {
        nodes: vec![
            input("in", src, selection),
            Node::new("out", "Output")
                .with("path", text(name))
                .with("type", text("source"))
                .with("data_window", text("source")),
        ],
        edges: vec![Edge::new(format!("in.{port}"), "out.color")],
        ..Graph::default()
    };
    run(&graph, out)
}

/// Up to five layers through one `ImageInput` each → `MultiLayerOutput` into `out/name`,
/// one part a layer where they come from several parts.
fn through_multi_layer_output(
    src: &Path,
    layers: &[(&Layer, &Selection)],
    out: &Path,
    name: &str,
) -> Result<(), String> {
    let per_layer = layers.iter().any(|(l, _)| l.part != layers[0].0.part);
    let mut sink = Node::new("out", "MultiLayerOutput")
        .with("path", text(name))
        .with("compression", text("zips"))
        .with("data_window", text("source"))
        .with(
            "parts",
            text(if per_layer { "per_layer" } else { "single" }),
        )
        .with("color_type", text("source"));
    let mut graph = Graph::default();
    for (i, (layer, selection)) in layers.iter().enumerate() {
        let id = format!("in{i}");
        let port = if i == 0 {
            "color".to_owned()
        } else {
            sink = sink.with(&format!("layer{i}_type"), text("source"));
            format!("layer{i}")
        };
        graph.nodes.push(input(&id, src, selection));
        let from = Want::of(layer.kind).port();
        graph
            .edges
            .push(Edge::new(format!("{id}.{from}"), format!("out.{port}")));
    }
    graph.nodes.push(sink);
    run(&graph, out)
}

/// Counts of what the round trips held.
#[derive(Debug, Default)]
struct Counts {
    files: usize,
    deep: usize,
    layers: usize,
    identical: usize,
    cropped: usize,
    converted: usize,
    reconstructed: usize,
    whole_files: usize,
    whole_identical: usize,
}

impl Counts {
    fn add(&mut self, kind: Kind) {
        match kind {
            Kind::Identical => self.identical += 1,
            Kind::Cropped => self.cropped += 1,
            Kind::Converted => self.converted += 1,
            Kind::Reconstructed => self.reconstructed += 1,
        }
    }
}

/// Every layer of the file `name` through `Output`, and up to five of them through
/// `MultiLayerOutput`; what was written goes into `manifest`.
fn round_trip_file(
    root: &Path,
    name: &str,
    reference: &Value,
    out: &Path,
    counts: &mut Counts,
    manifest: &mut Vec<Value>,
) -> Result<(), String> {
    let src = root.join(name);
    let info = exr::inspect(&src).map_err(|e| e.to_string())?;
    let all = info.layers();
    let layers: Vec<(Layer, Selection)> = all
        .iter()
        .map(|l| {
            selection_of(&info, l)
                .map(|s| (l.clone(), s))
                .ok_or_else(|| format!("no name finds layer {:?}", l.name))
        })
        .collect::<Result<_, _>>()?;
    let stem = name.replace(['/', '.'], "_");
    // Frames 2 and 3 of the Beachball sequence have frame 1's ten parts: their layers go
    // through Output one by one only with LUMAGRAPH_ROUND_TRIP_ALL set (8 s more).
    let each = std::env::var_os("LUMAGRAPH_ROUND_TRIP_ALL").is_some()
        || !name.starts_with("Beachball/multipart.000")
        || name.ends_with("0001.exr");
    for (i, (layer, selection)) in layers.iter().enumerate().filter(|_| each) {
        let file = format!("{stem}.layer{i}.exr");
        let written = out.join(&file);
        through_output(&src, layer, selection, out, &file)
            .map_err(|e| format!("layer {:?}: {e}", layer.name))?;
        let back = exr::inspect(&written).map_err(|e| e.to_string())?;
        let kinds = check_part(
            (&src, &info, reference),
            (&written, &back, 0),
            &[(layer, selection)],
        )?;
        counts.layers += 1;
        counts.add(kinds[0]);
        manifest.push(json!({
            "written": file, "source": name, "node": "Output",
            "parts": [{
                "source_part": layer.part,
                "channels": expect(&info.parts[layer.part], layer).1,
                "kind": format!("{:?}", kinds[0]),
            }],
        }));
    }
    let whole: Vec<(&Layer, &Selection)> = layers.iter().take(5).map(|(l, s)| (l, s)).collect();
    let file = format!("{stem}.whole.exr");
    let written = out.join(&file);
    through_multi_layer_output(&src, &whole, out, &file)?;
    let back = exr::inspect(&written).map_err(|e| e.to_string())?;
    let per_layer = whole.iter().any(|(l, _)| l.part != whole[0].0.part);
    let groups: Vec<Vec<(&Layer, &Selection)>> = if per_layer {
        whole.iter().map(|l| vec![*l]).collect()
    } else {
        vec![whole.clone()]
    };
    if back.parts.len() != groups.len() {
        return Err(format!(
            "{} parts written, {} expected",
            back.parts.len(),
            groups.len()
        ));
    }
    let mut kinds = Vec::new();
    let mut parts = Vec::new();
    for (b, group) in groups.iter().enumerate() {
        let part_kinds = check_part((&src, &info, reference), (&written, &back, b), group)?;
        let mut channels = Vec::new();
        for (l, _) in group {
            channels.extend(expect(&info.parts[l.part], l).1);
        }
        let kind = part_kinds
            .iter()
            .find(|k| **k != Kind::Identical)
            .unwrap_or(&Kind::Identical);
        parts.push(json!({
            "source_part": group[0].0.part,
            "channels": channels,
            "kind": format!("{kind:?}"),
        }));
        kinds.extend(part_kinds);
    }
    counts.whole_files += 1;
    let identical = kinds.iter().all(|k| *k == Kind::Identical);
    if identical && whole.len() == layers.len() {
        counts.whole_identical += 1;
    }
    manifest.push(json!({
        "written": file, "source": name, "node": "MultiLayerOutput", "parts": parts,
    }));
    Ok(())
}

#[test]
fn sample_files_come_back_as_they_were_read() {
    let Some(root) = images() else { return };
    if common::gpu().is_none() {
        return;
    }
    let start = std::time::Instant::now();
    let text = std::fs::read_to_string(common::repo("tests/exr/openexr_reference.json")).unwrap();
    let reference: Value = serde_json::from_str(&text).unwrap();
    let (out, _keep) = out_dir();
    let mut counts = Counts::default();
    let mut manifest = Vec::new();
    let mut wrong = Vec::new();
    for (name, want) in reference["files"].as_object().unwrap() {
        let deep = want["parts"]
            .as_array()
            .unwrap()
            .iter()
            .any(|p| p["type"].as_str().unwrap().starts_with("deep"));
        if deep {
            counts.deep += 1;
            continue;
        }
        counts.files += 1;
        if let Err(e) = round_trip_file(&root, name, want, &out, &mut counts, &mut manifest) {
            wrong.push(format!("{name}: {e}"));
        }
    }
    std::fs::write(
        out.join("manifest.json"),
        serde_json::to_string_pretty(&json!({"images": root, "files": manifest})).unwrap(),
    )
    .unwrap();
    println!(
        "EXR round trip over {} flat files ({} deep skipped), {:.1} s: {} layers through \
         Output: {} bit-identical, {} identical inside the display window (overscan \
         cropped when read), {} converted to Rec. 709, {} luminance/chroma written as RGB; \
         {} files (up to five layers) through MultiLayerOutput, {} of them whole and \
         bit-identical; {} wrong",
        counts.files,
        counts.deep,
        start.elapsed().as_secs_f64(),
        counts.layers,
        counts.identical,
        counts.cropped,
        counts.converted,
        counts.reconstructed,
        counts.whole_files,
        counts.whole_identical,
        wrong.len()
    );
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}

/// Through a node that changes the pixels (Exposure, +1 stop), `Output` still finds the
/// file its input was read from (the first input of each node upstream): the display
/// window and `pixelAspectRatio` 1.5 of `DisplayWindow/t15.exr` are written, the data
/// window is the bounding box of what is not black (`auto`), and the values are the
/// doubled source as halves.
#[test]
fn a_node_between_passes_the_source_on_and_auto_crops() {
    let Some(root) = images() else { return };
    if common::gpu().is_none() {
        return;
    }
    let src = root.join("DisplayWindow/t15.exr");
    let dir = tempfile::tempdir().unwrap();
    let graph = Graph {
        nodes: vec![
            input("in", &src, &Selection::default()),
            Node::new("grade", "Exposure").with("ev", ParamValue::Float(1.0)),
            Node::new("out", "Output")
                .with("path", text("t15.exr"))
                .with("type", text("half"))
                .with("data_window", text("auto")),
        ],
        edges: vec![
            Edge::new("in.color", "grade.color"),
            Edge::new("grade.color", "out.color"),
        ],
        ..Graph::default()
    };
    run(&graph, dir.path()).unwrap();
    let out = dir.path().join("t15.exr");
    let (a, b) = (exr::inspect(&src).unwrap(), exr::inspect(&out).unwrap());
    let (a, b) = (&a.parts[0], &b.parts[0]);
    assert_eq!(b.display_window, a.display_window);
    assert!(a.data_window.contains(&b.data_window), "{}", b.data_window);
    assert!(b.data_window.width() > 300, "{}", b.data_window);
    let names: Vec<&str> = b.channels.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, ["B", "G", "R"]);
    let aspect = |p: &exr::Part| {
        p.attributes
            .iter()
            .find(|(k, _)| k == "pixelAspectRatio")
            .map(|(_, v)| v.clone())
    };
    assert_eq!(aspect(b).as_deref(), Some("1.5"));
    let want = exr::read_layer(&src, &Selection::default(), Want::Rgba).unwrap();
    let got = exr::read_layer(&out, &Selection::default(), Want::Rgba).unwrap();
    let mut differ = 0;
    for (i, (g, w)) in got.pixels.iter().zip(&want.pixels).enumerate() {
        let w = exr::half_to_f32(exr::f32_to_half(w * 2.0));
        if i % 4 != 3 && g.to_bits() != w.to_bits() && !(g.is_nan() && w.is_nan()) {
            differ += 1;
        }
    }
    assert_eq!(differ, 0);
}
