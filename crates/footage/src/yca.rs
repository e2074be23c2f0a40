//! Luminance/chroma (YC) reconstruction, as `OpenEXR`'s `Imf::RgbaInputFile` does it.
//!
//! A luminance/chroma image stores luminance `Y` at full resolution and the chroma
//! differences `RY = (R - Y) / Y` and `BY = (B - Y) / Y` at half resolution both ways
//! (sampling 2 × 2), optionally with alpha `A`. `OpenEXR`'s `RgbaInputFile` (class
//! `FromYca`, with `ImfRgbaYca.cpp`) turns them back into RGBA; this module does the same
//! arithmetic in the same order, rounding to half floats where `OpenEXR` stores a half, so
//! its results match `OpenEXR`'s bit for bit:
//!
//! 1. every even line's missing chroma samples (odd x) are filled in by a 27-tap
//!    horizontal filter over the line's chroma samples, the line padded with copies of its
//!    first and last samples;
//! 2. the odd lines' chroma is filled in by the same filter run vertically over the even
//!    lines, the image padded by repeating the first line above and the second-to-last
//!    line below (`OpenEXR` clamps line `y < y_min` to `y_min`, `y > y_max` to `y_max - 1`);
//! 3. `R = (RY + 1) Y`, `B = (BY + 1) Y`, `G = (Y - R w_r - B w_b) / w_g` with the
//!    luminance weights of the file's primaries ([`luminance_weights`]), or `R = G = B = Y`
//!    where both chroma values are zero;
//! 4. pixels far more saturated than their neighbours above and below are desaturated
//!    towards them (`fixSaturation`), keeping their luminance.
//!
//! Luminance-only images (no `RY`, no `BY`) give `R = G = B = Y`, as `RgbaInputFile`
//! gives them.

use half::f16;

/// Why [`to_rgba`] refused its input.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A plane holds a different number of samples than the image needs.
    #[error(
        "channel {channel} holds {len} samples, not the {expected} a {width} × {height} image needs"
    )]
    Length {
        /// `"Y"`, `"RY"`, `"BY"` or `"A"`.
        channel: &'static str,
        /// Samples given.
        len: usize,
        /// Samples needed.
        expected: usize,
        /// The data window's width.
        width: usize,
        /// The data window's height.
        height: usize,
    },
    /// Chroma is present but the data window's size or position is odd, which
    /// 2 × 2 chroma sampling forbids.
    #[error(
        "a {width} × {height} data window at {origin:?} cannot hold 2 × 2 subsampled chroma: its size and position must be even"
    )]
    OddWindow {
        /// The data window's width.
        width: usize,
        /// The data window's height.
        height: usize,
        /// The data window's top-left corner.
        origin: (i32, i32),
    },
}

/// The Rec. 709 primaries and D65 white point, `OpenEXR`'s default chromaticities:
/// red, green, blue and white `(x, y)`.
pub const REC709: [f32; 8] = [0.64, 0.33, 0.30, 0.60, 0.15, 0.06, 0.3127, 0.3290];

/// The luminance weights `(w_r, w_g, w_b)` of the primaries `chromaticities` (red,
/// green, blue and white `(x, y)`, as in the `chromaticities` attribute), computed in
/// `f32` as `OpenEXR`'s `RgbaYca::computeYw` computes them: the middle row of
/// `RGBtoXYZ(chromaticities, 1)`, divided by its sum. `None` means Rec. 709
/// ([`REC709`]), `OpenEXR`'s default, giving about `(0.2126, 0.7152, 0.0722)`.
///
/// Primaries from which `OpenEXR` cannot build a matrix (white `y` zero, collinear
/// primaries), for which `RgbaInputFile` throws, give Rec. 709's weights too, as do any
/// that give weights that are not finite.
#[must_use]
pub fn luminance_weights(chromaticities: Option<[f32; 8]>) -> [f32; 3] {
    chromaticities
        .and_then(weights_of)
        .unwrap_or_else(|| weights_of(REC709).unwrap_or([0.2126, 0.7152, 0.0722]))
}

