//! `Sharpen`, `ChromaticAberration`, `FilmGrain` and `Crop` (generic post filters) against their
//! CPU references on the HDR test chart. Tolerances, per channel:
//! - Sharpen: 1e-5 × (1 + amount) × the largest |texel| in the footprint + 1e-7: the
//!   normalized Gaussian sum in f32 against f64.
//! - `ChromaticAberration`: bilinear through the GPU's sampler, as Resize's `bilinear`:
//!   2^-8 × the range of the 4 texels (8-bit filter weights on some GPUs) + 1e-6 relative.
//! - `FilmGrain`: the same PCG hash in u32 on both sides; the normal number n = r·cos(2πu),
//!   r = √(−2 ln u₁), through f32 `log`, `sqrt` and `cos`. Vulkan allows `log` an absolute
//!   error of 2^-21 near 1, which `sqrt` turns into δr = min(2^-20 / r, 2^-9.5); the f32
//!   angle is off by up to ~4e-7: δn = δr + 4e-6 × r, and the bound is
//!   δn × intensity × |c| + 1e-6 × |c| + 1e-7.
//! - Crop: exact (a copy).
//!
//! Measured worst errors are printed per case as fractions of their bound.

use crate::common;

use common::{assert_within, map_pixels, run_node};
use lumagraph::graph::ParamValue;
use lumagraph::render::cpu::Image;
use lumagraph::render::image_io;

const CHART: &str = "assets/test_chart.exr";

fn chart() -> Image {
    image_io::load(&common::repo(CHART)).unwrap()
}

fn texel(image: &Image, x: i64, y: i64) -> [f64; 4] {
    let x = x.clamp(0, i64::from(image.width) - 1) as usize;
    let y = y.clamp(0, i64::from(image.height) - 1) as usize;
    image.pixels[y * image.width as usize + x].map(f64::from)
}

#[test]
fn sharpen_matches_cpu() {
    let image = chart();
    let w = image.width as usize;
    for (amount, sigma) in [(0.5, 1.0), (2.0, 0.3), (1.0, 2.7)] {
        let params = [
            ("amount", ParamValue::Float(amount)),
            ("sigma", ParamValue::Float(sigma)),
        ];
        let Some(got) = run_node("Sharpen", &params, &[("color", CHART)]) else {
            return;
        };
        let r = (3.0 * sigma).ceil() as i64;
        let mut peak = vec![0.0_f64; image.pixels.len()];
        let want = map_pixels(&image, |i, p| {
            let (x, y) = ((i % w) as i64, (i / w) as i64);
            let mut sum = [0.0; 4];
            let mut weight = 0.0;
            for dy in -r..=r {
                for dx in -r..=r {
                    let k = (-((dx * dx + dy * dy) as f64) / (2.0 * sigma * sigma)).exp();
                    let t = texel(&image, x + dx, y + dy);
                    for c in 0..4 {
                        sum[c] += k * t[c];
                    }
                    weight += k;
                }
            }
            [0, 1, 2, 3].map(|c| {
                let s = p[c] + amount * (p[c] - sum[c] / weight);
                if c == 3 { s } else { s.max(0.0) }
            })
        });
        for (i, m) in peak.iter_mut().enumerate() {
            let (x, y) = ((i % w) as i64, (i / w) as i64);
            for dy in -r..=r {
                for dx in -r..=r {
                    let t = texel(&image, x + dx, y + dy);
                    *m = t.iter().fold(*m, |m, v| m.max(v.abs()));
                }
            }
        }
        assert_within(
            &format!("Sharpen {amount} σ {sigma}"),
            &got,
            &want,
            |i, _| 1e-5 * (1.0 + amount) * peak[i] + 1e-7,
        );
    }
}

#[test]
fn chromatic_aberration_matches_cpu() {
    let image = chart();
    let (w, h) = (f64::from(image.width), f64::from(image.height));
    let bilinear = |u: f64, v: f64, c: usize| -> (f64, f64) {
        let (x, y) = (u * w - 0.5, v * h - 0.5);
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let t = [(0, 0), (1, 0), (0, 1), (1, 1)]
            .map(|(dx, dy)| texel(&image, x0 as i64 + dx, y0 as i64 + dy)[c]);
        let value =
            (t[0] * (1.0 - fx) + t[1] * fx) * (1.0 - fy) + (t[2] * (1.0 - fx) + t[3] * fx) * fy;
        let (lo, hi) = t
            .iter()
            .fold((f64::MAX, f64::MIN), |(l, u), v| (l.min(*v), u.max(*v)));
        (
            value,
            (hi - lo) / 256.0 + 1e-6 * lo.abs().max(hi.abs()) + 1e-7,
        )
    };
    for strength in [0.005, 0.05, -0.03] {
        let params = [("strength", ParamValue::Float(strength))];
        let Some(got) = run_node("ChromaticAberration", &params, &[("color", CHART)]) else {
            return;
        };
        let mut bounds = vec![[0.0_f64; 4]; image.pixels.len()];
        let want = map_pixels(&image, |i, p| {
            let (x, y) = (
                (i % image.width as usize) as f64,
                (i / image.width as usize) as f64,
            );
            let (du, dv) = ((x + 0.5) / w - 0.5, (y + 0.5) / h - 0.5);
            let (r, rb) = bilinear(0.5 + du * (1.0 + strength), 0.5 + dv * (1.0 + strength), 0);
            let (b, bb) = bilinear(0.5 + du * (1.0 - strength), 0.5 + dv * (1.0 - strength), 2);
            bounds[i] = [rb, 0.0, bb, 0.0];
            [r, p[1], b, p[3]]
        });
        assert_within(
            &format!("ChromaticAberration {strength}"),
            &got,
            &want,
            |i, c| bounds[i][c],
        );
    }
}

