// Math: one operation with `value` on each of r, g, b (alpha kept) (the CPU reference is in
// tests/post/combine.rs).
#import "post/filter.wgsl"

struct Params {
    operation: u32,
    value: f32,
}

const MATH_ADD: u32 = 0u;
const MATH_MULTIPLY: u32 = 1u;
const MATH_POWER: u32 = 2u;
const MATH_MINIMUM: u32 = 3u;
const MATH_MAXIMUM: u32 = 4u;
const MATH_CLAMP: u32 = 5u;

fn filter_pixel(c: vec4f, pixel: vec2u, size: vec2u) -> vec4f {
    let v = vec3f(params.value);
    var rgb = c.rgb;
    switch params.operation {
        case MATH_ADD: {
            rgb = c.rgb + v;
        }
        case MATH_MULTIPLY: {
            rgb = c.rgb * v;
        }
        case MATH_POWER: {
            rgb = pow(max(c.rgb, vec3f(0.0)), v);
        }
        case MATH_MINIMUM: {
            rgb = min(c.rgb, v);
        }
        case MATH_MAXIMUM: {
            rgb = max(c.rgb, v);
        }
        case MATH_CLAMP: {
            rgb = clamp(c.rgb, vec3f(0.0), v);
        }
        default: {}
    }
    return vec4f(rgb, c.a);
}
