//! A graph in ACEScg (`working_space: "ACEScg"`): files are read into ACEScg, nodes whose
//! maths is Rec. 709's get their colour converted around them, and what a display shows
//! is the Rec. 709 graph's. Tolerances: OpenColorIO's matrices on the GPU in f32, there
//! and back, 1e-5 relative on linear values (measured 1.1e-7); display outputs within one
//! 8-bit code (a value at half a code may round either way; measured 0).

use lumagraph::color::ColorConfig;
use lumagraph::graph::{Edge, Graph, Node, ParamValue, WorkingSpace};
use lumagraph::render::cpu::Image;

use crate::common;

/// The test chart → `Tonemap` (AgX), and → `DisplayView` (the CG config's default view):
/// the chart as read, and both display outputs.
fn run(space: WorkingSpace) -> Option<Vec<Image>> {
    let graph = Graph {
        nodes: vec![
            Node::new("input", "ImageInput")
                .with("path", ParamValue::Str("assets/test_chart.exr".into())),
            Node::new("tonemap", "Tonemap").with("operator", ParamValue::Str("agx".into())),
            Node::new("view", "DisplayView"),
        ],
        edges: vec![
            Edge::new("input.color", "tonemap.color"),
            Edge::new("input.color", "view.color"),
        ],
        working_space: space,
        ..Graph::default()
    };
    let dir = tempfile::tempdir().unwrap();
    common::run_graph(
        &graph,
        &["input.color", "tonemap.color", "view.color"],
        dir.path(),
    )
}

fn worst_code(a: &Image, b: &Image) -> i32 {
    a.pixels
        .iter()
        .zip(&b.pixels)
        .flat_map(|(p, q)| {
            (0..3).map(move |c| {
                ((p[c].clamp(0.0, 1.0) * 255.0).round() - (q[c].clamp(0.0, 1.0) * 255.0).round())
                    .abs() as i32
            })
        })
        .max()
        .unwrap_or(0)
}

#[test]
fn an_acescg_graph_reads_into_acescg_and_displays_as_rec709_does() {
    let (Some(rec709), Some(aces)) = (run(WorkingSpace::Rec709), run(WorkingSpace::AcesCg)) else {
        return;
    };
    // Read into ACEScg: the Rec. 709 values through OpenColorIO's CPU processor.
    let config = ColorConfig::load(
        "ocio://cg-config-v4.0.0_aces-v2.0_ocio-v2.5",
        &common::root(),
    )
    .unwrap();
    let to_aces = config.processor("Linear Rec.709 (sRGB)", "ACEScg").unwrap();
    let mut worst = 0.0_f32;
    for (r, a) in rec709[0].pixels.iter().zip(&aces[0].pixels) {
        let want = to_aces.apply_rgb([r[0], r[1], r[2]]);
        for c in 0..3 {
            worst = worst.max((a[c] - want[c]).abs() / want[c].abs().max(1e-3));
        }
        assert_eq!(a[3], r[3]);
    }
    assert!(worst < 1e-5, "read into ACEScg: {worst}");
    // What a display shows does not depend on the working space.
    let tonemap = worst_code(&rec709[1], &aces[1]);
    let view = worst_code(&rec709[2], &aces[2]);
    eprintln!(
        "ACEScg against Rec. 709: read {worst:.1e} relative; Tonemap {tonemap} code(s), DisplayView {view}"
    );
    assert!(
        tonemap <= 1 && view <= 1,
        "Tonemap {tonemap}, DisplayView {view}"
    );
}

