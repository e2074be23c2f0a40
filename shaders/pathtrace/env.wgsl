// Environment lighting from an equirectangular map, importance sampled by pixel: each
// pixel's probability is proportional to its luminance times sin(theta) (its solid angle),
// drawn with an alias table, and the pdf is constant over a pixel. The radiance is Mitsuba's
// `envmap` lookup: bilinear between texel values placed at u = (x + 1/2) / W (wrapping
// around) and v = y / (H - 1), so renders compare with Mitsuba's pixel for pixel. The includer declares `env_texels: array<vec4f>` (rgb radiance,
// a = pixel probability), `env_alias: array<AliasEntry>` and `frame` (map size, rotation,
// scale in `frame.settings`).
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

// Radiance of the map (unscaled) at `uv`: Mitsuba's bilinear lookup (see above).
fn env_radiance(uv: vec2f) -> vec3f {
    let w = frame.env_width;
    let h = frame.env_height;
    let x = uv.x * f32(w) - 0.5;
    let y = uv.y * f32(max(h, 2u) - 1u);
    let xf = floor(x);
    let fx = x - xf;
    let x0 = u32(i32(xf) + i32(w)) % w;
    let x1 = (x0 + 1u) % w;
    let y0 = min(u32(max(floor(y), 0.0)), h - 1u);
    let fy = clamp(y - f32(y0), 0.0, 1.0);
    let y1 = min(y0 + 1u, h - 1u);
    let top = mix(env_texels[y0 * w + x0].rgb, env_texels[y0 * w + x1].rgb, fx);
    let bottom = mix(env_texels[y1 * w + x0].rgb, env_texels[y1 * w + x1].rgb, fx);
    return mix(top, bottom, fy);
}

fn env_texel(uv: vec2f) -> u32 {
    let w = frame.env_width;
    let h = frame.env_height;
    let x = min(u32(uv.x * f32(w)), w - 1u);
    let y = min(u32(uv.y * f32(h)), h - 1u);
    return y * w + x;
}

// Solid-angle pdf of a direction whose pixel has probability `p`.
fn env_pixel_pdf(p: f32, sin_theta: f32) -> f32 {
    let n = f32(frame.env_width * frame.env_height);
    return select(0.0, p * n / (2.0 * PI * PI * sin_theta), sin_theta > 0.0);
}

// Radiance (rgb) and solid-angle pdf (a) of the map in world direction d.
fn env_eval(d: vec3f) -> vec4f {
    let m = env_to_map(d);
    let uv = env_uv(m);
    let p = env_texels[env_texel(uv)].a;
    let sin_theta = sqrt(max(0.0, 1.0 - m.y * m.y));
    return vec4f(env_radiance(uv) * frame.settings.env_radiance, env_pixel_pdf(p, sin_theta));
}

struct EnvSample {
    wi: vec3f,
    radiance: vec3f,
    pdf: f32,
}

fn sample_env(u_pick: f32, u: vec2f) -> EnvSample {
    let n = frame.env_width * frame.env_height;
    let scaled = u_pick * f32(n);
    let i = min(u32(scaled), n - 1u);
    let e = env_alias[i];
    let idx = select(e.other, i, scaled - f32(i) < e.prob);
    let x = idx % frame.env_width;
    let y = idx / frame.env_width;
    let uv = vec2f((f32(x) + u.x) / f32(frame.env_width), (f32(y) + u.y) / f32(frame.env_height));
    let pdf = env_pixel_pdf(env_texels[idx].a, sin(uv.y * PI));
    return EnvSample(env_from_map(env_dir(uv)), env_radiance(uv) * frame.settings.env_radiance, pdf);
}
