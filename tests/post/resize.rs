//! Resize (a generic post filter on `shaders/post/resample.wgsl`: its registry entry,
//! `shaders/post/resize.wgsl` and this file are all there is of it) against its CPU
//! reference on the HDR test chart: shrinking and enlarging, by `scale`, by one side
//! (aspect kept) and by both, with both kernels.
//!
//! Tolerances, per channel:
//! - `lanczos3`: |gpu − cpu| ≤ (1e-5 · Σ|w·texel| + δ · Σ|∂w/∂x·texel|) / |Σw| + 1e-7: the
//!   rounding error of the weighted sum (f32 `sin` and sums on the GPU, f64 here), plus
//!   what the f32 sample position, off by δ = 4 ulps of its coordinates, moves the
//!   weights by. Measured on lavapipe: at most 3 % of the bound (printed per case); a
//!   sampling position off by a hundredth of a pixel is already far outside it.
//! - `bilinear` goes through the GPU's filtering sampler, whose weights other GPUs keep in
//!   8 fractional bits: |gpu − cpu| ≤ 2^-8 · (largest − smallest of the 4 texels) +
//!   1e-6 · largest |texel| + 1e-7. Measured on lavapipe: at most 1 % of the bound.

use crate::common;

use lumagraph::graph::{Edge, Graph, Node, ParamValue};
use lumagraph::render::cpu::Image;
use lumagraph::render::image_io;

fn texel(image: &Image, x: i64, y: i64) -> [f64; 4] {
    let x = x.clamp(0, i64::from(image.width) - 1) as usize;
    let y = y.clamp(0, i64::from(image.height) - 1) as usize;
    image.pixels[y * image.width as usize + x].map(f64::from)
}

fn lanczos3(x: f64) -> f64 {
    let sinc = |x: f64| {
        if x.abs() < 1e-6 {
            1.0
        } else {
            (std::f64::consts::PI * x).sin() / (std::f64::consts::PI * x)
        }
    };
    if x.abs() >= 3.0 {
        0.0
    } else {
        sinc(x) * sinc(x / 3.0)
    }
}

/// One output pixel: the value and the bound the GPU's must be within.
type Pixel = ([f64; 4], [f64; 4]);

