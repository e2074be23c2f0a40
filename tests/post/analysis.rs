//! Difference and `AutoExposure` against their CPU references, and what they measure.
//!
//! Difference: its reference of another size refused when the graph compiles; the metric within 1e-5 relative of `render::metrics` (f32 per-pixel terms
//! summed per 16×16 tile in f32, the tiles in f64: ~1e-7 relative each); the heat map
//! within 1.5/255 per channel of `nodes::difference::heat` (it is stored in 8 bits and the
//! per-pixel error is f32). `AutoExposure`: the exposure within 1e-3 stops of
//! `cpu::auto_exposure_target` on the same histogram (a pixel on a bin edge may land in the
//! next bin on the GPU: 1/(pixels) of a bin width each), within half a bin width (0.078
//! stops) of the exact answer on a flat image, and the image within 2e-6 relative of
//! input × 2^exposure; adaptation over frames exactly as documented.

use crate::common;

use common::{assert_within, map_pixels, repo};
use lumagraph::graph::{Edge, Graph, Node, ParamValue};
use lumagraph::pathtrace::library::compile;
use lumagraph::render::cpu::{self, Image};
use lumagraph::render::nodes::difference::heat;
use lumagraph::render::{Executor, Resources, image_io, metrics};

const CHART: &str = "assets/test_chart.exr";

/// `ImageInput` nodes of `inputs` (`(port, path)`) → `n` (`kind` with `params`); the executor
/// after one frame, keeping `n.<port>`.
fn run(
    kind: &str,
    params: &[(&str, ParamValue)],
    inputs: &[(&str, &str)],
    port: &str,
) -> Option<(Executor, Image)> {
    let ctx = common::gpu()?;
    let mut node = Node::new("n", kind);
    for (k, v) in params {
        node = node.with(k, v.clone());
    }
    let mut graph = Graph {
        nodes: vec![node],
        edges: Vec::new(),
        ..Graph::default()
    };
    for (to, path) in inputs {
        let id = format!("in_{to}");
        graph
            .nodes
            .push(Node::new(&id, "ImageInput").with("path", ParamValue::Str((*path).into())));
        graph
            .edges
            .push(Edge::new(format!("{id}.color"), format!("n.{to}")));
    }
    let keep = vec![format!("n.{port}")];
    let plan = compile(&graph, &keep, None).unwrap();
    let resources = Resources {
        base_dir: common::root(),
        ..Resources::default()
    };
    let mut exec = lumagraph::pathtrace::library::executor(ctx, plan, &resources).unwrap();
    exec.run_frame().unwrap();
    let image = exec.read_port(&keep[0]).unwrap();
    Some((exec, image))
}

fn measured(exec: &mut Executor, name: &str) -> f64 {
    exec.measurements()
        .unwrap()
        .iter()
        .find(|(_, m)| m.name == name)
        .map(|(_, m)| m.value)
        .unwrap_or_else(|| panic!("nothing measured as {name}"))
}

fn write_exr(dir: &std::path::Path, name: &str, image: &Image) -> String {
    let path = dir.join(name);
    std::fs::write(&path, image_io::encode_exr(image, false).unwrap()).unwrap();
    path.to_str().unwrap().to_owned()
}

