//! Every GPU post node against its plain-Rust reference, on the shared adapter.
//!
//! Tolerances: Exposure is one f32 multiply on both sides, so it must agree to 1 ulp-ish
//! (relative 1e-6). Tonemap output is stored in 8 bits; the GPU's `pow`/`log2` differ from
//! Rust's in the last bits, which can flip a rounding, so each channel may differ by one
//! 8-bit step (1/255) and the mean difference must stay below 0.05 steps.

use crate::common;

use lumagraph::graph::{Edge, Graph, Node, ParamValue};
use lumagraph::pathtrace::library::compile;
use lumagraph::render::cpu::{self, Image};
use lumagraph::render::{Resources, image_io};

/// Runs `graph` once with `keep` ports kept alive and returns them.
fn run(graph: &Graph, keep: &[&str], out_dir: &std::path::Path) -> Option<Vec<Image>> {
    common::run_graph(graph, keep, out_dir)
}

fn chart() -> Image {
    image_io::load(&common::repo("assets/test_chart.exr")).unwrap()
}

fn post_graph(ev: f64, operator: &str) -> Graph {
    Graph {
        nodes: vec![
            Node::new("input", "ImageInput")
                .with("path", ParamValue::Str("assets/test_chart.exr".into())),
            Node::new("exposure", "Exposure").with("ev", ParamValue::Float(ev)),
            Node::new("tonemap", "Tonemap").with("operator", ParamValue::Str(operator.into())),
            Node::new("out", "Output").with("path", ParamValue::Str("out.png".into())),
        ],
        edges: vec![
            Edge::new("input.color", "exposure.color"),
            Edge::new("exposure.color", "tonemap.color"),
            Edge::new("tonemap.color", "out.color"),
        ],
        ..Graph::default()
    }
}

#[test]
fn shipped_chart_is_the_generated_one() {
    // The asset is stored as half floats: it must match the generator to f16 precision.
    let (stored, generated) = (chart(), image_io::test_chart());
    assert_eq!(
        (stored.width, stored.height),
        (generated.width, generated.height)
    );
    for (a, b) in stored.pixels.iter().zip(&generated.pixels) {
        for c in 0..4 {
            assert!(
                (a[c] - b[c]).abs() <= b[c].abs() * 1e-3 + 1e-7,
                "{a:?} vs {b:?}"
            );
        }
    }
}

#[test]
fn exposure_matches_cpu() {
    let dir = tempfile::tempdir().unwrap();
    for ev in [-7.5, 0.0, 1.7, 12.0] {
        let Some(out) = run(&post_graph(ev, "aces"), &["exposure.color"], dir.path()) else {
            return;
        };
        let expected = cpu::exposure(&chart(), cpu::exposure_scale(ev));
        for (g, c) in out[0].pixels.iter().zip(&expected.pixels) {
            for k in 0..4 {
                assert!(
                    (g[k] - c[k]).abs() <= c[k].abs() * 1e-6,
                    "ev {ev}: GPU {g:?} CPU {c:?}"
                );
            }
        }
    }
}

#[test]
fn every_tonemap_operator_matches_cpu() {
    let dir = tempfile::tempdir().unwrap();
    for (op_index, (op, _)) in lumagraph::graph::registry::TONEMAP_OPERATORS
        .iter()
        .enumerate()
    {
        for ev in [-4.0, 0.0, 6.0] {
            let Some(out) = run(&post_graph(ev, op), &["tonemap.color"], dir.path()) else {
                return;
            };
            let input = cpu::exposure(&chart(), cpu::exposure_scale(ev));
            let expected = cpu::tonemap(&input, u32::try_from(op_index).unwrap(), 4.0);
            let mut sum = 0.0_f64;
            for (g, c) in out[0].pixels.iter().zip(&expected.pixels) {
                for k in 0..4 {
                    let steps = (f32::from(cpu::to_u8(g[k])) - f32::from(cpu::to_u8(c[k]))).abs();
                    assert!(steps <= 1.0, "{op} ev {ev}: GPU {g:?} CPU {c:?}");
                    sum += f64::from(steps);
                }
            }
            let mean = sum / (out[0].pixels.len() * 4) as f64;
            assert!(mean < 0.05, "{op} ev {ev}: mean difference {mean} steps");
        }
    }
}

#[test]
fn tonemap_curves_are_monotonic_and_bounded_on_cpu() {
    for op in 0..5 {
        let mut last = -1.0_f32;
        for i in 0..=400 {
            let x = (f64::from(i) / 20.0 - 12.0).exp2() as f32;
            let y = cpu::tonemap_curve([x; 3], op, 4.0);
            assert!(
                y.iter().all(|v| v.is_finite() && (0.0..=1.0).contains(v)),
                "op {op} x {x}: {y:?}"
            );
            assert!(
                y[1] >= last - 1e-6,
                "op {op} not monotonic at {x}: {} < {last}",
                y[1]
            );
            last = y[1];
        }
    }
}

