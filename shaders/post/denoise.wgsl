// Denoise: one pass of the edge-avoiding à-trous wavelet filter (Dammertz et al. 2010) with
// SVGF's edge-stopping functions (Schied et al. 2017). The node runs a demodulation pass,
// then this filter `iterations` times with `step` = 1, 2, 4, …: a 5×5 B3-spline kernel
// (1/16, 1/4, 3/8, 1/4, 1/16) whose taps are `step` pixels apart.
//
// It filters illumination, not color: the demodulation pass (`params.first` = 1) divides the
// color by max(albedo, EPS) (and the variance by the square of the albedo's luminance) and
// writes illumination in rgb and its luminance variance in alpha; the filter passes read and
// write that layout; the last one (`params.last` = 1) multiplies the result by the same
// max(albedo, EPS). Each pass filters the variance with the squared weights, as SVGF does,
// so later passes stop at smaller luminance differences.
//
// Weight of tap q around pixel p (the center tap always gets its kernel weight alone, so the
// sum of weights is never 0):
//   w_l = exp(-|l_p - l_q| / (sigma_color * s + 1e-6))
//         s = sqrt(3×3 Gaussian of the variance) when variance-guided, else 2^-pass
//   w_n = exp(-max(1 - dot(n_p, n_q), 0) / max(sigma_normal, 1e-6))
//   w_z = exp(-|z_p - z_q| / (sigma_depth * |grad z · offset| + 1e-3 z_p + 1e-6))
// and 0 when one of p and q is an emitter and the other is not (GBuffer writes albedo alpha
// 2 on emitters, 1 elsewhere): a light beside a ceiling of the same normal, depth and albedo
// is told apart only by luminance, which a large variance at the light's edge pixels
// disarms, so without this the light bleeds into the dark strip around it.
// Every input is loaded through `finite`, so NaN or Inf anywhere becomes 0, never output.

struct Params {
    step: i32,
    first: u32,
    last: u32,
    guided: u32,
    sigma_color: f32,
    sigma_normal: f32,
    sigma_depth: f32,
    // 2^-pass: the luminance scale when not variance-guided.
    scale: f32,
}

@group(0) @binding(0) var src: texture_2d<f32>;
@group(0) @binding(1) var variance: texture_2d<f32>;
@group(0) @binding(2) var albedo: texture_2d<f32>;
@group(0) @binding(3) var normal: texture_2d<f32>;
@group(0) @binding(4) var depth: texture_2d<f32>;
@group(0) @binding(5) var dst: texture_storage_2d<rgba32float, write>;
@group(0) @binding(6) var<uniform> params: Params;

const EPS: f32 = 1e-3;
const LUMA = vec3f(0.2126, 0.7152, 0.0722);
const KERNEL = array<f32, 3>(0.375, 0.25, 0.0625);

// `v` with every non-finite component replaced by 0 (exponent bits, so a compiler that
// assumes finite math cannot fold the test away).
fn finite(v: vec4f) -> vec4f {
    let e = bitcast<vec4u>(v) & vec4u(0x7f800000u);
    return select(vec4f(0.0), v, e != vec4u(0x7f800000u));
}

// Whether the G-buffer marks `p` as an emitter (albedo alpha 2; 1 on other surfaces, 0 where
// nothing is hit or the albedo comes from elsewhere).
fn emitter_at(p: vec2i) -> bool {
    return finite(textureLoad(albedo, p, 0)).a > 1.5;
}

fn albedo_at(p: vec2i) -> vec3f {
    return max(finite(textureLoad(albedo, p, 0)).rgb, vec3f(EPS));
}

fn depth_at(p: vec2i) -> f32 {
    return finite(textureLoad(depth, p, 0)).r;
}

// Illumination (rgb) and its luminance variance (a) at `p`, from the ping-pong image.
fn illumination(p: vec2i) -> vec4f {
    return finite(textureLoad(src, p, 0));
}

