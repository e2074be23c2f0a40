// Accumulate: running mean of the input over frames, with Kahan-compensated f32 sums.
// History lives in two storage buffers owned by the node (it outlives a frame):
//   sum[i].rgb  running sum of the input,  sum[i].a  number of frames added (exact to 2^24);
//   comp[i].rgb Kahan compensation (the low-order bits the sum lost).
// Mirrored by `cpu::KahanMean`.
//
// When VARIANCE (accumulate_options.wgsl, set per node) is 1, a third buffer keeps
// Welford's second moment of the frames
//   m2[i].rgb  sum of (x - mean_before)(x - mean_after) per channel,  m2[i].a  the same of
//   the luminance,
// with the means taken from the Kahan sums above (which it never changes), and `variance_out`
// gets the variance of the mean, m2 / (n (n - 1)). After one frame there is no second frame
// to compare with; the variance is then estimated spatially, as SVGF does for short
// histories, over the pixel's 3×3 neighborhood: the sample variance per channel, and for the
// luminance (what Denoise reads) a robust one from the median absolute deviation, so a wall
// pixel beside the light does not look noisy.
//
// Pixels whose input alpha is 0 took no sample this frame (adaptive sampling): nothing is
// added there and the pixel's mean and variance are written as they stand, so each pixel's
// mean is over its own frames (`sum.a` counts them per pixel). The frame's arithmetic is
// otherwise unchanged (a separate early-out path, calling `present`, made the pass twice as
// slow on lavapipe).
//
// When `params.present` is 1 (a merge of partial renders, `lumagraph merge`), the pass adds
// nothing: it writes the mean and variance of the history as it stands, with the same
// arithmetic as the frame that added the last sample.
//
// Shader compilers may simplify `((s + y) - s) - y` to 0 (Mesa's NIR does, since naga marks no
// operation exact), which silently turns Kahan summation into a plain sum. Multiplying by
// `params.one` (1.0, but unknown to the compiler) keeps the compensation term alive.

#import "post/accumulate_options.wgsl"

struct Params {
    one: f32,
    // The same as VARIANCE (accumulate_options.wgsl), for the layout the node writes.
    variance: u32,
    size: vec2u,
    present: u32,
    // 1 when the history's first frame is an odd frame of the render.
    parity: u32,
}

@group(0) @binding(0) var input: texture_2d<f32>;
@group(0) @binding(1) var output: texture_storage_2d<rgba32float, write>;
@group(0) @binding(2) var<storage, read_write> sum: array<vec4f>;
@group(0) @binding(3) var<storage, read_write> comp: array<vec4f>;
@group(0) @binding(4) var<uniform> params: Params;
@group(0) @binding(5) var<storage, read_write> m2: array<vec4f>;
@group(0) @binding(6) var variance_out: texture_storage_2d<rgba32float, write>;

const LUMA = vec3f(0.2126, 0.7152, 0.0722);

// VARIANCE: no variance, from Welford's second moment over frames, or from halves.
const VARIANCE_OFF: u32 = 0u;
const VARIANCE_FRAMES: u32 = 1u;
const VARIANCE_HALVES: u32 = 2u;

// Sample variance (rgb, luminance) of the input over the 3×3 neighborhood of `p`.
fn spatial_variance(p: vec2i, size: vec2i) -> vec4f {
    var sum = vec4f(0.0);
    var sum2 = vec4f(0.0);
    var n = 0.0;
    for (var dy = -1; dy <= 1; dy++) {
        for (var dx = -1; dx <= 1; dx++) {
            let q = p + vec2i(dx, dy);
            if all(q >= vec2i(0)) && all(q < size) {
                let x = textureLoad(input, q, 0).rgb;
                let v = vec4f(x, dot(x, LUMA));
                sum += v;
                sum2 += v * v;
                n += 1.0;
            }
        }
    }
    let mean = sum / n;
    let v = max(sum2 / n - mean * mean, vec4f(0.0)) * (n / max(n - 1.0, 1.0));
    return vec4f(v.rgb, robust_luminance_variance(p, size));
}

// (1.4826 × median absolute deviation)² of the luminance over the 3×3 neighborhood: the
// variance of Gaussian noise, but a pixel next to an edge (a light beside a wall) is not
// made to look noisy by the other side, as long as its own side is the majority.
fn robust_luminance_variance(p: vec2i, size: vec2i) -> f32 {
    var v: array<f32, 9>;
    var n = 0;
    for (var dy = -1; dy <= 1; dy++) {
        for (var dx = -1; dx <= 1; dx++) {
            let q = p + vec2i(dx, dy);
            if all(q >= vec2i(0)) && all(q < size) {
                v[n] = dot(textureLoad(input, q, 0).rgb, LUMA);
                n++;
            }
        }
    }
    let median = median_of(&v, n);
    for (var i = 0; i < n; i++) {
        v[i] = abs(v[i] - median);
    }
    let mad = 1.4826 * median_of(&v, n);
    return mad * mad;
}