/// `computeYw`, with `RGBtoXYZ`'s checks; `None` where `OpenEXR` throws.
fn weights_of(c: [f32; 8]) -> Option<[f32; 3]> {
    let [rx, ry, gx, gy, bx, by, wx, wy] = c;
    let y = 1.0_f32;
    if wy.abs() <= 1.0 && (wx * y).abs() >= wy.abs() * f32::MAX {
        return None;
    }
    let x = wx * y / wy;
    let z = (1.0 - wx - wy) * y / wy;
    let d = rx * (by - gy) + bx * (gy - ry) + gx * (ry - by);
    let sr_n =
        x * (by - gy) - gx * (y * (by - 1.0) + by * (x + z)) + bx * (y * (gy - 1.0) + gy * (x + z));
    let sg_n =
        x * (ry - by) + rx * (y * (by - 1.0) + by * (x + z)) - bx * (y * (ry - 1.0) + ry * (x + z));
    let sb_n =
        x * (gy - ry) - rx * (y * (gy - 1.0) + gy * (x + z)) + gx * (y * (ry - 1.0) + ry * (x + z));
    let limit = d.abs() * f32::MAX;
    if d.abs() < 1.0 && (sr_n.abs() >= limit || sg_n.abs() >= limit || sb_n.abs() >= limit) {
        return None;
    }
    let (m01, m11, m21) = ((sr_n / d) * ry, (sg_n / d) * gy, (sb_n / d) * by);
    let sum = m01 + m11 + m21;
    let w = [m01 / sum, m11 / sum, m21 / sum];
    w.iter().all(|v| v.is_finite()).then_some(w)
}

/// A luminance/chroma image's planes over its data window, row-major from the top left.
///
/// Values are rounded to half floats first, as `RgbaInputFile` reads every plane into
/// halves; half values (such as a file's `HALF` channels widened to `f32`) pass unchanged.
#[derive(Clone, Copy, Debug)]
pub struct YcaInput<'a> {
    /// The data window's width.
    pub width: usize,
    /// The data window's height.
    pub height: usize,
    /// The data window's top-left corner, `(x_min, y_min)`: with chroma, both even.
    pub origin: (i32, i32),
    /// Luminance, `width * height` samples. (For a file with chroma but no `Y`,
    /// `RgbaInputFile` reads `Y` as 0.5 everywhere.)
    pub y: &'a [f32],
    /// `RY`, `(width / 2) * (height / 2)` samples; `None` (with `by` present) reads as 0.
    pub ry: Option<&'a [f32]>,
    /// `BY`, `(width / 2) * (height / 2)` samples; `None` (with `ry` present) reads as 0.
    pub by: Option<&'a [f32]>,
    /// Alpha, `width * height` samples; `None` reads as 1.
    pub a: Option<&'a [f32]>,
}

/// One pixel as `OpenEXR`'s `Rgba` holds it: four halves. In luminance/chroma form `r`
/// holds `RY`, `g` holds `Y` and `b` holds `BY`.
#[derive(Clone, Copy, Debug)]
struct Px {
    r: f16,
    g: f16,
    b: f16,
    a: f16,
}

/// The chroma reconstruction filter's 14 non-zero taps, at offsets −13, −11, … −1,
/// 1, … 13 from the sample being filled in (`reconstructChromaHoriz`/`Vert`).
const TAPS: [f32; 14] = [
    0.002128, -0.007540, 0.019597, -0.043159, 0.087929, -0.186077, 0.627123, 0.627123, -0.186077,
    0.087929, -0.043159, 0.019597, -0.007540, 0.002128,
];

/// `Σ sample(k) · TAPS[k]`, summed in `f32` from the first tap on, as `OpenEXR`'s
/// expression is.
fn filter(sample: impl Fn(usize) -> f32) -> f32 {
    (1..TAPS.len()).fold(sample(0) * TAPS[0], |sum, k| sum + sample(k) * TAPS[k])
}

