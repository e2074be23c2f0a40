// TemporalReuse: keeps a progressive render's samples across a camera move.
// Mirrored by `cpu::temporal` (crates/render/src/cpu/temporal.rs).
//
// History lives in three storage buffers owned by the node:
//   last[i]        rgb: the color written for pixel i in the last frame, a: its weight W in
//                  frames (0 before the first frame);
//   last_geo[i]    xyz: the normal, w: the depth at pixel i in that frame, negated on an
//                  emitter (with `albedo`, whose alpha is 2 there);
//   reprojected[i] rgb: the history reprojected into the current view at the last move,
//                  a: its weight w in frames (0: none, or dropped).
//
// Two stages, one dispatch each (`params.stage`):
//   STAGE_REPROJECT, once in the first frame after a move: for each pixel, the first hit
//     through its center (`depth` from the new camera) is projected into the old camera's
//     image; the four `last` texels around that point are blended bilinearly, keeping only
//     taps whose depth is the distance the old camera sees the hit at (within
//     `depth_tolerance`, relative), whose normal agrees (with `normal`) and which is an
//     emitter exactly when the new hit is one (with `albedo`: a light set in a ceiling
//     never bleeds into it), and which are not on the border of a surface with an
//     emitter or the background (a pixel there mixes both, and a light is a hundred
//     times brighter than the wall beside it), so a hit that
//     was hidden (disoccluded) or off screen gets no history. A pixel that sees nothing
//     (depth 0, the environment) is projected by its direction and keeps taps that saw
//     nothing too. The weight is the taps' W, capped at `history_cap`.
//   STAGE_BLEND, every frame: with n the frames since the move (Accumulate's mean `color`
//     is of them), out = (n color + w history) / (n + w); where w is 0 the mean passes
//     through unchanged. Writes `last` and `last_geo` for the next move.

struct Camera {
    position: vec3f,
    tan_half_fov: f32,
    right: vec3f,
    aspect: f32,
    up: vec3f,
    aperture_radius: f32,
    forward: vec3f,
    focus_distance: f32,
}

struct Params {
    // The camera `last` was rendered with, and the current one.
    old_camera: Camera,
    camera: Camera,
    size: vec2u,
    stage: u32,
    // Frames since the move, this one included.
    frames: u32,
    history_cap: f32,
    depth_tolerance: f32,
    // cos(normal_angle).
    normal_cos: f32,
    // 1 when the `normal` input is connected.
    has_normal: u32,
    // 1 when the `albedo` input is connected.
    has_albedo: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
}

@group(0) @binding(0) var color: texture_2d<f32>;
@group(0) @binding(1) var depth: texture_2d<f32>;
@group(0) @binding(2) var normal: texture_2d<f32>;
@group(0) @binding(3) var albedo: texture_2d<f32>;
@group(0) @binding(4) var out_color: texture_storage_2d<rgba32float, write>;
@group(0) @binding(5) var out_weight: texture_storage_2d<rgba32float, write>;
@group(0) @binding(6) var<storage, read_write> last: array<vec4f>;
@group(0) @binding(7) var<storage, read_write> last_geo: array<vec4f>;
@group(0) @binding(8) var<storage, read_write> reprojected: array<vec4f>;
@group(0) @binding(9) var<uniform> params: Params;

const STAGE_REPROJECT: u32 = 0u;
const STAGE_BLEND: u32 = 1u;

// The unit direction of the ray through the center of `pixel` (the path tracer's pinhole
// ray, `pinhole_ray` in pathtrace.wgsl).
fn pixel_ray(cam: Camera, pixel: vec2u) -> vec3f {
    let xy = (vec2f(pixel) + vec2f(0.5)) / vec2f(params.size);
    let dir = cam.forward + (2.0 * xy.x - 1.0) * cam.tan_half_fov * cam.aspect * cam.right
        - (2.0 * xy.y - 1.0) * cam.tan_half_fov * cam.up;
    return normalize(dir);
}

// The depth at `p`, negated on an emitter (when `albedo` is connected).
fn read_depth(p: vec2u) -> f32 {
    let d = textureLoad(depth, p, 0).r;
    if params.has_albedo == 1u && textureLoad(albedo, p, 0).a > 1.5 {
        return -d;
    }
    return d;
}