/// The CPU reference of one output pixel of a `w`×`h` resize.
fn reference(image: &Image, w: u32, h: u32, lanczos: bool, px: u32, py: u32) -> Pixel {
    let ratio = [
        f64::from(image.width) / f64::from(w),
        f64::from(image.height) / f64::from(h),
    ];
    let center = [
        (f64::from(px) + 0.5) * ratio[0] - 0.5,
        (f64::from(py) + 0.5) * ratio[1] - 0.5,
    ];
    if !lanczos {
        let (x0, y0) = (center[0].floor(), center[1].floor());
        let (fx, fy) = (center[0] - x0, center[1] - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let t = [
            texel(image, x0, y0),
            texel(image, x0 + 1, y0),
            texel(image, x0, y0 + 1),
            texel(image, x0 + 1, y0 + 1),
        ];
        let mut value = [0.0; 4];
        let mut bound = [0.0; 4];
        for c in 0..4 {
            value[c] = (t[0][c] * (1.0 - fx) + t[1][c] * fx) * (1.0 - fy)
                + (t[2][c] * (1.0 - fx) + t[3][c] * fx) * fy;
            let (lo, hi) = t.iter().fold((f64::MAX, f64::MIN), |(lo, hi), v| {
                (lo.min(v[c]), hi.max(v[c]))
            });
            bound[c] = (hi - lo) / 256.0 + 1e-6 * lo.abs().max(hi.abs()) + 1e-7;
        }
        return (value, bound);
    }
    let stretch = [ratio[0].max(1.0), ratio[1].max(1.0)];
    let lo = [0, 1].map(|a| (center[a] - 3.0 * stretch[a]).floor() as i64 + 1);
    let hi = [0, 1].map(|a| (center[a] + 3.0 * stretch[a]).floor() as i64);
    // The kernel's slope, for the error an f32 sample position brings.
    let slope = |x: f64| (lanczos3(x + 1e-4) - lanczos3(x - 1e-4)) / 2e-4;
    let mut sum = [0.0; 4];
    let mut abs = [0.0; 4];
    let mut moved = [0.0; 4];
    let mut weight = 0.0;
    for y in lo[1]..=hi[1] {
        let ty = (y as f64 - center[1]) / stretch[1];
        let wy = lanczos3(ty);
        for x in lo[0]..=hi[0] {
            let tx = (x as f64 - center[0]) / stretch[0];
            let wx = lanczos3(tx);
            let wgt = wy * wx;
            let dw = (slope(tx) * wy / stretch[0]).abs() + (wx * slope(ty) / stretch[1]).abs();
            let t = texel(image, x, y);
            for c in 0..4 {
                sum[c] += wgt * t[c];
                abs[c] += (wgt * t[c]).abs();
                moved[c] += (dw * t[c]).abs();
            }
            weight += wgt;
        }
    }
    let mut value = sum.map(|s| s / weight);
    for v in &mut value[..3] {
        *v = v.max(0.0);
    }
    // The GPU computes the sample position in f32: off by up to a few ulps of it.
    let position_error = 4.0 * f64::from(f32::EPSILON) * (center[0].abs() + center[1].abs() + 1.0);
    let bound =
        [0, 1, 2, 3].map(|c| (1e-5 * abs[c] + position_error * moved[c]) / weight.abs() + 1e-7);
    (value, bound)
}

/// Params of a Resize and the size they must give.
type Case = (Vec<(&'static str, ParamValue)>, (u32, u32));

fn graph(params: &[(&str, ParamValue)]) -> Graph {
    let mut r = Node::new("r", "Resize");
    for (k, v) in params {
        r = r.with(k, v.clone());
    }
    Graph {
        nodes: vec![
            Node::new("input", "ImageInput")
                .with("path", ParamValue::Str("assets/test_chart.exr".into())),
            r,
        ],
        edges: vec![Edge::new("input.color", "r.color")],
        ..Graph::default()
    }
}

#[test]
fn resize_matches_cpu() {
    let image = image_io::load(&common::repo("assets/test_chart.exr")).unwrap();
    let (iw, ih) = (image.width, image.height);
    let dir = tempfile::tempdir().unwrap();
    let int = |v: u32| ParamValue::Int(i64::from(v));
    let scaled = |s: f64| {
        let f = |v: u32| (f64::from(v) * s).round() as u32;
        (f(iw), f(ih))
    };
    let bilinear = ("kernel", ParamValue::Str("bilinear".into()));
    let cases: Vec<Case> = vec![
        (vec![], scaled(0.5)),
        (vec![("scale", ParamValue::Float(0.13))], scaled(0.13)),
        // The most lanczos3 shrinks in one node: 192 × 193 taps' loop iterations per pixel.
        (
            vec![("scale", ParamValue::Float(1.0 / 32.0))],
            scaled(1.0 / 32.0),
        ),
        (
            vec![("width", int(37))],
            (37, (f64::from(ih) * 37.0 / f64::from(iw)).round() as u32),
        ),
        (
            vec![("width", int(2 * iw + 3)), ("height", int(ih + 1))],
            (2 * iw + 3, ih + 1),
        ),
        (
            vec![("height", int(3 * ih)), bilinear.clone()],
            (3 * iw, 3 * ih),
        ),
        (
            vec![("scale", ParamValue::Float(0.75)), bilinear],
            scaled(0.75),
        ),
    ];
    for (params, (w, h)) in cases {
        let lanczos = !params.iter().any(|(k, _)| *k == "kernel");
        let Some(out) = common::run_graph(&graph(&params), &["r.color"], dir.path()) else {
            return;
        };
        let out = &out[0];
        assert_eq!((out.width, out.height), (w, h), "{params:?}");
        let mut worst = 0.0_f64;
        for py in 0..h {
            for px in 0..w {
                let (want, bound) = reference(&image, w, h, lanczos, px, py);
                let got = out.pixels[(py * w + px) as usize];
                for c in 0..4 {
                    let err = (f64::from(got[c]) - want[c]).abs();
                    worst = worst.max(err / bound[c]);
                    assert!(
                        err <= bound[c],
                        "{params:?} pixel ({px}, {py}) channel {c}: {} vs {} (bound {:.2e})",
                        got[c],
                        want[c],
                        bound[c]
                    );
                }
            }
        }
        eprintln!("{params:?} → {w}x{h}: worst error {worst:.3} of the bound");
    }
}

/// The plan gives the output its own size and the next node runs at it; a size over the
/// limit is an error naming the node, not a GPU failure.
#[test]
fn resize_sizes_its_output_in_the_plan() {
    use lumagraph::pathtrace::library::compile;
    let mut g = graph(&[("width", ParamValue::Int(40))]);
    g.nodes.push(Node::new("t", "Tonemap"));
    g.nodes.push(Node::new("out", "Output"));
    g.edges.push(Edge::new("r.color", "t.color"));
    g.edges.push(Edge::new("t.color", "out.color"));
    let plan = compile(&g, &[], None).unwrap();
    let chart = plan.pass("input").unwrap().extent;
    let r = plan.pass("r").unwrap();
    assert_eq!(r.extent, chart);
    let out = plan.texture(r.output("color").unwrap()).extent;
    assert_eq!(out.width, 40);
    assert_eq!(plan.pass("t").unwrap().extent, out);
    assert!(plan.to_string().contains("40x"), "{plan}");

    // Shrinking 100× with lanczos3 would sum 600² texels per pixel in one invocation, past
    // the 65 535 loop iterations after which llvmpipe ends loops (it came out 40× too
    // dark): an error naming the node and the limit. Bilinear has no loop.
    g.nodes[1] = Node::new("r", "Resize").with("scale", ParamValue::Float(0.01));
    let m = compile(&g, &[], None).unwrap_err().to_string();
    assert!(
        m.contains("node \"r\"") && m.contains("shrinks by at most 32×"),
        "{m}"
    );
    g.nodes[1] = g.nodes[1]
        .clone()
        .with("kernel", ParamValue::Str("bilinear".into()));
    compile(&g, &[], None).unwrap();

    // 16384 high at the chart's 2:1 aspect ratio is 32768 wide.
    g.nodes[1] = Node::new("r", "Resize").with("height", ParamValue::Int(16384));
    let m = compile(&g, &[], None).unwrap_err().to_string();
    assert!(
        m.contains("node \"r\"") && m.contains("a side is more than 16384"),
        "{m}"
    );
}
