//! The `RegressionDenoise` filter of `shaders/post/regression*.wgsl`, mirrored: preparation
//! (demodulation, classes), the guide (5×5 mean luminance of the same class and its
//! variance), then the per-pixel weighted first-order regression on position, normal and
//! albedo, solved by the same Cholesky factorization in the same order.

use super::{Image, V3, luminance, rgb};

/// Params of the regression filter, as the `RegressionDenoise` node's.
#[derive(Clone, Copy, Debug)]
pub struct RegressionParams {
    /// Window radius in pixels.
    pub radius: i32,
    /// Distance between the window's taps.
    pub stride: i32,
    /// Normal tolerance.
    pub sigma_normal: f32,
    /// Depth tolerance, relative to the pixel's depth.
    pub sigma_depth: f32,
    /// Luminance tolerance in standard deviations; 0 = off.
    pub sigma_color: f32,
    /// Ridge term, relative to each feature's spread.
    pub ridge: f32,
}

impl Default for RegressionParams {
    /// The registry's defaults.
    fn default() -> Self {
        Self {
            radius: 10,
            stride: 1,
            sigma_normal: 0.5,
            sigma_depth: 0.05,
            sigma_color: 3.0,
            ridge: 1e-3,
        }
    }
}

const EPS: f32 = 1e-3;
const K: usize = 9;

#[derive(Clone, Copy, PartialEq, Eq)]
enum Class {
    Miss,
    Surface,
    Emitter,
    Boundary,
}

fn finite4(p: [f32; 4]) -> [f32; 4] {
    p.map(|v| if v.is_finite() { v } else { 0.0 })
}

fn class_of(f: [f32; 4]) -> Class {
    if f[3] == 0.0 {
        Class::Miss
    } else if f[0] * f[0] + f[1] * f[1] + f[2] * f[2] < 0.25 {
        Class::Boundary
    } else if f[3] < 0.0 {
        Class::Emitter
    } else {
        Class::Surface
    }
}