#[test]
fn output_files_hold_what_the_gpu_made() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = post_graph(0.5, "agx");
    g.nodes
        .push(Node::new("linear", "Output").with("path", ParamValue::Str("linear.exr".into())));
    g.nodes
        .push(Node::new("linear_png", "Output").with("path", ParamValue::Str("linear.png".into())));
    g.edges.push(Edge::new("exposure.color", "linear.color"));
    g.edges
        .push(Edge::new("exposure.color", "linear_png.color"));
    let Some(out) = run(&g, &["exposure.color", "tonemap.color"], dir.path()) else {
        return;
    };

    // EXR: linear floats, bit for bit.
    let exr = image_io::load(&dir.path().join("linear.exr")).unwrap();
    assert_eq!(exr.pixels, out[0].pixels);
    // PNG of display color: the 8-bit values as they are.
    let png = image::open(dir.path().join("out.png")).unwrap().to_rgba8();
    for (p, g) in png.pixels().zip(&out[1].pixels) {
        assert_eq!(p.0, g.map(cpu::to_u8));
    }
    // PNG of linear color: sRGB-encoded and clipped.
    let png = image::open(dir.path().join("linear.png"))
        .unwrap()
        .to_rgba8();
    for (p, g) in png.pixels().zip(&out[0].pixels) {
        let encoded = g.map(|v| cpu::to_u8(cpu::srgb_encode(v)));
        assert_eq!(p.0[..3], encoded[..3]);
    }
}

#[test]
fn png_input_is_decoded_from_srgb() {
    let dir = tempfile::tempdir().unwrap();
    let values: Vec<u8> = (0..=255).flat_map(|v| [v, 255 - v, v / 2, 255]).collect();
    let png = dir.path().join("ramp.png");
    image_io::write_png(&png, 256, 1, &values).unwrap();
    let mut g = post_graph(0.0, "clamp");
    g.nodes[0]
        .params
        .insert("path".into(), ParamValue::Str(png.display().to_string()));
    let Some(out) = run(&g, &["input.color"], dir.path()) else {
        return;
    };
    for (i, p) in out[0].pixels.iter().enumerate() {
        let v = values[i * 4];
        assert!((p[0] - cpu::srgb_decode(f32::from(v) / 255.0)).abs() < 1e-6);
    }
    // and a round trip through Tonemap(clamp) gives the bytes back
    let Some(out) = run(&g, &["tonemap.color"], dir.path()) else {
        return;
    };
    for (i, p) in out[0].pixels.iter().enumerate() {
        for k in 0..3 {
            assert_eq!(cpu::to_u8(p[k]), values[i * 4 + k], "pixel {i}");
        }
    }
}

#[test]
fn dead_branch_never_executes() {
    // The dead branch reads a file that does not exist: running it would fail.
    let dir = tempfile::tempdir().unwrap();
    let mut g = post_graph(0.0, "aces");
    g.nodes.push(
        Node::new("ghost", "ImageInput").with("path", ParamValue::Str("no/such/file.exr".into())),
    );
    g.nodes.push(Node::new("dead", "Exposure"));
    g.edges.push(Edge::new("ghost.color", "dead.color"));
    let Some(ctx) = common::gpu() else { return };
    let plan = compile(&g, &[], None).unwrap_or_else(|e| panic!("{e}"));
    assert!(plan.pass("dead").is_none() && plan.pass("ghost").is_none());
    let paths = Resources {
        base_dir: common::root(),
        out_dir: dir.path().to_owned(),
        ..Resources::default()
    };
    let mut exec = lumagraph::pathtrace::library::executor(ctx, plan, &paths).unwrap();
    let report = exec.run_frame().unwrap();
    assert_eq!(report.executed, ["input", "exposure", "tonemap", "out"]);
    if let Some(times) = &report.pass_ms {
        assert!(times.iter().all(|(name, _)| name != "dead"));
    }
}

/// A kernel's bindings are its shader's: a pass that binds its output texture with `read`
/// and its input with `write` (swapped), or a storage buffer where the shader has a uniform,
/// is refused before anything is recorded, with the binding and the method it wants.
#[test]
fn swapped_or_mistyped_bindings_are_refused() {
    use lumagraph::render::kernel::Kernel;
    use lumagraph::render::{PooledTexture, uniform_buffer};
    let Some(ctx) = common::gpu() else { return };
    let kernel = Kernel::new(ctx, "post/exposure.wgsl").unwrap();
    let extent = lumagraph::graph::Extent::new(4, 4);
    let tex = |label| -> PooledTexture {
        lumagraph::render::create_texture(
            ctx,
            label,
            lumagraph::graph::TexFormat::Rgba32Float,
            extent,
        )
    };
    let (input, output) = (tex("input"), tex("output"));
    let params = uniform_buffer(ctx, "params", &[0; 16]);
    let storage = lumagraph::render::kernel::storage_buffer(ctx, "storage", &[0; 16]);
    kernel
        .pass("exposure")
        .read(&input.view)
        .write(&output.view)
        .uniform(&params)
        .check()
        .unwrap();
    let swapped = kernel
        .pass("exposure")
        .write(&input.view)
        .read(&output.view)
        .uniform(&params)
        .check()
        .unwrap_err()
        .to_string();
    assert!(
        swapped.contains("binding 0")
            && swapped.contains("bound with `write`")
            && swapped.contains("wants `read`"),
        "{swapped}"
    );
    let mixed = kernel
        .pass("exposure")
        .read(&input.view)
        .write(&output.view)
        .buffer(&storage)
        .check()
        .unwrap_err()
        .to_string();
    assert!(
        mixed.contains("binding 2") && mixed.contains("wants `uniform`"),
        "{mixed}"
    );
    let short = kernel
        .pass("exposure")
        .read(&input.view)
        .write(&output.view)
        .check()
        .unwrap_err()
        .to_string();
    assert!(
        short.contains("2 resources given for 3 bindings"),
        "{short}"
    );
}
