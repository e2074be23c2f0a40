//! Vignette (a generic post filter: its registry entry, `shaders/post/vignette.wgsl` and this
//! file are all there is of it) against its CPU reference on the HDR test chart, at its
//! defaults and at three other settings, on non-square images too. The GPU and the CPU do
//! the same f32 operations but round `length`, `smoothstep` and their division apart: each
//! channel within 1e-5 relative (plus 1e-6 absolute) of the reference (measured: at most
//! 1.4e-7 relative on lavapipe; the bound leaves room for other GPUs' `length`).

use crate::common;

use lumagraph::graph::{Edge, Graph, Node, ParamValue};
use lumagraph::render::cpu::Image;
use lumagraph::render::image_io;

/// The CPU reference: color × (1 − strength · smoothstep(radius, radius + softness, d)), d the
/// distance of the pixel center from the image center in half-diagonals.
fn vignette(image: &Image, strength: f32, radius: f32, softness: f32) -> Image {
    let (w, h) = (image.width as f32, image.height as f32);
    let half = [0.5 * w, 0.5 * h];
    let diag = half[0].hypot(half[1]);
    let mut out = image.clone();
    for (i, p) in out.pixels.iter_mut().enumerate() {
        let (x, y) = (
            (i % image.width as usize) as f32,
            (i / image.width as usize) as f32,
        );
        let d = (x + 0.5 - half[0]).hypot(y + 0.5 - half[1]) / diag;
        let t = ((d - radius) / softness).clamp(0.0, 1.0);
        let s = t * t * (3.0 - 2.0 * t);
        let k = 1.0 - strength * s;
        for c in 0..3 {
            p[c] *= k;
        }
    }
    out
}

fn graph(path: &str, params: &[(&str, f64)]) -> Graph {
    let mut v = Node::new("v", "Vignette");
    for (k, x) in params {
        v = v.with(k, ParamValue::Float(*x));
    }
    Graph {
        nodes: vec![
            Node::new("input", "ImageInput").with("path", ParamValue::Str(path.into())),
            v,
        ],
        edges: vec![Edge::new("input.color", "v.color")],
        ..Graph::default()
    }
}

#[test]
fn vignette_matches_cpu() {
    let chart = "assets/test_chart.exr";
    let image = image_io::load(&common::repo(chart)).unwrap();
    let dir = tempfile::tempdir().unwrap();
    // A 97×53 crop of the chart, for odd and non-square sizes.
    let crop = Image {
        width: 97,
        height: 53,
        pixels: (0..53)
            .flat_map(|y| (0..97).map(move |x| (x, y)))
            .map(|(x, y)| image.pixels[y * image.width as usize + x])
            .collect(),
    };
    let crop_path = dir.path().join("crop.exr");
    std::fs::write(&crop_path, image_io::encode_exr(&crop, false).unwrap()).unwrap();
    let cases: [(&str, &Image, [f64; 3]); 4] = [
        (chart, &image, [0.5, 0.6, 0.6]),
        (chart, &image, [1.0, 0.0, 0.001]),
        (chart, &image, [0.3, 1.2, 2.0]),
        (crop_path.to_str().unwrap(), &crop, [0.8, 0.2, 0.5]),
    ];
    for (path, source, [strength, radius, softness]) in cases {
        let params = [
            ("strength", strength),
            ("radius", radius),
            ("softness", softness),
        ];
        let Some(out) = common::run_graph(&graph(path, &params), &["v.color"], dir.path()) else {
            return;
        };
        #[expect(clippy::cast_possible_truncation, reason = "f32 reference")]
        let want = vignette(source, strength as f32, radius as f32, softness as f32);
        let mut worst = 0.0_f32;
        for (g, c) in out[0].pixels.iter().zip(&want.pixels) {
            for k in 0..4 {
                let err = (g[k] - c[k]).abs() / (c[k].abs() + 1e-1);
                worst = worst.max(err);
                assert!(
                    (g[k] - c[k]).abs() <= 1e-5 * c[k].abs() + 1e-6,
                    "{params:?}: {} vs {}",
                    g[k],
                    c[k]
                );
            }
        }
        eprintln!("{params:?}: worst relative difference {worst:.2e}");
    }
}
