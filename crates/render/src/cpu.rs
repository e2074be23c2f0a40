//! Plain-Rust reference implementations of the GPU post nodes and the à-trous filter,
//! written to mirror the WGSL line for line. Tests run both and compare.

/// An image as linear RGBA `f32`, row-major, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width * height` RGBA pixels.
    pub pixels: Vec<[f32; 4]>,
}

impl Image {
    /// An image filled with one value.
    pub fn filled(width: u32, height: u32, value: [f32; 4]) -> Self {
        Self {
            width,
            height,
            pixels: vec![value; width as usize * height as usize],
        }
    }

    /// Applies `f` to every pixel.
    #[must_use]
    pub fn map(&self, f: impl Fn([f32; 4]) -> [f32; 4]) -> Self {
        Self {
            width: self.width,
            height: self.height,
            pixels: self.pixels.iter().map(|&p| f(p)).collect(),
        }
    }
}

mod regression;
pub use regression::{RegressionParams, regression};
pub mod temporal;

type V3 = [f32; 3];

fn rgb(p: [f32; 4]) -> V3 {
    [p[0], p[1], p[2]]
}

fn map3(v: V3, f: impl Fn(f32) -> f32) -> V3 {
    [f(v[0]), f(v[1]), f(v[2])]
}

/// Rec. 709 luminance.
pub fn luminance(c: V3) -> f32 {
    c[0] * 0.2126 + c[1] * 0.7152 + c[2] * 0.0722
}

/// Linear → sRGB and sRGB → linear transfers, clamped to \[0, 1\] (the scene crate's:
/// textures and vertex colours are decoded with them).
pub use lumagraph_scene::texture::{srgb_decode, srgb_encode};

/// Quantizes a value in \[0, 1\] to 8 bits, rounding to nearest.
#[expect(
    clippy::cast_possible_truncation,
    clippy::cast_sign_loss,
    reason = "clamped to [0, 255]"
)]
pub fn to_u8(x: f32) -> u8 {
    (x.clamp(0.0, 1.0) * 255.0).round() as u8
}

/// Exposure: scales color by `scale` (= 2^ev), alpha unchanged.
pub fn exposure(image: &Image, scale: f32) -> Image {
    image.map(|p| [p[0] * scale, p[1] * scale, p[2] * scale, p[3]])
}

/// The scale an exposure of `ev` stops applies, in `f32` as the GPU receives it.
#[expect(clippy::cast_possible_truncation, reason = "GPU math is f32")]
pub fn exposure_scale(ev: f64) -> f32 {
    ev.exp2() as f32
}

fn mul_rows(v: V3, rows: [V3; 3]) -> V3 {
    // v * M in WGSL where M's columns are `rows`: out_i = dot(v, rows[i]).
    [0, 1, 2].map(|i| v[0] * rows[i][0] + v[1] * rows[i][1] + v[2] * rows[i][2])
}

fn mul_cols(cols: [V3; 3], v: V3) -> V3 {
    // M * v in WGSL where M's columns are `cols`.
    [0, 1, 2].map(|i| cols[0][i] * v[0] + cols[1][i] * v[1] + cols[2][i] * v[2])
}

fn reinhard(c: V3, white: f32) -> V3 {
    let l = luminance(c);
    if l <= 0.0 {
        return [0.0; 3];
    }
    let ld = l * (1.0 + l / (white * white)) / (1.0 + l);
    map3(c, |x| x * (ld / l))
}

fn aces(c: V3) -> V3 {
    let input = [
        [0.59719, 0.35458, 0.04823],
        [0.07600, 0.90834, 0.01566],
        [0.02840, 0.13383, 0.83777],
    ];
    let output = [
        [1.60475, -0.53108, -0.07367],
        [-0.10208, 1.10813, -0.00605],
        [-0.00327, -0.07276, 1.07602],
    ];
    let v = mul_rows(c, input);
    let fit = map3(v, |v| {
        (v * (v + 0.024_578_6) - 0.000_090_537) / (v * (0.983_729 * v + 0.432_951) + 0.238_081)
    });
    mul_rows(fit, output)
}

fn agx_contrast(x: f32) -> f32 {
    let x2 = x * x;
    let x4 = x2 * x2;
    15.5 * x4 * x2 - 40.14 * x4 * x + 31.96 * x4 - 6.868 * x2 * x + 0.4298 * x2 + 0.1191 * x
        - 0.00232
}