#[test]
fn difference_matches_cpu() {
    let chart = image_io::load(&repo(CHART)).unwrap();
    // The reference: the chart with every channel off by a different, smooth amount.
    let reference = map_pixels(&chart, |i, p| {
        let f = 1.0 + 0.3 * ((i % 97) as f64 / 97.0 - 0.5);
        [p[0] * f, p[1] / f, p[2] + 0.05 * f, p[3]]
    });
    let dir = tempfile::tempdir().unwrap();
    let ref_path = write_exr(dir.path(), "reference.exr", &reference);
    for (metric, max_error, decades) in [("relmse", 0.1, 4), ("rmse", 1.0, 3)] {
        let params = [
            ("metric", ParamValue::Str(metric.into())),
            ("max_error", ParamValue::Float(max_error)),
            ("decades", ParamValue::Int(decades)),
        ];
        let Some((mut exec, got)) = run(
            "Difference",
            &params,
            &[("color", CHART), ("reference", &ref_path)],
            "heat",
        ) else {
            return;
        };
        let value = measured(&mut exec, metric);
        let want = if metric == "relmse" {
            metrics::relmse(&chart, &reference)
        } else {
            metrics::rmse(&chart, &reference)
        };
        eprintln!("Difference {metric}: GPU {value:.9e}, CPU {want:.9e}");
        assert!(
            (value - want).abs() <= 1e-5 * want,
            "{metric}: {value} vs {want}"
        );
        let want_heat = map_pixels(&chart, |i, p| {
            let r = reference.pixels[i].map(f64::from);
            let term = |c: usize| {
                let d = (p[c] - r[c]) * (p[c] - r[c]);
                if metric == "relmse" {
                    d / (r[c] * r[c] + 0.01)
                } else {
                    d
                }
            };
            #[expect(clippy::cast_possible_truncation, reason = "f32 as the GPU")]
            let e = ((term(0) + term(1) + term(2)) / 3.0) as f32;
            #[expect(clippy::cast_possible_truncation, reason = "f32 as the GPU")]
            let h = heat(e, max_error as f32, decades as f32);
            [h[0], h[1], h[2], 1.0].map(|v| f64::from(cpu::to_u8(v)) / 255.0)
        });
        assert_within(
            &format!("Difference heat {metric}"),
            &got,
            &want_heat,
            |_, _| 1.5 / 255.0,
        );
    }
}

#[test]
fn difference_against_itself_is_zero() {
    let inputs = [("color", CHART), ("reference", CHART)];
    let Some((mut exec, heat_map)) = run("Difference", &[], &inputs, "heat") else {
        return;
    };
    assert_eq!(measured(&mut exec, "relmse"), 0.0);
    let black = heat(0.0, 1.0, 4.0).map(|v| f64::from(cpu::to_u8(v)) / 255.0);
    for p in &heat_map.pixels {
        for c in 0..3 {
            assert!((f64::from(p[c]) - black[c]).abs() < 1e-6, "{p:?}");
        }
    }
}

#[test]
fn difference_refuses_a_reference_of_another_size() {
    let small = Image::filled(7, 5, [0.5, 0.5, 0.5, 1.0]);
    let dir = tempfile::tempdir().unwrap();
    let ref_path = write_exr(dir.path(), "small.exr", &small);
    let graph = Graph {
        nodes: vec![
            Node::new("in", "ImageInput").with("path", ParamValue::Str(CHART.into())),
            Node::new("ref", "ImageInput").with("path", ParamValue::Str(ref_path)),
            Node::new("diff", "Difference"),
        ],
        edges: vec![
            Edge::new("in.color", "diff.color"),
            Edge::new("ref.color", "diff.reference"),
        ],
        ..Graph::default()
    };
    let e = lumagraph::pathtrace::library::builtins()
        .compile_with(
            &graph,
            &lumagraph::graph::Registry::with_builtins(),
            &common::root(),
            &["diff.heat".to_owned()],
            None,
        )
        .unwrap_err()
        .to_string();
    assert!(e.contains("diff") && e.contains("7x5"), "{e}");
}

