//! CPU mirror of `TemporalReuse` (`shaders/post/temporal.wgsl`), line for line: the
//! history a node keeps, the reprojection at a camera move and the blend of every frame.

use lumagraph_scene::GpuCamera;

use super::Image;

/// `TemporalReuse`'s params as the shader gets them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TemporalParams {
    /// Most frames of reprojected history a pixel keeps.
    pub history_cap: f32,
    /// Largest relative depth difference of a tap.
    pub depth_tolerance: f32,
    /// Cosine of the largest angle between a tap's normal and the new one.
    pub normal_cos: f32,
}

/// What the node keeps across frames (see the shader's header).
#[derive(Clone, Debug, PartialEq)]
pub struct TemporalHistory {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// The last frame's output (rgb) and its weight in frames (a).
    pub last: Vec<[f32; 4]>,
    /// The last frame's normal (xyz) and depth (w).
    pub last_geo: Vec<[f32; 4]>,
    /// The history reprojected at the last move (rgb) and its weight (a).
    pub reprojected: Vec<[f32; 4]>,
}

impl TemporalHistory {
    /// Empty history (what a reset leaves) for a `width × height` image.
    pub fn new(width: u32, height: u32) -> Self {
        let n = width as usize * height as usize;
        Self {
            width,
            height,
            last: vec![[0.0; 4]; n],
            last_geo: vec![[0.0; 4]; n],
            reprojected: vec![[0.0; 4]; n],
        }
    }
}

type V3 = [f32; 3];

fn dot(a: V3, b: V3) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn scale(a: V3, s: f32) -> V3 {
    a.map(|x| x * s)
}

fn xyz(p: [f32; 4]) -> V3 {
    [p[0], p[1], p[2]]
}

/// The unit direction of the ray through the center of pixel `(x, y)` of a `size` image.
#[expect(clippy::cast_precision_loss, reason = "image sizes are small")]
pub fn pixel_ray(cam: &GpuCamera, (x, y): (u32, u32), size: (u32, u32)) -> V3 {
    let u = (x as f32 + 0.5) / size.0 as f32;
    let v = (y as f32 + 0.5) / size.1 as f32;
    let dir = sub(
        add(
            cam.forward,
            scale(cam.right, (2.0 * u - 1.0) * cam.tan_half_fov * cam.aspect),
        ),
        scale(cam.up, (2.0 * v - 1.0) * cam.tan_half_fov),
    );
    let l = dot(dir, dir).sqrt();
    scale(dir, 1.0 / l)
}

/// Whether a tap that saw `geo` (normal, signed depth) sees the hit at distance
/// `expected` with normal `n` and signed depth `signed` (see the shader's `same_surface`).
fn same_surface(
    signed: f32,
    expected: f32,
    n: Option<V3>,
    geo: [f32; 4],
    params: &TemporalParams,
) -> bool {
    if signed == 0.0 || geo[3] == 0.0 {
        return signed == 0.0 && geo[3] == 0.0;
    }
    if (signed < 0.0) != (geo[3] < 0.0) {
        return false;
    }
    if (geo[3].abs() - expected).abs() > params.depth_tolerance * expected {
        return false;
    }
    n.is_none_or(|n| dot(n, xyz(geo)) >= params.normal_cos)
}

/// 0 where nothing was hit, 1 on a surface, 2 on an emitter, from a signed depth.
fn class_of(signed: f32) -> u32 {
    if signed == 0.0 {
        0
    } else if signed < 0.0 {
        2
    } else {
        1
    }
}

/// Whether texel `(x, y)` of the last frame has a 4-neighbor of another class.
#[expect(
    clippy::cast_possible_wrap,
    clippy::cast_sign_loss,
    reason = "pixel coordinates, checked in range"
)]
fn on_border(history: &TemporalHistory, (x, y): (u32, u32)) -> bool {
    let (w, h) = (history.width as i32, history.height as i32);
    let c = class_of(history.last_geo[(y * history.width + x) as usize][3]);
    [(1, 0), (-1, 0), (0, 1), (0, -1)].iter().any(|(dx, dy)| {
        let (qx, qy) = (x as i32 + dx, y as i32 + dy);
        qx >= 0
            && qy >= 0
            && qx < w
            && qy < h
            && class_of(history.last_geo[(qy * w + qx) as usize][3]) != c
    })
}

/// The depth at pixel `i`, negated on an emitter (albedo alpha 2) when `albedo` is given.
fn signed_depth(depth: &Image, albedo: Option<&Image>, i: usize) -> f32 {
    let d = depth.pixels[i][0];
    if albedo.is_some_and(|a| a.pixels[i][3] > 1.5) {
        -d
    } else {
        d
    }
}