// The demodulation pass's value at `p`: color / albedo and variance / luminance(albedo)².
fn demodulate(p: vec2i) -> vec4f {
    let s = finite(textureLoad(src, p, 0));
    let a = albedo_at(p);
    let v = max(finite(textureLoad(variance, p, 0)).a, 0.0);
    let la = max(dot(a, LUMA), EPS);
    let c = max(s.rgb, vec3f(0.0)) / a;
    return finite(vec4f(c, v / (la * la)));
}

fn in_image(p: vec2i, size: vec2i) -> bool {
    return all(p >= vec2i(0)) && all(p < size);
}

// 3×3 Gaussian (1/4, 1/2, 1/4) of the variance around `p`, clamped to the image.
fn blurred_variance(p: vec2i, size: vec2i) -> f32 {
    var sum = 0.0;
    var wsum = 0.0;
    for (var dy = -1; dy <= 1; dy++) {
        for (var dx = -1; dx <= 1; dx++) {
            let q = p + vec2i(dx, dy);
            if in_image(q, size) {
                let w = (select(0.25, 0.5, dx == 0)) * (select(0.25, 0.5, dy == 0));
                sum += w * illumination(q).a;
                wsum += w;
            }
        }
    }
    return sum / wsum;
}

// One-sided difference with the smaller magnitude, so the gradient does not jump an edge.
fn depth_gradient(p: vec2i, size: vec2i, z: f32) -> vec2f {
    var g = vec2f(0.0);
    for (var axis = 0; axis < 2; axis++) {
        let e = select(vec2i(0, 1), vec2i(1, 0), axis == 0);
        var best = 1e30;
        if in_image(p + e, size) {
            best = depth_at(p + e) - z;
        }
        if in_image(p - e, size) {
            let b = z - depth_at(p - e);
            if abs(b) < abs(best) {
                best = b;
            }
        }
        g[axis] = select(0.0, best, abs(best) < 1e29);
    }
    return g;
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3u) {
    let size = vec2i(textureDimensions(dst));
    let p = vec2i(id.xy);
    if !in_image(p, size) {
        return;
    }
    if params.first == 1u {
        textureStore(dst, p, demodulate(p));
        return;
    }
    let center = illumination(p);
    let l_p = dot(center.rgb, LUMA);
    let n_p = finite(textureLoad(normal, p, 0)).xyz;
    let z_p = depth_at(p);
    let e_p = emitter_at(p);
    let grad = depth_gradient(p, size, z_p);

    var s = params.scale;
    if params.guided == 1u {
        s = sqrt(max(blurred_variance(p, size), 0.0));
    }
    let l_denom = params.sigma_color * s + 1e-6;
    let n_denom = max(params.sigma_normal, 1e-6);
    let z_eps = 1e-3 * z_p + 1e-6;

    let h0 = KERNEL[0] * KERNEL[0];
    var color = h0 * center.rgb;
    var var_sum = h0 * h0 * center.a;
    var wsum = h0;
    for (var dy = -2; dy <= 2; dy++) {
        for (var dx = -2; dx <= 2; dx++) {
            if dx == 0 && dy == 0 {
                continue;
            }
            let offset = vec2i(dx, dy) * params.step;
            let q = p + offset;
            if !in_image(q, size) {
                continue;
            }
            let c = illumination(q);
            let n_q = finite(textureLoad(normal, q, 0)).xyz;
            let z_q = depth_at(q);
            let h = KERNEL[abs(dx)] * KERNEL[abs(dy)];
            let w_l = abs(l_p - dot(c.rgb, LUMA)) / l_denom;
            let w_n = max(1.0 - dot(n_p, n_q), 0.0) / n_denom;
            let z_scale = params.sigma_depth * abs(dot(grad, vec2f(offset))) + z_eps;
            let w_z = abs(z_p - z_q) / z_scale;
            let same = e_p == emitter_at(q);
            let w = select(0.0, h * exp(-(w_l + w_n + w_z)), same);
            color += w * c.rgb;
            var_sum += w * w * c.a;
            wsum += w;
        }
    }
    var out = finite(vec4f(color / wsum, var_sum / (wsum * wsum)));
    if params.last == 1u {
        out = vec4f(out.rgb * albedo_at(p), 1.0);
    }
    textureStore(dst, p, out);
}
