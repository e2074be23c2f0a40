// Adaptive sampling: before each frame of the path tracer, decides which pixels stop taking
// samples, and writes where the samples went (PathTrace's `samples` output).
//
// The path tracer keeps, per pixel, the sums and frame counts of its even and of its odd
// frames (`halves`), which come from two independent Sobol replicates. With `a` and `b` the
// means of the n_a and n_b frames of each, (a - b)^2 n_a n_b / n^2 estimates the variance of
// the pixel's mean without bias (Accumulate's `variance_estimate: halves`), with one degree
// of freedom per channel. A pixel's relative error is that variance over (mean^2 + 0.01) per
// channel, the weight relMSE gives it, averaged over the channels and over the pixel's 5×5
// neighborhood (about 75 degrees of freedom, so one unlucky frame does not stop a noisy
// pixel). The pixel stops for good once it has taken `min_frames` frames and that average
// is below `error2`; it is checked about four times per doubling of its frames (at 16, 20,
// 24, 28, 32, 40… frames), not every frame, since each check is a chance for a low estimate
// to stop it early. The pixels still sampling are listed for the path tracer, which traces
// them with its first invocations.

struct Params {
    size: vec2u,
    // Frames every pixel takes before it may stop.
    min_frames: u32,
    // The threshold on the relative variance: `adaptive_error` squared; negative when
    // adaptive sampling is off (every pixel samples every frame; only `samples` is written).
    error2: f32,
    // Frames the path tracer has run before this one, and the samples each takes.
    frames: u32,
    samples_per_frame: u32,
    pad0: u32,
    pad1: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> halves: array<vec4f>;
@group(0) @binding(2) var<storage, read_write> stopped: array<u32>;
@group(0) @binding(3) var samples: texture_storage_2d<rgba32float, write>;
// The pixels still sampling this frame: their count (cleared before the pass), then each
// one's x | y << 16, a workgroup's pixels together.
@group(0) @binding(4) var<storage, read_write> listed: array<atomic<u32>>;

const RADIUS: i32 = 2;

// The pixel's relative variance from its halves (even, odd frames); -1 until both have a
// frame.
fn relative_variance(even: vec4f, odd: vec4f) -> f32 {
    let na = even.a;
    let nb = odd.a;
    if na < 1.0 || nb < 1.0 {
        return -1.0;
    }
    let n = na + nb;
    let d = even.rgb / na - odd.rgb / nb;
    let mean = (even.rgb + odd.rgb) / n;
    let v = d * d * (na * nb / (n * n)) / (mean * mean + vec3f(0.01));
    return (v.x + v.y + v.z) / 3.0;
}

// Whether a pixel with `frames` frames is checked: about four times per doubling.
fn checked_at(frames: u32) -> bool {
    let step = max(1u, (1u << firstLeadingBit(max(frames, 1u))) / 4u);
    return frames % step == 0u;
}

var<workgroup> group_count: atomic<u32>;
var<workgroup> group_base: u32;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3u, @builtin(local_invocation_index) lane: u32) {
    let size = params.size;
    let inside = id.x < size.x && id.y < size.y;
    if params.error2 < 0.0 {
        if inside {
            let taken = f32(params.frames + 1u);
            textureStore(samples, id.xy, vec4f(vec3f(1.0), taken * f32(params.samples_per_frame)));
        }
        return;
    }
    var stop = true;
    var taken = 0.0;
    if inside {
        let i = id.y * size.x + id.x;
        let frames = u32(halves[2u * i].a + halves[2u * i + 1u].a);
        stop = stopped[i] != 0u;
        if !stop && frames >= params.min_frames && checked_at(frames) {
            stop = neighborhood_error(vec2i(id.xy), size) < params.error2;
            if stop {
                stopped[i] = 1u;
            }
        }
        // After this frame: the pixel's frames, and their share of all frames.
        taken = f32(frames) + select(1.0, 0.0, stop);
        let share = taken / f32(params.frames + 1u);
        textureStore(samples, id.xy, vec4f(vec3f(share), taken * f32(params.samples_per_frame)));
    }
    // The pixels still sampling join the list, each workgroup's together.
    var slot = 0u;
    if !stop {
        slot = atomicAdd(&group_count, 1u);
    }
    workgroupBarrier();
    if lane == 0u {
        group_base = atomicAdd(&listed[0], atomicLoad(&group_count));
    }
    let base = workgroupUniformLoad(&group_base);
    if !stop {
        atomicStore(&listed[1u + base + slot], id.x | (id.y << 16u));
    }
}

// The mean relative variance over the 5×5 neighborhood of `p` (pixels with both halves).
fn neighborhood_error(p: vec2i, size: vec2u) -> f32 {
    var sum = 0.0;
    var count = 0.0;
    for (var dy = -RADIUS; dy <= RADIUS; dy++) {
        for (var dx = -RADIUS; dx <= RADIUS; dx++) {
            let q = p + vec2i(dx, dy);
            if all(q >= vec2i(0)) && all(q < vec2i(size)) {
                let j = 2u * (u32(q.y) * size.x + u32(q.x));
                let v = relative_variance(halves[j], halves[j + 1u]);
                if v >= 0.0 {
                    sum += v;
                    count += 1.0;
                }
            }
        }
    }
    return select(F32_MAX, sum / count, count > 0.0);
}

const F32_MAX: f32 = 3.4028235e38;