/// The images a `TemporalReuse` pass reads besides the color: first-hit depth, and the
/// optional normal and albedo.
#[derive(Clone, Copy, Debug)]
pub struct Guides<'a> {
    /// Distance to the first hit through the pixel center (0: none).
    pub depth: &'a Image,
    /// Its shading normal.
    pub normal: Option<&'a Image>,
    /// Its albedo, alpha 2 on emitters.
    pub albedo: Option<&'a Image>,
}

/// The reprojection stage: fills `history.reprojected` for the view of `camera`, whose
/// first hits are `guides`, from `history.last` rendered with `old`.
#[expect(
    clippy::cast_precision_loss,
    clippy::cast_possible_truncation,
    clippy::cast_sign_loss,
    reason = "pixel coordinates, checked in range"
)]
pub fn reproject(
    history: &mut TemporalHistory,
    guides: Guides<'_>,
    old: &GpuCamera,
    camera: &GpuCamera,
    params: &TemporalParams,
) {
    let (w, h) = (history.width, history.height);
    let size = [w as f32, h as f32];
    for y in 0..h {
        for x in 0..w {
            let i = (y * w + x) as usize;
            let signed = signed_depth(guides.depth, guides.albedo, i);
            let d = signed.abs();
            let n = guides.normal.map(|n| xyz(n.pixels[i]));
            let dir = pixel_ray(camera, (x, y), (w, h));
            let (v, expected) = if d > 0.0 {
                let v = sub(add(camera.position, scale(dir, d)), old.position);
                (v, dot(v, v).sqrt())
            } else {
                (dir, 0.0)
            };
            let z = dot(v, old.forward);
            if z <= 0.0 {
                history.reprojected[i] = [0.0; 4];
                continue;
            }
            let u = dot(v, old.right) / (z * old.tan_half_fov * old.aspect);
            let t = dot(v, old.up) / (z * old.tan_half_fov);
            let q = [
                0.5 * (u + 1.0) * size[0] - 0.5,
                0.5 * (1.0 - t) * size[1] - 0.5,
            ];
            let base = [q[0].floor(), q[1].floor()];
            let f = [q[0] - base[0], q[1] - base[1]];
            let mut sum = [0.0f32; 4];
            let mut total = 0.0f32;
            for k in 0..4u32 {
                let o = [(k & 1) as f32, (k >> 1) as f32];
                let tap = [base[0] + o[0], base[1] + o[1]];
                let bw = (if o[0] > 0.0 { f[0] } else { 1.0 - f[0] })
                    * (if o[1] > 0.0 { f[1] } else { 1.0 - f[1] });
                if bw <= 0.0
                    || tap[0] < 0.0
                    || tap[1] < 0.0
                    || tap[0] >= size[0]
                    || tap[1] >= size[1]
                {
                    continue;
                }
                let j = (tap[1] as u32 * w + tap[0] as u32) as usize;
                let hist = history.last[j];
                if hist[3] <= 0.0
                    || !same_surface(signed, expected, n, history.last_geo[j], params)
                    || on_border(history, (tap[0] as u32, tap[1] as u32))
                {
                    continue;
                }
                for c in 0..4 {
                    sum[c] += bw * hist[c];
                }
                total += bw;
            }
            history.reprojected[i] = if total <= 0.0 {
                [0.0; 4]
            } else {
                let m = sum.map(|s| s / total);
                [m[0], m[1], m[2], m[3].min(params.history_cap)]
            };
        }
    }
}

/// The blend stage for a frame `frames` frames after the move (Accumulate's mean `color`
/// is of them): returns the node's `color` and `weight` outputs and updates the history.
#[expect(clippy::cast_precision_loss, reason = "frame counts are small")]
pub fn blend(
    history: &mut TemporalHistory,
    color: &Image,
    guides: Guides<'_>,
    frames: u32,
) -> (Image, Image) {
    let (w, h) = (history.width, history.height);
    let mut out = Image::filled(w, h, [0.0; 4]);
    let mut weight = Image::filled(w, h, [0.0; 4]);
    let n = frames as f32;
    for i in 0..(w as usize * h as usize) {
        let mean = color.pixels[i];
        let r = history.reprojected[i];
        let mut o = xyz(mean);
        if r[3] > 0.0 {
            for c in 0..3 {
                o[c] = (n * mean[c] + r[3] * r[c]) / (n + r[3]);
            }
        }
        out.pixels[i] = [o[0], o[1], o[2], mean[3]];
        weight.pixels[i] = [r[3], n, n + r[3], 1.0];
        history.last[i] = [o[0], o[1], o[2], n + r[3]];
        let nv = guides.normal.map_or([0.0; 3], |im| xyz(im.pixels[i]));
        history.last_geo[i] = [
            nv[0],
            nv[1],
            nv[2],
            signed_depth(guides.depth, guides.albedo, i),
        ];
    }
    (out, weight)
}
