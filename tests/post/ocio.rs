//! `ColorSpace` and `DisplayView` on the GPU against PyOpenColorIO: every colour space of
//! OpenColorIO's default built-in config to the working space and back, and every display
//! and view, over the reference's pixels ([−1, 1e4]: greys, primaries, secondaries, random
//! HDR colours), from `tests/color/ocio_reference.json` (`scripts/ocio/reference.py`).
//! One graph per direction: the pixels in, one node per conversion, all kept.
//!
//! Tolerance: OpenColorIO's GPU path is held to its CPU path within 1e-3 relative (1e-3
//! absolute below 1) by the `ocio` crate's own tests; here relative to the pixel's largest
//! component (a matrix after a curve cancels large values into small ones), and for
//! display-encoded outputs, stored in 8 bits, half a code value (0.5 / 255) more.

use std::path::Path;

use lumagraph::graph::{Edge, Graph, Node, ParamValue};
use lumagraph::render::cpu::Image;
use serde_json::Value;

use crate::common;

fn reference() -> Value {
    let text = std::fs::read_to_string(common::repo("tests/color/ocio_reference.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

fn number(v: &Value) -> f32 {
    match v {
        Value::String(s) => s.parse().unwrap(),
        v => v.as_f64().unwrap() as f32,
    }
}

/// The reference's pixels as an image `width` wide (rows padded with zeros).
fn pixels_image(pixels: &[Value], dir: &Path) -> (String, u32) {
    let width = 16_u32;
    let height = u32::try_from(pixels.len()).unwrap().div_ceil(width);
    let mut image = Image::filled(width, height, [0.0, 0.0, 0.0, 1.0]);
    for (i, p) in pixels.iter().enumerate() {
        let p = p.as_array().unwrap();
        image.pixels[i] = [number(&p[0]), number(&p[1]), number(&p[2]), 1.0];
    }
    let path = dir.join("pixels.exr");
    lumagraph::render::image_io::save(&path, &image, true).unwrap();
    (path.to_str().unwrap().to_owned(), width)
}

/// Runs one node of `kind` per entry of `nodes` (id, params) on the image at `input`, all
/// in one graph; each node's output.
fn run(kind: &str, nodes: &[(String, Vec<(&str, String)>)], input: &str) -> Option<Vec<Image>> {
    let mut graph = Graph::default();
    graph
        .nodes
        .push(Node::new("in", "ImageInput").with("path", ParamValue::Str(input.into())));
    let mut keep = Vec::new();
    for (id, params) in nodes {
        let mut node = Node::new(id, kind);
        for (k, v) in params {
            node = node.with(k, ParamValue::Str(v.clone()));
        }
        graph.nodes.push(node);
        graph
            .edges
            .push(Edge::new("in.color", format!("{id}.color")));
        keep.push(format!("{id}.color"));
    }
    let keep: Vec<&str> = keep.iter().map(String::as_str).collect();
    let dir = tempfile::tempdir().unwrap();
    common::run_graph(&graph, &keep, dir.path())
}

/// The worst error of `got` against `want` (the reference's triples) as a fraction of the
/// tolerance; `display`: 8-bit output.
fn worst(got: &Image, want: &[Value], display: bool) -> (f64, usize) {
    let mut worst = (0.0_f64, 0);
    for (i, w) in want.iter().enumerate() {
        let w = w.as_array().unwrap();
        // Relative to the pixel's largest component: a matrix after a curve cancels large
        // values into small ones (P3 display code 379.6 is 6.2e6 in red and −3.1e3 in blue).
        let scale = (0..3)
            .map(|c| f64::from(number(&w[c])).abs())
            .filter(|v| v.is_finite())
            .fold(1.0_f64, f64::max);
        for c in 0..3 {
            let (g, r) = (f64::from(got.pixels[i][c]), f64::from(number(&w[c])));
            if !r.is_finite() {
                continue;
            }
            let mut bound = 1e-3 * scale;
            if display {
                bound += 0.5 / 255.0;
                // Stored in [0, 1]: what the display encodes beyond is clipped.
                let clipped = r.clamp(0.0, 1.0);
                let e = (g - clipped).abs() / bound;
                if e > worst.0 {
                    worst = (e, i);
                }
                continue;
            }
            let e = (g - r).abs() / bound;
            if e > worst.0 || g.is_nan() {
                worst = (if g.is_nan() { f64::INFINITY } else { e }, i);
            }
        }
    }
    worst
}

#[test]
fn every_colour_space_and_view_of_the_default_config_matches_pyopencolorio() {
    if common::gpu().is_none() {
        return;
    }
    let reference = reference();
    let config = &reference["configs"]["ocio://cg-config-v4.0.0_aces-v2.0_ocio-v2.5"];
    let dir = tempfile::tempdir().unwrap();
    let (input, _) = pixels_image(reference["pixels"].as_array().unwrap(), dir.path());
    let uri = "ocio://cg-config-v4.0.0_aces-v2.0_ocio-v2.5".to_owned();
    let mut failures = Vec::new();
    let mut checked = 0;
    // Every colour space into the working space.
    let spaces: Vec<(&String, &Value)> = config["to_working"]
        .as_object()
        .unwrap()
        .iter()
        .filter(|(_, v)| v.is_array())
        .collect();
    let nodes: Vec<(String, Vec<(&str, String)>)> = spaces
        .iter()
        .enumerate()
        .map(|(i, (name, _))| {
            (
                format!("s{i}"),
                vec![("config", uri.clone()), ("from", (*name).clone())],
            )
        })
        .collect();
    let Some(images) = run("ColorSpace", &nodes, &input) else {
        return;
    };
    for ((name, want), got) in spaces.iter().zip(&images) {
        let (w, at) = worst(got, want.as_array().unwrap(), false);
        checked += 1;
        if w > 1.0 {
            failures.push(format!(
                "{name} → working: {w:.2} of the tolerance at pixel {at}"
            ));
        }
    }
    // Every display and view from the working space.
    let mut views = Vec::new();
    for (display, vs) in config["displays"].as_object().unwrap() {
        for (view, want) in vs.as_object().unwrap() {
            if want.is_array() {
                views.push((display.clone(), view.clone(), want));
            }
        }
    }
    let nodes: Vec<(String, Vec<(&str, String)>)> = views
        .iter()
        .enumerate()
        .map(|(i, (d, v, _))| {
            (
                format!("v{i}"),
                vec![
                    ("config", uri.clone()),
                    ("display", d.clone()),
                    ("view", v.clone()),
                ],
            )
        })
        .collect();
    let Some(images) = run("DisplayView", &nodes, &input) else {
        return;
    };
    for ((d, v, want), got) in views.iter().zip(&images) {
        let (w, at) = worst(got, want.as_array().unwrap(), true);
        checked += 1;
        if w > 1.0 {
            failures.push(format!("{d} / {v}: {w:.2} of the tolerance at pixel {at}"));
        }
    }
    eprintln!(
        "OpenColorIO on the GPU against PyOpenColorIO: {checked} conversions, {} beyond the tolerance",
        failures.len()
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(checked > 40, "{checked}");
}
