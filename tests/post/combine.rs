//! Mix and Math (generic post filters) against their CPU references on the HDR test chart
//! and a second image made from it (channels rotated, scaled, flipped), every mode and
//! operation. Each channel within 1e-5 relative of the reference's largest operand plus
//! 1e-7 (f32 on the GPU, f64 here; `pow` a few ulps; measured worst printed per case).

use crate::common;

use common::{assert_within, map_pixels, run_node};
use lumagraph::graph::ParamValue;
use lumagraph::render::cpu::Image;
use lumagraph::render::image_io;

/// A per-channel operation of two values.
type BinOp = fn(f64, f64) -> f64;

const CHART: &str = "assets/test_chart.exr";

fn chart() -> Image {
    image_io::load(&common::repo(CHART)).unwrap()
}

#[test]
fn mix_matches_cpu() {
    let a = chart();
    // b: the chart upside down, channels rotated, scaled: every pixel differs from a's.
    let (w, h) = (a.width as usize, a.height as usize);
    let b = map_pixels(&a, |i, _| {
        let q = a.pixels[(h - 1 - i / w) * w + i % w].map(f64::from);
        [0.7 * q[1], 1.3 * q[2], 0.9 * q[0], q[3]]
    });
    let dir = tempfile::tempdir().unwrap();
    let b_path = dir.path().join("b.exr");
    std::fs::write(&b_path, image_io::encode_exr(&b, false).unwrap()).unwrap();
    let b_path = b_path.to_str().unwrap();
    let modes: [(&str, BinOp); 7] = [
        ("mix", |_, b| b),
        ("add", |a, b| a + b),
        ("multiply", |a, b| a * b),
        ("screen", |a, b| 1.0 - (1.0 - a) * (1.0 - b)),
        ("overlay", |a, b| {
            if a < 0.5 {
                2.0 * a * b
            } else {
                1.0 - 2.0 * (1.0 - a) * (1.0 - b)
            }
        }),
        ("difference", |a, b| (a - b).abs()),
        ("subtract", |a, b| a - b),
    ];
    for (mode, f) in modes {
        for factor in [0.5, 1.0, 0.2] {
            let params = [
                ("mode", ParamValue::Str(mode.into())),
                ("factor", ParamValue::Float(factor)),
            ];
            let Some(got) = run_node("Mix", &params, &[("a", CHART), ("b", b_path)]) else {
                return;
            };
            let want = map_pixels(&a, |i, p| {
                let q = b.pixels[i].map(f64::from);
                [0, 1, 2, 3].map(|c| {
                    if c == 3 {
                        p[3]
                    } else {
                        p[c] + factor * (f(p[c], q[c]) - p[c])
                    }
                })
            });
            let scale = |i: usize, c: usize| {
                let (x, y) = (f64::from(a.pixels[i][c]), f64::from(b.pixels[i][c]));
                x.abs().max(y.abs()).max(x.abs() * y.abs()).max(1.0)
            };
            assert_within(&format!("Mix {mode} {factor}"), &got, &want, |i, c| {
                1e-5 * scale(i, c) + 1e-7
            });
        }
    }
}

#[test]
fn math_matches_cpu() {
    let image = chart();
    let ops: [(&str, f64, BinOp); 7] = [
        ("add", -0.25, |c, v| c + v),
        ("multiply", 3.5, |c, v| c * v),
        ("power", 2.2, |c, v| c.max(0.0).powf(v)),
        ("power", 0.4545, |c, v| c.max(0.0).powf(v)),
        ("minimum", 0.5, f64::min),
        ("maximum", 0.25, f64::max),
        ("clamp", 1.0, |c, v| c.clamp(0.0, v)),
    ];
    for (op, value, f) in ops {
        let params = [
            ("operation", ParamValue::Str(op.into())),
            ("value", ParamValue::Float(value)),
        ];
        let Some(got) = run_node("Math", &params, &[("color", CHART)]) else {
            return;
        };
        let want = map_pixels(&image, |_, p| {
            [0, 1, 2, 3].map(|c| if c == 3 { p[3] } else { f(p[c], value) })
        });
        assert_within(&format!("Math {op} {value}"), &got, &want, |i, c| {
            1e-5 * f64::from(want.pixels[i][c].abs()).max(f64::from(image.pixels[i][c].abs()))
                + 1e-7
        });
    }
}

/// Split gives each channel as a grey image with alpha 1; Combine puts red channels back,
/// here with red and blue swapped, with and without alpha. Both only move f32 values:
/// bit-exact.
#[test]
fn split_and_combine_move_channels_exactly() {
    // The chart with an alpha that varies over the image.
    let image = map_pixels(&chart(), |i, p| [p[0], p[1], p[2], (i % 13) as f64 / 12.0]);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("alpha.exr");
    std::fs::write(&path, image_io::encode_exr(&image, false).unwrap()).unwrap();
    let path = path.to_str().unwrap();
    use lumagraph::graph::{Edge, Graph, Node};
    let graph = Graph {
        nodes: vec![
            Node::new("in", "ImageInput").with("path", ParamValue::Str(path.into())),
            Node::new("split", "Split"),
            Node::new("swap", "Combine"),
            Node::new("opaque", "Combine"),
        ],
        edges: vec![
            Edge::new("in.color", "split.color"),
            Edge::new("split.b", "swap.r"),
            Edge::new("split.g", "swap.g"),
            Edge::new("split.r", "swap.b"),
            Edge::new("split.a", "swap.a"),
            Edge::new("split.r", "opaque.r"),
            Edge::new("split.g", "opaque.g"),
            Edge::new("split.b", "opaque.b"),
        ],
        ..Graph::default()
    };
    let keep = [
        "split.r",
        "split.g",
        "split.b",
        "split.a",
        "swap.color",
        "opaque.color",
    ];
    let Some(got) = common::run_graph(&graph, &keep, dir.path()) else {
        return;
    };
    for (c, channel) in got[..4].iter().enumerate() {
        let want = image.map(|p| [p[c], p[c], p[c], 1.0]);
        assert_eq!(channel, &want, "{}", keep[c]);
    }
    assert_eq!(got[4], image.map(|p| [p[2], p[1], p[0], p[3]]), "swap");
    assert_eq!(got[5], image.map(|p| [p[0], p[1], p[2], 1.0]), "opaque");
}

/// An output of Split that nothing reads is not computed into the plan, and the node
/// still runs (its store goes to a stand-in).
#[test]
fn split_runs_with_one_output_used() {
    use lumagraph::graph::{Edge, Graph, Node};
    let graph = Graph {
        nodes: vec![
            Node::new("in", "ImageInput").with("path", ParamValue::Str(CHART.into())),
            Node::new("split", "Split"),
        ],
        edges: vec![Edge::new("in.color", "split.color")],
        ..Graph::default()
    };
    let dir = tempfile::tempdir().unwrap();
    let Some(got) = common::run_graph(&graph, &["split.g"], dir.path()) else {
        return;
    };
    assert_eq!(got[0], chart().map(|p| [p[1], p[1], p[1], 1.0]));
}