fn dot3(a: V3, b: V3) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The regression filter. Depth is read from channel 0 of `depth`; an albedo alpha above 1.5
/// marks an emitter; `variance` is read from its alpha. With `variance` `None` the luminance
/// weight is off.
///
/// # Panics
/// When the images differ in size.
#[expect(clippy::too_many_lines, reason = "mirrors the shaders pass by pass")]
pub fn regression(
    color: &Image,
    variance: Option<&Image>,
    albedo: &Image,
    normal: &Image,
    depth: &Image,
    params: &RegressionParams,
) -> Image {
    let (w, h) = (color.width as i32, color.height as i32);
    for other in [albedo, normal, depth].into_iter().chain(variance) {
        assert_eq!((other.width, other.height), (color.width, color.height));
    }
    let idx = |x: i32, y: i32| (y * w + x) as usize;
    let inside = |x: i32, y: i32| x >= 0 && y >= 0 && x < w && y < h;
    let alb = |i: usize| rgb(finite4(albedo.pixels[i])).map(|v| v.max(EPS));

    // Preparation.
    let raw_class = |i: usize| {
        if finite4(depth.pixels[i])[0] <= 0.0 {
            Class::Miss
        } else if finite4(albedo.pixels[i])[3] > 1.5 {
            Class::Emitter
        } else {
            Class::Surface
        }
    };
    let mut illumination = vec![[0.0_f32; 4]; color.pixels.len()];
    let mut features = vec![[0.0_f32; 4]; color.pixels.len()];
    for y in 0..h {
        for x in 0..w {
            let i = idx(x, y);
            let a = alb(i);
            let la = luminance(a).max(EPS);
            let s = finite4(color.pixels[i]);
            let v = variance.map_or(0.0, |v| finite4(v.pixels[i])[3].max(0.0)) / (la * la);
            illumination[i] = finite4([
                s[0].max(0.0) / a[0],
                s[1].max(0.0) / a[1],
                s[2].max(0.0) / a[2],
                v,
            ]);
            let class = raw_class(i);
            let mut boundary = false;
            if class != Class::Miss {
                for dy in -1..=1 {
                    for dx in -1..=1 {
                        if inside(x + dx, y + dy) {
                            let o = raw_class(idx(x + dx, y + dy));
                            boundary = boundary
                                || (class == Class::Surface && o == Class::Emitter)
                                || (class == Class::Emitter && o != Class::Emitter);
                        }
                    }
                }
            }
            let z = finite4(depth.pixels[i])[0].max(0.0);
            let mut n = rgb(finite4(normal.pixels[i]));
            if boundary || dot3(n, n) < 0.25 {
                n = [0.0; 3];
            }
            features[i] = [
                n[0],
                n[1],
                n[2],
                if class == Class::Emitter { -z } else { z },
            ];
        }
    }

    // Guide.
    let mut guide = vec![[0.0_f32; 2]; color.pixels.len()];
    for y in 0..h {
        for x in 0..w {
            let i = idx(x, y);
            let class = class_of(features[i]);
            let (mut sum, mut var_sum, mut n) = (0.0_f32, 0.0_f32, 0.0_f32);
            if matches!(class, Class::Surface | Class::Emitter) {
                for dy in -2..=2 {
                    for dx in -2..=2 {
                        if inside(x + dx, y + dy)
                            && class_of(features[idx(x + dx, y + dy)]) == class
                        {
                            let d = illumination[idx(x + dx, y + dy)];
                            sum += luminance(rgb(d));
                            var_sum += d[3];
                            n += 1.0;
                        }
                    }
                }
            }
            let n = n.max(1.0);
            let g = finite4([sum / n, var_sum / (n * n), 0.0, 0.0]);
            guide[i] = [g[0], g[1]];
        }
    }

    // Regression.
    let same_class_depth = |x: i32, y: i32, class: Class| {
        if !inside(x, y) {
            return 1e30;
        }
        let f = features[idx(x, y)];
        if class_of(f) == class {
            f[3].abs()
        } else {
            1e30
        }
    };
    let guided = variance.is_some() && params.sigma_color > 0.0;
    let r = params.radius.max(1);
    let stride = params.stride.max(1);
    let steps = r / stride;
    #[expect(clippy::cast_precision_loss, reason = "small radius")]
    let inv_r = 1.0 / r as f32;
    let n_denom = params.sigma_normal.max(1e-6);
    let c2 = params.sigma_color * params.sigma_color;
    let mut out = vec![[0.0_f32; 4]; color.pixels.len()];
    for y in 0..h {
        for x in 0..w {
            let i = idx(x, y);
            let a = alb(i);
            let center = illumination[i];
            let f_p = features[i];
            let class = class_of(f_p);
            if matches!(class, Class::Miss | Class::Boundary) {
                out[i] = [center[0] * a[0], center[1] * a[1], center[2] * a[2], 1.0];
                continue;
            }
            let z_p = f_p[3].abs();
            let n_p = rgb(f_p);
            let grad = [(1, 0), (0, 1)].map(|(ex, ey)| {
                let mut best = 1e30_f32;
                let f = same_class_depth(x + ex, y + ey, class);
                if f < 1e29 {
                    best = f - z_p;
                }
                let b = same_class_depth(x - ex, y - ey, class);
                if b < 1e29 && (z_p - b).abs() < best.abs() {
                    best = z_p - b;
                }
                if best.abs() < 1e29 { best } else { 0.0 }
            });
            let g_p = guide[i];
            let z_denom = params.sigma_depth.max(1e-6) * z_p + 1e-6;
            // Sums: w, w x, w y, w x xᵀ (full 6×6), w x yᵀ.
            let mut s = 0.0_f32;
            let mut sx = [0.0_f32; K];
            let mut sy = [0.0_f32; 3];
            let mut sxx = [[0.0_f32; K]; K];
            let mut sxy = [[0.0_f32; 3]; K];
            for j in -steps..=steps {
                for ii in -steps..=steps {
                    let (dx, dy) = (ii * stride, j * stride);
                    if !inside(x + dx, y + dy) {
                        continue;
                    }
                    let q = idx(x + dx, y + dy);
                    let f_q = features[q];
                    if class_of(f_q) != class {
                        continue;
                    }
                    let yq = rgb(illumination[q]);
                    let a_q = alb(q);
                    let z_q = f_q[3].abs();
                    #[expect(clippy::cast_precision_loss, reason = "small offsets")]
                    let df = [dx as f32, dy as f32];
                    let e = (z_q - z_p - (grad[0] * df[0] + grad[1] * df[1])) / z_denom;
                    let mut arg = 2.0 * (df[0] * df[0] + df[1] * df[1]) * inv_r * inv_r;
                    arg += (1.0 - dot3(n_p, rgb(f_q))).max(0.0) / n_denom;
                    arg += e * e;
                    if guided {
                        let g_q = guide[q];
                        let dl = g_p[0] - g_q[0];
                        let v = g_p[1] + g_q[1];
                        arg += (dl * dl - v).max(0.0) / (c2 * v + 1e-12);
                    }
                    let wt = (-arg).exp();
                    let xq = [
                        df[0] * inv_r,
                        df[1] * inv_r,
                        (z_q - z_p) / z_p,
                        f_q[0] - n_p[0],
                        f_q[1] - n_p[1],
                        f_q[2] - n_p[2],
                        a_q[0] - a[0],
                        a_q[1] - a[1],
                        a_q[2] - a[2],
                    ];
                    s += wt;
                    for c in 0..3 {
                        sy[c] += wt * yq[c];
                    }
                    for u in 0..K {
                        let wx = wt * xq[u];
                        sx[u] += wx;
                        for v in 0..K {
                            sxx[u][v] += wx * xq[v];
                        }
                        for c in 0..3 {
                            sxy[u][c] += yq[c] * wx;
                        }
                    }
                }
            }
            let mean_y = sy.map(|v| v / s);
            let m = sx.map(|v| v / s);
            let mut b = [[0.0_f32; 3]; K];
            let mut l = [[0.0_f32; K]; K];
            for u in 0..K {
                for c in 0..3 {
                    b[u][c] = sxy[u][c] - s * m[u] * mean_y[c];
                }
                for v in 0..=u {
                    // The shader keeps the blocks of different feature groups (position,
                    // normal, albedo) as Σ (w x_v) x_u, v's group before u's.
                    let mut c = if v / 3 < u / 3 { sxx[v][u] } else { sxx[u][v] };
                    c -= s * m[u] * m[v];
                    if u == v {
                        c = c.max(0.0) * (1.0 + params.ridge) + 1e-7 * s;
                    }
                    l[u][v] = c;
                }
            }
            for u in 0..K {
                let mut diag = l[u][u];
                for k in 0..u {
                    diag -= l[u][k] * l[u][k];
                }
                let root = diag.max(1e-7 * s).sqrt();
                l[u][u] = root;
                for v in u + 1..K {
                    let mut c = l[v][u];
                    for k in 0..u {
                        c -= l[v][k] * l[u][k];
                    }
                    l[v][u] = c / root;
                }
            }
            for u in 0..K {
                for c in 0..3 {
                    let mut acc = b[u][c];
                    for k in 0..u {
                        acc -= l[u][k] * b[k][c];
                    }
                    b[u][c] = acc / l[u][u];
                }
            }
            for u in (0..K).rev() {
                for c in 0..3 {
                    let mut acc = b[u][c];
                    for k in u + 1..K {
                        acc -= l[k][u] * b[k][c];
                    }
                    b[u][c] = acc / l[u][u];
                }
            }
            let mut fit = mean_y;
            for u in 0..K {
                for c in 0..3 {
                    fit[c] -= b[u][c] * m[u];
                }
            }
            if !fit.iter().all(|v| v.is_finite()) {
                fit = mean_y;
            }
            out[i] = finite4([
                fit[0].max(0.0) * a[0],
                fit[1].max(0.0) * a[1],
                fit[2].max(0.0) * a[2],
                1.0,
            ]);
        }
    }
    Image {
        width: color.width,
        height: color.height,
        pixels: out,
    }
}
