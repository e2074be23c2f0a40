//! Blur and Bloom (nodes with their own passes and node-owned images) against their CPU
//! references on the HDR test chart. Both are sums of texels with positive weights, so the
//! f32 rounding error of a pixel is bounded by a small multiple of the same filter applied
//! to |texels|: each channel within 1e-5 × that + 1e-7 (measured worst printed per case as
//! a fraction of the bound). Bloom also keeps the image's mean (it spreads light).

use crate::common;

use common::{assert_within, run_node};
use lumagraph::graph::ParamValue;
use lumagraph::render::cpu::Image;
use lumagraph::render::image_io;

const CHART: &str = "assets/test_chart.exr";

/// An image as f64 channels.
#[derive(Clone)]
struct Img {
    w: usize,
    h: usize,
    p: Vec<[f64; 4]>,
}

impl Img {
    fn from(image: &Image) -> Self {
        Self {
            w: image.width as usize,
            h: image.height as usize,
            p: image.pixels.iter().map(|p| p.map(f64::from)).collect(),
        }
    }

    fn abs(&self) -> Self {
        Self {
            p: self.p.iter().map(|p| p.map(f64::abs)).collect(),
            ..self.clone()
        }
    }

    fn at(&self, x: i64, y: i64) -> [f64; 4] {
        let x = x.clamp(0, self.w as i64 - 1) as usize;
        let y = y.clamp(0, self.h as i64 - 1) as usize;
        self.p[y * self.w + x]
    }

    fn to_image(&self) -> Image {
        Image {
            width: self.w as u32,
            height: self.h as u32,
            pixels: self.p.iter().map(|p| p.map(|v| v as f32)).collect(),
        }
    }
}

/// One separable Gaussian pass along `axis`.
fn blur_pass(img: &Img, sigma: f64, axis: usize) -> Img {
    let r = (3.0 * sigma).ceil() as i64;
    let mut out = img.clone();
    for y in 0..img.h {
        for x in 0..img.w {
            let mut sum = [0.0; 4];
            let mut weight = 0.0;
            for d in -r..=r {
                let w = (-((d * d) as f64) / (2.0 * sigma * sigma)).exp();
                let (dx, dy) = if axis == 0 { (d, 0) } else { (0, d) };
                let t = img.at(x as i64 + dx, y as i64 + dy);
                for c in 0..4 {
                    sum[c] += w * t[c];
                }
                weight += w;
            }
            out.p[y * img.w + x] = sum.map(|s| s / weight);
        }
    }
    out
}

fn blur(img: &Img, sigma: f64) -> Img {
    blur_pass(&blur_pass(img, sigma, 0), sigma, 1)
}

fn down(img: &Img) -> Img {
    let (w, h) = (img.w.div_ceil(2), img.h.div_ceil(2));
    let k = [0.125, 0.375, 0.375, 0.125];
    let mut p = Vec::with_capacity(w * h);
    for y in 0..h {
        for x in 0..w {
            let mut sum = [0.0; 4];
            for j in 0..4 {
                for i in 0..4 {
                    let t = img.at(2 * x as i64 - 1 + i as i64, 2 * y as i64 - 1 + j as i64);
                    for c in 0..4 {
                        sum[c] += k[i] * k[j] * t[c];
                    }
                }
            }
            p.push(sum);
        }
    }
    Img { w, h, p }
}

/// a × fine + b × bilinear(coarse), coarse taken as half fine's resolution.
fn up_add(fine: &Img, coarse: &Img, a: f64, b: f64) -> Img {
    let mut out = fine.clone();
    for y in 0..fine.h {
        for x in 0..fine.w {
            let (cx, cy) = ((x as f64 + 0.5) * 0.5 - 0.5, (y as f64 + 0.5) * 0.5 - 0.5);
            let (x0, y0) = (cx.floor(), cy.floor());
            let (fx, fy) = (cx - x0, cy - y0);
            let (x0, y0) = (x0 as i64, y0 as i64);
            let q = [
                coarse.at(x0, y0),
                coarse.at(x0 + 1, y0),
                coarse.at(x0, y0 + 1),
                coarse.at(x0 + 1, y0 + 1),
            ];
            let i = y * fine.w + x;
            for c in 0..4 {
                let up = (q[0][c] * (1.0 - fx) + q[1][c] * fx) * (1.0 - fy)
                    + (q[2][c] * (1.0 - fx) + q[3][c] * fx) * fy;
                out.p[i][c] = a * fine.p[i][c] + b * up;
            }
        }
    }
    out
}

fn bloom(img: &Img, intensity: f64, levels: usize) -> Img {
    let mut pyramid = vec![down(img)];
    while pyramid.len() < levels
        && !(pyramid.last().unwrap().w == 1 && pyramid.last().unwrap().h == 1)
    {
        pyramid.push(down(pyramid.last().unwrap()));
    }
    let n = pyramid.len();
    let mut sum = pyramid[n - 1].clone();
    for i in (0..n - 1).rev() {
        sum = up_add(&pyramid[i], &sum, 1.0, 1.0);
    }
    up_add(img, &sum, 1.0 - intensity, intensity / n as f64)
}

#[test]
fn blur_matches_cpu() {
    let image = image_io::load(&common::repo(CHART)).unwrap();
    let img = Img::from(&image);
    for sigma in [0.3, 2.0, 7.5] {
        let Some(got) = run_node(
            "Blur",
            &[("sigma", ParamValue::Float(sigma))],
            &[("color", CHART)],
        ) else {
            return;
        };
        let want = blur(&img, sigma);
        let scale = blur(&img.abs(), sigma);
        assert_within(
            &format!("Blur σ {sigma}"),
            &got,
            &want.to_image(),
            |i, c| 1e-5 * scale.p[i][c] + 1e-7,
        );
    }
}

#[test]
fn bloom_matches_cpu_and_keeps_the_mean() {
    let image = image_io::load(&common::repo(CHART)).unwrap();
    let img = Img::from(&image);
    for (intensity, levels) in [(0.04, 6), (0.5, 1), (1.0, 12)] {
        let params = [
            ("intensity", ParamValue::Float(intensity)),
            ("levels", ParamValue::Int(levels)),
        ];
        let Some(got) = run_node("Bloom", &params, &[("color", CHART)]) else {
            return;
        };
        let want = bloom(&img, intensity, levels as usize);
        let scale = bloom(&img.abs(), intensity, levels as usize);
        assert_within(
            &format!("Bloom {intensity} over {levels} levels"),
            &got,
            &want.to_image(),
            |i, c| 1e-5 * scale.p[i][c] + 1e-7,
        );
        // Energy: the mean of each channel is kept to 1 % (light spread past the edges is
        // clamped back in, so not exactly).
        for c in 0..3 {
            let mean = |p: &mut dyn Iterator<Item = f64>| p.sum::<f64>() / img.p.len() as f64;
            let before = mean(&mut img.p.iter().map(|p| p[c]));
            let after = mean(&mut got.pixels.iter().map(|p| f64::from(p[c])));
            assert!(
                (after / before - 1.0).abs() < 0.01,
                "channel {c}: mean {before} → {after}"
            );
        }
    }
}
