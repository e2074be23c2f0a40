// ASC CDL: out = clamp(in × slope + offset, 0)^power per channel, then saturation around
// the Rec.709 luma (the CPU reference is in tests/post/grade.rs).
#import "post/filter.wgsl"

struct Params {
    slope_r: f32,
    slope_g: f32,
    slope_b: f32,
    offset_r: f32,
    offset_g: f32,
    offset_b: f32,
    power_r: f32,
    power_g: f32,
    power_b: f32,
    saturation: f32,
}

fn filter_pixel(c: vec4f, pixel: vec2u, size: vec2u) -> vec4f {
    let slope = vec3f(params.slope_r, params.slope_g, params.slope_b);
    let offset = vec3f(params.offset_r, params.offset_g, params.offset_b);
    let power = vec3f(params.power_r, params.power_g, params.power_b);
    let sop = pow(max(c.rgb * slope + offset, vec3f(0.0)), power);
    let luma = dot(sop, vec3f(0.2126, 0.7152, 0.0722));
    return vec4f(luma + params.saturation * (sop - luma), c.a);
}