fn agx(c: V3) -> V3 {
    let inset = [
        [0.842_479_1, 0.042_328_24, 0.042_375_655],
        [0.078_433_6, 0.878_468_6, 0.078_433_6],
        [0.079_223_745, 0.079_166_13, 0.879_143],
    ];
    let outset = [
        [1.196_879, -0.052_896_85, -0.052_971_635],
        [-0.098_020_88, 1.151_903_1, -0.098_043_45],
        [-0.099_029_74, -0.098_961_18, 1.151_073_7],
    ];
    let (min_ev, max_ev) = (-12.473_93_f32, 4.026_069_f32);
    let v = mul_cols(inset, map3(c, |x| x.max(1e-10)));
    let v = map3(v, |x| {
        (x.max(1e-10).log2().clamp(min_ev, max_ev) - min_ev) / (max_ev - min_ev)
    });
    let v = mul_cols(outset, map3(v, agx_contrast));
    map3(v, |x| x.max(0.0).powf(2.2))
}

fn pbr_neutral(mut c: V3) -> V3 {
    let start = 0.8 - 0.04;
    let desaturation = 0.15;
    let x = c[0].min(c[1].min(c[2]));
    let offset = if x < 0.08 { x - 6.25 * x * x } else { 0.04 };
    c = map3(c, |v| v - offset);
    let peak = c[0].max(c[1].max(c[2]));
    if peak < start {
        return c;
    }
    let d = 1.0 - start;
    let new_peak = 1.0 - d * d / (peak + d - start);
    c = map3(c, |v| v * (new_peak / peak));
    let g = 1.0 - 1.0 / (desaturation * (peak - new_peak) + 1.0);
    map3(c, |v| v + (new_peak - v) * g)
}

/// Applies tone curve number `op` (the registry's operator order) to linear color, clamped.
pub fn tonemap_curve(c: V3, op: u32, white: f32) -> V3 {
    let c = map3(c, |x| x.max(0.0));
    let out = match op {
        1 => reinhard(c, white),
        2 => aces(c),
        3 => agx(c),
        4 => pbr_neutral(c),
        _ => c,
    };
    map3(out, |x| x.clamp(0.0, 1.0))
}

/// The Tonemap node: tone curve then sRGB encoding, as floats in \[0, 1\] (before 8-bit storage).
pub fn tonemap(image: &Image, op: u32, white: f32) -> Image {
    image.map(|p| {
        let d = map3(tonemap_curve(rgb(p), op, white), srgb_encode);
        [d[0], d[1], d[2], p[3].clamp(0.0, 1.0)]
    })
}

/// Kahan-compensated running mean, per channel, exactly as `post/accumulate.wgsl` does it.
#[derive(Clone, Debug, Default)]
pub struct KahanMean {
    sum: [f32; 3],
    comp: [f32; 3],
    frames: f32,
}

impl KahanMean {
    /// Adds one frame's value.
    pub fn add(&mut self, x: [f32; 3]) {
        for ((s, c), x) in self.sum.iter_mut().zip(&mut self.comp).zip(x) {
            let y = x - *c;
            let t = *s + y;
            *c = (t - *s) - y;
            *s = t;
        }
        self.frames += 1.0;
    }

    /// The mean so far.
    pub fn mean(&self) -> [f32; 3] {
        self.sum.map(|s| s / self.frames)
    }
}

/// Params of the à-trous filter, as the `Denoise` node's.
#[derive(Clone, Copy, Debug)]
pub struct DenoiseParams {
    /// Filter passes (taps 1, 2, 4… pixels apart).
    pub iterations: u32,
    /// Luminance tolerance.
    pub sigma_color: f32,
    /// Normal tolerance.
    pub sigma_normal: f32,
    /// Depth tolerance.
    pub sigma_depth: f32,
    /// Scale the luminance tolerance by the standard deviation.
    pub variance_guided: bool,
}

fn finite4(p: [f32; 4]) -> [f32; 4] {
    p.map(|v| if v.is_finite() { v } else { 0.0 })
}

/// The depth gradient at (x, y): per axis the one-sided difference of smaller magnitude
/// (0 at the image's edge on both sides), as the GPU filter computes it.
fn depth_gradient(depth: &Image, x: i32, y: i32) -> [f32; 2] {
    let (w, h) = (depth.width as i32, depth.height as i32);
    let z = |x: i32, y: i32| {
        (x >= 0 && y >= 0 && x < w && y < h).then(|| finite4(depth.pixels[(y * w + x) as usize])[0])
    };
    let z_p = z(x, y).unwrap_or(0.0);
    [(1, 0), (0, 1)].map(|(ex, ey)| {
        let forward = z(x + ex, y + ey).map(|q| q - z_p);
        let backward = z(x - ex, y - ey).map(|q| z_p - q);
        match (forward, backward) {
            (Some(f), Some(b)) => {
                if b.abs() < f.abs() {
                    b
                } else {
                    f
                }
            }
            (Some(d), None) | (None, Some(d)) => d,
            (None, None) => 0.0,
        }
    })
}

