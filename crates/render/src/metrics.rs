//! Image error metrics, as the reference renders define them: over every pixel and RGB
//! channel, `rmse = sqrt(mean((x - ref)^2))` and `relmse = mean((x - ref)^2 / (ref^2 + 1e-2))`;
//! and SSIM on clipped luminance ([`ssim`]).

use crate::cpu::Image;

fn pairs<'a>(a: &'a Image, b: &'a Image) -> impl Iterator<Item = (f64, f64)> + 'a {
    assert_eq!(
        (a.width, a.height),
        (b.width, b.height),
        "images differ in size"
    );
    a.pixels
        .iter()
        .zip(&b.pixels)
        .flat_map(|(p, q)| (0..3).map(move |c| (f64::from(p[c]), f64::from(q[c]))))
}

#[expect(clippy::cast_precision_loss, reason = "pixel counts")]
fn mean(sum: f64, image: &Image) -> f64 {
    sum / (image.pixels.len() * 3) as f64
}

/// Root mean squared error of `x` against `reference`.
///
/// # Panics
/// When the sizes differ.
pub fn rmse(x: &Image, reference: &Image) -> f64 {
    mean(pairs(x, reference).map(|(a, b)| (a - b) * (a - b)).sum(), x).sqrt()
}

/// Relative mean squared error of `x` against `reference`.
///
/// # Panics
/// When the sizes differ.
pub fn relmse(x: &Image, reference: &Image) -> f64 {
    mean(
        pairs(x, reference)
            .map(|(a, b)| (a - b) * (a - b) / (b * b + 1e-2))
            .sum(),
        x,
    )
}

/// Mean of each channel over `block`×`block` tiles, row-major: `[tile][channel]`.
pub fn block_means(image: &Image, block: u32) -> Vec<[f64; 3]> {
    let (bw, bh) = (image.width / block, image.height / block);
    let mut out = vec![[0.0; 3]; (bw * bh) as usize];
    for y in 0..bh * block {
        for x in 0..bw * block {
            let p = image.pixels[(y * image.width + x) as usize];
            let t = &mut out[((y / block) * bw + x / block) as usize];
            for c in 0..3 {
                t[c] += f64::from(p[c]);
            }
        }
    }
    let n = f64::from(block * block);
    for t in &mut out {
        for v in t.iter_mut() {
            *v /= n;
        }
    }
    out
}

/// Mean of each channel over the whole image.
pub fn channel_means(image: &Image) -> [f64; 3] {
    let mut m = [0.0; 3];
    for p in &image.pixels {
        for c in 0..3 {
            m[c] += f64::from(p[c]);
        }
    }
    #[expect(clippy::cast_precision_loss, reason = "pixel counts")]
    let n = image.pixels.len() as f64;
    m.map(|v| v / n)
}

/// Luminance (Rec. 709 weights) of each pixel, clipped to \[0, 1\] (non-finite values → 0).
fn clipped_luminance(image: &Image) -> Vec<f64> {
    image
        .pixels
        .iter()
        .map(|p| {
            let y = 0.2126 * f64::from(p[0]) + 0.7152 * f64::from(p[1]) + 0.0722 * f64::from(p[2]);
            if y.is_finite() {
                y.clamp(0.0, 1.0)
            } else {
                0.0
            }
        })
        .collect()
}

/// Separable Gaussian blur (σ = 1.5, 11 taps) with the window renormalized at the borders.
fn gaussian(v: &[f64], w: usize, h: usize) -> Vec<f64> {
    const R: isize = 5;
    let k: Vec<f64> = (-R..=R)
        .map(|i| {
            #[expect(clippy::cast_precision_loss, reason = "small offsets")]
            let x = i as f64;
            (-x * x / (2.0 * 1.5 * 1.5)).exp()
        })
        .collect();
    let pass = |src: &[f64], horizontal: bool| {
        let mut out = vec![0.0; src.len()];
        for y in 0..h {
            for x in 0..w {
                let (mut s, mut ws) = (0.0, 0.0);
                for (j, kw) in k.iter().enumerate() {
                    let d = j.cast_signed() - R;
                    let (u, v) = if horizontal {
                        (x.cast_signed() + d, y.cast_signed())
                    } else {
                        (x.cast_signed(), y.cast_signed() + d)
                    };
                    if u >= 0 && v >= 0 && u < w.cast_signed() && v < h.cast_signed() {
                        s += kw * src[v.cast_unsigned() * w + u.cast_unsigned()];
                        ws += kw;
                    }
                }
                out[y * w + x] = s / ws;
            }
        }
        out
    };
    pass(&pass(v, true), false)
}

/// Mean SSIM (Wang et al. 2004) of `x` against `reference`, on luminance clipped to
/// \[0, 1\] (dynamic range L = 1, so C1 = 0.01², C2 = 0.03²), with an 11×11 Gaussian window
/// of σ = 1.5 (renormalized at the borders). 1 means identical. Linear HDR values above 1
/// (light sources) count as 1: the index is about the image's visible structure, relMSE is
/// the HDR measure.
///
/// # Panics
/// When the sizes differ.
pub fn ssim(x: &Image, reference: &Image) -> f64 {
    assert_eq!(
        (x.width, x.height),
        (reference.width, reference.height),
        "images differ in size"
    );
    let (w, h) = (x.width as usize, x.height as usize);
    let (a, b) = (clipped_luminance(x), clipped_luminance(reference));
    let prod = |p: &[f64], q: &[f64]| p.iter().zip(q).map(|(u, v)| u * v).collect::<Vec<_>>();
    let (ma, mb) = (gaussian(&a, w, h), gaussian(&b, w, h));
    let (aa, bb, ab) = (
        gaussian(&prod(&a, &a), w, h),
        gaussian(&prod(&b, &b), w, h),
        gaussian(&prod(&a, &b), w, h),
    );
    let (c1, c2) = (0.01_f64.powi(2), 0.03_f64.powi(2));
    let sum: f64 = (0..w * h)
        .map(|i| {
            let (va, vb, cov) = (
                aa[i] - ma[i] * ma[i],
                bb[i] - mb[i] * mb[i],
                ab[i] - ma[i] * mb[i],
            );
            ((2.0 * ma[i] * mb[i] + c1) * (2.0 * cov + c2))
                / ((ma[i] * ma[i] + mb[i] * mb[i] + c1) * (va + vb + c2))
        })
        .sum();
    #[expect(clippy::cast_precision_loss, reason = "pixel counts")]
    let n = (w * h).max(1) as f64;
    sum / n
}
