// Exposure: color × 2^ev.
#import "post/filter.wgsl"

struct Params {
    ev: f32,
}

fn filter_pixel(c: vec4f, pixel: vec2u, size: vec2u) -> vec4f {
    return vec4f(c.rgb * exp2(params.ev), c.a);
}