/// The variance (alpha of `cur`) at (x, y) blurred by the 3×3 binomial kernel over the
/// pixels inside the image, clamped at 0.
fn blurred_variance(cur: &[[f32; 4]], width: u32, height: u32, x: i32, y: i32) -> f32 {
    let (w, h) = (width as i32, height as i32);
    let (mut sum, mut wsum) = (0.0, 0.0);
    for dy in -1..=1 {
        for dx in -1..=1 {
            let (qx, qy) = (x + dx, y + dy);
            if qx >= 0 && qy >= 0 && qx < w && qy < h {
                let wt = if dx == 0 { 0.5 } else { 0.25 } * if dy == 0 { 0.5 } else { 0.25 };
                sum += wt * finite4(cur[(qy * w + qx) as usize])[3];
                wsum += wt;
            }
        }
    }
    (sum / wsum).max(0.0)
}

/// The à-trous filter of `shaders/post/denoise.wgsl`, mirrored: demodulation, then
/// `iterations` passes, then remodulation. Depth is read from channel 0 of `depth`; an albedo
/// alpha above 1.5 marks an emitter, which shares no taps with other pixels.
///
/// # Panics
/// When the images differ in size.
pub fn denoise(
    color: &Image,
    variance: &Image,
    albedo: &Image,
    normal: &Image,
    depth: &Image,
    params: &DenoiseParams,
) -> Image {
    const EPS: f32 = 1e-3;
    const KERNEL: [f32; 3] = [0.375, 0.25, 0.0625];
    let (w, h) = (color.width as i32, color.height as i32);
    for other in [variance, albedo, normal, depth] {
        assert_eq!((other.width, other.height), (color.width, color.height));
    }
    let idx = |x: i32, y: i32| (y * w + x) as usize;
    let inside = |x: i32, y: i32| x >= 0 && y >= 0 && x < w && y < h;
    let alb = |i: usize| map3(rgb(finite4(albedo.pixels[i])), |v| v.max(EPS));
    let z = |i: usize| finite4(depth.pixels[i])[0];
    let nrm = |i: usize| rgb(finite4(normal.pixels[i]));
    let emitter = |i: usize| finite4(albedo.pixels[i])[3] > 1.5;
    let dot3 = |a: V3, b: V3| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    // Demodulation.
    let mut cur: Vec<[f32; 4]> = (0..color.pixels.len())
        .map(|i| {
            let s = finite4(color.pixels[i]);
            let a = alb(i);
            let v = finite4(variance.pixels[i])[3].max(0.0);
            let la = luminance(a).max(EPS);
            let c = [
                s[0].max(0.0) / a[0],
                s[1].max(0.0) / a[1],
                s[2].max(0.0) / a[2],
            ];
            finite4([c[0], c[1], c[2], v / (la * la)])
        })
        .collect();
    for pass in 0..params.iterations {
        let step = 1_i32 << pass;
        let last = pass + 1 == params.iterations;
        let scale = 0.5_f32.powi(pass as i32);
        let mut next = cur.clone();
        for y in 0..h {
            for x in 0..w {
                let i = idx(x, y);
                let center = finite4(cur[i]);
                let l_p = luminance(rgb(center));
                let n_p = nrm(i);
                let z_p = z(i);
                let grad = depth_gradient(depth, x, y);
                let s = if params.variance_guided {
                    blurred_variance(&cur, color.width, color.height, x, y).sqrt()
                } else {
                    scale
                };
                let l_denom = params.sigma_color * s + 1e-6;
                let n_denom = params.sigma_normal.max(1e-6);
                let z_eps = 1e-3 * z_p + 1e-6;
                let h0 = KERNEL[0] * KERNEL[0];
                let mut acc = [h0 * center[0], h0 * center[1], h0 * center[2]];
                let mut var_sum = h0 * h0 * center[3];
                let mut wsum = h0;
                for dy in -2_i32..=2 {
                    for dx in -2_i32..=2 {
                        let (qx, qy) = (x + dx * step, y + dy * step);
                        if (dx == 0 && dy == 0) || !inside(qx, qy) {
                            continue;
                        }
                        let q = idx(qx, qy);
                        if emitter(q) != emitter(i) {
                            continue;
                        }
                        let c = finite4(cur[q]);
                        let hk =
                            KERNEL[dx.unsigned_abs() as usize] * KERNEL[dy.unsigned_abs() as usize];
                        let w_l = (l_p - luminance(rgb(c))).abs() / l_denom;
                        let w_n = (1.0 - dot3(n_p, nrm(q))).max(0.0) / n_denom;
                        #[expect(clippy::cast_precision_loss, reason = "small offsets")]
                        let off = [(dx * step) as f32, (dy * step) as f32];
                        let z_scale = params.sigma_depth
                            * (grad[0] * off[0] + grad[1] * off[1]).abs()
                            + z_eps;
                        let w_z = (z_p - z(q)).abs() / z_scale;
                        let wt = hk * (-(w_l + w_n + w_z)).exp();
                        for k in 0..3 {
                            acc[k] += wt * c[k];
                        }
                        var_sum += wt * wt * c[3];
                        wsum += wt;
                    }
                }
                let mut out = finite4([
                    acc[0] / wsum,
                    acc[1] / wsum,
                    acc[2] / wsum,
                    var_sum / (wsum * wsum),
                ]);
                if last {
                    let a = alb(i);
                    out = [out[0] * a[0], out[1] * a[1], out[2] * a[2], 1.0];
                }
                next[i] = out;
            }
        }
        cur = next;
    }
    Image {
        width: color.width,
        height: color.height,
        pixels: cur,
    }
}

