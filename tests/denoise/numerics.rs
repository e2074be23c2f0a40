//! Numerical care of the Denoise node: every degenerate input gives a finite image.
//!
//! The color comes from an EXR written by the test (through `ImageInput` → `Accumulate`, so
//! the variance input is Accumulate's own), the guides from `GBuffer` on the Cornell box:
//! - every sigma at its minimum, 0 (guided and unguided);
//! - zero variance (two identical frames): finite, and the image is kept as it is, since
//!   no neighbor's luminance is within 0 standard deviations;
//! - black input: exactly black output;
//! - NaN and ±Inf pixels in the color: finite everywhere. (Accumulate's variance of such a
//!   pixel comes out 0 or Inf, not NaN, on lavapipe: `max(NaN, 0)` is 0 there; the filter
//!   sanitizes every input it loads anyway.)

use crate::common;

use std::sync::Arc;

use lumagraph::graph::{Node, ParamValue};
use lumagraph::pathtrace::library::compile;
use lumagraph::render::cpu::Image;
use lumagraph::render::{Resources, image_io};
use lumagraph::scene::{GpuScene, Scene};

const SIZE: u32 = 256;

/// A deterministic noisy image in [0, 2).
fn noise() -> Image {
    let pixels = (0..SIZE * SIZE)
        .map(|i| {
            let h = |k: u32| {
                let x = (i ^ (k << 24)).wrapping_mul(0x9e37_79b9).rotate_left(13);
                #[expect(clippy::cast_precision_loss, reason = "test data")]
                let v = x.wrapping_mul(0x85eb_ca6b) as f32 / u32::MAX as f32;
                2.0 * v
            };
            [h(1), h(2), h(3), 1.0]
        })
        .collect();
    Image {
        width: SIZE,
        height: SIZE,
        pixels,
    }
}

/// Runs `frames` frames of `ImageInput`(`color`) → `Accumulate` → `Denoise`(`params`);
/// returns the filtered image, Accumulate's variance and its mean (Denoise's color input).
fn denoise(
    color: &Image,
    frames: u32,
    params: &[(&str, ParamValue)],
) -> Option<(Image, Image, Image)> {
    let ctx = common::gpu()?;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("color.exr");
    std::fs::write(&path, image_io::encode_exr(color, false).unwrap()).unwrap();
    let scene = Scene::load(&common::repo("assets/cornell.ron")).unwrap();
    let scene = Arc::new(GpuScene::build(&scene).unwrap());
    let source = Node::new("img", "ImageInput")
        .with("path", ParamValue::Str(path.to_string_lossy().into_owned()));
    let graph = common::denoise_graph(source, params);
    let plan = compile(
        &graph,
        &["dn.color".into(), "acc.variance".into(), "acc.color".into()],
        Some(&scene),
    )
    .unwrap();
    let resources = Resources {
        scene: Some(scene),
        ..Resources::default()
    };
    let mut exec = lumagraph::pathtrace::library::executor(ctx, plan, &resources).unwrap();
    exec.run_frames(frames, true).unwrap();
    Some((
        exec.read_port("dn.color").unwrap(),
        exec.read_port("acc.variance").unwrap(),
        exec.read_port("acc.color").unwrap(),
    ))
}

fn assert_finite(image: &Image, what: &str) {
    let bad = image
        .pixels
        .iter()
        .filter(|p| p.iter().any(|v| !v.is_finite()))
        .count();
    assert_eq!(bad, 0, "{what}: {bad} pixels not finite");
}

#[test]
fn sigmas_at_zero_give_finite_output() {
    for guided in [true, false] {
        let params = [
            ("sigma_color", ParamValue::Float(0.0)),
            ("sigma_normal", ParamValue::Float(0.0)),
            ("sigma_depth", ParamValue::Float(0.0)),
            ("variance_guided", ParamValue::Bool(guided)),
        ];
        let Some((out, ..)) = denoise(&noise(), 2, &params) else {
            return;
        };
        assert_finite(&out, &format!("sigmas 0, guided {guided}"));
    }
}

#[test]
fn zero_variance_keeps_the_image() {
    let input = noise();
    let Some((out, variance, _)) = denoise(&input, 2, &[]) else {
        return;
    };
    assert!(
        variance.pixels.iter().all(|p| p == &[0.0; 4]),
        "two identical frames must have zero variance"
    );
    assert_finite(&out, "zero variance");
    let worst = out
        .pixels
        .iter()
        .zip(&input.pixels)
        .flat_map(|(o, i)| (0..3).map(move |c| (o[c] - i[c]).abs() / i[c].max(1e-3)))
        .fold(0.0_f32, f32::max);
    assert!(
        worst < 1e-4,
        "zero variance changed a pixel by {worst} (relative)"
    );
}

#[test]
fn black_input_gives_black_output() {
    let black = Image {
        width: SIZE,
        height: SIZE,
        pixels: vec![[0.0, 0.0, 0.0, 1.0]; (SIZE * SIZE) as usize],
    };
    // 1 pass (no ping-pong), 2 (one image of each), 8 (the most, taps 128 px apart).
    for iterations in [1, 2, 8] {
        let Some((out, ..)) = denoise(&black, 2, &[("iterations", ParamValue::Int(iterations))])
        else {
            return;
        };
        assert_finite(&out, "black");
        assert!(
            out.pixels.iter().all(|p| p[..3] == [0.0; 3]),
            "{iterations} iterations"
        );
    }
}

#[test]
fn nan_and_inf_input_give_finite_output() {
    let mut input = noise();
    for (i, p) in input.pixels.iter_mut().enumerate() {
        if i % 7 == 0 {
            p[0] = f32::NAN;
        }
        if i % 11 == 0 {
            p[1] = f32::INFINITY;
        }
        if i % 13 == 0 {
            p[2] = f32::NEG_INFINITY;
        }
    }
    for guided in [true, false] {
        let Some((out, _, mean)) =
            denoise(&input, 3, &[("variance_guided", ParamValue::Bool(guided))])
        else {
            return;
        };
        assert!(
            mean.pixels.iter().flatten().any(|v| v.is_nan()),
            "the color input should carry the NaNs"
        );
        assert_finite(&out, &format!("NaN/Inf input, guided {guided}"));
    }
}
