// Contrast around a pivot, for linear HDR color: pivot × (c / pivot)^contrast per channel,
// so the pivot stays and ratios above and below it are raised to `contrast` (the CPU
// reference is in tests/post/grade.rs).
#import "post/filter.wgsl"

struct Params {
    contrast: f32,
    pivot: f32,
}

fn filter_pixel(c: vec4f, pixel: vec2u, size: vec2u) -> vec4f {
    let rgb = params.pivot * pow(max(c.rgb, vec3f(0.0)) / params.pivot, vec3f(params.contrast));
    return vec4f(rgb, c.a);
}
