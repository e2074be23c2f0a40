// AutoExposure, pass 2 (one invocation): the mean log2 luminance of the histogram's pixels
// between the `low` and `high` fractions of the count, the exposure that maps it to `key`
// (clamped to [min_ev, max_ev]), and the adapted exposure in `state`: the target itself on
// the first frame after a reset (state.valid = 0), else `adaptation` of the way from the
// last frame's value. The CPU reference is `render::cpu::auto_exposure_target`.
#import "post/luminance_bins.wgsl"

struct Params {
    key: f32,
    low: f32,
    high: f32,
    min_ev: f32,
    max_ev: f32,
    adaptation: f32,
    pad0: f32,
    pad1: f32,
}

struct State {
    ev: f32,
    valid: u32,
}

@group(0) @binding(0) var<storage, read> bins: array<u32, 256>;
@group(0) @binding(1) var<storage, read_write> state: State;
@group(0) @binding(2) var<uniform> params: Params;

@compute @workgroup_size(1)
fn main() {
    var total = 0.0;
    for (var i = 0u; i < HISTOGRAM_BINS; i++) {
        total += f32(bins[i]);
    }
    if total == 0.0 {
        return;
    }
    let lo = total * params.low;
    let hi = total * params.high;
    var below = 0.0;
    var sum = 0.0;
    var weight = 0.0;
    for (var i = 0u; i < HISTOGRAM_BINS; i++) {
        let n = f32(bins[i]);
        let take = clamp(below + n, lo, hi) - clamp(below, lo, hi);
        sum += take * bin_center(i);
        weight += take;
        below += n;
    }
    var mean = bin_center(0u);
    if weight > 0.0 {
        mean = sum / weight;
    }
    let target_ev = clamp(log2(params.key) - mean, params.min_ev, params.max_ev);
    if state.valid == 0u {
        state.ev = target_ev;
        state.valid = 1u;
    } else {
        state.ev = state.ev + (target_ev - state.ev) * params.adaptation;
    }
}
