//! The image metrics on known cases (no GPU): SSIM is 1 for identical images, falls with
//! noise, and ignores what clipping hides; relMSE and RMSE of known offsets.

use lumagraph::render::cpu::Image;
use lumagraph::render::metrics;

fn ramp(offset: f32, noise: f32) -> Image {
    let (w, h) = (64_u32, 48_u32);
    let pixels = (0..w * h)
        .map(|i| {
            #[expect(clippy::cast_precision_loss, reason = "test data")]
            let x = (i % w) as f32 / w as f32;
            let n = if i.wrapping_mul(2_654_435_761).rotate_left(7) % 2 == 0 {
                noise
            } else {
                -noise
            };
            let v = x * 0.8 + offset + n;
            [v, v, v, 1.0]
        })
        .collect();
    Image {
        width: w,
        height: h,
        pixels,
    }
}

#[test]
fn ssim_of_identical_and_noisy_images() {
    let a = ramp(0.1, 0.0);
    assert!((metrics::ssim(&a, &a) - 1.0).abs() < 1e-9);
    let slightly = metrics::ssim(&ramp(0.1, 0.02), &a);
    let very = metrics::ssim(&ramp(0.1, 0.1), &a);
    assert!(slightly < 1.0 && very < slightly, "{slightly} {very}");
    // Values above 1 are clipped: two images that differ only there score 1.
    let (b, c) = (ramp(2.0, 0.0), ramp(3.0, 0.0));
    assert!((metrics::ssim(&b, &c) - 1.0).abs() < 1e-9);
}

#[test]
fn rmse_and_relmse_of_an_offset() {
    let (a, b) = (ramp(0.1, 0.0), ramp(0.2, 0.0));
    assert!((metrics::rmse(&b, &a) - 0.1).abs() < 1e-6);
    let rel = metrics::relmse(&b, &a);
    assert!(rel > 0.0 && rel < 0.01 / 0.01, "{rel}");
}
