// Mix: b blended over a by `mode`, then lerp(a, blended, factor); alpha from a (the CPU
// reference is in tests/post/combine.rs). Overlay and screen are defined for [0, 1] and
// applied as is to HDR values.
#import "post/filter2.wgsl"

struct Params {
    mode: u32,
    factor: f32,
}

const MIX_MIX: u32 = 0u;
const MIX_ADD: u32 = 1u;
const MIX_MULTIPLY: u32 = 2u;
const MIX_SCREEN: u32 = 3u;
const MIX_OVERLAY: u32 = 4u;
const MIX_DIFFERENCE: u32 = 5u;
const MIX_SUBTRACT: u32 = 6u;

fn filter_pixels(a: vec4f, b: vec4f, pixel: vec2u, size: vec2u) -> vec4f {
    var m = b.rgb;
    switch params.mode {
        case MIX_ADD: {
            m = a.rgb + b.rgb;
        }
        case MIX_MULTIPLY: {
            m = a.rgb * b.rgb;
        }
        case MIX_SCREEN: {
            m = 1.0 - (1.0 - a.rgb) * (1.0 - b.rgb);
        }
        case MIX_OVERLAY: {
            m = select(1.0 - 2.0 * (1.0 - a.rgb) * (1.0 - b.rgb), 2.0 * a.rgb * b.rgb, a.rgb < vec3f(0.5));
        }
        case MIX_DIFFERENCE: {
            m = abs(a.rgb - b.rgb);
        }
        case MIX_SUBTRACT: {
            m = a.rgb - b.rgb;
        }
        default: {}
    }
    return vec4f(mix(a.rgb, m, params.factor), a.a);
}