#[test]
fn auto_exposure_matches_cpu() {
    let chart = image_io::load(&repo(CHART)).unwrap();
    let bins = cpu::luminance_histogram(&chart);
    for (key, low, high) in [(0.18, 0.1, 0.9), (0.5, 0.0, 1.0), (0.05, 0.5, 0.98)] {
        let params = [
            ("key", ParamValue::Float(key)),
            ("low", ParamValue::Float(low)),
            ("high", ParamValue::Float(high)),
        ];
        let Some((mut exec, got)) = run("AutoExposure", &params, &[("color", CHART)], "color")
        else {
            return;
        };
        let ev = measured(&mut exec, "exposure_ev");
        #[expect(clippy::cast_possible_truncation, reason = "f32 as the GPU")]
        let want =
            cpu::auto_exposure_target(&bins, key as f32, [low as f32, high as f32], [-10.0, 10.0])
                .unwrap();
        eprintln!("AutoExposure key {key} [{low}, {high}]: GPU {ev:.6} EV, CPU {want:.6} EV");
        assert!((ev - f64::from(want)).abs() <= 1e-3, "{ev} vs {want}");
        let scale = ev.exp2();
        let want_image = map_pixels(&chart, |_, p| {
            [p[0] * scale, p[1] * scale, p[2] * scale, p[3]]
        });
        assert_within(&format!("AutoExposure {key}"), &got, &want_image, |i, c| {
            2e-6 * f64::from(want_image.pixels[i][c].abs()) + 1e-9
        });
    }
}

#[test]
fn auto_exposure_of_a_flat_image_maps_it_to_the_key() {
    let dir = tempfile::tempdir().unwrap();
    // Luminance 0.02 (grey): 0.18 / 0.02 = 9, log2 9 = 3.17 stops; one clamped at max_ev.
    let flat = write_exr(
        dir.path(),
        "flat.exr",
        &Image::filled(40, 30, [0.02, 0.02, 0.02, 1.0]),
    );
    for (max_ev, want) in [(10.0, (0.18_f64 / 0.02).log2()), (2.0, 2.0)] {
        let params = [("max_ev", ParamValue::Float(max_ev))];
        let Some((mut exec, _)) = run("AutoExposure", &params, &[("color", &flat)], "color") else {
            return;
        };
        let ev = measured(&mut exec, "exposure_ev");
        eprintln!("flat 0.02, max_ev {max_ev}: {ev:.4} EV (exact {want:.4})");
        assert!((ev - want).abs() <= 40.0 / 256.0 / 2.0, "{ev} vs {want}");
    }
}

#[test]
fn auto_exposure_adapts_over_frames_and_restarts_at_the_target() {
    let Some(ctx) = common::gpu() else {
        return;
    };
    let graph = |key: f64| Graph {
        nodes: vec![
            Node::new("in", "ImageInput").with("path", ParamValue::Str(CHART.into())),
            Node::new("ae", "AutoExposure")
                .with("key", ParamValue::Float(key))
                .with("adaptation", ParamValue::Float(0.25)),
        ],
        edges: vec![Edge::new("in.color", "ae.color")],
        ..Graph::default()
    };
    let keep = ["ae.color".to_owned()];
    let resources = Resources {
        base_dir: common::root(),
        ..Resources::default()
    };
    let mut exec = lumagraph::pathtrace::library::executor(
        ctx,
        compile(&graph(0.18), &keep, None).unwrap(),
        &resources,
    )
    .unwrap();
    exec.run_frame().unwrap();
    let ev1 = measured(&mut exec, "exposure_ev");
    // Twice the key: the target is one stop up; each frame takes a quarter of what is left.
    assert!(
        exec.update_params(compile(&graph(0.36), &keep, None).unwrap())
            .unwrap()
    );
    exec.run_frame().unwrap();
    let ev2 = measured(&mut exec, "exposure_ev");
    exec.run_frame().unwrap();
    let ev3 = measured(&mut exec, "exposure_ev");
    eprintln!("adaptation: {ev1:.5} → {ev2:.5} → {ev3:.5} EV");
    assert!((ev2 - (ev1 + 0.25)).abs() < 1e-5, "{ev1} → {ev2}");
    assert!(
        (ev3 - (ev1 + 0.25 + 0.75 * 0.25)).abs() < 1e-5,
        "{ev2} → {ev3}"
    );
    exec.reset_history();
    exec.run_frame().unwrap();
    let ev4 = measured(&mut exec, "exposure_ev");
    assert!(
        (ev4 - (ev1 + 1.0)).abs() < 1e-5,
        "after a reset: {ev4}, target {}",
        ev1 + 1.0
    );
}