fn pcg(v: u32) -> u32 {
    let state = v.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
    (word >> 22) ^ word
}

#[test]
fn film_grain_matches_cpu() {
    let image = chart();
    let w = image.width;
    let mut normals = Vec::new();
    for (intensity, seed) in [(0.05, 0_u32), (0.3, 12345)] {
        let params = [
            ("intensity", ParamValue::Float(intensity)),
            ("seed", ParamValue::Int(i64::from(seed))),
        ];
        let Some(got) = run_node("FilmGrain", &params, &[("color", CHART)]) else {
            return;
        };
        let mut n_of = vec![0.0; image.pixels.len()];
        let mut radius = vec![0.0; image.pixels.len()];
        let want = map_pixels(&image, |i, p| {
            let (x, y) = (i as u32 % w, i as u32 / w);
            let hash = pcg(x.wrapping_add(pcg(y.wrapping_add(pcg(seed)))));
            let u1 = (f64::from(hash >> 8) + 1.0) / 16_777_216.0;
            let u2 = f64::from(pcg(hash) >> 8) / 16_777_216.0;
            let n = (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos();
            n_of[i] = n;
            radius[i] = (-2.0 * u1.ln()).sqrt();
            [0, 1, 2, 3].map(|c| {
                if c == 3 {
                    p[3]
                } else {
                    (p[c] * (1.0 + intensity * n)).max(0.0)
                }
            })
        });
        assert_within(
            &format!("FilmGrain {intensity} seed {seed}"),
            &got,
            &want,
            |i, c| {
                let v = f64::from(image.pixels[i][c].abs());
                let r = radius[i];
                let dr = (2.0_f64.powi(-20) / r).min(2.0_f64.powf(-9.5));
                (dr + 4e-6 * r) * intensity * v + 1e-6 * v + 1e-7
            },
        );
        normals.push(n_of);
    }
    // The draws are standard normal: mean and variance over the 131 072 pixels within
    // 5 standard errors (mean: 1/√n; variance: √(2/n)), and two seeds differ.
    for n in &normals {
        let len = n.len() as f64;
        let mean = n.iter().sum::<f64>() / len;
        let var = n.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / len;
        assert!(mean.abs() < 5.0 / len.sqrt(), "mean {mean}");
        assert!(
            (var - 1.0).abs() < 5.0 * (2.0 / len).sqrt(),
            "variance {var}"
        );
    }
    assert_ne!(normals[0][..16], normals[1][..16]);
}

#[test]
fn crop_copies_the_rectangle() {
    let image = chart();
    let int = |v: i64| ParamValue::Int(v);
    for (x, y, cw, ch) in [
        (0, 0, 0, 0),
        (10, 20, 100, 50),
        (300, 7, 0, 0),
        (511, 255, 1, 1),
    ] {
        let params = [
            ("x", int(x)),
            ("y", int(y)),
            ("width", int(cw)),
            ("height", int(ch)),
        ];
        let Some(got) = run_node("Crop", &params, &[("color", CHART)]) else {
            return;
        };
        let w = if cw == 0 {
            i64::from(image.width) - x
        } else {
            cw
        };
        let h = if ch == 0 {
            i64::from(image.height) - y
        } else {
            ch
        };
        let want = Image {
            width: w as u32,
            height: h as u32,
            pixels: (0..h)
                .flat_map(|j| (0..w).map(move |i| (i, j)))
                .map(|(i, j)| image.pixels[((y + j) * i64::from(image.width) + x + i) as usize])
                .collect(),
        };
        assert_within(
            &format!("Crop {w}x{h} at ({x}, {y})"),
            &got,
            &want,
            |_, _| 0.0,
        );
    }
    // A rectangle reaching past the image is refused at compile time, naming the node.
    let mut g = lumagraph::graph::Graph::new();
    g.nodes = vec![
        lumagraph::graph::Node::new("in", "ImageInput").with("path", ParamValue::Str(CHART.into())),
        lumagraph::graph::Node::new("c", "Crop")
            .with("x", int(500))
            .with("width", int(20)),
        lumagraph::graph::Node::new("out", "Output"),
    ];
    g.edges = vec![
        lumagraph::graph::Edge::new("in.color", "c.color"),
        lumagraph::graph::Edge::new("c.color", "out.color"),
    ];
    g.origin = None;
    let e = lumagraph::pathtrace::library::compile(&g, &[], None)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("node \"c\"") && e.contains("reaches past the 512x256 input"),
        "{e}"
    );
}