// Median of the first `n` values (insertion sort; n <= 9).
fn median_of(v: ptr<function, array<f32, 9>>, n: i32) -> f32 {
    for (var i = 1; i < n; i++) {
        let x = (*v)[i];
        var j = i - 1;
        while j >= 0 && (*v)[j] > x {
            (*v)[j + 1] = (*v)[j];
            j--;
        }
        (*v)[j + 1] = x;
    }
    let h = n / 2;
    return select(0.5 * ((*v)[h - 1] + (*v)[h]), (*v)[h], n % 2 == 1);
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3u) {
    let size = params.size;
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    let i = id.y * size.x + id.x;
    if params.present == 1u {
        present(id.xy, i);
        return;
    }
    let input_px = textureLoad(input, id.xy, 0);
    let x = input_px.rgb;
    var s = sum[i];
    let before = s;
    // A pixel of alpha 0 took no sample this frame (PathTrace's adaptive sampling stopped
    // it): it adds nothing, once the history has a frame.
    let add = input_px.a != 0.0 || s.a == 0.0;
    if add {
        let c = comp[i].rgb;
        let y = x - c;
        let t = (s.rgb + y) * params.one;
        comp[i] = vec4f((t - s.rgb) - y, 0.0);
        s = vec4f(t, s.a + 1.0);
        sum[i] = s;
    }
    let mean = s.rgb / s.a;
    textureStore(output, id.xy, vec4f(mean, 1.0));

    if VARIANCE == VARIANCE_FRAMES {
        var moment = m2[i];
        if add {
            let mean_before = select(x, before.rgb / before.a, before.a > 0.0);
            let d = vec4f(x - mean_before, dot(x - mean_before, LUMA));
            let e = vec4f(x - mean, dot(x - mean, LUMA));
            moment += d * e;
            m2[i] = moment;
        }
        textureStore(variance_out, id.xy, frames_variance(moment, s.a, vec2i(id.xy)));
    } else if VARIANCE == VARIANCE_HALVES {
        // Odd frames of the render (the path tracer's second Sobol replicate) make the
        // second half.
        var odd = m2[i];
        if add && ((u32(before.a) + params.parity) & 1u) == 1u {
            odd += vec4f(x, 1.0);
            m2[i] = odd;
        }
        textureStore(variance_out, id.xy, halves_variance(s, odd, vec2i(id.xy)));
    }
}

// The variance of the mean of `n` frames from Welford's second moment `moment`; after one
// frame, estimated over the pixel's neighborhood.
fn frames_variance(moment: vec4f, n: f32, p: vec2i) -> vec4f {
    if n >= 2.0 {
        return max(moment, vec4f(0.0)) / (n * (n - 1.0));
    }
    return spatial_variance(p, vec2i(params.size));
}

// The variance of the mean from its two halves: with `a` and `b` the means of the n_a and
// n_b frames of each, (a - b)^2 n_a n_b / n^2 estimates the variance of the mean of all
// n = n_a + n_b frames without bias (for n_a = n_b; nearly, for n_a = n_b + 1) as long as
// the halves are independent of each other, whatever the correlation of the frames within
// a half (stratified Sobol frames are negatively correlated, which the spread over frames
// does not see). One degree of freedom
// per channel: Denoise blurs it before use. After one frame, estimated spatially.
fn halves_variance(sum: vec4f, odd: vec4f, p: vec2i) -> vec4f {
    let n = sum.a;
    let nb = odd.a;
    let na = n - nb;
    if nb < 1.0 || na < 1.0 {
        return spatial_variance(p, vec2i(params.size));
    }
    let d = (sum.rgb - odd.rgb) / na - odd.rgb / nb;
    let dd = vec4f(d, dot(d, LUMA));
    return dd * dd * (na * nb / (n * n));
}

// The mean (and variance) of the history as it stands, adding nothing.
fn present(p: vec2u, i: u32) {
    let s = sum[i];
    textureStore(output, p, vec4f(s.rgb / s.a, 1.0));
    if VARIANCE == VARIANCE_FRAMES {
        textureStore(variance_out, p, frames_variance(m2[i], s.a, vec2i(p)));
    } else if VARIANCE == VARIANCE_HALVES {
        textureStore(variance_out, p, halves_variance(s, m2[i], vec2i(p)));
    }
}