/// The image's RGBA, `width * height` pixels row-major over the data window, each value
/// a half float widened to `f32`; alpha is 1 where `a` is `None`. Bit for bit what
/// `OpenEXR`'s `RgbaInputFile` gives (see the [module documentation](self)), with
/// `weights` from [`luminance_weights`].
///
/// # Errors
/// A plane of the wrong length, or chroma in an odd-sized or odd-placed data window.
pub fn to_rgba(input: &YcaInput, weights: [f32; 3]) -> Result<Vec<[f32; 4]>, Error> {
    let (w, h) = (input.width, input.height);
    let length = |channel, plane: &[f32], expected| {
        if plane.len() == expected {
            Ok(())
        } else {
            Err(Error::Length {
                channel,
                len: plane.len(),
                expected,
                width: w,
                height: h,
            })
        }
    };
    length("Y", input.y, w * h)?;
    if let Some(a) = input.a {
        length("A", a, w * h)?;
    }
    let half = |v: f32| f16::from_f32(v);
    let alpha = |i: usize| input.a.map_or(f16::ONE, |a| half(a[i]));
    if input.ry.is_none() && input.by.is_none() {
        return Ok((0..w * h)
            .map(|i| {
                let y = half(input.y[i]).to_f32();
                [y, y, y, alpha(i).to_f32()]
            })
            .collect());
    }
    if w % 2 != 0 || h % 2 != 0 || input.origin.0 % 2 != 0 || input.origin.1 % 2 != 0 {
        return Err(Error::OddWindow {
            width: w,
            height: h,
            origin: input.origin,
        });
    }
    for (channel, plane) in [("RY", input.ry), ("BY", input.by)] {
        if let Some(plane) = plane {
            length(channel, plane, (w / 2) * (h / 2))?;
        }
    }
    if w == 0 || h == 0 {
        return Ok(Vec::new());
    }

    // Steps 1: every even line, its chroma filled in horizontally.
    let even: Vec<Vec<Px>> = (0..h / 2).map(|row| horizontal(input, 2 * row)).collect();
    // Line `l` (relative, may lie outside the image) as OpenEXR buffers it: clamped.
    let clamp = |l: isize| -> usize {
        if l < 0 {
            0
        } else if l as usize > h - 1 {
            h - 2
        } else {
            l as usize
        }
    };
    // Steps 2 and 3: line `l` in RGB, before the saturation fix.
    let rgb = |l: isize| -> Vec<Px> {
        let c = clamp(l);
        if l.rem_euclid(2) == 0 {
            // An even line: clamped, still even.
            return even[c / 2].iter().map(|&p| to_rgb(p, weights)).collect();
        }
        (0..w)
            .map(|x| {
                let row = |k: usize| &even[clamp(l - 13 + 2 * k as isize) / 2][x];
                let p = Px {
                    r: half(filter(|k| row(k).r.to_f32())),
                    g: half(input.y[c * w + x]),
                    b: half(filter(|k| row(k).b.to_f32())),
                    a: alpha(c * w + x),
                };
                to_rgb(p, weights)
            })
            .collect()
    };

    // Step 4, line by line over a window of three RGB lines.
    let mut out = Vec::with_capacity(w * h);
    let (mut above, mut line) = (rgb(-1), rgb(0));
    for l in 0..h as isize {
        let below = rgb(l + 1);
        fix_saturation(weights, &above, &line, &below, &mut out);
        (above, line) = (line, below);
    }
    Ok(out)
}

/// Even line `row` (relative) with its odd pixels' chroma filled in: `padTmpBuf` and
/// `reconstructChromaHoriz`. Chroma of pixel `x` (even) is sample `x / 2`; the line is
/// padded left with pixel 0's and right with pixel `w - 2`'s.
fn horizontal(input: &YcaInput, row: usize) -> Vec<Px> {
    let w = input.width;
    let start = (row / 2) * (w / 2);
    let chroma = |plane: Option<&[f32]>, x: isize| -> f32 {
        let x = x.clamp(0, w as isize - 2) as usize;
        plane.map_or(0.0, |p| f16::from_f32(p[start + x / 2]).to_f32())
    };
    (0..w)
        .map(|x| {
            let i = row * w + x;
            let (r, b) = if x % 2 == 0 {
                (chroma(input.ry, x as isize), chroma(input.by, x as isize))
            } else {
                let at = |k: usize| x as isize - 13 + 2 * k as isize;
                (
                    filter(|k| chroma(input.ry, at(k))),
                    filter(|k| chroma(input.by, at(k))),
                )
            };
            Px {
                r: f16::from_f32(r),
                g: f16::from_f32(input.y[i]),
                b: f16::from_f32(b),
                a: input.a.map_or(f16::ONE, |a| f16::from_f32(a[i])),
            }
        })
        .collect()
}