fn read_normal(p: vec2u) -> vec3f {
    if params.has_normal == 1u {
        return textureLoad(normal, p, 0).xyz;
    }
    return vec3f(0.0);
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3u) {
    if id.x >= params.size.x || id.y >= params.size.y {
        return;
    }
    let i = id.y * params.size.x + id.x;
    if params.stage == STAGE_REPROJECT {
        reprojected[i] = reproject(id.xy);
        return;
    }
    let mean = textureLoad(color, id.xy, 0);
    let n = f32(params.frames);
    let h = reprojected[i];
    var out = mean.rgb;
    if h.a > 0.0 {
        out = (n * mean.rgb + h.a * h.rgb) / (n + h.a);
    }
    textureStore(out_color, id.xy, vec4f(out, mean.a));
    textureStore(out_weight, id.xy, vec4f(h.a, n, n + h.a, 1.0));
    last[i] = vec4f(out, n + h.a);
    last_geo[i] = vec4f(read_normal(id.xy), read_depth(id.xy));
}

// The history seen from the current camera at `pixel`: rgb and weight (0: none).
fn reproject(pixel: vec2u) -> vec4f {
    let signed = read_depth(pixel);
    let d = abs(signed);
    let n = read_normal(pixel);
    let cam = params.camera;
    let old = params.old_camera;
    let dir = pixel_ray(cam, pixel);
    // Where the old camera sees the hit (or, for a miss, the direction) and how far.
    var v = dir;
    var expected = 0.0;
    if d > 0.0 {
        v = cam.position + d * dir - old.position;
        expected = length(v);
    }
    let z = dot(v, old.forward);
    if z <= 0.0 {
        return vec4f(0.0);
    }
    let u = dot(v, old.right) / (z * old.tan_half_fov * old.aspect);
    let w = dot(v, old.up) / (z * old.tan_half_fov);
    let size = vec2f(params.size);
    let q = vec2f(0.5 * (u + 1.0), 0.5 * (1.0 - w)) * size - vec2f(0.5);
    let base = floor(q);
    let f = q - base;
    var sum = vec4f(0.0);
    var total = 0.0;
    for (var k = 0u; k < 4u; k++) {
        let o = vec2f(f32(k & 1u), f32(k >> 1u));
        let t = base + o;
        let bw = select(1.0 - f.x, f.x, o.x > 0.0) * select(1.0 - f.y, f.y, o.y > 0.0);
        if bw <= 0.0 || any(t < vec2f(0.0)) || any(t >= size) {
            continue;
        }
        let j = u32(t.y) * params.size.x + u32(t.x);
        let geo = last_geo[j];
        let hist = last[j];
        if hist.a <= 0.0 || !same_surface(signed, expected, n, geo) || on_border(t, geo.w) {
            continue;
        }
        sum += bw * hist;
        total += bw;
    }
    if total <= 0.0 {
        return vec4f(0.0);
    }
    let h = sum / total;
    return vec4f(h.rgb, min(h.a, params.history_cap));
}

// 0 where nothing was hit, 1 on a surface, 2 on an emitter, from a signed depth.
fn class_of(signed: f32) -> u32 {
    return select(select(1u, 2u, signed < 0.0), 0u, signed == 0.0);
}

// Whether a texel `t` of the last frame, of signed depth `signed`, has a 4-neighbor of
// another class (see `class_of`).
fn on_border(t: vec2f, signed: f32) -> bool {
    let c = class_of(signed);
    let p = vec2i(t);
    let size = vec2i(params.size);
    for (var k = 0; k < 4; k++) {
        let q = p + array(vec2i(1, 0), vec2i(-1, 0), vec2i(0, 1), vec2i(0, -1))[k];
        if all(q >= vec2i(0)) && all(q < size)
            && class_of(last_geo[u32(q.y * size.x + q.x)].w) != c {
            return true;
        }
    }
    return false;
}

// Whether a tap that saw `geo` (normal, signed depth) sees the hit at `expected` from the
// old camera with normal `n` and signed depth `signed` (0 and 0: both see nothing; the
// signs: both emitters or neither).
fn same_surface(signed: f32, expected: f32, n: vec3f, geo: vec4f) -> bool {
    if signed == 0.0 || geo.w == 0.0 {
        return signed == 0.0 && geo.w == 0.0;
    }
    if (signed < 0.0) != (geo.w < 0.0) {
        return false;
    }
    if abs(abs(geo.w) - expected) > params.depth_tolerance * expected {
        return false;
    }
    return params.has_normal == 0u || dot(n, geo.xyz) >= params.normal_cos;
}
