// The bins of the luminance histogram AutoExposure reduces (mirrored by
// `render::cpu::luminance_bin`): 256 bins of log2 luminance over [-24, 16] EV; luminance
// at or below 2^-24 (black) falls in bin 0, above 2^16 in bin 255.
#import "common/color.wgsl"

const HISTOGRAM_BINS: u32 = 256u;
const LOG2_LUMINANCE_MIN: f32 = -24.0;
const LOG2_LUMINANCE_MAX: f32 = 16.0;

// The bin of linear color `c`, or HISTOGRAM_BINS for a color that is not finite (left out).
fn luminance_bin(c: vec3f) -> u32 {
    let l = luminance(max(c, vec3f(0.0)));
    if (bitcast<u32>(l) & 0x7f800000u) == 0x7f800000u {
        return HISTOGRAM_BINS;
    }
    if l <= exp2(LOG2_LUMINANCE_MIN) {
        return 0u;
    }
    let t = (log2(l) - LOG2_LUMINANCE_MIN) / (LOG2_LUMINANCE_MAX - LOG2_LUMINANCE_MIN);
    return u32(clamp(t * f32(HISTOGRAM_BINS), 0.0, f32(HISTOGRAM_BINS - 1u)));
}

// The log2 luminance at the middle of bin `i`.
fn bin_center(i: u32) -> f32 {
    let width = (LOG2_LUMINANCE_MAX - LOG2_LUMINANCE_MIN) / f32(HISTOGRAM_BINS);
    return LOG2_LUMINANCE_MIN + (f32(i) + 0.5) * width;
}