/// `YCAtoRGBA` for one pixel: `g` holds `Y`, `r` and `b` the chroma.
fn to_rgb(p: Px, [wr, wg, wb]: [f32; 3]) -> Px {
    if p.r.to_f32() == 0.0 && p.b.to_f32() == 0.0 {
        return Px {
            r: p.g,
            g: p.g,
            b: p.g,
            a: p.a,
        };
    }
    let y = p.g.to_f32();
    let r = (p.r.to_f32() + 1.0) * y;
    let b = (p.b.to_f32() + 1.0) * y;
    let g = (y - r * wr - b * wb) / wg;
    Px {
        r: f16::from_f32(r),
        g: f16::from_f32(g),
        b: f16::from_f32(b),
        a: p.a,
    }
}

/// `std::max` as C++ defines it: `a < b ? b : a` (NaN handling included).
fn max(a: f32, b: f32) -> f32 {
    if a < b { b } else { a }
}

/// `std::min` as C++ defines it: `b < a ? b : a`.
fn min(a: f32, b: f32) -> f32 {
    if b < a { b } else { a }
}

fn saturation(p: Px) -> f32 {
    let (r, g, b) = (p.r.to_f32(), p.g.to_f32(), p.b.to_f32());
    let (hi, lo) = (max(r, max(g, b)), min(r, min(g, b)));
    if hi > 0.0 { 1.0 - lo / hi } else { 0.0 }
}

fn desaturate(p: Px, f: f32, [wr, wg, wb]: [f32; 3]) -> Px {
    let (r, g, b) = (p.r.to_f32(), p.g.to_f32(), p.b.to_f32());
    let hi = max(r, max(g, b));
    let toward = |v: f32| f16::from_f32(max(hi - (hi - v) * f, 0.0));
    let mut out = Px {
        r: toward(r),
        g: toward(g),
        b: toward(b),
        a: p.a,
    };
    let y_in = r * wr + g * wg + b * wb;
    let y_out = out.r.to_f32() * wr + out.g.to_f32() * wg + out.b.to_f32() * wb;
    if y_out > 0.0 {
        let k = y_in / y_out;
        for v in [&mut out.r, &mut out.g, &mut out.b] {
            *v = f16::from_f32(v.to_f32() * k);
        }
    }
    out
}

/// `fixSaturation` on `line`, between `above` and `below`, appending to `out`.
fn fix_saturation(
    weights: [f32; 3],
    above: &[Px],
    line: &[Px],
    below: &[Px],
    out: &mut Vec<[f32; 4]>,
) {
    let n = line.len();
    let (mut a1, mut a2) = (saturation(above[0]), saturation(above[0]));
    let (mut b1, mut b2) = (saturation(below[0]), saturation(below[0]));
    for i in 0..n {
        let (a0, b0) = (a1, b1);
        (a1, b1) = (a2, b2);
        if i + 1 < n {
            a2 = saturation(above[i + 1]);
            b2 = saturation(below[i + 1]);
        }
        let mean = min(1.0, 0.25 * (a0 + a2 + b0 + b2));
        let p = line[i];
        let s = saturation(p);
        let mut q = p;
        if s > mean {
            let most = min(1.0, 1.0 - (1.0 - mean) * 0.25);
            if s > most {
                q = desaturate(p, most / s, weights);
            }
        }
        out.push([q.r.to_f32(), q.g.to_f32(), q.b.to_f32(), q.a.to_f32()]);
    }
}
