// Environment lighting from an equirectangular map. Radiance is Mitsuba's `envmap` lookup:
// bilinear between texel values placed at u = (x + 1/2) / W (wrapping around) and
// v = y / (H - 1), so renders compare with Mitsuba's pixel for pixel. Sampling follows the
// same interpolant (crates/pathtrace/src/env_map.rs): a cell between four texel points is drawn
// with an alias table by its weights (luminance x sin theta), then a point in it from their
// bilinear interpolant; `a` of each texel is that interpolant's value over its integral, the
// pdf in (u, v). The includer declares `env_texels: array<vec4f>`, `env_alias:
// array<AliasEntry>` (one entry per cell) and `frame` (map size, rotation, scale in
// `frame.settings`).
// requires: var frame, var env_texels, var env_alias (integrator/pathtrace.wgsl)
#import "pathtrace/scene_types.wgsl"
#import "common/sampling.wgsl"

// The map is placed as Mitsuba's `envmap` with to_world = R_y(azimuth) R_x(elevation)
// (right-handed rotations). World direction to the map's frame: undo the azimuth, then the
// elevation.
fn env_to_map(d: vec3f) -> vec3f {
    let az = frame.settings.env_azimuth;
    let el = frame.settings.env_elevation;
    let a = vec3f(cos(az) * d.x - sin(az) * d.z, d.y, sin(az) * d.x + cos(az) * d.z);
    return vec3f(a.x, cos(el) * a.y + sin(el) * a.z, -sin(el) * a.y + cos(el) * a.z);
}

fn env_from_map(m: vec3f) -> vec3f {
    let az = frame.settings.env_azimuth;
    let el = frame.settings.env_elevation;
    let a = vec3f(m.x, cos(el) * m.y - sin(el) * m.z, sin(el) * m.y + cos(el) * m.z);
    return vec3f(cos(az) * a.x + sin(az) * a.z, a.y, -sin(az) * a.x + cos(az) * a.z);
}

// Mitsuba's equirectangular mapping: u = atan2(x, -z) / 2pi (mod 1), so the image's left edge
// is seen along -z, its centre column along +z and u = 1/4 along +x; v grows from +y (top
// row) down.
fn env_uv(m: vec3f) -> vec2f {
    let u = fract(atan2(m.x, -m.z) * (0.5 * INV_PI) + 1.0);
    let v = acos(clamp(m.y, -1.0, 1.0)) * INV_PI;
    return vec2f(u, v);
}

fn env_dir(uv: vec2f) -> vec3f {
    let phi = uv.x * TWO_PI;
    let theta = uv.y * PI;
    let s = sin(theta);
    return vec3f(s * sin(phi), cos(theta), -s * cos(phi));
}

// Where `uv` falls between texel points: the cell's corners (x0, x1 wrapping; y0, y1) and
// the position inside it.
struct EnvCell {
    x0: u32,
    x1: u32,
    y0: u32,
    y1: u32,
    f: vec2f,
}

fn env_cell(uv: vec2f) -> EnvCell {
    let w = frame.env_width;
    let h = frame.env_height;
    let x = uv.x * f32(w) - 0.5;
    let y = uv.y * f32(h - 1u);
    let xf = floor(x);
    let x0 = u32(i32(xf) + i32(w)) % w;
    let y0 = min(u32(max(floor(y), 0.0)), h - 2u);
    return EnvCell(x0, (x0 + 1u) % w, y0, y0 + 1u, vec2f(x - xf, clamp(y - f32(y0), 0.0, 1.0)));
}

// Bilinear interpolation of the texels at the corners of `c`.
fn env_lerp(c: EnvCell) -> vec4f {
    let w = frame.env_width;
    let top = mix(env_texels[c.y0 * w + c.x0], env_texels[c.y0 * w + c.x1], c.f.x);
    let bottom = mix(env_texels[c.y1 * w + c.x0], env_texels[c.y1 * w + c.x1], c.f.x);
    return mix(top, bottom, c.f.y);
}

// Solid-angle pdf of a direction whose (u, v) pdf is `p`.
fn env_solid_angle_pdf(p: f32, sin_theta: f32) -> f32 {
    return select(0.0, p / (2.0 * PI * PI * sin_theta), sin_theta > 0.0);
}

// Radiance (rgb) and solid-angle pdf (a) of the map in world direction d.
fn env_eval(d: vec3f) -> vec4f {
    let m = env_to_map(d);
    let t = env_lerp(env_cell(env_uv(m)));
    let sin_theta = sqrt(max(0.0, 1.0 - m.y * m.y));
    return vec4f(t.rgb * frame.settings.env_radiance, env_solid_angle_pdf(t.a, sin_theta));
}

// A sample of [0, 1) with density proportional to (1 - x) a + x b (pbrt-v4's SampleLinear).
fn sample_linear(u: f32, a: f32, b: f32) -> f32 {
    if a == b {
        return u;
    }
    let x = u * (a + b) / (a + sqrt(mix(a * a, b * b, u)));
    return min(x, 0.99999994);
}

struct EnvSample {
    wi: vec3f,
    radiance: vec3f,
    pdf: f32,
}

fn sample_env(u_pick: f32, u: vec2f) -> EnvSample {
    let w = frame.env_width;
    let cells = w * (frame.env_height - 1u);
    let scaled = u_pick * f32(cells);
    let i = min(u32(scaled), cells - 1u);
    let e = env_alias[i];
    let idx = select(e.other, i, scaled - f32(i) < e.prob);
    var c: EnvCell;
    c.x0 = idx % w;
    c.x1 = (c.x0 + 1u) % w;
    c.y0 = idx / w;
    c.y1 = c.y0 + 1u;
    // A point of the cell from the bilinear interpolant of its corners' pdfs: v from the
    // marginal, then u given v.
    let p00 = env_texels[c.y0 * w + c.x0].a;
    let p10 = env_texels[c.y0 * w + c.x1].a;
    let p01 = env_texels[c.y1 * w + c.x0].a;
    let p11 = env_texels[c.y1 * w + c.x1].a;
    c.f.y = sample_linear(u.y, p00 + p10, p01 + p11);
    c.f.x = sample_linear(u.x, mix(p00, p01, c.f.y), mix(p10, p11, c.f.y));
    let uv = vec2f(
        fract((f32(c.x0) + 0.5 + c.f.x) / f32(w)),
        (f32(c.y0) + c.f.y) / f32(frame.env_height - 1u),
    );
    let t = env_lerp(c);
    let pdf = env_solid_angle_pdf(t.a, sin(uv.y * PI));
    return EnvSample(env_from_map(env_dir(uv)), t.rgb * frame.settings.env_radiance, pdf);
}