/// Bins of the `AutoExposure` histogram, and the log2 luminance range they cover
/// (`shaders/post/luminance_bins.wgsl`).
pub const HISTOGRAM_BINS: usize = 256;
const LOG2_LUMINANCE_MIN: f32 = -24.0;
const LOG2_LUMINANCE_MAX: f32 = 16.0;

/// The histogram bin of linear color `c`, or `None` when its luminance is not finite.
pub fn luminance_bin(c: V3) -> Option<usize> {
    let l = luminance(map3(c, |v| v.max(0.0)));
    if !l.is_finite() {
        return None;
    }
    if l <= LOG2_LUMINANCE_MIN.exp2() {
        return Some(0);
    }
    let t = (l.log2() - LOG2_LUMINANCE_MIN) / (LOG2_LUMINANCE_MAX - LOG2_LUMINANCE_MIN);
    #[expect(clippy::cast_precision_loss, reason = "256")]
    let top = (HISTOGRAM_BINS - 1) as f32;
    #[expect(clippy::cast_possible_truncation, reason = "clamped to [0, 255]")]
    #[expect(clippy::cast_sign_loss, reason = "clamped to [0, 255]")]
    Some((t * HISTOGRAM_BINS as f32).clamp(0.0, top) as usize)
}

/// The log2 luminance at the middle of histogram bin `i`.
#[expect(clippy::cast_precision_loss, reason = "i < 256")]
pub fn bin_center(i: usize) -> f32 {
    let width = (LOG2_LUMINANCE_MAX - LOG2_LUMINANCE_MIN) / HISTOGRAM_BINS as f32;
    LOG2_LUMINANCE_MIN + (i as f32 + 0.5) * width
}

/// The luminance histogram of `image` (pixels whose luminance is not finite left out).
pub fn luminance_histogram(image: &Image) -> Vec<u32> {
    let mut bins = vec![0; HISTOGRAM_BINS];
    for p in &image.pixels {
        if let Some(b) = luminance_bin(rgb(*p)) {
            bins[b] += 1;
        }
    }
    bins
}

/// The exposure, in stops, `AutoExposure` aims for on `bins`: the mean log2 luminance of
/// the pixels between the `low` and `high` fractions of the count mapped to `key`, clamped
/// to `[min_ev, max_ev]`; `None` for an empty histogram (the node keeps its last value).
/// The node passes `high ≥ low` and `max_ev ≥ min_ev` ([`auto_exposure_ranges`]).
pub fn auto_exposure_target(
    bins: &[u32],
    key: f32,
    [low, high]: [f32; 2],
    [min_ev, max_ev]: [f32; 2],
) -> Option<f32> {
    #[expect(clippy::cast_precision_loss, reason = "as the shader: f32 counts")]
    let counts: Vec<f32> = bins.iter().map(|&n| n as f32).collect();
    let total: f32 = counts.iter().sum();
    if total == 0.0 {
        return None;
    }
    let (lo, hi) = (total * low, total * high);
    let (mut below, mut sum, mut weight) = (0.0_f32, 0.0_f32, 0.0_f32);
    for (i, n) in counts.iter().enumerate() {
        let take = (below + n).clamp(lo, hi) - below.clamp(lo, hi);
        sum += take * bin_center(i);
        weight += take;
        below += n;
    }
    let mean = if weight > 0.0 {
        sum / weight
    } else {
        bin_center(0)
    };
    Some((key.log2() - mean).clamp(min_ev, max_ev))
}

/// The percentile and exposure ranges as `AutoExposure` uses them: a `high` below `low` is
/// taken as `low`, a `max_ev` below `min_ev` as `min_ev`.
pub fn auto_exposure_ranges(low: f32, high: f32, min_ev: f32, max_ev: f32) -> [[f32; 2]; 2] {
    [[low, high.max(low)], [min_ev, max_ev.max(min_ev)]]
}
