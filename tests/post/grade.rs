//! The colour-grading post filters (generic post filters: a registry entry, a shader and
//! the CPU reference here each) against their CPU references on the HDR test chart, at
//! their defaults (which must change nothing) and at settings far from them.
//!
//! The references compute in f64 what the shaders compute in f32; each channel must be
//! within 1e-5 relative (plus an absolute floor for values near 0) unless a node says
//! otherwise below. `pow` and `exp`/`log` on GPUs are accurate to a few ulps; 1e-5 is
//! ~80 ulps, measured at most ~1e-6 on lavapipe (printed per case as a fraction of the
//! bound).

use crate::common;

use common::{assert_within, map_pixels, run_node};
use lumagraph::graph::ParamValue;
use lumagraph::render::image_io;

const CHART: &str = "assets/test_chart.exr";

fn chart() -> lumagraph::render::cpu::Image {
    image_io::load(&common::repo(CHART)).unwrap()
}

fn floats(params: &[(&'static str, f64)]) -> Vec<(&'static str, ParamValue)> {
    params
        .iter()
        .map(|(k, v)| (*k, ParamValue::Float(*v)))
        .collect()
}

/// Relative bound `rel` on the reference's value, `abs` floor.
fn relative(
    want: &lumagraph::render::cpu::Image,
    rel: f64,
    abs: f64,
) -> impl Fn(usize, usize) -> f64 {
    move |i, c| rel * f64::from(want.pixels[i][c].abs()) + abs
}

fn mat_vec(m: [[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|r| m[r][0] * v[0] + m[r][1] * v[1] + m[r][2] * v[2])
}

/// CIE 1960 uv of the Planckian locus (Krystek) and its derivative, at `t` kelvin.
fn planck(t: f64) -> ([f64; 2], [f64; 2]) {
    let rational = |n: [f64; 3], d: [f64; 2]| {
        let num = n[0] + n[1] * t + n[2] * t * t;
        let den = 1.0 + d[0] * t + d[1] * t * t;
        let dnum = n[1] + 2.0 * n[2] * t;
        let dden = d[0] + 2.0 * d[1] * t;
        (num / den, (dnum * den - num * dden) / (den * den))
    };
    let u = rational(
        [0.860_117_757, 1.541_182_54e-4, 1.286_412_12e-7],
        [8.424_202_35e-4, 7.081_451_63e-7],
    );
    let v = rational(
        [0.317_398_726, 4.228_062_45e-5, 4.204_816_91e-8],
        [-2.897_418_16e-5, 1.614_560_53e-7],
    );
    ([u.0, v.0], [u.1, v.1])
}

fn white_xyz(t: f64, tint: f64) -> [f64; 3] {
    let (p, d) = planck(t);
    let len = d[0].hypot(d[1]);
    let normal = [-d[1] / len, d[0] / len];
    let (u, v) = (
        p[0] + 0.02 * tint * normal[0],
        p[1] + 0.02 * tint * normal[1],
    );
    let x = 3.0 * u / (2.0 * u - 8.0 * v + 4.0);
    let y = 2.0 * v / (2.0 * u - 8.0 * v + 4.0);
    [x / y, 1.0, (1.0 - x - y) / y]
}

const RGB_TO_XYZ: [[f64; 3]; 3] = [
    [0.412_390_8, 0.357_584_3, 0.180_480_8],
    [0.212_639_0, 0.715_168_7, 0.072_192_3],
    [0.019_330_8, 0.119_194_8, 0.950_532_2],
];
const XYZ_TO_RGB: [[f64; 3]; 3] = [
    [3.240_969_9, -1.537_383_2, -0.498_610_8],
    [-0.969_243_6, 1.875_967_5, 0.041_555_1],
    [0.055_630_1, -0.203_977_0, 1.056_971_5],
];
const BRADFORD: [[f64; 3]; 3] = [
    [0.8951, 0.2664, -0.1614],
    [-0.7502, 1.7135, 0.0367],
    [0.0389, -0.0685, 1.0296],
];
const BRADFORD_INV: [[f64; 3]; 3] = [
    [0.986_992_9, -0.147_054_3, 0.159_962_7],
    [0.432_305_3, 0.518_360_3, 0.049_291_2],
    [-0.008_528_7, 0.040_042_8, 0.968_486_7],
];

#[test]
fn white_balance_matches_cpu() {
    let image = chart();
    for (t, tint) in [(6504.0, 0.0), (3200.0, 0.0), (9000.0, -0.6), (1800.0, 1.0)] {
        let params = floats(&[("temperature", t), ("tint", tint)]);
        let Some(got) = run_node("WhiteBalance", &params, &[("color", CHART)]) else {
            return;
        };
        let src = mat_vec(BRADFORD, white_xyz(t, tint));
        let dst = mat_vec(BRADFORD, white_xyz(6504.0, 0.0));
        let want = map_pixels(&image, |_, p| {
            let lms = mat_vec(BRADFORD, mat_vec(RGB_TO_XYZ, [p[0], p[1], p[2]]));
            let adapted = [0, 1, 2].map(|c| lms[c] * dst[c] / src[c]);
            let rgb = mat_vec(XYZ_TO_RGB, mat_vec(BRADFORD_INV, adapted));
            [rgb[0], rgb[1], rgb[2], p[3]]
        });
        // The three matrix products mix channels of different size: bound each channel
        // by the pixel's largest, not by its own value.
        let scale = |i: usize| {
            f64::from(
                image.pixels[i][..3]
                    .iter()
                    .fold(0.0_f32, |m, v| m.max(v.abs())),
            )
        };
        let bound = |i: usize, c: usize| if c == 3 { 0.0 } else { 2e-5 * scale(i) + 1e-7 };
        assert_within(
            &format!("WhiteBalance {t} K, tint {tint}"),
            &got,
            &want,
            bound,
        );
        if t == 6504.0 {
            assert_within("WhiteBalance defaults", &got, &image, bound);
        }
    }
    // Warm light is cooled: a 3200 K correction lowers red against blue.
    let Some(got) = run_node(
        "WhiteBalance",
        &floats(&[("temperature", 3200.0)]),
        &[("color", CHART)],
    ) else {
        return;
    };
    let sum = |img: &lumagraph::render::cpu::Image, c: usize| {
        img.pixels.iter().map(|p| f64::from(p[c])).sum::<f64>()
    };
    assert!(sum(&got, 0) / sum(&got, 2) < sum(&image, 0) / sum(&image, 2));
}

#[test]
fn cdl_matches_cpu() {
    let image = chart();
    let cases: [[f64; 10]; 3] = [
        [1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0],
        [1.2, 0.9, 0.7, 0.01, -0.02, 0.05, 0.8, 1.1, 1.4, 0.6],
        [0.5, 2.0, 1.0, -0.1, 0.0, 0.2, 2.2, 0.45, 1.0, 1.8],
    ];
    let names = [
        "slope_r",
        "slope_g",
        "slope_b",
        "offset_r",
        "offset_g",
        "offset_b",
        "power_r",
        "power_g",
        "power_b",
        "saturation",
    ];
    for v in cases {
        let params: Vec<_> = names.iter().zip(v).map(|(n, x)| (*n, x)).collect();
        let Some(got) = run_node("CDL", &floats(&params), &[("color", CHART)]) else {
            return;
        };
        let want = map_pixels(&image, |_, p| {
            let sop = [0, 1, 2].map(|c| (p[c] * v[c] + v[3 + c]).max(0.0).powf(v[6 + c]));
            let luma = 0.2126 * sop[0] + 0.7152 * sop[1] + 0.0722 * sop[2];
            let s = v[9];
            [0, 1, 2, 3].map(|c| {
                if c == 3 {
                    p[3]
                } else {
                    luma + s * (sop[c] - luma)
                }
            })
        });
        // Saturation subtracts the luma: bound by the largest channel of the graded pixel.
        let scale = |i: usize| {
            f64::from(
                want.pixels[i][..3]
                    .iter()
                    .fold(0.0_f32, |m, x| m.max(x.abs())),
            )
        };
        assert_within(&format!("CDL {v:?}"), &got, &want, |i, c| {
            1e-5 * scale(i).max(f64::from(want.pixels[i][c].abs())) + 1e-7
        });
    }
}

#[test]
fn contrast_matches_cpu() {
    let image = chart();
    for (contrast, pivot) in [(1.0, 0.18), (1.6, 0.18), (0.5, 1.0), (3.0, 0.05)] {
        let params = floats(&[("contrast", contrast), ("pivot", pivot)]);
        let Some(got) = run_node("Contrast", &params, &[("color", CHART)]) else {
            return;
        };
        let want = map_pixels(&image, |_, p| {
            [0, 1, 2, 3].map(|c| {
                if c == 3 {
                    p[3]
                } else {
                    pivot * (p[c].max(0.0) / pivot).powf(contrast)
                }
            })
        });
        assert_within(
            &format!("Contrast {contrast} around {pivot}"),
            &got,
            &want,
            relative(&want, 1e-5, 1e-7),
        );
    }
}

#[test]
fn hue_saturation_matches_cpu() {
    let image = chart();
    for (hue, saturation, value) in [
        (0.0, 1.0, 1.0),
        (120.0, 1.0, 1.0),
        (-45.0, 0.3, 2.0),
        (170.0, 2.5, 0.5),
    ] {
        let params = floats(&[("hue", hue), ("saturation", saturation), ("value", value)]);
        let Some(got) = run_node("HueSaturation", &params, &[("color", CHART)]) else {
            return;
        };
        let a = hue.to_radians();
        let k = 1.0 / 3.0_f64.sqrt();
        let want = map_pixels(&image, |_, p| {
            let grey = (p[0] + p[1] + p[2]) / 3.0;
            let d = [p[0] - grey, p[1] - grey, p[2] - grey];
            let cross = [k * (d[2] - d[1]), k * (d[0] - d[2]), k * (d[1] - d[0])];
            let r = [0, 1, 2].map(|c| d[c] * a.cos() + cross[c] * a.sin());
            let rgb = [0, 1, 2].map(|c| (value * (grey + saturation * r[c])).max(0.0));
            [rgb[0], rgb[1], rgb[2], p[3]]
        });
        // Rotation mixes channels: bound by the pixel's largest channel.
        let scale = |i: usize| {
            f64::from(
                image.pixels[i][..3]
                    .iter()
                    .fold(0.0_f32, |m, x| m.max(x.abs())),
            )
        };
        let bound = |i: usize, c: usize| {
            if c == 3 {
                0.0
            } else {
                1e-5 * value * saturation.max(1.0) * scale(i) + 1e-7
            }
        };
        assert_within(
            &format!("HueSaturation {hue}° ×{saturation} ×{value}"),
            &got,
            &want,
            bound,
        );
    }
}