/// What an ACEScg graph writes: an EXR tagged with ACEScg's primaries and white, which a
/// Rec. 709 graph reads back as the original (OpenColorIO converts an ACES-tagged file,
/// within 1e-5 of the pixel's largest component; measured in the message), and a PNG of linear colour that is the
/// Rec. 709 graph's PNG (within one code).
#[test]
fn an_acescg_graph_writes_tagged_exr_and_rec709_png() {
    let write = |space: WorkingSpace, dir: &std::path::Path| {
        let graph = Graph {
            nodes: vec![
                Node::new("input", "ImageInput")
                    .with("path", ParamValue::Str("assets/test_chart.exr".into())),
                Node::new("exr", "Output").with("path", ParamValue::Str("chart.exr".into())),
                Node::new("png", "Output").with("path", ParamValue::Str("chart.png".into())),
            ],
            edges: vec![
                Edge::new("input.color", "exr.color"),
                Edge::new("input.color", "png.color"),
            ],
            working_space: space,
            ..Graph::default()
        };
        common::run_graph(&graph, &["input.color"], dir).map(|mut v| v.remove(0))
    };
    let (rec709_dir, aces_dir) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let (Some(original), Some(_)) = (
        write(WorkingSpace::Rec709, rec709_dir.path()),
        write(WorkingSpace::AcesCg, aces_dir.path()),
    ) else {
        return;
    };
    let written = aces_dir.path().join("chart.exr");
    let info = lumagraph::footage::exr::inspect(&written).unwrap();
    assert_eq!(
        info.parts[0].chromaticities.unwrap().to_array(),
        WorkingSpace::AcesCg.chromaticities()
    );
    // Read back in a Rec. 709 graph.
    let graph = Graph {
        nodes: vec![
            Node::new("input", "ImageInput")
                .with("path", ParamValue::Str(written.to_str().unwrap().into())),
        ],
        ..Graph::default()
    };
    let dir = tempfile::tempdir().unwrap();
    let back = common::run_graph(&graph, &["input.color"], dir.path())
        .unwrap()
        .remove(0);
    let mut worst = 0.0_f32;
    for (o, b) in original.pixels.iter().zip(&back.pixels) {
        // Relative to the pixel's largest component: a matrix and its inverse cancel
        // large components into small ones.
        let scale = o[..3].iter().fold(1e-3_f32, |m, v| m.max(v.abs()));
        for c in 0..3 {
            worst = worst.max((o[c] - b[c]).abs() / scale);
        }
    }
    eprintln!("ACEScg EXR read back in Rec. 709: worst {worst:.1e} relative");
    assert!(worst < 1e-5, "{worst}");
    let png = |d: &std::path::Path| image::open(d.join("chart.png")).unwrap().to_rgba8();
    let (a, b) = (png(rec709_dir.path()), png(aces_dir.path()));
    let codes = a
        .pixels()
        .zip(b.pixels())
        .flat_map(|(p, q)| (0..3).map(move |c| (i32::from(p.0[c]) - i32::from(q.0[c])).abs()))
        .max()
        .unwrap();
    assert!(codes <= 1, "PNG: {codes} codes");
}

/// The path tracer in an ACEScg graph: its Rec. 709 colour (what `tests/mitsuba_suite.rs`
/// holds to Mitsuba 3's references) is converted into ACEScg after it and accumulated
/// there; the same Cornell box render (64², 8 frames of 1 spp, the same seed) through
/// `Tonemap` comes out as the Rec. 709 graph's, within one 8-bit code, and the accumulation
/// is OpenColorIO's conversion of the Rec. 709 one (1e-5 of the pixel's largest component).
#[test]
fn the_path_tracer_in_an_acescg_graph_shows_the_rec709_render() {
    if common::gpu().is_none() {
        return;
    }
    let scene = common::gpu_scene("assets/cornell.ron", Some(64));
    let run = |space: WorkingSpace| {
        let mut graph = common::progressive_graph(&[]);
        graph
            .nodes
            .push(Node::new("tm", "Tonemap").with("operator", ParamValue::Str("agx".into())));
        graph.edges.push(Edge::new("acc.color", "tm.color"));
        graph.working_space = space;
        let mut exec = common::executor(&graph, &["acc.color", "tm.color"], &scene).unwrap();
        exec.run_frames(8, true).unwrap();
        (
            exec.read_port("acc.color").unwrap(),
            exec.read_port("tm.color").unwrap(),
        )
    };
    let (rec709, rec709_tm) = run(WorkingSpace::Rec709);
    let (aces, aces_tm) = run(WorkingSpace::AcesCg);
    let config = ColorConfig::load(
        "ocio://cg-config-v4.0.0_aces-v2.0_ocio-v2.5",
        &common::root(),
    )
    .unwrap();
    let to_aces = config.processor("Linear Rec.709 (sRGB)", "ACEScg").unwrap();
    let mut worst = 0.0_f32;
    for (r, a) in rec709.pixels.iter().zip(&aces.pixels) {
        let want = to_aces.apply_rgb([r[0], r[1], r[2]]);
        let scale = want.iter().fold(1e-3_f32, |m, v| m.max(v.abs()));
        for c in 0..3 {
            worst = worst.max((a[c] - want[c]).abs() / scale);
        }
    }
    let codes = worst_code(&rec709_tm, &aces_tm);
    eprintln!("path tracer in ACEScg: accumulation {worst:.1e}, Tonemap {codes} code(s)");
    assert!(worst < 1e-5, "{worst}");
    assert!(codes <= 1, "{codes}");
}
