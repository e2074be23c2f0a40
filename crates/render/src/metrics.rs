//! Image error metrics, as the reference renders define them: over every pixel and RGB
//! channel, `rmse = sqrt(mean((x - ref)^2))` and `relmse = mean((x - ref)^2 / (ref^2 + 1e-2))`.

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
